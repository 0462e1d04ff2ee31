// The calibration job's steps across its files, internal to the job (calibration.hpp is the
// entry, calibration.cpp): the job's state, the stages of a method (stages.cpp), one LM fit
// with its significance test (lm_fit.cpp) and the joint-term stages (joint_terms.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/calibration.hpp"
#include "hivecal/model/full_params.hpp"

namespace hivecal::detail {

/// The job's state while it runs: the inputs and where the result goes.
struct Job {
  const RobotModel& start;    ///< the baseline's model: the start joints with the tool point fitted
  const RobotModel& nominal;  ///< the job's start model as given (the tool point given): the prior's centre
  DatasetBase& dataset;
  const CalibrationOptions& options;
  CalibrationWorkspaceBase& workspace;
  CalibrationResult& result;
  CalibrationObserver* observer;
};

// ---- stages.cpp: the stages of a method on a split dataset

/// Which stages a method runs.
struct StagePlan {
  bool gsa = false;     ///< GSA on the link lengths
  bool abc = false;     ///< ABC on the link lengths
  bool lm = false;      ///< LM
  bool hybrid = false;  ///< LM starts from the population stage's result
};

/// The stages `method` runs.
StagePlan plan_for(CalibrationMethod method);

/// Records in *result that the job stopped at `step` with `status`; returns the status.
Status fail(CalibrationResult* result, CalibrationStep step, Status status);

/// Tells the observer, if any, that `phase` began or ended.
void report_phase(CalibrationObserver* observer, CalibrationPhase phase, bool ended);

/// Fills the next stage slot from r.lm after an LM stage that ended with `status`.
void lm_stage(Job& job, Status status, bool refines_previous, bool compliance, TraceBase& trace);

/// LM from the start geometry, or (hybrid) from the previous stage's geometry and base, with
/// the significance test (fit_lm; level from choose_significance).
Status run_lm(Job& job, bool hybrid, ParamMask* pruned);

/// Baseline and stages on a dataset already split (train / test).
Status run_split(const RobotModel& start, DatasetBase* dataset, const CalibrationOptions& options,
                 CalibrationWorkspaceBase* workspace, CalibrationResult* r, CalibrationObserver* observer);

// ---- lm_fit.cpp: one LM fit of the job and its significance test

/// The tool point's three bits in the parameters of `model`.
ParamMask tool_params_mask(const RobotModel& model);

/// The six base parameters' bits in the parameters of `model`.
ParamMask base_params_mask(const RobotModel& model);

/// The base and tool bits the options hold fixed (base_known, tool_known).
ParamMask known_params_mask(const CalibrationOptions& options, const RobotModel& model);

/// The levels the joint terms of a stage must clear [-].
struct JointTermLevels {
  double gravity_t = 0.0;   ///< a gravity term: CalibrationCompliance::significance_t
  double harmonic_t = 0.0;  ///< a harmonic: that, raised for the whole family (harmonic_level)
  ParamMask harmonics = 0;  ///< the harmonic terms' parameters
};

/// The levels of `reference`'s joint terms. `compliance_t`: CalibrationCompliance::significance_t;
/// `dof`: the fit's residual degrees of freedom.
JointTermLevels joint_term_levels(const RobotModel& reference, double compliance_t, int dof);

/// One LM fit of the job: what it starts from, what it may move, on which samples.
struct LmFit {
  /// The start values (job.start, with the compliance terms and their start coefficients for
  /// the LM+compliance stage): what a dropped or insignificant parameter is put back to.
  const RobotModel* reference = nullptr;
  const RobotModel* start_model = nullptr;  ///< the geometry LM starts from (a stage's or the job's)
  const RigidTransform* base = nullptr;     ///< base -> tracker to start from; null: fitted first
  bool reset_moved = false;                 ///< put back a parameter LM drops that an earlier stage moved
  bool compliance = false;                  ///< the reference's compliance terms are free too, starting on start_model
  Span<const Sample> samples;               ///< the samples fitted
  double significance_t = 0.0;              ///< a change below this many sigma is not significant [-]
  /// Joint terms held at their start values: after LM+compliance, the gravity terms it did not
  /// keep (the harmonics' stage adds harmonics to that model, it does not reopen its choice).
  ParamMask fixed_terms = 0;
  /// Start where the last fit (r.lm) ended instead of start_model: its coefficients kept, those
  /// of fixed_terms put back to their start values; a refit takes a few iterations.
  bool warm = false;
};

/// Where a fit reports: its trace, its observer (both may be null), the parameters fixed as
/// not significant.
struct LmFitReport {
  TraceBase* trace = nullptr;      ///< LM's RMS per iteration
  LmObserver* observer = nullptr;  ///< progress
  ParamMask* pruned = nullptr;     ///< receives the parameters fixed as not significant
};

/// LM for `fit` into r.lm. Runs again while (a) it drops a parameter an earlier stage moved
/// (with reset_moved: put back to its start value) or (b) a joint term's coefficient is not
/// plausible (implausible_joint_term, whatever the significance level: fixed at its start value,
/// so that every result reads back) or (c) an estimated parameter's change is not significant
/// (below significance_t sigma: fixed at its start value, one at a time, the least significant
/// first; a small set then fits fewer parameters instead of its noise; the geometry of a larger
/// one is not tested, tests_geometry).
Status fit_lm(Job& job, const LmFit& fit, const LmFitReport& report);

/// The significance level for this stage: options.significance_t, or (when negative and the
/// training set is small) the one of kSignificanceGrid with the least leave-one-out 3-D MAE
/// on the training samples (each pose, with the samples of all its targets, left out and
/// predicted by a fit of the others; ties go to the simpler model); a large set gets
/// kDefaultSignificance.
double choose_significance(Job& job, const RobotModel& from, const RigidTransform* base, bool reset);

/// Whether training sample i is the first of its pose (same_pose).
bool first_of_its_pose(Span<const Sample> train, std::size_t i);

/// Moves the first n samples' ones at the pose of `pose` (same_pose: every target) to the end of
/// the n, each with one exchange; moved[m] receives the position the m-th exchange took it from,
/// so that put_pose_back restores the order. Returns how many moved [-].
std::size_t move_pose_to_end(DatasetBase& dataset, std::size_t n, const Sample& pose, std::uint8_t* moved);

/// Undoes move_pose_to_end: the exchanges in reverse order.
void put_pose_back(DatasetBase& dataset, std::size_t n, const std::uint8_t* moved, std::size_t count);

/// Sum of the 3-D errors of `samples` under r.lm's fit [m].
double left_out_error_sum_m(const LmResult& lm, Span<const Sample> samples);

// ---- joint_terms.cpp: the joint-term stages (docs/compliance.md)

/// The compliance model the LM+compliance stage starts from: the options' terms, or the
/// default ones of `start`'s geometry; `gravity_only`: without the harmonics. invalid_argument
/// when there are none or they are unusable.
Status compliance_start(const RobotModel& start, const CalibrationCompliance& options, bool gravity_only,
                        ComplianceModel* out);

/// The options' joint terms are gravity terms followed by harmonics (both families, in that
/// order, as the command line builds them): the job then runs LM+compliance (the gravity terms)
/// before LM+compliance+harmonics, so that Table 1 shows what each family bought; the second
/// stage's model extends the first's. Any other mix runs as one stage.
bool gravity_stage_first(const RobotModel& start, const CalibrationCompliance& options);

/// LM+compliance: from the rigid LM stage's geometry and base, the geometry and the joint terms
/// (`gravity_only`: the gravity terms alone, before the harmonics' stage) together, at the
/// rigid stage's significance level (joint_terms.cpp says how its terms are admitted).
Status run_compliance_lm(Job& job, ParamMask* pruned, bool gravity_only);

}  // namespace hivecal::detail
