#include "textio/log_rows.hpp"

#include "hivecal/port/error.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {

bool TimeOrder::accept(std::uint64_t t_us, bool* repeated, std::string* problem) {
  if (started_ && t_us < last_us_) {
    *problem = "timestamp " + format_double(static_cast<double>(t_us) * 1e-6) + " s does not increase (previous " +
               format_double(static_cast<double>(last_us_) * 1e-6) + " s)";
    return false;
  }
  *repeated = started_ && t_us == last_us_;
  started_ = true;
  last_us_ = t_us;
  return true;
}

const std::vector<std::string>& expected_joint_names(const RobotLogOptions& options) {
  static const std::vector<std::string> none;
  if (!options.joint_names.empty()) return options.joint_names;
  return ur_joints(options.units.joints) ? kUrJointNames : none;
}

JointMatch match_joints(const std::vector<std::string_view>& names, const RobotLogOptions& options,
                        int source[kMaxJoints]) {
  const std::vector<std::string>& expected = expected_joint_names(options);
  const int count = options.units.joints.count;
  if (expected.empty()) {  // no names: the message's own order, as many as the arm's joints
    if (names.size() != static_cast<std::size_t>(count)) return JointMatch::other_count;
    for (int j = 0; j < count; ++j) source[j] = j;
    return JointMatch::found;
  }
  if (expected.size() != static_cast<std::size_t>(count)) return JointMatch::missing;  // names of another arm
  bool all = true;
  for (std::size_t j = 0; j < expected.size(); ++j) {
    source[j] = -1;
    for (std::size_t k = 0; k < names.size() && source[j] < 0; ++k) {
      if (names[k] == expected[j]) source[j] = static_cast<int>(k);
    }
    all = all && source[j] >= 0;
  }
  return all ? JointMatch::found : JointMatch::missing;
}

std::string other_joint_count_message(const std::vector<std::string_view>& names, const InputJoints& joints) {
  return "it names " + std::to_string(names.size()) + " joints (" + port::quoted(join_names(names), 200) +
         "), but the robot model has " + std::to_string(joints.count) + " joints (" + joint_names(joints.count) +
         "): the joints of another arm? (--robot-model names the arm; --joint-names N1,..,N" +
         std::to_string(joints.count) + " picks the arm's joints by name, in order)";
}

std::string join_names(const std::vector<std::string_view>& names) {
  std::string out;
  for (const std::string_view n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

std::string missing_joints_message(const std::string& file, const std::vector<std::string>& expected,
                                   const std::string& names_found) {
  return file + ": no message names all of the joints " +
         join_names(std::vector<std::string_view>(expected.begin(), expected.end())) + "; the log names " +
         port::quoted(names_found, 200) + " (give the robot's joint names: --joint-names)";
}

}  // namespace hivecal::textio
