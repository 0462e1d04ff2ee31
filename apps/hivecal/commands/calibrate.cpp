// hivecal calibrate: inputs (paired samples, serial captures or CSV logs) -> dataset ->
// ABC / GSA / Levenberg-Marquardt -> tables, result JSON, UR deltas and HTML report.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/commands/commands.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/solve/population_stage.hpp"
#include "report/report.hpp"
#include "streams/session.hpp"
#include "textio/calibration_json.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::cli {
namespace {

constexpr const char* kCommand = "calibrate";
constexpr std::size_t kTraceCapacity = 1024;

/// Dataset capacity of the command-line tool (samples).
constexpr std::size_t kCliDatasetCapacity = 8192;
using CliDataset = Dataset<kCliDatasetCapacity>;

/// Validated command-line settings.
struct CalibrateSettings {
  RobotType robot = RobotType::ur5;  ///< --robot-model
  Vec3 tool_m = Vec3(0.0, 0.0, 0.1695);  ///< --tool: nominal tool point in the flange frame [m]
  bool paper_params = false;         ///< --params paper
  std::string method = "abc+lm";     ///< --method
  std::uint64_t seed = 1;            ///< --seed
  double train_fraction = 0.7;       ///< --split
  bool robust = false;               ///< --robust
  bool progress = false;             ///< progress lines on stderr
};

/// What one solver stage produced.
struct Stage {
  std::string method;                ///< "ABC", "GSA", "LM", ...
  std::string params;                ///< "paper-6" or "full"
  RobotModel model;                  ///< calibrated geometry
  RigidTransform base_to_tracker;    ///< fitted or estimated base -> tracker
  std::vector<double> trace_m;       ///< best cost per iteration [m]
  double seconds = 0.0;              ///< wall time [s]
  long long evaluations = 0;         ///< cost evaluations (LM: iterations)
  bool is_lm = false;                ///< lm below is meaningful
  LmResult lm;                       ///< LM details (identifiability, sigma)
};

/// Prints one progress line per iteration on stderr, overwritten in place.
class Progress final : public ProgressObserver, public LmObserver {
 public:
  Progress(bool enabled, std::string label) : enabled_(enabled), label_(std::move(label)) {}
  ~Progress() {
    if (enabled_ && printed_) std::fprintf(stderr, "\n");
  }
  void on_iteration(const SolverProgress& p) override {
    print("iteration %zu/%zu, best MAE %.2f um", p.iteration, p.iteration_count, p.best_cost * 1e6);
  }
  bool on_iteration(const LmIterationInfo& info) override {
    print("iteration %d, RMS %.2f um", info.iteration, info.rms_m * 1e6);
    return true;
  }

