// Serial wire codec of the robot and tracker streams (docs/wire-format.md implements
// shared/spec/serial-protocol.md, version 1): encoders for whole frames and a
// streaming decoder with a fixed buffer. No heap, no OS: usable in firmware as is.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/wire/cobs.hpp"
#include "hivecal/wire/crc32c.hpp"
#include "hivecal/wire/records.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/span.hpp"

namespace hivecal {

/// The only protocol version this codec reads and writes.
inline constexpr std::uint8_t kProtocolVersion = 1;

/// Packet type byte (offset 1 of a packet).
enum class PacketType : std::uint8_t {
  joint_state = 0x01,    ///< JointStateRecord
  tracker_point = 0x02,  ///< TrackerPointRecord
  device_info = 0x03,    ///< DeviceInfoRecord
};

inline constexpr std::size_t kPacketHeaderBytes = 12;         ///< version, type, sequence, timestamp [bytes]
inline constexpr std::size_t kPacketCrcBytes = 4;             ///< CRC-32C trailer [bytes]
inline constexpr std::size_t kJointStatePayloadBytes = 120;   ///< JOINT_STATE payload [bytes]
inline constexpr std::size_t kTrackerPointPayloadBytes = 28;  ///< TRACKER_POINT payload [bytes]
inline constexpr std::size_t kDeviceInfoPayloadBytes = 32;    ///< DEVICE_INFO payload [bytes]
inline constexpr std::size_t kDeviceNameBytes = 24;           ///< DEVICE_INFO name field [bytes]
/// Largest packet (JOINT_STATE) before COBS [bytes].
inline constexpr std::size_t kMaxPacketBytes = kPacketHeaderBytes + kJointStatePayloadBytes + kPacketCrcBytes;
/// Largest encoded frame: COBS overhead and the 0x00 delimiter included [bytes] (= 138).
inline constexpr std::size_t kMaxFrameBytes = cobs_max_encoded_bytes(kMaxPacketBytes) + 1;

/// Whole frame (COBS + delimiter) of a record into `out`; *written = frame bytes.
/// buffer_too_small if out is shorter than the frame (nothing written).
Status encode_joint_state(const JointStateRecord& record, Span<std::uint8_t> out, std::size_t* written);
/// As encode_joint_state. NaN positions (beam lost) are sent bit for bit.
Status encode_tracker_point(const TrackerPointRecord& record, Span<std::uint8_t> out, std::size_t* written);
/// As encode_joint_state; invalid_argument unless `name` is NUL-terminated printable ASCII (0x20..0x7E).
Status encode_device_info(const DeviceInfoRecord& record, Span<std::uint8_t> out, std::size_t* written);

/// Receives decoded packets; default implementations ignore them. A handler must not call
/// feed() or reset() of the decoder that is calling it.
class FrameHandler {
 public:
  /// A JOINT_STATE packet that passed every check.
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
  std::uint64_t bytes_total = 0;        ///< bytes fed [bytes]
  std::uint64_t bytes_accepted = 0;     ///< bytes of frames delivered, delimiters included [bytes]
  std::uint64_t bytes_idle = 0;         ///< extra 0x00 between frames [bytes]
  std::uint64_t bytes_discarded = 0;    ///< bytes of rejected or skipped frames, delimiters included [bytes]
  std::uint64_t bytes_pending = 0;      ///< bytes of the unfinished frame buffered at the end of feed() [bytes]
  std::uint64_t frames_ok = 0;          ///< packets delivered to the handler [frames]
  std::uint64_t joint_states = 0;       ///< of which JOINT_STATE [frames]
  std::uint64_t tracker_points = 0;     ///< of which TRACKER_POINT [frames]
  std::uint64_t device_infos = 0;       ///< of which DEVICE_INFO [frames]
  std::uint64_t crc_failures = 0;       ///< CRC-32C mismatch [frames]
  std::uint64_t bad_lengths = 0;        ///< shorter than header + CRC, or CRC-valid with a size not its type's [frames]
  std::uint64_t bad_versions = 0;       ///< CRC-valid with version != 1 [frames]
  std::uint64_t unknown_types = 0;      ///< CRC-valid, version 1, unknown type: skipped [frames]
  std::uint64_t bad_payloads = 0;       ///< CRC-valid, padding not zero or name not printable ASCII [frames]
  std::uint64_t cobs_errors = 0;        ///< malformed COBS [frames]
  std::uint64_t oversized_frames = 0;   ///< longer than kMaxFrameBytes before a delimiter [frames]
  std::uint64_t leading_fragments = 0;  ///< unusable bytes before the first delimiter (stream began mid-frame) [frames]
  std::uint64_t sequence_gaps =
      0;  ///< jumps forward in the stream's sequence numbers (every CRC-valid v1 packet) [events]
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
  /// Last CRC-valid version-1 packet of the stream, whatever its type: the base for gap detection.
  struct SequenceState {
    std::uint64_t timestamp_us = 0;  ///< its timestamp [us]
    std::uint16_t sequence = 0;      ///< its sequence number
    bool seen = false;               ///< false until the stream's first such packet
  };

  void take_frame_bytes(const std::uint8_t* bytes, std::size_t count);
  void close_frame(FrameHandler& handler);
  Status decode_frame(FrameHandler& handler);
  template <typename Record>
  Status deliver(const std::uint8_t* packet, std::size_t packet_bytes, FrameHandler& handler);
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
