// Levenberg-Marquardt calibration: recovery of a known truth (exact without noise, within
// noise and within its sigma with noise), parameter sets, hybrid starts, trace and observer.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::lm_test {
namespace {

const Vec3 kTrueTool_m(0.012, -0.018, 0.15);

struct Session {
  RobotModel truth;
  RigidTransform base;
};

/// This file's training and fresh sets, workspace and result.
test::LmTestStorage<400>& lm() {
  static test::LmTestStorage<400> storage;
  return storage;
}

/// A perturbed arm, `train_count` samples with `noise_m`, 200 noise-free fresh poses.
Session simulate(RobotType type, std::uint64_t seed, std::size_t train_count, double noise_m) {
  Random random(seed);
  Session s{test::perturbed_parallel_model(type, &random, 3e-4, 3e-4, kTrueTool_m), test::example_base_to_tracker()};
  lm().train.clear();
  lm().fresh.clear();
  test::fill_dataset(s.truth, s.base, train_count, noise_m, &random, &lm().train);
  test::fill_dataset(s.truth, s.base, 200, 0.0, &random, &lm().fresh);
  return s;
}

/// The nominal arm with the tool point guessed on the flange axis: what a user starts from.
RobotModel nominal_start(RobotType type) {
  RobotModel start = nominal_model(type);
  start.tool_m = Vec3(0.0, 0.0, 0.15);
  return start;
}

/// Parameters that appear in some dropped combination (the rest are determined alone).
ParamMask combination_members(const IdentifiabilityReport& report) {
  ParamMask mask = 0;
  for (int d = 0; d < report.dropped_count; ++d) {
    for (int index : report.dropped[d].component_index) {
      if (index >= 0) mask |= param_bit(index);
    }
  }
  return mask;
}

void expect_exact_recovery(RobotType type, std::uint64_t seed) {
  SCOPED_TRACE(robot_type_name(type));
  const Session s = simulate(type, seed, 150, 0.0);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(nominal_start(type), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace,
                                       &lm().result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  const LmResult& r = lm().result;
  EXPECT_EQ(r.identifiability.kept_count(), 25);
  EXPECT_LE(test::max_prediction_gap(r.model, r.base_to_tracker, s.truth, s.base, lm().fresh.samples()), 1e-9);
  // Each parameter the data determines alone equals the truth.
  const ParamMask alone = r.identifiability.kept_mask & ~combination_members(r.identifiability);
  const ModelParams estimated = to_params(r.model);
  const ModelParams truth = to_params(s.truth);
  int checked = 0;
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(alone, i)) continue;
    EXPECT_NEAR(estimated(i), truth(i), 1e-9) << full_param_name(i, kSixJoints);
    ++checked;
  }
  EXPECT_GE(checked, 15);
  // And each identifiable combination does too.
  EXPECT_NEAR(test::parallel_offset_sum_m(r.model), test::parallel_offset_sum_m(s.truth), 1e-9);
  const RigidTransform est_frame1 = test::base_through_joint1(r.model, r.base_to_tracker);
  const RigidTransform true_frame1 = test::base_through_joint1(s.truth, s.base);
  EXPECT_LE((est_frame1.rotation - true_frame1.rotation).norm(), 1e-9);
  EXPECT_LE((est_frame1.translation_m - true_frame1.translation_m).norm(), 1e-9);
  for (double q6 : {0.0, 2.0, 4.0}) {
    EXPECT_LE((test::tool_in_frame5(r.model, q6) - test::tool_in_frame5(s.truth, q6)).norm(), 1e-9);
  }
}

TEST(Lm, RecoversIdentifiableParametersExactlyWithoutNoiseUr5) {
  expect_exact_recovery(RobotType::ur5, 101);
}
TEST(Lm, RecoversIdentifiableParametersExactlyWithoutNoiseUr10) {
  expect_exact_recovery(RobotType::ur10, 102);
}
TEST(Lm, RecoversIdentifiableParametersExactlyWithoutNoiseUr5e) {
  expect_exact_recovery(RobotType::ur5e, 103);
}

