// Wire codec: spec test vectors both ways, every rejection path, name padding, unknown
// types, one sequence counter per stream with wrap-around, streams that start mid-frame
// (CRC-32C and COBS on their own: test_crc32c.cpp, test_cobs.cpp).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "hivecal/core/math.hpp"
#include "hivecal/wire/codec.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::codec_test {
namespace {

using Bytes = std::vector<std::uint8_t>;

// serial-protocol.md, "Test vectors" (whole frames, delimiter included).
constexpr const char* kJointStateVector =
    "040101070440420f01010101010101010101010121182d4454fb21f9bf182d4454fb21f93f182d4454fb21f9bf182d4454fb21f9bf"
    "0101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101"
    "01010101010101010101010101010101010101010101010101010502256b2800";
constexpr const char* kTrackerPointVector =
    "090102ffff15cd5b0701010101010101010103f43f010101010103e0bf010101010103e83f010101058b23b33d00";
constexpr const char* kDeviceInfoVector =
    "0301030101010101010101010202010101010e2041747261636b65722d73696d01010101010101010101010105540a210a00";

/// A copy of `base` with one byte replaced.
Bytes patched(const Bytes& base, std::size_t offset, std::uint8_t value) {
  Bytes copy = base;
  if (offset < copy.size()) copy[offset] = value;
  return copy;
}

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes all;
  for (const Bytes& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

JointStateRecord vector1_record() {
  JointStateRecord r;
  r.sequence = 7;
  r.timestamp_us = 1000000;
  const double q[kSixJoints] = {0.0, -math::kHalfPi, math::kHalfPi, -math::kHalfPi, -math::kHalfPi, 0.0};
  std::memcpy(r.q_rad, q, sizeof q);
  return r;
}

TrackerPointRecord vector2_record() {
  TrackerPointRecord r;
  r.sequence = 65535;
  r.timestamp_us = 123456789;
  r.point_m[0] = 1.25;
  r.point_m[1] = -0.5;
  r.point_m[2] = 0.75;
  r.status = 0;
  return r;
}

DeviceInfoRecord vector3_record() {
  DeviceInfoRecord r;
  r.sequence = 0;
  r.timestamp_us = 0;
  r.device_kind = static_cast<std::uint8_t>(DeviceKind::tracker);
  r.nominal_rate_hz = 10.0f;
  std::strcpy(r.name, "tracker-sim");
  return r;
}

/// Keeps the last record of each type and counts callbacks.
struct LastRecordHandler : FrameHandler {
  void on_joint_state(const JointStateRecord& r) override {
    joint = r;
    ++joints;
  }
  void on_tracker_point(const TrackerPointRecord& r) override {
    tracker = r;
    ++trackers;
  }
  void on_device_info(const DeviceInfoRecord& r) override {
    info = r;
    ++infos;
  }
  JointStateRecord joint;
  TrackerPointRecord tracker;
  DeviceInfoRecord info;
  int joints = 0;
  int trackers = 0;
  int infos = 0;
};

DecoderStats decode_all(const Bytes& stream, FrameHandler& handler) {
  StreamDecoder decoder;
  EXPECT_NO_HEAP(decoder.feed(stream.data(), stream.size(), handler));
  return decoder.stats();
}

/// Builds a CRC-valid frame from packet bytes (header + payload); the CRC is appended here.
Bytes frame_of_packet(Bytes packet) {
  std::uint32_t crc = 0;
  EXPECT_NO_HEAP(crc = crc32c(packet.data(), packet.size()));
  for (int i = 0; i < 4; ++i) packet.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));
  Bytes frame(cobs_max_encoded_bytes(packet.size()) + 1);
  std::size_t written = 0;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = cobs_encode(Span<const std::uint8_t>(packet.data(), packet.size()),
                                      Span<std::uint8_t>(frame.data(), frame.size()), &written));
  EXPECT_EQ(status, Status::ok);
  frame.resize(written);
  frame.push_back(0);
  return frame;
}

/// The packet (CRC excluded) of an encoded frame.
Bytes packet_of_frame(const Bytes& frame) {
  Bytes packet(frame.size());
  std::size_t written = 0;
  EXPECT_EQ(test::no_heap([&] {
              return cobs_decode(Span<const std::uint8_t>(frame.data(), frame.size() - 1),
                                 Span<std::uint8_t>(packet.data(), packet.size()), &written);
            }),
            Status::ok);
  packet.resize(written - 4);
  return packet;
}