 private:
  template <typename... Args>
  void print(const char* format, Args... args) {
    if (!enabled_) return;
    std::fprintf(stderr, "\r[%s] ", label_.c_str());
    std::fprintf(stderr, format, args...);
    std::fflush(stderr);
    printed_ = true;
  }
  bool enabled_;
  std::string label_;
  bool printed_ = false;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<double> trace_values(const TraceBase& trace) {
  std::vector<double> v;
  for (double x : trace.values()) v.push_back(x);
  return v;
}

/// ABC or GSA on the paper's six lengths, base refitted per candidate.
Status run_population(bool use_abc, const RobotModel& start, Span<const Sample> train, std::uint64_t seed,
                      bool progress_on, Stage* stage) {
  static Paper6Cost<kCliDatasetCapacity> cost;
  static AbcSolver<150, kPaper6Dimension> abc;
  static GsaSolver<150, kPaper6Dimension> gsa;
  static Trace<kTraceCapacity> trace;
  trace.clear();
  Paper6StageResult result;
  Progress progress(progress_on, use_abc ? "ABC" : "GSA");
  const auto start_time = std::chrono::steady_clock::now();
  Status status = Status::ok;
  if (use_abc) {
    AbcOptions options;
    options.seed = seed;
    status = calibrate_paper6_abc(start, train, options, kPaper6DefaultHalfWidth_m, &cost, &abc, &result, &trace,
                                  &progress);
  } else {
    GsaOptions options;
    options.seed = seed;
    status = calibrate_paper6_gsa(start, train, options, kPaper6DefaultHalfWidth_m, &cost, &gsa, &result, &trace,
                                  &progress);
  }
  if (status != Status::ok) return status;
  stage->method = use_abc ? "ABC" : "GSA";
  stage->params = "paper-6";
  stage->seconds = seconds_since(start_time);
  stage->evaluations = static_cast<long long>(result.evaluations);
  stage->trace_m = trace_values(trace);
  stage->model = result.model;
  stage->base_to_tracker = result.base_to_tracker;
  return Status::ok;
}

/// Levenberg-Marquardt from a starting geometry.
Status run_lm(const RobotModel& start, const RigidTransform* start_base, Span<const Sample> train, bool paper_params,
              bool robust, bool progress_on, Stage* stage) {
  static LmWorkspace workspace;
  static JointTrig joint_trig_storage[kCliDatasetCapacity];
  workspace.joint_trig = joint_trig_storage;
  static Trace<kTraceCapacity> trace;
  trace.clear();
  LmOptions options;
  options.params = paper_params ? LmParamSet::paper6 : LmParamSet::full;
  options.loss = robust ? LmLoss::huber : LmLoss::squared;
  Progress progress(progress_on, "LM");
  const auto start_time = std::chrono::steady_clock::now();
  const Status status = calibrate_lm(start, start_base, train, options, &workspace, &stage->lm, &trace, &progress);
  if (status != Status::ok && status != Status::not_converged) return status;
  stage->method = "LM";
  stage->params = paper_params ? "paper-6" : "full";
  stage->is_lm = true;
  stage->seconds = seconds_since(start_time);
  stage->evaluations = stage->lm.iterations;
  stage->trace_m = trace_values(trace);
  stage->model = stage->lm.model;
  stage->base_to_tracker = stage->lm.base_to_tracker;
  return Status::ok;
}

report::MethodRow method_row(const Stage& stage, const DatasetBase& dataset) {
  report::MethodRow row;
  row.method = stage.method;
  row.parameters = stage.params;
  if (stage.is_lm) {
    row.parameters += " (" + std::to_string(stage.lm.identifiability.kept_count()) + " estimated)";
  }
  row.train = position_error_stats(stage.model, stage.base_to_tracker, dataset.train());
  row.test = position_error_stats(stage.model, stage.base_to_tracker, dataset.test());
  row.seconds = stage.seconds;
  row.evaluations = stage.evaluations;
  return row;
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

std::vector<std::string> parameter_lines(const Stage& stage, const RobotModel& start) {
  std::vector<std::string> lines;
  const ModelParams before = to_params(start);
  const ModelParams after = to_params(stage.model);
  char buf[160];
  for (int k = 0; k < kModelParamCount; ++k) {
    const bool estimated = stage.is_lm && mask_has(stage.lm.identifiability.kept_mask, k);
    const bool changed = after(k) != before(k);
    if (!estimated && !changed) continue;
    const bool angle = k < kDhParamCount && (k % kParamsPerJoint == 0 || k % kParamsPerJoint == 3);
    const double scale = angle ? 1e3 : 1e3;
    std::snprintf(buf, sizeof buf, "%-8s %+.9f %s  (change %+.4f %s%s)", full_param_name(k), after(k),
                  angle ? "rad" : "m", (after(k) - before(k)) * scale, angle ? "mrad" : "mm",
                  estimated ? (", sigma " + std::to_string(stage.lm.sigma(k) * scale) + (angle ? " mrad" : " mm")).c_str()
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

const std::vector<OptionSpec>& option_specs() {
  static const std::vector<OptionSpec> specs = {
      {"robot", "FILE|BAG", "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
      {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
      {"joint-names", "N1,..,N6", "joint names in ROS logs (rostopic, bag), joints 1..6 in order (default: the UR drivers')", ""},
      {"samples", "FILE", "paired static samples q1..q6,x,y,z (CSV; '-': stdin) instead of --robot/--tracker", ""},
      {"ur-calibration", "FILE", "UR calibration.conf: start from the controller's calibration", ""},
      {"robot-model", "NAME", std::string("nominal geometry: ") + robot_type_names(), "ur5"},
      {"tool", "X,Y,Z", "nominal retroreflector centre in the flange frame [m] (LM refines it)", "0,0,0.1695"},
      {"params", "full|paper", "full identifiable model, or the paper's six lengths", "full"},
      {"method", "abc+lm|gsa+lm|lm|abc|gsa|all", "solver; 'all' runs GSA, ABC and LM (Table 1)", "abc+lm"},
      {"robust", "", "Huber loss in LM (a few bad tracker points do not drag the fit)", ""},
      {"seed", "N", "seed of the train/test split and of ABC/GSA", "1"},
      {"split", "FRACTION", "share of samples used for training", "0.7"},
      {"out", "FILE", "calibration result (robot-calibration/1 JSON; '-': stdout)", "result.json"},
      {"ur-deltas", "FILE", "also write the model as UR calibration.conf [mounting] deltas", ""},
      {"report", "DIR", "write an HTML report with figures into DIR", ""},
      {"quiet", "", "no progress on stderr", ""},
  };
  return specs;
}

// --- parse ------------------------------------------------------------------------------------

Error settings_from_options(const Options& options, CalibrateSettings* settings) {
  Error error = robot_model_option(options, "robot-model", &settings->robot);
  if (error.ok()) error = vec3_option(options, "tool", &settings->tool_m);
  if (!error.ok()) return error;
  const std::string params = options.get("params");
  if (params != "full" && params != "paper") return Error::usage("--params must be 'full' or 'paper', not " + port::quoted(params));
  settings->paper_params = params == "paper";
  settings->method = options.get("method");
  const char* methods[] = {"abc+lm", "gsa+lm", "lm", "abc", "gsa", "all"};
  bool known = false;
  for (const char* m : methods) known = known || settings->method == m;
  if (!known) {
    return Error::usage("--method must be one of abc+lm, gsa+lm, lm, abc, gsa, all; not " + port::quoted(settings->method));
  }
  double seed = 0.0;
  if (!textio::parse_double(options.get("seed"), &seed) || seed < 0.0 || seed > 9.007199254740992e15 ||
      seed != static_cast<double>(static_cast<std::uint64_t>(seed))) {
    return Error::usage("--seed must be a non-negative integer");
  }
  settings->seed = static_cast<std::uint64_t>(seed);
  if (!textio::parse_double(options.get("split"), &settings->train_fraction) ||
      !(settings->train_fraction > 0.0 && settings->train_fraction < 1.0)) {
    return Error::usage("--split must be a fraction in (0, 1)");
  }
  const bool samples = !options.get("samples").empty();
  const bool streams = !options.get("robot").empty() || !options.get("tracker").empty();
  if (samples == streams) return Error::usage("give either --samples, or --robot and --tracker (see --help)");
  if (streams && (options.get("robot").empty() || options.get("tracker").empty())) {
    return Error::usage("--robot and --tracker go together");
  }
  settings->robust = options.given("robust");
  settings->progress = progress_enabled(options);
  return Error{};
}

/// Where the results go, declared (and checked) before the long work.
struct OutputIds {
  std::size_t result = 0;     ///< --out
  std::size_t ur_deltas = 0;  ///< --ur-deltas, when given
  std::size_t report = 0;     ///< --report, when given
};

Error declare_outputs(const Options& options, port::OutputSet* outputs, OutputIds* ids) {
  for (const char* input : {"samples", "robot", "tracker", "ur-calibration"}) {
    Error error = outputs->add_input(options.get(input), std::string("--") + input);
    if (!error.ok()) return error;
  }
  Error error = outputs->add_file(options.get("out"), "--out", &ids->result);
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
  *start = nominal_model(settings.robot);
  start->tool_m = settings.tool_m;
  if (options.get("ur-calibration").empty()) return Error{};
  UrCalibrationDeltas deltas;
  const port::Error r = textio::read_ur_calibration_conf(options.get("ur-calibration"), &deltas);
  if (!r.ok()) return r;
  (void)apply_ur_deltas(nominal_model(settings.robot), deltas, start);
  start->tool_m = settings.tool_m;
  return Error{};
}

/// The dataset, checked for size and split.
Error load_dataset(const Options& options, const CalibrateSettings& settings, CliDataset* dataset,
                   streams::SessionFacts* facts) {
  streams::SessionConfig config;
  config.speed_model = nominal_model(settings.robot);
  config.speed_model.tool_m = settings.tool_m;  // for tool speeds only
  config.progress = settings.progress;
  Error error = streams::joint_names_option(options.get("joint-names"), &config.log_options);
  if (!error.ok()) return error;
  error = streams::load_session({options.get("samples"), options.get("robot"), options.get("tracker")}, config,
                                      dataset, facts);
  if (!error.ok()) return error;
  const std::size_t minimum = settings.paper_params ? 12 : 24;
  if (dataset->size() < minimum) {
    return Error::input("only " + std::to_string(dataset->size()) + " static samples; at least " +
                        std::to_string(minimum) + " are needed to identify the parameters");
  }
  if (dataset->split(settings.train_fraction, settings.seed) != Status::ok || dataset->test().empty()) {
    return Error::usage("--split " + options.get("split") + " leaves no training or no test sample");
  }
  return Error{};
}

// --- run (the computation; the lib's calibration entry replaces its body) -------------------

Error run(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset, bool from_controller,
          Stage* uncalibrated_out, std::vector<Stage>* stages_out) {
  const bool progress_on = settings.progress;
  // --- uncalibrated row
  Stage uncalibrated;
  uncalibrated.method = "uncalibrated";
  uncalibrated.params = from_controller ? "controller" : "nominal";
  uncalibrated.model = start;
  Status status = fit_base_to_tracker(start, dataset.train(), &uncalibrated.base_to_tracker);
  if (status != Status::ok) {
    return Error::input(std::string("cannot fit the tracker frame: ") + status_message(status) +
                        (status == Status::degenerate_geometry ? " (are all samples at one pose?)" : ""));
  }

  // --- solvers
  std::vector<Stage> stages;
  auto fail = [&](const char* what, Status s) { return Error::failure(std::string(what) + " failed: " + status_message(s)); };
  const std::string& method = settings.method;
  const bool run_gsa = method == "gsa" || method == "gsa+lm" || method == "all";
  const bool run_abc = method == "abc" || method == "abc+lm" || method == "all";
  const bool run_lm_stage = method == "lm" || method == "abc+lm" || method == "gsa+lm" || method == "all";
  if (run_gsa) {
    Stage gsa;
    status = run_population(false, start, dataset.train(), settings.seed, progress_on, &gsa);
    if (status != Status::ok) return fail("GSA", status);
    stages.push_back(gsa);
  }
  if (run_abc) {
    Stage abc;
    status = run_population(true, start, dataset.train(), settings.seed, progress_on, &abc);
    if (status != Status::ok) return fail("ABC", status);
    stages.push_back(abc);
  }
  if (run_lm_stage) {
    // Hybrid: start LM where the population solver ended ('all' starts from the nominal model
    // so that its row stands on its own).
    const bool hybrid = method == "abc+lm" || method == "gsa+lm";
    const Stage* seed_stage = hybrid ? &stages.back() : nullptr;
    Stage lm;
    status = run_lm(seed_stage ? seed_stage->model : start, seed_stage ? &seed_stage->base_to_tracker : nullptr,
                    dataset.train(), settings.paper_params, settings.robust, progress_on, &lm);
    if (status != Status::ok) return fail("LM", status);
    if (hybrid) lm.method = seed_stage->method + "+LM";
    stages.push_back(lm);
  }
  *uncalibrated_out = uncalibrated;
  *stages_out = stages;
  return Error{};
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

/// Tables and figures of a run, and the text of the terminal.
report::ReportData present(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset,
                           const streams::SessionFacts& facts, const Stage& uncalibrated,
                           const std::vector<Stage>& stages) {
  const Stage& final_stage = stages.back();
  report::ReportData data;
  data.title = "hivecal calibration: " + std::string(robot_type_name(settings.robot));
  data.info_lines = facts.info_lines;
  data.info_lines.push_back("samples: " + std::to_string(dataset.size()) + " (train " +
                            std::to_string(dataset.train().size()) + ", test " + std::to_string(dataset.test().size()) +
                            ")");
  data.methods.push_back(method_row(uncalibrated, dataset));
  for (const Stage& stage : stages) data.methods.push_back(method_row(stage, dataset));
  data.uncalibrated = accuracy_report(uncalibrated.model, uncalibrated.base_to_tracker, dataset);
  data.calibrated = accuracy_report(final_stage.model, final_stage.base_to_tracker, dataset);
  for (const Stage& stage : stages) data.convergence.push_back({stage.method, stage.trace_m});
  for (const Sample& s : dataset.test()) {
    data.test_measured_m.push_back(s.point_m);
    data.test_uncalibrated_m.push_back(uncalibrated.base_to_tracker.apply(fk_tool_point(uncalibrated.model, s.q_rad)));
    data.test_calibrated_m.push_back(final_stage.base_to_tracker.apply(fk_tool_point(final_stage.model, s.q_rad)));
  }
  if (final_stage.is_lm) {
    for (const std::string& line : identifiability_lines(final_stage.lm)) data.info_lines.push_back(line);
  }
  data.parameter_lines = parameter_lines(final_stage, start);
  return data;
}

/// The terminal text (on stdout, or on stderr when stdout carries the result).
void print_tables(std::FILE* out, const report::ReportData& data, const Stage& final_stage) {
  for (const std::string& line : data.info_lines) std::fprintf(out, "%s\n", line.c_str());
  std::fprintf(out, "\n%s", report::format_tables_text(data).c_str());
  std::fprintf(out, "\nCalibrated parameters (%s):\n", final_stage.method.c_str());
  for (const std::string& line : data.parameter_lines) std::fprintf(out, "  %s\n", line.c_str());
}

std::string result_json(const CalibrateSettings& settings, const report::ReportData& data,
                        const streams::SessionFacts& facts, const Stage& final_stage) {
  textio::CalibrationFile file;
  file.robot = settings.robot;
  file.model = final_stage.model;
  file.base_to_tracker = final_stage.base_to_tracker;
  file.has_metrics = true;
  file.metrics = data.calibrated;
  const UrCalibrationDeltas deltas = ur_deltas_between(nominal_model(settings.robot), final_stage.model);
  return textio::format_calibration_json(file, [&](textio::JsonWriter& w) {
    w.key("method").value(final_stage.method);
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
    if (final_stage.is_lm) write_lm_details(w, final_stage.lm);
    write_ur_deltas(w, deltas);
    write_input_facts(w, facts);
  });
}

// --- write ------------------------------------------------------------------------------------

/// Stages every output, then commits them together: all or nothing.
Error write_outputs(const Options& options, const CalibrateSettings& settings, const report::ReportData& data,
                    const streams::SessionFacts& facts, const Stage& final_stage, port::OutputSet* outputs,
                    const OutputIds& ids) {
  Error error = outputs->stage_text(ids.result, "", result_json(settings, data, facts, final_stage));
  if (error.ok() && !options.get("ur-deltas").empty()) {
    const UrCalibrationDeltas deltas = ur_deltas_between(nominal_model(settings.robot), final_stage.model);
    error = outputs->stage_text(ids.ur_deltas, "", textio::format_ur_calibration_conf(deltas));
  }
  if (error.ok() && !options.get("report").empty()) {
    error = outputs->stage_text(ids.report, "index.html", report::render_html(data));
  }
  return error.ok() ? outputs->commit() : error;
}

Error calibrate(const Options& options) {
  CalibrateSettings settings;
  Error error = settings_from_options(options, &settings);
  port::OutputSet outputs;
  OutputIds ids;
  if (error.ok()) error = declare_outputs(options, &outputs, &ids);
  RobotModel start;
  if (error.ok()) error = start_geometry(options, settings, &start);
  static CliDataset dataset;  // static: 8192 samples; emptied for each call (tests run several in one process)
  dataset.clear();
  streams::SessionFacts facts;
  if (error.ok()) error = load_dataset(options, settings, &dataset, &facts);
  Stage uncalibrated;
  std::vector<Stage> stages;
  if (error.ok()) error = run(settings, start, dataset, !options.get("ur-calibration").empty(), &uncalibrated, &stages);
  if (!error.ok()) return error;
  const report::ReportData data = present(settings, start, dataset, facts, uncalibrated, stages);
  const bool result_on_stdout = options.get("out") == "-";
  std::FILE* terminal = result_on_stdout ? stderr : stdout;
  print_tables(terminal, data, stages.back());
  error = write_outputs(options, settings, data, facts, stages.back(), &outputs, ids);
  if (!error.ok()) return error;
  if (!result_on_stdout) std::fprintf(terminal, "\nresult: %s\n", options.get("out").c_str());
  if (!options.get("ur-deltas").empty()) std::fprintf(terminal, "UR deltas: %s\n", options.get("ur-deltas").c_str());
  if (!options.get("report").empty()) std::fprintf(terminal, "report: %s/index.html\n", options.get("report").c_str());
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
  return exit_with(kCommand, calibrate(options));
}

}  // namespace hivecal::cli