TEST(Lm, WithNoiseRecoversWithinNoiseAndWithinSigma) {
  const double noise_m = 1e-5;
  const Session s = simulate(RobotType::ur5, 104, 300, noise_m);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(nominal_start(RobotType::ur5), nullptr, lm().train.samples(), LmOptions{},
                                       &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  const LmResult& r = lm().result;
  // Predictions on fresh poses against the noise-free truth: noise-limited, i.e. about
  // noise * sqrt(p / N) per axis, far below the noise itself.
  ErrorStats validation;
  EXPECT_NO_HEAP(validation = position_error_stats(r.model, r.base_to_tracker, lm().fresh.samples()));
  EXPECT_LT(validation.mae(ErrorAxis::norm_3d), 0.5 * noise_m);
  EXPECT_LT(validation.max(ErrorAxis::norm_3d), 2.0 * noise_m);
  EXPECT_NEAR(r.residual_sigma_m, noise_m, 0.1 * noise_m);
  const ParamMask alone = r.identifiability.kept_mask & ~combination_members(r.identifiability);
  const ModelParams estimated = to_params(r.model);
  const ModelParams truth = to_params(s.truth);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(alone, i)) continue;
    EXPECT_GT(r.sigma(i), 0.0) << full_param_name(i, kSixJoints);
    EXPECT_LT(std::fabs(estimated(i) - truth(i)), 4.0 * r.sigma(i)) << full_param_name(i, kSixJoints);
  }
  // d2 and d3 are held, so sigma(d4) is the sigma of the sum d2 + d3 + d4.
  const int d4 = model_param_index(3, DhField::d);
  EXPECT_LT(std::fabs(test::parallel_offset_sum_m(r.model) - test::parallel_offset_sum_m(s.truth)), 4.0 * r.sigma(d4));
  for (int d = 0; d < r.identifiability.dropped_count; ++d) {
    EXPECT_EQ(r.sigma(r.identifiability.dropped[d].index), 0.0);
  }
}

// sigma_p is the spread of the estimate over repeated sessions: compare it with the
// empirical standard deviation over 24 noise draws of the same poses.
TEST(Lm, SigmaMatchesMonteCarloSpread) {
  const double noise_m = 1e-5;
  Random random(105);
  const RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, kTrueTool_m);
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<120> poses;
  static Dataset<120> noisy;
  poses.clear();
  test::fill_dataset(truth, base, 120, 0.0, &random, &poses);
  const int watched[] = {model_param_index(1, DhField::a), model_param_index(3, DhField::alpha),
                         model_param_index(4, DhField::theta_offset), tool_param_index(kSixJoints, 2)};
  constexpr int kRuns = 24;
  double sum[4] = {};
  double sum2[4] = {};
  double sigma_mean[4] = {};
  for (int run = 0; run < kRuns; ++run) {
    noisy.clear();
    for (const Sample& sample : poses.samples()) {
      const Vec3 noise = test::gaussian_vector(&random);
      ASSERT_EQ(noisy.add(sample.q_rad, sample.point_m + noise_m * noise), Status::ok);
    }
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate_lm(truth, &base, noisy.samples(), LmOptions{}, &lm().workspace, &lm().result));
    ASSERT_EQ(status, Status::ok);
    const ModelParams p = to_params(lm().result.model);
    for (int k = 0; k < 4; ++k) {
      sum[k] += p(watched[k]);
      sum2[k] += p(watched[k]) * p(watched[k]);
      sigma_mean[k] += lm().result.sigma(watched[k]) / kRuns;
    }
  }
  for (int k = 0; k < 4; ++k) {
    const double mean = sum[k] / kRuns;
    const double spread = std::sqrt((sum2[k] - kRuns * mean * mean) / (kRuns - 1));
    EXPECT_GT(spread, 0.6 * sigma_mean[k]) << full_param_name(watched[k], kSixJoints);
    EXPECT_LT(spread, 1.5 * sigma_mean[k]) << full_param_name(watched[k], kSixJoints);
  }
}

TEST(Lm, Paper6MovesOnlyItsParameters) {
  simulate(RobotType::ur5, 106, 100, 1e-5);
  LmOptions options;
  options.params = LmParamSet::link_lengths;
  const RobotModel start = nominal_start(RobotType::ur5);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(start, nullptr, lm().train.samples(), options, &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  const IdentifiabilityReport& report = lm().result.identifiability;
  ParamMask paper6 = 0;
  EXPECT_NO_HEAP(paper6 = lm_param_mask(LmParamSet::link_lengths, 0, start));
  EXPECT_EQ(report.free_mask, paper6);
  EXPECT_EQ(mask_count(report.free_mask), 12);
  EXPECT_EQ(report.kept_count(), 11);  // d1 trades against the base height
  EXPECT_FALSE(mask_has(report.kept_mask, model_param_index(0, DhField::d)) &&
               mask_has(report.kept_mask, base_translation_param_index(kSixJoints, 2)));
  const ModelParams before = to_params(start);
  const ModelParams after = to_params(lm().result.model);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(report.kept_mask, i)) {
      EXPECT_EQ(after(i), before(i)) << full_param_name(i, kSixJoints);
    }
  }
  EXPECT_NE(after(model_param_index(1, DhField::a)), before(model_param_index(1, DhField::a)));
  // Six lengths cannot explain angle errors: better than nominal, worse than full.
  const double paper6_rms = lm().result.rms_m;
  EXPECT_NO_HEAP(status =
                     calibrate_lm(start, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok);
  EXPECT_GT(paper6_rms, 2.0 * lm().result.rms_m);
}

