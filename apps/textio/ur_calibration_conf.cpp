#include "textio/ur_calibration_conf.hpp"

#include <cstdio>
#include <limits>
#include <string_view>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_kinematics.hpp"

namespace hivecal::textio {
namespace {

struct DeltaKey {
  const char* name;
  double* values;
  bool seen;
};

port::Error failure(const std::string& source, std::size_t line, const std::string& what) {
  return port::Error::input(source + ":" + std::to_string(line) + ": " + what);
}

/// Parses "[ v1, v2, ..., v6 ]" into values; returns an error text or "".
std::string parse_six_values(std::string_view list, double* values) {
  list = trim(list);
  if (list.size() < 2 || list.front() != '[' || list.back() != ']') return "expected [v1, ..., v6]";
  list = list.substr(1, list.size() - 2);
  int count = 0;
  while (!list.empty()) {
    const std::size_t comma = list.find(',');
    const std::string_view field = list.substr(0, comma);
    if (count == kSixJoints) return "more than 6 values";
    double v = 0.0;
    if (!parse_double(field, &v)) return "not a number: " + port::quoted(trim(field));
    if (!math::is_finite(v)) return "value is NaN or Inf";
    values[count++] = v;
    if (comma == std::string_view::npos) break;
    list.remove_prefix(comma + 1);
  }
  if (count != kSixJoints) return "expected 6 values, found " + std::to_string(count);
  return "";
}

}  // namespace

port::Error parse_ur_calibration_conf(const std::string& text, const std::string& source_name,
                                      UrCalibrationDeltas* deltas) {
  UrCalibrationDeltas parsed;
  DeltaKey keys[] = {{"delta_theta", parsed.delta_theta_rad, false},
                     {"delta_a", parsed.delta_a_m, false},
                     {"delta_d", parsed.delta_d_m, false},
                     {"delta_alpha", parsed.delta_alpha_rad, false}};
  bool in_mounting = false;
  bool saw_mounting = false;
  std::size_t line_number = 0;
  std::string_view rest;
  const port::Error encoding = utf8_text(text, source_name, &rest);
  if (!encoding.ok()) return encoding;
  while (!rest.empty()) {
    ++line_number;
    const std::size_t newline = rest.find('\n');
    std::string_view line = rest.substr(0, newline);
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
    const std::size_t hash = line.find('#');
    line = trim(line.substr(0, hash));
    if (line.empty()) continue;
    if (line.front() == '[' && line.find('=') == std::string_view::npos) {
      in_mounting = lower(line) == "[mounting]";  // section names are not case-sensitive
      saw_mounting = saw_mounting || in_mounting;
      continue;
    }
    if (!in_mounting) continue;
    const std::size_t equals = line.find('=');
    if (equals == std::string_view::npos) return failure(source_name, line_number, "expected key = value");
    const std::string_view key = trim(line.substr(0, equals));
    for (DeltaKey& entry : keys) {
      if (key != entry.name) continue;
      if (entry.seen) return failure(source_name, line_number, std::string(entry.name) + " given twice");
      const std::string error = parse_six_values(line.substr(equals + 1), entry.values);
      if (!error.empty()) return failure(source_name, line_number, std::string(entry.name) + ": " + error);
      entry.seen = true;
    }
  }
  if (!saw_mounting) return port::Error::input(source_name + ": no [mounting] section");
  for (const DeltaKey& entry : keys) {
    if (!entry.seen) return port::Error::input(source_name + ": [mounting] has no " + entry.name);
  }
  *deltas = parsed;
  return port::Error{};
}

std::string joint_shape(const RobotModel& model) {
  const std::string count = std::to_string(model.joint_count);
  if (all_revolute(model)) return count + (model.joint_count == 1 ? " revolute joint" : " revolute joints");
  std::string prismatic;
  int slides = 0;
  for (int j = 0; j < model.joint_count; ++j) {
    if (joint_type(model, j) != JointType::prismatic) continue;
    prismatic += (slides++ == 0 ? "" : ", ") + std::to_string(j + 1);
  }
  return count + (model.joint_count == 1 ? " joint, " : " joints, ") + (slides == 1 ? "joint " : "joints ") +
         prismatic + " prismatic";
}

port::Error require_ur_joints(const RobotModel& model, const std::string& model_name, const std::string& feature) {
  if (has_ur_joints(model)) return port::Error{};
  return port::Error::usage(feature + " is a Universal Robots controller's (six revolute joints); " +
                            port::printable(model_name, 60) + " has " + joint_shape(model));
}

port::Error read_ur_calibration_conf(const std::string& path, UrCalibrationDeltas* deltas) {
  std::string text;
  const port::Error read = port::read_whole_file(path, port::kMaxTextInputBytes, &text);
  if (!read.ok()) return read;
  return parse_ur_calibration_conf(text, path, deltas);
}

double ur_deltas_tool_shift_m(const RobotModel& nominal, const UrCalibrationDeltas& deltas) {
  RobotModel calibrated = nominal;
  if (apply_ur_deltas(nominal, deltas, &calibrated) != Status::ok) return std::numeric_limits<double>::infinity();
  Random random(20260);  // fixed poses: the same verdict on every run
  double worst_m = 0.0;
  for (int i = 0; i < kUrDeltaTestPoses; ++i) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-math::kPi, math::kPi);
    const double shift_m = (fk_tool_point(calibrated, q) - fk_tool_point(nominal, q)).norm();
    worst_m = shift_m > worst_m || !math::is_finite(shift_m) ? shift_m : worst_m;
  }
  return worst_m;
}

