// Plausibility of a finished calibration (docs/cli.md, "Warnings"): parameters that moved more
// than a bound from the uncalibrated geometry, or a test error worse than the baseline's. They
// are warnings, not errors: the result is still written and `calibrate` exits with
// kExitWarnings (5), so a script notices and a person can look.
#pragma once

#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "report/report.hpp"

namespace hivecal::cli {

/// How far a calibration may move the geometry before it is questioned.
struct FitBounds {
  double max_length_change_m = 0.020;                 ///< d, a and the tool point (--max-change-mm) [m]
  double max_angle_change_rad = 0.03490658503988659;  ///< theta offsets and alpha, 2 deg (--max-change-deg) [rad]
};

/// The warnings about `result` (empty when none): one line per parameter of the final stage's
/// model that moved beyond `bounds` from the baseline model (name, both values, the change),
/// and one when the final stage's test MAE (3D) is above the baseline's (only with test samples).
/// `parameters` (Table 4's rows, may be empty): a moved parameter with |correlation| > 0.95 to
/// another says so and what would separate them.
std::vector<std::string> fit_warnings(const CalibrationResult& result, const FitBounds& bounds,
                                      const std::vector<report::ParameterRow>& parameters = {});

}  // namespace hivecal::cli