TEST(CodecVectors, DecodeToTheStatedValues) {
  LastRecordHandler handler;
  const Bytes stream = concat(
      {test::from_hex(kJointStateVector), test::from_hex(kTrackerPointVector), test::from_hex(kDeviceInfoVector)});
  const DecoderStats stats = decode_all(stream, handler);
  ASSERT_EQ(handler.joints, 1);
  ASSERT_EQ(handler.trackers, 1);
  ASSERT_EQ(handler.infos, 1);
  EXPECT_EQ(stats.frames_ok, 3u);
  EXPECT_EQ(stats.frames_rejected(), 0u);
  EXPECT_EQ(stats.bytes_accepted, stream.size());

  EXPECT_EQ(handler.joint.sequence, 7);
  EXPECT_EQ(handler.joint.timestamp_us, 1000000u);
  const double q[kSixJoints] = {0.0, -1.5707963267948966, 1.5707963267948966, -1.5707963267948966, -1.5707963267948966,
                                0.0};
  for (int j = 0; j < kSixJoints; ++j) {
    EXPECT_EQ(handler.joint.q_rad[j], q[j]) << j;
    EXPECT_EQ(handler.joint.qd_rad_s[j], 0.0);
    EXPECT_EQ(handler.joint.current_a[j], 0.0f);
  }
  EXPECT_EQ(handler.joint.q_rad[1], -math::kHalfPi);

  EXPECT_EQ(handler.tracker.sequence, 65535);
  EXPECT_EQ(handler.tracker.timestamp_us, 123456789u);
  EXPECT_EQ(handler.tracker.point_m[0], 1.25);
  EXPECT_EQ(handler.tracker.point_m[1], -0.5);
  EXPECT_EQ(handler.tracker.point_m[2], 0.75);
  EXPECT_EQ(handler.tracker.status, 0);
  EXPECT_TRUE(handler.tracker.is_valid());

  EXPECT_EQ(handler.info.sequence, 0);
  EXPECT_EQ(handler.info.timestamp_us, 0u);
  EXPECT_EQ(handler.info.device_kind, static_cast<std::uint8_t>(DeviceKind::tracker));
  EXPECT_EQ(handler.info.nominal_rate_hz, 10.0f);
  EXPECT_STREQ(handler.info.name, "tracker-sim");
}

template <typename Record>
Bytes encode(const Record& record, Status (*encoder)(const Record&, Span<std::uint8_t>, std::size_t*)) {
  Bytes out(kMaxFrameBytes);
  std::size_t written = 0;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = encoder(record, Span<std::uint8_t>(out.data(), out.size()), &written));
  EXPECT_EQ(status, Status::ok);
  out.resize(written);
  return out;
}

TEST(CodecVectors, EncodeToTheExactBytes) {
  EXPECT_EQ(encode(vector1_record(), encode_joint_state), test::from_hex(kJointStateVector));
  EXPECT_EQ(encode(vector2_record(), encode_tracker_point), test::from_hex(kTrackerPointVector));
  EXPECT_EQ(encode(vector3_record(), encode_device_info), test::from_hex(kDeviceInfoVector));
  EXPECT_EQ(test::from_hex(kJointStateVector).size(), kMaxSpecFrameBytes);
}

TEST(CodecEncode, RefusesShortBuffersAndNullOutput) {
  const Bytes expected = test::from_hex(kTrackerPointVector);
  Bytes out(expected.size() - 1, 0x5A);
  std::size_t written = 99;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = encode_tracker_point(vector2_record(), Span<std::uint8_t>(out.data(), out.size()), &written));
  EXPECT_EQ(status, Status::buffer_too_small);
  EXPECT_EQ(written, 0u);
  EXPECT_EQ(std::count(out.begin(), out.end(), 0x5A), static_cast<long>(out.size()));  // untouched
  out.resize(expected.size());
  EXPECT_EQ(test::no_heap([&] {
              return encode_tracker_point(vector2_record(), Span<std::uint8_t>(out.data(), out.size()), &written);
            }),
            Status::ok);
  EXPECT_EQ(out, expected);
  EXPECT_EQ(test::no_heap([&] {
              return encode_tracker_point(vector2_record(), Span<std::uint8_t>(out.data(), out.size()), nullptr);
            }),
            Status::invalid_argument);
  EXPECT_EQ(test::no_heap([&] {
              return encode_joint_state(vector1_record(), Span<std::uint8_t>(out.data(), out.size()), &written);
            }),
            Status::buffer_too_small);
}

