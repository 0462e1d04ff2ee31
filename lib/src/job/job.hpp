// The calibration job's steps across its files, internal to the job (calibration.hpp is the
// entry, calibration.cpp): the job's state, the stages of a method with their LM fits and the
// significance test (stages.cpp; one file: one copy of the models' assignment in the firmware's
// flash) and the joint-term stages (joint_terms.cpp).
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

// ---- stages.cpp too: one LM fit of the job, its significance test and the left-out poses

/// The tool point's three bits in the parameters of `model`.
ParamMask tool_params_mask(const RobotModel& model);

/// The six base parameters' bits in the parameters of `model`.
ParamMask base_params_mask(const RobotModel& model);

/// The base and tool bits the options hold fixed (base_known, tool_known).
ParamMask known_params_mask(const CalibrationOptions& options, const RobotModel& model);

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

/// JointTermHoldout for a joint-term stage `stage_fit` that kept some of `new_terms` with the
/// parameters `pruned` fixed: each training pose left out in turn, the others fitted twice with
/// the stage's choice of parameters (no significance test of their own), with and without the
/// `new_terms`. Overwrites r.lm; the dataset's order is restored.
JointTermHoldout check_on_left_out_poses(Job& job, const LmFit& stage_fit, ParamMask pruned, ParamMask new_terms);

/// The joint terms a stage of the families `families` (kJointTermFamilies) starts from: the
/// options' terms, or (none given) each family's default ones for `start`'s geometry
/// (JointTermFamily::default_size), then those of the families in `families` alone, in their
/// order. invalid_argument when there are none or they are unusable.
Status compliance_start(const RobotModel& start, const CalibrationCompliance& options, JointTermFamilySet families,
                        ComplianceModel* out);

/// The joint-term stages of the options' terms (plan_joint_term_stages of kJointTermFamilies):
/// one per family in the table's order when the terms come in that order (as the command line
/// builds them: LM+compliance, then LM+compliance+harmonics), else one of every term.
JointTermStages joint_term_stages(const RobotModel& start, const CalibrationCompliance& options);

// ---- joint_terms.cpp: the joint-term stages (docs/compliance.md)

/// A joint-term stage: from the rigid LM stage's geometry and base, the geometry and the terms
/// of the families `families` together, at the rigid stage's significance level, each term at
/// its family's level; the terms it adds to the previous joint-term stage's admitted by their
/// families' rules (joint_terms.cpp).
Status run_compliance_lm(Job& job, ParamMask* pruned, JointTermFamilySet families);

}  // namespace hivecal::detail
