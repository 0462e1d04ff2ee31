#include "commands/fit_checks.hpp"

#include <cmath>
#include <cstdio>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"

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

}  // namespace

std::vector<std::string> fit_warnings(const CalibrationResult& result, const FitBounds& bounds,
                                      const std::vector<report::ParameterRow>& parameters) {
  std::vector<std::string> warnings;
  const CalibrationStage* final_stage = result.final_stage();
  if (final_stage == nullptr) return warnings;
  const RobotModel& model = final_stage->model;
  const ModelParams before = to_params(result.baseline.model);
  const ModelParams after = to_params(model);
  char line[512];
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