port::Error check_ur_deltas_plausible(const RobotModel& nominal, const UrCalibrationDeltas& deltas,
                                      const std::string& source_name, const std::string& model_name) {
  const double shift_m = ur_deltas_tool_shift_m(nominal, deltas);
  if (shift_m <= kMaxUrDeltaToolShift_m) return port::Error{};
  char text[200];
  std::snprintf(text, sizeof text,
                ": its deltas move the tool of the nominal %s by up to %.1f mm over %d test poses (a controller "
                "calibration corrects a few mm; limit %.0f mm): not a calibration of this robot model?",
                model_name.c_str(), shift_m * 1e3, kUrDeltaTestPoses, kMaxUrDeltaToolShift_m * 1e3);
  return port::Error::input(source_name + text);
}

std::string format_ur_calibration_conf(const UrCalibrationDeltas& deltas) {
  const struct {
    const char* name;
    const double* values;
  } rows[] = {{"delta_theta", deltas.delta_theta_rad},
              {"delta_a", deltas.delta_a_m},
              {"delta_d", deltas.delta_d_m},
              {"delta_alpha", deltas.delta_alpha_rad}};
  std::string out = "[mounting]\n";
  for (const auto& row : rows) {
    out += row.name;
    out += " = [";
    for (int j = 0; j < kSixJoints; ++j) {
      out += (j == 0 ? " " : ", ");
      out += format_double(row.values[j]);
    }
    out += "]\n";
  }
  return out;
}

port::Error read_ur_calibrated_model(const std::string& path, const RobotModel& nominal, const std::string& model_name,
                                     RobotModel* calibrated) {
  port::Error r = require_ur_joints(nominal, model_name, "a calibration.conf");
  if (!r.ok()) return r;
  UrCalibrationDeltas deltas;
  const bool turned = is_ur_table_turned(nominal);
  const RobotModel ur_table = turned ? turned_by_pi(nominal) : nominal;
  r = read_ur_calibration_conf(path, &deltas);
  if (r.ok()) r = check_ur_deltas_plausible(ur_table, deltas, path, port::printable(model_name));
  if (!r.ok()) return r;
  RobotModel applied;
  (void)apply_ur_deltas(ur_table, deltas, &applied);  // finite: the reader refuses NaN
  *calibrated = turned ? turned_by_pi(applied) : applied;
  return r;
}

UrCalibrationDeltas ur_deltas_in_ur_table(const RobotModel& nominal, const RobotModel& calibrated) {
  if (!is_ur_table_turned(nominal)) return ur_deltas_between(nominal, calibrated);
  return ur_deltas_between(turned_by_pi(nominal), turned_by_pi(calibrated));
}

}  // namespace hivecal::textio
