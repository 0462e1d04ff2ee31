// ROS 2 bags (rosbag2) as a robot log: topic /joint_states, sensor_msgs/msg/JointState,
// CDR-encoded, in the sqlite3 storage (a folder with metadata.yaml and *.db3, or one .db3).
// Read with Debian's libsqlite3; a build without it (cross targets) refuses bags with a
// message. MCAP storage is refused: no Debian package reads it (docs/formats.md).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "textio/logs.hpp"

namespace hivecal::textio {

/// Why an MCAP bag is not read.
inline constexpr const char* kMcapRefusal =
    "MCAP storage is not read (no Debian package reads it): convert the bag with "
    "`ros2 bag convert` to storage_id sqlite3";

/// One sensor_msgs/msg/JointState message, as far as hivecal needs it.
struct JointStateMessage {
  std::uint64_t stamp_us = 0;           ///< header.stamp [us]
  std::vector<std::string_view> names;  ///< joint names (views into the message bytes)
  std::vector<double> positions_rad;    ///< positions, same order as names [rad]
};

/// Decodes a CDR-serialised JointState (4-byte encapsulation header, little or big endian);
/// false with *error set when it is truncated or malformed.
bool decode_joint_state_cdr(const std::uint8_t* data, std::size_t size, JointStateMessage* message, std::string* error);

/// Reads /joint_states of the bag at `path` (folder or .db3) as a robot log.
RobotLog read_ros2_bag_joint_states(const std::string& path, const RobotLogOptions& options);

}  // namespace hivecal::textio
