// hivecal calibrate: a run rendered as report data and console tables (calibrate_parts.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hivecal/calibration.hpp"
#include "commands/fit_checks.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "report/report.hpp"
#include "streams/session.hpp"
#include "textio/csv.hpp"
#include "commands/calibrate_parts.hpp"
#include "commands/uncertainty.hpp"

namespace hivecal::cli {
namespace {

std::vector<double> trace_values(Span<const double> trace) {
  std::vector<double> v;
  for (double x : trace) v.push_back(x);
  return v;
}

report::MethodRow method_row(std::string method, std::string parameters, const ErrorStats& train,
                             const ErrorStats& test, double seconds, long long evaluations) {
  report::MethodRow row;
  row.method = std::move(method);
  row.parameters = std::move(parameters);
  row.train = train;
  row.test = test;
  row.seconds = seconds;
  row.evaluations = evaluations;
  return row;
}

report::MethodRow stage_row(const Run& run, std::size_t k) {
  const CalibrationStage& stage = run.result.stages[k];
  std::string params =
      stage.params == CalibrationParams::paper ? "paper-" + std::to_string(run.link_length_count) : "full";
  if (stage.solver == CalibrationSolver::lm) {
    if (stage.params == CalibrationParams::paper && run.result.baseline.tool_fitted) params += " + tool";
    if (stage.compliance) {  // the joint terms, as the stage's name lists them ("LM+compliance+harmonics")
      const std::string name = run.result.stage_name(k);
      for (std::size_t at = name.find('+'); at != std::string::npos;) {
        const std::size_t next = name.find('+', at + 1);
        params += " + " + name.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1);
        at = next;
      }
    }
    bool last_lm = true;  // result.lm holds the last LM stage's analysis only
    for (std::size_t later = k + 1; later < run.result.stage_count; ++later)
      last_lm = last_lm && run.result.stages[later].solver != CalibrationSolver::lm;
    if (last_lm) params += " (" + std::to_string(run.result.lm.identifiability.kept_count()) + " estimated)";
  }
  // A refining stage's row (ABC+LM) is the whole chain: its time includes the stage it refined.
  const double seconds = run.seconds[k] + (stage.refines_previous && k > 0 ? run.seconds[k - 1] : 0.0);
  if (stage.solver != CalibrationSolver::lm) {
    params += run.result.baseline.tool_fitted ? ", tool fitted" : ", tool as given";
    if (stage.searched_samples < run.result.train_count) {  // a hybrid's start on a spanning subset
      params += ", searched on " + std::to_string(stage.searched_samples) + " of " +
                std::to_string(run.result.train_count) + " samples";
    }
  }
  return method_row(run.result.stage_name(k), params, stage.train, stage.test, seconds,
                    static_cast<long long>(stage.evaluations));
}

/// The non-separable combination of a dropped parameter, e.g. "+0.707*d2 -0.707*d4".
std::string combination_text(const DroppedParam& d, const RobotModel& model) {
  std::string combination;
  char buf[96];
  for (int c = 0; c < kNullComponentCount; ++c) {
    if (d.component_index[c] < 0) continue;
    std::snprintf(buf, sizeof buf, "%s%+.3g*%s", combination.empty() ? "" : " ", d.component[c],
                  full_param_name(d.component_index[c], model));
    combination += buf;
  }
  return combination;
}

/// No new joint term of `model` passed its significance test: which levels they had to clear,
/// and which fit is kept (the rigid one, or LM+compliance when `after_compliance`).
std::string rigid_kept_line(double significance_t, const RobotModel& model, bool after_compliance, int dof) {
  const ComplianceModel& terms = model.compliance;
  double gravity_t = 0.0;
  double harmonic_t = 0.0;
  for (int t = 0; t < terms.term_count; ++t) {
    const double level = parameter_significance_level(model, compliance_param_index(model, t), significance_t,
                                                      CalibrationCompliance{}.significance_t, dof);
    (is_harmonic(terms.terms[t]) ? harmonic_t : gravity_t) = level;
  }
  char buf[240];
  if (after_compliance) {
    std::snprintf(buf, sizeof buf,
                  "harmonics: no term passed the %.3g sigma test (the joints show no harmonic error): the "
                  "LM+compliance fit is kept",
                  harmonic_t);
  } else if (harmonic_t == 0.0) {
    std::snprintf(buf, sizeof buf,
                  "compliance: no term passed the %.3g sigma test (the data show no bending): the rigid fit is kept",
                  gravity_t);
  } else if (gravity_t == 0.0) {
    std::snprintf(buf, sizeof buf,
                  "harmonics: no term passed the %.3g sigma test (the joints show no harmonic error): the rigid fit "
                  "is kept",
                  harmonic_t);
  } else {
    std::snprintf(buf, sizeof buf,
                  "compliance and harmonics: no term passed its test (gravity %.3g sigma, harmonics %.3g sigma): the "
                  "rigid fit is kept",
                  gravity_t, harmonic_t);
  }
  return buf;
}

/// A joint-term stage's check on left-out poses (JointTermHoldout), when it ran: what the
/// stage's new terms (`family`: "compliance", "harmonics", ...) predicted, and what was kept.
std::string holdout_line(const char* family, const JointTermHoldout& holdout, bool after_compliance) {
  const char* previous = after_compliance ? "LM+compliance" : "rigid";
  char buf[360];
  if (holdout.poses < 2) {
    std::snprintf(buf, sizeof buf,
                  "%s: the terms that passed the significance test could not be checked on left-out poses (too few "
                  "poses to fit without one): the %s fit is kept",
                  family, previous);
    return buf;
  }
  char numbers[160];
  std::snprintf(numbers, sizeof numbers,
                "leave-one-pose-out MAE %.4f mm with them, %.4f mm without, improvement %+.4f +/- %.4f mm, %zu poses",
                holdout.with_terms_mae_m * 1e3, holdout.without_terms_mae_m * 1e3,
                (holdout.without_terms_mae_m - holdout.with_terms_mae_m) * 1e3, holdout.improvement_se_m * 1e3,
                holdout.poses);
  if (holdout.passed) {
    std::snprintf(buf, sizeof buf,
                  "%s: the terms that passed the significance test also predict left-out poses better (%s)", family,
                  numbers);
  } else {
    std::snprintf(buf, sizeof buf,
                  "%s: the terms that passed the significance test do not predict left-out poses better by %.3g "
                  "standard errors (%s; a small set): the %s fit is kept",
                  family, kHoldoutImprovementT, numbers, previous);
  }
  return buf;
}

/// The names of the parameters of `mask` in `model`, comma separated.
std::string parameter_names(ParamMask mask, const RobotModel& model) {
  std::string names;
  for (int k = 0; k < kFullParamCount; ++k) {
    if (!mask_has(mask, k)) continue;
    names += (names.empty() ? "" : ", ") + std::string(full_param_name(k, model));
  }
  return names;
}

/// The blocked folds of a joint-term stage of `family` ("compliance", "harmonics"): the terms
/// not admitted by their period, the folds' errors, the terms not admitted by them and, when they
/// failed, which fit is kept.
std::vector<std::string> blocked_fold_lines(const char* family, const BlockedFoldCheck& folds, const RobotModel& model,
                                            bool after_compliance) {
  std::vector<std::string> lines;
  char buf[1200];
  if (folds.coverage_rejected != 0) {
    std::snprintf(buf, sizeof buf,
                  "%s: not admitted: %s (the training poses turn their joint through less than %.3g of their period: "
                  "nothing ties them down beyond the poses' range)",
                  family, parameter_names(folds.coverage_rejected, model).c_str(), kHarmonicMinPeriodShare);
    lines.push_back(buf);
  }
  if (!folds.checked) return lines;
  std::string per_joint;
  for (int j = 0; j < model.joint_count; ++j) {
    if (!(folds.with_terms_mae_m[j] > 0.0)) continue;
    char part[80];
    std::snprintf(part, sizeof part, "%sjoint %d %.4f / %.4f", per_joint.empty() ? "" : ", ", j + 1,
                  folds.with_terms_mae_m[j] * 1e3, folds.without_terms_mae_m[j] * 1e3);
    per_joint += part;
  }
  std::snprintf(buf, sizeof buf,
                "%s: beyond the training poses' joint ranges (each joint's lowest and highest %.0f %% of them "
                "predicted by a fit of the others) MAE %.4f mm with the terms, %.4f mm without (per joint's ends, mm, "
                "with / without: %s)",
                family, kBlockedFoldShare * 100.0, folds.with_all_mae_m * 1e3, folds.without_all_mae_m * 1e3,
                per_joint.c_str());
  lines.push_back(buf);
  if (folds.fold_rejected != 0) {
    std::snprintf(buf, sizeof buf, "%s: not admitted: %s (they predict their own joint's range ends worse)", family,
                  parameter_names(folds.fold_rejected, model).c_str());
    lines.push_back(buf);
  }
  if (!folds.passed) {
    std::snprintf(buf, sizeof buf,
                  "%s: the terms that passed the significance test do not hold beyond the training poses' joint "
                  "ranges: the %s fit is kept",
                  family, after_compliance ? "LM+compliance" : "rigid");
    lines.push_back(buf);
  }
  return lines;
}

std::vector<std::string> identifiability_lines(const LmResult& lm, const CalibrationResult& result,
                                               const RobotModel& model) {
  const ParamMask pruned = result.lm_pruned_mask;
  const double significance_t = result.significance_t;
  std::vector<std::string> lines;
  const IdentifiabilityReport& id = lm.identifiability;
  char buf[256];
  std::snprintf(buf, sizeof buf, "identifiability: %d of %d free parameters estimated, condition number %.3g -> %.3g",
                id.kept_count(), mask_count(id.free_mask), id.condition_before, id.condition_after);
  lines.push_back(buf);
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    std::snprintf(buf, sizeof buf, "  dropped %-8s (%s, sigma ratio %.2g): %s", full_param_name(d.index, model),
                  unidentifiable_reason_name(d.reason), d.singular_ratio, combination_text(d, model).c_str());
    lines.push_back(buf);
  }
  for (int k = 0; k < kFullParamCount; ++k) {
    if (!mask_has(pruned, k)) continue;
    const double level =
        parameter_significance_level(model, k, significance_t, CalibrationCompliance{}.significance_t, lm.residual_dof);
    if (std::isinf(level)) {
      std::snprintf(buf, sizeof buf, "  fixed   %-8s (not testable: the fit leaves %d residual degrees of freedom)",
                    full_param_name(k, model), lm.residual_dof);
    } else {
      std::snprintf(buf, sizeof buf,
                    "  fixed   %-8s (not significant: change below %.3g sigma; kept at its start value)",
                    full_param_name(k, model), level);
    }
    lines.push_back(buf);
  }
  if (!result.geometry_tested && significance_t > 0.0) {
    std::snprintf(buf, sizeof buf,
                  "  significance test: the geometry is not tested on %zu%s training poses (%.3g or more per estimated "
                  "rigid parameter, %zu): all are estimated, as a least-squares fit does (--significance T tests them)",
                  result.significance_poses, result.significance_poses >= kDistinctPointLimit ? " or more" : "",
                  kSignificancePosesPerParam, result.significance_params);
    lines.push_back(buf);
  }
  return lines;
}

