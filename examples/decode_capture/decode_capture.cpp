// Decodes a serial capture (the raw bytes of one robot or tracker port, as `hivecal record`
// writes them) with the library's streaming decoder and prints what it holds.
//   decode_capture <file.cap>
// Without an argument it encodes a few frames in memory and decodes those instead.
#include <cstdint>
#include <cstdio>

#include "hivecal/hivecal.hpp"  // the whole library; single headers build faster

namespace {

using namespace hivecal;

/// Counts the packets and remembers the time span of each kind.
class Summary final : public FrameHandler {
 public:
  void on_joint_state(const JointStateRecord& record) override { note(record.timestamp_us, &robot_); }
  void on_tracker_point(const TrackerPointRecord& record) override {
    note(record.timestamp_us, &tracker_);
    if (!record.is_valid()) ++invalid_points_;
  }

  void print() const {
    print_span("joint states", robot_);
    print_span("tracker points", tracker_);
    std::printf("tracker points without a valid measurement: %llu\n", static_cast<unsigned long long>(invalid_points_));
  }

 private:
  struct Span_us {
    std::uint64_t first = 0;  ///< first timestamp [us]
    std::uint64_t last = 0;   ///< last timestamp [us]
    std::uint64_t count = 0;  ///< packets
  };
  static void note(std::uint64_t t_us, Span_us* span) {
    if (span->count++ == 0) span->first = t_us;
    span->last = t_us;
  }
  static void print_span(const char* what, const Span_us& span) {
    std::printf("%s: %llu over %.3f s\n", what, static_cast<unsigned long long>(span.count),
                span.count == 0 ? 0.0 : static_cast<double>(span.last - span.first) * 1e-6);
  }

  Span_us robot_;
  Span_us tracker_;
  std::uint64_t invalid_points_ = 0;
};

/// Feeds a file through the decoder in 4 kB reads: the decoder keeps no more than one frame.
bool decode_file(const char* path, StreamDecoder* decoder, Summary* summary) {
  std::FILE* file = std::fopen(path, "rb");
  if (file == nullptr) {
    std::perror(path);
    return false;
  }
  std::uint8_t chunk[4096];
  std::size_t got = 0;
  while ((got = std::fread(chunk, 1, sizeof chunk, file)) > 0) decoder->feed(chunk, got, *summary);
  const bool ok = std::ferror(file) == 0;
  std::fclose(file);
  return ok;
}

/// Three tracker frames, one of them cut short on purpose, decoded from memory.
void decode_in_memory(StreamDecoder* decoder, Summary* summary) {
  std::uint8_t stream[3 * kMaxFrameBytes];
  std::size_t used = 0;
  for (std::uint16_t i = 0; i < 3; ++i) {
    TrackerPointRecord point;
    point.sequence = i;
    point.timestamp_us = 1000000u + 100000u * i;  // 10 Hz
    point.point_m[0] = 1.0;
    point.point_m[1] = 2.0;
    point.point_m[2] = 0.001 * i;
    std::size_t written = 0;
    (void)encode_tracker_point(point, Span<std::uint8_t>(stream + used, sizeof stream - used), &written);
    used += written;
  }
  stream[used - 5] ^= 0xFF;  // corrupt the last frame: the decoder counts a CRC failure
  decoder->feed(stream, used, *summary);
}

}  // namespace

int main(int argc, char** argv) {
  StreamDecoder decoder;
  Summary summary;
  if (argc > 1) {
    if (!decode_file(argv[1], &decoder, &summary)) return 1;
  } else {
    decode_in_memory(&decoder, &summary);
  }
  summary.print();
  const DecoderStats& stats = decoder.stats();
  std::printf("frames: %llu ok, %llu rejected (%llu CRC failures), %llu packets lost in sequence gaps\n",
              static_cast<unsigned long long>(stats.frames_ok),
              static_cast<unsigned long long>(stats.frames_rejected()),
              static_cast<unsigned long long>(stats.crc_failures), static_cast<unsigned long long>(stats.packets_lost));
  return stats.frames_ok > 0 ? 0 : 1;
}
