// hivecal calibrate: inputs (paired samples, serial captures or CSV logs) -> dataset ->
// lib's calibrate() (ABC / GSA / Levenberg-Marquardt) -> tables, result JSON, UR deltas and
// HTML report. The settings, the renderers and the result file are in calibrate_*.cpp.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/calibration.hpp"
#include "commands/calibrate_parts.hpp"
#include "commands/commands.hpp"
#include "commands/fit_checks.hpp"
#include "commands/host_storage.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "report/report.hpp"
#include "streams/session.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::cli {
namespace {

constexpr std::size_t kTraceCapacity = 1024;

/// One run's storage on the heap (nothing kept between runs; tests run several in one process):
/// the dataset, lib's result (~5 KB) and the job's workspace, shared by the job and --cv (exact
/// double paper-6 terms for any arm's link lengths and joint trig storage, ~450 B per sample).
struct JobMemory {
  CliDataset dataset;
  Run job;
  HostWorkspace<kTraceCapacity> workspace;
  CalibrationResult cv_scratch;  ///< each fold's result
};

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Wall time per part of the command (--profile), in the order first seen; a part seen again
/// (a stage or w-test of the job's next run) adds up and counts its passes.
class Profile {
 public:
  void add(const std::string& part, double seconds) {
    for (Part& p : parts_) {
      if (p.name == part) {
        p.seconds += seconds;
        ++p.passes;
        return;
      }
    }
    parts_.push_back(Part{part, seconds, 1});
  }
  void print(std::FILE* out, double total_seconds) const {
    std::fprintf(out, "profile: wall time [s] of the command, %.3f in all\n", total_seconds);
    double listed = 0.0;
    for (const Part& p : parts_) {
      std::fprintf(out, "  %-40s %8.3f", p.name.c_str(), p.seconds);
      if (p.passes > 1) std::fprintf(out, "  (%d passes)", p.passes);
      std::fprintf(out, "\n");
      listed += p.seconds;
    }
    std::fprintf(out, "  %-40s %8.3f\n", "other (options, start geometry, memory)", total_seconds - listed);
  }