report::IdentifiabilityTable identifiability_table(const LmResult& lm, const RobotModel& model) {
  const IdentifiabilityReport& id = lm.identifiability;
  report::IdentifiabilityTable table;
  table.present = true;
  table.free_count = mask_count(id.free_mask);
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) table.estimated.push_back(full_param_name(k, model));
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    table.dropped.push_back({full_param_name(d.index, model), unidentifiable_reason_name(d.reason), d.singular_ratio,
                             combination_text(d, model)});
  }
  table.condition_before = id.condition_before;
  table.condition_after = id.condition_after;
  return table;
}

/// Parameter k's strongest correlation into its table row (nothing when every one is 0).
void set_partner(const NormalMatrix& correlation, int k, const RobotModel& model, report::ParameterRow* row) {
  const CorrelationPartner partner = strongest_correlation(correlation, k);
  if (partner.index < 0) return;
  row->correlation = partner.correlation;
  row->correlated_with = full_param_name(partner.index, model);
}

/// The estimated or changed parameters. `lm`: the LM details when `stage` is the LM stage, else null.
std::vector<report::ParameterRow> parameter_rows(const CalibrationStage& stage, const LmResult* lm,
                                                 const RobotModel& start, Span<const Sample> train) {
  std::vector<report::ParameterRow> rows;
  const auto scratch = std::make_unique<CorrelationScratch>();  // ~54 kB with the matrix: not on the stack
  const auto correlation = std::make_unique<NormalMatrix>();
  const bool correlated =
      lm != nullptr &&
      parameter_correlations(stage.model, stage.base_to_tracker, train, PointLoss{lm->huber_threshold_m},
                             lm->identifiability.kept_mask, scratch.get(), correlation.get()) == Status::ok;
  const ModelParams before = to_params(start);
  const ModelParams after = to_params(stage.model);
  for (int k = 0; k < model_param_count(stage.model); ++k) {
    const bool estimated = lm != nullptr && mask_has(lm->identifiability.kept_mask, k);
    if (!estimated && after(k) == before(k)) continue;
    report::ParameterRow row;
    row.name = full_param_name(k, stage.model);
    row.angle = model_param_is_angle(k, stage.model.joint_count);
    row.start = before(k);
    row.value = after(k);
    row.sigma = estimated ? lm->sigma(k) : 0.0;
    if (correlated && estimated) set_partner(*correlation, k, stage.model, &row);
    rows.push_back(row);
  }
  const ComplianceModel& compliance = stage.model.compliance;
  for (int t = 0; t < compliance.term_count; ++t) {  // LM+compliance: the coefficients, in their own unit
    const int k = compliance_param_index(stage.model, t);
    report::ParameterRow row;
    row.name = compliance_term_name(compliance, t);
    row.compliance_unit = textio::term_unit(compliance, t);
    row.start = t < start.compliance.term_count ? start.compliance.coefficient[t] : 0.0;
    row.value = compliance.coefficient[t];
    row.sigma = lm != nullptr && mask_has(lm->identifiability.kept_mask, k) ? lm->sigma(k) : 0.0;
    if (correlated && row.sigma > 0.0) set_partner(*correlation, k, stage.model, &row);
    rows.push_back(row);
  }
  for (int target = 1; lm != nullptr && target < kMaxTargets; ++target) {  // estimated with several targets
    const Vec3& sigma_m = lm->other_tools_sigma_m[target - 1];
    if (sigma_m.isZero()) continue;
    for (int axis = 0; axis < 3; ++axis) {
      report::ParameterRow row;
      row.name = other_tool_param_name(target, axis);
      row.start = target_tool(start, target)(axis);
      row.value = target_tool(stage.model, target)(axis);
      row.sigma = sigma_m(axis);
      rows.push_back(row);
    }
  }
  return rows;
}

