// hivecal calibrate: inputs (paired samples, serial captures or CSV logs) -> dataset ->
// ABC / GSA / Levenberg-Marquardt -> tables, result JSON, UR deltas and HTML report.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "hivecal/core/math.hpp"
#include "cli/options.hpp"
#include "hivecal/calibration.hpp"
#include "commands/commands.hpp"
#include "commands/fit_checks.hpp"
#include "commands/host_storage.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "report/report.hpp"
#include "report/report_json.hpp"
#include "streams/session.hpp"
#include "textio/calibration_json.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::cli {
namespace {

constexpr const char* kCommand = "calibrate";
constexpr std::size_t kTraceCapacity = 1024;

/// The command's dataset: as large as its input.
using CliDataset = HostDataset;

/// Validated command-line settings.
struct CalibrateSettings {
  textio::RobotDescription robot;    ///< --robot-model: built-in table or description file
  Vec3 tool_m = Vec3(0.0, 0.0, 0.1695);  ///< --tool (or the description file's): nominal tool point in the flange frame [m]
  bool paper_params = false;         ///< --params paper
  CalibrationMethod method = CalibrationMethod::abc_lm;  ///< --method
  std::uint64_t seed = 1;            ///< --seed
  double train_fraction = 0.7;       ///< --split
  bool robust = false;               ///< --robust
  bool keep_outliers = false;        ///< --keep-outliers
  double significance_t = 2.0;       ///< --significance
  std::size_t population_subset = kDefaultPopulationSubset;  ///< --population-subset: a hybrid's ABC/GSA samples (0: all) [-]
  std::size_t cv_folds = 0;          ///< --cv K; 1: leave-one-out (lib's folds = 0); 0: no cross-validation
  bool progress = false;             ///< progress lines on stderr
  textio::InputUnits units;          ///< --length-unit, --angle-unit of text inputs
  FitBounds bounds;                  ///< --max-change-mm, --max-change-deg
  bool compliance = false;           ///< --compliance: an LM+compliance stage after the rigid LM
  /// --compliance basis|masses: the terms (default_compliance_terms), unit gravity direction
  /// (--gravity) and, for masses, the arm's masses and the payload (--payload); zero coefficients.
  ComplianceModel compliance_model;
  textio::OrientationInput orientation;  ///< --position-sigma-m, --angle-sigma-rad, --orientation-lever-m
  double joint_sigma_rad = 0.0;      ///< --joint-sigma-rad / --joint-sigma-deg: joint reading noise (0: off) [rad]
  bool controller_tcp = false;       ///< --controller-tcp: base (identity) and tool (--tool) known, not fitted
};

/// The job's workspace for `samples` samples, shared by the job and --cv: exact (double)
/// paper-6 terms for any arm's link lengths and joint trig storage (~450 B per sample).
HostWorkspace<kTraceCapacity>::View& cli_workspace(std::size_t samples) {
  static HostWorkspace<kTraceCapacity> workspace;
  return workspace.for_samples(samples);
}

/// Times the stages (lib takes no time) and prints one progress line per iteration on
/// stderr, overwritten in place.
class JobObserver final : public CalibrationObserver {
 public:
  explicit JobObserver(bool enabled) : enabled_(enabled) {}
  ~JobObserver() { end_line(); }
  void on_stage_begin(std::size_t, CalibrationSolver solver) override {
    label_ = calibration_solver_name(solver);
    start_ = std::chrono::steady_clock::now();
  }
  void on_stage_end(std::size_t index, const CalibrationStage&) override {
    seconds[index] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    end_line();
  }
  void on_iteration(const SolverProgress& p) override {
    print("iteration %zu/%zu, best MAE %.2f um", p.iteration, p.iteration_count, p.best_cost * 1e6);
  }
  bool on_iteration(const LmIterationInfo& info) override {
    print("iteration %d, RMS %.2f um", info.iteration, info.rms_m * 1e6);
    return true;
  }
  double seconds[kMaxCalibrationStages] = {};  ///< wall time per stage [s]

