// The calibration job, one entry for the command-line tool, the firmware and the tests:
//   split -> baseline (start geometry, base fitted on the training samples) -> the solver
//   stages of CalibrationOptions::method (ABC / GSA on the link lengths, then or instead
//   Levenberg-Marquardt on the full model) -> train/test errors of every stage.
// Like ruckig's Ruckig / InputParameter / Result: options in, a caller-sized workspace, one
// result struct out. No heap, no clock: a caller that wants stage timings takes them in its
// CalibrationObserver. Method and figures: docs/architecture.md, "The calibration job".
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/solve/population_stage.hpp"

namespace hivecal {

/// Which solvers run, in order.
enum class CalibrationMethod : std::uint8_t {
  lm,      ///< Levenberg-Marquardt from the start geometry
  abc,     ///< ABC on the link lengths (for UR the paper's six)
  gsa,     ///< GSA on the link lengths (for UR the paper's six)
  abc_lm,  ///< ABC, then LM from its geometry and base (the hybrid)
  gsa_lm,  ///< GSA, then LM from its geometry and base
  all,     ///< the paper's Table 1: GSA, ABC and LM, each from the start geometry
};

/// What LM may move (ABC and GSA always search the link lengths: link_length_set(start)).
enum class CalibrationParams : std::uint8_t {
  full,   ///< every parameter the data identifies (LmParamSet::full)
  paper,  ///< the link lengths (for UR the paper's six) and the base (LmParamSet::link_lengths)
};

/// One solver of a stage.
enum class CalibrationSolver : std::uint8_t { abc, gsa, lm };

/// Settings of one job; the defaults are the command-line tool's.
struct CalibrationOptions {
  CalibrationMethod method = CalibrationMethod::abc_lm;  ///< solvers and their order
  CalibrationParams params = CalibrationParams::full;    ///< what LM may move
  double train_fraction = kDefaultTrainFraction;         ///< share of samples for training, in (0, 1]; 1: no test samples [-]
  std::uint64_t seed = 1;                                ///< seed of the split and of ABC/GSA [-]
  bool robust = false;                                   ///< Huber loss in LM (sets lm.loss)
  std::size_t abc_food_sources = 150;                    ///< ABC SN, <= the workspace's population capacity [-]
  std::size_t abc_cycles = 300;                          ///< ABC MCN [-]
  std::size_t gsa_agents = 150;                          ///< GSA N, <= the workspace's population capacity [-]
  std::size_t gsa_iterations = 200;                      ///< GSA t_max [-]
  double paper6_half_width_m = kPaper6DefaultHalfWidth_m;  ///< ABC/GSA box: start lengths +/- this [m]
  LmOptions lm;                                          ///< LM settings; `params` and `robust` override its params and loss
};

/// Lower-case name of a method as the command line spells it ("abc+lm", "all", ...).
const char* calibration_method_name(CalibrationMethod method);
/// Samples the job needs at least (12 for the paper's set, 24 for the full model) [-].
std::size_t calibration_minimum_samples(CalibrationParams params);

/// The start geometry, before any solver.
struct CalibrationBaseline {
  RobotModel model;                 ///< the start geometry
  RigidTransform base_to_tracker;   ///< its base fitted on the training samples
  ErrorStats train;                 ///< errors on the training samples [m]
  ErrorStats test;                  ///< errors on the test samples (count 0 without a test split) [m]
};

/// What one solver stage produced.
struct CalibrationStage {
  CalibrationSolver solver = CalibrationSolver::lm;    ///< which solver ran
  bool refines_previous = false;                      ///< LM started from the previous stage's geometry and base
  CalibrationParams params = CalibrationParams::paper;  ///< parameters it could move
  Status status = Status::ok;                         ///< ok, or not_converged (LM's last point kept)
  RobotModel model;                                   ///< calibrated geometry
  RigidTransform base_to_tracker;                     ///< its base -> tracker transform
  std::uint64_t evaluations = 0;                      ///< cost evaluations (LM: iterations) [-]
  std::size_t iterations = 0;                         ///< cycles / iterations run [-]
  double best_cost_m = 0.0;                           ///< ABC/GSA: best training MAE as the cost computed it; LM: final RMS [m]
  ErrorStats train;                                   ///< errors on the training samples [m]
  ErrorStats test;                                    ///< errors on the test samples [m]
  Span<const double> trace_m;                         ///< best cost (ABC/GSA: MAE, LM: RMS) per iteration [m]; views the workspace
};

/// Stages a job runs at most ('all': GSA, ABC, LM).
inline constexpr std::size_t kMaxCalibrationStages = 3;

/// The steps of a job, in order (CalibrationResult::step is the last one reached).
enum class CalibrationStep : std::uint8_t { input, split, baseline, gsa, abc, lm, done };

/// Short name of a stage ("ABC", "GSA", "LM", "ABC+LM", "GSA+LM"; the previous stage's name is
/// taken from `refines_previous` and `previous`).
const char* calibration_stage_name(const CalibrationStage& stage, const CalibrationStage* previous);
/// Name of a solver ("ABC", "GSA", "LM").
const char* calibration_solver_name(CalibrationSolver solver);
/// Name of a step ("input", "split", "baseline", "gsa", "abc", "lm", "done").
const char* calibration_step_name(CalibrationStep step);

/// Everything a job returns (~5 KB with the LmResult: static storage on a small target).
struct CalibrationResult {
  Status status = Status::invalid_argument;     ///< ok, or why the job stopped at `step`
  CalibrationStep step = CalibrationStep::input;  ///< done on success, else the step that failed
  std::size_t train_count = 0;                  ///< training samples [-]
  std::size_t test_count = 0;                   ///< test samples [-]
  CalibrationBaseline baseline;                 ///< the start geometry's fit
  CalibrationStage stages[kMaxCalibrationStages];  ///< the stages run, in order
  std::size_t stage_count = 0;                  ///< entries of `stages` used [-]
  bool has_lm = false;                          ///< an LM stage ran: `lm` is meaningful
  LmResult lm;                                  ///< LM details: identifiability, sigma, rms, termination