 private:
  struct Part {
    std::string name;
    double seconds;
    int passes;
  };
  std::vector<Part> parts_;
};

/// What --profile calls a phase of the job outside its stages.
const char* phase_label(CalibrationPhase phase) {
  switch (phase) {
    case CalibrationPhase::screen: return "job: screen of the start geometry";
    case CalibrationPhase::baseline: return "job: baseline fit";
    case CalibrationPhase::blunder_test: return "job: blunder search (w-tests, refits)";
  }
  return "job: phase";
}

/// Times the stages and the job's phases (lib takes no time) and prints one progress line per
/// iteration on stderr, overwritten in place.
class JobObserver final : public CalibrationObserver {
 public:
  explicit JobObserver(bool enabled, Profile* profile = nullptr) : enabled_(enabled), profile_(profile) {}
  ~JobObserver() { end_line(); }
  void on_phase(CalibrationPhase phase, bool ended) override {
    if (!ended) {
      phase_start_ = Clock::now();
    } else {
      add(phase_label(phase), seconds_since(phase_start_));
    }
  }
  void on_stage_begin(std::size_t, CalibrationSolver solver) override {
    label_ = calibration_solver_name(solver);
    start_ = Clock::now();
  }
  void on_stage_end(std::size_t index, const CalibrationStage& stage) override {
    seconds[index] = seconds_since(start_);
    add(std::string("job: ") + calibration_stage_name(stage, nullptr) + " stage", seconds[index]);
    end_line();
  }
  /// Wall time of the phases and stages reported so far [s].
  double timed_seconds() const { return timed_s_; }
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
  void add(const std::string& part, double part_s) {
    timed_s_ += part_s;
    if (profile_ != nullptr) profile_->add(part, part_s);
  }
  void end_line() {
    if (enabled_ && printed_) std::fprintf(stderr, "\n");
    printed_ = false;
  }
  bool enabled_;
  Profile* profile_;  // null: no --profile
  double timed_s_ = 0.0;
  const char* label_ = "";
  bool printed_ = false;
  Clock::time_point start_;
  Clock::time_point phase_start_;
};

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
    error = outputs->add_folder(options.get("report"), "--report", {report::kReportPageName}, &ids->report);
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

// --- run (the computation: lib's calibrate()) ---------------------------------------------------

/// --cv after the job (whose messages name the failing step), then the dataset put back as
/// the job left it (the same set aside and seeded split) for the tables.
Error cross_validation(const CalibrateSettings& settings, const RobotModel& start, const CalibrationOptions& job,
                       JobMemory* memory) {
  CliDataset* dataset = &memory->dataset;
  Run* run = &memory->job;
  auto& workspace = memory->workspace.for_samples(dataset->size());
  JobObserver quiet(false);
  const Status status = cross_validate(start, dataset, job, settings.cv_folds == 1 ? 0 : settings.cv_folds, &workspace,
                                       &memory->cv_scratch, &run->cv, &quiet);
  // The samples each fold held out, drawn again as cross_validate drew them: what it set aside
  // (left in the dataset), then split_fold's seeded order.
  std::vector<std::uint32_t> cv_aside;
  for (const Sample& s : dataset->set_aside()) cv_aside.push_back(s.index);
  run->cv_held_out.assign(status == Status::ok ? run->cv.fold_count : 0, {});
  for (std::size_t f = 0; f < run->cv_held_out.size(); ++f) {
    dataset->set_aside(Span<const std::uint32_t>(cv_aside.data(), cv_aside.size()));
    if (dataset->split_fold(f, run->cv.fold_count, job.seed) != Status::ok) break;
    for (const Sample& s : dataset->test()) run->cv_held_out[f].push_back(s.index);
    std::sort(run->cv_held_out[f].begin(), run->cv_held_out[f].end());
  }
  std::vector<std::uint32_t> aside;
  for (const CalibrationOutlier& o : run->result.outlier_list()) aside.push_back(o.index);
  dataset->set_aside(Span<const std::uint32_t>(aside.data(), aside.size()));
  if (dataset->split(job.train_fraction, job.seed) != Status::ok || status != Status::ok) {
    return Error::failure(std::string("cross-validation failed: ") + status_message(status));
  }
  return Error{};
}

Error run(const CalibrateSettings& settings, const RobotModel& start, const streams::SessionFacts& facts,
          JobMemory* memory, Profile* profile) {
  CliDataset* dataset = &memory->dataset;
  Run* run = &memory->job;
  CalibrationOptions job;
  job.method = settings.method;
  job.params = settings.paper_params ? CalibrationParams::paper : CalibrationParams::full;
  job.train_fraction = settings.train_fraction;
  job.seed = settings.seed;
  job.robust = settings.robust;
  job.keep_outliers = settings.keep_outliers;
  job.base_known = settings.controller_tcp;  // known_base_to_tracker: the identity
  job.tool_known = settings.controller_tcp;  // the start model's tool points: --tool and the orientation's lever
  job.detect_controller_frames = settings.detect_controller_frames;
  const double stated_m = settings.orientation.position_sigma_m;
  const double joint_m = joint_point_noise_m(settings, start, facts, dataset->samples());
  // The frames test's noise, over every pose (the split comes later; the report's noise line
  // takes the training poses).
  job.measurement_sigma_m = std::sqrt(stated_m * stated_m + joint_m * joint_m);
  job.significance_t = settings.significance_t;
  job.significance_every_set = settings.significance_every_set;
  job.population_subset = settings.population_subset;
  job.lm.joint_sigma_rad = settings.joint_sigma_rad;
  job.lm.position_sigma_m = settings.orientation.position_sigma_m;
  job.blunder_test.tracker_sigma_m = settings.orientation.position_sigma_m;
  job.prior = settings.prior;
  job.compliance.enabled = settings.compliance;
  if (settings.compliance) job.compliance.model = settings.compliance_model;
  auto& workspace = memory->workspace.for_samples(dataset->size());
  JobObserver observer(settings.progress, profile);
  run->target_count = target_count(dataset->samples());
  run->options = job;
  const Clock::time_point job_start = Clock::now();
  const Status status = hivecal::calibrate(start, dataset, job, &workspace, &run->result, &observer);
  profile->add("job: the rest (split, outlier lists)", seconds_since(job_start) - observer.timed_seconds());
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
  if (!run->has_cv) return Error{};
  const Clock::time_point cv_start = Clock::now();
  // The frames the job chose: the cross-validation's own job runs once, not the test again.
  const Error cv = cross_validation(settings, start, options_with_chosen_frames(job, run->result), memory);
  profile->add("cross-validation", seconds_since(cv_start));
  return cv;
}

// --- write ------------------------------------------------------------------------------------

/// Stages every output, then commits them together: all or nothing.
Error write_outputs(const Options& options, const CalibrateSettings& settings, const report::ReportData& data,
                    const streams::SessionFacts& facts, const Run& run, const std::vector<std::string>& warnings,
                    port::OutputSet* outputs, const OutputIds& ids) {
  const CalibrationStage& final_stage = run.final_stage();
  Error error = outputs->stage_text(ids.result, "", calibration_result_json(settings, data, facts, run, warnings));
  if (error.ok() && !options.get("ur-deltas").empty()) {
    const UrCalibrationDeltas deltas = textio::ur_deltas_in_ur_table(settings.robot.model, final_stage.model);
    error = outputs->stage_text(ids.ur_deltas, "", textio::format_ur_calibration_conf(deltas));
  }
  if (error.ok() && !options.get("report").empty()) {
    error = outputs->stage_text(ids.report, report::kReportPageName, report::render_html(data));
  }
  return error.ok() ? outputs->commit() : error;
}

/// The training poses of the run against the parameters its model has (fit_checks.hpp): the
/// fit's free rigid parameters (the set of --params, less the frames it knew) over a spread of
/// poses with the input's targets, and the other targets' tool points when it fitted them.
PoseSpan pose_span(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset,
                   const streams::SessionFacts& facts, const Run& run) {
  const CalibrationOptions chosen = options_with_chosen_frames(run.options, run.result);
  ParamMask free_mask = lm_param_mask(settings.paper_params ? LmParamSet::link_lengths : LmParamSet::full, 0, start);
  for (int axis = 0; axis < 3; ++axis) {
    const ParamMask base =
        param_bit(base_rotation_param_index(start, axis)) | param_bit(base_translation_param_index(start, axis));
    const ParamMask tool = param_bit(tool_param_index(start, axis));
    if (settings.paper_params && !chosen.tool_known) free_mask |= tool;  // the paper's set with the tool fitted
    if (chosen.base_known) free_mask &= ~base;
    if (chosen.tool_known) free_mask &= ~tool;
  }
  PoseSpan span;
  const Span<const Sample> train = dataset.train();
  span.poses = distinct_configurations(train);
  const std::size_t points = distinct_points(train);
  if (span.poses >= kDistinctPointLimit || points >= kDistinctPointLimit) return span;  // plenty: no parameters asked
  // A measured orientation's three points of a pose are a rigid triangle: 6 numbers, not 9.
  span.coordinates = 3 * points - (facts.orientation.poses > 0 ? std::min(3 * span.poses, 3 * points) : 0);
  span.parameters =
      model_parameter_count(start, free_mask, run.target_count) + (chosen.tool_known ? 0 : 3 * (run.target_count - 1));
  return span;
}

/// `*warnings`: the fit's plausibility warnings (fit_checks.hpp), printed on stderr; the
/// outputs are written all the same.
Error calibrate(const Options& options, std::vector<std::string>* warnings) {
  if (options.given("fit")) return calibrate_registration(options, warnings);
  const Clock::time_point command_start = Clock::now();
  Profile profile;
  CalibrateSettings settings;
  Error error = calibrate_settings_from_options(options, &settings);
  if (error.ok() && options.given("ur-deltas")) {
    error = textio::require_ur_joints(settings.robot.model, settings.robot.robot, "--ur-deltas (calibration.conf)");
  }
  port::OutputSet outputs;
  OutputIds ids;
  if (error.ok()) error = declare_outputs(options, &outputs, &ids);
  RobotModel start;
  if (error.ok()) error = start_geometry(options, settings, &start);
  const auto memory = std::make_unique<JobMemory>();
  CliDataset& dataset = memory->dataset;
  Run& job = memory->job;
  streams::SessionFacts facts;
  PointFates fates;
  Clock::time_point part_start = Clock::now();
  if (error.ok()) error = load_dataset(options, settings, &dataset, &facts, &fates);
  profile.add("read the input", seconds_since(part_start));
  if (error.ok()) textio::start_orientation_targets(facts.orientation, &start);
  job.from_controller = !options.get("ur-calibration").empty();
  job.link_length_count = link_length_set(start).count;
  if (error.ok()) error = run(settings, start, facts, memory.get(), &profile);
  if (!error.ok()) return error;
  part_start = Clock::now();
  report::ReportData data = present_calibration(settings, start, dataset, facts, job);
  const double tables_s = seconds_since(part_start);
  part_start = Clock::now();
  add_uncertainty(settings, start, dataset, &job, &data);
  profile.add("uncertainty: covariance and domain", seconds_since(part_start));
  part_start = Clock::now();
  if (facts.has_stream) data.timeline = fates.timeline(120);
  // Any output on stdout (the result, or --ur-deltas -) keeps the tables off it.
  const bool result_on_stdout = options.get("out") == "-" || options.get("ur-deltas") == "-";
  std::FILE* terminal = result_on_stdout ? stderr : stdout;
  print_calibration_tables(terminal, data, facts, job);
  const PoseSpan span = pose_span(settings, start, dataset, facts, job);
  *warnings = fit_warnings(job.result, settings.bounds, data.parameters, &span);
  const std::string orientation =
      constant_orientation_warning(facts.orientation.orientation_constant, data.fit_sigma_m, data.noise_sigma_m);
  if (!orientation.empty()) warnings->push_back(orientation);
  // An implausible fit of a built-in UR: another type's nominal geometry may explain the data
  // (not on poses too few for the model, where any table fits about as well).
  const bool spanned = span.parameters == 0 || span.coordinates > static_cast<std::size_t>(span.parameters);
  const std::string other_arm =
      warnings->empty() || !spanned ? "" : other_arm_hint(settings.robot.robot, start, dataset.train());
  if (!other_arm.empty()) warnings->push_back(other_arm);
  profile.add("final w-test, accuracy and tables", tables_s + seconds_since(part_start));
  part_start = Clock::now();
  error = write_outputs(options, settings, data, facts, job, *warnings, &outputs, ids);
  profile.add("write the outputs", seconds_since(part_start));
  if (!error.ok()) return error;
  if (settings.profile) profile.print(stderr, seconds_since(command_start));
  if (!result_on_stdout) std::fprintf(terminal, "\nresult: %s\n", options.get("out").c_str());
  if (!options.get("ur-deltas").empty()) std::fprintf(terminal, "UR deltas: %s\n", options.get("ur-deltas").c_str());
  if (!options.get("report").empty()) std::fprintf(terminal, "report: %s/index.html\n", options.get("report").c_str());
  for (const std::string& warning : *warnings) cli::error(kCalibrateCommand, "warning: " + warning);
  return Error{};
}

}  // namespace

