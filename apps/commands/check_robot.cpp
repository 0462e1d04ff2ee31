// hivecal check-robot: what hivecal reads from a robot file (description JSON, URDF, result, or
// a built-in name), printed so that a user can check it before calibrating.
#include <cstdio>
#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"

namespace hivecal::cli {

namespace {

using math::kDegPerRad;

std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char text[200];
  std::snprintf(text, sizeof text, format, a, b, c, d);
  return text;
}

const char* type_name(const RobotModel& model, int joint) {
  return joint_type(model, joint) == JointType::prismatic ? "prismatic" : "revolute";
}

/// The table as the file's convention writes it, in mm and degrees, a row per joint with its type.
std::string dh_table(const textio::RobotDescription& robot) {
  std::string s = robot.convention == DhConvention::modified
                      ? "joint  alpha(i-1) [deg]    a(i-1) [mm]   theta offset [deg]         d [mm]  type\n"
                      : "joint  theta offset [deg]         d [mm]          a [mm]      alpha [deg]  type\n";
  ModifiedDhRow rows[kMaxJoints];
  Vec3 tool_m = robot.model.tool_m;
  if (robot.convention == DhConvention::modified)
    modified_dh_from_model(robot.model, robot.modified_base, rows, &tool_m);
  for (int j = 0; j < robot.model.joint_count; ++j) {
    if (robot.convention == DhConvention::modified) {
      const ModifiedDhRow& r = rows[j];
      s += fmt("%5.0f", j + 1) + fmt("  %16.6f  %13.4f  %19.6f  %13.4f", r.alpha_prev_rad * kDegPerRad,
                                     r.a_prev_m * 1e3, r.theta_offset_rad * kDegPerRad, r.d_m * 1e3);
    } else {
      const DhJoint& r = robot.model.joints[j];
      s += fmt("%5.0f", j + 1) + fmt("  %18.6f  %13.4f  %14.4f  %15.6f", r.theta_offset_rad * kDegPerRad, r.d_m * 1e3,
                                     r.a_m * 1e3, r.alpha_rad * kDegPerRad);
    }
    s += std::string("  ") + type_name(robot.model, j) + "\n";
  }
  return s;
}

/// "joint limits: 1 -170.0..170.0 deg, ..." (a prismatic joint's in mm), or what plan assumes without them.
std::string joint_limits_line(const textio::RobotDescription& robot) {
  if (!robot.has_joint_limits) return "joint limits: none given (plan assumes a built-in type's, else +-360 deg)\n";
  std::string s = "joint limits:";
  for (int j = 0; j < robot.model.joint_count; ++j) {
    const bool slides = joint_type(robot.model, j) == JointType::prismatic;
    const double scale = slides ? 1e3 : kDegPerRad;
    s += fmt(j == 0 ? " %.0f" : ", %.0f", j + 1) +
         fmt(slides ? " %.1f..%.1f mm" : " %.1f..%.1f deg", robot.lower_rad(j) * scale, robot.upper_rad(j) * scale);
  }
  return s + "\n";
}

/// " (q [deg] 0.000 -90.000 ...)": the pose's joints, a prismatic one's in mm.
std::string pose_text(const RobotModel& model, const JointVector& q) {
  std::string s = " (q [deg] ";
  for (int j = 0; j < model.joint_count; ++j) {
    const bool slides = joint_type(model, j) == JointType::prismatic;
    s += fmt(j == 0 ? "%.3f" : " %.3f", q(j) * (slides ? 1e3 : kDegPerRad)) + (slides ? " mm" : "");
  }
  return s + ")";
}

Error check_robot(const Options& options) {
  textio::RobotDescription robot;
  bool from_file = false;
  Error error = robot_model_option(options, "robot-model", &robot, &from_file);
  if (!error.ok()) return error;
  std::vector<JointVector> poses;
  if (!options.get("joints").empty()) {
    textio::InputUnits units;
    error = input_units_option(options, &units);
    units.joints = textio::input_joints(robot.model);
    if (error.ok()) error = textio::read_joints_csv(options.get("joints"), &poses, units);
    if (!error.ok()) return error;
  }
  // The name and the path are the file's and the user's text: printed as every message prints input.
  std::string s = "robot: " + port::printable(robot.robot) + " (" +
                  (from_file ? "file " + port::printable(options.get("robot-model"), 4096) : "built-in table") +
                  ")\nconvention: " + textio::dh_convention_name(robot.convention) + "\n";
  if (robot.base_turned_by_pi) {
    s += "base: UR's own, the URDF's root turned by 180 deg about z (ROS's 'base' frame): the table and the FK "
         "below are in it\n";
  }
  s += dh_table(robot);
  if (robot.convention == DhConvention::modified) {
    s += fmt("base offset: alpha_0 %.6f deg, a_0 %.4f mm (folded into the table above as row 1's)\n",
             robot.modified_base.alpha0_rad * kDegPerRad, robot.modified_base.a0_m * 1e3);
  }
  for (int k = 0; k < robot.target_count; ++k) {
    const Vec3& t = target_tool(robot.model, k);
    s += fmt("tool point %.0f (flange frame): ", k + 1) +
         fmt("%.4f, %.4f, %.4f mm\n", t.x() * 1e3, t.y() * 1e3, t.z() * 1e3);
  }
  s += "compliance terms: " + std::to_string(robot.model.compliance.term_count) + "\n";
  s += joint_limits_line(robot);
  // FK in the file's own base frame: at zero, then at each given pose.
  const RigidTransform file_base =
      robot.convention == DhConvention::modified ? robot.modified_base.transform() : RigidTransform{};
  poses.insert(poses.begin(), JointVector::Zero());
  for (std::size_t p = 0; p < poses.size(); ++p) {
    const JointVector& q = poses[p];
    s += p == 0 ? "FK at q = 0" : "FK at pose " + std::to_string(p);
    s += pose_text(robot.model, q) + ":";
    for (int k = 0; k < robot.target_count; ++k) {
      const Vec3 point = file_base.apply(fk_target_point(robot.model, q, k));
      s += fmt(" tool %.0f at", k + 1) + fmt(" %.4f, %.4f, %.4f mm", point.x() * 1e3, point.y() * 1e3, point.z() * 1e3);
    }
    s += "\n";
  }
  std::fputs(s.c_str(), stdout);
  return Error{};
}

}  // namespace