// Hybrid mode: a metaheuristic's result (here a geometry a few tenths of a millimetre off
// and its own base estimate) is refined to the same predictions as a nominal start.
TEST(Lm, HybridStartFromAnyModelAndBase) {
  const Session s = simulate(RobotType::ur5, 107, 150, 0.0);
  Random random(7);
  RobotModel guess = test::perturbed_model(s.truth, &random, 2e-4, 2e-4);
  guess.tool_m += Vec3(0.001, -0.001, 0.002);
  RigidTransform guess_base = s.base;
  guess_base.translation_m += Vec3(0.002, 0.001, -0.003);
  Mat3 tilt;
  EXPECT_NO_HEAP(tilt = rotation_from_vector(Vec3(0.002, -0.001, 0.003)));
  guess_base.rotation = guess_base.rotation * tilt;
  Status status = Status::ok;
  EXPECT_NO_HEAP(
      status = calibrate_lm(guess, &guess_base, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  EXPECT_LE(
      test::max_prediction_gap(lm().result.model, lm().result.base_to_tracker, s.truth, s.base, lm().fresh.samples()),
      1e-9);
  EXPECT_NEAR(lm().result.base_to_tracker.rotation.determinant(), 1.0, 1e-12);
}

struct CountingObserver final : LmObserver {
  int calls = 0;
  int stop_after = 1000;
  int last_iteration = 0;
  double last_rms_m = 0.0;
  bool on_iteration(const LmIterationInfo& info) override {
    ++calls;
    EXPECT_GT(info.iteration, last_iteration);
    last_iteration = info.iteration;
    last_rms_m = info.rms_m;
    return calls < stop_after;
  }
};

TEST(Lm, TraceAndObserverFollowTheIterations) {
  simulate(RobotType::ur5, 108, 100, 1e-5);
  static Trace<64> trace;
  trace.clear();
  CountingObserver observer;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(nominal_start(RobotType::ur5), nullptr, lm().train.samples(), LmOptions{},
                                       &lm().workspace, &lm().result, &trace, &observer));
  ASSERT_EQ(status, Status::ok);
  // The start value, then one per iteration that tried a step (a convergence test that
  // fires before any step ends a phase without a value).
  EXPECT_EQ(static_cast<std::size_t>(observer.calls) + 1, trace.size());
  EXPECT_LE(observer.calls, lm().result.iterations);
  EXPECT_GE(observer.calls, lm().result.iterations - 4);
  EXPECT_GT(trace.values()[0], 100.0 * trace.values()[trace.size() - 1]);
  for (std::size_t i = 1; i < trace.size(); ++i) EXPECT_LE(trace.values()[i], trace.values()[i - 1] * 1.01);
  EXPECT_DOUBLE_EQ(observer.last_rms_m, trace.values()[trace.size() - 1]);

  CountingObserver stopper;
  stopper.stop_after = 2;
  EXPECT_NO_HEAP(status = calibrate_lm(nominal_start(RobotType::ur5), nullptr, lm().train.samples(), LmOptions{},
                                       &lm().workspace, &lm().result, nullptr, &stopper));
  EXPECT_EQ(status, Status::solver_cancelled);
  EXPECT_EQ(lm().result.termination, LmTermination::cancelled);
  EXPECT_EQ(lm().result.iterations, 2);
}

TEST(Lm, IterationLimitReportsNotConvergedWithTheLastPoint) {
  simulate(RobotType::ur5, 109, 100, 1e-5);
  LmOptions options;
  options.max_iterations = 1;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(nominal_start(RobotType::ur5), nullptr, lm().train.samples(), options,
                                       &lm().workspace, &lm().result));
  EXPECT_EQ(status, Status::not_converged);
  EXPECT_EQ(lm().result.termination, LmTermination::max_iterations);
  EXPECT_EQ(lm().result.iterations, 1);
  EXPECT_GT(lm().result.rms_m, 0.0);
  EXPECT_TRUE(all_finite(lm().result.sigma));
  const char* name = nullptr;
  EXPECT_NO_HEAP(name = lm_termination_name(LmTermination::max_iterations));
  EXPECT_STREQ(name, "max_iterations");
}