 private:
  template <typename... Args>
  void print(const char* format, Args... args) {
    if (!enabled_) return;
    std::fprintf(stderr, "\r[%s] ", label_);
    std::fprintf(stderr, format, args...);
    std::fflush(stderr);
    printed_ = true;
  }
  void end_line() {
    if (enabled_ && printed_) std::fprintf(stderr, "\n");
    printed_ = false;
  }
  bool enabled_;
  const char* label_ = "";
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_;
};

/// The fate of every tracker point in the extraction pass (kept, or its drop reason), for the
/// report's timeline.
class PointFates final : public ExtractionObserver {
 public:
  void on_sample(const ExtractedSample& sample) override { events.push_back({sample.tracker_us, -1}); }
  void on_drop(std::uint64_t tracker_us, DropReason reason) override {
    events.push_back({static_cast<double>(tracker_us), static_cast<int>(reason)});
  }
  /// In `bins` equal time bins: "kept", then the drop reasons that occurred (enum order).
  report::PointTimeline timeline(std::size_t bins) const;
  std::vector<std::pair<double, int>> events;  ///< tracker time [us], -1 (kept) or the DropReason
};

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

/// What the job produced, with the CLI's stage timings.
struct Run {
  CalibrationResult result;                     ///< lib's result (~5 KB)
  double seconds[kMaxCalibrationStages] = {};   ///< wall time per stage [s]
  bool from_controller = false;                 ///< the start geometry is the controller's
  std::size_t link_length_count = kPaper6Dimension;  ///< lengths the population stages search [-]
  bool has_cv = false;                          ///< --cv ran: `cv` is meaningful
  CrossValidationResult cv;                     ///< per-fold held-out errors (~20 KB)
  int target_count = 1;                         ///< targets (reflectors) in the samples: the result's "tools" [-]
  CalibrationOptions options;                   ///< the job's options, as lib ran it
  /// The job's answer (run() returns an error when no stage ran).
  const CalibrationStage& final_stage() const { return result.stages[result.stage_count - 1]; }
  /// Its name ("ABC+LM", ...).
  std::string final_method() const { return result.stage_name(result.stage_count - 1); }
  /// The LM details when the final stage is LM, else null.
  const LmResult* final_lm() const {
    return final_stage().solver == CalibrationSolver::lm ? &result.lm : nullptr;
  }
};

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
  std::string params = stage.params == CalibrationParams::paper ? "paper-" + std::to_string(run.link_length_count) : "full";
  if (stage.solver == CalibrationSolver::lm) {
    if (stage.params == CalibrationParams::paper && run.result.baseline.tool_fitted) params += " + tool";
    if (stage.compliance) params += " + compliance";
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

std::vector<std::string> identifiability_lines(const LmResult& lm, ParamMask pruned, double significance_t,
                                               const RobotModel& model) {
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
    std::snprintf(buf, sizeof buf, "  fixed   %-8s (not significant: change below %.3g sigma; kept at its start value)",
                  full_param_name(k, model), significance_t);
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
std::vector<report::ParameterRow> parameter_rows(const CalibrationStage& stage, const LmResult* lm, const RobotModel& start,
                                                 Span<const Sample> train) {
  std::vector<report::ParameterRow> rows;
  static CorrelationScratch scratch;  // static: ~35 kB with the matrix
  static NormalMatrix correlation;
  const bool correlated =
      lm != nullptr && parameter_correlations(stage.model, stage.base_to_tracker, train, PointLoss{lm->huber_threshold_m},
                                              lm->identifiability.kept_mask, &scratch, &correlation) == Status::ok;
  const ModelParams before = to_params(start);
  const ModelParams after = to_params(stage.model);
  for (int k = 0; k < kModelParamCount; ++k) {
    const bool estimated = lm != nullptr && mask_has(lm->identifiability.kept_mask, k);
    if (!estimated && after(k) == before(k)) continue;
    report::ParameterRow row;
    row.name = full_param_name(k);
    row.angle = model_param_is_angle(k);
    row.start = before(k);
    row.value = after(k);
    row.sigma = estimated ? lm->sigma(k) : 0.0;
    if (correlated && estimated) set_partner(correlation, k, stage.model, &row);
    rows.push_back(row);
  }
  const ComplianceModel& compliance = stage.model.compliance;
  for (int t = 0; t < compliance.term_count; ++t) {  // LM+compliance: the coefficients, in their own unit
    const int k = compliance_param_index(t);
    report::ParameterRow row;
    row.name = compliance_term_name(compliance, t);
    row.compliance_unit = textio::compliance_unit(compliance.load);
    row.start = t < start.compliance.term_count ? start.compliance.coefficient[t] : 0.0;
    row.value = compliance.coefficient[t];
    row.sigma = lm != nullptr && mask_has(lm->identifiability.kept_mask, k) ? lm->sigma(k) : 0.0;
    if (correlated && row.sigma > 0.0) set_partner(correlation, k, stage.model, &row);
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

void write_stage_list(textio::JsonWriter& json, const std::vector<report::MethodRow>& rows) {
  json.key("methods").begin_array();
  for (const report::MethodRow& row : rows) {
    json.begin_object();
    json.key("method").value(row.method);
    json.key("params").value(row.parameters);
    json.key("train_mae_m").value(row.train.mae(ErrorAxis::norm_3d));
    if (row.test.count > 0) json.key("test_mae_m").value(row.test.mae(ErrorAxis::norm_3d));  // --split 1: none
    json.key("evaluations").value(row.evaluations);
    json.end_object();
  }
  json.end_array();
}

void write_lm_details(textio::JsonWriter& json, const LmResult& lm, const RobotModel& model) {
  const IdentifiabilityReport& id = lm.identifiability;
  json.key("identifiability").begin_object();
  json.key("estimated").begin_array();
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) json.value(full_param_name(k, model));
  for (int target = 1; target < kMaxTargets; ++target) {  // several targets: their tool points
    if (lm.other_tools_sigma_m[target - 1].isZero()) continue;
    for (int axis = 0; axis < 3; ++axis) json.value(other_tool_param_name(target, axis));
  }
  json.end_array();
  json.key("dropped").begin_array();
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    json.begin_object();
    json.key("param").value(full_param_name(d.index, model));
    json.key("reason").value(unidentifiable_reason_name(d.reason));
    json.key("singular_ratio").value(d.singular_ratio);
    json.key("combination").begin_object();
    for (int c = 0; c < kNullComponentCount; ++c)
      if (d.component_index[c] >= 0) json.key(full_param_name(d.component_index[c], model)).value(d.component[c]);
    json.end_object();
    json.end_object();
  }
  json.end_array();
  json.key("singular_values").inline_array(id.singular_values_before, static_cast<std::size_t>(id.singular_count_before));
  json.key("condition_before").value(id.condition_before);
  json.key("condition_after").value(id.condition_after);
  json.end_object();
  json.key("sigma").begin_object();
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) json.key(full_param_name(k, model)).value(lm.sigma(k));
  for (int target = 1; target < kMaxTargets; ++target) {
    const Vec3& sigma_m = lm.other_tools_sigma_m[target - 1];
    if (sigma_m.isZero()) continue;
    for (int axis = 0; axis < 3; ++axis) json.key(other_tool_param_name(target, axis)).value(sigma_m(axis));
  }
  json.end_object();
  json.key("lm").begin_object();
  json.key("iterations").value(static_cast<long long>(lm.iterations));
  json.key("termination").value(lm_termination_name(lm.termination));
  json.key("rms_m").value(lm.rms_m);
  json.key("residual_sigma_m").value(lm.residual_sigma_m);
  json.end_object();
}

void write_ur_deltas(textio::JsonWriter& json, const UrCalibrationDeltas& deltas) {
  json.key("ur_deltas").begin_object();
  json.key("delta_theta").inline_array(deltas.delta_theta_rad, kJointCount);
  json.key("delta_a").inline_array(deltas.delta_a_m, kJointCount);
  json.key("delta_d").inline_array(deltas.delta_d_m, kJointCount);
  json.key("delta_alpha").inline_array(deltas.delta_alpha_rad, kJointCount);
  json.end_object();
}

const std::vector<OptionSpec>& option_specs() {
  static const std::vector<OptionSpec> specs = [] {
    std::vector<OptionSpec> list = {
      {"robot", "FILE|BAG", "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
      {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
      {"joint-names", "N1,..,N6", "joint names in ROS logs (rostopic, bag), joints 1..6 in order (default: the UR drivers')", ""},
      {"samples", "FILE", "paired static samples q1..q6,x,y,z[,rx,ry,rz] (CSV; '-': stdin) instead of --robot/--tracker", ""},
      {"ur-calibration", "FILE", "UR calibration.conf: start from the controller's calibration", ""},
      {"robot-model", "NAME|FILE", std::string("nominal geometry: ") + robot_type_names() +
                                       ", or a robot description .json (standard or modified DH; a result file works)", "ur5"},
      {"tool", "X,Y,Z", "nominal retroreflector centre in the flange frame [m] (LM refines it; default: the description file's)", "0,0,0.1695"},
      {"params", "full|paper", "full identifiable model, or the link lengths (every non-zero d and a; for UR the paper's six)", "full"},
      {"method", "abc+lm|gsa+lm|lm|abc|gsa|all", "solver; 'all' runs GSA, ABC and LM (Table 1)", "abc+lm"},
      {"population-subset", "N", "hybrids (abc+lm, gsa+lm): ABC/GSA search on N training samples spread over the poses (farthest-point in joint space), LM refines on all; 0: every sample. --method abc, gsa and all always search on every sample", std::to_string(kDefaultPopulationSubset)},
      {"robust", "", "Huber loss in LM (a few bad tracker points do not drag the fit)", ""},
      {"seed", "N", "seed of the train/test split and of ABC/GSA", "1"},
      {"split", "FRACTION", "share of samples used for training (1: all, no test rows)", "0.7"},
      {"cv", "K|loo", "also cross-validate: K folds (or leave-one-out), held-out MAE per fold", ""},
      {"keep-outliers", "", "use every sample (no blunder search)", ""},
      {"controller-tcp", "", "the points are the controller's own TCP readings (a pendant export, RTDE actual_TCP_pose): in the base frame, at the TCP offset --tool; neither is fitted, joint 1's parameters are estimated instead (LM only; implies --method lm)", ""},
      {"significance", "T|auto", "LM fixes parameters whose change is below T sigma (0: off; auto: chosen by leave-one-out up to 64 training samples)", "2"},
      {"out", "FILE", "calibration result (robot-calibration/1 JSON; '-': stdout)", "result.json"},
      {"ur-deltas", "FILE", "also write the model as UR calibration.conf [mounting] deltas", ""},
      {"report", "DIR", "write an HTML report with figures into DIR", ""},
      {"max-change-mm", "X", "warn (exit 5) when a length moves more than this from the start geometry [mm]", "20"},
      {"max-change-deg", "X", "warn (exit 5) when an angle moves more than this from the start geometry [deg]", "2"},
      {"compliance", "basis|masses", "also fit the joints' gravity deflection (LM+compliance stage, docs/compliance.md): the generic gravity basis, or the link masses (UR3e, UR5e)", "", "basis"},
      {"gravity", "X,Y,Z", "with --compliance: gravity direction in the robot base frame (wall or ceiling mounts)", "0,0,-1"},
      {"payload", "KG@X,Y,Z", "with --compliance masses: payload mass [kg] and its centre in the flange frame [m]", ""},
      {"quiet", "", "no progress on stderr", ""},
      {"tracker-sigma-um", "S", "stated noise of the tracker per axis: the blunder test's sigma when the fit leaves too little redundancy, and the report's measurement noise (the same as --position-sigma-m) [um]", "10"},
      {"position-sigma-m", "S", "stated noise of the measured positions; with --angle-sigma-rad it weighs a measured orientation (rx, ry, rz columns of --samples) [m]", "1e-05"},
      {"angle-sigma-rad", "S", "stated noise of the measured orientations rx, ry, rz [rad]", "0.001"},
      {"joint-sigma-rad", "S", "noise of the joint readings, in the units of --position-sigma-m (e.g. the readings' rounding step): LM weighs each sample by its point covariance (errors in variables, docs/robust.md; 0: off) [rad]", "0"},
      {"joint-sigma-deg", "S", "--joint-sigma-rad in degrees (a UR pendant export's rounding: 0.01) [deg]", ""},
      {"orientation-form", "rotation-vector|euler-xyz", "what rx, ry, rz are: the tool frame's rotation vector, or intrinsic X-Y-Z Euler angles (R = Rx(rx) Ry(ry) Rz(rz), e.g. a Leica T-Mac export)", "rotation-vector"},
      {"orientation-lever-m", "L", "a measured orientation adds two points at this lever along the tool frame's x and y axes (targets 2, 3; 0: rx, ry, rz not used) [m] (default: position / angle sigma)", ""},
    };
    for (const OptionSpec& spec : input_unit_option_specs()) list.push_back(spec);
    return list;
  }();
  return specs;
}

// --- parse ------------------------------------------------------------------------------------

/// The built-in types whose published link masses the library holds, e.g. "ur3e, ur5e".
std::string arms_with_masses() {
  std::string names;
  const std::string all = robot_type_names();  // "ur3, ur5, ..."
  for (std::size_t at = 0; at < all.size();) {
    const std::size_t end = std::min(all.find(',', at), all.size());
    const std::string name(textio::trim(std::string_view(all).substr(at, end - at)));
    RobotType type = RobotType::ur5;
    ArmMasses masses;
    if (!name.empty() && robot_type_from_name(name.c_str(), &type) == Status::ok &&
        nominal_arm_masses(type, &masses) == Status::ok) {
      names += (names.empty() ? "" : ", ") + name;
    }
    at = end + 1;
  }
  return names;
}

/// --payload KG@X,Y,Z into *masses.
Error payload_option(const Options& options, ArmMasses* masses) {
  const std::string text = options.get("payload");
  const std::size_t at = text.find('@');
  const Error bad = Error::usage("--payload must be KG@X,Y,Z: a mass in kg >= 0 and its centre in the flange frame "
                                 "in metres (e.g. 1.2@0,0,0.05), not " + port::quoted(text));
  double kg = 0.0;
  if (at == std::string::npos || !textio::parse_double(text.substr(0, at), &kg) || !(kg >= 0.0 && kg < 1e4)) return bad;
  Vec3 com_m = Vec3::Zero();
  if (!parse_vec3(std::string_view(text).substr(at + 1), &com_m)) return bad;
  if (!com_m.allFinite() || com_m.norm() > 10.0) return bad;
  masses->payload_kg = kg;
  masses->payload_com_m = com_m;
  return Error{};
}

/// --compliance, --gravity, --payload into settings->compliance_model (the default terms of the
/// start model's nominal geometry); refused: a kind other than basis|masses, masses for an arm
/// without published masses, a zero or non-finite gravity, --gravity / --payload without the
/// compliance they set.
Error compliance_from_options(const Options& options, CalibrateSettings* settings) {
  settings->compliance = options.given("compliance");
  if (!settings->compliance) {
    for (const char* name : {"gravity", "payload"})
      if (options.given(name)) return Error::usage(std::string("--") + name + " needs --compliance (see --help)");
    return Error{};
  }
  if (settings->method == CalibrationMethod::abc || settings->method == CalibrationMethod::gsa) {
    return Error::usage(std::string("--compliance needs a method with LM (abc+lm, gsa+lm, lm, all), not --method ") +
                        calibration_method_name(settings->method));
  }
  const std::string kind = options.get("compliance");
  if (kind != "basis" && kind != "masses") {
    return Error::usage("--compliance must be 'basis' or 'masses', not " + port::quoted(kind));
  }
  const ComplianceLoad load = kind == "masses" ? ComplianceLoad::arm_masses : ComplianceLoad::point;
  if (options.given("payload") && load != ComplianceLoad::arm_masses) {
    return Error::usage("--payload needs --compliance masses (the basis kind weighs unit masses, not the payload)");
  }
  Vec3 gravity = Vec3::Zero();
  if (!parse_vec3(options.get("gravity"), &gravity) || !gravity.allFinite() || !(gravity.norm() > 1e-9)) {
    return Error::usage("--gravity must be X,Y,Z: the direction of gravity in the robot base frame, not zero (e.g. "
                        "0,0,-1 for a floor mount, 0,0,1 for a ceiling mount), not " + port::quoted(options.get("gravity")));
  }
  ComplianceModel& model = settings->compliance_model;
  if (load == ComplianceLoad::arm_masses) {
    RobotType type = RobotType::ur5;
    if (robot_type_from_name(settings->robot.robot.c_str(), &type) != Status::ok ||
        nominal_arm_masses(type, &model.masses) != Status::ok) {
      return Error::usage("--compliance masses needs the arm's link masses, which are known here for " +
                          arms_with_masses() + " only (by --robot-model's name); " +
                          port::quoted(settings->robot.robot) + " has none: use --compliance basis");
    }
    if (options.given("payload")) {
      const Error payload = payload_option(options, &model.masses);
      if (!payload.ok()) return payload;
    }
  }
  if (default_compliance_terms(settings->robot.model, gravity, load, &model) != Status::ok) {
    return Error::usage("--compliance: no joint of " + port::quoted(settings->robot.robot) +
                        " has a horizontal axis at q = 0 under --gravity " + options.get("gravity") +
                        " (the shoulder and elbow carry the deflection): check --gravity");
  }
  return Error{};
}

/// --position-sigma-m, --angle-sigma-rad, --orientation-lever-m (csv.hpp, OrientationInput).
Error orientation_options(const Options& options, textio::OrientationInput* orientation) {
  if (options.given("position-sigma-m") && options.given("tracker-sigma-um")) {
    return Error::usage("--tracker-sigma-um and --position-sigma-m say the same: give one");
  }
  Error error = number_option(options, "position-sigma-m", &orientation->position_sigma_m);
  if (error.ok() && options.given("tracker-sigma-um")) {
    double sigma_um = 0.0;
    error = number_option(options, "tracker-sigma-um", &sigma_um);
    orientation->position_sigma_m = sigma_um * 1e-6;
    if (error.ok() && !(sigma_um > 0.0 && sigma_um < 1e6)) return Error::usage("--tracker-sigma-um must be in (0, 1e6)");
  }
  if (error.ok()) error = number_option(options, "angle-sigma-rad", &orientation->angle_sigma_rad);
  if (error.ok() && options.given("orientation-lever-m")) error = number_option(options, "orientation-lever-m", &orientation->lever_m);
  if (!error.ok()) return error;
  if (!(orientation->position_sigma_m > 0.0 && orientation->position_sigma_m < 1.0) ||
      !(orientation->angle_sigma_rad > 0.0 && orientation->angle_sigma_rad < 1.0)) {
    return Error::usage("--position-sigma-m and --angle-sigma-rad must be in (0, 1)");
  }
  if (options.given("orientation-lever-m") && !(orientation->lever_m >= 0.0 && orientation->lever_m <= 1.0)) {
    return Error::usage("--orientation-lever-m must be in [0, 1] m");
  }
  const std::string form = options.get("orientation-form");
  if (form == "euler-xyz") {
    orientation->form = textio::OrientationForm::euler_xyz;
  } else if (form != "rotation-vector") {
    return Error::usage("--orientation-form must be rotation-vector or euler-xyz, not " + port::quoted(form));
  }
  return Error{};
}

/// --joint-sigma-rad or --joint-sigma-deg (not both), in [0, 1) rad.
Error joint_sigma_option(const Options& options, double* sigma_rad) {
  const bool in_degrees = options.given("joint-sigma-deg");
  if (in_degrees && options.given("joint-sigma-rad")) return Error::usage("give --joint-sigma-rad or --joint-sigma-deg, not both");
  const Error error = number_option(options, in_degrees ? "joint-sigma-deg" : "joint-sigma-rad", sigma_rad);
  if (!error.ok()) return error;
  if (in_degrees) *sigma_rad *= math::kRadPerDeg;
  if (!(*sigma_rad >= 0.0 && *sigma_rad < 1.0)) return Error::usage("--joint-sigma-rad must be in [0, 1) rad");
  return Error{};
}

Error settings_from_options(const Options& options, CalibrateSettings* settings) {
  bool from_file = false;
  Error error = robot_model_option(options, "robot-model", &settings->robot, &from_file);
  if (error.ok() && from_file && !options.given("tool")) settings->tool_m = settings->robot.model.tool_m;
  if (error.ok() && (!from_file || options.given("tool"))) error = vec3_option(options, "tool", &settings->tool_m);
  if (!error.ok()) return error;
  const std::string params = options.get("params");
  if (params != "full" && params != "paper") return Error::usage("--params must be 'full' or 'paper', not " + port::quoted(params));
  settings->paper_params = params == "paper";
  if (calibration_method_from_name(options.get("method").c_str(), &settings->method) != Status::ok) {
    return Error::usage(std::string("--method must be one of ") + calibration_method_names() + "; not " +
                        port::quoted(options.get("method")));
  }
  Error seeded = seed_option(options, "seed", &settings->seed);
  if (seeded.ok()) {
    seeded = count_option(options, "population-subset", 0, kDefaultPopulationSubset, &settings->population_subset);
  }
  if (!seeded.ok()) return seeded;
  if (!textio::parse_double(options.get("split"), &settings->train_fraction) ||
      !(settings->train_fraction > 0.0 && settings->train_fraction <= 1.0)) {
    return Error::usage("--split must be a fraction in (0, 1], not " + port::quoted(options.get("split")));
  }
  const std::string cv = options.get("cv");
  double folds = 0.0;
  if (cv == "loo") {
    settings->cv_folds = 1;
  } else if (!cv.empty()) {
    if (!textio::parse_double(cv, &folds) || folds < 2.0 || folds > static_cast<double>(kMaxCrossValidationFolds) ||
        folds != static_cast<double>(static_cast<std::size_t>(folds))) {
      return Error::usage("--cv must be 'loo' or a number of folds in [2, " + std::to_string(kMaxCrossValidationFolds) +
                          "], not " + port::quoted(cv));
    }
    settings->cv_folds = static_cast<std::size_t>(folds);
  }
  settings->keep_outliers = options.given("keep-outliers");
  settings->controller_tcp = options.given("controller-tcp");
  if (settings->controller_tcp) {
    if (options.given("method") && settings->method != CalibrationMethod::lm) {
      return Error::usage("--controller-tcp works with --method lm only (ABC and GSA fit their own base), not " +
                          port::quoted(options.get("method")));
    }
    settings->method = CalibrationMethod::lm;
  }
  if (options.get("significance") == "auto") {
    settings->significance_t = -1.0;  // lib: chosen by leave-one-out on small sets
  } else if (!textio::parse_double(options.get("significance"), &settings->significance_t) ||
             !(settings->significance_t >= 0.0 && settings->significance_t <= 10.0)) {
    return Error::usage("--significance must be 'auto' or a number in [0, 10]");
  }
  const bool samples = !options.get("samples").empty();
  const bool streams = !options.get("robot").empty() || !options.get("tracker").empty();
  if (samples == streams) return Error::usage("give either --samples, or --robot and --tracker (see --help)");
  if (streams && (options.get("robot").empty() || options.get("tracker").empty())) {
    return Error::usage("--robot and --tracker go together");
  }
  error = input_units_option(options, &settings->units);
  if (!error.ok()) return error;
  double max_mm = 0.0;
  double max_deg = 0.0;
  error = number_option(options, "max-change-mm", &max_mm);
  if (error.ok()) error = number_option(options, "max-change-deg", &max_deg);
  if (!error.ok()) return error;
  if (!(max_mm > 0.0 && max_mm < 1e9) || !(max_deg > 0.0 && max_deg <= 360.0)) {
    return Error::usage("--max-change-mm must be positive and --max-change-deg in (0, 360]");
  }
  settings->bounds.max_length_change_m = max_mm * 1e-3;
  settings->bounds.max_angle_change_rad = max_deg * math::kRadPerDeg;
  settings->robust = options.given("robust");
  settings->progress = progress_enabled(options);
  const Error compliance = compliance_from_options(options, settings);
  if (!compliance.ok()) return compliance;
  error = orientation_options(options, &settings->orientation);
  if (error.ok()) error = joint_sigma_option(options, &settings->joint_sigma_rad);
  return error;
}

/// Where the results go, declared (and checked) before the long work.
struct OutputIds {
  std::size_t result = 0;     ///< --out
  std::size_t ur_deltas = 0;  ///< --ur-deltas, when given
  std::size_t report = 0;     ///< --report, when given
};

Error declare_outputs(const Options& options, port::OutputSet* outputs, OutputIds* ids) {
  Error error = declare_inputs(options, {"out", "ur-deltas", "report"}, outputs);
  if (error.ok()) error = outputs->add_file(options.get("out"), "--out", &ids->result);
  if (error.ok() && !options.get("ur-deltas").empty()) {
    error = outputs->add_file(options.get("ur-deltas"), "--ur-deltas", &ids->ur_deltas);
  }
  if (error.ok() && !options.get("report").empty()) {
    error = outputs->add_folder(options.get("report"), "--report", &ids->report);
  }
  return error;
}

/// The start geometry: nominal, or the controller's calibration.conf.
Error start_geometry(const Options& options, const CalibrateSettings& settings, RobotModel* start) {
  *start = settings.robot.model;
  start->tool_m = settings.tool_m;
  if (options.get("ur-calibration").empty()) return Error{};
  const port::Error r = textio::read_ur_calibrated_model(options.get("ur-calibration"), settings.robot.model,
                                                         settings.robot.robot, start);
  if (!r.ok()) return r;
  start->tool_m = settings.tool_m;
  return Error{};
}

/// The dataset, checked for size and split.
Error load_dataset(const Options& options, const CalibrateSettings& settings, CliDataset* dataset,
                   streams::SessionFacts* facts, PointFates* fates) {
  streams::SessionConfig config;
  config.observer = fates;
  config.speed_model = settings.robot.model;
  config.speed_model.tool_m = settings.tool_m;  // for tool speeds only
  config.progress = settings.progress;
  config.log_options.units = settings.units;
  config.orientation = settings.orientation;
  Error error = streams::joint_names_option(options.get("joint-names"), &config.log_options);
  if (!error.ok()) return error;
  error = streams::load_session({options.get("samples"), options.get("robot"), options.get("tracker")}, config,
                                      dataset, facts);
  if (!error.ok()) return error;
  // No floor on the sample count: the identifiability analysis decides what the samples determine.
  // The job splits; fewer than 3 training poses cannot even place the tracker frame.
  const std::size_t train_poses = dataset->train_count_for(settings.train_fraction);
  if (train_poses < 3 && train_poses < dataset->pose_count()) {
    return Error::usage("--split " + options.get("split") + " leaves " + std::to_string(train_poses) + " training pose(s) of " +
                        std::to_string(dataset->pose_count()) + "; the tracker frame needs at least 3");
  }
  // Folds hold out whole poses (with several reflectors, a pose's samples stay together).
  const std::string units = dataset->pose_count() == dataset->size() ? " samples" : " poses";
  if (settings.cv_folds > dataset->pose_count()) {
    return Error::usage("--cv " + options.get("cv") + ": more folds than the " + std::to_string(dataset->pose_count()) +
                        units);
  }
  if (settings.cv_folds == 1 && dataset->pose_count() > kMaxCrossValidationFolds) {
    return Error::usage("--cv loo: at most " + std::to_string(kMaxCrossValidationFolds) + units + " (use --cv K)");
  }
  return Error{};
}

// --- run (the computation: lib's calibrate()) ---------------------------------------------------

/// --cv after the job (whose messages name the failing step), then the dataset put back as
/// the job left it (the same set aside and seeded split) for the tables.
Error cross_validation(const CalibrateSettings& settings, const RobotModel& start, const CalibrationOptions& job,
                       CliDataset* dataset, Run* run) {
  auto& workspace = cli_workspace(dataset->size());
  static CalibrationResult scratch;  // ~5 KB
  JobObserver quiet(false);
  const Status status = cross_validate(start, dataset, job, settings.cv_folds == 1 ? 0 : settings.cv_folds, &workspace,
                                       &scratch, &run->cv, &quiet);
  std::vector<std::uint32_t> aside;
  for (const CalibrationOutlier& o : run->result.outlier_list()) aside.push_back(o.index);
  dataset->set_aside(Span<const std::uint32_t>(aside.data(), aside.size()));
  if (dataset->split(job.train_fraction, job.seed) != Status::ok || status != Status::ok) {
    return Error::failure(std::string("cross-validation failed: ") + status_message(status));
  }
  return Error{};
}

Error run(const CalibrateSettings& settings, const RobotModel& start, CliDataset* dataset, Run* run) {
  CalibrationOptions job;
  job.method = settings.method;
  job.params = settings.paper_params ? CalibrationParams::paper : CalibrationParams::full;
  job.train_fraction = settings.train_fraction;
  job.seed = settings.seed;
  job.robust = settings.robust;
  job.keep_outliers = settings.keep_outliers;
  job.base_known = settings.controller_tcp;  // known_base_to_tracker: the identity
  job.tool_known = settings.controller_tcp;  // the start model's tool points: --tool and the orientation's lever
  job.significance_t = settings.significance_t;
  job.population_subset = settings.population_subset;
  job.lm.joint_sigma_rad = settings.joint_sigma_rad;
  job.lm.position_sigma_m = settings.orientation.position_sigma_m;
  job.blunder_test.tracker_sigma_m = settings.orientation.position_sigma_m;
  job.compliance.enabled = settings.compliance;
  if (settings.compliance) job.compliance.model = settings.compliance_model;
  auto& workspace = cli_workspace(dataset->size());
  JobObserver observer(settings.progress);
  run->target_count = target_count(dataset->samples());
  run->options = job;
  const Status status = hivecal::calibrate(start, dataset, job, &workspace, &run->result, &observer);
  for (std::size_t k = 0; k < kMaxCalibrationStages; ++k) run->seconds[k] = observer.seconds[k];
  const CalibrationStep step = run->result.step;
  if (step == CalibrationStep::baseline) {
    return Error::input(std::string("cannot fit the tracker frame: ") + status_message(status) +
                        (status == Status::degenerate_geometry || status == Status::too_few_samples
                             ? " (at least 3 samples at non-collinear tool points are needed)"
                             : ""));
  }
  if (status == Status::too_few_samples && step == CalibrationStep::lm) {
    return Error::input(std::string("LM needs more samples than free parameters / 3 (") +
                        std::to_string(run->result.train_count) +
                        " training samples); try --params paper, --split 1 or more poses");
  }
  if (status != Status::ok) {
    const char* what = step == CalibrationStep::abc   ? "ABC"
                       : step == CalibrationStep::gsa ? "GSA"
                       : step == CalibrationStep::lm  ? "LM"
                                                      : calibration_step_name(step);
    return Error::failure(std::string(what) + " failed: " + status_message(status));
  }
  run->has_cv = settings.cv_folds > 0;
  return run->has_cv ? cross_validation(settings, start, job, dataset, run) : Error{};
}

// --- present ----------------------------------------------------------------------------------

void write_input_facts(textio::JsonWriter& json, const streams::SessionFacts& facts) {
  if (!facts.has_stream) return;
  const ClockFit& clock = facts.run.clock;
  json.key("clock").begin_object();
  json.key("offset_at_reference_s").value(clock.offset_at_reference_us * 1e-6);
  json.key("offset_sigma_s").value(clock.sigma_offset_at_reference_us * 1e-6);
  json.key("drift").value(clock.drift);
  json.key("drift_sigma").value(clock.sigma_drift);
  json.end_object();
  json.key("extraction").begin_object();
  json.key("tracker_points").value(static_cast<long long>(facts.run.counts.tracker_points));
  json.key("kept").value(static_cast<long long>(facts.run.counts.kept));
  json.key("dropped").begin_object();
  for (const auto& [reason, count] : facts.dropped) json.key(reason).value(static_cast<long long>(count));
  json.end_object();
  json.end_object();
}

/// Every sample (training first) and each model's prediction of it, for the figures.
void add_samples(const CliDataset& dataset, const Run& run, report::ReportData* data) {
  for (const bool test : {false, true}) {
    for (const Sample& s : test ? dataset.test() : dataset.train()) {
      report::SampleRow row;
      for (int j = 0; j < kJointCount; ++j) row.q_rad[j] = s.q_rad(j);
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

/// Where sample `index` (Sample::index) came from: "file:line" for paired samples.
std::string sample_source(const streams::SessionFacts& facts, std::uint32_t index) {
  if (index < facts.sample_sources.size()) return facts.sample_sources[index];
  return "sample " + std::to_string(index);
}

/// "noise: ..." — the fit's residual sigma against the tracker's stated noise, and what the ratio says.
std::string noise_statement(double fit_sigma_m, double tracker_sigma_m) {
  const double ratio = fit_sigma_m / tracker_sigma_m;
  char line[300];
  std::snprintf(line, sizeof line,
                "noise: the fit's residual sigma %s mm per axis is %.1fx the tracker's stated %s mm (--tracker-sigma-um)%s",
                format_mm(fit_sigma_m).c_str(), ratio, format_mm(tracker_sigma_m).c_str(),
                ratio > 2.0 ? ": unmodelled effects (or a wrong stated noise) dominate the residuals, not the tracker"
                            : ": the model explains the data to the measurement noise");
  return line;
}

/// Collects each pose's test under the final calibration: the kept poses' w, the uncontrolled ones.
class PoseTests final : public UnitTestVisitor {
 public:
  PoseTests(const streams::SessionFacts& facts, std::vector<std::uint32_t> aside, report::OutlierTable* table)
      : facts_(facts), aside_(std::move(aside)), table_(table) {}
  void on_unit(const UnitTest& t) override {
    if (t.fitted && t.critical_w > 0.0) table_->critical_w = t.critical_w;
    if (t.fitted && !t.controlled) {
      table_->uncontrolled.push_back(sample_source(facts_, t.index));
    } else if (t.controlled && std::find(aside_.begin(), aside_.end(), t.index) == aside_.end()) {
      table_->kept_w.push_back(t.w);
    }
  }

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
  if (table.searched && r.final_stage() != nullptr) {
    static ReliabilityWorkspace workspace;  // ~26 kB
    std::vector<std::uint32_t> aside;
    for (const CalibrationOutlier& o : r.outlier_list()) aside.push_back(o.index);
    PoseTests tests(facts, std::move(aside), &table);
    BlunderTestSummary summary;
    test_final_calibration(r, dataset, run.options, &workspace, &tests, &summary);
  }
  for (const CalibrationOutlier& o : r.outlier_list()) {
    char line[300];
    std::snprintf(line, sizeof line, "set aside as a blunder: %s, residual %s mm, w %.2f > %.2f (alpha %.2g %% for the set)",
                  sample_source(facts, o.index).c_str(), format_mm(o.residual_m).c_str(), o.w, o.critical_w,
                  table.alpha * 100.0);
    data->info_lines.push_back(line);
    table.rows.push_back({sample_source(facts, o.index), o.residual_m, o.w});
  }
  if (r.blunder_verdict == BlunderVerdict::model_error) {
    data->info_lines.push_back("blunder test: more than " + std::to_string(r.blunder_limit) +
                               " training pose(s) fail the w-test: the model, not the data, is wrong (unmodelled "
                               "effects); none removed by the test");
  }
  for (const std::string& source : table.uncontrolled) {
    data->info_lines.push_back("uncontrolled pose (redundancy below 0.1: a blunder there cannot be told from the "
                               "geometry; kept, not tested): " + source);
  }
}

/// Tables and figures of a run, and the text of the terminal.
report::ReportData present(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset,
                           const streams::SessionFacts& facts, const Run& run) {
  const CalibrationBaseline& uncalibrated = run.result.baseline;
  const CalibrationStage& final_stage = run.final_stage();
  report::ReportData data;
  data.title = "hivecal calibration: " + settings.robot.robot;
  data.input_lines = facts.info_lines;
  data.info_lines.push_back("samples: " + std::to_string(dataset.size()) + " (train " +
                            std::to_string(dataset.train().size()) + ", test " + std::to_string(dataset.test().size()) +
                            ")");
  const std::string orientation = streams::orientation_line(facts);
  if (!orientation.empty()) data.info_lines.push_back(orientation);  // in the report's "info" too
  if (settings.controller_tcp) {
    data.info_lines.push_back("known (--controller-tcp): the base (identity) and the tool points; not fitted, joint 1 estimated instead");
  }
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
    for (const std::string& line : identifiability_lines(*lm, run.result.lm_pruned_mask, run.result.significance_t,
                                                          final_stage.model)) {
      data.info_lines.push_back(line);
    }
    if (final_stage.rigid_kept) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "compliance: no term passed the %.3g sigma test (the data show no bending): the rigid fit is kept",
                    std::fmax(run.result.significance_t, CalibrationCompliance{}.significance_t));
      data.info_lines.push_back(buf);
    }
    data.identifiability = identifiability_table(*lm, final_stage.model);
    for (int k = 0; k < kFullParamCount; ++k)
      if (mask_has(run.result.lm_pruned_mask, k)) data.identifiability.fixed.push_back(full_param_name(k, final_stage.model));
    data.identifiability.significance_t = run.result.significance_t;
    data.fit_sigma_m = lm->residual_sigma_m;
  }
  data.noise_sigma_m = settings.orientation.position_sigma_m;
  if (data.fit_sigma_m > 0.0) data.info_lines.push_back(noise_statement(data.fit_sigma_m, data.noise_sigma_m));
  data.parameters = parameter_rows(final_stage, run.final_lm(), start, dataset.train());
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
    for (std::size_t k = 0; k < run.cv.fold_count; ++k) {
      const CrossValidationFold& f = run.cv.folds[k];
      data.cross_validation.folds.push_back(
          {f.train_count, f.test.count, f.train.mae(ErrorAxis::norm_3d), f.test.mae(ErrorAxis::norm_3d)});
    }
  }
  return data;
}

/// The terminal text (on stdout, or on stderr when stdout carries the result).
void print_tables(std::FILE* out, const report::ReportData& data, const Run& run) {
  for (const std::string& line : data.input_lines) std::fprintf(out, "%s\n", line.c_str());
  for (const std::string& line : data.info_lines) std::fprintf(out, "%s\n", line.c_str());
  std::fprintf(out, "\n%s", report::format_tables_text(data).c_str());
  if (run.has_cv) {
    const CrossValidationResult& cv = run.cv;
    std::fprintf(out, "\nCross-validation (%zu folds over %zu samples, held-out 3-D MAE):\n", cv.fold_count,
                 cv.sample_count);
    std::fprintf(out, "  fold  train  test  MAE [mm]\n");
    for (std::size_t k = 0; k < cv.fold_count; ++k) {
      std::fprintf(out, "  %4zu  %5zu  %4zu  %8s\n", k + 1, cv.folds[k].train_count, cv.folds[k].test.count,
                   format_mm(cv.folds[k].test.mae(ErrorAxis::norm_3d)).c_str());
    }
    std::fprintf(out, "  all held-out samples: %s mm (fold mean %s, worst %s; uncalibrated %s mm)\n",
                 format_mm(cv.mae_3d_m).c_str(), format_mm(cv.fold_mae_3d_mean_m).c_str(),
                 format_mm(cv.fold_mae_3d_max_m).c_str(), format_mm(cv.baseline_mae_3d_m).c_str());
  }
  std::fprintf(out, "\nCalibrated parameters (%s):\n", run.final_method().c_str());
  for (const std::string& line : report::format_parameters_text(data)) std::fprintf(out, "  %s\n", line.c_str());
}

void write_outliers(textio::JsonWriter& w, const streams::SessionFacts& facts, const Run& run) {
  w.key("outlier_search").value(run.result.outlier_rounds > 0);
  w.key("blunder_verdict").value(blunder_verdict_name(run.result.blunder_verdict));
  w.key("outliers").begin_array();
  for (const CalibrationOutlier& o : run.result.outlier_list()) {
    w.begin_object();
    w.key("index").value(static_cast<long long>(o.index));
    w.key("source").value(sample_source(facts, o.index));
    w.key("residual_m").value(o.residual_m);
    w.key("w").value(o.w);
    w.key("critical_w").value(o.critical_w);
    w.end_object();
  }
  w.end_array();
}

void write_cross_validation(textio::JsonWriter& w, const CrossValidationResult& cv) {
  w.key("cross_validation").begin_object();
  w.key("folds").value(static_cast<long long>(cv.fold_count));
  w.key("samples").value(static_cast<long long>(cv.sample_count));
  w.key("mae_3d_m").value(cv.mae_3d_m);
  w.key("baseline_mae_3d_m").value(cv.baseline_mae_3d_m);
  w.key("fold_mae_3d_mean_m").value(cv.fold_mae_3d_mean_m);
  w.key("fold_mae_3d_max_m").value(cv.fold_mae_3d_max_m);
  w.key("per_fold").begin_array();
  for (std::size_t k = 0; k < cv.fold_count; ++k) {
    w.begin_object();
    w.key("train_count").value(static_cast<long long>(cv.folds[k].train_count));
    w.key("test_count").value(static_cast<long long>(cv.folds[k].test.count));
    w.key("train_mae_3d_m").value(cv.folds[k].train.mae(ErrorAxis::norm_3d));
    w.key("test_mae_3d_m").value(cv.folds[k].test.mae(ErrorAxis::norm_3d));
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

/// `warnings`: the fit's plausibility warnings, a "warnings" array when there are any.
std::string result_json(const CalibrateSettings& settings, const report::ReportData& data,
                        const streams::SessionFacts& facts, const Run& run, const std::vector<std::string>& warnings) {
  const CalibrationStage& final_stage = run.final_stage();
  textio::CalibrationFile file;
  static_cast<textio::RobotDescription&>(file) = settings.robot;  // name and convention as given
  file.model = final_stage.model;
  file.target_count = run.target_count;
  file.base_to_tracker = final_stage.base_to_tracker;
  file.has_metrics = true;
  file.metrics = data.calibrated;
  for (int t = 0; run.final_lm() != nullptr && t < final_stage.model.compliance.term_count; ++t) {
    const int k = compliance_param_index(t);
    if (mask_has(run.final_lm()->identifiability.kept_mask, k)) file.compliance_sigma[t] = run.final_lm()->sigma(k);
  }
  const UrCalibrationDeltas deltas = ur_deltas_between(settings.robot.model, final_stage.model);
  return textio::format_calibration_json(file, [&](textio::JsonWriter& w) {
    w.key("method").value(run.final_method());
    w.key("params").value(settings.paper_params ? "paper" : "full");
    w.key("seed").value(static_cast<unsigned long long>(settings.seed));
    w.key("split").value(settings.train_fraction);
    w.key("uncalibrated_metrics").begin_object();
    w.key("train");
    textio::write_error_stats(w, data.uncalibrated.train);
    w.key("test");
    textio::write_error_stats(w, data.uncalibrated.test);
    w.end_object();
    write_stage_list(w, data.methods);
    if (run.final_lm() != nullptr) {
      write_lm_details(w, *run.final_lm(), final_stage.model);
      w.key("significance_t").value(run.result.significance_t);
      w.key("not_significant").begin_array();
      for (int k = 0; k < kFullParamCount; ++k)
        if (mask_has(run.result.lm_pruned_mask, k)) w.value(full_param_name(k, final_stage.model));
      w.end_array();
      if (settings.joint_sigma_rad > 0.0) {  // only when given: the results of the default stay byte for byte
        w.key("joint_sigma_rad").value(settings.joint_sigma_rad);
        w.key("joint_sigma_position_sigma_m").value(settings.orientation.position_sigma_m);
      }
      if (settings.controller_tcp) {  // only when given, likewise
        w.key("known").value("base (identity) and tool points: the controller's TCP readings (--controller-tcp)");
      }
    }
    write_ur_deltas(w, deltas);
    write_input_facts(w, facts);
    if (facts.orientation.poses > 0) {
      w.key("orientation").begin_object();
      w.key("poses").value(static_cast<long long>(facts.orientation.poses));
      w.key("lever_m").value(facts.orientation.lever_m);
      w.key("position_sigma_m").value(facts.orientation_input.position_sigma_m);
      w.key("angle_sigma_rad").value(facts.orientation_input.angle_sigma_rad);
      w.key("targets").value("2 and 3 are the measured point moved by lever_m along the measured x and y axes");
      w.end_object();
    }
    write_outliers(w, facts, run);
    if (run.has_cv) write_cross_validation(w, run.cv);
    if (!warnings.empty()) {
      w.key("warnings").begin_array();
      for (const std::string& warning : warnings) w.value(warning);
      w.end_array();
    }
    w.key("report");  // what `hivecal report` draws the page from
    report::write_report_data(w, data);
  });
}

// --- write ------------------------------------------------------------------------------------

/// Stages every output, then commits them together: all or nothing.
Error write_outputs(const Options& options, const CalibrateSettings& settings, const report::ReportData& data,
                    const streams::SessionFacts& facts, const Run& run, const std::vector<std::string>& warnings,
                    port::OutputSet* outputs, const OutputIds& ids) {
  const CalibrationStage& final_stage = run.final_stage();
  Error error = outputs->stage_text(ids.result, "", result_json(settings, data, facts, run, warnings));
  if (error.ok() && !options.get("ur-deltas").empty()) {
    const UrCalibrationDeltas deltas = ur_deltas_between(settings.robot.model, final_stage.model);
    error = outputs->stage_text(ids.ur_deltas, "", textio::format_ur_calibration_conf(deltas));
  }
  if (error.ok() && !options.get("report").empty()) {
    error = outputs->stage_text(ids.report, "index.html", report::render_html(data));
  }
  return error.ok() ? outputs->commit() : error;
}

/// `*warnings`: the fit's plausibility warnings (fit_checks.hpp), printed on stderr; the
/// outputs are written all the same.
Error calibrate(const Options& options, std::vector<std::string>* warnings) {
  CalibrateSettings settings;
  Error error = settings_from_options(options, &settings);
  port::OutputSet outputs;
  OutputIds ids;
  if (error.ok()) error = declare_outputs(options, &outputs, &ids);
  RobotModel start;
  if (error.ok()) error = start_geometry(options, settings, &start);
  static CliDataset dataset;  // static: its storage is kept; emptied for each call (tests run several in one process)
  dataset.clear();
  streams::SessionFacts facts;
  PointFates fates;
  if (error.ok()) error = load_dataset(options, settings, &dataset, &facts, &fates);
  if (error.ok()) textio::start_orientation_targets(facts.orientation, &start);
  static Run job;  // static: the CalibrationResult is ~5 KB
  job.from_controller = !options.get("ur-calibration").empty();
  job.link_length_count = link_length_set(start).count;
  if (error.ok()) error = run(settings, start, &dataset, &job);
  if (!error.ok()) return error;
  report::ReportData data = present(settings, start, dataset, facts, job);
  if (facts.has_stream) data.timeline = fates.timeline(120);
  // Any output on stdout (the result, or --ur-deltas -) keeps the tables off it.
  const bool result_on_stdout = options.get("out") == "-" || options.get("ur-deltas") == "-";
  std::FILE* terminal = result_on_stdout ? stderr : stdout;
  print_tables(terminal, data, job);
  *warnings = fit_warnings(job.result, settings.bounds, data.parameters);
  error = write_outputs(options, settings, data, facts, job, *warnings, &outputs, ids);
  if (!error.ok()) return error;
  if (!result_on_stdout) std::fprintf(terminal, "\nresult: %s\n", options.get("out").c_str());
  if (!options.get("ur-deltas").empty()) std::fprintf(terminal, "UR deltas: %s\n", options.get("ur-deltas").c_str());
  if (!options.get("report").empty()) std::fprintf(terminal, "report: %s/index.html\n", options.get("report").c_str());
  for (const std::string& warning : *warnings) cli::error(kCommand, "warning: " + warning);
  return Error{};
}

}  // namespace

int calibrate_main(int argc, char** argv) {
  Options options;
  const int parsed = parse_options(kCommand,
                                   "Estimates the robot geometry and the base -> tracker transform from tracker\n"
                                   "measurements, prints the paper-style tables and writes the result.",
                                   option_specs(), argc, argv, &options);
  if (parsed >= 0) return parsed;
  std::vector<std::string> warnings;
  const int code = exit_with(kCommand, calibrate(options, &warnings));
  return code == kExitOk && !warnings.empty() ? kExitWarnings : code;
}

}  // namespace hivecal::cli