/// Every sample (training first) and each model's prediction of it, for the figures.
void add_samples(const CliDataset& dataset, const Run& run, report::ReportData* data) {
  for (const bool test : {false, true}) {
    for (const Sample& s : test ? dataset.test() : dataset.train()) {
      report::SampleRow row;
      row.joint_count = run.final_stage().model.joint_count;
      for (int j = 0; j < row.joint_count; ++j) row.q_rad[j] = s.q_rad(j);
      row.measured_m = s.point_m;
      row.test = test;
      row.target = s.target;
      data->samples.push_back(row);
    }
  }
  const CalibrationBaseline& uncalibrated = run.result.baseline;
  data->predictions.push_back(
      report::predict_samples("uncalibrated", uncalibrated.model, uncalibrated.base_to_tracker, data->samples));
  for (std::size_t k = 0; k < run.result.stage_count; ++k) {
    const CalibrationStage& stage = run.result.stages[k];
    data->predictions.push_back(
        report::predict_samples(run.result.stage_name(k), stage.model, stage.base_to_tracker, data->samples));
  }
}

std::string format_mm(double value_m) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3f", value_m * 1e3);
  return buf;
}

/// "noise: ..." — the fit's residual sigma against the measurement noise and where that comes
/// from (`source`: the report's noise source), and what the ratio says.
std::string noise_statement(double fit_sigma_m, double noise_sigma_m, const std::string& source) {
  const double ratio = fit_sigma_m / noise_sigma_m;
  const bool measured = source == "repeated readings";
  const char* what = measured             ? "the tracker's measured"
                     : source == "stated" ? "the tracker's stated"
                                          : "the measurement noise, the tracker's stated and the joints' reading,";
  char line[360];
  std::snprintf(line, sizeof line, "noise: the fit's residual sigma %s mm per axis is %.1fx %s %s mm%s%s",
                format_mm(fit_sigma_m).c_str(), ratio, what, format_mm(noise_sigma_m).c_str(),
                measured ? " (repeated readings)" : " (--tracker-sigma-um)",
                ratio > 2.0 ? (measured ? ": unmodelled effects dominate the residuals, not the tracker"
                                        : ": unmodelled effects (or a wrong stated noise) dominate the residuals, "
                                          "not the tracker")
                            : ": the model explains the data to the measurement noise");
  return line;
}

