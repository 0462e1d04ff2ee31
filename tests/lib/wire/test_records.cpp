// Decoded stream records (wire/records.hpp): zero defaults, field widths and enum values as in
// serial-protocol.md's tables, u16 sequence wrap-around, is_valid() true for status 0 only
// (whatever the other fields), plain copies that keep NaN payloads bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "hivecal/core/random.hpp"
#include "hivecal/wire/codec.hpp"
#include "hivecal/wire/records.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::records_test {
namespace {

/// True when every element of `values` equals zero.
template <typename T, std::size_t N>
bool all_zero(const T (&values)[N]) {
  for (const T& v : values) {
    if (v != T{}) return false;
  }
  return true;
}

TEST(Records, DefaultsAreAllZero) {
  const JointStateRecord joint;
  EXPECT_EQ(joint.sequence, 0);
  EXPECT_EQ(joint.timestamp_us, 0u);
  EXPECT_TRUE(all_zero(joint.q_rad));
  EXPECT_TRUE(all_zero(joint.qd_rad_s));
  EXPECT_TRUE(all_zero(joint.current_a));

  const TrackerPointRecord point;
  EXPECT_EQ(point.sequence, 0);
  EXPECT_EQ(point.timestamp_us, 0u);
  EXPECT_TRUE(all_zero(point.point_m));
  EXPECT_EQ(point.status, 0);
  EXPECT_TRUE(point.is_valid());  // status 0 is a measurement

  const DeviceInfoRecord info;
  EXPECT_EQ(info.sequence, 0);
  EXPECT_EQ(info.timestamp_us, 0u);
  EXPECT_EQ(info.device_kind, 0);  // neither robot (1) nor tracker (2)
  EXPECT_EQ(info.nominal_rate_hz, 0.0f);
  EXPECT_TRUE(all_zero(info.name));  // empty and NUL-padded
  EXPECT_STREQ(info.name, "");
}

TEST(Records, FieldWidthsMatchTheSpecTables) {
  // Header: u16 sequence, u64 microsecond timestamp.
  static_assert(std::is_same_v<decltype(JointStateRecord::sequence), std::uint16_t>, "u16");
  static_assert(std::is_same_v<decltype(TrackerPointRecord::sequence), std::uint16_t>, "u16");
  static_assert(std::is_same_v<decltype(DeviceInfoRecord::sequence), std::uint16_t>, "u16");
  static_assert(std::is_same_v<decltype(JointStateRecord::timestamp_us), std::uint64_t>, "u64");
  static_assert(std::is_same_v<decltype(TrackerPointRecord::timestamp_us), std::uint64_t>, "u64");
  static_assert(std::is_same_v<decltype(DeviceInfoRecord::timestamp_us), std::uint64_t>, "u64");
  // JOINT_STATE, 120 bytes: 6 x f64 position, 6 x f64 velocity, 6 x f32 current.
  EXPECT_EQ(kSixJoints, 6);
  static_assert(std::is_same_v<std::remove_extent_t<decltype(JointStateRecord::q_rad)>, double>, "f64");
  static_assert(std::is_same_v<std::remove_extent_t<decltype(JointStateRecord::qd_rad_s)>, double>, "f64");
  static_assert(std::is_same_v<std::remove_extent_t<decltype(JointStateRecord::current_a)>, float>, "f32");
  static_assert(std::numeric_limits<double>::is_iec559 && sizeof(double) == 8, "IEEE-754 binary64");
  static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "IEEE-754 binary32");
  // The record holds the build's joints (version 2 carries up to kMaxJoints); six of each is 120.
  const JointStateRecord joint;
  EXPECT_EQ(joint.joint_count, 6);
  EXPECT_EQ(std::extent_v<decltype(JointStateRecord::q_rad)>, static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ(std::extent_v<decltype(JointStateRecord::qd_rad_s)>, static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ(std::extent_v<decltype(JointStateRecord::current_a)>, static_cast<std::size_t>(kMaxJoints));
  EXPECT_EQ((sizeof joint.q_rad + sizeof joint.qd_rad_s + sizeof joint.current_a) / kMaxJoints * 6, 120u);
  EXPECT_EQ(kJointStatePayloadBytes, 120u);
  EXPECT_EQ(counted_joint_state_payload_bytes(6), 124u);  // the count and its padding first
  // TRACKER_POINT, 28 bytes: 3 x f64 position, u8 status, 3 bytes padding.
  const TrackerPointRecord point;
  static_assert(std::is_same_v<std::remove_extent_t<decltype(TrackerPointRecord::point_m)>, double>, "f64");
  static_assert(std::is_same_v<decltype(TrackerPointRecord::status), std::uint8_t>, "u8");
  EXPECT_EQ(sizeof point.point_m + sizeof point.status + 3, 28u);
  // DEVICE_INFO, 32 bytes: u8 kind, 3 bytes zero, f32 rate, 24 bytes of name (+ our NUL).
  const DeviceInfoRecord info;
  static_assert(std::is_same_v<decltype(DeviceInfoRecord::device_kind), std::uint8_t>, "u8");
  static_assert(std::is_same_v<decltype(DeviceInfoRecord::nominal_rate_hz), float>, "f32");
  EXPECT_EQ(sizeof info.name, 24u + 1u);
  EXPECT_EQ(sizeof info.device_kind + 3 + sizeof info.nominal_rate_hz + (sizeof info.name - 1), 32u);
  // A 24-character name fits with its terminator.
  DeviceInfoRecord named;
  std::memcpy(named.name, "ABCDEFGHIJKLMNOPQRSTUVWX", 25);
  EXPECT_EQ(std::strlen(named.name), 24u);
}

TEST(Records, EnumValuesAreTheWireValues) {
  EXPECT_EQ(static_cast<int>(TrackerStatus::valid), 0);
  EXPECT_EQ(static_cast<int>(TrackerStatus::beam_lost), 1);
  EXPECT_EQ(static_cast<int>(TrackerStatus::unstable), 2);
  EXPECT_EQ(static_cast<int>(DeviceKind::robot), 1);
  EXPECT_EQ(static_cast<int>(DeviceKind::tracker), 2);
  static_assert(sizeof(TrackerStatus) == 1 && sizeof(DeviceKind) == 1, "one byte on the wire");
}

TEST(Records, SequenceNumbersWrapFrom65535ToZero) {
  JointStateRecord joint;
  TrackerPointRecord point;
  DeviceInfoRecord info;
  joint.sequence = point.sequence = info.sequence = 65535;
  ++joint.sequence;
  ++point.sequence;
  ++info.sequence;
  EXPECT_EQ(joint.sequence, 0);
  EXPECT_EQ(point.sequence, 0);
  EXPECT_EQ(info.sequence, 0);
  // Timestamps hold any u64 microsecond count (clocks that started long ago).
  joint.timestamp_us = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(joint.timestamp_us, 18446744073709551615ULL);
}

TEST(Records, IsValidOnlyForStatusZero) {
  // Every status byte: 0 valid; 1 beam lost, 2 unstable and any other value not valid.
  TrackerPointRecord point;
  point.point_m[0] = 1.25;
  point.point_m[1] = -0.5;
  point.point_m[2] = 0.75;
  int valid = 0;
  for (int status = 0; status < 256; ++status) {
    point.status = static_cast<std::uint8_t>(status);
    bool is_valid = false;
    EXPECT_NO_HEAP(is_valid = point.is_valid());
    EXPECT_EQ(is_valid, status == 0) << status;
    valid += is_valid ? 1 : 0;
  }
  EXPECT_EQ(valid, 1);
  point.status = static_cast<std::uint8_t>(TrackerStatus::beam_lost);
  EXPECT_FALSE(point.is_valid());
  point.status = static_cast<std::uint8_t>(TrackerStatus::unstable);
  EXPECT_FALSE(point.is_valid());
}

TEST(Records, IsValidReadsTheStatusAlone) {
  // The position, sequence and time do not matter: a NaN point with status 0 is still
  // "valid" by status (the extraction drops it as non_finite_point), a finite one with
  // status 1 is not.
  Random random(61);
  for (int trial = 0; trial < 2000; ++trial) {
    TrackerPointRecord point;
    point.sequence = static_cast<std::uint16_t>(random.next());
    point.timestamp_us = random.next();
    for (double& c : point.point_m) c = test::random_bits_f64(&random);  // any bits: NaN, Inf included
    const std::uint64_t pick = random.below(4);
    point.status = static_cast<std::uint8_t>(pick < 2 ? pick : random.below(256));
    EXPECT_EQ(point.is_valid(), point.status == 0) << trial;
  }
  TrackerPointRecord nan_point;
  nan_point.point_m[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(nan_point.is_valid());
}

TEST(Records, CopiesArePlainAndKeepEveryBit) {
  // Queues and rings copy records by value with no heap; NaN payloads (beam lost) survive.
  static_assert(std::is_trivially_copyable_v<JointStateRecord>, "plain copy");
  static_assert(std::is_trivially_copyable_v<TrackerPointRecord>, "plain copy");
  static_assert(std::is_trivially_copyable_v<DeviceInfoRecord>, "plain copy");
  static_assert(std::is_standard_layout_v<TrackerPointRecord>, "standard layout");
  Random random(62);
  for (int trial = 0; trial < 200; ++trial) {
    const auto sequence = static_cast<std::uint16_t>(random.next());
    const std::uint64_t time_us = random.next();
    const JointStateRecord joint = test::random_joint_state(&random, sequence, time_us);
    const TrackerPointRecord point = test::random_tracker_point(&random, sequence, time_us);
    const DeviceInfoRecord info = test::random_device_info(&random, sequence, time_us);
    JointStateRecord joint_copy;
    TrackerPointRecord point_copy;
    DeviceInfoRecord info_copy;
    EXPECT_NO_HEAP(joint_copy = joint);
    EXPECT_NO_HEAP(point_copy = point);
    EXPECT_NO_HEAP(info_copy = info);
    EXPECT_TRUE(test::same_bits(joint_copy, joint)) << trial;
    EXPECT_TRUE(test::same_bits(point_copy, point)) << trial;
    EXPECT_TRUE(test::same_bits(info_copy, info)) << trial;
  }
  // A signalling NaN payload, copied through a record, keeps its bits.
  TrackerPointRecord lost;
  lost.status = static_cast<std::uint8_t>(TrackerStatus::beam_lost);
  const std::uint64_t snan = 0x7FF0000000000001ULL;
  std::memcpy(&lost.point_m[2], &snan, sizeof snan);
  const TrackerPointRecord copy = lost;
  std::uint64_t bits = 0;
  std::memcpy(&bits, &copy.point_m[2], sizeof bits);
  EXPECT_EQ(bits, snan);
  EXPECT_TRUE(std::isnan(copy.point_m[2]));
  EXPECT_FALSE(copy.is_valid());
}

}  // namespace
}  // namespace hivecal::records_test
