// The pose planner (plan/pose_plan.hpp): every planned pose meets every constraint, the same
// bits for a seed (the golden digest: test_plan_golden.cpp), the exchange step improves on the greedy start, no heap;
// simulated sessions calibrated by the job are more accurate from planned poses than from random ones under the same
// constraints; the tool-down session's unidentifiable parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/plan/pose_plan.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/plan_test_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::pose_plan_test {
namespace {

PlanWorkspace workspace;
PlanResult result;
PlanResult other;

using test::digest_of;
using test::kNominalTool;
using test::planning_model;
using test::small_options;
using test::tracker_base;
using test::tracker_position;

TEST(PosePlan, EveryPlannedPoseMeetsEveryConstraint) {
  const PlanOptions options = small_options(512, 30, 3);
  const RobotModel model = planning_model();
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = plan_session(model, options, &workspace, &result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  ASSERT_EQ(result.pose_count, 30u);
  const double cos_acceptance = math::cos(options.constraints.acceptance_rad);
  for (std::size_t i = 0; i < result.pose_count; ++i) {
    const JointVector& q = result.poses[i];
    EXPECT_TRUE(pose_meets_constraints(model, options.constraints, q)) << i;
    // The constraints, checked here on their own rather than through the library's test.
    const RigidTransform flange = fk_flange(model, q);
    const Vec3 reflector = flange.apply(model.tool_m);
    EXPECT_GE(reflector.z(), options.constraints.floor_z_m) << i;
    EXPECT_GE(reflector.head<2>().norm(), options.constraints.keep_out_radius_m) << i;
    const Vec3 line = (options.constraints.tracker_m - reflector).normalized();
    EXPECT_GE(flange.rotation.col(2).dot(line), cos_acceptance - 1e-12) << i;
    for (int j = 0; j < kSixJoints; ++j) {
      EXPECT_GE(q(j), options.constraints.limits.lower_rad(j));
      EXPECT_LE(q(j), options.constraints.limits.upper_rad(j));
    }
  }
  // The path visits each selected pose once: ordering permutes, it does not invent.
  EXPECT_LE(result.travel_s, result.unordered_travel_s);
  EXPECT_NEAR(result.session_s, result.travel_s + 30 * options.dwell_s, 1e-9);
  std::printf("[plan] %zu candidates from %zu draws; pool keeps %d of 33; travel %.1f s (unordered %.1f s)\n",
              result.candidate_count, result.attempts, result.pool.kept_count(), result.travel_s,
              result.unordered_travel_s);
}

TEST(PosePlan, SameBitsForASeedAndOtherBitsForAnother) {
  const RobotModel model = planning_model();
  ASSERT_EQ(plan_session(model, small_options(256, 20, 5), &workspace, &result), Status::ok);
  ASSERT_EQ(plan_session(model, small_options(256, 20, 5), &workspace, &other), Status::ok);
  EXPECT_EQ(digest_of(result), digest_of(other));
  ASSERT_EQ(plan_session(model, small_options(256, 20, 6), &workspace, &other), Status::ok);
  EXPECT_NE(digest_of(result), digest_of(other));
  std::printf("[plan] digest seed 5: %016llx\n", static_cast<unsigned long long>(digest_of(result)));
}

TEST(PosePlan, ExchangeImprovesOnTheGreedyStartAndBothBeatRandom) {
  const RobotModel model = planning_model();
  PlanOptions options = small_options(512, 30, 11);
  options.criterion = PlanCriterion::d_optimal;
  options.restarts = 1;
  options.refine_passes = 0;  // the pool's poses only: the greedy start and its exchanges
  ASSERT_EQ(plan_session(model, options, &workspace, &result), Status::ok);
  EXPECT_GT(result.exchanges, 0);
  EXPECT_GT(result.planned.log_det, result.greedy_log_det);
  EXPECT_GT(result.greedy_log_det, result.random.log_det);
  EXPECT_GT(result.planned.smallest_singular, result.random.smallest_singular);
  EXPECT_LT(result.planned.condition, result.random.condition);
  std::printf(
      "[plan] log det random %.2f greedy %.2f exchange %.2f (%d swaps, %d passes); cond %.1f -> %.1f;"
      " sigma_min %.4f -> %.4f\n",
      result.random.log_det, result.greedy_log_det, result.planned.log_det, result.exchanges, result.exchange_passes,
      result.random.condition, result.planned.condition, result.random.smallest_singular,
      result.planned.smallest_singular);
  // Without exchange passes the result is the greedy start.
  options.max_exchange_passes = 0;
  ASSERT_EQ(plan_session(model, options, &workspace, &other), Status::ok);
  EXPECT_EQ(other.planned.log_det, result.greedy_log_det);
}

// Restarts keep the best criterion: never worse than the greedy start's run alone, and here
// (I-optimal over the cell, the default) better.
TEST(PosePlan, RestartsKeepTheBestCriterion) {
  const RobotModel model = planning_model();
  PlanOptions options = small_options(512, 24, 11);
  options.restarts = 1;
  options.refine_passes = 0;  // the runs' own criteria, before the refinement of the winner
  ASSERT_EQ(plan_session(model, options, &workspace, &other), Status::ok);
  EXPECT_EQ(other.best_restart, 0);
  options.restarts = 6;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = plan_session(model, options, &workspace, &result));
  ASSERT_EQ(status, Status::ok);
  EXPECT_LE(result.planned.prediction_variance, other.planned.prediction_variance);
  EXPECT_LT(result.planned.prediction_variance, result.random.prediction_variance);
  std::printf("[plan] mean prediction variance over the cell: random %.3f, one run %.3f, best of 6 %.3f (run %d)\n",
              result.random.prediction_variance, other.planned.prediction_variance, result.planned.prediction_variance,
              result.best_restart);
  options.restarts = 0;
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
}

// The joint-space refinement (the default) moves the chosen poses off the pool to a better
// criterion, every pose still within every constraint, for both criteria; 0 passes leave the
// pool's poses.
TEST(PosePlan, RefinementLowersTheCriterionWithinTheConstraints) {
  const RobotModel model = planning_model();
  for (const PlanCriterion criterion : {PlanCriterion::i_optimal_workspace, PlanCriterion::d_optimal}) {
    PlanOptions options = small_options(512, 24, 11);
    options.criterion = criterion;
    options.refine_passes = 0;
    ASSERT_EQ(plan_session(model, options, &workspace, &other), Status::ok);
    options.refine_passes = 2;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = plan_session(model, options, &workspace, &result));
    ASSERT_EQ(status, Status::ok);
    if (criterion == PlanCriterion::d_optimal) {
      EXPECT_GT(result.planned.log_det, other.planned.log_det);
    } else {
      EXPECT_LT(result.planned.prediction_variance, other.planned.prediction_variance);
    }
    std::size_t off_pool = 0;
    for (std::size_t i = 0; i < result.pose_count; ++i) {
      EXPECT_TRUE(pose_meets_constraints(model, options.constraints, result.poses[i])) << i;
      bool in_pool = false;
      for (std::size_t k = 0; k < options.candidate_count; ++k)
        in_pool = in_pool || workspace.candidates[k].q_rad == result.poses[i];
      off_pool += in_pool ? 0 : 1;
    }
    EXPECT_GT(off_pool, 0u);
    std::printf(
        "[plan] %s refinement: log det %.3f -> %.3f, mean prediction variance %.4f -> %.4f; %zu of %zu poses moved\n",
        plan_criterion_name(criterion), other.planned.log_det, result.planned.log_det,
        other.planned.prediction_variance, result.planned.prediction_variance, off_pool, result.pose_count);
  }
  PlanOptions options = small_options(64, 20, 1);
  options.refine_passes = -1;
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
}

