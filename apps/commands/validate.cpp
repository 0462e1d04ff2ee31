// hivecal validate: a calibration against a reference geometry (e.g. the simulator's
// noise-free truth.json) on fresh random poses: how far apart do they predict the tool?
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/sample_reader.hpp"
#include "commands/validation.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "sim/sim_model.hpp"
#include "textio/robot_description.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

ValidationStats validate_on_fresh_poses(const RobotModel& model, const RigidTransform& base_to_tracker,
                                        const RobotModel& reference, const RigidTransform& reference_base_to_tracker,
                                        long poses, std::uint64_t seed,
                                        const ReferenceCompliance& reference_compliance) {
  const bool bent = reference_compliance.joint2_rad != 0.0 || reference_compliance.joint3_rad != 0.0;
  Random random(seed);
  ValidationStats stats;
  double sum_m = 0.0;
  for (long i = 0; i < poses; ++i) {
    JointVector q = JointVector::Zero();  // the workspace the simulator and the paper use: shoulder up, tool down-ish
    const double first_six[kSixJoints][2] = {{-3.0, 3.0}, {-2.6, -0.5}, {-2.4, 2.4},
                                             {-3.0, 0.0}, {-2.8, -0.3}, {-3.0, 3.0}};
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(first_six[j][0], first_six[j][1]);
    // A 7th .. joint turns as the simulator's (a slide anywhere on its first half metre), drawn
    // after the six so that a six-joint arm's poses stay as they were.
    for (int j = kSixJoints; j < std::max(model.joint_count, reference.joint_count); ++j)
      q(j) = random.uniform(-1.5, 1.5);
    for (int j = 0; j < model.joint_count; ++j) {
      if (joint_type(model, j) == JointType::prismatic) q(j) = 0.5 * std::fabs(q(j)) / 3.0;
    }
    const Vec3 a = base_to_tracker.apply(fk_tool_point(model, q));
    const JointVector q_reference =
        bent ? JointVector(q + sim::simulated_compliance(reference, reference_compliance.joint2_rad,
                                                         reference_compliance.joint3_rad, q))
             : q;
    const Vec3 b = reference_base_to_tracker.apply(fk_tool_point(reference, q_reference));
    const double e = (a - b).norm();
    sum_m += e;
    stats.max_m = std::max(stats.max_m, e);
  }
  stats.poses = poses;
  stats.mae_m = poses > 0 ? sum_m / static_cast<double>(poses) : 0.0;
  return stats;
}

namespace {

/// `model` without its compliance: the geometry alone.
RobotModel rigid_part(RobotModel model) {
  model.compliance = ComplianceModel{};
  return model;
}

/// A simulator's truth file: its "simulation"."compliance" (*found false for any other file).
port::Error simulated_compliance_of(const std::string& path, ReferenceCompliance* compliance, bool* found) {
  *found = false;
  std::string text;
  textio::JsonValue root;
  port::Error r = port::read_whole_file(path, port::kMaxTextInputBytes, &text);
  if (r.ok()) r = textio::parse_json(text, &root);
  if (!r.ok()) return r;
  const textio::JsonValue* simulation = root.find("simulation");
  const textio::JsonValue* c = simulation != nullptr ? simulation->find("compliance") : nullptr;
  if (c == nullptr) return port::Error{};
  const textio::JsonValue* j2 = c->find("joint2_rad");
  const textio::JsonValue* j3 = c->find("joint3_rad");
  if (j2 == nullptr || j3 == nullptr || j2->kind != textio::JsonValue::Kind::number ||
      j3->kind != textio::JsonValue::Kind::number) {
    return port::Error::input(path + ": \"simulation\".\"compliance\" must hold numbers joint2_rad and joint3_rad");
  }
  for (const textio::JsonValue* joint : {j2, j3}) {  // a joint's gravity deflection: bounded as a coefficient is
    if (!(std::fabs(joint->number) <= kMaxJointTermCoefficient)) {
      return port::Error::input(path + ": \"simulation\".\"compliance\" " +
                                (joint == j2 ? "joint2_rad" : "joint3_rad") + " = " +
                                textio::format_double(joint->number) + " must be within +/-" +
                                textio::format_double(kMaxJointTermCoefficient) +
                                " rad (a joint's deflection under gravity; real arms: 1e-6 .. 1e-4)");
    }
  }
  compliance->joint2_rad = j2->number;
  compliance->joint3_rad = j3->number;
  *found = true;
  return port::Error{};
}

}  // namespace