  /// The stages run, in order.
  Span<const CalibrationStage> stage_list() const { return Span<const CalibrationStage>(stages, stage_count); }
  /// The last stage (the job's answer); null when none ran.
  const CalibrationStage* final_stage() const { return stage_count == 0 ? nullptr : &stages[stage_count - 1]; }
  /// Name of stage k < stage_count (see calibration_stage_name).
  const char* stage_name(std::size_t k) const {
    return calibration_stage_name(stages[k], k == 0 ? nullptr : &stages[k - 1]);
  }
};

/// Optional hooks: stage begin and end (for timings, which lib does not take) and the
/// solvers' per-iteration progress. The defaults do nothing and never cancel.
class CalibrationObserver : public ProgressObserver, public LmObserver {
 public:
  /// Before stage `index` with `solver` starts (its cost is built inside the stage).
  virtual void on_stage_begin(std::size_t index, CalibrationSolver solver) {
    (void)index;
    (void)solver;
  }
  /// After stage `index` succeeded (not called for a failing stage).
  virtual void on_stage_end(std::size_t index, const CalibrationStage& stage) {
    (void)index;
    (void)stage;
  }
  void on_iteration(const SolverProgress& progress) override { (void)progress; }
  bool on_iteration(const LmIterationInfo& info) override {
    (void)info;
    return true;
  }

 protected:
  CalibrationObserver() = default;
  CalibrationObserver(const CalibrationObserver&) = default;
  CalibrationObserver& operator=(const CalibrationObserver&) = default;
  ~CalibrationObserver() = default;
};

/// Capacity-erased workspace: the phases of a job (population cost + solver, LM workspace)
/// are built one at a time in one arena, and the stage traces outlive them.
class CalibrationWorkspaceBase {
 public:
  CalibrationWorkspaceBase(const CalibrationWorkspaceBase&) = delete;
  CalibrationWorkspaceBase& operator=(const CalibrationWorkspaceBase&) = delete;

  /// The objects of a population phase.
  struct PopulationPhase {
    Paper6CostBase* cost = nullptr;  ///< paper-6 cost with room for the training samples
    AbcSolverBase* abc = nullptr;    ///< set by open_abc()
    GsaSolverBase* gsa = nullptr;    ///< set by open_gsa()
  };
  /// Ends any open phase, builds a cost and an ABC solver in the arena.
  virtual PopulationPhase open_abc() = 0;
  /// Ends any open phase, builds a cost and a GSA solver in the arena.
  virtual PopulationPhase open_gsa() = 0;
  /// Ends any open phase, builds an LM workspace (joint trig storage attached if the type has it).
  virtual LmWorkspace* open_lm() = 0;
  /// Ends the open phase (its objects are destroyed).
  virtual void close() = 0;
  /// The trace of stage `index` (< kMaxCalibrationStages).
  virtual TraceBase& trace(std::size_t index) = 0;

