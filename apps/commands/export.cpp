// hivecal export: a calibration (or a nominal arm) in the robot's own formats: URDF, or a
// robot description JSON (what --robot-model reads).
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/uncertainty.hpp"
#include "hivecal/calibration.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"
#include "record/report_json.hpp"
#include "textio/robot_description.hpp"
#include "textio/json.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/ur_kinematics.hpp"
#include "textio/urdf.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

namespace {

/// The arm to export: a result (with its base -> tracker; *result_text gets the file's text),
/// or --robot-model with --ur-calibration's deltas applied when given.
Error load_arm(const Options& options, record::CalibrationFile* arm, bool* has_tracker, std::string* result_text) {
  const bool from_result = !options.get("calibration").empty();
  if (from_result == options.given("robot-model")) {
    return Error::usage("give either --calibration (a result) or --robot-model (see --help)");
  }
  if (from_result && options.given("ur-calibration")) {
    return Error::usage("--ur-calibration goes with --robot-model: a result is calibrated already");
  }
  *has_tracker = from_result;
  if (from_result) return record::read_calibration_json(options.get("calibration"), arm, result_text);
  textio::RobotDescription& robot = *arm;
  const Error error = robot_model_option(options, "robot-model", &robot);
  if (!error.ok() || options.get("ur-calibration").empty()) return error;
  const RobotModel nominal = robot.model;
  return textio::read_ur_calibrated_model(options.get("ur-calibration"), nominal, robot.robot, &robot.model);
}

/// `model`'s point of a sample (its target) in the tracker frame [m].
Vec3 predicted_m(const RobotModel& model, const RigidTransform& base_to_tracker, const report::SampleRow& s) {
  return base_to_tracker.apply(fk_target_point(model, joint_vector(s.q_rad), s.target));
}

/// Mean 3D distance of `model`'s predictions from the samples' tracker points [m].
double mae_m(const RobotModel& model, const RigidTransform& base_to_tracker,
             const std::vector<report::SampleRow>& samples) {
  double sum_m = 0.0;
  for (const report::SampleRow& s : samples) sum_m += (predicted_m(model, base_to_tracker, s) - s.measured_m).norm();
  return sum_m / static_cast<double>(samples.size());
}

/// "2 compliance term(s) (joint deflection under gravity) and 12 harmonic term(s) (joint-angle
/// harmonics: ...)": each kind of the terms in use (a coefficient other than 0); "" when none is.
std::string terms_text(const ComplianceModel& compliance) {
  int harmonics = 0;
  int gravity = 0;
  for (int t = 0; t < compliance.term_count; ++t) {
    if (compliance.coefficient[t] == 0.0) continue;
    (is_harmonic(compliance.terms[t]) ? harmonics : gravity) += 1;
  }
  std::string text;
  if (gravity > 0) text = std::to_string(gravity) + " compliance term(s) (joint deflection under gravity)";
  if (gravity > 0 && harmonics > 0) text += " and ";
  if (harmonics > 0) {
    text += std::to_string(harmonics) +
            " harmonic term(s) (joint-angle harmonics: encoder eccentricity, transmission error)";
  }
  return text;
}

/// The rigid chain that best reproduces a model with joint terms: LM fits the rigid model's
/// geometry, tool points and base (every parameter the poses identify, the model's rigid part
/// as the prior with the job's tolerances) to the full model's points of the training poses.
struct RigidApproximation {
  RobotModel model;                ///< the rigid chain [m, rad]
  RigidTransform base_to_tracker;  ///< its base -> tracker transform
  double mean_m = 0.0;             ///< mean distance from the full model's points over the poses [m]
  double max_m = 0.0;              ///< the largest [m]
};

/// Fits the rigid chain of `arm` (joint terms) to its own predictions of `train`; false when LM fails.
bool fit_rigid_chain(const record::CalibrationFile& arm, const std::vector<report::SampleRow>& train,
                     RigidApproximation* out) {
  std::vector<Sample> samples;
  samples.reserve(train.size());
  for (const report::SampleRow& s : train) {
    Sample sample;
    sample.q_rad = joint_vector(s.q_rad);
    sample.point_m = predicted_m(arm.model, arm.base_to_tracker, s);
    sample.target = s.target;
    sample.index = static_cast<std::uint32_t>(samples.size());
    samples.push_back(sample);
  }
  RobotModel rigid = arm.model;
  rigid.compliance = ComplianceModel{};
  LmOptions options;
  options.other_target_tools = arm.target_count > 1;
  options.prior = LmPrior{&rigid, kDefaultPriorTolerances};
  const auto workspace = std::make_unique<LmWorkspaceWithTargets>();
  const auto result = std::make_unique<LmResult>();
  const Status status = calibrate_lm(rigid, &arm.base_to_tracker, Span<const Sample>(samples.data(), samples.size()),
                                     options, workspace.get(), result.get());
  if (status != Status::ok && status != Status::not_converged) return false;
  out->model = result->model;
  out->base_to_tracker = result->base_to_tracker;
  out->mean_m = 0.0;
  out->max_m = 0.0;
  for (const Sample& s : samples) {
    const double gap_m =
        (out->base_to_tracker.apply(fk_target_point(out->model, s.q_rad, s.target)) - s.point_m).norm();
    out->mean_m += gap_m / static_cast<double>(samples.size());
    out->max_m = std::fmax(out->max_m, gap_m);
  }
  return true;
}

/// What a format cannot hold is said, never dropped in silence: a model with joint terms goes
/// out as the rigid chain fitted to it over the result's training poses (*arm then holds it),
/// with the difference that remains, and what the terms' rigid part alone would have cost.
void write_rigid_chain_of_terms(const std::string& format, const std::string& result_text,
                                const std::string& result_path, record::CalibrationFile* arm) {
  if (arm->model.compliance.term_count == 0 || format == "robot-json") return;
  const char* into = format == "urdf" ? "URDF" : "the UR kinematics YAML";
  const std::string terms = terms_text(arm->model.compliance);
  if (terms.empty()) {  // every term at 0 (none admitted): the model is its rigid chain
    arm->model.compliance = ComplianceModel{};
    return;
  }
  const std::vector<report::SampleRow> train = result_text.empty()
                                                   ? std::vector<report::SampleRow>()
                                                   : record::report_training_samples(result_text, result_path);
  RigidApproximation fitted;
  if (train.empty() || !fit_rigid_chain(*arm, train, &fitted)) {
    std::fprintf(stderr,
                 "hivecal export: note: the model's %s cannot be written in %s, and the file keeps no training poses "
                 "to fit a rigid chain to the full model on: the chain is the rigid geometry as it is; predict with "
                 "the result file (or --format robot-json) for the full model\n",
                 terms.c_str(), into);
    arm->model.compliance = ComplianceModel{};
    return;
  }
  RobotModel rigid_part = arm->model;
  rigid_part.compliance = ComplianceModel{};
  const double full_m = mae_m(arm->model, arm->base_to_tracker, train);
  const double part_m = mae_m(rigid_part, arm->base_to_tracker, train);
  const double chain_m = mae_m(fitted.model, fitted.base_to_tracker, train);
  std::fprintf(
      stderr,
      "hivecal export: note: the model's %s cannot be written in %s: the chain written is the rigid chain that "
      "best reproduces the full model on the result's %zu training samples (tool points and tracker frame "
      "fitted with it), %.2f um from the full model's points on average, %.2f um at most; predict with the "
      "result file (or --format robot-json) for the full model\n",
      terms.c_str(), into, train.size(), fitted.mean_m * 1e6, fitted.max_m * 1e6);
  std::fprintf(stderr,
               "hivecal export: note: on those samples the MAE (3D) is %.2f um with the full model, %.2f um with the "
               "chain written, %.2f um with the full model's rigid part alone\n",
               full_m * 1e6, chain_m * 1e6, part_m * 1e6);
  arm->model = fitted.model;
  arm->base_to_tracker = fitted.base_to_tracker;
}

/// The ROS UR kinematics YAML of `arm`, its hash the robot's (--ur-hash) or one of its own.
Error ur_kinematics_yaml(const Options& options, const record::CalibrationFile& arm, std::string* yaml) {
  if (arm.convention != DhConvention::standard) {
    return Error::input("--format ur-kinematics: the arm is described in modified DH: not a UR arm; use --format urdf");
  }
  if (textio::is_ur_table_turned(arm.model)) {
    std::fprintf(stderr,
                 "hivecal export: note: the arm's table is UR's with every a and alpha negated (described from a base "
                 "turned by 180 deg about z, as ROS's base_link is): the YAML is written in UR's own base\n");
  }
  textio::UrKinematics kinematics;
  std::string why;
  if (!textio::ur_kinematics_from_model(arm.model, &kinematics, &why))
    return Error::input("--format ur-kinematics: " + why);
  const Vec3 flange_offset = kinematics.flange.translation_m;
  const double flange_twist_rad = std::acos(std::fmin(1.0, std::fmax(-1.0, kinematics.flange.rotation(1, 1))));
  if (flange_offset.norm() > 0.0 || flange_twist_rad > 0.0) {
    std::fprintf(stderr,
                 "hivecal export: note: the YAML has no flange entry: a6 = %.4f mm and alpha6 = %.4f mrad are left "
                 "out; they belong in the TCP set on the controller (Tx(a6) Rx(alpha6) before the tool point)\n",
                 flange_offset.x() * 1e3, flange_twist_rad * 1e3);
  }
  std::string hash = options.get("ur-hash");
  if (hash.empty()) {
    // The driver compares this with the robot's own calibration hash and warns when they differ.
    Digest digest;
    for (const RigidTransform& frame : kinematics.joint_frames) {
      digest.add(frame.rotation);
      digest.add(frame.translation_m);
    }
    char text[48];
    std::snprintf(text, sizeof text, "calib_hivecal_%016llx", static_cast<unsigned long long>(digest.value()));
    hash = text;
    std::fprintf(stderr,
                 "hivecal export: note: hash %s is hivecal's: the UR driver warns that it is not the robot's own "
                 "(--ur-hash passes the robot's through)\n",
                 hash.c_str());
  }
  *yaml = textio::format_ur_kinematics_yaml(kinematics, hash);
  return Error{};
}

Error export_arm(const Options& options) {
  const std::string format = options.get("format");
  if (format != "urdf" && format != "robot-json" && format != "ur-kinematics") {
    return Error::usage("--format must be urdf, ur-kinematics or robot-json, not " + port::quoted(format));
  }
  const std::string hash = options.get("ur-hash");
  if (options.given("ur-hash") && format != "ur-kinematics") {  // it was dropped without a word
    return Error::usage("--ur-hash goes with --format ur-kinematics: a " + format +
                        " has no calibration hash; leave it out, or give --format ur-kinematics");
  }
  for (const char c : hash) {
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) {
      return Error::usage("--ur-hash must be letters, digits and '_' (e.g. calib_12788084448423163542), not " +
                          port::quoted(hash));
    }
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  Error error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (!error.ok()) return error;
  record::CalibrationFile arm;
  bool has_tracker = false;
  std::string result_text;  // read once: the arm, and the training samples of its report
  error = load_arm(options, &arm, &has_tracker, &result_text);
  if (!error.ok()) return error;
  write_rigid_chain_of_terms(format, result_text, options.get("calibration"), &arm);
  for (const std::string& line :
       domain_lines(arm.uncertainty, arm.model.joint_count))  // what the exported model holds within
    std::fprintf(stderr, "hivecal export: note: %s\n", line.c_str());
  std::string text;
  if (format == "urdf") {
    text = textio::format_urdf(arm, has_tracker ? &arm.base_to_tracker : nullptr);
  } else if (format == "ur-kinematics") {
    error = ur_kinematics_yaml(options, arm, &text);
  } else {
    text = textio::format_robot_description(arm);
  }
  if (error.ok()) error = outputs.stage_text(out_id, "", text);
  return error.ok() ? outputs.commit() : error;
}

}  // namespace

