// libFuzzer target for the stream decoder. Input: byte 0 = largest chunk - 1, byte 1 =
// chunk-size seed, the rest = the wire. The wire is decoded twice, in one call and in
// chunks, and every invariant of docs/wire-format.md is checked; any breach traps.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "hivecal/wire/codec.hpp"
#include "testkit/codec_support.hpp"

namespace {

using namespace hivecal;

void require(bool condition) {
  if (!condition) __builtin_trap();
}

/// Re-encodes every delivered record: the frame must re-verify and be found verbatim in the input.
class ReencodingHandler : public test::DigestHandler {
 public:
  ReencodingHandler(const std::uint8_t* wire, std::size_t size) : wire_(wire), size_(size) {}
  void on_joint_state(const JointStateRecord& r) override {
    DigestHandler::on_joint_state(r);
    check(r, encode_joint_state);
  }
  void on_tracker_point(const TrackerPointRecord& r) override {
    DigestHandler::on_tracker_point(r);
    check(r, encode_tracker_point);
  }
  void on_device_info(const DeviceInfoRecord& r) override {
    DigestHandler::on_device_info(r);
    check(r, encode_device_info);
  }

 private:
  template <typename Record>
  void check(const Record& record, Status (*encode)(const Record&, Span<std::uint8_t>, std::size_t*)) {
    std::uint8_t frame[kMaxFrameBytes];
    std::size_t frame_bytes = 0;
    require(encode(record, frame, &frame_bytes) == Status::ok);
    require(frame_bytes <= kMaxFrameBytes && frame[frame_bytes - 1] == 0);
    std::uint8_t packet[kMaxFrameBytes];
    std::size_t packet_bytes = 0;
    require(cobs_decode(Span<const std::uint8_t>(frame, frame_bytes - 1), packet, &packet_bytes) == Status::ok);
    require(packet_bytes >= kPacketHeaderBytes + kPacketCrcBytes);
    const std::size_t covered = packet_bytes - kPacketCrcBytes;
    const std::uint32_t sent_crc =
        static_cast<std::uint32_t>(packet[covered]) | static_cast<std::uint32_t>(packet[covered + 1]) << 8 |
        static_cast<std::uint32_t>(packet[covered + 2]) << 16 | static_cast<std::uint32_t>(packet[covered + 3]) << 24;
    require(crc32c(packet, covered) == sent_crc);
    require(found_in_wire(frame, frame_bytes));
  }
  bool found_in_wire(const std::uint8_t* frame, std::size_t frame_bytes) const {
    for (std::size_t at = 0; at + frame_bytes <= size_; ++at)
      if (std::memcmp(wire_ + at, frame, frame_bytes) == 0) return true;
    return false;
  }
  const std::uint8_t* wire_;
  std::size_t size_;
};

void check_stats(const DecoderStats& s, const std::uint8_t* wire, std::size_t size, const test::DigestHandler& h) {
  std::uint64_t zeros = 0;
  for (std::size_t i = 0; i < size; ++i) zeros += wire[i] == 0 ? 1 : 0;
  require(s.bytes_total == size);
  require(s.bytes_accepted + s.bytes_idle + s.bytes_discarded + s.bytes_pending == s.bytes_total);
  require(s.bytes_pending < kMaxFrameBytes);
  require(s.frames_ok == h.count);
  require(s.frames_ok == s.joint_states + s.tracker_points + s.device_infos);
  // Every frame but an oversized one (or an oversized leading fragment) is closed by its own 0x00.
  require(s.frames_ok + s.frames_rejected() + s.bytes_idle <= zeros + s.oversized_frames + s.leading_fragments);
  require(s.bytes_accepted <= s.frames_ok * kMaxFrameBytes);
  require(s.leading_fragments <= 1);
  // Sequenced packets: every CRC-valid version-1 packet, delivered or not; the first has no base.
  require(s.sequence_gaps + s.sequence_resets <=
          s.frames_ok + s.unknown_types + s.bad_lengths + s.bad_payloads + s.leading_fragments);
  require(s.packets_lost <= s.sequence_gaps * 0x7FFF);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::size_t max_chunk = static_cast<std::size_t>(data[0]) + 1;
  Random chunk_sizes(data[1]);
  const std::uint8_t* wire = data + 2;
  const std::size_t wire_bytes = size - 2;

  static StreamDecoder whole;  // static: as in firmware, no large objects on the stack
  whole.reset();
  ReencodingHandler checked(wire, wire_bytes);
  whole.feed(wire, wire_bytes, checked);
  check_stats(whole.stats(), wire, wire_bytes, checked);

  static StreamDecoder chunked;
  chunked.reset();
  test::DigestHandler digest;
  for (std::size_t at = 0; at < wire_bytes;) {
    std::size_t chunk = 1 + static_cast<std::size_t>(chunk_sizes.below(max_chunk));
    if (chunk > wire_bytes - at) chunk = wire_bytes - at;
    chunked.feed(wire + at, chunk, digest);
    at += chunk;
  }
  require(test::same_stats(chunked.stats(), whole.stats()));
  require(digest.count == checked.count && digest.digest.value() == checked.digest.value());
  return 0;
}
