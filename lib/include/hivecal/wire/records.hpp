// Decoded stream records: what the wire codec produces and the clock sync consumes.
// Units are in the names; timestamps are on the sending device's own clock.
#pragma once

#include <cstdint>

#include "hivecal/core/joints.hpp"

namespace hivecal {

/// One joint-state packet of the robot stream (125 Hz nominal): JOINT_STATE (six joints) or
/// JOINT_STATE_N (any count up to kMaxJoints). A prismatic joint's values are [m], [m/s].
struct JointStateRecord {
  std::uint16_t sequence = 0;        ///< +1 per packet, wraps 65535 -> 0
  std::uint64_t timestamp_us = 0;    ///< robot clock [us]
  int joint_count = kSixJoints;      ///< joints in the record, 1 .. kMaxJoints [-]
  double q_rad[kMaxJoints] = {};     ///< joint positions [rad]; the first joint_count are used
  double qd_rad_s[kMaxJoints] = {};  ///< joint velocities [rad/s]
  float current_a[kMaxJoints] = {};  ///< motor currents [A]
};

/// TRACKER_POINT status byte (serial-protocol.md); any other value is not valid either.
enum class TrackerStatus : std::uint8_t {
  valid = 0,      ///< a measurement
  beam_lost = 1,  ///< position fields are NaN
  unstable = 2,   ///< present but not to be trusted for calibration
};

/// One TRACKER_POINT packet of the tracker stream (10 Hz nominal).
struct TrackerPointRecord {
  std::uint16_t sequence = 0;      ///< +1 per packet, wraps 65535 -> 0
  std::uint64_t timestamp_us = 0;  ///< tracker clock [us]
  double point_m[3] = {};          ///< position in the tracker frame [m]
  std::uint8_t status = 0;         ///< TrackerStatus value as received

  /// True only for status 0 (valid); 1, 2 and unknown values are not usable.
  bool is_valid() const { return status == static_cast<std::uint8_t>(TrackerStatus::valid); }
};

/// DEVICE_INFO device kind.
enum class DeviceKind : std::uint8_t { robot = 1, tracker = 2 };

/// One DEVICE_INFO packet (sent at stream start, may repeat).
struct DeviceInfoRecord {
  std::uint16_t sequence = 0;      ///< +1 per packet of that stream
  std::uint64_t timestamp_us = 0;  ///< device clock [us]
  std::uint8_t device_kind = 0;    ///< DeviceKind value as received
  float nominal_rate_hz = 0.0f;    ///< nominal packet rate [Hz]
  char name[25] = {};              ///< ASCII name, NUL-terminated (24 bytes on the wire)
};

}  // namespace hivecal
