// The outputs of one run, written all or nothing (docs/cli.md "Outputs"):
//  1. declare: every output (file, folder with the names of the files it will hold, or '-' for
//     stdout) and every input is declared before the long work; an output that is blank, a
//     device, FIFO, socket or folder, whose folder does not exist or is not writable, or that
//     is an input, another output or a file another output writes (same realpath, or same
//     device + inode) is refused at once;
//  2. stage: each output is written to a temporary beside its target (a symlink is followed:
//     the temporary goes beside the link's target, the link stays), every write, the fsync
//     and the close checked; stdout's bytes are kept in memory;
//  3. commit: the folders the outputs go into are locked (flock, each folder once however it
//     is named: concurrent runs commit one whole set after the other), stdout (an output
//     staged for it, and whatever the run printed before) is written and flushed (a full
//     device is an error, and nothing is replaced), then every temporary is renamed onto its target
//     with the old file's mode (and owner, when allowed). A new folder that another run
//     created meanwhile is written into as an existing one.
// A set destroyed without commit() removes its temporaries: a failed run leaves no output; a
// signal removes them too (temporaries.hpp), and waits while the set is moved into place.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hivecal/port/error.hpp"
#include "hivecal/port/input_file.hpp"

namespace hivecal::port {

/// One output being written to its temporary (buffered; every system call checked).
class StagedFile {
 public:
  StagedFile() = default;
  ~StagedFile();
  StagedFile(const StagedFile&) = delete;
  StagedFile& operator=(const StagedFile&) = delete;

  /// Appends bytes; after a failure, further writes do nothing and finish() reports it.
  void write(const void* bytes, std::size_t count);
  /// Appends text.
  void write(const std::string& text) { write(text.data(), text.size()); }
  /// Flushes, sets the mode, fsyncs and closes; the first failure of the whole file or ok.
  Error finish();

 private:
  friend class OutputSet;
  bool flush();

  int fd_ = -1;
  std::string temp_path_;   ///< the temporary
  std::string shown_path_;  ///< the target as the user named it (messages)
  mode_t mode_ = 0644;      ///< mode of the committed file
  bool set_owner_ = false;  ///< give the file owner_uid_/owner_gid_ (an existing file's)
  uid_t owner_uid_ = 0;
  gid_t owner_gid_ = 0;
  std::string memory_;      ///< stdout's bytes (fd_ stays -1)
  bool to_memory_ = false;  ///< this stages stdout
  std::vector<char> buffer_;
  Error error_;
  bool finished_ = false;
};

/// The declared outputs of one run.
class OutputSet {
 public:
  OutputSet();
  ~OutputSet();  ///< removes every temporary not committed
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Declares an input (`label`: how the user named it, e.g. "--samples"): no output may be it.
  Error add_input(const std::string& path, const std::string& label);
  /// Declares an output file ("-": stdout) and checks that it can be written; *id names it.
  Error add_file(const std::string& path, const std::string& label, std::size_t* id);
  /// Declares an output folder (created with its missing parents at commit; files already
  /// in it that the run does not write stay) that will hold the files `names` (no others).
  Error add_folder(const std::string& path, const std::string& label, const std::vector<std::string>& names,
                   std::size_t* id);

  /// Starts the content of output file `id`, or of file `name` inside output folder `id`.
  /// The StagedFile belongs to the set; call finish() on it when written.
  Error stage(std::size_t id, const std::string& name, StagedFile** file);
  /// The whole content of output file `id` (or file `name` in folder `id`) at once.
  Error stage_text(std::size_t id, const std::string& name, const std::string& content);

  /// Writes stdout, then moves every staged temporary into place. After a failure nothing
  /// more is moved and the remaining temporaries are removed.
  Error commit();
  /// Removes every temporary (what the destructor does).
  void abandon();

 private:
  struct Output;
  struct Input {
    std::string label;
    std::string path;
    FileIdentity identity;
  };
  Error check_distinct(const FileIdentity& identity, const std::string& who) const;
  Error stage_in_folder(Output& folder, const std::string& name, StagedFile** file);
  std::vector<std::string> folders_to_lock() const;
  Error write_into_folders_made_meanwhile();

  std::vector<Input> inputs_;
  std::vector<std::unique_ptr<Output>> outputs_;
  bool committed_ = false;
};

/// Flushes stdout and checks that everything printed on it was written (e.g. not to a full
/// device); Fault::output with the reason otherwise, naming the outputs this process has
/// committed already (a failure after a commit leaves them written).
Error finish_stdout();

}  // namespace hivecal::port
