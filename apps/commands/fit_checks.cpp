#include "commands/fit_checks.hpp"

#include <cmath>
#include <cstdio>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"

namespace hivecal::cli {

bool model_param_is_angle(int index) {
  if (index < 0 || index >= kDhParamCount) return false;  // the tool point is a length
  const int field = index % kParamsPerJoint;
  return field == static_cast<int>(DhField::theta_offset) || field == static_cast<int>(DhField::alpha);
}

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

std::vector<std::string> prior_held_lines(const LmResult& lm, const LmPriorTolerances& tolerances,
                                          const std::vector<report::ParameterRow>& parameters) {
  std::vector<std::string> lines;
  for (int k = 0; k < kModelParamCount; ++k) {
    const double tolerance = prior_tolerance(tolerances, k);
    if (!mask_has(lm.identifiability.kept_mask, k) || !(tolerance > 0.0) ||
        !(lm.sigma(k) > kPriorHeldSigmaShare * tolerance)) {
      continue;
    }
    const bool angle = model_param_is_angle(k);
    const double unit = 1e3;  // mm, mrad
    char line[400];
    std::snprintf(line, sizeof line,
                  "  held    %-8s (by the nominal model's prior: sigma %.3g %s of its %.3g %s tolerance, the poses "
                  "determine it less than the tolerance does",
                  full_param_name(k), lm.sigma(k) * unit, angle ? "mrad" : "mm", tolerance * unit,
                  angle ? "mrad" : "mm");
    std::string text = line;
    for (const report::ParameterRow& row : parameters) {
      if (row.name != full_param_name(k) || row.correlated_with.empty()) continue;
      std::snprintf(line, sizeof line, "; correlated %+.3f with %s in the data: %s would separate them",
                    row.correlation, row.correlated_with.c_str(),
                    what_separates(row.name, row.correlated_with).c_str());
      text += line;
    }
    lines.push_back(text + ")");
  }
  return lines;
}

std::vector<std::string> fit_warnings(const CalibrationResult& result, const FitBounds& bounds,
                                      const std::vector<report::ParameterRow>& parameters) {
  std::vector<std::string> warnings;
  const CalibrationStage* final_stage = result.final_stage();
  if (final_stage == nullptr) return warnings;
  const ModelParams before = to_params(result.baseline.model);
  const ModelParams after = to_params(final_stage->model);
  char line[512];
  for (int k = 0; k < kModelParamCount; ++k) {
    const double change = after(k) - before(k);
    const bool angle = model_param_is_angle(k);
    if (std::fabs(change) <= (angle ? bounds.max_angle_change_rad : bounds.max_length_change_m)) continue;
    if (angle) {
      std::snprintf(line, sizeof line,
                    "%s moved %+.3f deg (%.6f -> %.6f rad), more than %.3g deg (--max-change-deg): wrong model, "
                    "joint zero or units?",
                    full_param_name(k), change * math::kDegPerRad, before(k), after(k),
                    bounds.max_angle_change_rad * math::kDegPerRad);
    } else {
      std::snprintf(line, sizeof line,
                    "%s moved %+.3f mm (%.6f -> %.6f m), more than %.3g mm (--max-change-mm): wrong model, tool "
                    "guess or units?",
                    full_param_name(k), change * 1e3, before(k), after(k), bounds.max_length_change_m * 1e3);
    }
    warnings.push_back(line + correlation_cause(full_param_name(k), parameters));
  }
  // Many samples of a few stops determine no more than those stops: 3 coordinates per distinct
  // point. No more of them than the parameters the fit determines (estimated, or fixed by the
  // significance test; not the structural nulls the identifiability analysis drops) leaves no
  // redundancy: the poses do not span the model, and test samples of the same stops do not show it.
  const int determined = result.has_lm ? mask_count(result.lm.identifiability.kept_mask | result.lm_pruned_mask) : 0;
  if (determined > 0 && 3 * result.train_points <= static_cast<std::size_t>(determined)) {
    std::snprintf(line, sizeof line,
                  "the %zu training samples stand at only %zu distinct poses (%zu coordinates) for the %d parameters "
                  "the fit determines: the poses do not span the model, so the calibration holds near these poses "
                  "only, and test samples at the same poses do not show it; measure more poses spread over every "
                  "joint's range (hivecal plan)",
                  result.train_count, result.train_points, 3 * result.train_points, determined);
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