Error load_dataset(const Options& options, const CalibrateSettings& settings, CliDataset* dataset,
                   streams::SessionFacts* facts, PointFates* fates) {
  RobotModel arm = settings.robot.model;
  arm.tool_m = settings.tool_m;  // for tool speeds and the joints' noise only
  streams::SessionConfig config = sample_session_config(settings, arm);
  config.observer = fates;
  config.progress = settings.progress;
  config.log_options.arm_name = settings.robot.robot;
  Error error = streams::joint_names_option(options.get("joint-names"), &config.log_options);
  if (!error.ok()) return error;
  error = streams::load_session({options.get("samples"), options.get("robot"), options.get("tracker")}, config, dataset,
                                facts);
  if (!error.ok()) return error;
  // No floor on the sample count: the identifiability analysis decides what the samples determine.
  // The job splits; fewer than 3 training poses cannot even place the tracker frame.
  const std::size_t train_poses = dataset->train_count_for(settings.train_fraction);
  if (train_poses < 3 && train_poses < dataset->pose_count()) {
    return Error::usage("--split " + options.get("split") + " leaves " + std::to_string(train_poses) +
                        " training pose(s) of " + std::to_string(dataset->pose_count()) +
                        "; the tracker frame needs at least 3");
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
  if (settings.cv_folds == 0 || dataset->pose_count() == 0) return Error{};  // no folds to size
  // Each fold trains on the others (DatasetBase::split_fold): the largest fold held out leaves the fewest.
  const std::size_t poses = dataset->pose_count();
  const std::size_t folds = settings.cv_folds == 1 ? poses : settings.cv_folds;
  const std::size_t fold_train_poses = poses - (poses + folds - 1) / folds;
  if (fold_train_poses < 3) {
    return Error::usage("--cv " + options.get("cv") + " on " + std::to_string(poses) + units + ": a fold trains on " +
                        std::to_string(fold_train_poses) + " of them, and a fit needs at least 3 (as --split's " +
                        "training set): too few" + units + " for " + std::to_string(folds) + " folds; measure more" +
                        units + (folds < poses ? ", or hold out fewer at a time (more folds; --cv loo: one)" : ""));
  }
  return Error{};
}

int calibrate_main(int argc, char** argv) {
  Options options;
  const int parsed = parse_options(kCalibrateCommand,
                                   "Estimates the robot geometry and the base -> tracker transform from tracker\n"
                                   "measurements, prints the paper-style tables and writes the result.",
                                   calibrate_option_specs(), argc, argv, &options);
  if (parsed >= 0) return parsed;
  std::vector<std::string> warnings;
  const int code = exit_with(kCalibrateCommand, calibrate(options, &warnings));
  return code == kExitOk && !warnings.empty() ? kExitWarnings : code;
}

}  // namespace hivecal::cli