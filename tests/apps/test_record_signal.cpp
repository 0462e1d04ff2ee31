// `hivecal record` stopped by SIGTERM or SIGHUP (a closed terminal) in the middle of a frame:
// the child exits cleanly and its capture holds every byte it had read, decoding up to the cut.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <string>
#include <vector>

#include "commands/streams.hpp"
#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/pty.hpp"
#include "hivecal/wire/codec.hpp"
#include "sim/sim_model.hpp"
#include "sim/sim_outputs.hpp"

namespace hivecal::record_signal_test {
namespace {

/// Counts what a decoder delivers.
struct Counter final : FrameHandler {
  std::size_t joints = 0;
  void on_joint_state(const JointStateRecord&) override { ++joints; }
};

long long file_size(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 ? static_cast<long long>(info.st_size) : -1;
}

/// Records a pty in a child, sends it 300.5 frames, stops it with `signal`, checks the capture.
void record_and_stop(int signal) {
  port::PtyPair pty;
  std::string error;
  ASSERT_TRUE(port::open_pty(&pty).ok()) << error;
  const std::string capture = "hivecal_sigterm_" + std::to_string(::getpid()) + ".cap";

  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::vector<std::string> args = {"--robot-port", pty.slave_path, "--robot-out", capture};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    ::_exit(streams::record_main(static_cast<int>(argv.size()), argv.data()));
  }

  // 300 joint-state frames, then the first half of one more: the cut falls mid-frame.
  sim::SimConfig config;
  config.waypoint_count = 3;
  config.duration_s = 20.0;
  const sim::Session session(config);
  sim::RobotStream stream(session);
  std::vector<std::uint8_t> bytes;
  JointStateRecord record;
  for (int i = 0; i < 301 && stream.next(&record); ++i) ASSERT_TRUE(sim::append_frame(record, &bytes));
  std::vector<std::uint8_t> last;
  ASSERT_TRUE(sim::append_frame(record, &last));
  const std::size_t sent = bytes.size() - last.size() / 2;
  port::sleep_ms(200);  // the child opens the port
  ASSERT_TRUE(port::write_all(pty.master_fd, bytes.data(), sent));
  const std::int64_t give_up_ms = port::monotonic_ms() + 20000;
  while (file_size(capture) < static_cast<long long>(sent) && port::monotonic_ms() < give_up_ms) port::sleep_ms(10);
  ASSERT_EQ(::kill(child, signal), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);

  std::FILE* file = std::fopen(capture.c_str(), "rb");
  ASSERT_NE(file, nullptr);
  std::vector<std::uint8_t> captured(sent + 16);
  captured.resize(std::fread(captured.data(), 1, captured.size(), file));
  std::fclose(file);
  ASSERT_EQ(captured.size(), sent);
  EXPECT_TRUE(std::equal(captured.begin(), captured.end(), bytes.begin()));
  StreamDecoder decoder;
  Counter counter;
  decoder.feed(captured.data(), captured.size(), counter);
  EXPECT_EQ(counter.joints, 300u);
  EXPECT_EQ(decoder.stats().frames_rejected(), 0u);
  EXPECT_GT(decoder.stats().bytes_pending, 0u);  // the half frame, neither delivered nor an error
  port::close_pty(&pty);
  ::unlink(capture.c_str());
}

TEST(RecordCommand, SigtermKeepsEveryByteReadAndTheCaptureDecodesUpToTheCut) {
  record_and_stop(SIGTERM);
}

TEST(RecordCommand, SighupEndsItAsCleanlyAsSigterm) {
  record_and_stop(SIGHUP);
}

}  // namespace
}  // namespace hivecal::record_signal_test
