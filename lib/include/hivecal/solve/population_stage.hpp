// The population stage of the paper's calibration (docs/solvers-abc-gsa.md): ABC or GSA on
// the link lengths (for UR the paper's six) over the precomputed paper-6 cost, the base refitted per candidate, then
// the best geometry's base fit. The calibration job (calibration.hpp) runs it alone or
// before Levenberg-Marquardt. No heap: every large object is the caller's.
#pragma once

#include <cstdint>

#include "hivecal/solve/abc.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/objective.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"

namespace hivecal {

/// What the population stage on the link lengths produced.
struct Paper6StageResult {
  RobotModel model;                ///< the start geometry with the best link lengths
  RigidTransform base_to_tracker;  ///< Kabsch fit of `model` on the training samples
  double best_cost_m = 0.0;        ///< training MAE at the best lengths, as the cost computed it [m]
  std::uint64_t evaluations = 0;   ///< cost evaluations made
  std::size_t iterations = 0;      ///< solver iterations (cycles) run
};

/// ABC on the paper-6 cost: cost->build(start, train, subset) (the samples at the positions
/// `subset` of `train`, ascending; empty: all of them), box = start's lengths +/- half_width_m,
/// solver->minimize, then the best geometry and its base fit. `cost` and `solver` are scratch
/// (static storage: Paper6Cost<N[, float[, K]]>, AbcSolver<SN, K> for up to K link lengths:
/// 6 for UR arms). Errors: those of build, link_length_box, minimize (dimension_out_of_range:
/// more lengths than the solver holds) and fit_base_to_tracker (on every training sample);
/// *result is written only on success.
Status calibrate_paper6_abc(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                            const AbcOptions& options, double half_width_m, Paper6CostBase* cost, AbcSolverBase* solver,
                            Paper6StageResult* result, TraceBase* trace = nullptr,
                            ProgressObserver* progress = nullptr);

/// The same with GSA.
Status calibrate_paper6_gsa(const RobotModel& start, Span<const Sample> train, Span<const std::uint32_t> subset,
                            const GsaOptions& options, double half_width_m, Paper6CostBase* cost, GsaSolverBase* solver,
                            Paper6StageResult* result, TraceBase* trace = nullptr,
                            ProgressObserver* progress = nullptr);

}  // namespace hivecal
