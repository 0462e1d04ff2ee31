// Rules shared by every log reader (text logs in logs.cpp, ROS 2 bags in ros2_bag.cpp): one
// place for the time order and the joint mapping by name. Internal to textio.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/core/types.hpp"

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

/// Joint j of the robot is names[source[j]]; false when one of `expected` is not in `names`
/// (names not expected, e.g. a gripper's, are ignored).
bool map_joints_by_name(const std::vector<std::string_view>& names, const std::array<std::string, kSixJoints>& expected,
                        int source[kSixJoints]);
/// "a, b, c" of names, for messages.
std::string join_names(const std::vector<std::string_view>& names);
/// The error of a ROS log none of whose messages names all expected joints.
std::string missing_joints_message(const std::string& file, const std::array<std::string, kSixJoints>& expected,
                                   const std::string& names_found);

}  // namespace hivecal::textio
