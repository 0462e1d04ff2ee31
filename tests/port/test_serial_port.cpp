// POSIX serial reader through real pseudo-terminals: partial reads, signals during waits,
// a device that vanishes and comes back, capture replay with pacing, and recording.
#include <gtest/gtest.h>

#include <pthread.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "hivecal/port/capture_file.hpp"
#include "hivecal/port/pty.hpp"
#include "hivecal/port/recorder.hpp"
#include "hivecal/port/serial_port.hpp"

namespace hivecal::port::serial_port_test {
namespace {

/// A deterministic byte pattern with every value, zeros included.
std::vector<std::uint8_t> pattern(std::size_t count, unsigned seed) {
  std::vector<std::uint8_t> bytes(count);
  unsigned x = seed;
  for (std::uint8_t& b : bytes) {
    x = x * 1103515245u + 12345u;
    b = static_cast<std::uint8_t>(x >> 16);
  }
  return bytes;
}

/// Reads from `port` until `count` bytes came, the stream ended or `limit_ms` passed.
std::vector<std::uint8_t> read_bytes(ByteSource* port, std::size_t count, int limit_ms) {
  std::vector<std::uint8_t> got;
  std::uint8_t buffer[512];
  const std::int64_t end_ms = monotonic_ms() + limit_ms;
  while (got.size() < count && monotonic_ms() < end_ms) {
    const ReadResult r = port->read(buffer, sizeof buffer, 50);
    if (r.status == ReadStatus::data) got.insert(got.end(), buffer, buffer + r.bytes);
    if (r.status == ReadStatus::end_of_stream) break;
  }
  return got;
}

/// A temporary path under the test's working directory.
std::string temp_path(const std::string& name) {
  return "hivecal_port_test_" + std::to_string(::getpid()) + "_" + name;
}

/// Runs `work` in a child process whose files may not grow beyond `max_bytes` (a full disk;
/// SIGXFSZ ignored, as hivecal has it: the write fails with EFBIG); what it returns.
std::string with_file_size_limit(rlim_t max_bytes, const std::function<std::string()>& work) {
  int report[2];
  if (::pipe(report) != 0) return "no pipe";
  const pid_t child = ::fork();
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{max_bytes, max_bytes};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    const std::string result = work();
    (void)!::write(report[1], result.data(), result.size());
    ::_exit(0);
  }
  ::close(report[1]);
  std::string result;
  char buffer[512];
  for (ssize_t got; (got = ::read(report[0], buffer, sizeof buffer)) > 0;)
    result.append(buffer, static_cast<std::size_t>(got));
  ::close(report[0]);
  ::waitpid(child, nullptr, 0);
  return result;
}

TEST(SerialPort, DeliversEveryByteOfDribbledWrites) {
  PtyPair pty;
  std::string error;
  ASSERT_TRUE(open_pty(&pty).ok()) << error;
  SerialPort port(SerialOptions{pty.slave_path, kRobotBaud});
  ASSERT_TRUE(port.open().ok()) << error;
  const std::vector<std::uint8_t> sent = pattern(20000, 7);
  std::thread writer([&] {
    std::size_t at = 0;
    std::size_t piece = 1;
    while (at < sent.size()) {
      const std::size_t n = std::min(piece, sent.size() - at);
      ASSERT_TRUE(write_all(pty.master_fd, sent.data() + at, n));
      at += n;
      piece = piece * 7 % 257 + 1;  // 1..257-byte pieces, frames cut anywhere
      if (at % 5 == 0) usleep(200);
    }
  });
  const std::vector<std::uint8_t> got = read_bytes(&port, sent.size(), 10000);
  writer.join();
  EXPECT_EQ(got, sent);
  close_pty(&pty);
}

TEST(SerialPort, ASecondReaderOfOnePortIsRefused) {
  // Two recorders (or --robot-port P --tracker-port P) would split the bytes between them.
  PtyPair pty;
  ASSERT_TRUE(open_pty(&pty).ok());
  SerialPort first(SerialOptions{pty.slave_path, kRobotBaud});
  ASSERT_TRUE(first.open().ok());
  SerialPort second(SerialOptions{pty.slave_path, kRobotBaud});
  const Error error = second.open();
  EXPECT_EQ(error.fault, Fault::input);
  EXPECT_NE(error.message.find("in use by another reader"), std::string::npos) << error.message;
  first.close();
  EXPECT_TRUE(second.open().ok());  // free again once the first lets go
  close_pty(&pty);
}

std::atomic<int> g_signals{0};
void count_signal(int) {
  g_signals.fetch_add(1);
}

TEST(SerialPort, SignalsNeitherLoseBytesNorShortenTimeouts) {
  struct sigaction action {};
  action.sa_handler = count_signal;  // no SA_RESTART: poll() and read() see EINTR
  sigemptyset(&action.sa_mask);
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  PtyPair pty;
  std::string error;
  ASSERT_TRUE(open_pty(&pty).ok()) << error;
  SerialPort port(SerialOptions{pty.slave_path, kTrackerBaud});
  ASSERT_TRUE(port.open().ok()) << error;

  const pthread_t reader = pthread_self();
  std::atomic<bool> running{true};
  g_signals = 0;
  std::thread pest([&] {
    while (running) {
      pthread_kill(reader, SIGUSR1);
      usleep(500);
    }
  });
  // Nothing to read: the timeout is honoured in full despite the signals.
  std::uint8_t buffer[64];
  const std::int64_t start_ms = monotonic_ms();
  const ReadResult idle = port.read(buffer, sizeof buffer, 150);
  EXPECT_EQ(idle.status, ReadStatus::timeout);
  EXPECT_GE(monotonic_ms() - start_ms, 150);
  // Bytes written while signals keep coming all arrive.
  const std::vector<std::uint8_t> sent = pattern(3000, 9);
  std::thread writer([&] {
    for (std::size_t at = 0; at < sent.size(); at += 100) {
      ASSERT_TRUE(write_all(pty.master_fd, sent.data() + at, 100));
      usleep(1000);
    }
  });
  const std::vector<std::uint8_t> got = read_bytes(&port, sent.size(), 10000);
  writer.join();
  running = false;
  pest.join();
  EXPECT_EQ(got, sent);
  EXPECT_GT(g_signals.load(), 10);
  sigaction(SIGUSR1, &previous, nullptr);
  close_pty(&pty);
}

TEST(SerialPort, ReopensADeviceThatVanishesAndComesBack) {
  // The port is opened through a symlink (like /dev/serial/by-id/...); the first pty goes
  // away (master closed), a new one appears under the same link.
  const std::string link = temp_path("link");
  PtyPair first;
  std::string error;
  ASSERT_TRUE(open_pty(&first).ok()) << error;
  ::unlink(link.c_str());
  ASSERT_EQ(::symlink(first.slave_path.c_str(), link.c_str()), 0);
  SerialPort port(SerialOptions{link, kRobotBaud, 10, 100});
  ASSERT_TRUE(port.open().ok()) << error;
  const std::vector<std::uint8_t> before = pattern(500, 1);
  ASSERT_TRUE(write_all(first.master_fd, before.data(), before.size()));
  EXPECT_EQ(read_bytes(&port, before.size(), 5000), before);

  close_pty(&first);
  std::uint8_t buffer[64];
  ReadResult lost = port.read(buffer, sizeof buffer, 1000);
  EXPECT_EQ(lost.status, ReadStatus::disconnected);
  EXPECT_FALSE(port.is_open());
  EXPECT_EQ(port.read(buffer, sizeof buffer, 50).status, ReadStatus::disconnected);  // link points nowhere useful

  PtyPair second;
  ASSERT_TRUE(open_pty(&second).ok()) << error;
  const std::string fresh = link + ".new";
  ASSERT_EQ(::symlink(second.slave_path.c_str(), fresh.c_str()), 0);
  ASSERT_EQ(::rename(fresh.c_str(), link.c_str()), 0);
  const std::vector<std::uint8_t> after = pattern(700, 2);
  ASSERT_TRUE(write_all(second.master_fd, after.data(), after.size()));
  EXPECT_EQ(read_bytes(&port, after.size(), 5000), after);
  EXPECT_EQ(port.reconnects(), 1u);
  EXPECT_EQ(port.disconnects(), 1u);
  close_pty(&second);
  ::unlink(link.c_str());
}

TEST(CaptureFile, ReplaysExactlyAndPaces) {
  const std::string path = temp_path("replay.cap");
  const std::vector<std::uint8_t> bytes = pattern(5000, 3);
  CaptureWriter writer;
  std::string error;
  ASSERT_TRUE(writer.open(path, true).ok()) << error;
  ASSERT_TRUE(writer.write(bytes.data(), bytes.size()).ok()) << error;
  ASSERT_TRUE(writer.close().ok()) << error;
  EXPECT_EQ(writer.bytes_written(), bytes.size());

  CaptureFileSource fast(path);
  ASSERT_TRUE(fast.open().ok()) << error;
  EXPECT_EQ(read_bytes(&fast, bytes.size() + 1, 2000), bytes);
  std::uint8_t buffer[16];
  EXPECT_EQ(fast.read(buffer, sizeof buffer, 0).status, ReadStatus::end_of_stream);

  CaptureFileSource paced(path, 20000.0);  // 5000 bytes at 20 kB/s: >= 250 ms
  ASSERT_TRUE(paced.open().ok()) << error;
  const std::int64_t start_ms = monotonic_ms();
  EXPECT_EQ(read_bytes(&paced, bytes.size(), 5000), bytes);
  EXPECT_GE(monotonic_ms() - start_ms, 240);
  ::unlink(path.c_str());
}

TEST(CaptureFile, ASecondRecorderOfTheSameFileIsRefusedEvenWithForce) {
  // Two `record ... --robot-out same.txt --force`: both wrote the file, one recording lost.
  const std::string path = temp_path("locked.cap");
  const std::vector<std::uint8_t> first_bytes = pattern(300, 8);
  CaptureWriter first;
  ASSERT_TRUE(first.open(path, true).ok());
  ASSERT_TRUE(first.write(first_bytes.data(), first_bytes.size()).ok());
  CaptureWriter second;
  const Error error = second.open(path, true);
  EXPECT_EQ(error.fault, Fault::output);
  EXPECT_NE(error.message.find("another process is recording into it"), std::string::npos) << error.message;
  ASSERT_TRUE(first.close().ok());
  CaptureFileSource replay(path);
  ASSERT_TRUE(replay.open().ok());
  EXPECT_EQ(read_bytes(&replay, first_bytes.size() + 1, 2000), first_bytes) << "the first recording was truncated";
  CaptureWriter after;  // once the first has closed, --force replaces it
  EXPECT_TRUE(after.open(path, true).ok());
  ::unlink(path.c_str());
}

TEST(CaptureFile, ARecordThatDoesNotFitIsCutOffAndTheFileEndsWhole) {
  // A full disk (here the file size limit) in the middle of a log row: the part that went in
  // is cut off again, so that every reader still takes the file.
  const std::string path = temp_path("rows.txt");
  const std::string message = with_file_size_limit(1000, [&path] {
    CaptureWriter writer;
    const std::string line = std::string(63, 'r') + "\n";
    if (!writer.open(path, true).ok()) return std::string("not opened");
    Error error;
    while (error.ok()) error = writer.write_whole(reinterpret_cast<const std::uint8_t*>(line.data()), line.size());
    (void)writer.close();
    return error.message;
  });
  EXPECT_NE(message.find("the file ends at the last whole record (960 bytes)"), std::string::npos) << message;
  CaptureFileSource replay(path);
  ASSERT_TRUE(replay.open().ok());
  EXPECT_EQ(read_bytes(&replay, 2000, 2000).size(), 960u);  // 15 rows of 64 bytes
  ::unlink(path.c_str());
}

TEST(Recorder, CopiesTwoPortsToCaptures) {
  PtyPair robot;
  PtyPair tracker;
  std::string error;
  ASSERT_TRUE(open_pty(&robot).ok()) << error;
  ASSERT_TRUE(open_pty(&tracker).ok()) << error;
  SerialPort robot_port(SerialOptions{robot.slave_path, kRobotBaud});
  SerialPort tracker_port(SerialOptions{tracker.slave_path, kTrackerBaud});
  ASSERT_TRUE(robot_port.open().ok() && tracker_port.open().ok()) << error;
  const std::string robot_path = temp_path("robot.cap");
  const std::string tracker_path = temp_path("tracker.cap");
  CaptureWriter robot_file;
  CaptureWriter tracker_file;
  ASSERT_TRUE(robot_file.open(robot_path, true).ok() && tracker_file.open(tracker_path, true).ok()) << error;
  const std::vector<std::uint8_t> robot_bytes = pattern(30000, 4);
  const std::vector<std::uint8_t> tracker_bytes = pattern(4000, 5);
  volatile std::sig_atomic_t stop = 0;
  std::thread devices([&] {
    for (std::size_t i = 0; i < 10; ++i) {
      ASSERT_TRUE(write_all(robot.master_fd, robot_bytes.data() + i * 3000, 3000));
      ASSERT_TRUE(write_all(tracker.master_fd, tracker_bytes.data() + i * 400, 400));
      usleep(5000);
    }
    usleep(300000);
    stop = 1;
  });
  RecordStats stats;
  EXPECT_TRUE(
      record_streams({&robot_port, &tracker_port}, {&robot_file, &tracker_file}, &stop, RecordOptions(), &stats).ok());
  devices.join();
  EXPECT_TRUE(stats.ended_by_stop_flag);
  EXPECT_EQ(stats.bytes[0], robot_bytes.size());
  EXPECT_EQ(stats.bytes[1], tracker_bytes.size());
  CaptureFileSource robot_replay(robot_path);
  CaptureFileSource tracker_replay(tracker_path);
  ASSERT_TRUE(robot_replay.open().ok() && tracker_replay.open().ok()) << error;
  EXPECT_EQ(read_bytes(&robot_replay, robot_bytes.size() + 1, 2000), robot_bytes);
  EXPECT_EQ(read_bytes(&tracker_replay, tracker_bytes.size() + 1, 2000), tracker_bytes);
  close_pty(&robot);
  close_pty(&tracker);
  ::unlink(robot_path.c_str());
  ::unlink(tracker_path.c_str());
}

// A capture that cannot take every byte (a full disk; here the file size limit) is counted
// as what it holds, and what was read but not written is counted apart: the stats line never
// overstates the capture.
TEST(Recorder, CountsWhatTheCaptureHoldsWhenTheDiskIsFull) {
  const std::string source_path = temp_path("full-source.cap");
  const std::string capture_path = temp_path("full-capture.cap");
  const std::vector<std::uint8_t> bytes = pattern(5000, 7);
  CaptureWriter source_writer;
  ASSERT_TRUE(source_writer.open(source_path, true).ok());
  ASSERT_TRUE(source_writer.write(bytes.data(), bytes.size()).ok());
  ASSERT_TRUE(source_writer.close().ok());
  const std::string reported = with_file_size_limit(1000, [&] {
    CaptureFileSource source(source_path);
    CaptureWriter writer;
    std::uint64_t out[3] = {0, 0, 0};
    if (source.open().ok() && writer.open(capture_path, true).ok()) {
      RecordStats stats;
      out[0] = record_streams({&source}, {&writer}, nullptr, RecordOptions(), &stats).ok() ? 1 : 0;
      out[1] = stats.bytes[0];
      out[2] = stats.bytes_read[0];
    }
    return std::string(reinterpret_cast<const char*>(out), sizeof out);
  });
  std::uint64_t got[3] = {9, 0, 0};
  ASSERT_EQ(reported.size(), sizeof got);
  std::memcpy(got, reported.data(), sizeof got);
  EXPECT_EQ(got[0], 0u) << "the failed write is an error";
  EXPECT_EQ(got[1], 1000u) << "bytes in the capture";
  EXPECT_EQ(got[2], bytes.size()) << "bytes read";
  CaptureFileSource replay(capture_path);
  ASSERT_TRUE(replay.open().ok());
  EXPECT_EQ(read_bytes(&replay, bytes.size(), 2000).size(), got[1]);
  ::unlink(source_path.c_str());
  ::unlink(capture_path.c_str());
}

}  // namespace
}  // namespace hivecal::port::serial_port_test
