// hivecal export: a calibration (or a nominal arm) in the robot's own formats: URDF, or a
// robot description JSON (what --robot-model reads).
#include <cstdio>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"
#include "report/report_json.hpp"
#include "textio/calibration_json.hpp"
#include "textio/json.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/urdf.hpp"

namespace hivecal::cli {

namespace {

constexpr const char* kCommand = "export";

/// The arm to export: a result (with its base -> tracker), or --robot-model with
/// --ur-calibration's deltas applied when given.
Error load_arm(const Options& options, textio::CalibrationFile* arm, bool* has_tracker) {
  const bool from_result = !options.get("calibration").empty();
  if (from_result == options.given("robot-model")) {
    return Error::usage("give either --calibration (a result) or --robot-model (see --help)");
  }
  if (from_result && options.given("ur-calibration")) {
    return Error::usage("--ur-calibration goes with --robot-model: a result is calibrated already");
  }
  *has_tracker = from_result;
  if (from_result) return textio::read_calibration_json(options.get("calibration"), arm);
  textio::RobotDescription& robot = *arm;
  Error error = robot_model_option(options, "robot-model", &robot);
  if (!error.ok() || options.get("ur-calibration").empty()) return error;
  UrCalibrationDeltas deltas;
  port::Error r = textio::read_ur_calibration_conf(options.get("ur-calibration"), &deltas);
  if (r.ok()) r = textio::check_ur_deltas_plausible(robot.model, deltas, options.get("ur-calibration"), robot.robot);
  if (!r.ok()) return r;
  RobotModel calibrated;
  (void)apply_ur_deltas(robot.model, deltas, &calibrated);
  calibrated.tool_m = robot.model.tool_m;
  robot.model = calibrated;
  return Error{};
}

/// The training samples a result keeps in its report (none when it has no report).
std::vector<report::SampleRow> training_samples(const std::string& result_path) {
  std::string text;
  textio::JsonValue root;
  report::ReportData data;
  const textio::JsonValue* saved = nullptr;
  if (!port::read_whole_file(result_path, port::kMaxTextInputBytes, &text).ok() ||
      !textio::parse_json(text, &root).ok() || (saved = root.find("report")) == nullptr ||
      !report::parse_report_data(*saved, result_path, &data).ok()) {
    return {};
  }
  std::vector<report::SampleRow> train;
  for (const report::SampleRow& sample : data.samples)
    if (!sample.test) train.push_back(sample);
  return train;
}

/// Mean 3D distance of `model`'s predictions from the samples' tracker points [m].
double mae_m(const RobotModel& model, const RigidTransform& base_to_tracker, const std::vector<report::SampleRow>& samples) {
  double sum_m = 0.0;
  for (const report::SampleRow& s : samples) {
    const JointVector q = Eigen::Map<const JointVector>(s.q_rad);
    sum_m += (base_to_tracker.apply(fk_target_point(model, q, s.target)) - s.measured_m).norm();
  }
  return sum_m / static_cast<double>(samples.size());
}

/// What a format cannot hold is said, with what leaving it out costs on the result's own
/// training samples, never dropped in silence.
void say_what_is_left_out(const textio::CalibrationFile& arm, const std::string& format, const std::string& result_path) {
  if (arm.model.compliance.term_count == 0 || format != "urdf") return;
  std::fprintf(stderr,
               "hivecal export: note: the model's %d compliance terms (joint deflection under gravity) cannot be "
               "written in URDF: the chain is the rigid geometry only; predict with the result file for the full "
               "model\n",
               arm.model.compliance.term_count);
  const std::vector<report::SampleRow> train = result_path.empty() ? std::vector<report::SampleRow>() : training_samples(result_path);
  if (train.empty()) return;
  RobotModel rigid = arm.model;
  rigid.compliance = ComplianceModel{};
  const double full_m = mae_m(arm.model, arm.base_to_tracker, train);
  const double rigid_m = mae_m(rigid, arm.base_to_tracker, train);
  std::fprintf(stderr,
               "hivecal export: note: on the result's %zu training samples the MAE (3D) is %.2f um with the compliance "
               "and %.2f um with the URDF's rigid chain (%+.2f um)\n",
               train.size(), full_m * 1e6, rigid_m * 1e6, (rigid_m - full_m) * 1e6);
}

Error export_arm(const Options& options) {
  const std::string format = options.get("format");
  if (format != "urdf" && format != "robot-json") {
    return Error::usage("--format must be urdf or robot-json, not " + port::quoted(format));
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  Error error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (!error.ok()) return error;
  textio::CalibrationFile arm;
  bool has_tracker = false;
  error = load_arm(options, &arm, &has_tracker);
  if (!error.ok()) return error;
  say_what_is_left_out(arm, format, options.get("calibration"));
  const std::string text = format == "urdf" ? textio::format_urdf(arm, has_tracker ? &arm.base_to_tracker : nullptr)
                                            : textio::format_robot_description(arm);
  error = outputs.stage_text(out_id, "", text);
  return error.ok() ? outputs.commit() : error;
}

}  // namespace

int export_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result (robot-calibration/1 JSON) to export", ""},
      {"robot-model", "NAME|FILE", "or a nominal arm: built-in table name or robot description .json", ""},
      {"ur-calibration", "FILE", "with --robot-model: a UR calibration.conf applied to it", ""},
      {"format", "urdf|robot-json", "URDF serial chain (tcp per target, tracker frame), or a robot description", "urdf"},
      {"out", "FILE", "where the document goes; '-' for stdout", "-"},
  };
  Options options;
  const int parsed = parse_options(kCommand,
                                   "Writes a calibration (or a nominal arm, with a UR calibration.conf applied) in\n"
                                   "the robot's own formats: a URDF chain whose forward kinematics equal the\n"
                                   "model's (joints turn about z of each DH frame; links base_link, link_1..6,\n"
                                   "flange, tcp per target, tracker), or a robot description JSON.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kCommand, export_arm(options));
}

}  // namespace hivecal::cli