TEST(CodecDeviceInfo, NamePaddingBothWays) {
  // Encoding pads with 0x00 whatever follows the terminator in the record.
  DeviceInfoRecord record = vector3_record();
  std::memset(record.name + 12, 'x', 10);  // garbage after the NUL at [11]
  EXPECT_EQ(encode(record, encode_device_info), test::from_hex(kDeviceInfoVector));

  // A 24-character name fills the field and comes back terminated.
  std::strcpy(record.name, "ABCDEFGHIJKLMNOPQRSTUVWX");
  LastRecordHandler handler;
  decode_all(encode(record, encode_device_info), handler);
  ASSERT_EQ(handler.infos, 1);
  EXPECT_STREQ(handler.info.name, "ABCDEFGHIJKLMNOPQRSTUVWX");
  EXPECT_EQ(handler.info.name[24], '\0');

  // Empty name: all padding.
  record.name[0] = '\0';
  decode_all(encode(record, encode_device_info), handler);
  EXPECT_STREQ(handler.info.name, "");
  EXPECT_EQ(handler.infos, 2);

  // Unterminated or non-printable names are not encodable.
  Bytes out(kMaxFrameBytes);
  std::size_t written = 0;
  std::memset(record.name, 'A', sizeof record.name);
  EXPECT_EQ(
      test::no_heap([&] { return encode_device_info(record, Span<std::uint8_t>(out.data(), out.size()), &written); }),
      Status::invalid_argument);
  std::strcpy(record.name, "bad\x1b[2Jname");
  EXPECT_EQ(
      test::no_heap([&] { return encode_device_info(record, Span<std::uint8_t>(out.data(), out.size()), &written); }),
      Status::invalid_argument);
  std::strcpy(record.name, "caf\xc3\xa9");
  EXPECT_EQ(
      test::no_heap([&] { return encode_device_info(record, Span<std::uint8_t>(out.data(), out.size()), &written); }),
      Status::invalid_argument);
}

TEST(CodecDeviceInfo, RejectsBadPaddingWithValidCrc) {
  const Bytes packet = packet_of_frame(test::from_hex(kDeviceInfoVector));
  struct Damage {
    std::size_t offset;
    std::uint8_t value;
  };
  // Name is packet bytes 20..43: a byte after the NUL, a control byte, a non-ASCII byte; kind padding 13..15.
  const Damage damages[] = {{32, 'x'}, {40, 'y'}, {22, 0x07}, {20, 0xC3}, {14, 1}};
  for (const Damage& d : damages) {
    Bytes bad = packet;
    bad[d.offset] = d.value;
    LastRecordHandler handler;
    const DecoderStats stats = decode_all(frame_of_packet(bad), handler);
    EXPECT_EQ(stats.bad_payloads, 1u) << d.offset;
    EXPECT_EQ(stats.frames_ok, 0u);
    EXPECT_EQ(handler.infos, 0);
  }
  LastRecordHandler handler;
  EXPECT_EQ(decode_all(frame_of_packet(packet), handler).frames_ok, 1u);  // the undamaged packet re-framed
}

