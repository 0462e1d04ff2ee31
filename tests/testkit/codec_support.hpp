// Test helpers for the wire codec, shared by the unit tests and the fuzz target: bitwise
// record comparison, digests of records and counters, random records. Header-only, no gtest.
#pragma once

#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

#include "hivecal/wire/codec.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/core/random.hpp"

namespace hivecal::test {

// Counters are compared and hashed as an array of u64: no padding may hide in the struct.
static_assert(std::has_unique_object_representations_v<DecoderStats>, "DecoderStats is plain u64 fields");
inline constexpr std::size_t kStatsWords = sizeof(DecoderStats) / sizeof(std::uint64_t);

/// The bytes a lower-case hex string spells ("0a1b..."), as the spec's test vectors are written.
inline std::vector<std::uint8_t> from_hex(const char* hex) {
  std::vector<std::uint8_t> bytes;
  for (std::size_t i = 0; hex[i] != '\0' && hex[i + 1] != '\0'; i += 2) {
    auto nibble = [](char c) { return static_cast<std::uint8_t>(c <= '9' ? c - '0' : c - 'a' + 10); };
    bytes.push_back(static_cast<std::uint8_t>(nibble(hex[i]) << 4 | nibble(hex[i + 1])));
  }
  return bytes;
}

/// Every counter equal.
inline bool same_stats(const DecoderStats& a, const DecoderStats& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

/// Hashes every counter in declaration order.
inline void add_stats(Digest* digest, const DecoderStats& stats) {
  std::uint64_t words[kStatsWords];
  std::memcpy(words, &stats, sizeof words);
  for (const std::uint64_t word : words) digest->add_u64(word);
}

/// Field-by-field bit equality (struct padding excluded; NaN payloads compared as bits).
inline bool same_bits(const JointStateRecord& a, const JointStateRecord& b) {
  return a.sequence == b.sequence && a.timestamp_us == b.timestamp_us && a.joint_count == b.joint_count &&
         std::memcmp(a.q_rad, b.q_rad, sizeof a.q_rad) == 0 &&
         std::memcmp(a.qd_rad_s, b.qd_rad_s, sizeof a.qd_rad_s) == 0 &&
         std::memcmp(a.current_a, b.current_a, sizeof a.current_a) == 0;
}
inline bool same_bits(const TrackerPointRecord& a, const TrackerPointRecord& b) {
  return a.sequence == b.sequence && a.timestamp_us == b.timestamp_us &&
         std::memcmp(a.point_m, b.point_m, sizeof a.point_m) == 0 && a.status == b.status;
}
inline bool same_bits(const DeviceInfoRecord& a, const DeviceInfoRecord& b) {
  return a.sequence == b.sequence && a.timestamp_us == b.timestamp_us && a.device_kind == b.device_kind &&
         std::memcmp(&a.nominal_rate_hz, &b.nominal_rate_hz, sizeof a.nominal_rate_hz) == 0 &&
         std::memcmp(a.name, b.name, sizeof a.name) == 0;
}

inline void add_f32(Digest* digest, float value) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  digest->add_u64(bits);
}
/// The record's joints only (a six-joint record hashes as in a build of six).
inline void add_record(Digest* digest, const JointStateRecord& r) {
  digest->add_u64(r.sequence);
  digest->add_u64(r.timestamp_us);
  for (int j = 0; j < r.joint_count; ++j) digest->add(r.q_rad[j]);
  for (int j = 0; j < r.joint_count; ++j) digest->add(r.qd_rad_s[j]);
  for (int j = 0; j < r.joint_count; ++j) add_f32(digest, r.current_a[j]);
}
inline void add_record(Digest* digest, const TrackerPointRecord& r) {
  digest->add_u64(r.sequence);
  digest->add_u64(r.timestamp_us);
  for (double v : r.point_m) digest->add(v);
  digest->add_u64(r.status);
}
inline void add_record(Digest* digest, const DeviceInfoRecord& r) {
  digest->add_u64(r.sequence);
  digest->add_u64(r.timestamp_us);
  digest->add_u64(r.device_kind);
  add_f32(digest, r.nominal_rate_hz);
  digest->add_bytes(r.name, sizeof r.name);
}

/// Hashes every delivered record, tagged with its type, in arrival order.
class DigestHandler : public FrameHandler {
 public:
  void on_joint_state(const JointStateRecord& r) override { note(PacketType::joint_state, r); }
  void on_tracker_point(const TrackerPointRecord& r) override { note(PacketType::tracker_point, r); }
  void on_device_info(const DeviceInfoRecord& r) override { note(PacketType::device_info, r); }

  Digest digest;            ///< over (type, record bits) of every record
  std::uint64_t count = 0;  ///< records delivered

 private:
  template <typename Record>
  void note(PacketType type, const Record& record) {
    digest.add_u64(static_cast<std::uint64_t>(type));
    add_record(&digest, record);
    ++count;
  }
};

/// 64 random bits as a double (any pattern: NaN, Inf, subnormal included).
inline double random_bits_f64(Random* random) {
  const std::uint64_t bits = random->next();
  double value = 0.0;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}
inline float random_bits_f32(Random* random) {
  const auto bits = static_cast<std::uint32_t>(random->next());
  float value = 0.0f;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

/// Plausible joint state half the time, arbitrary bit patterns otherwise.
inline JointStateRecord random_joint_state(Random* random, std::uint16_t sequence, std::uint64_t timestamp_us) {
  JointStateRecord r;
  r.sequence = sequence;
  r.timestamp_us = timestamp_us;
  const bool raw = random->below(2) == 0;
  for (int j = 0; j < kSixJoints; ++j) {
    r.q_rad[j] = raw ? random_bits_f64(random) : random->uniform(-6.3, 6.3);
    r.qd_rad_s[j] = raw ? random_bits_f64(random) : random->uniform(-3.2, 3.2);
    r.current_a[j] = raw ? random_bits_f32(random) : static_cast<float>(random->uniform(-5.0, 5.0));
  }
  return r;
}

/// Valid, beam-lost (NaN position), unstable or out-of-range status, as a tracker sends them.
inline TrackerPointRecord random_tracker_point(Random* random, std::uint16_t sequence, std::uint64_t timestamp_us) {
  TrackerPointRecord r;
  r.sequence = sequence;
  r.timestamp_us = timestamp_us;
  const std::uint64_t kind = random->below(8);
  r.status = kind < 5 ? 0 : kind == 5 ? 1 : kind == 6 ? 2 : static_cast<std::uint8_t>(3 + random->below(253));
  for (double& c : r.point_m) {
    if (r.status == 1) {
      const std::uint64_t nan_bits = 0x7FF8000000000000ULL | (random->next() & 0x0007FFFFFFFFFFFFULL);
      std::memcpy(&c, &nan_bits, sizeof c);
    } else {
      c = random->uniform(-20.0, 20.0);
    }
  }
  return r;
}

/// Random kind and rate, and a printable name of 0..24 characters.
inline DeviceInfoRecord random_device_info(Random* random, std::uint16_t sequence, std::uint64_t timestamp_us) {
  DeviceInfoRecord r;
  r.sequence = sequence;
  r.timestamp_us = timestamp_us;
  r.device_kind = static_cast<std::uint8_t>(random->below(256));
  r.nominal_rate_hz = static_cast<float>(random->uniform(0.0, 1000.0));
  const std::uint64_t length = random->below(kDeviceNameBytes + 1);
  for (std::uint64_t i = 0; i < length; ++i) r.name[i] = static_cast<char>(0x20 + random->below(0x5F));
  return r;
}

}  // namespace hivecal::test