TEST(PosePlan, BadOptionsAreRejected) {
  const RobotModel model = planning_model();
  PlanOptions options = small_options(64, 20, 1);
  options.pose_count = 0;
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
  options = small_options(64, 65, 1);  // more poses than candidates
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
  options = small_options(64, 20, 1);
  options.constraints.acceptance_rad = 0.0;
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
  options = small_options(64, 20, 1);
  options.constraints.floor_z_m = 5.0;  // nothing reaches above 5 m
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::too_few_samples);
}

TEST(PosePlan, OrderingShortensAPathAndKeepsItsPoses) {
  PlanOptions options;
  JointVector poses[6];
  for (int i = 0; i < 6; ++i) poses[i] = JointVector::Constant(static_cast<double>((i * 4) % 6));  // 0 4 2 0 4 2
  double sum_before = 0.0;
  for (const JointVector& q : poses) sum_before += q.sum();
  const double t = order_poses(poses, 6, options);
  double sum_after = 0.0;
  for (const JointVector& q : poses) sum_after += q.sum();
  EXPECT_EQ(sum_before, sum_after);
  // 0 -> 0 -> 2 -> 2 -> 4 -> 4: two moves of 2 rad.
  EXPECT_NEAR(t, 2.0 * movej_time_s(JointVector::Zero(), JointVector::Constant(2.0), options), 1e-12);
  // Short moves never reach the speed: 2 sqrt(d / a).
  EXPECT_NEAR(movej_time_s(JointVector::Zero(), JointVector::Constant(0.1), options), 2.0 * std::sqrt(0.1 / 1.4),
              1e-12);
}

