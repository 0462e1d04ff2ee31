#include "commands/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/identifiability.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/core/random.hpp"

namespace hivecal::cli {

namespace {

/// |correlation| above which a moved parameter's warning names the one it cannot be told from.
constexpr double kStrongCorrelation = 0.95;

/// "; strongly correlated with X (rho = ...): ..." for `name` in `parameters`, or "".
std::string correlation_cause(const char* name, const std::vector<report::ParameterRow>& parameters) {
  for (const report::ParameterRow& row : parameters) {
    if (row.name != name || row.correlated_with.empty() || !(std::fabs(row.correlation) > kStrongCorrelation)) continue;
    char text[300];
    std::snprintf(text, sizeof text,
                  "; it is strongly correlated with %s (rho = %.3f): the data cannot separate the two, so the move "
                  "may be theirs together (more poses spread over the joints that couple them, the tool's "
                  "orientation, or a second reflector would separate them)",
                  row.correlated_with.c_str(), row.correlation);
    return text;
  }
  return "";
}

/// The tool point's and the base's bits of `model`: what the job's baseline fits (fit_baseline).
ParamMask baseline_mask(const RobotModel& model) {
  ParamMask mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    mask |= param_bit(tool_param_index(model, axis)) | param_bit(base_rotation_param_index(model, axis)) |
            param_bit(base_translation_param_index(model, axis));
  }
  return mask;
}

/// Training MAE (3D) of `model` with its tool points and base fitted to `train` as the job's
/// baseline fits them (closed form, then LM over the tool point and the base) [m]; +inf when
/// the fit fails.
double baseline_mae_m(RobotModel model, Span<const Sample> train, LmWorkspace* workspace, LmResult* fit) {
  RigidTransform base;
  if (fit_base_and_target_tools(train, &model, &base) != Status::ok) return HUGE_VAL;
  LmOptions options;
  options.params = LmParamSet::custom;
  options.custom_mask = baseline_mask(model);
  if (3 * train.size() > 9) {  // fewer samples: the closed form's base alone, as the job's baseline
    const Status status = calibrate_lm(model, &base, train, options, workspace, fit);
    if (status != Status::ok && status != Status::not_converged) return HUGE_VAL;
    model = fit->model;
    base = fit->base_to_tracker;
  }
  return position_error_stats(model, base, train).mae(ErrorAxis::norm_3d);
}

/// Joint number (1-based) of a DH parameter's name ("d5" -> 5), 0 for any other name.
int joint_of(const std::string& name) {
  const bool dh =
      name.rfind("theta", 0) == 0 || name.rfind("alpha", 0) == 0 || name.rfind("d", 0) == 0 || name.rfind("a", 0) == 0;
  const char last = name.empty() ? '\0' : name.back();
  return dh && last >= '1' && last <= '9' ? last - '0' : 0;
}

/// What poses would tell parameters `a` and `b` apart: more tool orientations when the tool
/// point or the wrist (joints 5, 6) takes part, a wider range of each joint they belong to,
/// poses spread wider when the base does.
std::string what_separates(const std::string& a, const std::string& b) {
  std::vector<std::string> ways;
  const int joints[] = {joint_of(a), joint_of(b)};
  const bool tool = a.rfind("tool", 0) == 0 || b.rfind("tool", 0) == 0;
  if (tool || joints[0] >= 5 || joints[1] >= 5) ways.push_back("more tool orientations");
  for (int k = 0; k < 2; ++k) {
    if (joints[k] == 0 || (k == 1 && joints[1] == joints[0])) continue;
    ways.push_back("a wider range of joint " + std::to_string(joints[k]));
  }
  if (a.rfind("base", 0) == 0 || b.rfind("base", 0) == 0) ways.push_back("poses spread wider over the workspace");
  if (ways.empty()) ways.push_back("poses spread wider over every joint's range");
  std::string text = ways[0];
  for (std::size_t k = 1; k < ways.size(); ++k) text += " or " + ways[k];
  return text;
}

}  // namespace

