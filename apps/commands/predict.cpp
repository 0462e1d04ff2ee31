// hivecal predict: tool positions of joint poses through a calibration result.
#include <cstdio>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/port/output_files.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"
#include "commands/uncertainty.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

namespace {

Error predict(const Options& options) {
  // parse
  const std::string frame = options.get("frame");
  const bool nominal = options.given("robot-model");
  if ((options.get("calibration").empty() == !nominal) || options.get("joints").empty()) {
    return Error::usage("--joints and either --calibration or --robot-model are required (see --help)");
  }
  if (nominal && options.given("frame") && frame != "base") {
    return Error::usage("--robot-model has no tracker frame: it predicts in the base frame (--frame base)");
  }
  if (frame != "tracker" && frame != "base") {
    return Error::usage("--frame must be 'tracker' or 'base', not " + port::quoted(frame));
  }
  const std::string output_unit = options.get("output-length-unit");
  if (output_unit != "m" && output_unit != "mm") {
    return Error::usage("--output-length-unit must be 'm' or 'mm', not " + port::quoted(output_unit));
  }
  const std::string target_text = options.get("target");
  int target = 0;  // 1-based as given, checked against the result below
  for (const char c : target_text) target = c >= '0' && c <= '9' && target < 1000 ? 10 * target + (c - '0') : -1;
  if (target_text.empty() || target < 1) {
    return Error::usage("--target must be a target number 1, 2, ..., not " + port::quoted(target_text));
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  Error error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (!error.ok()) return error;
  // load
  record::CalibrationFile calibration;
  port::Error r = nominal ? robot_model_option(options, "robot-model", &calibration)
                          : record::read_calibration_json(options.get("calibration"), &calibration);
  if (!r.ok()) return r;
  if (target > calibration.target_count) {
    return Error::usage("--target " + target_text + ": " + options.get("calibration") + " holds " +
                        std::to_string(calibration.target_count) + " target" +
                        (calibration.target_count == 1 ? "" : "s"));
  }
  std::vector<JointVector> poses;
  textio::InputUnits units;
  error = input_units_option(options, &units);
  if (!error.ok()) return error;
  units.joints = textio::input_joints(calibration.model);
  r = textio::read_joints_csv(options.get("joints"), &poses, units);
  if (!r.ok()) return r;
  // run
  const Predictor predict_point(calibration);
  const PredictionFrame in = frame == "base" || nominal ? PredictionFrame::base : PredictionFrame::tracker;
  std::vector<Vec3> points;
  std::vector<double> sigmas;
  std::vector<bool> extrapolated;
  ExtrapolationCount count;
  for (const JointVector& q : poses) {
    const Prediction p = predict_point(q, target - 1, in);
    points.push_back(p.point_m);
    sigmas.push_back(p.sigma_m);
    extrapolated.push_back(p.extrapolation.extrapolated());
    count.add(p.extrapolation);
  }
  // write
  const bool uncertain = predict_point.has_uncertainty();
  error = outputs.stage_text(out_id, "",
                             uncertain ? textio::format_predictions_csv(points, sigmas, extrapolated, output_unit)
                                       : textio::format_points_csv(points, output_unit));
  if (error.ok()) error = outputs.commit();
  if (error.ok() && uncertain) {
    std::fprintf(stderr, "%s: %s: extrapolated when %s\n", kPredictCommand, count.text().c_str(),
                 extrapolation_rule(calibration.uncertainty.domain).c_str());
  } else if (error.ok() && !nominal) {
    std::fprintf(stderr,
                 "%s: %s holds no covariance and domain (made before they were written): no sigma_m, no "
                 "extrapolated column\n",
                 kPredictCommand, options.get("calibration").c_str());
  }
  return error;
}

}  // namespace

int predict_main(int argc, char** argv) {
  std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result (robot-calibration/1 JSON)", ""},
      {"robot-model", "NAME|FILE",
       "or a nominal arm (built-in name, description .json or .urdf): base frame; checks a robot file", ""},
      {"joints", "FILE",
       "poses to predict: CSV q1..qN (the calibrated arm's N joints) [rad], optional leading t column ('-': stdin)",
       ""},
      {"frame", "tracker|base", "frame of the predicted positions", "tracker"},
      {"target", "K", "which target's (reflector's) positions: 1 .. the result's \"tools\" count", "1"},
      {"out", "FILE",
       "predicted positions x,y,z [m] (CSV; '-' for stdout), with a result's covariance and domain also sigma_m (1 "
       "sigma per axis) and extrapolated (0/1)",
       "-"},
      {"output-length-unit", "m|mm", "unit of the predicted positions (mm: header x [mm],y [mm],z [mm])", "m"},
  };
  for (const OptionSpec& spec : input_unit_option_specs())  // the poses are joints: no length unit
    if (spec.name != "length-unit") specs.push_back(spec);
  Options options;
  const int parsed = parse_options(kPredictCommand,
                                   "Predicts the tool position of each joint pose with a calibrated model:\n"
                                   "base_to_tracker * FK(q) * tool (or FK(q) * tool with --frame base); --target K\n"
                                   "uses target K's tool point.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kPredictCommand, predict(options));
}

}  // namespace hivecal::cli