// ---- Simulated sessions: planned vs random poses under the same constraints ----------------

using JobWorkspace = CalibrationWorkspace<kPlanPoseCapacity, double, 2, 200>;
JobWorkspace job_workspace;
CalibrationResult job_result;
Dataset<kPlanPoseCapacity> session;
PlanWorkspace measurable_pool;
PlanWorkspace workspace_pool;

/// Mean |prediction - truth| [m] of a calibrated model over `validation` (noise-free truth).
double validation_mae_m(const RobotModel& truth, const CalibrationStage& lm, Span<const Sample> validation) {
  const RigidTransform base = tracker_base();
  double sum = 0.0;
  for (const Sample& v : validation) {
    const Vec3 predicted = lm.base_to_tracker.apply(fk_tool_point(lm.model, v.q_rad));
    sum += (predicted - base.apply(fk_tool_point(truth, v.q_rad))).norm();
  }
  return sum / static_cast<double>(validation.size());
}

/// Calibrates `truth` from `poses` (10 um tracker noise) with the job (LM, full model, its
/// significance test at `significance_t`) and adds its validation MAE [m] on the measurable
/// region and on the whole cell to mae[0], mae[1].
void add_session_mae(const RobotModel& truth, Span<const Sample> poses, double significance_t, Random* noise,
                     double* mae) {
  const RigidTransform base = tracker_base();
  session.clear();
  for (const Sample& pose : poses) {
    const Vec3 point = base.apply(fk_tool_point(truth, pose.q_rad)) + 10e-6 * test::gaussian_vector(noise);
    EXPECT_EQ(session.add(pose.q_rad, point), Status::ok);
  }
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.params = CalibrationParams::full;
  options.train_fraction = 1.0;
  options.significance_t = significance_t;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(planning_model(), &session, options, &job_workspace, &job_result));
  EXPECT_TRUE(status == Status::ok || status == Status::not_converged) << status_message(status);
  if (job_result.stage_count == 0) {  // the job stopped before any stage: no model to validate
    ADD_FAILURE() << "the job stopped at " << calibration_step_name(job_result.step);
    return;
  }
  const CalibrationStage& lm = job_result.stages[job_result.stage_count - 1];
  mae[0] += validation_mae_m(truth, lm, Span<const Sample>(measurable_pool.candidates, 200));
  mae[1] += validation_mae_m(truth, lm, Span<const Sample>(workspace_pool.candidates, 200));
}

/// Summed validation MAEs over `arms` perturbed UR5s: [planned, random] x [measurable, cell].
struct Comparison {
  double planned[2] = {};  ///< planned poses: measurable region, whole cell [m]
  double random[2] = {};   ///< the pool's first draws: the same [m]
};

