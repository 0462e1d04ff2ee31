// Rules shared by every log reader (text logs in logs.cpp, ROS 2 bags in ros2_bag.cpp): one
// place for the time order and the joint mapping by name. Internal to textio.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/core/types.hpp"
#include "textio/logs.hpp"

namespace hivecal::textio {

/// Whole microseconds in time order: a later time is taken, the same one is a repeat (the
/// row is dropped and counted), an earlier one is an error.
class TimeOrder {
 public:
  /// True when t_us may follow the times before (*repeated when equal to the last one);
  /// false with *problem set when it goes back.
  bool accept(std::uint64_t t_us, bool* repeated, std::string* problem);

 private:
  bool started_ = false;
  std::uint64_t last_us_ = 0;
};

/// How a message's joint names meet the arm's joints.
enum class JointMatch {
  found,        ///< every joint of the arm in the message: source[] set
  missing,      ///< an expected name is not in the message (the message is dropped and counted)
  other_count,  ///< no names to map, and the message names another count than the arm's joints
};
/// Joint j of the arm (options.units.joints.count of them) is names[source[j]]: by the
/// expected names (expected_joint_names; names not expected, e.g. a gripper's, ignored), or,
/// without any, by the message's own order when it names exactly the arm's joints.
JointMatch match_joints(const std::vector<std::string_view>& names, const RobotLogOptions& options,
                        int source[kMaxJoints]);
/// The names joints 1..N must carry: the user's (--joint-names), UR's for a UR-shaped arm, or
/// none (the message's own order).
const std::vector<std::string>& expected_joint_names(const RobotLogOptions& options);
/// The error of a message that names `names` (another count than the arm's) with no names to map.
std::string other_joint_count_message(const std::vector<std::string_view>& names, const InputJoints& joints);
/// "a, b, c" of names, for messages.
std::string join_names(const std::vector<std::string_view>& names);
/// The error of a ROS log none of whose messages names all expected joints.
std::string missing_joints_message(const std::string& file, const std::vector<std::string>& expected,
                                   const std::string& names_found);

}  // namespace hivecal::textio
