#include "hivecal/port/output_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>

#include "hivecal/port/temporaries.hpp"

namespace hivecal::port {
namespace {

constexpr std::size_t kBufferBytes = 64 * 1024;

std::string folder_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

std::string name_of(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string join(const std::string& folder, const std::string& name) {
  return folder == "/" ? "/" + name : folder + "/" + name;
}

/// The process's umask (read by setting it and putting it back).
mode_t umask_bits() {
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return mask;
}

/// mkstemp's pattern for a temporary beside `path`: its name + ".tmp.XXXXXX", the name cut
/// so that the whole stays within NAME_MAX (a legal 250-byte name still gets its temporary).
std::string temp_pattern(const std::string& path) {
  constexpr std::size_t kSuffix = sizeof(".tmp.XXXXXX") - 1;
  constexpr std::size_t kNameMax = 255;
  const std::size_t slash = path.rfind('/');
  const std::size_t name_start = slash == std::string::npos ? 0 : slash + 1;
  std::string pattern = path;
  if (path.size() - name_start > kNameMax - kSuffix) pattern.resize(name_start + kNameMax - kSuffix);
  return pattern + ".tmp.XXXXXX";
}

/// Mode of a new file: 0666 & ~umask, as open() would give it.
mode_t default_mode() {
  return static_cast<mode_t>(0666 & ~umask_bits());
}

std::string kind_of(mode_t mode) {
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISREG(mode)) return "a regular file";
  return "a special file";
}

/// `label 'path'` for messages.
std::string named(const std::string& label, const std::string& path) {
  return (label.empty() ? "" : label + " ") + quoted(path, 200);
}

/// Empty or white space only (a path such as "  " is a mistake, never a name meant).
bool blank(const std::string& text) {
  return text.find_first_not_of(" \t\r\n\v\f") == std::string::npos;
}

/// Refuses a path that is blank or ends in a blank name ("dir/  "; "report/" is "report").
Error check_not_blank(const std::string& path, const std::string& label, const char* what) {
  const std::size_t last = path.find_last_not_of('/');
  const bool root = !path.empty() && last == std::string::npos;
  if (root || (!blank(path) && !blank(name_of(path.substr(0, last + 1))))) return Error{};
  return Error::usage(label + ": " + (path.empty() ? std::string("empty path") : quoted(path) + " is blank") +
                      ": give " + what);
}

/// The folder exists and this process may create files in it.
Error check_folder_writable(const std::string& folder, const std::string& who) {
  struct stat info {};
  if (::stat(folder.c_str(), &info) != 0) {
    return Error::output(who + ": folder " + quoted(folder, 200) + " does not exist (" + system_message(errno) + ")");
  }
  if (!S_ISDIR(info.st_mode)) return Error::output(who + ": " + quoted(folder, 200) + " is not a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0) {
    return Error::output(who + ": cannot create files in folder " + quoted(folder, 200) + " (" + system_message(errno) +
                         ")");
  }
  return Error{};
}

/// Where a new file goes: an existing regular file keeps its mode and owner; anything else
/// that exists is refused. The path given is already the final one (symlinks resolved).
Error check_file_target(const std::string& target, const std::string& who, bool* existed, struct stat* info) {
  *existed = ::stat(target.c_str(), info) == 0;
  if (*existed && !S_ISREG(info->st_mode)) {
    return Error::output(who + ": is " + kind_of(info->st_mode) +
                         "; refusing to replace it (only regular files are written; '-' writes to stdout)");
  }
  return check_folder_writable(folder_of(target), who);
}

/// Follows a symlink at `path` to its final target; `path` itself otherwise.
Error resolve_link(const std::string& path, const std::string& who, std::string* target) {
  struct stat link {};
  *target = path;
  if (::lstat(path.c_str(), &link) != 0 || !S_ISLNK(link.st_mode)) return Error{};
  char* resolved = ::realpath(path.c_str(), nullptr);
  if (resolved == nullptr) {
    return Error::output(who + ": is a symlink whose target cannot be resolved (" + system_message(errno) + ")");
  }
  *target = resolved;
  std::free(resolved);
  return Error{};
}

bool make_folders(const std::string& path) {
  for (std::size_t slash = path.find('/', 1);; slash = path.find('/', slash + 1)) {
    const std::string prefix = path.substr(0, slash);
    if (!prefix.empty() && ::mkdir(prefix.c_str(), 0777) != 0 && errno != EEXIST) return false;
    if (slash == std::string::npos) return true;
  }
}

/// The deepest existing ancestor folder of `path` ("." for a relative path with none).
std::string existing_ancestor(const std::string& path) {
  std::string folder = folder_of(path);
  struct stat info {};
  while (::stat(folder.c_str(), &info) != 0 && folder != "." && folder != "/") folder = folder_of(folder);
  return folder;
}

/// The outputs this process has committed ("--out 'r.json'"), for finish_stdout's message.
std::vector<std::string>& written_outputs() {
  static std::vector<std::string> written;
  return written;
}

void sync_folder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);  // best effort: the renames are already visible
  ::close(fd);
}

}  // namespace