/// Plans `poses` poses for each of `arms` perturbed UR5s with `plan` (pool of 1024, seed per
/// arm) and calibrates both sets with the job at `significance_t`.
Comparison compare_sessions(const PlanOptions& plan, std::size_t poses, std::uint64_t arms,
                            double significance_t = kDefaultSignificance) {
  const double per_arm_um = 1e6 / static_cast<double>(arms);
  const RobotModel model = planning_model();
  Comparison c;
  for (std::uint64_t arm = 0; arm < arms; ++arm) {
    Random random(100 + arm);
    const Vec3 tool = kNominalTool + 2e-3 * test::gaussian_vector(&random);
    const RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool);
    PlanOptions options = plan;
    const PlanOptions cell = small_options(1024, poses, 20 + arm);
    options.constraints = cell.constraints;
    options.candidate_count = cell.candidate_count;
    options.pose_count = cell.pose_count;
    options.seed = cell.seed;
    EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::ok);
    Sample planned[kPlanPoseCapacity];
    for (std::size_t i = 0; i < poses; ++i) planned[i] = Sample{result.poses[i], Vec3::Zero()};
    add_session_mae(truth, Span<const Sample>(planned, poses), significance_t, &random, c.planned);
    add_session_mae(truth, Span<const Sample>(workspace.candidates, poses), significance_t, &random, c.random);
  }
  std::printf(
      "[plan] %s (prior %.1f mm / %.1f mrad, %d restarts), %zu poses, %llu arms, significance %.0f sigma:"
      " validation MAE planned / random: measurable region %.3f (%.2f / %.2f um), whole cell %.3f"
      " (%.2f / %.2f um)\n",
      plan_criterion_name(plan.criterion), plan.prior_length_m * 1e3, plan.prior_angle_rad * 1e3, plan.restarts, poses,
      static_cast<unsigned long long>(arms), significance_t, c.planned[0] / c.random[0], c.planned[0] * per_arm_um,
      c.random[0] * per_arm_um, c.planned[1] / c.random[1], c.planned[1] * per_arm_um, c.random[1] * per_arm_um);
  return c;
}

/// Fresh validation poses: 200 under the session's constraints, 200 anywhere in the cell.
void make_validation_pools() {
  const RobotModel model = planning_model();
  PlanOptions fresh = small_options(200, 24, 999);
  std::size_t draws = 0;
  ASSERT_EQ(generate_candidates(model, fresh, &measurable_pool, &draws), Status::ok);
  fresh.constraints.acceptance_rad = math::kPi;
  ASSERT_EQ(generate_candidates(model, fresh, &workspace_pool, &draws), Status::ok);
}

// The random sets are the pool's first draws, i.e. random poses under the same constraints;
// the planner and the job run with their defaults (I-optimal over the cell with the 1 mm /
// 1 mrad prior, the tool off the flange axis by its prior in the objective, 4 restarts, 2
// refinement passes; LM, full model, significance test at 2 sigma).
// Two tests (24 and 16 poses), so that CTest runs them side by side.
TEST(PosePlan, PlannedSessionsOf24PosesCalibrateBetterThanRandomOnes) {
  make_validation_pools();
  // Measured (x86-64, 24 arms), planned / random validation MAE on the measurable region and
  // on the whole cell: 24 poses 0.828 / 0.656 (the tool off the axis alone 0.703, the
  // refinement alone 0.712); 16 poses 0.803 / 0.756; 20 poses 0.807 / 0.701 (not asserted:
  // ~60 s more); see docs/planning.md. The bounds leave ~0.03-0.04.
  const Comparison n24 = compare_sessions(PlanOptions{}, 24, 24);
  EXPECT_LE(n24.planned[0], 0.86 * n24.random[0]);
  EXPECT_LE(n24.planned[1], 0.70 * n24.random[1]);
}

TEST(PosePlan, PlannedSessionsOf16PosesCalibrateBetterThanRandomOnes) {
  make_validation_pools();
  const Comparison n16 = compare_sessions(PlanOptions{}, 16, 24);
  EXPECT_LE(n16.planned[1], 0.79 * n16.random[1]);
}

// ---- The paper's situation: the tool always pointing down ----------------------------------