TEST(CodecTrackerPoint, BeamLostNanAndPaddingRules) {
  TrackerPointRecord record = vector2_record();
  record.status = static_cast<std::uint8_t>(TrackerStatus::beam_lost);
  const std::uint64_t nan_bits[3] = {0x7FF8000000000001ULL, 0xFFF8000000000000ULL,
                                     0x7FF0000000000001ULL};  // last: sNaN
  std::memcpy(record.point_m, nan_bits, sizeof nan_bits);
  LastRecordHandler handler;
  decode_all(encode(record, encode_tracker_point), handler);
  ASSERT_EQ(handler.trackers, 1);
  EXPECT_TRUE(test::same_bits(handler.tracker, record));
  EXPECT_FALSE(handler.tracker.is_valid());

  Bytes packet = packet_of_frame(test::from_hex(kTrackerPointVector));
  packet[12 + 25] = 1;  // padding byte after status
  EXPECT_EQ(decode_all(frame_of_packet(packet), handler).bad_payloads, 1u);
  packet[12 + 25] = 0;
  packet[12 + 24] = 200;  // unknown status: delivered as received, not valid
  EXPECT_EQ(decode_all(frame_of_packet(packet), handler).frames_ok, 1u);
  EXPECT_EQ(handler.tracker.status, 200);
  EXPECT_FALSE(handler.tracker.is_valid());
}

TEST(CodecDecode, CountsEveryRejectionAndResynchronises) {
  const Bytes good = test::from_hex(kTrackerPointVector);
  const Bytes packet = packet_of_frame(good);
  const Bytes flipped = patched(good, 20, static_cast<std::uint8_t>(good[20] ^ 0x10));  // CRC failure
  const Bytes bad_version = patched(packet, 0, 3);
  const Bytes unknown = patched(packet, 1, 0x04);
  Bytes wrong_length = packet;
  wrong_length.push_back(0);  // TRACKER_POINT one byte too long, CRC valid
  const Bytes short_packet = frame_of_packet(Bytes{1, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0});  // 15 bytes with CRC
  const Bytes cobs_broken = {0x09, 0x01, 0x02, 0x00};                                  // code runs past the end
  const Bytes oversized(kMaxSpecFrameBytes, 0x41);                                     // 138 bytes, no delimiter
  Bytes just_fits(kMaxSpecFrameBytes - 1, 0x41);  // 137 bytes: not oversized; one COBS run, CRC wrong
  just_fits[0] = static_cast<std::uint8_t>(kMaxSpecFrameBytes - 1);
  just_fits.push_back(0);
  Bytes oversized_frame = oversized;
  oversized_frame.push_back(0);

  const Bytes stream = concat({good, flipped, good, frame_of_packet(bad_version), frame_of_packet(unknown),
                               frame_of_packet(wrong_length), short_packet, cobs_broken, oversized_frame, just_fits,
                               Bytes{0, 0, 0}, good});
  LastRecordHandler handler;
  const DecoderStats stats = decode_all(stream, handler);
  EXPECT_EQ(stats.frames_ok, 3u);
  EXPECT_EQ(stats.tracker_points, 3u);
  EXPECT_EQ(handler.trackers, 3);
  EXPECT_EQ(stats.crc_failures, 2u);  // the flipped frame and the 137 x 0x41 one
  EXPECT_EQ(stats.bad_versions, 1u);
  EXPECT_EQ(stats.unknown_types, 1u);
  EXPECT_EQ(stats.bad_lengths, 2u);
  EXPECT_EQ(stats.cobs_errors, 1u);
  EXPECT_EQ(stats.oversized_frames, 1u);
  EXPECT_EQ(stats.leading_fragments, 0u);
  EXPECT_EQ(stats.bytes_idle, 3u);
  EXPECT_EQ(stats.bytes_total, stream.size());
  EXPECT_EQ(stats.bytes_accepted, 3 * good.size());
  EXPECT_EQ(stats.bytes_accepted + stats.bytes_idle + stats.bytes_discarded + stats.bytes_pending, stats.bytes_total);
  EXPECT_EQ(stats.bytes_pending, 0u);
  // The same header (sequence 65535) five times: good, good, unknown type, wrong length, good
  // (not the CRC failure nor the other version): four repeats, each read as a restart.
  EXPECT_EQ(stats.sequence_resets, 4u);
  EXPECT_EQ(stats.packets_lost, 0u);
}