std::string other_arm_hint(const std::string& robot, const RobotModel& start, Span<const Sample> train) {
  RobotType given = RobotType::ur5;
  if (robot_type_from_name(robot.c_str(), &given) != Status::ok) return "";
  const RobotModel nominal = nominal_model(given);
  if (nominal.joint_count != start.joint_count) return "";
  for (int j = 0; j < nominal.joint_count; ++j) {  // a description file or a controller's calibration: not the table
    const DhJoint& a = nominal.joints[j];
    const DhJoint& b = start.joints[j];
    if (a.theta_offset_rad != b.theta_offset_rad || a.d_m != b.d_m || a.a_m != b.a_m || a.alpha_rad != b.alpha_rad)
      return "";
  }
  const auto workspace = std::make_unique<LmWorkspaceWithTargets>();
  const auto fit = std::make_unique<LmResult>();
  const double given_mae_m = baseline_mae_m(start, train, workspace.get(), fit.get());
  RobotType best = given;
  double best_mae_m = given_mae_m;
  for (const RobotType other : builtin_robot_types()) {  // the arms of as many joints as the one given
    RobotModel model = nominal_model(other);
    if (other == given || model.joint_count != nominal.joint_count) continue;
    model.tool_m = start.tool_m;  // the same tool points to start from
    for (int k = 0; k < kMaxTargets - 1; ++k) model.other_tools_m[k] = start.other_tools_m[k];
    const double mae_m = baseline_mae_m(model, train, workspace.get(), fit.get());
    if (mae_m < best_mae_m) {
      best = other;
      best_mae_m = mae_m;
    }
  }
  if (best == given || !(best_mae_m < kOtherArmMaeRatio * given_mae_m)) return "";
  const std::string name = robot_type_name(best);
  char line[400];
  std::snprintf(line, sizeof line,
                "this looks like a %s (--robot-model %s): its nominal geometry with the tool point and base fitted "
                "leaves %.3f mm (MAE 3D) on the training samples, against %.3f mm for the %s given",
                name.c_str(), name.c_str(), best_mae_m * 1e3, given_mae_m * 1e3, robot.c_str());
  return line;
}

int model_parameter_count(const RobotModel& start, ParamMask free_mask, int targets) {
  constexpr int kPoses = 48;  // well spread: a UR's 33 need some 15; the analysis is ~0.2 ms
  std::vector<Sample> samples;
  Random random(1);
  for (int pose = 0; pose < kPoses; ++pose) {
    JointVector q;  // the validate command's workspace: shoulder up, tool down-ish
    q << random.uniform(-3.0, 3.0), random.uniform(-2.6, -0.5), random.uniform(-2.4, 2.4), random.uniform(-3.0, 0.0),
        random.uniform(-2.8, -0.3), random.uniform(-3.0, 3.0);
    for (int target = 0; target < targets; ++target) {
      Sample sample;
      sample.q_rad = q;
      sample.point_m = fk_target_point(start, q, target);
      sample.target = target;
      sample.index = static_cast<std::uint32_t>(samples.size());
      samples.push_back(sample);
    }
  }
  const auto normal = std::make_unique<NormalEquations>();
  const auto workspace = std::make_unique<IdentifiabilityWorkspace>();
  const auto report = std::make_unique<IdentifiabilityReport>();
  const ParamMask rigid = free_mask & rigid_params_mask(start);
  if (accumulate_normal_equations(start, RigidTransform{}, Span<const Sample>(samples.data(), samples.size()),
                                  PointLoss{}, normal.get(), rigid) != Status::ok ||
      analyze_identifiability(normal->jtwj, rigid, kDefaultIdentifiabilityThreshold, workspace.get(), report.get(), 0,
                              IdentifiabilityOutput::kept_set) != Status::ok) {
    return 0;
  }
  return report->kept_count();
}

std::string constant_orientation_warning(bool constant, double fit_sigma_m, double noise_sigma_m) {
  if (!constant || !(fit_sigma_m > kConstantOrientationNoiseRatio * noise_sigma_m)) return "";
  char line[400];
  std::snprintf(line, sizeof line,
                "the orientation columns rx, ry, rz hold one value on every row, and the fit's residual sigma is "
                "%.0fx the measurement noise: the orientation carries no information here (the joints turn the tool, "
                "the columns say it never turned) and contradicts the positions; leave it out (--orientation-lever-m "
                "0) or export the measured orientation",
                fit_sigma_m / noise_sigma_m);
  return line;
}

