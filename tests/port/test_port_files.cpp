// port/posix input and output files (issue 13, hostile and careless use): only regular files
// are read or replaced, symlinks and modes are kept, an output may not be an input or another
// output, and a run's outputs appear all together or not at all.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <functional>

#include <atomic>
#include <cstdio>
#include <thread>
#include <string>

#include "hivecal/port/error.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"

namespace hivecal::port::port_files_test {
namespace {

std::string read(const std::string& path) {
  std::string text;
  return read_whole_file(path, kMaxTextInputBytes, &text).ok() ? text : "<unreadable>";
}

/// The st_mode of `path` (lstat: a link's own when `own_link`), 0 if it cannot be read.
mode_t mode_of(const std::string& path, bool own_link = false) {
  struct stat info {};
  const int read_status = own_link ? ::lstat(path.c_str(), &info) : ::stat(path.c_str(), &info);
  return read_status == 0 ? info.st_mode : 0;
}

/// Writes `text` as the only output at `path`.
Error write_one(const std::string& path, const std::string& text) {
  OutputSet outputs;
  std::size_t id = 0;
  Error error = outputs.add_file(path, "--out", &id);
  if (error.ok()) error = outputs.stage_text(id, "", text);
  return error.ok() ? outputs.commit() : error;
}

TEST(OutputFiles, DevNullIsRefusedAndStaysADevice) {
  if (::geteuid() != 0) GTEST_SKIP() << "only root could replace /dev/null";
  const Error error = write_one("/dev/null", "x");
  EXPECT_EQ(error.fault, Fault::output);
  EXPECT_NE(error.message.find("character device"), std::string::npos) << error.message;
  EXPECT_TRUE(S_ISCHR(mode_of("/dev/null")));
}

TEST(OutputFiles, SymlinkIsFollowedAndKept) {
  const test::TempDir dir("hivecal_port_files");
  const std::string target = dir.write("target.json", "old");
  const std::string link = dir.path() + "/link.json";
  ASSERT_EQ(::symlink("target.json", link.c_str()), 0);
  ASSERT_TRUE(write_one(link, "new").ok());
  EXPECT_TRUE(S_ISLNK(mode_of(link, true)));
  EXPECT_EQ(read(target), "new");
}

TEST(OutputFiles, FifoIsRefusedAtOnce) {
  const test::TempDir dir("hivecal_port_files");
  const std::string fifo = dir.path() + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const Error error = write_one(fifo, "x");
  EXPECT_EQ(error.fault, Fault::output);
  EXPECT_NE(error.message.find("FIFO"), std::string::npos) << error.message;
  EXPECT_TRUE(S_ISFIFO(mode_of(fifo)));
}

TEST(OutputFiles, ModeOfAnExistingFileIsKept) {
  const test::TempDir dir("hivecal_port_files");
  const std::string path = dir.write("out.csv", "old");
  ASSERT_EQ(::chmod(path.c_str(), 0640), 0);
  ASSERT_TRUE(write_one(path, "new").ok());
  EXPECT_EQ(mode_of(path) & 07777, 0640u);
  EXPECT_EQ(read(path), "new");
}

TEST(OutputFiles, AnOutputThatIsAnInputIsRefused) {
  const test::TempDir dir("hivecal_port_files");
  const std::string samples = dir.write("samples.csv", "data");
  OutputSet outputs;
  std::size_t id = 0;
  ASSERT_TRUE(outputs.add_input(samples, "--samples").ok());
  const Error error = outputs.add_file(
      dir.path() + "/../" + dir.path().substr(dir.path().rfind('/') + 1) + "/samples.csv", "--out", &id);
  EXPECT_EQ(error.fault, Fault::usage);
  EXPECT_NE(error.message.find("same file as the input --samples"), std::string::npos) << error.message;
  const std::string link = dir.path() + "/alias.csv";  // the same file under another name
  ASSERT_EQ(::link(samples.c_str(), link.c_str()), 0);
  EXPECT_EQ(outputs.add_file(link, "--out", &id).fault, Fault::usage);
  EXPECT_EQ(read(samples), "data");
}

TEST(OutputFiles, TwoOutputsOnOnePathAreRefused) {
  const test::TempDir dir("hivecal_port_files");
  OutputSet outputs;
  std::size_t a = 0, b = 0;
  ASSERT_TRUE(outputs.add_file(dir.path() + "/r.json", "--out", &a).ok());
  const Error error = outputs.add_file(dir.path() + "/r.json", "--ur-deltas", &b);
  EXPECT_EQ(error.fault, Fault::usage);
  EXPECT_NE(error.message.find("same file as the output --out"), std::string::npos) << error.message;
}

TEST(OutputFiles, NothingAppearsUnlessEverythingIsCommitted) {
  const test::TempDir dir("hivecal_port_files");
  // A result file and a report folder, both staged; false if any step fails.
  const auto stage_result_and_report = [&dir](OutputSet* outputs) {
    std::size_t result = 0, report = 0;
    return outputs->add_file(dir.path() + "/result.json", "--out", &result).ok() &&
           outputs->add_folder(dir.path() + "/report/deep", "--report", {"index.html"}, &report).ok() &&
           outputs->stage_text(result, "", "{}").ok() && outputs->stage_text(report, "index.html", "<html>").ok();
  };
  {
    OutputSet outputs;
    ASSERT_TRUE(stage_result_and_report(&outputs));
    // the run fails here: no commit
  }
  EXPECT_EQ(::access((dir.path() + "/result.json").c_str(), F_OK), -1);
  EXPECT_EQ(::access((dir.path() + "/report").c_str(), F_OK), -1);
  EXPECT_EQ(std::system(("test -z \"$(ls -A '" + dir.path() + "')\"").c_str()), 0) << "temporaries left";
  OutputSet outputs;
  ASSERT_TRUE(stage_result_and_report(&outputs));
  ASSERT_TRUE(outputs.commit().ok());
  EXPECT_EQ(read(dir.path() + "/result.json"), "{}");
  EXPECT_EQ(read(dir.path() + "/report/deep/index.html"), "<html>");
}

TEST(OutputFiles, ALegalNameOf255BytesGetsItsTemporary) {
  const test::TempDir dir("hivecal_port_files");
  for (std::size_t length : {245u, 250u, 255u}) {
    const std::string path = dir.path() + "/" + std::string(length - 5, 'r') + ".json";
    const Error error = write_one(path, "{}");
    ASSERT_TRUE(error.ok()) << length << ": " << error.message;
    EXPECT_EQ(read(path), "{}");
  }
}

TEST(OutputFiles, ANewReportFolderTakesTheUmask) {
  // mkdtemp's 0700 must not survive into the folder the user gets.
  const test::TempDir dir("hivecal_port_files");
  const mode_t old_mask = ::umask(022);
  {
    OutputSet outputs;
    std::size_t report = 0;
    ASSERT_TRUE(outputs.add_folder(dir.path() + "/report", "--report", {"index.html"}, &report).ok());
    ASSERT_TRUE(outputs.stage_text(report, "index.html", "<html>").ok());
    ASSERT_TRUE(outputs.commit().ok());
  }
  ::umask(old_mask);
  EXPECT_EQ(mode_of(dir.path() + "/report") & 0777, 0755u);
}

TEST(OutputFiles, AFileOfAnOutputFolderThatIsAnInputIsRefusedAtDeclaration) {
  const test::TempDir dir("hivecal_port_files");
  ASSERT_TRUE(write_one(dir.path() + "/truth.json", "input").ok());
  OutputSet outputs;
  std::size_t folder = 0;
  ASSERT_TRUE(outputs.add_input(dir.path() + "/truth.json", "--robot-model").ok());
  const Error error = outputs.add_folder(dir.path(), "--out-dir", {"robot.cap", "truth.json"}, &folder);
  EXPECT_EQ(error.fault, Fault::usage);
  EXPECT_NE(error.message.find("truth.json', which is the same file as the input --robot-model"), std::string::npos)
      << error.message;
  // Declared the other way round: the input comes after the folder.
  OutputSet later;
  ASSERT_TRUE(later.add_folder(dir.path(), "--out-dir", {"truth.json"}, &folder).ok());
  EXPECT_EQ(later.add_input(dir.path() + "/truth.json", "--robot-model").fault, Fault::usage);
  EXPECT_EQ(read(dir.path() + "/truth.json"), "input");
}

TEST(OutputFiles, AFileThatAnOutputFolderWritesIsRefusedBeforeAnyWork) {
  // calibrate --out rp/index.html --report rp: the report's page would replace the result.
  const test::TempDir dir("hivecal_port_files");
  const std::string report = dir.path() + "/rp";
  ASSERT_EQ(::mkdir(report.c_str(), 0755), 0);
  for (const bool page_exists : {false, true}) {
    if (page_exists) {
      ASSERT_TRUE(write_one(report + "/index.html", "old page").ok());
    }
    OutputSet outputs;
    std::size_t result = 0, folder = 0;
    ASSERT_TRUE(outputs.add_file(report + "/index.html", "--out", &result).ok());
    Error error = outputs.add_folder(report, "--report", {"index.html"}, &folder);
    EXPECT_EQ(error.fault, Fault::usage) << page_exists;
    EXPECT_NE(error.message.find("--report '" + report + "' writes '" + report +
                                 "/index.html', which is the same file as the output --out"),
              std::string::npos)
        << error.message;
    OutputSet reversed;  // the folder first: the file is refused, both options named
    ASSERT_TRUE(reversed.add_folder(report + "/", "--report", {"index.html"}, &folder).ok());
    error = reversed.add_file(dir.path() + "/./rp/index.html", "--ur-deltas", &result);
    EXPECT_EQ(error.fault, Fault::usage) << page_exists;
    EXPECT_NE(error.message.find("--ur-deltas"), std::string::npos) << error.message;
    EXPECT_NE(error.message.find("which the output --report"), std::string::npos) << error.message;
  }
  EXPECT_EQ(read(report + "/index.html"), "old page");
  OutputSet beside;  // a file of the folder's that the folder does not write is fine
  std::size_t a = 0, b = 0;
  EXPECT_TRUE(beside.add_folder(report, "--report", {"index.html"}, &a).ok());
  EXPECT_TRUE(beside.add_file(report + "/result.json", "--out", &b).ok());
}

TEST(OutputFiles, ABlankPathIsRefused) {
  OutputSet outputs;
  std::size_t id = 0;
  for (const char* blank : {"", "  ", "\t", "sub/ "}) {
    Error error = outputs.add_file(blank, "--out", &id);
    EXPECT_EQ(error.fault, Fault::usage) << "'" << blank << "'";
    EXPECT_NE(error.message.find("--out: "), std::string::npos) << error.message;
    error = outputs.add_folder(blank, "--report", {"index.html"}, &id);
    EXPECT_EQ(error.fault, Fault::usage) << "'" << blank << "'";
  }
  EXPECT_NE(outputs.add_file("  ", "--out", &id).message.find("'  ' is blank"), std::string::npos);
}

/// Runs `commit` in a child process; true when it ended within `limit_s` with exit 0.
bool commits_in_time(const std::function<bool()>& commit, int limit_s) {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(commit() ? 0 : 1);
  for (int waited_ms = 0; waited_ms < limit_s * 1000; waited_ms += 20) {
    int status = 0;
    if (::waitpid(child, &status, WNOHANG) == child) return WIFEXITED(status) && WEXITSTATUS(status) == 0;
    ::usleep(20000);
  }
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  return false;
}

TEST(OutputFiles, AFolderNamedTwoWaysIsLockedOnceAndTheCommitEnds) {
  // --out $PWD/x/result.json --report report (inside x), sub/../d.conf, a symlinked folder:
  // one folder under several names; a second flock on it waited for the first forever.
  const test::TempDir dir("hivecal_port_files");
  char* absolute = ::realpath(dir.path().c_str(), nullptr);
  ASSERT_NE(absolute, nullptr);
  const std::string x = absolute;
  std::free(absolute);
  ASSERT_EQ(::mkdir((x + "/sub").c_str(), 0755), 0);
  ASSERT_EQ(::symlink(x.c_str(), (x + "/alias").c_str()), 0);
  const bool committed = commits_in_time(
      [&] {
        if (::chdir(x.c_str()) != 0) return false;
        OutputSet outputs;
        std::size_t result = 0, deltas = 0, other = 0, report = 0;
        return outputs.add_file(x + "/result.json", "--out", &result).ok() &&
               outputs.add_file("sub/../d.conf", "--ur-deltas", &deltas).ok() &&
               outputs.add_file("alias/other.csv", "--urscript", &other).ok() &&
               outputs.add_folder("report", "--report", {"index.html"}, &report).ok() &&
               outputs.stage_text(result, "", "{}").ok() && outputs.stage_text(deltas, "", "d").ok() &&
               outputs.stage_text(other, "", "o").ok() && outputs.stage_text(report, "index.html", "<html>").ok() &&
               outputs.commit().ok();
      },
      20);
  EXPECT_TRUE(committed) << "the commit did not end (a folder locked twice?)";
  EXPECT_EQ(read(x + "/result.json"), "{}");
  EXPECT_EQ(read(x + "/d.conf"), "d");
  EXPECT_EQ(read(x + "/other.csv"), "o");
  EXPECT_EQ(read(x + "/report/index.html"), "<html>");
}

TEST(OutputFiles, TwoRunsCreatingOneFolderBothSucceed) {
  // Concurrent runs with the same new --report folder: the one that commits second finds the
  // folder made by the first and writes into it (it failed with "Directory not empty").
  const test::TempDir dir("hivecal_port_files");
  const std::string folder = dir.path() + "/report";
  OutputSet first, second;
  std::size_t a = 0, b = 0;
  ASSERT_TRUE(first.add_folder(folder, "--report", {"index.html", "first.txt"}, &a).ok());
  ASSERT_TRUE(second.add_folder(folder, "--report", {"index.html", "second.txt"}, &b).ok());
  ASSERT_TRUE(first.stage_text(a, "index.html", "first").ok());
  ASSERT_TRUE(first.stage_text(a, "first.txt", "1").ok());
  ASSERT_TRUE(second.stage_text(b, "index.html", "second").ok());
  ASSERT_TRUE(second.stage_text(b, "second.txt", "2").ok());
  ASSERT_TRUE(first.commit().ok());
  const Error error = second.commit();
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_EQ(read(folder + "/index.html"), "second");  // the later run's set, whole
  EXPECT_EQ(read(folder + "/first.txt"), "1");        // nothing of the first run lost
  EXPECT_EQ(read(folder + "/second.txt"), "2");
  EXPECT_EQ(std::system(("test \"$(ls -A '" + dir.path() + "')\" = report").c_str()), 0) << "temporaries left";
}

TEST(OutputFiles, ACommitWaitsForAnotherRunsCommitInTheSameFolder) {
  // Two runs on the same outputs: one set is replaced after the other, never interleaved. The
  // other run's commit is stood in for by holding the folder's lock here.
  const test::TempDir dir("hivecal_port_files");
  const int folder = ::open(dir.path().c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(folder, 0);
  ASSERT_EQ(::flock(folder, LOCK_EX), 0);
  std::atomic<bool> done{false};
  std::thread run([&] {
    EXPECT_TRUE(write_one(dir.path() + "/result.json", "{}").ok());
    done = true;
  });
  ::usleep(300000);
  EXPECT_FALSE(done.load()) << "the commit did not wait for the folder's lock";
  EXPECT_EQ(::access((dir.path() + "/result.json").c_str(), F_OK), -1);
  ::close(folder);  // the other commit ends
  run.join();
  EXPECT_TRUE(done.load());
  EXPECT_EQ(read(dir.path() + "/result.json"), "{}");
}

TEST(OutputFiles, ATargetThatBecomesAFifoDuringTheRunIsNotReplaced) {
  const test::TempDir dir("hivecal_port_files");
  const std::string path = dir.path() + "/out.csv";
  OutputSet outputs;
  std::size_t id = 0;
  ASSERT_TRUE(outputs.add_file(path, "--out", &id).ok());
  ASSERT_TRUE(outputs.stage_text(id, "", "x").ok());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);  // appears while the run computes
  EXPECT_EQ(outputs.commit().fault, Fault::output);
  EXPECT_TRUE(S_ISFIFO(mode_of(path)));
}

TEST(OutputFiles, AFailedMovePutsBackWhatWasMovedBefore) {
  const test::TempDir dir("hivecal_port_files");
  const std::string first = dir.write("first.json", "old first");
  ASSERT_EQ(::mkdir((dir.path() + "/sub").c_str(), 0755), 0);
  OutputSet outputs;
  std::size_t a = 0, b = 0;
  ASSERT_TRUE(outputs.add_file(first, "--out", &a).ok());
  ASSERT_TRUE(outputs.add_file(dir.path() + "/sub/second.conf", "--ur-deltas", &b).ok());
  ASSERT_TRUE(outputs.stage_text(a, "", "new first").ok());
  ASSERT_TRUE(outputs.stage_text(b, "", "new second").ok());
  // The second temporary vanishes: its move fails after the first output was moved.
  ASSERT_EQ(std::system(("rm -f '" + dir.path() + "'/sub/second.conf.tmp.*").c_str()), 0);
  EXPECT_EQ(outputs.commit().fault, Fault::output);
  EXPECT_EQ(read(first), "old first");
  EXPECT_EQ(std::system(("test \"$(ls -A '" + dir.path() + "')\" = \"first.json\nsub\"").c_str()), 0)
      << "backups or temporaries left";
}

TEST(OutputFiles, AMissingFolderIsFoundBeforeAnyWork) {
  const test::TempDir dir("hivecal_port_files");
  OutputSet outputs;
  std::size_t id = 0;
  const Error error = outputs.add_file(dir.path() + "/no/such/out.json", "--out", &id);
  EXPECT_EQ(error.fault, Fault::output);
  EXPECT_NE(error.message.find("does not exist"), std::string::npos) << error.message;
}

TEST(InputFiles, DevZeroIsRefusedAtOnce) {
  InputFile file;
  const Error error = file.open("/dev/zero", kMaxStreamInputBytes);
  EXPECT_EQ(error.fault, Fault::input);
  EXPECT_NE(error.message.find("character device, not a regular file"), std::string::npos) << error.message;
}

TEST(InputFiles, AFifoIsRefusedWithoutBlocking) {
  const test::TempDir dir("hivecal_port_files");
  const std::string fifo = dir.path() + "/fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  InputFile file;
  EXPECT_EQ(file.open(fifo, kMaxStreamInputBytes).fault, Fault::input);
}

TEST(InputFiles, AFileOverTheLimitIsRefusedBeforeReading) {
  const test::TempDir dir("hivecal_port_files");
  const std::string path = dir.write("big.json", std::string(2000, ' '));
  InputFile file;
  const Error error = file.open(path, 1000);
  EXPECT_EQ(error.fault, Fault::input);
  EXPECT_TRUE(file.open(path, 4000).ok());
}

TEST(Messages, HugeAndBinaryTextIsEscapedAndCut) {
  const std::string huge(1 << 20, 'a');
  const std::string shown = printable(huge);
  EXPECT_LT(shown.size(), 120u);
  EXPECT_NE(shown.find("...[1048576 bytes]"), std::string::npos);
  EXPECT_EQ(printable(std::string("a\0b\x1b[31m\xff", 9)), "a\\x00b\\x1b[31m\\xff");
  EXPECT_EQ(quoted("x\ny"), "'x\\x0ay'");
}

// UTF-8 is shown as written ("µm" was "\xc2\xb5m" in every message and the report): only what
// steers a terminal (C0, DEL, C1: U+009B is a CSI), the bidirectional overrides and isolates,
// and bytes that are no UTF-8 (a lone continuation, an overlong form, a surrogate, beyond
// U+10FFFF, a character cut by the file's end) are escaped; a cut never splits a character.
TEST(Messages, Utf8IsKeptAndOnlyWhatSteersTheTerminalIsEscaped) {
  EXPECT_EQ(printable("[\xc2\xb5m] 90\xc2\xb0 \xd0\xa0 \xe2\x82\xac \xf0\x9f\x98\x80"),
            "[\xc2\xb5m] 90\xc2\xb0 \xd0\xa0 \xe2\x82\xac \xf0\x9f\x98\x80");
  EXPECT_EQ(printable("a\xc2\x9b"
                      "2Jb"),
            "a\\xc2\\x9b2Jb");                                  // C1 CSI
  EXPECT_EQ(printable("x\xe2\x80\xaey"), "x\\xe2\\x80\\xaey");  // right-to-left override
  EXPECT_EQ(printable("x\xe2\x81\xa6y"), "x\\xe2\\x81\\xa6y");  // left-to-right isolate
  EXPECT_EQ(printable("\x80|\xc0\x80|\xed\xa0\x80|\xf5\x80\x80\x80|\xe2\x82"),
            "\\x80|\\xc0\\x80|\\xed\\xa0\\x80|\\xf5\\x80\\x80\\x80|\\xe2\\x82");
  EXPECT_EQ(printable("ab\xc2\xb5", 3), "ab...[4 bytes]");  // the cut falls inside the µ: not shown
  EXPECT_EQ(printable("ab\xc2\xb5", 4), "ab\xc2\xb5");
  EXPECT_EQ(utf8_sequence_bytes("\xf4\x8f\xbf\xbf", 0), 4u);  // U+10FFFF
  EXPECT_EQ(utf8_sequence_bytes("\xf4\x90\x80\x80", 0), 0u);  // beyond it
}

}  // namespace
}  // namespace hivecal::port::port_files_test
