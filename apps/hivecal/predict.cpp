// hivecal predict: tool positions of joint poses through a calibration result.
#include <cstdio>
#include <vector>

#include "calibration_json.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "csv.hpp"
#include "text_util.hpp"

namespace hivecal::cli {

int predict_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result (robot-calibration/1 JSON)", ""},
      {"joints", "FILE", "poses to predict: CSV q1..q6 [rad], optional leading t column", ""},
      {"frame", "tracker|base", "frame of the predicted positions", "tracker"},
      {"out", "FILE", "predicted positions x,y,z [m] (CSV); '-' for stdout", "-"},
  };
  Options options;
  const int parsed = parse_options("predict",
                                   "Predicts the tool position of each joint pose with a calibrated model:\n"
                                   "base_to_tracker * FK(q) * tool (or FK(q) * tool with --frame base).",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  const std::string frame = options.get("frame");
  if (options.get("calibration").empty() || options.get("joints").empty()) {
    error("predict", "--calibration and --joints are required (see --help)");
    return kExitUsage;
  }
  if (frame != "tracker" && frame != "base") {
    error("predict", "--frame must be 'tracker' or 'base', not '" + frame + "'");
    return kExitUsage;
  }
  textio::CalibrationFile calibration;
  textio::ParseResult r = textio::read_calibration_json(options.get("calibration"), &calibration);
  if (!r.ok) {
    error("predict", r.message);
    return kExitBadInput;
  }
  std::vector<JointVector> poses;
  r = textio::read_joints_csv(options.get("joints"), &poses);
  if (!r.ok) {
    error("predict", r.message);
    return kExitBadInput;
  }
  std::vector<Vec3> points;
  points.reserve(poses.size());
  for (const JointVector& q : poses) {
    const Vec3 base_point = fk_tool_point(calibration.model, q);
    points.push_back(frame == "base" ? base_point : calibration.base_to_tracker.apply(base_point));
  }
  const std::string csv = textio::format_points_csv(points);
  const std::string out = options.get("out");
  if (out == "-") {
    std::fwrite(csv.data(), 1, csv.size(), stdout);
    return kExitOk;
  }
  std::string write_error;
  if (!textio::write_file_atomically(out, csv, &write_error)) {
    error("predict", write_error);
    return kExitOutputError;
  }
  return kExitOk;
}

}  // namespace hivecal::cli