std::vector<std::string> prior_held_lines(const LmResult& lm, const LmPriorTolerances& tolerances,
                                          const std::vector<report::ParameterRow>& parameters) {
  std::vector<std::string> lines;
  const int joints = lm.model.joint_count;
  for (int k = 0; k < model_param_count(joints); ++k) {
    const double tolerance = prior_tolerance(tolerances, joints, k);
    if (!mask_has(lm.identifiability.kept_mask, k) || !(tolerance > 0.0) ||
        !(lm.sigma(k) > kPriorHeldSigmaShare * tolerance)) {
      continue;
    }
    const bool angle = model_param_is_angle(k, joints);
    const double unit = 1e3;  // mm, mrad
    char line[400];
    std::snprintf(line, sizeof line,
                  "  held    %-8s (by the nominal model's prior: sigma %.3g %s of its %.3g %s tolerance, the poses "
                  "determine it less than the tolerance does",
                  full_param_name(k, joints), lm.sigma(k) * unit, angle ? "mrad" : "mm", tolerance * unit,
                  angle ? "mrad" : "mm");
    std::string text = line;
    for (const report::ParameterRow& row : parameters) {
      if (row.name != full_param_name(k, joints) || row.correlated_with.empty()) continue;
      std::snprintf(line, sizeof line, "; correlated %+.3f with %s in the data: %s would separate them",
                    row.correlation, row.correlated_with.c_str(),
                    what_separates(row.name, row.correlated_with).c_str());
      text += line;
    }
    lines.push_back(text + ")");
  }
  return lines;
}

std::string prior_widened_line(const LmPriorTolerances& stated, const LmPriorTolerances& widened) {
  const auto factor = [](double held, double given) { return given > 0.0 ? held / given : 1.0; };
  char line[480];
  std::snprintf(line, sizeof line,
                "prior: the poses put the nominal model farther off than its tolerances allow (the prior's chi-square "
                "beyond its 5 %% quantile): tolerances widened to %.3g mm per DH length (x%.2f), %.3g mrad per DH "
                "angle (x%.2f), %.3g mm per tool coordinate (x%.2f) (--dh-tolerance-mm, --dh-tolerance-mrad, "
                "--tool-tolerance-mm)",
                widened.dh_length_m * 1e3, factor(widened.dh_length_m, stated.dh_length_m), widened.dh_angle_rad * 1e3,
                factor(widened.dh_angle_rad, stated.dh_angle_rad), widened.tool_m * 1e3,
                factor(widened.tool_m, stated.tool_m));
  return line;
}