int export_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result (robot-calibration/1 JSON) to export", ""},
      {"robot-model", "NAME|FILE", "or a nominal arm: built-in table name or robot description .json", ""},
      {"ur-calibration", "FILE", "with --robot-model: a UR calibration.conf applied to it", ""},
      {"format", "urdf|ur-kinematics|robot-json",
       "URDF serial chain (tcp per target, tracker frame), the ROS UR driver's kinematics YAML, or a robot description",
       "urdf"},
      {"ur-hash", "HASH", "with ur-kinematics: the robot's own calibration hash (e.g. calib_12788084448423163542)", ""},
      {"out", "FILE", "where the document goes; '-' for stdout", "-"},
  };
  Options options;
  const int parsed = parse_options(kExportCommand,
                                   "Writes a calibration (or a nominal arm, with a UR calibration.conf applied) in\n"
                                   "the robot's own formats: a URDF chain whose forward kinematics equal the\n"
                                   "model's (joints turn about z of each DH frame; links base_link, link_1..6,\n"
                                   "flange, tcp per target, tracker), the ROS UR driver's kinematics YAML (UR arms;\n"
                                   "the parallel joints' frames moved along their axes as UR's converter does), or a\n"
                                   "robot description JSON.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kExportCommand, export_arm(options));
}

}  // namespace hivecal::cli
