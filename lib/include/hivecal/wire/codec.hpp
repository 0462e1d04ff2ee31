// Serial wire codec of the robot and tracker streams (docs/wire-format.md implements
// shared/spec/serial-protocol.md, version 1, and adds version 2 of JOINT_STATE, a joint record
// that carries its joint count): encoders for whole frames and a streaming decoder with a fixed
// buffer. No heap, no OS: usable in firmware as is.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/wire/cobs.hpp"
#include "hivecal/wire/crc32c.hpp"
#include "hivecal/wire/records.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/span.hpp"

namespace hivecal {

/// The spec's protocol version: every packet type of serial-protocol.md.
inline constexpr std::uint8_t kProtocolVersion = 1;
/// The version of JOINT_STATE that carries its joint count (any count up to the build's
/// kMaxJoints); version 2 defines no other type.
inline constexpr std::uint8_t kCountedJointsVersion = 2;

/// Packet type byte (offset 1 of a packet).
enum class PacketType : std::uint8_t {
  joint_state = 0x01,    ///< JointStateRecord: six joints (version 1), or its count of joints (version 2)
  tracker_point = 0x02,  ///< TrackerPointRecord
  device_info = 0x03,    ///< DeviceInfoRecord
};

inline constexpr std::size_t kPacketHeaderBytes = 12;        ///< version, type, sequence, timestamp [bytes]
inline constexpr std::size_t kPacketCrcBytes = 4;            ///< CRC-32C trailer [bytes]
inline constexpr std::size_t kJointStatePayloadBytes = 120;  ///< JOINT_STATE payload [bytes]
/// JOINT_STATE version 2 payload of `joint_count` joints: the count, 3 zero bytes, then 20 per joint [bytes].
constexpr std::size_t counted_joint_state_payload_bytes(int joint_count) {
  return 4 + 20 * static_cast<std::size_t>(joint_count);
}
inline constexpr std::size_t kTrackerPointPayloadBytes = 28;  ///< TRACKER_POINT payload [bytes]
inline constexpr std::size_t kDeviceInfoPayloadBytes = 32;    ///< DEVICE_INFO payload [bytes]
inline constexpr std::size_t kDeviceNameBytes = 24;           ///< DEVICE_INFO name field [bytes]
/// Largest packet of the spec's types (JOINT_STATE) before COBS [bytes].
inline constexpr std::size_t kMaxSpecPacketBytes = kPacketHeaderBytes + kJointStatePayloadBytes + kPacketCrcBytes;
/// Largest encoded frame of the spec's types: COBS overhead and the 0x00 delimiter included
/// [bytes] (= 138); a longer frame of these types is oversized.
inline constexpr std::size_t kMaxSpecFrameBytes = cobs_max_encoded_bytes(kMaxSpecPacketBytes) + 1;
/// Largest packet before COBS: JOINT_STATE version 2 of the build's kMaxJoints, or version 1 [bytes].
inline constexpr std::size_t kMaxPacketBytes = kPacketHeaderBytes + counted_joint_state_payload_bytes(kMaxJoints) +
                                                           kPacketCrcBytes >
                                                       kMaxSpecPacketBytes
                                                   ? kPacketHeaderBytes +
                                                         counted_joint_state_payload_bytes(kMaxJoints) + kPacketCrcBytes
                                                   : kMaxSpecPacketBytes;
/// Largest encoded frame the decoder holds: COBS overhead and the 0x00 delimiter included
/// [bytes] (182 for eight joints, 142 for six).
inline constexpr std::size_t kMaxFrameBytes = cobs_max_encoded_bytes(kMaxPacketBytes) + 1;

/// Whole frame (COBS + delimiter) of a record into `out`; *written = frame bytes: JOINT_STATE
/// version 1 for six joints (the spec's packet, which every reader of it reads), version 2 (with
/// the count) for any other count. buffer_too_small if out is shorter than the frame (nothing written);
/// invalid_argument for a joint count outside [1, kMaxJoints].
Status encode_joint_state(const JointStateRecord& record, Span<std::uint8_t> out, std::size_t* written);
/// As encode_joint_state. NaN positions (beam lost) are sent bit for bit.
Status encode_tracker_point(const TrackerPointRecord& record, Span<std::uint8_t> out, std::size_t* written);
/// As encode_joint_state; invalid_argument unless `name` is NUL-terminated printable ASCII (0x20..0x7E).
Status encode_device_info(const DeviceInfoRecord& record, Span<std::uint8_t> out, std::size_t* written);

/// Receives decoded packets; default implementations ignore them. A handler must not call
/// feed() or reset() of the decoder that is calling it.
class FrameHandler {
 public:
  /// A JOINT_STATE packet (either version) that passed every check.
  virtual void on_joint_state(const JointStateRecord& /*record*/) {}
  /// A TRACKER_POINT packet that passed every check (check is_valid() before using the point).
  virtual void on_tracker_point(const TrackerPointRecord& /*record*/) {}
  /// A DEVICE_INFO packet that passed every check.
  virtual void on_device_info(const DeviceInfoRecord& /*record*/) {}