/// Joints' noise that changes the measurement noise by less than this share of the tracker's is
/// left out (a log written in full digits: ~1e-16 of it) [-].
constexpr double kNegligibleJointNoise = 0.1;

}  // namespace

double joint_point_noise_m(const CalibrateSettings& settings, const RobotModel& start,
                           const streams::SessionFacts& facts, Span<const Sample> samples) {
  const double step_rad = facts.orientation.joint_resolution_rad;
  const double joint_sigma_rad = settings.joint_sigma_rad > 0.0 ? settings.joint_sigma_rad : step_rad / std::sqrt(12.0);
  if (!(joint_sigma_rad > 0.0) || samples.empty()) return 0.0;
  std::vector<JointVector> poses;
  for (const Sample& s : samples)
    if (s.target == 0) poses.push_back(s.q_rad);
  const double joint_m = std::sqrt(
      textio::joint_position_variance_m2(joint_sigma_rad, start, Span<const JointVector>(poses.data(), poses.size())));
  return joint_m > kNegligibleJointNoise * settings.orientation.position_sigma_m ? joint_m : 0.0;
}

namespace {

/// The joints' reading noise as noise of the tool point (the tracker's stated beside it): read
/// with sigma_q (--joint-sigma-rad, else a rounding to their written resolution: step / sqrt(12)),
/// the joints move the point by sigma_q |J| / sqrt(3) per axis through the arm
/// (textio::joint_position_variance_m2 over the training poses). A line says so; the noise is
/// the two together.
void add_joint_reading_noise(const CalibrateSettings& settings, const RobotModel& start,
                             const streams::SessionFacts& facts, Span<const Sample> train, report::ReportData* data) {
  const bool given = settings.joint_sigma_rad > 0.0;
  const double step_rad = facts.orientation.joint_resolution_rad;
  const double joint_sigma_rad = given ? settings.joint_sigma_rad : step_rad / std::sqrt(12.0);
  const double stated_m = data->noise_sigma_m;
  const double joint_m = joint_point_noise_m(settings, start, facts, train);
  if (joint_m == 0.0) return;
  data->noise_sigma_m = std::sqrt(stated_m * stated_m + joint_m * joint_m);
  data->noise_source = "stated, with the joints' reading";
  char why[96];
  if (given) {
    std::snprintf(why, sizeof why, "read with sigma %.3g deg (--joint-sigma)", joint_sigma_rad / math::kRadPerDeg);
  } else {
    std::snprintf(why, sizeof why, "written to %.3g deg (a rounding: sigma %.2g deg)", step_rad / math::kRadPerDeg,
                  joint_sigma_rad / math::kRadPerDeg);
  }
  char line[320];
  std::snprintf(line, sizeof line,
                "joint noise: the joints, %s, move the tool point %s mm per axis through the arm: the measurement "
                "noise is %s mm with the tracker's stated %s mm",
                why, format_mm(joint_m).c_str(), format_mm(data->noise_sigma_m).c_str(), format_mm(stated_m).c_str());
  data->info_lines.push_back(line);
}

/// The measurement noise: what repeated readings show when the input has them (a line says
/// so, beside the stated figure), else the stated sigma with the joints' reading noise.
void measurement_noise(const CalibrateSettings& settings, const RepeatedReadingNoise& repeated, const RobotModel& start,
                       const streams::SessionFacts& facts, Span<const Sample> train, report::ReportData* data) {
  data->noise_sigma_m = settings.orientation.position_sigma_m;
  char line[300];
  if (repeated.measured()) {
    data->noise_sigma_m = repeated.sigma_m;
    data->noise_source = "repeated readings";
    std::snprintf(
        line, sizeof line,
        "tracker noise: %zu readings of %zu repeated points scatter %s mm per axis (x %s, y %s, z %s; stated %s mm)",
        repeated.readings, repeated.groups, format_mm(repeated.sigma_m).c_str(),
        format_mm(repeated.sigma_axis_m[0]).c_str(), format_mm(repeated.sigma_axis_m[1]).c_str(),
        format_mm(repeated.sigma_axis_m[2]).c_str(), format_mm(settings.orientation.position_sigma_m).c_str());
    data->info_lines.push_back(line);
    return;
  }
  if (repeated.groups > 0) {
    std::snprintf(line, sizeof line,
                  "tracker noise: %zu readings of %zu repeated points are identical (rounded, or simulated without "
                  "noise): the stated %s mm is the noise",
                  repeated.readings, repeated.groups, format_mm(settings.orientation.position_sigma_m).c_str());
    data->info_lines.push_back(line);
  }
  add_joint_reading_noise(settings, start, facts, train, data);
}

/// Collects each pose's test under the final calibration: the kept poses' w, the uncontrolled ones.
class PoseTests final : public UnitTestVisitor {
 public:
  PoseTests(const streams::SessionFacts& facts, std::vector<std::uint32_t> aside, report::OutlierTable* table)
      : facts_(facts), aside_(std::move(aside)), table_(table) {}
  void on_unit(const UnitTest& t) override {
    if (t.fitted && t.critical_w > 0.0) table_->critical_w = t.critical_w;
    if (t.fitted && !t.controlled) {
      table_->uncontrolled.push_back(streams::sample_source(facts_, t.index));
    } else if (t.controlled && std::find(aside_.begin(), aside_.end(), t.index) == aside_.end()) {
      table_->kept_w.push_back(t.w);
      if (t.fitted && t.rejected()) kept_failing.push_back(t);
    }
  }
  std::vector<UnitTest> kept_failing;  ///< kept training poses above their threshold (BlunderVerdict::at_threshold)