// --- StagedFile ----------------------------------------------------------------------------

StagedFile::~StagedFile() {
  if (fd_ >= 0) ::close(fd_);
}

bool StagedFile::flush() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t put = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (put < 0 && errno == EINTR) continue;
    if (put <= 0) {
      error_ = Error::output(quoted(shown_path_, 200) + ": write failed: " + system_message(put < 0 ? errno : EIO));
      return false;
    }
    done += static_cast<std::size_t>(put);
  }
  buffer_.clear();
  return true;
}

void StagedFile::write(const void* bytes, std::size_t count) {
  if (!error_.ok() || finished_) return;
  const char* data = static_cast<const char*>(bytes);
  if (to_memory_) {
    memory_.append(data, count);
    return;
  }
  buffer_.insert(buffer_.end(), data, data + count);
  if (buffer_.size() >= kBufferBytes) (void)flush();
}

Error StagedFile::finish() {
  if (finished_ || to_memory_) {
    finished_ = true;
    return error_;
  }
  finished_ = true;
  if (error_.ok() && flush()) {
    const std::string where = quoted(shown_path_, 200);
    if (::fchmod(fd_, mode_) != 0) {
      error_ = Error::output(where + ": cannot set the mode: " + system_message(errno));
    } else if (set_owner_ && ::fchown(fd_, owner_uid_, owner_gid_) != 0 && errno != EPERM) {
      error_ = Error::output(where + ": cannot keep the owner: " + system_message(errno));
    } else if (::fsync(fd_) != 0) {
      error_ = Error::output(where + ": fsync failed: " + system_message(errno));
    }
  }
  if (::close(fd_) != 0 && error_.ok()) {
    error_ = Error::output(quoted(shown_path_, 200) + ": close failed: " + system_message(errno));
  }
  fd_ = -1;
  return error_;
}

// --- OutputSet -----------------------------------------------------------------------------

struct OutputSet::Output {
  std::string label;                               ///< option name, for messages
  std::string path;                                ///< as given
  bool is_stdout = false;                          ///< "-"
  bool is_folder = false;                          ///< a folder of files
  std::string target;                              ///< final path (a symlink resolved)
  std::vector<std::string> names;                  ///< a folder: the files it will hold
  bool existed = false;                            ///< the file / folder was there before the run
  struct stat old {};                              ///< its metadata when it existed (a file)
  std::string temp_folder;                         ///< a new folder is built here, then renamed
  std::string emptied_folder;                      ///< temp_folder once its files go one by one
  std::vector<std::unique_ptr<StagedFile>> files;  ///< staged content
  std::vector<std::string> finals;  ///< where each staged file goes (inside temp_folder for a new folder)
  std::vector<bool> moved;          ///< renamed into place already
  bool folder_moved = false;
};

OutputSet::OutputSet() = default;
OutputSet::~OutputSet() {
  abandon();
}

Error OutputSet::check_distinct(const FileIdentity& identity, const std::string& who) const {
  for (const Input& input : inputs_) {
    if (same_file(identity, input.identity)) {
      return Error::usage(who + " is the same file as the input " + named(input.label, input.path) +
                          ": refusing to overwrite an input");
    }
  }
  for (const auto& output : outputs_) {
    if (output->is_stdout) continue;
    if (same_file(identity, identify(output->target))) {
      return Error::usage(who + " is the same file as the output " + named(output->label, output->path) +
                          ": each output needs its own path");
    }
    for (const std::string& name : output->names) {
      if (same_file(identity, identify(join(output->target, name)))) {
        return Error::usage(who + " is " + quoted(join(output->path, name), 200) + ", which the output " +
                            named(output->label, output->path) + " writes: each output needs its own path");
      }
    }
  }
  return Error{};
}

