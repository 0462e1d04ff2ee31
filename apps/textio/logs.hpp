// Robot and tracker logs, hivecal's own and those other tools write (io-formats.md, "Logs
// written by other tools"), read whole into the records the stream path consumes: one call
// per log, "log file -> records + counters + error". Recognised by their header:
//   robot:   hivecal `t,q1..qN` (the arm's N joints); UR RTDE recorder `timestamp`,
//            `actual_q_0..5` (never `target_q`; a UR's six joints, other arms refused); ROS 1
//            `rostopic echo -p /joint_states` (`field.header.stamp` [ns], the arm's joints
//            mapped by `field.nameK`); a ROS 2 bag folder (ros2_bag.hpp);
//   tracker: hivecal `t,x,y,z[,status]`; exports with a time column and X, Y, Z in any unit.
// Any delimiter and column order (delimited.hpp); units in brackets become SI, columns
// without one are in the declared InputUnits (SI by default); joints beyond one turn and
// points beyond 100 m are refused with the likely cause; times become whole microseconds and
// must increase.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/wire/records.hpp"
#include "textio/delimited.hpp"

namespace hivecal::textio {

/// What a log turned out to be.
enum class LogFormat {
  unknown,          ///< not recognised (error set)
  hivecal_robot,    ///< hivecal's `t,q1..qN`
  ur_rtde,          ///< UR RTDE recorder: `timestamp`, `actual_q_0..5`
  rostopic,         ///< `rostopic echo -p /joint_states`
  ros2_bag,         ///< rosbag2 folder, sqlite3 storage, /joint_states
  hivecal_tracker,  ///< hivecal's `t,x,y,z[,status]`
  tracker_export,   ///< a tracker software's export: time, X, Y, Z with units
};
/// A short English name of `format` ("UR RTDE log", ...).
const char* log_format_name(LogFormat format);

/// The UR drivers' joint names, joints 1..6 in order.
inline const std::vector<std::string> kUrJointNames = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                       "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};

/// How to read a robot log.
struct RobotLogOptions {
  /// Names of joints 1..N in ROS logs (`field.nameK`, bag `name`), in the robot's order
  /// (--joint-names); empty: UR's six for an arm of six revolute joints, for another arm the
  /// message's own joints in its order, a message naming another count than the arm's refused.
  std::vector<std::string> joint_names{};
  /// Units of joint columns without a bracket unit (--angle-unit), and the arm's joints
  /// (units.joints: how many, which slide); a bag's are rad by definition.
  InputUnits units;
  /// The arm's name for messages (--robot-model's: "iiwa14"); "" when not known.
  std::string arm_name{};
};

/// 1 .. kMaxJoints different comma-separated joint names into options->joint_names; false
/// (options unchanged) for an empty name, a name given twice or more than kMaxJoints.
bool parse_joint_names(std::string_view text, RobotLogOptions* options);
/// True when the arm of `joints` is a UR's shape of six revolute joints (RTDE, UR's ROS names).
bool ur_joints(const InputJoints& joints);

/// What reading a log met, per reason; rows dropped are counted, never silent.
struct LogCounters {
  std::uint64_t rows = 0;            ///< data rows (bag: /joint_states messages) read
  std::uint64_t records = 0;         ///< records produced
  std::uint64_t repeated_time = 0;   ///< rows dropped: same timestamp (to 1 us) as the record before
  std::uint64_t missing_joints = 0;  ///< ROS rows dropped: not every expected joint name present
  std::uint64_t not_valid = 0;       ///< tracker records marked not valid (status != 0, or no x, y, z)
  std::uint64_t other_messages = 0;  ///< bag messages of other topics, not read
};

/// One line about a log for the user: "UR RTDE log: 1000 rows, 998 records; dropped: 2 repeated time".
std::string describe_log(LogFormat format, const LogCounters& counters);

/// Outcome of reading one log.
template <typename Record>
struct LogRead {
  bool ok = false;                        ///< the whole log was understood
  std::string error;                      ///< "file[:line]: what" when not ok
  LogFormat format = LogFormat::unknown;  ///< what the log is
  std::vector<Record> records;            ///< in time order, timestamps strictly increasing
  LogCounters counters;                   ///< rows read, dropped per reason
  std::uint64_t bytes_read = 0;           ///< [bytes]
};
using RobotLog = LogRead<JointStateRecord>;      ///< a robot log's joint states
using TrackerLog = LogRead<TrackerPointRecord>;  ///< a tracker log's points

/// Reads a robot log: a text file of any robot format above, or a ROS 2 bag (folder or .db3).
RobotLog read_robot_log(const std::string& path, const RobotLogOptions& options = {});
/// Reads a tracker log (text); columns without a bracket unit are in `units`.
TrackerLog read_tracker_log(const std::string& path, const InputUnits& units = {});
/// Reads a robot log from text in memory; `name` stands for the file in messages.
RobotLog parse_robot_log(std::string_view text, const std::string& name, const RobotLogOptions& options = {});
/// Reads a tracker log from text in memory; `name` stands for the file in messages.
TrackerLog parse_tracker_log(std::string_view text, const std::string& name, const InputUnits& units = {});

/// What a --robot/--tracker path is.
enum class StreamFileKind {
  capture,   ///< raw serial bytes (serial-protocol.md)
  text_log,  ///< a text log (its header is checked when read)
  ros2_bag,  ///< a rosbag2 folder or its .db3 file
  mcap,      ///< an MCAP file (not readable: see docs/formats.md)
};
/// Detects the kind by content: a folder or SQLite file is a bag; a first line of printable
/// text with a delimiter is a text log; anything else, an unreadable file included, is a
/// capture (whose reader then reports the problem).
StreamFileKind detect_stream_file(const std::string& path);

}  // namespace hivecal::textio