TEST(CodecDecode, UnknownTypesAreSkippedAndCounted) {
  const Bytes tracker = test::from_hex(kTrackerPointVector);
  Bytes stream;
  std::size_t unknown_bytes = 0;
  const std::uint8_t unknown_types[] = {0x00, 0x04, 0x7F, 0xFF};
  for (const std::uint8_t type : unknown_types) {
    for (const std::size_t payload_bytes : {std::size_t{0}, std::size_t{28}, std::size_t{120}}) {
      Bytes packet = {kProtocolVersion, type, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0};
      packet.resize(kPacketHeaderBytes + payload_bytes, 0x5A);
      const Bytes frame = frame_of_packet(packet);
      unknown_bytes += frame.size();
      stream = concat({stream, frame, tracker});
    }
  }
  LastRecordHandler handler;
  const DecoderStats stats = decode_all(stream, handler);
  EXPECT_EQ(stats.unknown_types, 12u);
  EXPECT_EQ(stats.frames_rejected(), 12u);
  EXPECT_EQ(stats.frames_ok, 12u);  // every known frame after an unknown one still arrives
  EXPECT_EQ(handler.trackers, 12);
  EXPECT_EQ(handler.joints + handler.infos, 0);
  EXPECT_EQ(stats.bytes_discarded, unknown_bytes);
}

TEST(CodecDecode, StreamStartingMidFrameIsNotAnError) {
  const Bytes joint = test::from_hex(kJointStateVector);
  const Bytes tracker = test::from_hex(kTrackerPointVector);
  for (std::size_t cut = 1; cut < joint.size(); ++cut) {
    const Bytes stream = concat({Bytes(joint.begin() + static_cast<long>(cut), joint.end()), tracker});
    LastRecordHandler handler;
    const DecoderStats stats = decode_all(stream, handler);
    EXPECT_EQ(handler.joints, 0) << cut;
    EXPECT_EQ(stats.frames_ok, 1u) << cut;
    const std::uint64_t leading = cut + 1 == joint.size() ? 0 : 1;  // only the delimiter left: an idle byte
    EXPECT_EQ(stats.leading_fragments, leading) << cut;
    EXPECT_EQ(stats.frames_rejected(), leading) << cut;
    EXPECT_EQ(stats.bytes_discarded + stats.bytes_idle, joint.size() - cut) << cut;
  }
  // Garbage longer than any frame before the first delimiter: still the leading fragment.
  const Bytes noise(500, 0x33);
  LastRecordHandler handler;
  DecoderStats stats = decode_all(concat({noise, Bytes{0}, tracker}), handler);
  EXPECT_EQ(stats.leading_fragments, 1u);
  EXPECT_EQ(stats.oversized_frames, 0u);
  EXPECT_EQ(stats.frames_ok, 1u);
  // The same garbage once synchronised is an oversized frame; the decoder then resynchronises.
  stats = decode_all(concat({tracker, noise, Bytes{0}, tracker}), handler);
  EXPECT_EQ(stats.oversized_frames, 1u);
  EXPECT_EQ(stats.leading_fragments, 0u);
  EXPECT_EQ(stats.frames_ok, 2u);
  EXPECT_EQ(stats.bytes_discarded, noise.size() + 1);
}

TEST(CodecDecode, UnfinishedFrameStaysPendingAndResetForgetsIt) {
  const Bytes tracker = test::from_hex(kTrackerPointVector);
  StreamDecoder decoder;
  LastRecordHandler handler;
  EXPECT_NO_HEAP(decoder.feed(tracker.data(), tracker.size() - 1, handler));
  EXPECT_EQ(decoder.stats().bytes_pending, tracker.size() - 1);
  EXPECT_EQ(handler.trackers, 0);
  EXPECT_NO_HEAP(decoder.reset());
  EXPECT_EQ(decoder.stats().bytes_total, 0u);
  const std::uint8_t zero = 0;
  EXPECT_NO_HEAP(decoder.feed(&zero, 1, handler));
  EXPECT_EQ(handler.trackers, 0);  // the pending bytes were dropped by reset()
  EXPECT_EQ(decoder.stats().bytes_idle, 1u);
  EXPECT_NO_HEAP(decoder.feed(nullptr, 10, handler));
  EXPECT_EQ(decoder.stats().bytes_total, 1u);
}

/// What one packet of a mixed test stream is.
enum class Kind { joint, tracker, info, unknown_type, wrong_length, bad_version, bad_crc };

/// One packet of a mixed test stream.
struct Packet {
  Kind kind;
  std::uint16_t sequence;
  std::uint64_t timestamp_us;
};

