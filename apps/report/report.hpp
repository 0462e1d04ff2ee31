// What a calibration run reports: the paper-style tables (as text for the terminal and as
// HTML) and a self-contained HTML page with SVG figures (docs/report.md lists them and the
// question each answers). ReportData is all the page needs; it is kept in result.json
// (record/report_json.hpp, all but the input facts and stage times) so that `hivecal report`
// regenerates the page from a result alone.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/sync/clock_sync.hpp"

namespace hivecal::report {

/// One row of Table 1: a method's accuracy.
struct MethodRow {
  std::string method;         ///< e.g. "uncalibrated", "ABC", "GSA", "LM"
  std::string parameters;     ///< e.g. "paper-6", "full (31 estimated)"
  ErrorStats train;           ///< on the training samples [m]
  ErrorStats test;            ///< on the test samples [m]
  double seconds = 0.0;       ///< stage wall time [s] (0: not timed; never in result.json)
  long long evaluations = 0;  ///< cost evaluations or LM iterations (0: n/a)
};

/// A solver's convergence: best cost per cycle (ABC, GSA) or per iteration (LM).
struct ConvergenceSeries {
  std::string method;               ///< legend label
  bool per_iteration = false;       ///< LM iterations (own panel), not global-search cycles
  std::vector<double> best_cost_m;  ///< best MAE [m] (RMS for LM) after each cycle / iteration
};

/// One paired sample as the figures need it.
struct SampleRow {
  double q_rad[kMaxJoints] = {};   ///< joint positions: angles [rad], a prismatic joint's [m]
  int joint_count = kSixJoints;    ///< joints of the arm: q_rad's first entries [-]
  Vec3 measured_m = Vec3::Zero();  ///< tracker point [m]
  bool test = false;               ///< held out (test set), else training
  int target = 0;                  ///< reflector measured, 0-based (several targets) [-]
};

/// One model and its predictions of every sample (same order as ReportData::samples).
struct PredictionSet {
  std::string method;              ///< "uncalibrated", or a stage name ("ABC", "ABC+LM", ...)
  RobotModel model;                ///< its geometry
  RigidTransform base_to_tracker;  ///< its base -> tracker transform
  std::vector<Vec3> points_m;      ///< base_to_tracker * FK(q) * tool per sample [m] (predict_samples)
};

/// A parameter set aside by the identifiability analysis.
struct DroppedRow {
  std::string param;          ///< its name (e.g. "d4")
  std::string reason;         ///< why (no effect / not separable)
  double singular_ratio = 0;  ///< sigma_k / sigma_max of its direction [-]
  std::string combination;    ///< the non-separable combination, e.g. "+0.71*d2 -0.71*d4"
};

/// What LM could estimate.
struct IdentifiabilityTable {
  bool present = false;                ///< an LM stage ran
  int free_count = 0;                  ///< parameters free by the options
  std::vector<std::string> estimated;  ///< names of the estimated parameters
  std::vector<DroppedRow> dropped;     ///< set aside, in the order they were dropped
  double condition_before = 0.0;       ///< of the column-scaled Jacobian over the free parameters [-]
  double condition_after = 0.0;        ///< over the estimated parameters [-]
  std::vector<std::string> fixed{};    ///< fixed at their start values by LM's significance test
  double significance_t = 0.0;         ///< that test's level: a change below t sigma is not significant [-]
};

/// A sample the calibration set aside as a blunder.
struct OutlierRow {
  std::string source;       ///< where it came from: "file:line", or "sample N"
  double residual_m = 0.0;  ///< |predicted - measured| under the final calibration [m]
  double w = 0.0;           ///< its pose's normalised residual against the fit without it [-]
};

/// The blunder search (the w-test of each pose, docs/robust.md): what it set aside, the
/// threshold, which poses it cannot control.
struct OutlierTable {
  bool searched = false;            ///< a blunder search ran (not --keep-outliers)
  std::string verdict;              ///< blunder_verdict_name of the result ("clean", "removed", "model_error", ...)
  double critical_w = 0.0;          ///< w above which a pose is a blunder (the training poses') [-]
  double alpha = 0.0;               ///< the test's significance for the whole set [-]
  std::string sigma_source;         ///< "data" (the fit's residuals) or "tracker" (the stated noise)
  double sigma_m = 0.0;             ///< the test's sigma per axis [m]
  bool pooled_correlation = false;  ///< a pose's readings tested with their correlation pooled over the poses
  std::vector<OutlierRow> rows;     ///< the samples set aside, by increasing sample index
  std::vector<std::string> uncontrolled;  ///< poses whose redundancy is below the floor: never tested, by source
  std::vector<double> kept_w;             ///< w of every kept pose under the final calibration (the figure) [-]
  /// Kept poses when kept_w holds only the w at evenly spaced ranks of them, sorted (keep_at_most;
  /// 0: kept_w holds every kept pose's) [-].
  std::size_t kept_total = 0;
};

/// One fold of a cross-validation.
struct FoldRow {
  std::size_t train_count = 0;  ///< samples it was calibrated on [-]
  std::size_t test_count = 0;   ///< samples held out [-]
  double train_mae_m = 0.0;     ///< 3-D MAE on its training samples [m]
  double test_mae_m = 0.0;      ///< 3-D MAE on its held-out samples [m]
  std::string held_out{};  ///< which it held out, as ranges of CrossValidationTable::held_out_of ("2-4, 7"); "" unknown
};

/// A cross-validation's folds (--cv).
struct CrossValidationTable {
  bool present = false;            ///< a cross-validation ran
  std::size_t sample_count = 0;    ///< samples split into folds [-]
  double mae_3d_m = 0.0;           ///< 3-D MAE over every held-out sample of every fold [m]
  double baseline_mae_3d_m = 0.0;  ///< the same for each fold's uncalibrated baseline [m]
  std::string held_out_of;         ///< what FoldRow::held_out counts: "lines of FILE" or "samples (...)"; "" unknown
  std::vector<FoldRow> folds;      ///< per fold, in fold order
};

/// One model parameter: start, calibrated value and uncertainty.
struct ParameterRow {
  std::string name;               ///< e.g. "a2", "alpha3", "tool_z"
  bool angle = false;             ///< [rad] (shown in mrad), else [m] (shown in mm)
  double start = 0.0;             ///< start value [rad] or [m]
  double value = 0.0;             ///< calibrated value [rad] or [m]
  double sigma = 0.0;             ///< standard deviation [rad] or [m]; 0: not estimated
  std::string correlated_with{};  ///< the estimated parameter it is most correlated with ("" if none)
  double correlation = 0.0;       ///< that correlation coefficient [-]
  /// A compliance coefficient's unit, "rad/m" or "rad/(kg m)" (shown per urad); "" for a
  /// length or angle (`angle`).
  std::string compliance_unit{};
};

/// |correlation| above which Table 4 warns: the two are hard to tell apart in this data.
constexpr double kCorrelationWarning = 0.9;

/// Stream input: what became of the tracker points over the session, in equal time bins.
struct PointTimeline {
  double duration_s = 0.0;                         ///< from the first to the last tracker point [s]
  std::vector<std::string> reasons;                ///< "kept", then each drop reason that occurred
  std::vector<std::vector<std::uint32_t>> counts;  ///< per reason, tracker points per time bin
};

/// Stream input: what the clock fit matched (ClockEstimatorBase::match_profiles), one
/// entry per time bin; all four the same length.
struct ClockMatchSeries {
  double speed_gain = 1.0;                ///< tracker/robot path-length ratio of the fit [-]
  std::vector<double> t_s;                ///< bin time since the first tracker point [s]
  std::vector<double> robot_speed_m_s;    ///< robot tool speed at the fitted robot times [m/s]
  std::vector<double> tracker_speed_m_s;  ///< tracker point speed [m/s]
  std::vector<double> residual_m_s;       ///< tracker speed - speed_gain * robot speed [m/s]
};

/// Everything the report shows.
struct ReportData {
  std::string title;                     ///< page title
  std::vector<std::string> input_lines;  ///< inputs and stream facts (not in result.json: they name files and formats)
  std::vector<std::string> info_lines;   ///< run facts from the result: samples, identifiability
  std::vector<MethodRow> methods;        ///< Table 1 rows, first the uncalibrated model
  AccuracyReport uncalibrated;           ///< Table 2, before
  AccuracyReport calibrated;             ///< Table 2, after (the chosen method)
  std::vector<ConvergenceSeries> convergence;  ///< one per stage
  std::vector<SampleRow> samples;              ///< every sample (training and test), or a subset: sample_total
  /// The run's samples when `samples` holds an evenly spaced subset of them (keep_at_most; 0:
  /// `samples` holds every sample) [-].
  std::size_t sample_total = 0;
  std::vector<PredictionSet> predictions;  ///< first the uncalibrated model, last the result
  double noise_sigma_m = 0.0;  ///< measurement noise per axis: the tracker's stated sigma (with the joints' reading),
                               ///< or what repeated readings show [m]; 0: unknown
  std::string noise_source = "stated";   ///< where noise_sigma_m comes from: "stated" (--tracker-sigma-um), "stated,
                                         ///< with the joints' reading" or "repeated readings"
  double fit_sigma_m = 0.0;              ///< the final fit's residual sigma per axis, sqrt(SSR / dof) [m]; 0: unknown
  IdentifiabilityTable identifiability;  ///< Table 3
  std::vector<ParameterRow> parameters;  ///< Table 4: estimated or changed parameters
  std::vector<std::pair<std::string, std::uint64_t>> drops;  ///< stream input: drop reason -> tracker points
  bool has_stream = false;                                   ///< the samples came from two streams
  PointTimeline timeline;                 ///< stream input: kept / drop reason per tracker point over time
  ClockMatchSeries clock_match;           ///< stream input: the clock fit's matched speed profiles
  OutlierTable outliers;                  ///< blunders set aside (none when the search found none)
  CrossValidationTable cross_validation;  ///< --cv: held-out errors per fold
};

/// Samples a report keeps, in result.json and on the page (keep_at_most): a larger run keeps an
/// evenly spaced subset of its training and of its test samples, this many in all, and as many
/// of its poses' w; the tables' statistics are over every sample. The result stays ~1.5 MB
/// whatever the run's size (10^6 samples wrote 271 MiB, more than any command reads) [-].
inline constexpr std::size_t kReportSampleCap = 5000;

/// Thins `data` to at most `cap` samples (an evenly spaced subset of the training samples and
/// of the test samples, in proportion, in their order, with each prediction set's points) and
/// `cap` kept poses' w (the sorted values at evenly spaced ranks, the smallest and the largest
/// among them), recording the totals (sample_total, OutlierTable::kept_total). Data within the
/// cap is left as it is.
void keep_at_most(std::size_t cap, ReportData* data);

/// A prediction set of `model` for every sample of `samples` (result.json keeps the model,
/// not the points: both calibrate and `hivecal report` compute them here, the same bits).
PredictionSet predict_samples(const std::string& method, const RobotModel& model, const RigidTransform& base_to_tracker,
                              const std::vector<SampleRow>& samples);

/// The report's copy of ClockEstimatorBase::match_profiles' bins and the fit's speed gain.
ClockMatchSeries clock_match_series(const std::vector<ClockMatchBin>& bins, double speed_gain);

/// Table 1 and Table 2 as aligned plain text (micrometres).
std::string format_tables_text(const ReportData& data);
/// The parameter table as text lines (one per parameter).
std::vector<std::string> format_parameters_text(const ReportData& data);
/// The whole HTML page (inline SVG, no scripts, no external resources).
std::string render_html(const ReportData& data);
/// The file render_html's page goes into, in the report's folder.
inline constexpr const char* kReportPageName = "index.html";
/// The ids of the figures render_html draws for `data`, in page order (for tests).
std::vector<std::string> figure_ids(const ReportData& data);

/// An HTML table of text cells, the first row as the header (every cell escaped).
std::string html_table(const std::vector<std::vector<std::string>>& rows);
/// The start of a report page with the report's style, up to and including its <h1> title;
/// the caller appends the body and "</body>\n</html>\n".
std::string html_page_head(const std::string& title);

}  // namespace hivecal::report