 protected:
  CalibrationWorkspaceBase() = default;
  ~CalibrationWorkspaceBase() = default;
};

namespace detail {
/// Joint trig storage for LM, or none (Samples = 0).
template <std::size_t Samples>
struct JointTrigStorage {
  JointTrig values[Samples];
  Span<JointTrig> view() { return Span<JointTrig>(values, Samples); }
};
template <>
struct JointTrigStorage<0> {
  Span<JointTrig> view() { return Span<JointTrig>(); }
};
template <std::size_t A, std::size_t B>
inline constexpr std::size_t max_of = A > B ? A : B;
}  // namespace detail

/// A workspace for jobs on up to `Samples` training samples and up to `MaxLinkLengths` link
/// lengths (6: UR arms, the firmware; kMaxLinkLengths: any arm): paper-6 cost with `CostScalar`
/// terms (double: exact; float: half the memory, the firmware's choice), ABC and GSA with up to
/// `Population` members, traces of `TraceCapacity` iterations per stage, and joint trig
/// storage for LM when `JointTrigSamples` > 0 (faster, same bits). Big: give it static storage.
template <std::size_t Samples, typename CostScalar = double, std::size_t Population = 150,
          std::size_t TraceCapacity = 300, std::size_t JointTrigSamples = 0, std::size_t MaxLinkLengths = kPaper6Dimension>
class CalibrationWorkspace final : public CalibrationWorkspaceBase {
 public:
  using Cost = Paper6Cost<Samples, CostScalar, MaxLinkLengths>;  ///< the population stages' cost
  /// The ABC phase's objects.
  struct AbcPhase {
    Cost cost;
    AbcSolver<Population, MaxLinkLengths> solver;
  };
  /// The GSA phase's objects.
  struct GsaPhase {
    Cost cost;
    GsaSolver<Population, MaxLinkLengths> solver;
  };
  /// The LM phase's objects.
  struct LmPhase {
    LmWorkspace lm;
    detail::JointTrigStorage<JointTrigSamples> joint_trig;
  };
  /// Bytes of the arena: the largest phase.
  static constexpr std::size_t kArenaBytes =
      detail::max_of<detail::max_of<sizeof(AbcPhase), sizeof(GsaPhase)>, sizeof(LmPhase)>;

  CalibrationWorkspace() = default;
  ~CalibrationWorkspace() { close(); }

  PopulationPhase open_abc() override {
    close();
    abc_ = new (arena_) AbcPhase();
    return PopulationPhase{&abc_->cost, &abc_->solver, nullptr};
  }
  PopulationPhase open_gsa() override {
    close();
    gsa_ = new (arena_) GsaPhase();
    return PopulationPhase{&gsa_->cost, nullptr, &gsa_->solver};
  }
  LmWorkspace* open_lm() override {
    close();
    lm_ = new (arena_) LmPhase();
    lm_->lm.joint_trig = lm_->joint_trig.view();
    return &lm_->lm;
  }
  void close() override {
    if (abc_ != nullptr) abc_->~AbcPhase();
    if (gsa_ != nullptr) gsa_->~GsaPhase();
    if (lm_ != nullptr) lm_->~LmPhase();
    abc_ = nullptr;
    gsa_ = nullptr;
    lm_ = nullptr;
  }
  TraceBase& trace(std::size_t index) override { return traces_[index]; }

 private:
  alignas(alignof(std::max_align_t)) unsigned char arena_[kArenaBytes];
  Trace<TraceCapacity> traces_[kMaxCalibrationStages];
  AbcPhase* abc_ = nullptr;  // the open phase (at most one is set), built in arena_
  GsaPhase* gsa_ = nullptr;
  LmPhase* lm_ = nullptr;
};

/// Runs the job of `options` on `*dataset` from `start` (geometry and tool): splits the
/// dataset (in place, seeded), fits the baseline, runs the stages, fills *result. `observer`
/// may be null. Returns ok (LM's not_converged counts as a result: its last point is used), or
/// the failure, with result->step naming the step that failed:
///  - input: invalid_argument (a null pointer, an unknown method or parameter set),
///    dataset_empty, too_few_samples (below calibration_minimum_samples);
///  - split: invalid_argument (the fraction leaves no training sample);
///  - baseline: the errors of fit_base_to_tracker (e.g. degenerate_geometry);
///  - gsa / abc / lm: the stage's own error (calibrate_paper6_gsa/abc, calibrate_lm), e.g.
///    population_out_of_range (population above the workspace's capacity), dataset_full
///    (more training samples than the workspace's cost holds), solver_cancelled (the
///    observer stopped LM).
/// *result is always written when it is not null.
Status calibrate(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* result,
                 CalibrationObserver* observer = nullptr);

}  // namespace hivecal