/// The frame of one packet: a valid one of each type, or a CRC-valid version-1 packet of an
/// unknown type (0x04) or of TRACKER_POINT one byte too long, or one that fails the version
/// or CRC check.
Bytes frame_of(const Packet& p) {
  JointStateRecord joint = vector1_record();
  TrackerPointRecord tracker = vector2_record();
  DeviceInfoRecord info = vector3_record();
  joint.sequence = tracker.sequence = info.sequence = p.sequence;
  joint.timestamp_us = tracker.timestamp_us = info.timestamp_us = p.timestamp_us;
  switch (p.kind) {
    case Kind::joint: return encode(joint, encode_joint_state);
    case Kind::tracker: return encode(tracker, encode_tracker_point);
    case Kind::info: return encode(info, encode_device_info);
    case Kind::unknown_type:
      return frame_of_packet(patched(packet_of_frame(encode(tracker, encode_tracker_point)), 1, 0x04));
    case Kind::wrong_length: {
      Bytes packet = packet_of_frame(encode(tracker, encode_tracker_point));
      packet.push_back(0);
      return frame_of_packet(packet);
    }
    case Kind::bad_version:
      return frame_of_packet(patched(packet_of_frame(encode(tracker, encode_tracker_point)), 0, 3));
    case Kind::bad_crc: {
      const Bytes frame = encode(tracker, encode_tracker_point);
      return patched(frame, 20, static_cast<std::uint8_t>(frame[20] ^ 0x10));
    }
  }
  return {};
}