 private:
  const streams::SessionFacts& facts_;
  std::vector<std::uint32_t> aside_;
  report::OutlierTable* table_;
};

/// The blunder search's table and console lines: the job's verdict and set-aside samples, and
/// each pose's w under the final calibration (lib's test_for_blunders on the final fit).
void blunder_report(const streams::SessionFacts& facts, const CliDataset& dataset, const Run& run,
                    report::ReportData* data) {
  report::OutlierTable& table = data->outliers;
  const CalibrationResult& r = run.result;
  table.searched = r.outlier_rounds > 0;
  table.verdict = blunder_verdict_name(r.blunder_verdict);
  table.alpha = run.options.blunder_test.alpha;
  table.sigma_source = sigma_source_name(r.blunder_test.sigma_source);
  table.sigma_m = r.blunder_test.sigma_m;
  table.pooled_correlation = r.blunder_test.pooled_correlation;
  if (table.searched && r.final_stage() != nullptr) {
    const auto workspace = std::make_unique<ReliabilityWorkspace>();  // ~26 kB: not on the stack
    std::vector<std::uint32_t> aside;
    for (const CalibrationOutlier& o : r.outlier_list()) aside.push_back(o.index);
    PoseTests tests(facts, std::move(aside), &table);
    BlunderTestSummary summary;
    test_final_calibration(r, dataset, run.options, workspace.get(), &tests, &summary);
    for (const UnitTest& t : tests.kept_failing) {
      if (r.blunder_verdict != BlunderVerdict::at_threshold) break;  // model_error, list_full: said below
      char line[400];
      std::snprintf(line, sizeof line,
                    "kept at the threshold: %s, w %.2f > %.2f while fitted, below it when left out (the split moves "
                    "with it, run after run): not set aside",
                    streams::sample_source(facts, t.index).c_str(), t.w, t.critical_w);
      data->info_lines.push_back(line);
    }
  }
  // One line per source: the samples a row of a measured orientation makes (its point and
  // targets 2, 3) come from one line and go together, said once with their largest residual.
  const Span<const CalibrationOutlier> outliers = r.outlier_list();
  for (std::size_t k = 0; k < outliers.size();) {
    const std::string source = streams::sample_source(facts, outliers[k].index);
    const CalibrationOutlier& first = outliers[k];
    double largest_m = first.residual_m;
    std::size_t end = k + 1;
    for (; end < outliers.size() && streams::sample_source(facts, outliers[end].index) == source; ++end) {
      largest_m = std::max(largest_m, outliers[end].residual_m);
    }
    const std::string named = end - k > 1 ? source + " (" + std::to_string(end - k) + " samples)" : source;
    char line[400];
    std::snprintf(line, sizeof line,
                  "set aside as a blunder: %s, residual %s mm, w %.2f > %.2f (alpha %.2g %% for the set)",
                  named.c_str(), format_mm(largest_m).c_str(), first.w, first.critical_w, table.alpha * 100.0);
    data->info_lines.push_back(line);
    table.rows.push_back({named, largest_m, first.w});
    k = end;
  }
  if (table.searched && table.pooled_correlation) {
    char line[300];
    std::snprintf(line, sizeof line,
                  "blunder test: the readings of a pose share their error (their correlation pooled over the poses): "
                  "a pose is tested as one error seen several times, not as independent readings (threshold w %.2f)",
                  table.critical_w);
    data->info_lines.push_back(line);
  }
  if (r.blunder_verdict == BlunderVerdict::model_error) {
    data->info_lines.push_back("blunder test: more than " + std::to_string(r.blunder_limit) +
                               " training pose(s) fail the w-test: the model, not the data, is wrong (unmodelled "
                               "effects); none removed by the test");
  }
  if (r.blunder_verdict == BlunderVerdict::prediction_error) {
    data->info_lines.push_back(
        "blunder test: more than " + std::to_string(r.test_blunder_limit) +
        " test pose(s) fail as predictions: the fit does not carry to poses it did not see (too few poses for its "
        "parameters, or unmodelled effects), not bad readings; none of them set aside");
  }
  for (const std::string& source : table.uncontrolled) {
    data->info_lines.push_back(
        "uncontrolled pose (redundancy below 0.1: a blunder there cannot be told from the "
        "geometry; kept, not tested): " +
        source);
  }
}

}  // namespace

