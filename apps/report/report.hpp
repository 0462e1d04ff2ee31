// What a calibration run reports: the paper-style tables (as text for the terminal and as
// HTML) and a self-contained HTML page with SVG figures like the paper's Figs 4-8.
#pragma once

#include <string>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/metrics.hpp"

namespace hivecal::report {

/// One row of Table 1: a method's accuracy.
struct MethodRow {
  std::string method;          ///< e.g. "uncalibrated", "ABC", "GSA", "LM"
  std::string parameters;      ///< e.g. "paper-6", "full (31 of 33)"
  ErrorStats train;            ///< on the training samples [m]
  ErrorStats test;             ///< on the test samples [m]
  double seconds = 0.0;        ///< solver wall time [s] (0: not timed)
  long long evaluations = 0;   ///< cost evaluations or LM iterations (0: n/a)
};

/// A solver's convergence: best cost per iteration.
struct ConvergenceSeries {
  std::string method;               ///< legend label
  std::vector<double> best_cost_m;  ///< best MAE [m] (or RMS for LM) after each iteration
};

/// Everything the report shows.
struct ReportData {
  std::string title;                        ///< page title
  std::vector<std::string> info_lines;      ///< run facts: inputs, clock, samples, dropped parameters...
  std::vector<MethodRow> methods;           ///< Table 1 rows, first the uncalibrated model
  AccuracyReport uncalibrated;              ///< Table 2, before
  AccuracyReport calibrated;                ///< Table 2, after (the chosen method)
  std::vector<ConvergenceSeries> convergence;  ///< Figs 4-5
  std::vector<Vec3> test_measured_m;        ///< test samples: tracker points [m]
  std::vector<Vec3> test_uncalibrated_m;    ///< test samples: nominal-model predictions [m]
  std::vector<Vec3> test_calibrated_m;      ///< test samples: calibrated predictions [m]
  std::vector<std::string> parameter_lines;  ///< calibrated parameters with sigma, one per line
};

/// Table 1 and Table 2 as aligned plain text (micrometres).
std::string format_tables_text(const ReportData& data);
/// The whole HTML page (inline SVG, no scripts, no external resources).
std::string render_html(const ReportData& data);

}  // namespace hivecal::report