 protected:
  ~FrameHandler() = default;
};

/// What the decoder saw. Every byte fed lands in exactly one of bytes_accepted, bytes_idle,
/// bytes_discarded, bytes_pending; every closed non-empty frame in exactly one of frames_ok
/// or the rejection counters (see frames_rejected()). docs/wire-format.md has the details.
struct DecoderStats {
  std::uint64_t bytes_total = 0;      ///< bytes fed [bytes]
  std::uint64_t bytes_accepted = 0;   ///< bytes of frames delivered, delimiters included [bytes]
  std::uint64_t bytes_idle = 0;       ///< extra 0x00 between frames [bytes]
  std::uint64_t bytes_discarded = 0;  ///< bytes of rejected or skipped frames, delimiters included [bytes]
  std::uint64_t bytes_pending = 0;    ///< bytes of the unfinished frame buffered at the end of feed() [bytes]
  std::uint64_t frames_ok = 0;        ///< packets delivered to the handler [frames]
  std::uint64_t joint_states = 0;     ///< of which JOINT_STATE, either version [frames]
  std::uint64_t tracker_points = 0;   ///< of which TRACKER_POINT [frames]
  std::uint64_t device_infos = 0;     ///< of which DEVICE_INFO [frames]
  std::uint64_t crc_failures = 0;     ///< CRC-32C mismatch [frames]
  std::uint64_t bad_lengths =
      0;  ///< shorter than header + CRC, or CRC-valid with a size not its type's (version 2: its count's) [frames]
  std::uint64_t bad_versions = 0;   ///< CRC-valid with version not 1 or 2 [frames]
  std::uint64_t unknown_types = 0;  ///< CRC-valid, a version's unknown type: skipped [frames]
  std::uint64_t bad_payloads =
      0;  ///< CRC-valid, padding not zero, name not printable ASCII, or a JOINT_STATE of 0 joints [frames]
  std::uint64_t cobs_errors = 0;       ///< malformed COBS [frames]
  std::uint64_t oversized_frames = 0;  ///< longer before a delimiter than its type's longest frame (kMaxSpecFrameBytes;
                                       ///< version 2: kMaxFrameBytes) [frames]
  std::uint64_t leading_fragments = 0;  ///< unusable bytes before the first delimiter (stream began mid-frame) [frames]
  std::uint64_t sequence_gaps =
      0;  ///< jumps forward in the stream's sequence numbers (every CRC-valid v1 or v2 packet) [events]
  std::uint64_t packets_lost = 0;     ///< packets missing in those jumps [packets]
  std::uint64_t sequence_resets = 0;  ///< sequence or timestamp went backwards (restart): no loss counted [events]

  /// Frames closed without delivery: the sum of the eight rejection counters [frames].
  std::uint64_t frames_rejected() const {
    return crc_failures + bad_lengths + bad_versions + unknown_types + bad_payloads + cobs_errors + oversized_frames +
           leading_fragments;
  }
};

/// Streaming decoder with a fixed internal buffer (kMaxFrameBytes): feed any number of
/// bytes at a time; results do not depend on how the stream is cut into calls.
class StreamDecoder {
 public:
  /// Consumes `count` bytes (ignored if bytes is nullptr) and calls `handler` for every valid packet.
  void feed(const std::uint8_t* bytes, std::size_t count, FrameHandler& handler);
  /// Counters since construction or the last reset().
  const DecoderStats& stats() const { return stats_; }
  /// Forgets the partial frame, the sequence history and the counters (a new stream starts).
  void reset();

 private:
  /// Last CRC-valid version-1 or 2 packet of the stream, whatever its type: the base for gap detection.
  struct SequenceState {
    std::uint64_t timestamp_us = 0;  ///< its timestamp [us]
    std::uint16_t sequence = 0;      ///< its sequence number
    bool seen = false;               ///< false until the stream's first such packet
  };

  void take_frame_bytes(const std::uint8_t* bytes, std::size_t count);
  void close_frame(FrameHandler& handler);
  Status decode_frame(FrameHandler& handler);
  template <typename Layout>
  Status deliver(const std::uint8_t* packet, std::size_t packet_bytes, FrameHandler& handler);
  bool oversized() const;
  void track_sequence(std::uint16_t sequence, std::uint64_t timestamp_us);
  void count_rejection(Status status);

  std::uint8_t frame_[kMaxFrameBytes - 1] = {};  ///< encoded frame so far, delimiter excluded
  std::size_t frame_bytes_ = 0;                  ///< bytes used in frame_ [bytes]
  bool discarding_ = false;                      ///< dropping an oversized frame up to the next delimiter
  bool synchronised_ = false;                    ///< a delimiter has been seen since reset
  SequenceState sequence_;                       ///< one per stream: every type shares the counter
  DecoderStats stats_;                           ///< counters
};

}  // namespace hivecal
