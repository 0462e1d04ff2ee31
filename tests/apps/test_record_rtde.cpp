// `hivecal record --rtde` against a stand-in UR controller (testkit/rtde_controller.hpp): an
// IPv6 address with a port, a chattering controller that does not flood the terminal, a full
// disk that leaves the log ending at a whole row (exit 4), and a second recording into the
// same file refused even with --force (exit 4, its summary saying it wrote nothing) while the
// first keeps its rows (issue 54).
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/streams.hpp"
#include "hivecal/port/byte_source.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/rtde_controller.hpp"

namespace hivecal::record_rtde_test {
namespace {

using test::ControllerScript;
using test::StandInController;

std::string read_all(const std::string& path) {
  std::string text;
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return "<none>";
  char buffer[4096];
  for (std::size_t got; (got = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, got);
  std::fclose(file);
  return text;
}

std::size_t lines_of(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

/// Runs `record` with `args` in a child process (its own signal handlers, its own limits:
/// a file size limit of `max_file_bytes` when > 0); its exit code, -1 if it did not exit.
int record_in_child(std::vector<std::string> args, rlim_t max_file_bytes = 0) {
  const pid_t child = ::fork();
  if (child == 0) {
    if (max_file_bytes > 0) {
      const rlimit limit{max_file_bytes, max_file_bytes};
      ::setrlimit(RLIMIT_FSIZE, &limit);
      std::signal(SIGXFSZ, SIG_IGN);  // as main() has it: the write fails with EFBIG
    }
    ::_exit(test::run(streams::record_main, std::move(args)));
  }
  int status = 0;
  if (child < 0 || ::waitpid(child, &status, 0) != child || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

TEST(RecordRtde, AnIpv6AddressWithAPortIsRecorded) {
  const test::TempDir dir("hivecal_record_rtde");
  ControllerScript script;
  script.ipv6 = true;
  script.data_packages = 30;
  script.close_mid_stream = true;
  const StandInController controller(script);
  const std::string out = dir.path() + "/ipv6.txt";
  const int code = record_in_child(
      {"--rtde", "[::1]:" + std::to_string(controller.port()), "--robot-out", out, "--duration-s", "5"});
  EXPECT_EQ(code, cli::kExitOk);
  EXPECT_EQ(lines_of(read_all(out)), 31u);
}

TEST(RecordRtde, AChatteringControllerDoesNotFloodTheTerminal) {
  // 220k text lines on stderr in 2 s: now a few, then a note, then the refusal.
  const test::TempDir dir("hivecal_record_rtde");
  ControllerScript script;
  script.chatter_only = true;
  script.chatter_after_start = true;
  script.chatter_limit_s = 6.0;
  const StandInController controller(script);
  std::string err;
  const int code = test::run_capturing_stderr(
      streams::record_main,
      {"--rtde", "127.0.0.1:" + std::to_string(controller.port()), "--robot-out", dir.path() + "/chatter.txt"}, &err);
  EXPECT_EQ(code, cli::kExitBadInput);
  EXPECT_LE(lines_of(err), 25u) << err.substr(0, 2000);
  EXPECT_NE(err.find("further controller messages are counted, not shown"), std::string::npos) << err.substr(0, 2000);
  EXPECT_NE(err.find("far more than the 125 Hz asked for"), std::string::npos) << err.substr(0, 2000);
}

TEST(RecordRtde, AFullDiskEndsTheLogAtAWholeRowWithExit4) {
  const test::TempDir dir("hivecal_record_rtde");
  ControllerScript script;
  script.data_packages = 200;
  script.close_mid_stream = true;
  const StandInController controller(script);
  const std::string out = dir.path() + "/full.txt";
  const int code = record_in_child(
      {"--rtde", "127.0.0.1:" + std::to_string(controller.port()), "--robot-out", out, "--duration-s", "5"}, 2000);
  EXPECT_EQ(code, cli::kExitOutputError);
  const std::string log = read_all(out);
  ASSERT_FALSE(log.empty());
  EXPECT_EQ(log.back(), '\n') << "the last row was cut: ..." << log.substr(log.size() > 80 ? log.size() - 80 : 0);
  EXPECT_LE(log.size(), 2000u);
}

TEST(RecordRtde, ASecondRecordingIntoTheSameFileFailsEvenWithForce) {
  const test::TempDir dir("hivecal_record_rtde");
  ControllerScript slow;
  slow.data_packages = 150;
  slow.data_period_ms = 8;  // 1.2 s of data
  slow.close_mid_stream = true;
  const StandInController first(slow);
  ControllerScript quick;
  quick.data_packages = 40;
  quick.close_mid_stream = true;
  const StandInController second(quick);
  const std::string out = dir.path() + "/same.txt";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::_exit(test::run(streams::record_main, {"--rtde", "127.0.0.1:" + std::to_string(first.port()), "--robot-out", out,
                                             "--force", "--duration-s", "10"}));
  }
  for (int k = 0; k < 200 && lines_of(read_all(out)) < 3; ++k) port::sleep_ms(10);  // the first is recording
  std::string err;
  ::testing::internal::CaptureStdout();
  const int code = test::run_capturing_stderr(
      streams::record_main,
      {"--rtde", "127.0.0.1:" + std::to_string(second.port()), "--robot-out", out, "--force", "--duration-s", "10"},
      &err);
  const std::string summary = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, cli::kExitOutputError);
  EXPECT_NE(err.find("another process is recording into it"), std::string::npos) << err;
  // Its summary says it wrote nothing (it said "-> same.txt: 0 data packages, 0 rows", as if
  // the file held an empty recording of its own).
  EXPECT_NE(summary.find(": nothing recorded, nothing written to " + out), std::string::npos) << summary;
  EXPECT_EQ(summary.find("data packages"), std::string::npos) << summary;
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == cli::kExitOk);
  EXPECT_EQ(lines_of(read_all(out)), 151u) << "the first recording lost rows";
}

}  // namespace
}  // namespace hivecal::record_rtde_test