Error OutputSet::add_input(const std::string& path, const std::string& label) {
  if (path.empty() || path == "-") return Error{};
  Input input{label, path, identify(path)};
  for (const auto& output : outputs_) {
    if (output->is_stdout) continue;
    std::string written = same_file(input.identity, identify(output->target)) ? output->path : "";
    for (const std::string& name : output->names) {
      if (same_file(input.identity, identify(join(output->target, name)))) written = join(output->path, name);
    }
    if (!written.empty()) {
      return Error::usage(named(output->label, output->path) +
                          (written == output->path ? "" : " writes " + quoted(written, 200) + ", which") +
                          " is the same file as the input " + named(label, path) + ": refusing to overwrite an input");
    }
  }
  inputs_.push_back(std::move(input));
  return Error{};
}

Error OutputSet::add_file(const std::string& path, const std::string& label, std::size_t* id) {
  const std::string who = named(label, path);
  Error error = check_not_blank(path, label, "a file name ('-': stdout)");
  if (!error.ok()) return error;
  auto output = std::make_unique<Output>();
  output->label = label;
  output->path = path;
  if (path == "-") {
    for (const auto& other : outputs_) {
      if (other->is_stdout) return Error::usage(who + ": " + other->label + " already writes to stdout");
    }
    output->is_stdout = true;
  } else {
    error = resolve_link(path, who, &output->target);
    if (error.ok()) error = check_file_target(output->target, who, &output->existed, &output->old);
    if (error.ok()) error = check_distinct(identify(output->target), who);
    if (!error.ok()) return error;
  }
  *id = outputs_.size();
  outputs_.push_back(std::move(output));
  return Error{};
}

Error OutputSet::add_folder(const std::string& path, const std::string& label, const std::vector<std::string>& names,
                            std::size_t* id) {
  const std::string who = named(label, path);
  Error error = check_not_blank(path, label, "a folder path");
  if (error.ok() && path == "-") error = Error::usage(label + ": a folder path is needed, not stdout ('-')");
  if (!error.ok()) return error;
  auto output = std::make_unique<Output>();
  output->label = label;
  output->path = path;
  output->is_folder = true;
  error = resolve_link(path, who, &output->target);
  if (!error.ok()) return error;
  struct stat info {};
  output->existed = ::stat(output->target.c_str(), &info) == 0;
  if (output->existed && !S_ISDIR(info.st_mode)) {
    return Error::output(who + ": exists and is " + kind_of(info.st_mode) + ", not a folder");
  }
  error = check_folder_writable(output->existed ? output->target : existing_ancestor(output->target), who);
  if (error.ok()) error = check_distinct(identify(output->target), who);
  for (std::size_t k = 0; k < names.size() && error.ok(); ++k) {
    error = check_distinct(identify(join(output->target, names[k])),
                           who + " writes " + quoted(join(path, names[k]), 200) + ", which");
  }
  if (!error.ok()) return error;
  output->names = names;
  *id = outputs_.size();
  outputs_.push_back(std::move(output));
  return Error{};
}

