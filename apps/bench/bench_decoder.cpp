// StreamDecoder throughput on synthetic robot and tracker captures (docs/wire-format.md).
//   bench_decoder              time each capture for ~1 s: MB/s and frames/s
//   bench_decoder --count R    decode the robot capture R times, untimed: for instruction
//                              counts (callgrind, or the QEMU plugin with R = 1 and R = 11)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "hivecal/core/random.hpp"
#include "hivecal/wire/codec.hpp"

namespace {

using namespace hivecal;

constexpr std::size_t kCaptureFrames = 10000;
constexpr std::size_t kChunkBytes = 256;  // a typical UART DMA half-buffer

/// A capture: frames back to back, as a port delivers them.
struct Capture {
  std::uint8_t bytes[kCaptureFrames * kMaxFrameBytes];
  std::size_t size = 0;
  std::size_t frames = 0;
};

template <typename Record>
void append(Capture* capture, Status (*encode)(const Record&, Span<std::uint8_t>, std::size_t*), const Record& record) {
  std::size_t written = 0;
  if (encode(record, Span<std::uint8_t>(capture->bytes + capture->size, kMaxFrameBytes), &written) != Status::ok)
    std::abort();
  capture->size += written;
  ++capture->frames;
}

DeviceInfoRecord device_info(DeviceKind kind, float rate_hz, const char* name, std::uint16_t sequence,
                             std::uint64_t timestamp_us) {
  DeviceInfoRecord info;
  info.sequence = sequence;
  info.timestamp_us = timestamp_us;
  info.device_kind = static_cast<std::uint8_t>(kind);
  info.nominal_rate_hz = rate_hz;
  std::strncpy(info.name, name, kDeviceNameBytes);
  return info;
}

/// Every packet of a capture takes the stream's next sequence number, whatever its type.
std::uint16_t next_sequence(const Capture& capture) {
  return static_cast<std::uint16_t>(capture.frames);
}

/// 125 Hz joint states with a DEVICE_INFO once a second.
void make_robot_capture(Capture* capture) {
  Random random(1);
  JointStateRecord record;
  for (std::size_t i = 0; capture->frames < kCaptureFrames; ++i) {
    if (i % 125 == 0)
      append(capture, encode_device_info,
             device_info(DeviceKind::robot, 125.0f, "ur5-sim", next_sequence(*capture), 8000 * i));
    record.sequence = next_sequence(*capture);
    record.timestamp_us = 8000 * i;
    for (int j = 0; j < kSixJoints; ++j) {
      record.q_rad[j] = random.uniform(-3.0, 3.0);
      record.qd_rad_s[j] = random.uniform(-1.0, 1.0);
      record.current_a[j] = static_cast<float>(random.uniform(-2.0, 2.0));
    }
    append(capture, encode_joint_state, record);
  }
}

/// 10 Hz tracker points (some beam-lost) with a DEVICE_INFO once a second.
void make_tracker_capture(Capture* capture) {
  Random random(2);
  TrackerPointRecord record;
  for (std::size_t i = 0; capture->frames < kCaptureFrames; ++i) {
    if (i % 10 == 0)
      append(capture, encode_device_info,
             device_info(DeviceKind::tracker, 10.0f, "tracker-sim", next_sequence(*capture), 100000 * i));
    record.sequence = next_sequence(*capture);
    record.timestamp_us = 100000 * i;
    record.status = random.below(50) == 0 ? 1 : 0;
    for (double& c : record.point_m) c = random.uniform(-5.0, 5.0);
    append(capture, encode_tracker_point, record);
  }
}

struct CountingHandler : FrameHandler {
  void on_joint_state(const JointStateRecord& r) override { sum += r.sequence; }
  void on_tracker_point(const TrackerPointRecord& r) override { sum += r.sequence; }
  void on_device_info(const DeviceInfoRecord& r) override { sum += r.device_kind; }
  std::uint64_t sum = 0;  ///< keeps the records observable
};

/// Feeds the capture once in kChunkBytes pieces; returns frames decoded.
std::uint64_t decode_once(const Capture& capture, StreamDecoder* decoder, CountingHandler& handler) {
  const std::uint64_t before = decoder->stats().frames_ok;
  for (std::size_t at = 0; at < capture.size; at += kChunkBytes) {
    const std::size_t chunk = capture.size - at < kChunkBytes ? capture.size - at : kChunkBytes;
    decoder->feed(capture.bytes + at, chunk, handler);
  }
  return decoder->stats().frames_ok - before;
}

void time_capture(const char* name, const Capture& capture) {
  static StreamDecoder decoder;
  decoder.reset();
  CountingHandler handler;
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  double elapsed_s = 0.0;
  std::uint64_t frames = 0;
  std::uint64_t bytes = 0;
  while (elapsed_s < 1.0) {
    frames += decode_once(capture, &decoder, handler);
    bytes += capture.size;
    elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  }
  const DecoderStats& s = decoder.stats();
  if (s.frames_rejected() != 0 || s.packets_lost != 0 || frames == 0) {
    std::fprintf(stderr, "bench_decoder: %s capture did not decode cleanly\n", name);
    std::exit(1);
  }
  std::printf("%-8s %6.1f B/frame  %8.1f MB/s  %10.0f frames/s  %6.1f ns/frame  (check %llu)\n", name,
              static_cast<double>(capture.size) / static_cast<double>(capture.frames),
              static_cast<double>(bytes) / elapsed_s / 1e6, static_cast<double>(frames) / elapsed_s,
              elapsed_s * 1e9 / static_cast<double>(frames), static_cast<unsigned long long>(handler.sum));
}

Capture g_robot;
Capture g_tracker;

}  // namespace

int main(int argc, char** argv) {
  make_robot_capture(&g_robot);
  if (argc == 3 && std::strcmp(argv[1], "--count") == 0) {
    const long repeats = std::strtol(argv[2], nullptr, 10);
    static StreamDecoder decoder;
    CountingHandler handler;
    std::uint64_t frames = 0;
    for (long r = 0; r < repeats; ++r) frames += decode_once(g_robot, &decoder, handler);
    std::printf("robot capture: %zu bytes, %zu frames per pass; decoded %llu frames (check %llu)\n", g_robot.size,
                g_robot.frames, static_cast<unsigned long long>(frames), static_cast<unsigned long long>(handler.sum));
    return frames == g_robot.frames * static_cast<std::uint64_t>(repeats) ? 0 : 1;
  }
  make_tracker_capture(&g_tracker);
  time_capture("robot", g_robot);
  time_capture("tracker", g_tracker);
  return 0;
}
