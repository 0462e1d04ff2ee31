// hivecal calibrate: inputs (paired samples, serial captures or CSV logs) -> dataset ->
// ABC / GSA / Levenberg-Marquardt -> tables, result JSON, UR deltas and HTML report.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "calibrate_inputs.hpp"
#include "calibration_json.hpp"
#include "cli.hpp"
#include "commands.hpp"
#include "hivecal/calibration.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "report.hpp"
#include "text_util.hpp"
#include "ur_calibration_conf.hpp"

namespace hivecal::cli {
namespace {

constexpr std::size_t kTraceCapacity = 1024;
/// The job's workspace: exact (double) paper-6 terms and joint trig storage for the CLI's
/// largest dataset (static: ~2.3 MB).
using CliWorkspace = CalibrationWorkspace<kCliDatasetCapacity, double, 150, kTraceCapacity, kCliDatasetCapacity>;

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

std::vector<double> trace_values(Span<const double> trace) {
  std::vector<double> v;
  for (double x : trace) v.push_back(x);
  return v;
}

CalibrationMethod method_from_name(const std::string& name) {
  for (CalibrationMethod m : {CalibrationMethod::lm, CalibrationMethod::abc, CalibrationMethod::gsa,
                              CalibrationMethod::abc_lm, CalibrationMethod::gsa_lm, CalibrationMethod::all}) {
    if (name == calibration_method_name(m)) return m;
  }
  return CalibrationMethod::abc_lm;  // settings_from_options accepts only the names above
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

report::MethodRow stage_row(const CalibrationResult& result, std::size_t k, double seconds) {
  const CalibrationStage& stage = result.stages[k];
  std::string params = stage.params == CalibrationParams::paper ? "paper-6" : "full";
  if (stage.solver == CalibrationSolver::lm) {
    params += " (" + std::to_string(result.lm.identifiability.kept_count()) + " estimated)";
  }
  return method_row(result.stage_name(k), params, stage.train, stage.test, seconds,
                    static_cast<long long>(stage.evaluations));
}

std::vector<std::string> identifiability_lines(const LmResult& lm) {
  std::vector<std::string> lines;
  const IdentifiabilityReport& id = lm.identifiability;
  char buf[256];
  std::snprintf(buf, sizeof buf, "identifiability: %d of %d free parameters estimated, condition number %.3g -> %.3g",
                id.kept_count(), mask_count(id.free_mask), id.condition_before, id.condition_after);
  lines.push_back(buf);
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    std::string combination;
    for (int c = 0; c < kNullComponentCount; ++c) {
      if (d.component_index[c] < 0) continue;
      std::snprintf(buf, sizeof buf, "%s%+.3g*%s", combination.empty() ? "" : " ", d.component[c],
                    full_param_name(d.component_index[c]));
      combination += buf;
    }
    std::snprintf(buf, sizeof buf, "  dropped %-8s (%s, sigma ratio %.2g): %s", full_param_name(d.index),
                  unidentifiable_reason_name(d.reason), d.singular_ratio, combination.c_str());
    lines.push_back(buf);
  }
  return lines;
}

/// `lm`: the LM details when `stage` is the LM stage, else null.
std::vector<std::string> parameter_lines(const CalibrationStage& stage, const LmResult* lm, const RobotModel& start) {
  std::vector<std::string> lines;
  const ModelParams before = to_params(start);
  const ModelParams after = to_params(stage.model);
  char buf[160];
  for (int k = 0; k < kModelParamCount; ++k) {
    const bool estimated = lm != nullptr && mask_has(lm->identifiability.kept_mask, k);
    const bool changed = after(k) != before(k);
    if (!estimated && !changed) continue;
    const bool angle = k < kDhParamCount && (k % kParamsPerJoint == 0 || k % kParamsPerJoint == 3);
    const double scale = angle ? 1e3 : 1e3;
    std::snprintf(buf, sizeof buf, "%-8s %+.9f %s  (change %+.4f %s%s)", full_param_name(k), after(k),
                  angle ? "rad" : "m", (after(k) - before(k)) * scale, angle ? "mrad" : "mm",
                  estimated ? (", sigma " + std::to_string(lm->sigma(k) * scale) + (angle ? " mrad" : " mm")).c_str()
                            : "");
    lines.push_back(buf);
  }
  return lines;
}

void write_stage_list(textio::JsonWriter& json, const std::vector<report::MethodRow>& rows) {
  json.key("methods").begin_array();
  for (const report::MethodRow& row : rows) {
    json.begin_object();
    json.key("method").value(row.method);
    json.key("params").value(row.parameters);
    json.key("train_mae_m").value(row.train.mae(ErrorAxis::norm_3d));
    json.key("test_mae_m").value(row.test.mae(ErrorAxis::norm_3d));
    json.key("seconds").value(row.seconds);
    json.key("evaluations").value(row.evaluations);
    json.end_object();
  }
  json.end_array();
}

void write_lm_details(textio::JsonWriter& json, const LmResult& lm) {
  const IdentifiabilityReport& id = lm.identifiability;
  json.key("identifiability").begin_object();
  json.key("estimated").begin_array();
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) json.value(full_param_name(k));
  json.end_array();
  json.key("dropped").begin_array();
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    json.begin_object();
    json.key("param").value(full_param_name(d.index));
    json.key("reason").value(unidentifiable_reason_name(d.reason));
    json.key("singular_ratio").value(d.singular_ratio);
    json.key("combination").begin_object();
    for (int c = 0; c < kNullComponentCount; ++c)
      if (d.component_index[c] >= 0) json.key(full_param_name(d.component_index[c])).value(d.component[c]);
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
    if (mask_has(id.kept_mask, k)) json.key(full_param_name(k)).value(lm.sigma(k));
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

}  // namespace

int calibrate_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"robot", "FILE", "robot joint stream: serial capture or CSV log t,q1..q6 (detected by content)", ""},
      {"tracker", "FILE", "tracker stream: serial capture or CSV log t,x,y,z[,status]", ""},
      {"samples", "FILE", "paired static samples q1..q6,x,y,z (CSV) instead of --robot/--tracker", ""},
      {"ur-calibration", "FILE", "UR calibration.conf: start from the controller's calibration", ""},
      {"robot-model", "ur5|ur3|ur10|ur5e", "nominal geometry", "ur5"},
      {"tool", "X,Y,Z", "nominal retroreflector centre in the flange frame [m] (LM refines it)", "0,0,0.1695"},
      {"params", "full|paper", "full identifiable model, or the paper's six lengths", "full"},
      {"method", "abc+lm|gsa+lm|lm|abc|gsa|all", "solver; 'all' runs GSA, ABC and LM (Table 1)", "abc+lm"},
      {"robust", "", "Huber loss in LM (a few bad tracker points do not drag the fit)", ""},
      {"seed", "N", "seed of the train/test split and of ABC/GSA", "1"},
      {"split", "FRACTION", "share of samples used for training", "0.7"},
      {"out", "FILE", "calibration result (robot-calibration/1 JSON)", "result.json"},
      {"ur-deltas", "FILE", "also write the model as UR calibration.conf [mounting] deltas", ""},
      {"report", "DIR", "write an HTML report with figures into DIR", ""},
      {"quiet", "", "no progress on stderr", ""},
  };
  Options options;
  const int parsed = parse_options("calibrate",
                                   "Estimates the robot geometry and the base -> tracker transform from tracker\n"
                                   "measurements, prints the paper-style tables and writes the result.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;

  // --- options
  CalibrateSettings settings;
  std::string problem = settings_from_options(options, &settings);
  if (!problem.empty()) {
    error("calibrate", problem);
    return kExitUsage;
  }
  const bool progress_on = progress_enabled(options);

  // --- start geometry and data
  RobotModel start = nominal_model(settings.robot);
  start.tool_m = settings.tool_m;
  if (!options.get("ur-calibration").empty()) {
    UrCalibrationDeltas deltas;
    const textio::ParseResult r = textio::read_ur_calibration_conf(options.get("ur-calibration"), &deltas);
    if (!r.ok) {
      error("calibrate", r.message);
      return kExitBadInput;
    }
    (void)apply_ur_deltas(nominal_model(settings.robot), deltas, &start);
    start.tool_m = settings.tool_m;
  }
  static CliDataset dataset;  // static: 8192 samples; emptied for each call (tests run several in one process)
  dataset.clear();
  InputFacts facts;
  const int load = load_dataset(options, settings, progress_on, &dataset, &facts);
  if (load != kExitOk) return load;
  CalibrationOptions job;
  job.method = method_from_name(settings.method);
  job.params = settings.paper_params ? CalibrationParams::paper : CalibrationParams::full;
  job.train_fraction = settings.train_fraction;
  job.seed = settings.seed;
  job.robust = options.given("robust");
  const std::size_t minimum = calibration_minimum_samples(job.params);
  if (dataset.size() < minimum) {
    error("calibrate", "only " + std::to_string(dataset.size()) + " static samples; at least " +
                           std::to_string(minimum) + " are needed to identify the parameters");
    return kExitBadInput;
  }
  const std::size_t train_count = dataset.train_count_for(settings.train_fraction);
  if (train_count == 0 || train_count == dataset.size()) {
    error("calibrate", "--split " + options.get("split") + " leaves no training or no test sample");
    return kExitUsage;
  }

  // --- the job: split, baseline, solvers (lib's calibrate())
  static CliWorkspace workspace;
  static CalibrationResult result;
  JobObserver observer(progress_on);
  const Status status = calibrate(start, &dataset, job, &workspace, &result, &observer);
  if (result.step == CalibrationStep::baseline) {
    error("calibrate", std::string("cannot fit the tracker frame: ") + status_message(status) +
                           (status == Status::degenerate_geometry ? " (are all samples at one pose?)" : ""));
    return kExitBadInput;
  }
  if (status != Status::ok) {
    const CalibrationStep step = result.step;
    const char* what = step == CalibrationStep::abc ? "ABC" : step == CalibrationStep::gsa ? "GSA"
                       : step == CalibrationStep::lm ? "LM" : calibration_step_name(step);
    error("calibrate", std::string(what) + " failed: " + status_message(status));
    return kExitFailure;
  }
  std::vector<std::string> info = facts.info_lines;
  info.push_back("samples: " + std::to_string(dataset.size()) + " (train " + std::to_string(dataset.train().size()) +
                 ", test " + std::to_string(dataset.test().size()) + ")");
  const CalibrationBaseline& uncalibrated = result.baseline;
  const CalibrationStage& final_stage = result.stages[result.stage_count - 1];
  const std::string final_method = result.stage_name(result.stage_count - 1);
  const bool final_is_lm = final_stage.solver == CalibrationSolver::lm;

  // --- tables and facts
  report::ReportData data;
  data.title = "hivecal calibration: " + std::string(robot_type_name(settings.robot));
  data.info_lines = info;
  data.methods.push_back(method_row("uncalibrated", options.get("ur-calibration").empty() ? "nominal" : "controller",
                                    uncalibrated.train, uncalibrated.test, 0.0, 0));
  for (std::size_t k = 0; k < result.stage_count; ++k) data.methods.push_back(stage_row(result, k, observer.seconds[k]));
  data.uncalibrated = accuracy_report(uncalibrated.model, uncalibrated.base_to_tracker, dataset);
  data.calibrated = accuracy_report(final_stage.model, final_stage.base_to_tracker, dataset);
  for (std::size_t k = 0; k < result.stage_count; ++k) {
    data.convergence.push_back({result.stage_name(k), trace_values(result.stages[k].trace_m)});
  }
  for (const Sample& s : dataset.test()) {
    data.test_measured_m.push_back(s.point_m);
    data.test_uncalibrated_m.push_back(uncalibrated.base_to_tracker.apply(fk_tool_point(uncalibrated.model, s.q_rad)));
    data.test_calibrated_m.push_back(final_stage.base_to_tracker.apply(fk_tool_point(final_stage.model, s.q_rad)));
  }
  if (final_is_lm) {
    for (const std::string& line : identifiability_lines(result.lm)) data.info_lines.push_back(line);
  }
  data.parameter_lines = parameter_lines(final_stage, final_is_lm ? &result.lm : nullptr, start);

  for (const std::string& line : data.info_lines) std::printf("%s\n", line.c_str());
  std::printf("\n%s", report::format_tables_text(data).c_str());
  std::printf("\nCalibrated parameters (%s):\n", final_method.c_str());
  for (const std::string& line : data.parameter_lines) std::printf("  %s\n", line.c_str());

  // --- outputs
  textio::CalibrationFile file;
  file.robot = settings.robot;
  file.model = final_stage.model;
  file.base_to_tracker = final_stage.base_to_tracker;
  file.has_metrics = true;
  file.metrics = data.calibrated;
  const UrCalibrationDeltas deltas = ur_deltas_between(nominal_model(settings.robot), final_stage.model);
  const std::string json = textio::format_calibration_json(file, [&](textio::JsonWriter& w) {
    w.key("method").value(final_method);
    w.key("params").value(settings.paper_params ? "paper" : "full");
    w.key("seed").value(static_cast<long long>(settings.seed));
    w.key("split").value(settings.train_fraction);
    w.key("uncalibrated_metrics").begin_object();
    w.key("train");
    textio::write_error_stats(w, data.uncalibrated.train);
    w.key("test");
    textio::write_error_stats(w, data.uncalibrated.test);
    w.end_object();
    write_stage_list(w, data.methods);
    if (final_is_lm) write_lm_details(w, result.lm);
    write_ur_deltas(w, deltas);
    write_input_facts(w, facts);
  });
  std::string write_error;
  if (!textio::write_file_atomically(options.get("out"), json, &write_error)) {
    error("calibrate", write_error);
    return kExitOutputError;
  }
  std::printf("\nresult: %s\n", options.get("out").c_str());
  if (!options.get("ur-deltas").empty()) {
    if (!textio::write_file_atomically(options.get("ur-deltas"), textio::format_ur_calibration_conf(deltas), &write_error)) {
      error("calibrate", write_error);
      return kExitOutputError;
    }
    std::printf("UR deltas: %s\n", options.get("ur-deltas").c_str());
  }
  if (!options.get("report").empty()) {
    if (!report::write_html_report(options.get("report"), data, &write_error)) {
      error("calibrate", write_error);
      return kExitOutputError;
    }
    std::printf("report: %s/index.html\n", options.get("report").c_str());
  }
  return kExitOk;
}

}  // namespace hivecal::cli