int check_robot_main(int argc, char** argv) {
  std::vector<OptionSpec> specs = {
      {"robot-model", "NAME|FILE",
       "the robot file (description .json, .urdf or a result) or a built-in name; also the first argument", ""},
      {"joints", "FILE", "poses whose tool points to print: CSV q1..qN (the arm's N joints)", ""},
  };
  specs.push_back(input_unit_option_specs()[1]);  // --angle-unit of --joints
  // `hivecal check-robot FILE` as well as `--robot-model FILE`.
  std::vector<std::string> args(argv, argv + argc);
  if (!args.empty() && !args[0].empty() && args[0][0] != '-') args.insert(args.begin(), "--robot-model");
  std::vector<char*> pointers;
  for (std::string& a : args) pointers.push_back(a.data());
  Options options;
  const int parsed = parse_options(kCheckRobotCommand,
                                   "Prints what hivecal reads from a robot file: its convention, the DH table (mm,\n"
                                   "degrees), tool points, compliance, joint limits, and the tool points at q = 0 and\n"
                                   "at the poses of --joints, in the file's base frame. A file hivecal cannot use is\n"
                                   "refused with its name and the line or key at fault.",
                                   specs, static_cast<int>(pointers.size()), pointers.data(), &options);
  if (parsed >= 0) return parsed;
  if (options.get("robot-model").empty())
    return exit_with(kCheckRobotCommand, Error::usage("a robot file is required (see --help)"));
  return exit_with(kCheckRobotCommand, check_robot(options));
}

}  // namespace hivecal::cli