int validate_main(int argc, char** argv) {
  std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result to check (robot-calibration/1 JSON)", ""},
      {"truth", "FILE", "reference geometry (robot-calibration/1 JSON, e.g. the simulator's truth.json)", ""},
      {"poses", "N", "with --truth: number of fresh random poses", "1000"},
      {"seed", "N", "with --truth: seed of the poses", "7"},
      {"samples", "FILE",
       "or measured samples q1..qN,x,y,z[,rx,ry,rz] (the arm's N joints; read as calibrate reads them; '-': stdin): "
       "MAE, sigma and max "
       "per axis and 3D, each pose's error by file line",
       ""},
      {"fit", "base|frames",
       "with --samples: register the calibration on them first (the base -> tracker transform; 'frames': and the tool "
       "points)",
       ""},
      {"fit-poses", "N", "with --fit: register on the first N poses of --samples and score the others (default: all)",
       ""},
      {"keep-outliers", "", "with --fit: no w-test of the registration's poses", ""},
      {"out", "FILE", "with --samples: the metrics and the per-pose table as JSON ('-': stdout)", ""},
  };
  for (const OptionSpec& spec : sample_reader_option_specs()) specs.push_back(spec);
  Options options;
  const int parsed = parse_options(kValidateCommand,
                                   "With --truth: predicts the tool point of fresh random poses with both geometries\n"
                                   "(each with its own base -> tracker transform) and reports how far apart they are.\n"
                                   "With --samples: scores the calibration on measured samples (after registering it\n"
                                   "on them with --fit).",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  if (options.given("samples")) {
    std::vector<std::string> warnings;
    const int code = exit_with(kValidateCommand, validate_on_samples(options, &warnings));
    for (const std::string& warning : warnings) cli::error(kValidateCommand, "warning: " + warning);
    return code == kExitOk && !warnings.empty() ? kExitWarnings : code;
  }
  for (const char* name : {"fit", "fit-poses", "keep-outliers", "out"}) {
    if (options.given(name))
      return exit_with(kValidateCommand, Error::usage(std::string("--") + name + " needs --samples"));
  }
  if (options.get("calibration").empty() || options.get("truth").empty()) {
    return exit_with(kValidateCommand,
                     Error::usage("--calibration and --truth (or --samples) are required (see --help)"));
  }
  std::size_t poses = 0;
  std::uint64_t seed = 0;
  Error numbers = count_option(options, "poses", 1, 10000000, &poses);
  if (numbers.ok()) numbers = seed_option(options, "seed", &seed);
  if (!numbers.ok()) return exit_with(kValidateCommand, numbers);
  record::CalibrationFile calibration;
  record::CalibrationFile truth;
  for (auto [path, file] :
       {std::pair{options.get("calibration"), &calibration}, std::pair{options.get("truth"), &truth}}) {
    const port::Error r = record::read_calibration_json(path, file);
    if (!r.ok()) return exit_with(kValidateCommand, r);
  }
  if (calibration.model.joint_count != truth.model.joint_count) {  // the same poses mean nothing to both
    return exit_with(kValidateCommand,
                     port::Error::input("--calibration's arm has " + std::to_string(calibration.model.joint_count) +
                                        " joints but --truth's " + std::to_string(truth.model.joint_count) +
                                        ": the geometries of two different arms"));
  }
  ReferenceCompliance bent;
  bool simulated = false;
  const port::Error r = simulated_compliance_of(options.get("truth"), &bent, &simulated);
  if (!r.ok()) return exit_with(kValidateCommand, r);
  const long n = static_cast<long>(poses);
  const std::uint64_t s = static_cast<std::uint64_t>(seed);
  // The geometries alone (DH, tool, base; any compliance model left out): how well the
  // calibration recovered the truth's table.
  const ValidationStats geometry = validate_on_fresh_poses(rigid_part(calibration.model), calibration.base_to_tracker,
                                                           rigid_part(truth.model), truth.base_to_tracker, n, s);
  std::printf("validation on %ld fresh poses vs %s: MAE 3D %.2f um, max %.2f um%s\n", geometry.poses,
              options.get("truth").c_str(), geometry.mae_m * 1e6, geometry.max_m * 1e6,
              simulated || calibration.model.compliance.term_count > 0 ? " (geometry only, no compliance)" : "");
  ValidationStats points;
  if (simulated) {  // where the simulated tool truly was: the truth bent by the simulator's compliance
    points = validate_on_fresh_poses(calibration.model, calibration.base_to_tracker, truth.model, truth.base_to_tracker,
                                     n, s, bent);
    std::printf(
        "validation on %ld fresh poses vs the true tool points (the simulated compliance included): "
        "MAE 3D %.2f um, max %.2f um\n",
        points.poses, points.mae_m * 1e6, points.max_m * 1e6);
  }
  // A figure that is no number says nothing: the models' points overflowed (a huge file value).
  if (!std::isfinite(geometry.mae_m + geometry.max_m + points.mae_m + points.max_m)) {
    error(kValidateCommand,
          "warning: a validation figure is not finite (the predicted points overflow): check the files' values");
    return kExitWarnings;
  }
  return kExitOk;
}

}  // namespace hivecal::cli