// The step's system and factor, the trial point's normal equations and the identifiability
// scratch share one block (never alive together): LmWorkspace is the side-by-side layout it had
// before less one LmStepScratch and one NormalEquations (26.6 kB at 33 parameters). The
// goldens (LmGolden, CaptureJob) show the same bits.
TEST(Lm, WorkspaceSharesOneBlockAmongStepTrialAndAnalysis) {
  struct SideBySide {  // LmWorkspace until session 7, with the points it now also holds
    NormalEquations normal;
    LmPoint point;
    LmPoint trial_point;
    NormalEquations trial;
    LmStepScratch step;
    IdentifiabilityWorkspace identifiability;
    Span<JointTrig> joint_trig;
    Span<TargetBlock> target_blocks;
  };
  EXPECT_GE(sizeof(IdentifiabilityWorkspace), sizeof(LmStepScratch));
  EXPECT_GE(sizeof(IdentifiabilityWorkspace), sizeof(NormalEquations));
  EXPECT_EQ(sizeof(LmWorkspace), sizeof(SideBySide) - sizeof(LmStepScratch) - sizeof(NormalEquations));
}

// Sharing is only sound if no scratch set reads what the block held before: a block full
// of NaN from an earlier use gives the same bits as a clean run.
TEST(Lm, SharedScratchCarriesNothingBetweenUses) {
  simulate(RobotType::ur5, 110, 120, 1e-5);
  const RobotModel start = nominal_start(RobotType::ur5);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status =
                     calibrate_lm(start, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok);
  const LmResult first = lm().result;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  IdentifiabilityWorkspace* poisoned = lm().workspace.scratch.open_identifiability();
  poisoned->scaled.setConstant(nan);
  poisoned->rotated.setConstant(nan);
  poisoned->null_basis.setConstant(nan);
  poisoned->eigenvalues.setConstant(nan);
  LmStepScratch* step = lm().workspace.scratch.open_step();
  step->system.setConstant(nan);
  step->factorization.upper.setConstant(nan);
  NormalEquations* trial = lm().workspace.scratch.open_trial(Span<TargetBlock>());
  trial->jtwj.setConstant(nan);
  trial->jtwr.setConstant(nan);
  trial->loss_sum_m2 = nan;
  EXPECT_NO_HEAP(status =
                     calibrate_lm(start, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(first.identifiability.kept_mask, lm().result.identifiability.kept_mask);
  EXPECT_EQ(first.iterations, lm().result.iterations);
  EXPECT_EQ(first.rms_m, lm().result.rms_m);
  for (int i = 0; i < model_param_count(kSixJoints); ++i)
    EXPECT_EQ(to_params(first.model)(i), to_params(lm().result.model)(i));
  for (int i = 0; i < kFullParamCount; ++i) EXPECT_EQ(first.sigma(i), lm().result.sigma(i));
  EXPECT_TRUE(first.base_to_tracker.translation_m == lm().result.base_to_tracker.translation_m);
  EXPECT_TRUE(first.base_to_tracker.rotation == lm().result.base_to_tracker.rotation);
}

// A parameter the start's analysis keeps and the analysis after the first step drops goes back
// to its start value: theta6 turns the tool point about joint 6's axis, which a6 = 1 mm holds
// off at the start; the first step takes a6 to the truth's 0, where theta6 moves nothing.
TEST(Lm, WhatTheSecondAnalysisDropsGoesBackToItsStart) {
  RobotModel truth = nominal_model(RobotType::ur5);
  truth.tool_m << 0.0, 0.0, 0.1;
  RobotModel start = truth;
  start.joints[5].a_m = 1e-3;
  auto& s = lm();
  s.train.clear();
  Random random(5206);
  test::fill_dataset(truth, test::example_base_to_tracker(), 60, 10e-6, &random, &s.train);
  LmOptions options;
  options.params = LmParamSet::custom;
  options.custom_mask =
      param_bit(model_param_index(5, DhField::theta_offset)) | param_bit(model_param_index(5, DhField::a));
  for (int i = 0; i < kBaseParamCount; ++i) options.custom_mask |= param_bit(model_param_count(kSixJoints) + i);
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), options, &s.workspace, &s.result), Status::ok);
  const int theta6 = model_param_index(5, DhField::theta_offset);
  EXPECT_FALSE(mask_has(s.result.identifiability.kept_mask, theta6));
  EXPECT_EQ(s.result.model.joints[5].theta_offset_rad, start.joints[5].theta_offset_rad);
  EXPECT_LT(std::fabs(s.result.model.joints[5].a_m), 1e-5);
}

}  // namespace
}  // namespace hivecal::lm_test