std::vector<std::string> fit_warnings(const CalibrationResult& result, const FitBounds& bounds,
                                      const std::vector<report::ParameterRow>& parameters, const PoseSpan* span) {
  std::vector<std::string> warnings;
  const CalibrationStage* final_stage = result.final_stage();
  if (final_stage == nullptr) return warnings;
  const RobotModel& model = final_stage->model;
  const ModelParams before = to_params(result.baseline.model);
  const ModelParams after = to_params(model);
  char line[1024];
  for (int k = 0; k < model_param_count(model); ++k) {
    const double change = after(k) - before(k);
    const bool angle = model_param_is_angle(k, model.joint_count);
    if (std::fabs(change) <= (angle ? bounds.max_angle_change_rad : bounds.max_length_change_m)) continue;
    if (angle) {
      std::snprintf(line, sizeof line,
                    "%s moved %+.3f deg (%.6f -> %.6f rad), more than %.3g deg (--max-change-deg): wrong model, "
                    "joint zero or units?",
                    full_param_name(k, model), change * math::kDegPerRad, before(k), after(k),
                    bounds.max_angle_change_rad * math::kDegPerRad);
    } else {
      std::snprintf(line, sizeof line,
                    "%s moved %+.3f mm (%.6f -> %.6f m), more than %.3g mm (--max-change-mm): wrong model, tool "
                    "guess or units?",
                    full_param_name(k, model), change * 1e3, before(k), after(k), bounds.max_length_change_m * 1e3);
    }
    warnings.push_back(line + correlation_cause(full_param_name(k, model), parameters));
  }
  // Many samples of a few stops determine no more than those stops: 3 coordinates per distinct
  // point. No more of them than the parameters the fit determines (estimated, or fixed by the
  // significance test; not the structural nulls the identifiability analysis drops) leaves no
  // redundancy: the poses do not span the model, and test samples of the same stops do not show it.
  const int determined = result.has_lm ? mask_count(result.lm.identifiability.kept_mask | result.lm_pruned_mask) : 0;
  // The parameters the model has, not those the fit kept: with few poses the identifiability
  // analysis drops what they cannot tell apart, and the fit passes through them.
  if (span != nullptr && span->parameters > 0 && span->coordinates <= static_cast<std::size_t>(span->parameters)) {
    const double per_pose =
        static_cast<double>(span->coordinates) / static_cast<double>(std::max<std::size_t>(span->poses, 1));
    const int needed = static_cast<int>(std::floor(span->parameters / per_pose)) + 1;
    std::snprintf(line, sizeof line,
                  "the %zu training samples stand at only %zu distinct poses (%zu coordinates) for the %d "
                  "parameters this model has over a spread of poses (the fit estimated %d and dropped the others, "
                  "which these poses cannot tell apart): too few poses for the model, so the fit passes through them "
                  "and its training error says nothing of other poses; the poses do not span the model: measure at "
                  "least %d poses spread over every joint's range (hivecal plan)",
                  result.train_count, span->poses, span->coordinates, span->parameters,
                  result.has_lm ? result.lm.identifiability.kept_count() : 0, needed);
    warnings.push_back(line);
  } else if (span == nullptr && determined > 0 && 3 * result.train_points <= static_cast<std::size_t>(determined)) {
    std::snprintf(line, sizeof line,
                  "the %zu training samples stand at only %zu distinct poses (%zu coordinates) for the %d parameters "
                  "the fit determines: the poses do not span the model, so the calibration holds near these poses "
                  "only, and test samples at the same poses do not show it; measure more poses spread over every "
                  "joint's range (hivecal plan)",
                  result.train_count, result.train_points, 3 * result.train_points, determined);
    warnings.push_back(line);
  }
  // The prior holds what the data cannot move, so a wrong arm, joint zero or unit no longer
  // shows as parameters moved by centimetres: it shows as a residual no calibrated arm leaves.
  const double train_mae_m = final_stage->train.mae(ErrorAxis::norm_3d);
  if (final_stage->train.count > 0 && train_mae_m > kImplausibleTrainMae_m) {
    std::snprintf(line, sizeof line,
                  "the calibrated model leaves %.3f mm (MAE 3D) on its own training samples, more than the %.3g mm "
                  "no calibrated arm leaves: wrong model (--robot-model), joint zero, tool guess or units?",
                  train_mae_m * 1e3, kImplausibleTrainMae_m * 1e3);
    warnings.push_back(line);
  }
  // Worse by more than 1 %: a start model the fit leaves as it was (every change not significant)
  // has the baseline's test error up to rounding, which is no sign of a fit that does not carry.
  constexpr double kWorseThanBaselineRatio = 1.01;
  const double baseline_mae_m = result.baseline.test.mae(ErrorAxis::norm_3d);
  const double final_mae_m = final_stage->test.mae(ErrorAxis::norm_3d);
  if (final_stage->test.count > 0 && result.baseline.test.count > 0 &&
      final_mae_m > kWorseThanBaselineRatio * baseline_mae_m) {
    std::snprintf(line, sizeof line,
                  "test error %.4f mm (MAE 3D) is worse than the uncalibrated baseline's %.4f mm: the fit does not "
                  "carry to held-out poses (too few samples, blunders, or a wrong model?)",
                  final_mae_m * 1e3, baseline_mae_m * 1e3);
    warnings.push_back(line);
  }
  return warnings;
}

}  // namespace hivecal::cli
