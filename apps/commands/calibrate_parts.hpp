// The calibrate command's parts (apps/commands/calibrate*.cpp): its settings from the command
// line, the run's record, and the renderers of that record (console tables and report data,
// result.json). The command itself (calibrate.cpp) is parse -> load -> lib's calibrate() ->
// present -> write.
#pragma once

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "cli/options.hpp"
#include "commands/fit_checks.hpp"
#include "commands/host_storage.hpp"
#include "commands/sample_reader.hpp"
#include "hivecal/calibration.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "record/result_json.hpp"
#include "report/report.hpp"
#include "streams/session.hpp"
#include "textio/csv.hpp"
#include "textio/robot_description.hpp"
#include "textio/delimited.hpp"

namespace hivecal::cli {

/// The command's dataset: as large as its input.
using CliDataset = HostDataset;

/// Validated command-line settings (the reader options' among them).
struct CalibrateSettings : SampleReaderSettings {
  textio::RobotDescription robot;  ///< --robot-model: built-in table or description file
  Vec3 tool_m =
      Vec3(0.0, 0.0, 0.1695);  ///< --tool (or the description file's): nominal tool point in the flange frame [m]
  std::string tool_note;       ///< where --tool-transform put the tool point (a console line), "" without it
  bool paper_params = false;   ///< --params paper
  CalibrationMethod method = CalibrationMethod::abc_lm;  ///< --method
  std::uint64_t seed = 1;                                ///< --seed
  double train_fraction = 0.7;                           ///< --split
  bool robust = false;                                   ///< --robust
  bool keep_outliers = false;                            ///< --keep-outliers
  double significance_t = kDefaultSignificance;          ///< --significance
  bool significance_every_set = false;                   ///< --significance T given: the geometry tested on any set
  std::size_t population_subset =
      kDefaultPopulationSubset;  ///< --population-subset: a hybrid's ABC/GSA samples (0: all) [-]
  std::size_t cv_folds = 0;      ///< --cv K; 1: leave-one-out (lib's folds = 0); 0: no cross-validation
  bool progress = false;         ///< progress lines on stderr
  bool profile = false;          ///< --profile: where the wall time went, on stderr
  FitBounds bounds;              ///< --max-change-mm, --max-change-deg
  bool compliance = false;       ///< --compliance: an LM+compliance stage after the rigid LM
  /// --compliance basis|masses: the terms (default_compliance_terms), unit gravity direction
  /// (--gravity) and, for masses, the arm's masses and the payload (--payload); zero coefficients.
  ComplianceModel compliance_model;
  bool controller_tcp = false;  ///< --controller-tcp: base (identity) and tool (--tool) known, not fitted
  /// --frames auto: the job tests the controller's frames when the fitted base is near the
  /// identity (CalibrationOptions::detect_controller_frames)
  bool detect_controller_frames = true;
  /// --prior, --dh-tolerance-mm, --dh-tolerance-mrad, --tool-tolerance-mm: the start model's
  /// tolerances as LM's prior (all 0 with --prior off) [m], [rad]
  LmPriorTolerances prior = kDefaultPriorTolerances;
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

/// What the job produced, with the CLI's stage timings.
struct Run {
  CalibrationResult result;                          ///< lib's result (~5 KB)
  double seconds[kMaxCalibrationStages] = {};        ///< wall time per stage [s]
  bool from_controller = false;                      ///< the start geometry is the controller's
  std::size_t link_length_count = kPaper6Dimension;  ///< lengths the population stages search [-]
  bool has_cv = false;                               ///< --cv ran: `cv` is meaningful
  CrossValidationResult cv;                          ///< per-fold held-out errors (~20 KB)
  /// Per fold of `cv`: the Sample::index of each sample it held out, increasing.
  std::vector<std::vector<std::uint32_t>> cv_held_out;
  int target_count = 1;                        ///< targets (reflectors) in the samples: the result's "tools" [-]
  CalibrationOptions options;                  ///< the job's options, as lib ran it
  record::CalibrationUncertainty uncertainty;  ///< the final parameters' covariance, the training poses' domain
  /// The job's answer (run() returns an error when no stage ran).
  const CalibrationStage& final_stage() const { return result.stages[result.stage_count - 1]; }
  /// Its name ("ABC+LM", ...).
  std::string final_method() const { return result.stage_name(result.stage_count - 1); }
  /// The LM details when the final stage is LM, else null.
  const LmResult* final_lm() const { return final_stage().solver == CalibrationSolver::lm ? &result.lm : nullptr; }
};

/// The options of `hivecal calibrate` (for --help and the parser).
const std::vector<OptionSpec>& calibrate_option_specs();

/// The command line into *settings; a usage error names the option and what it must be.
Error calibrate_settings_from_options(const Options& options, CalibrateSettings* settings);

/// The dataset of the command line's inputs (samples, or two streams), checked for the split
/// and --cv; `fates` sees each tracker point of streams.
Error load_dataset(const Options& options, const CalibrateSettings& settings, CliDataset* dataset,
                   streams::SessionFacts* facts, PointFates* fates);

/// `calibrate --fit base|frames --robot-model RESULT.json`: registers RESULT on the inputs
/// instead of calibrating (calibrate_register.cpp); *warnings as calibrate's.
Error calibrate_registration(const Options& options, std::vector<std::string>* warnings);

/// The joints' reading noise as noise of the tool point per axis over the poses of `samples`
/// (--joint-sigma-rad, else a rounding to their written resolution, through the arm); 0 when
/// it is negligible beside the tracker's stated noise [m].
double joint_point_noise_m(const CalibrateSettings& settings, const RobotModel& start,
                           const streams::SessionFacts& facts, Span<const Sample> samples);

/// The final parameters' covariance and the training poses' domain into run->uncertainty
/// (compute_uncertainty); its statement joins data->info_lines.
void add_uncertainty(const CalibrateSettings& settings, const RobotModel& start, const CliDataset& dataset, Run* run,
                     report::ReportData* data);

/// Tables and figures of a run, and the text of the terminal.
report::ReportData present_calibration(const CalibrateSettings& settings, const RobotModel& start,
                                       const CliDataset& dataset, const streams::SessionFacts& facts, const Run& run);

/// What held_out_ranges() counts: "lines of FILE" (paired samples) or "samples (numbered from 1
/// in the order extracted)".
std::string held_out_unit(const streams::SessionFacts& facts);
/// Samples `indices` (Sample::index) as ranges of what held_out_unit() counts: "2-4, 7, 9"
/// (the lines of a row that made several samples once).
std::string held_out_ranges(const streams::SessionFacts& facts, const std::vector<std::uint32_t>& indices);

/// The terminal text (on stdout, or on stderr when stdout carries the result).
void print_calibration_tables(std::FILE* out, const report::ReportData& data, const streams::SessionFacts& facts,
                              const Run& run);

/// The result file (robot-calibration/1 JSON) of a run. `warnings`: the fit's plausibility
/// warnings, a "warnings" array when there are any.
std::string calibration_result_json(const CalibrateSettings& settings, const report::ReportData& data,
                                    const streams::SessionFacts& facts, const Run& run,
                                    const std::vector<std::string>& warnings);

}  // namespace hivecal::cli