report::PointTimeline PointFates::timeline(std::size_t bins) const {
  report::PointTimeline t;
  if (events.empty()) return t;
  double first = events.front().first;
  double last = first;
  for (const auto& e : events) {
    first = std::min(first, e.first);
    last = std::max(last, e.first);
  }
  t.duration_s = (last - first) * 1e-6;
  std::vector<int> row_of(kDropReasonCount + 1, -1);  // index reason + 1 (kept: 0)
  for (int reason = -1; reason < kDropReasonCount; ++reason) {
    bool seen = false;
    for (const auto& e : events) seen = seen || e.second == reason;
    if (!seen) continue;
    row_of[static_cast<std::size_t>(reason + 1)] = static_cast<int>(t.reasons.size());
    t.reasons.push_back(reason < 0 ? "kept" : drop_reason_name(static_cast<DropReason>(reason)));
    t.counts.emplace_back(bins, 0u);
  }
  for (const auto& e : events) {
    const double at = last > first ? (e.first - first) / (last - first) : 0.0;
    const std::size_t bin = std::min(bins - 1, static_cast<std::size_t>(at * static_cast<double>(bins)));
    ++t.counts[static_cast<std::size_t>(row_of[static_cast<std::size_t>(e.second + 1)])][bin];
  }
  return t;
}

namespace {

/// What the test of the controller's frames (--frames auto) found.
std::string frames_line(const ControllerFramesTest& test) {
  char gate[120];
  std::snprintf(gate, sizeof gate, "frames: the fitted base is within %.0f mm and %.0f mrad of the identity",
                kControllerBaseGate_m * 1e3, kControllerBaseGate_rad * 1e3);
  if (test.status != Status::ok) {  // ControllerFramesTest::status
    const std::string why = test.status == Status::invalid_argument ? "it sets aside more samples as blunders"
                            : test.status == Status::too_few_samples
                                ? "it leaves no residual degree of freedom"
                                : std::string("it failed: ") + status_message(test.status);
    return std::string(gate) + "; the fit with the controller's frames (the identity, --tool) cannot be tested (" +
           why + "): fitted";
  }
  char fit[220];
  std::snprintf(fit, sizeof fit,
                "with the base (identity) and the tool points (--tool) known the fit's residual sigma is %s mm per "
                "axis against the measurement noise %s mm (at most %s mm)",
                format_mm(test.residual_sigma_m).c_str(), format_mm(test.noise_sigma_m).c_str(),
                format_mm(test.critical_sigma_m).c_str());
  if (test.adopted) {
    return std::string(gate) + ", and " + fit +
           ": the points are the controller's own TCP readings; not fitted, joint 1 estimated instead, LM only "
           "(--frames fitted fits them)";
  }
  return std::string(gate) + ", but " + fit + ": fitted";
}

}  // namespace

