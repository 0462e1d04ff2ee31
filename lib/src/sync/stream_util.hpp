// Helpers shared by the clock estimator and the sample extractor (library-internal).
#pragma once

#include <cstdint>
#include <limits>

#include "hivecal/wire/records.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal::detail {

/// Quiet NaN: marks an unknown profile value.
inline constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

/// The joint positions of a record as a vector [rad] (its joint_count entries, zeros after).
inline JointVector joints_of(const JointStateRecord& record) {
  JointVector q;
  for (int j = 0; j < record.joint_count && j < kMaxJoints; ++j) q(j) = record.q_rad[j];
  return q;
}

/// The position of a tracker record as a vector [m].
inline Vec3 point_of(const TrackerPointRecord& record) {
  return Vec3(record.point_m[0], record.point_m[1], record.point_m[2]);
}

/// A timestamp [us] as a double (exact below 2^53 us, i.e. 285 years).
inline double us_to_double(std::uint64_t t_us) {
  return static_cast<double>(t_us);
}

}  // namespace hivecal::detail