Bytes frames_of(std::initializer_list<Packet> packets) {
  Bytes stream;
  for (const Packet& p : packets) {
    const Bytes frame = frame_of(p);
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  return stream;
}

/// Frames of one type with the given sequence numbers and timestamps.
Bytes tracker_frames(std::initializer_list<std::pair<std::uint16_t, std::uint64_t>> packets) {
  Bytes stream;
  for (const auto& [sequence, timestamp_us] : packets) {
    const Bytes frame = frame_of({Kind::tracker, sequence, timestamp_us});
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  return stream;
}

TEST(CodecSequence, OneCounterPerStreamWithWrapAround) {
  // One stream, one counter: wrap 65535 -> 0 is no gap; 1 -> 5 loses 3; 5 -> 65534 is a jump
  // backwards in sequence space (a restart), not 65528 lost packets.
  LastRecordHandler handler;
  const DecoderStats single = decode_all(tracker_frames({{65533, 10},
                                                         {65534, 20},
                                                         {65535, 30},
                                                         {0, 40},
                                                         {1, 50},
                                                         {5, 90},
                                                         {6, 100},
                                                         {65534, 110},
                                                         {65535, 120},
                                                         {2, 130}}),
                                         handler);
  EXPECT_EQ(single.frames_ok, 10u);
  EXPECT_EQ(single.sequence_gaps, 2u);  // 1->5, 65535->2
  EXPECT_EQ(single.packets_lost, 3u + 2u);
  EXPECT_EQ(single.sequence_resets, 1u);  // 6 -> 65534

  // The types share the counter: a decoder tracking each type on its own would see gaps in
  // every type here (joint 65534 -> 0 -> 2, tracker 65535 -> 1 -> 5, ...).
  const DecoderStats mixed = decode_all(frames_of({{Kind::info, 65533, 10},
                                                   {Kind::joint, 65534, 20},
                                                   {Kind::tracker, 65535, 30},
                                                   {Kind::joint, 0, 40},
                                                   {Kind::tracker, 1, 50},
                                                   {Kind::joint, 2, 60},
                                                   {Kind::joint, 3, 70},
                                                   {Kind::info, 4, 80},
                                                   {Kind::tracker, 5, 90}}),
                                        handler);
  EXPECT_EQ(mixed.frames_ok, 9u);
  EXPECT_EQ(mixed.joint_states, 4u);
  EXPECT_EQ(mixed.sequence_gaps + mixed.packets_lost + mixed.sequence_resets, 0u);

  // A real loss between packets of different types is counted once, with its size.
  const DecoderStats lost =
      decode_all(frames_of({{Kind::joint, 10, 10}, {Kind::tracker, 11, 20}, {Kind::joint, 14, 50}}), handler);
  EXPECT_EQ(lost.sequence_gaps, 1u);
  EXPECT_EQ(lost.packets_lost, 2u);  // 12 and 13, whatever their types were
}

TEST(CodecSequence, SkippedIntactPacketsAreNotLost) {
  // A CRC-valid version-1 packet of an unknown type, or of a known type with the wrong length,
  // was sent and took its number: skipping it is not a loss. A packet damaged in transit or
  // of another version has no header we can trust, so its number shows as lost.
  LastRecordHandler handler;
  const DecoderStats stats = decode_all(frames_of({{Kind::joint, 100, 10},
                                                   {Kind::unknown_type, 101, 20},
                                                   {Kind::joint, 102, 30},
                                                   {Kind::wrong_length, 103, 40},
                                                   {Kind::unknown_type, 104, 50},
                                                   {Kind::tracker, 105, 60},
                                                   {Kind::bad_crc, 106, 70},
                                                   {Kind::joint, 107, 80},
                                                   {Kind::bad_version, 108, 90},
                                                   {Kind::info, 109, 100}}),
                                        handler);
  EXPECT_EQ(stats.frames_ok, 5u);
  EXPECT_EQ(stats.unknown_types, 2u);
  EXPECT_EQ(stats.bad_lengths, 1u);
  EXPECT_EQ(stats.crc_failures, 1u);
  EXPECT_EQ(stats.bad_versions, 1u);
  EXPECT_EQ(stats.sequence_gaps, 2u);  // 105 -> 107 (CRC failure), 107 -> 109 (version 3)
  EXPECT_EQ(stats.packets_lost, 2u);
  EXPECT_EQ(stats.sequence_resets, 0u);

  // Skipped packets are also the base of the next comparison: an unknown-type packet after a
  // gap carries the gap, and its restart is a restart.
  const DecoderStats skipped_base = decode_all(frames_of({{Kind::joint, 1, 10},
                                                          {Kind::unknown_type, 4, 20},
                                                          {Kind::joint, 5, 30},
                                                          {Kind::unknown_type, 0, 5},
                                                          {Kind::joint, 1, 15}}),
                                               handler);
  EXPECT_EQ(skipped_base.frames_ok, 3u);
  EXPECT_EQ(skipped_base.sequence_gaps, 1u);  // 1 -> 4
  EXPECT_EQ(skipped_base.packets_lost, 2u);
  EXPECT_EQ(skipped_base.sequence_resets, 1u);  // 5 -> 0 with the clock going back
}

TEST(CodecSequence, RestartsAreNotLoss) {
  LastRecordHandler handler;
  // A restart detected by the timestamp: sequence 100 -> 120 but the clock went back, also
  // across types (one device, one clock).
  const DecoderStats restart = decode_all(tracker_frames({{100, 5000}, {120, 10}}), handler);
  EXPECT_EQ(restart.sequence_gaps, 0u);
  EXPECT_EQ(restart.packets_lost, 0u);
  EXPECT_EQ(restart.sequence_resets, 1u);
  const DecoderStats across =
      decode_all(frames_of({{Kind::joint, 100, 5000}, {Kind::info, 0, 0}, {Kind::joint, 1, 8}}), handler);
  EXPECT_EQ(across.sequence_resets, 1u);  // DEVICE_INFO of a restarted sender
  EXPECT_EQ(across.sequence_gaps + across.packets_lost, 0u);

  // Largest forward jump still read as loss: 32767 missing packets; one more is a restart.
  const DecoderStats big = decode_all(tracker_frames({{0, 1}, {32768, 2}, {32769, 3}, {100, 4}}), handler);
  EXPECT_EQ(big.sequence_gaps, 1u);
  EXPECT_EQ(big.packets_lost, 32767u);
  EXPECT_EQ(big.sequence_resets, 1u);  // 32769 -> 100: backwards
  const DecoderStats half = decode_all(tracker_frames({{0, 1}, {32769, 2}}), handler);
  EXPECT_EQ(half.packets_lost, 0u);
  EXPECT_EQ(half.sequence_resets, 1u);
}

TEST(CodecStatus, NewCodeHasAMessage) {
  EXPECT_STREQ(status_message(Status::bad_payload), "packet padding or name bytes not as specified");
}

}  // namespace
}  // namespace hivecal::codec_test