/// Tables and figures of a run, and the text of the terminal.
report::ReportData present_calibration(const CalibrateSettings& settings, const RobotModel& start,
                                       const CliDataset& dataset, const streams::SessionFacts& facts, const Run& run) {
  const CalibrationBaseline& uncalibrated = run.result.baseline;
  const CalibrationStage& final_stage = run.final_stage();
  report::ReportData data;
  data.title = "hivecal calibration: " + port::printable(settings.robot.robot);  // the file's text, made safe
  data.input_lines = facts.info_lines;
  data.info_lines.push_back("samples: " + std::to_string(dataset.size()) + " (train " +
                            std::to_string(dataset.train().size()) + ", test " + std::to_string(dataset.test().size()) +
                            ")");
  if (!settings.tool_note.empty()) data.info_lines.push_back(settings.tool_note);
  const std::string orientation = streams::orientation_line(facts);
  if (!orientation.empty()) data.info_lines.push_back(orientation);  // in the report's "info" too
  if (settings.controller_tcp) {
    data.info_lines.push_back(
        "known (--controller-tcp): the base (identity) and the tool points; not fitted, joint 1 estimated instead");
  }
  if (run.result.frames_test.tested) data.info_lines.push_back(frames_line(run.result.frames_test));
  const std::string joints = run.from_controller ? "controller" : "nominal";
  data.methods.push_back(method_row("uncalibrated", joints + (uncalibrated.tool_fitted ? ", tool fitted" : ""),
                                    uncalibrated.train, uncalibrated.test, 0.0, 0));
  for (std::size_t k = 0; k < run.result.stage_count; ++k) data.methods.push_back(stage_row(run, k));
  data.uncalibrated = accuracy_report(uncalibrated.model, uncalibrated.base_to_tracker, dataset);
  data.calibrated = accuracy_report(final_stage.model, final_stage.base_to_tracker, dataset);
  for (std::size_t k = 0; k < run.result.stage_count; ++k) {
    const CalibrationStage& stage = run.result.stages[k];
    data.convergence.push_back(
        {run.result.stage_name(k), stage.solver == CalibrationSolver::lm, trace_values(stage.trace_m)});
  }
  add_samples(dataset, run, &data);
  if (const LmResult* lm = run.final_lm(); lm != nullptr) {
    for (const std::string& line : identifiability_lines(*lm, run.result, final_stage.model)) {
      data.info_lines.push_back(line);
    }
    for (std::size_t k = 0; k < run.result.stage_count; ++k) {
      const CalibrationStage& stage = run.result.stages[k];
      const bool after_compliance = k > 0 && run.result.stages[k - 1].compliance;
      const char* name = run.result.stage_name(k);  // "LM+compliance", "LM+harmonics", ...
      const char* family = after_compliance ? "harmonics" : name + (std::strncmp(name, "LM+", 3) == 0 ? 3 : 0);
      if (stage.compliance) {
        for (const std::string& line : blocked_fold_lines(family, stage.folds, stage.model, after_compliance)) {
          data.info_lines.push_back(line);
        }
      }
      if (stage.holdout.checked) {
        data.info_lines.push_back(holdout_line(family, stage.holdout, after_compliance));
      } else if (stage.folds.checked && !stage.folds.passed) {
        // said by blocked_fold_lines
      } else if (stage.rigid_kept && k + 1 == run.result.stage_count) {
        data.info_lines.push_back(
            rigid_kept_line(run.result.significance_t, final_stage.model, after_compliance, lm->residual_dof));
      }
    }
    data.identifiability = identifiability_table(*lm, final_stage.model);
    for (int k = 0; k < kFullParamCount; ++k)
      if (mask_has(run.result.lm_pruned_mask, k))
        data.identifiability.fixed.push_back(full_param_name(k, final_stage.model));
    data.identifiability.significance_t = run.result.significance_t;
    data.fit_sigma_m = lm->residual_sigma_m;
  }
  measurement_noise(settings, run.result.reading_noise, start, facts, dataset.train(), &data);
  if (data.fit_sigma_m > 0.0)
    data.info_lines.push_back(noise_statement(data.fit_sigma_m, data.noise_sigma_m, data.noise_source));
  data.parameters = parameter_rows(final_stage, run.final_lm(), start, dataset.train());
  if (const LmResult* lm = run.final_lm(); lm != nullptr) {
    const LmPriorTolerances& held = lm->prior_tolerances;
    if (tolerances_widened(run.options.prior, held))
      data.info_lines.push_back(prior_widened_line(run.options.prior, held));
    for (const std::string& line : prior_held_lines(*lm, held, data.parameters)) {
      data.info_lines.push_back(line);
    }
  }
  data.has_stream = facts.has_stream;
  if (facts.has_stream) {
    data.drops.emplace_back("kept", facts.run.counts.kept);
    for (const auto& drop : facts.dropped) data.drops.push_back(drop);
    data.clock_match = report::clock_match_series(facts.run.clock_match, facts.run.clock.speed_gain);
  }
  blunder_report(facts, dataset, run, &data);
  if (run.has_cv) {
    data.cross_validation.present = true;
    data.cross_validation.sample_count = run.cv.sample_count;
    data.cross_validation.mae_3d_m = run.cv.mae_3d_m;
    data.cross_validation.baseline_mae_3d_m = run.cv.baseline_mae_3d_m;
    if (run.cv_held_out.size() == run.cv.fold_count) data.cross_validation.held_out_of = held_out_unit(facts);
    for (std::size_t k = 0; k < run.cv.fold_count; ++k) {
      const CrossValidationFold& f = run.cv.folds[k];
      data.cross_validation.folds.push_back(
          {f.train_count, f.test.count, f.train.mae(ErrorAxis::norm_3d), f.test.mae(ErrorAxis::norm_3d),
           data.cross_validation.held_out_of.empty() ? std::string() : held_out_ranges(facts, run.cv_held_out[k])});
    }
  }
  report::keep_at_most(report::kReportSampleCap, &data);  // the result and the page stay small
  return data;
}