Error OutputSet::stage_in_folder(Output& folder, const std::string& name, StagedFile** file) {
  const std::string who = named(folder.label, join(folder.path, name));
  if (std::find(folder.names.begin(), folder.names.end(), name) == folder.names.end()) {
    return Error::usage(who + ": internal: a file the folder was not declared with");
  }
  std::string base;
  if (folder.existed) {
    base = folder.target;
  } else {
    if (folder.temp_folder.empty()) {
      std::string pattern = temp_pattern(join(existing_ancestor(folder.target), name_of(folder.target)));
      if (::mkdtemp(pattern.data()) == nullptr) {
        return Error::output(who + ": cannot create a temporary folder: " + system_message(errno));
      }
      // mkdtemp makes it 0700; the folder it becomes gets what mkdir would give it.
      (void)::chmod(pattern.c_str(), static_cast<mode_t>(0777 & ~umask_bits()));
      folder.temp_folder = pattern;
      register_temporary(pattern, true);
    }
    base = folder.temp_folder;
  }
  auto staged = std::make_unique<StagedFile>();
  staged->shown_path_ = join(folder.path, name);
  staged->mode_ = default_mode();
  const std::string final_path = join(base, name);
  struct stat old {};
  bool existed = false;
  if (folder.existed) {
    const Error error = check_file_target(final_path, who, &existed, &old);
    if (!error.ok()) return error;
    if (existed) {
      staged->mode_ = old.st_mode & 07777;
      staged->set_owner_ = true;
      staged->owner_uid_ = old.st_uid;
      staged->owner_gid_ = old.st_gid;
    }
  }
  std::string pattern = temp_pattern(final_path);
  staged->fd_ = ::mkostemp(pattern.data(), O_CLOEXEC);
  if (staged->fd_ < 0)
    return Error::output(who + ": cannot create a temporary file beside it: " + system_message(errno));
  staged->temp_path_ = pattern;
  register_temporary(pattern, false);
  *file = staged.get();
  folder.files.push_back(std::move(staged));
  folder.finals.push_back(final_path);
  folder.moved.push_back(false);
  return Error{};
}

Error OutputSet::stage(std::size_t id, const std::string& name, StagedFile** file) {
  if (id >= outputs_.size() || committed_) return Error::usage("internal: staging an undeclared output");
  Output& output = *outputs_[id];
  if (output.is_folder) return stage_in_folder(output, name, file);
  const std::string who = named(output.label, output.path);
  if (!output.files.empty()) return Error::usage(who + ": staged twice");
  auto staged = std::make_unique<StagedFile>();
  staged->shown_path_ = output.is_stdout ? "stdout" : output.path;
  if (output.is_stdout) {
    staged->to_memory_ = true;
  } else {
    staged->mode_ = output.existed ? (output.old.st_mode & 07777) : default_mode();
    staged->set_owner_ = output.existed;
    staged->owner_uid_ = output.old.st_uid;
    staged->owner_gid_ = output.old.st_gid;
    std::string pattern = temp_pattern(output.target);
    staged->fd_ = ::mkostemp(pattern.data(), O_CLOEXEC);
    if (staged->fd_ < 0) {
      return Error::output(who + ": cannot create a temporary file beside it: " + system_message(errno));
    }
    staged->temp_path_ = pattern;
    register_temporary(pattern, false);
  }
  *file = staged.get();
  output.files.push_back(std::move(staged));
  output.finals.push_back(output.target);
  output.moved.push_back(false);
  return Error{};
}

Error OutputSet::stage_text(std::size_t id, const std::string& name, const std::string& content) {
  StagedFile* file = nullptr;
  Error error = stage(id, name, &file);
  if (!error.ok()) return error;
  file->write(content);
  return file->finish();
}

namespace {

/// Exclusive locks on the folders a commit writes into (flock on each folder itself: no lock
/// file is left behind), released on destruction: concurrent runs on the same outputs replace
/// them one set after the other, never interleaved. Each folder is locked once however it is
/// named ("x", "./x", "$PWD/x", a symlink: a second flock on a second descriptor of the same
/// folder would wait for the first forever), all in the order of device and inode, which every
/// run shares.
class FolderLocks {
 public:
  FolderLocks() = default;
  ~FolderLocks() { release(); }
  FolderLocks(const FolderLocks&) = delete;
  FolderLocks& operator=(const FolderLocks&) = delete;

  /// Releases what is held and locks `folders` (one that is not there has nothing to lock).
  void take(const std::vector<std::string>& folders) {
    release();
    struct Opened {
      dev_t device;
      ino_t inode;
      int fd;
    };
    std::vector<Opened> opened;
    for (const std::string& folder : folders) {
      const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
      struct stat info {};
      if (fd < 0) continue;  // not there (yet): nothing to serialise on
      const bool known = ::fstat(fd, &info) == 0 && std::any_of(opened.begin(), opened.end(), [&](const Opened& o) {
                           return o.device == info.st_dev && o.inode == info.st_ino;
                         });
      if (known) {
        ::close(fd);
      } else {
        opened.push_back(Opened{info.st_dev, info.st_ino, fd});
      }
    }
    std::sort(opened.begin(), opened.end(), [](const Opened& a, const Opened& b) {
      return a.device != b.device ? a.device < b.device : a.inode < b.inode;
    });
    for (const Opened& o : opened) {
      while (::flock(o.fd, LOCK_EX) != 0 && errno == EINTR) {
      }
      fds_.push_back(o.fd);
    }
  }