TEST(PosePlan, ToolDownLeavesParametersThatNoPoseSetIdentifies) {
  const RobotModel model = planning_model();
  PlanOptions down = small_options(512, 30, 4);
  down.constraints.orientation = PlanOrientation::tool_down;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = plan_session(model, down, &workspace, &result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  for (std::size_t i = 0; i < result.pose_count; ++i) {
    EXPECT_TRUE(pose_meets_constraints(model, down.constraints, result.poses[i])) << i;
    const Vec3 axis = fk_flange(model, result.poses[i]).rotation.col(2);
    EXPECT_NEAR(axis.z(), -1.0, 1e-9) << i;
  }
  IdentifiabilityReport facing;
  std::size_t attempts = 0;
  EXPECT_NO_HEAP(status = pool_identifiability(model, small_options(512, 30, 4), &workspace, &facing, &attempts));
  ASSERT_EQ(status, Status::ok);
  const ParamMask gained = facing.kept_mask & ~result.pool.kept_mask;
  std::printf("[plan] tool down: the pool keeps %d of 33; facing the tracker %d; freeing the orientation adds:",
              result.pool.kept_count(), facing.kept_count());
  for (int k = 0; k < kFullParamCount; ++k) {
    if (mask_has(gained, k)) std::printf(" %s", full_param_name(k, kSixJoints));
  }
  std::printf("\n");
  // Three more null directions with the joint 6 axis always vertical (the dropping rule names
  // one parameter of each): d6 and tool_z move the point as base_tz does, a1 becomes a
  // combination of theta4 and a4, d4 one of alpha4 (d2, d3 are lost either way).
  EXPECT_EQ(result.pool.kept_mask & ~facing.kept_mask, 0u);  // down identifies nothing more
  EXPECT_EQ(gained, param_bit(model_param_index(0, DhField::a)) | param_bit(model_param_index(3, DhField::d)) |
                        param_bit(tool_param_index(kSixJoints, 2)));
  // Every tool-down plan, whatever it selects, keeps at most what its pool keeps.
  EXPECT_EQ(result.planned.identifiability.kept_mask & ~result.pool.kept_mask, 0u);
}

// A seven-joint arm plans as any other: its extra joint is the planner's freedom (more poses
// meet the constraints), not an error; tool-down, a UR wrist's rule, needs six joints.
TEST(PosePlan, ASevenJointArmPlansWithinItsLimits) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints";
  RobotModel model = test::many_joint_arm_model(test::ManyJointArm::iiwa14);
  model.tool_m = kNominalTool;
  PlanOptions options = small_options(256, 20, 7);
  options.restarts = 1;
  options.refine_passes = 1;
  options.free_mask = lm_param_mask(LmParamSet::full, 0, model);
  for (int j = 0; j < 7; ++j) {
    options.constraints.limits.lower_rad(j) = -2.0;
    options.constraints.limits.upper_rad(j) = 2.0;
  }
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = plan_session(model, options, &workspace, &result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  ASSERT_EQ(result.pose_count, 20u);
  for (std::size_t i = 0; i < result.pose_count; ++i) {
    const JointVector& q = result.poses[i];
    EXPECT_TRUE(pose_meets_constraints(model, options.constraints, q)) << i;
    for (int j = 0; j < 7; ++j) {
      EXPECT_GE(q(j), -2.0);
      EXPECT_LE(q(j), 2.0);
    }
    for (int j = 7; j < kMaxJoints; ++j) EXPECT_EQ(q(j), 0.0);  // nothing beyond the arm's joints
  }
  EXPECT_GE(result.planned.identifiability.kept_count(), result.pool.kept_count());  // what the pool identifies
  options.constraints.orientation = PlanOrientation::tool_down;
  EXPECT_EQ(plan_session(model, options, &workspace, &result), Status::invalid_argument);
}

// A built-in type's limits: UR's controller's (+-360 deg, the elbow +-180 deg); a seven-axis
// arm's maker's, which plan keeps when the command names the arm.
TEST(PosePlan, DefaultLimitsAreTheControllersForUrAndTheMakersForTheOthers) {
  JointLimits limits;
  EXPECT_NO_HEAP(limits = default_joint_limits(RobotType::ur10e));
  EXPECT_EQ(limits.lower_rad(0), -2.0 * math::kPi);
  EXPECT_EQ(limits.upper_rad(2), math::kPi);
#if HIVECAL_MAX_JOINTS >= 7
  for (const RobotType type : {RobotType::iiwa14, RobotType::panda, RobotType::fr3, RobotType::gen3, RobotType::wam}) {
    JointVector lower;
    JointVector upper;
    ASSERT_EQ(maker_joint_limits(type, &lower, &upper), Status::ok);
    EXPECT_NO_HEAP(limits = default_joint_limits(type));
    EXPECT_EQ(limits.lower_rad, lower) << robot_type_name(type);
    EXPECT_EQ(limits.upper_rad, upper) << robot_type_name(type);
  }
  limits = default_joint_limits(RobotType::wam);
  EXPECT_EQ(limits.lower_rad(4), -4.76);  // Barrett's stops, not +-2 pi
  EXPECT_EQ(limits.upper_rad(3), 3.1);
#endif
}

}  // namespace
}  // namespace hivecal::pose_plan_test