void add_uncertainty(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset, Run* run,
                     report::ReportData* data) {
  const CalibrationStage& final_stage = run->final_stage();
  const LmResult* lm = run->final_lm();
  PointLoss loss;  // the final LM's, so that the covariance's diagonal is its sigmas squared
  if (lm != nullptr) loss.huber_threshold_m = lm->huber_threshold_m;
  if (settings.joint_sigma_rad > 0.0)
    loss.joint_noise_ratio_rad_per_m = settings.joint_sigma_rad / settings.orientation.position_sigma_m;
  const Vec3 none[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  std::string note;
  // The prior every LM fit of the job held (its sigmas are the posterior's).
  const LmPrior prior = lm != nullptr ? lm_prior(start, lm->prior_tolerances) : LmPrior{};
  compute_uncertainty(final_stage.model, final_stage.base_to_tracker, dataset.train(), loss, prior,
                      calibration_estimated_mask(run->result), lm != nullptr ? lm->other_tools_sigma_m : none,
                      &run->uncertainty, &note);
  if (!note.empty()) data->info_lines.push_back(note);
  for (const std::string& line : domain_lines(run->uncertainty, final_stage.model.joint_count))
    data->info_lines.push_back(line);
}

std::string held_out_unit(const streams::SessionFacts& facts) {
  if (facts.has_stream || facts.sample_sources.empty()) return "samples (numbered from 1 in the order extracted)";
  const std::string& first = facts.sample_sources.front();
  return "lines of " + first.substr(0, first.rfind(':'));
}

std::string held_out_ranges(const streams::SessionFacts& facts, const std::vector<std::uint32_t>& indices) {
  const bool by_line = !facts.has_stream && !facts.sample_sources.empty();
  std::vector<std::size_t> numbers;
  for (const std::uint32_t index : indices) {
    std::size_t number = index + 1;
    if (by_line && index < facts.sample_sources.size()) {  // "FILE:LINE" (session.cpp)
      const std::string& source = facts.sample_sources[index];
      number = static_cast<std::size_t>(std::strtoull(source.c_str() + source.rfind(':') + 1, nullptr, 10));
    }
    numbers.push_back(number);
  }
  std::sort(numbers.begin(), numbers.end());
  numbers.erase(std::unique(numbers.begin(), numbers.end()), numbers.end());
  std::string text;
  for (std::size_t i = 0; i < numbers.size();) {
    std::size_t last = i;
    while (last + 1 < numbers.size() && numbers[last + 1] == numbers[last] + 1) ++last;
    text += (text.empty() ? "" : ", ") + std::to_string(numbers[i]) +
            (last > i ? "-" + std::to_string(numbers[last]) : std::string());
    i = last + 1;
  }
  return text;
}

namespace {

/// `ranges` cut at a comma before `width` characters, "…" marking the rest (the console's
/// fold table; result.json holds them whole).
std::string cut_ranges(const std::string& ranges, std::size_t width) {
  if (ranges.size() <= width) return ranges;
  const std::size_t comma = ranges.rfind(", ", width - 5);
  return ranges.substr(0, comma == std::string::npos ? width - 5 : comma) + ", ...";
}

}  // namespace

/// The terminal text (on stdout, or on stderr when stdout carries the result).
void print_calibration_tables(std::FILE* out, const report::ReportData& data, const streams::SessionFacts& facts,
                              const Run& run) {
  for (const std::string& line : data.input_lines) std::fprintf(out, "%s\n", line.c_str());
  for (const std::string& line : data.info_lines) std::fprintf(out, "%s\n", line.c_str());
  std::fprintf(out, "\n%s", report::format_tables_text(data).c_str());
  if (run.has_cv) {
    const CrossValidationResult& cv = run.cv;
    std::fprintf(out, "\nCross-validation (%zu folds over %zu samples, held-out 3-D MAE):\n", cv.fold_count,
                 cv.sample_count);
    std::fprintf(out, "  fold  train  test  MAE [mm]  held out (%s)\n", held_out_unit(facts).c_str());
    for (std::size_t k = 0; k < cv.fold_count; ++k) {
      const std::string held_out =
          k < run.cv_held_out.size() ? cut_ranges(held_out_ranges(facts, run.cv_held_out[k]), 60) : "";
      std::fprintf(out, "  %4zu  %5zu  %4zu  %8s  %s\n", k + 1, cv.folds[k].train_count, cv.folds[k].test.count,
                   format_mm(cv.folds[k].test.mae(ErrorAxis::norm_3d)).c_str(), held_out.c_str());
    }
    std::fprintf(out, "  all held-out samples: %s mm (fold mean %s, worst %s; uncalibrated %s mm)\n",
                 format_mm(cv.mae_3d_m).c_str(), format_mm(cv.fold_mae_3d_mean_m).c_str(),
                 format_mm(cv.fold_mae_3d_max_m).c_str(), format_mm(cv.baseline_mae_3d_m).c_str());
  }
  std::fprintf(out, "\nCalibrated parameters (%s):\n", run.final_method().c_str());
  for (const std::string& line : report::format_parameters_text(data)) std::fprintf(out, "  %s\n", line.c_str());
}

}  // namespace hivecal::cli