 private:
  void release() {
    for (int fd : fds_) ::close(fd);  // closing releases the lock
    fds_.clear();
  }
  std::vector<int> fds_;
};

}  // namespace

std::vector<std::string> OutputSet::folders_to_lock() const {
  std::vector<std::string> folders;
  for (const auto& output : outputs_) {
    if (output->is_stdout) continue;
    struct stat info {};
    const bool folder_there = output->is_folder && ::stat(output->target.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
    // A folder's files go into it; a file, or a new folder, into the folder above it.
    folders.push_back(folder_there ? output->target : existing_ancestor(output->target));
  }
  std::sort(folders.begin(), folders.end());
  return folders;
}

Error OutputSet::write_into_folders_made_meanwhile() {
  for (auto& output : outputs_) {
    if (output->temp_folder.empty()) continue;
    struct stat info {};
    if (::stat(output->target.c_str(), &info) != 0) continue;  // still new: the whole folder is moved
    if (!S_ISDIR(info.st_mode)) {
      return Error::output(named(output->label, output->path) + ": became " + kind_of(info.st_mode) +
                           " during the run; refusing to replace it");
    }
    // Another run made the folder since the declaration: its files go in one by one, as into
    // a folder that was there (a file of that run's that this one writes is replaced whole).
    for (std::size_t k = 0; k < output->files.size(); ++k) {
      output->finals[k] = join(output->target, name_of(output->finals[k]));
      struct stat old {};
      if (::stat(output->finals[k].c_str(), &old) == 0 && S_ISREG(old.st_mode)) {
        StagedFile& file = *output->files[k];
        file.mode_ = old.st_mode & 07777;
        file.set_owner_ = true;
        file.owner_uid_ = old.st_uid;
        file.owner_gid_ = old.st_gid;
      }
    }
    output->emptied_folder = output->temp_folder;  // removed once its files have moved
    output->temp_folder.clear();
    output->existed = true;
  }
  return Error{};
}

Error OutputSet::commit() {
  FolderLocks locks;
  // A folder that appears while this run waits (another run made it) is locked too.
  for (std::vector<std::string> folders = folders_to_lock();;) {
    locks.take(folders);
    std::vector<std::string> now = folders_to_lock();
    if (now == folders) break;
    folders = std::move(now);
  }
  Error error = write_into_folders_made_meanwhile();
  const SignalsHeld held;  // the set is moved whole: a signal now is delivered after abandon()
  for (auto& output : outputs_) {
    for (auto& file : output->files) {
      const Error finished = file->finish();
      if (error.ok() && !finished.ok()) error = finished;
    }
  }
  struct Moved {
    std::string path;    ///< where a file or folder was moved
    std::string backup;  ///< the old file's second name, "" when there was none
    bool existed;        ///< an old file was replaced
    Output* output;      ///< whose
    std::size_t file;    ///< which staged file; files.size() for the folder itself
  };
  std::vector<Moved> done;
  for (auto& output : outputs_) {  // what was checked at declaration may have changed since
    for (std::size_t k = 0; k < output->files.size() && error.ok() && !output->is_stdout; ++k) {
      struct stat now {};
      if (::stat(output->finals[k].c_str(), &now) == 0 && !S_ISREG(now.st_mode)) {
        error = Error::output(named(output->label, output->finals[k]) + ": became " + kind_of(now.st_mode) +
                              " during the run; refusing to replace it");
      }
    }
  }
  // stdout first, what the run printed before (its tables) and an output staged for it: it
  // cannot be taken back, and when it does not arrive no file is replaced.
  for (auto& output : outputs_) {
    if (!error.ok() || !output->is_stdout || output->files.empty()) continue;
    const std::string& bytes = output->files.front()->memory_;
    if (std::fwrite(bytes.data(), 1, bytes.size(), stdout) != bytes.size()) {
      error = Error::output("stdout: write failed: " + system_message(errno));
    }
  }
  if (error.ok()) error = finish_stdout();
  if (!error.ok() && error.message.rfind("stdout:", 0) == 0) error.message += "; no output was replaced";
  for (auto& output : outputs_) {
    if (!error.ok()) break;
    if (output->is_stdout) continue;
    for (std::size_t k = 0; k < output->files.size() && error.ok(); ++k) {
      const std::string& final_path = output->finals[k];
      // The old file stays reachable under a second name until every output is in place.
      std::string backup = final_path + ".old." + std::to_string(::getpid());
      const bool existed = ::access(final_path.c_str(), F_OK) == 0;
      if (!existed || ::link(final_path.c_str(), backup.c_str()) != 0) backup.clear();  // or no hard links here
      if (std::rename(output->files[k]->temp_path_.c_str(), final_path.c_str()) != 0) {
        error = Error::output(named(output->label, output->path) +
                              ": cannot move the new file into place: " + system_message(errno));
        if (!backup.empty()) ::unlink(backup.c_str());
      } else {
        output->moved[k] = true;
        done.push_back(Moved{final_path, backup, existed, output.get(), k});
        sync_folder(folder_of(final_path));
      }
    }
    if (error.ok() && !output->temp_folder.empty()) {
      const std::string parent = folder_of(output->target);
      if (!make_folders(parent) || std::rename(output->temp_folder.c_str(), output->target.c_str()) != 0) {
        error = Error::output(named(output->label, output->path) +
                              ": cannot move the new folder into place: " + system_message(errno));
      } else {
        output->folder_moved = true;
        done.push_back(Moved{output->target, "", false, output.get(), output->files.size()});
        sync_folder(parent);
      }
    }
  }
  // All or nothing: after a failed move, what was moved goes back (old files restored).
  for (auto it = done.rbegin(); it != done.rend(); ++it) {
    if (error.ok()) {
      if (!it->backup.empty()) ::unlink(it->backup.c_str());
      continue;
    }
    Output& output = *it->output;
    if (it->file == output.files.size()) {  // a new folder: back to its temporary name
      if (std::rename(output.target.c_str(), output.temp_folder.c_str()) == 0) output.folder_moved = false;
    } else if (!output.temp_folder.empty()) {
      // inside a new folder's temporary: removed with it by abandon()
    } else if (!it->backup.empty()) {
      (void)std::rename(it->backup.c_str(), it->path.c_str());
      output.moved[it->file] = false;
    } else if (!it->existed) {
      ::unlink(it->path.c_str());
      output.moved[it->file] = false;
    }  // else: an old file without a second name (no hard links) cannot come back
  }
  committed_ = true;
  abandon();  // whatever is left (after a failure) goes
  if (error.ok()) {
    for (const auto& output : outputs_) {
      if (!output->is_stdout) written_outputs().push_back(named(output->label, output->path));
    }
  }
  return error;
}

void OutputSet::abandon() {
  for (auto& output : outputs_) {
    for (std::size_t k = 0; k < output->files.size(); ++k) {
      StagedFile& file = *output->files[k];
      if (file.fd_ >= 0) {
        ::close(file.fd_);
        file.fd_ = -1;
      }
      if (!file.temp_path_.empty() && !output->moved[k]) ::unlink(file.temp_path_.c_str());
      if (!output->temp_folder.empty() && !output->folder_moved && output->moved[k]) {
        ::unlink(output->finals[k].c_str());  // moved inside the temporary folder only
      }
      unregister_temporary(file.temp_path_);
    }
    if (!output->temp_folder.empty() && !output->folder_moved) ::rmdir(output->temp_folder.c_str());
    unregister_temporary(output->temp_folder);
    if (!output->emptied_folder.empty()) ::rmdir(output->emptied_folder.c_str());
    unregister_temporary(output->emptied_folder);
    output->emptied_folder.clear();
    output->files.clear();
    output->finals.clear();
    output->moved.clear();
    output->temp_folder.clear();
  }
}

Error finish_stdout() {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  if (flushed && std::ferror(stdout) == 0) return Error{};
  const int saved = errno;
  std::string written;  // a failure after a commit must not read as "nothing was written"
  for (const std::string& output : written_outputs()) written += (written.empty() ? "" : ", ") + output;
  return Error::output("stdout: write failed: " + (saved != 0 ? system_message(saved) : std::string("I/O error")) +
                       (written.empty() ? "" : "; the outputs were written before it: " + written));
}

}  // namespace hivecal::port
