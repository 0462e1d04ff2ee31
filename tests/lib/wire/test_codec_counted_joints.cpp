// JOINT_STATE version 2, the joint record that carries its joint count (docs/wire-format.md):
// every count of the build round-trips, six joints stay the spec's version-1 packet, the
// refusals are counted, and its longer frames do not change what is oversized for the spec's.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/wire/codec.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::codec_counted_joints_test {
namespace {

using Bytes = std::vector<std::uint8_t>;

// docs/wire-format.md, "JOINT_STATE version 2": seven joints, seq 7, t = 1000000 us,
// q = (0, -pi/2, pi/2, -pi/2, -pi/2, 0, 0.5), velocities and currents zero.
constexpr const char* kSevenJointVector =
    "040201070440420f0101010102070101010101010101010121182d4454fb21f9bf182d4454fb21f93f182d4454fb21f9bf182d44"
    "54fb21f9bf0101010101010101010101010103e03f01010101010101010101010101010101010101010101010101010101010101"
    "01010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101010101"
    "051efb37fb00";

/// The records delivered (the first few).
struct Records : FrameHandler {
  void on_joint_state(const JointStateRecord& r) override {
    if (count < 8) joints[count] = r;
    ++count;
  }
  JointStateRecord joints[8];
  std::size_t count = 0;
};

Bytes encode(const JointStateRecord& record) {
  Bytes out(kMaxFrameBytes);
  std::size_t written = 0;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = encode_joint_state(record, Span<std::uint8_t>(out.data(), out.size()), &written));
  EXPECT_EQ(status, Status::ok);
  out.resize(written);
  return out;
}

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes all;
  for (const Bytes& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

DecoderStats decode(const Bytes& stream, Records* records) {
  StreamDecoder decoder;
  EXPECT_NO_HEAP(decoder.feed(stream.data(), stream.size(), *records));
  return decoder.stats();
}

JointStateRecord random_record(int joints, Random* random) {
  JointStateRecord r;
  r.sequence = static_cast<std::uint16_t>(random->below(65536));
  r.timestamp_us = random->below(1000000000);
  r.joint_count = joints;
  for (int j = 0; j < joints; ++j) {
    r.q_rad[j] = random->uniform(-6.3, 6.3);
    r.qd_rad_s[j] = random->uniform(-3.0, 3.0);
    r.current_a[j] = static_cast<float>(random->uniform(-5.0, 5.0));
  }
  return r;
}

/// The packet inside a frame (COBS decoded, delimiter dropped).
Bytes packet_of(const Bytes& frame) {
  Bytes packet(frame.size());
  std::size_t size = 0;
  EXPECT_EQ(cobs_decode(Span<const std::uint8_t>(frame.data(), frame.size() - 1),
                        Span<std::uint8_t>(packet.data(), packet.size()), &size),
            Status::ok);
  packet.resize(size);
  return packet;
}

/// The frame of `packet` with its CRC recomputed.
Bytes frame_with_crc(Bytes packet) {
  const std::size_t covered = packet.size() - kPacketCrcBytes;
  const std::uint32_t crc = crc32c(packet.data(), covered);
  for (std::size_t i = 0; i < kPacketCrcBytes; ++i) packet[covered + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  Bytes frame(cobs_max_encoded_bytes(packet.size()) + 1);
  std::size_t encoded = 0;
  EXPECT_EQ(cobs_encode(Span<const std::uint8_t>(packet.data(), packet.size()),
                        Span<std::uint8_t>(frame.data(), frame.size()), &encoded),
            Status::ok);
  frame.resize(encoded);
  frame.push_back(0);
  return frame;
}

TEST(CodecCountedJoints, EveryCountOfTheBuildRoundTripsSixStaysTheSpecsPacket) {
  Random random(53);
  for (int joints = 1; joints <= kMaxJoints; ++joints) {
    for (int trial = 0; trial < 20; ++trial) {
      const JointStateRecord sent = random_record(joints, &random);
      const Bytes frame = encode(sent);
      const Bytes packet = packet_of(frame);
      if (joints == kSixJoints) {  // the spec's packet: every reader of version 1 reads it
        EXPECT_EQ(packet[0], kProtocolVersion);
        EXPECT_EQ(frame.size(), kMaxSpecFrameBytes);
      } else {
        EXPECT_EQ(packet[0], kCountedJointsVersion);
        EXPECT_EQ(packet[12], joints);  // the count leads the payload
        EXPECT_EQ(packet.size(), kPacketHeaderBytes + counted_joint_state_payload_bytes(joints) + kPacketCrcBytes);
      }
      EXPECT_EQ(packet[1], static_cast<std::uint8_t>(PacketType::joint_state));
      Records records;
      const DecoderStats stats = decode(frame, &records);
      ASSERT_EQ(records.count, 1u) << joints;
      EXPECT_TRUE(test::same_bits(records.joints[0], sent)) << joints;
      EXPECT_EQ(stats.joint_states, 1u);
      EXPECT_EQ(stats.frames_rejected(), 0u);
    }
  }
}

TEST(CodecCountedJoints, SevenJointVectorEncodesToTheDocumentedBytes) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of " << kMaxJoints << " joints";
  JointStateRecord r;
  r.sequence = 7;
  r.timestamp_us = 1000000;
  r.joint_count = 7;
  const double q[7] = {0.0, -math::kHalfPi, math::kHalfPi, -math::kHalfPi, -math::kHalfPi, 0.0, 0.5};
  std::memcpy(r.q_rad, q, sizeof q);
  EXPECT_EQ(encode(r), test::from_hex(kSevenJointVector));
  Records records;
  (void)decode(test::from_hex(kSevenJointVector), &records);
  ASSERT_EQ(records.count, 1u);
  EXPECT_TRUE(test::same_bits(records.joints[0], r));
}

TEST(CodecCountedJoints, CountsTheBuildCannotHoldAreRefused) {
  std::uint8_t out[kMaxFrameBytes];
  std::size_t written = 1;
  for (int joints : {0, -1, kMaxJoints + 1}) {
    JointStateRecord r;
    r.joint_count = joints;
    EXPECT_EQ(encode_joint_state(r, Span<std::uint8_t>(out), &written), Status::invalid_argument) << joints;
    EXPECT_EQ(written, 0u);
  }
}

TEST(CodecCountedJoints, MalformedPacketsAreCountedByWhatIsWrong) {
  Random random(54);
  JointStateRecord r = random_record(5, &random);
  const Bytes packet = packet_of(encode(r));
  Bytes zero_joints(kPacketHeaderBytes + counted_joint_state_payload_bytes(0) + kPacketCrcBytes, 0);
  std::memcpy(zero_joints.data(), packet.data(), kPacketHeaderBytes);  // a count of 0, nothing after it
  Bytes count_says_more = packet;
  count_says_more[12] = 6;  // six joints announced, five sent
  Bytes padding = packet;
  padding[13] = 1;
  Bytes other_type = packet;
  other_type[1] = static_cast<std::uint8_t>(PacketType::tracker_point);  // version 2 defines none
  Bytes other_version = packet;
  other_version[0] = 3;
  Records records;
  const DecoderStats stats =
      decode(concat({frame_with_crc(zero_joints), frame_with_crc(count_says_more), frame_with_crc(padding),
                     frame_with_crc(other_type), frame_with_crc(other_version), encode(r)}),
             &records);
  EXPECT_EQ(records.count, 1u);
  EXPECT_EQ(stats.bad_payloads, 2u);  // no joints; non-zero padding
  EXPECT_EQ(stats.bad_lengths, 1u);
  EXPECT_EQ(stats.unknown_types, 1u);
  EXPECT_EQ(stats.bad_versions, 1u);
  EXPECT_EQ(stats.frames_ok, 1u);
}

TEST(CodecCountedJoints, OnlyTheCountedRecordMayBeLongerThanTheSpecsFrames) {
  Random random(55);
  // A version-2 record of the build's most joints (with six, one this encoder never writes: a
  // sender of version 2 only may).
  Bytes counted = packet_of(encode(random_record(1, &random)));
  counted.resize(kPacketHeaderBytes + counted_joint_state_payload_bytes(kMaxJoints) + kPacketCrcBytes, 0);
  counted[kPacketHeaderBytes] = static_cast<std::uint8_t>(kMaxJoints);
  const Bytes longest = frame_with_crc(counted);
  ASSERT_GT(longest.size(), kMaxSpecFrameBytes);
  ASSERT_EQ(longest.size(), kMaxFrameBytes);
  // A spec-type frame of the same length: the version-1 JOINT_STATE's packet with bytes
  // appended (CRC valid): oversized, as it always was.
  Bytes stretched = packet_of(encode(random_record(kSixJoints, &random)));
  stretched.insert(stretched.end() - kPacketCrcBytes, longest.size() - kMaxSpecFrameBytes, 0x55);
  Records records;
  const DecoderStats stats = decode(concat({longest, frame_with_crc(stretched), longest}), &records);
  EXPECT_EQ(records.count, 2u);
  EXPECT_EQ(stats.oversized_frames, 1u);
}

}  // namespace
}  // namespace hivecal::codec_counted_joints_test
