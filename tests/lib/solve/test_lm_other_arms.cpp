// Any 6-axis arm: the link-length set, LM recovery and the identifiability analysis on
// non-UR arms (IRB120-, KR6 R900- and LR Mate 200iD-like tables, testkit/other_arms.hpp), and
// ABC on the link lengths through the calibration job.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/other_arms.hpp"

namespace hivecal::lm_other_arms_test {
namespace {

using test::OtherArm;

/// This file's training and fresh sets, workspace and result.
test::LmTestStorage<300>& lm() {
  static test::LmTestStorage<300> storage;
  return storage;
}

/// The nominal table with the reflector guessed on the flange axis.
RobotModel start_of(OtherArm arm) {
  RobotModel start = test::other_arm_model(arm);
  start.tool_m = Vec3(0.0, 0.0, 0.1);
  return start;
}

/// Largest distance [m] between the calibrated and the true tool point over the fresh poses,
/// both in the tracker frame (the identifiable part of the geometry is what predicts points).
double worst_fresh_error_m(const RobotModel& truth, const RigidTransform& base, const LmResult& r) {
  double worst_m = 0.0;
  for (const Sample& s : lm().fresh.samples()) {
    const Vec3 predicted = r.base_to_tracker.apply(fk_tool_point(r.model, s.q_rad));
    worst_m = std::fmax(worst_m, (predicted - base.apply(fk_tool_point(truth, s.q_rad))).norm());
  }
  return worst_m;
}

double rms_fresh_error_m(const RobotModel& truth, const RigidTransform& base, const LmResult& r) {
  double sum_m2 = 0.0;
  for (const Sample& s : lm().fresh.samples()) {
    const Vec3 predicted = r.base_to_tracker.apply(fk_tool_point(r.model, s.q_rad));
    sum_m2 += (predicted - base.apply(fk_tool_point(truth, s.q_rad))).squaredNorm();
  }
  return std::sqrt(sum_m2 / static_cast<double>(lm().fresh.size()));
}

/// A session of `arm`: truth, `count` training samples with noise_m, 200 noise-free fresh poses.
RobotModel simulate(OtherArm arm, std::uint64_t seed, std::size_t count, double noise_m, RigidTransform* base) {
  Random random(seed);
  const RobotModel truth = test::other_arm_truth(arm, &random);
  *base = test::example_base_to_tracker();
  lm().train.clear();
  lm().fresh.clear();
  test::fill_other_arm(truth, *base, count, noise_m, &random, &lm().train);
  test::fill_other_arm(truth, *base, 200, 0.0, &random, &lm().fresh);
  return truth;
}

TEST(OtherArms, LinkLengthSetIsEveryNonZeroDAndA) {
  struct Case {
    OtherArm arm;
    std::size_t count;
    int index[kMaxLinkLengths];
  };
  const Case cases[] = {
      {OtherArm::irb120,
       5,
       {model_param_index(0, DhField::d), model_param_index(1, DhField::a), model_param_index(2, DhField::a),
        model_param_index(3, DhField::d), model_param_index(5, DhField::d)}},
      {OtherArm::kr6_r900,
       6,
       {model_param_index(0, DhField::d), model_param_index(0, DhField::a), model_param_index(1, DhField::a),
        model_param_index(2, DhField::a), model_param_index(3, DhField::d), model_param_index(5, DhField::d)}},
      {OtherArm::lrmate200id,
       6,
       {model_param_index(0, DhField::d), model_param_index(0, DhField::a), model_param_index(1, DhField::a),
        model_param_index(2, DhField::a), model_param_index(3, DhField::d), model_param_index(5, DhField::d)}},
  };
  for (const Case& c : cases) {
    LinkLengthSet set;
    EXPECT_NO_HEAP(set = link_length_set(test::other_arm_model(c.arm)));
    ASSERT_EQ(set.count, c.count) << test::other_arm_name(c.arm);
    EXPECT_TRUE(set.has_d1());
    for (std::size_t k = 0; k < c.count; ++k)
      EXPECT_EQ(set.param_index[k], c.index[k]) << full_param_name(c.index[k], kSixJoints);
    ParamMask mask = 0;
    EXPECT_NO_HEAP(mask = lm_param_mask(LmParamSet::link_lengths, 0, test::other_arm_model(c.arm)));
    EXPECT_EQ(mask_count(mask), static_cast<int>(c.count) + kBaseParamCount);
  }
  RobotModel no_d1 = test::other_arm_model(OtherArm::irb120);
  no_d1.joints[0].d_m = 0.0;
  EXPECT_FALSE(link_length_set(no_d1).has_d1());
  EXPECT_EQ(link_length_set(RobotModel{}).count, 0u);
}

// Without noise, LM from the nominal table reproduces the true points to 1e-9 m on fresh
// poses: whatever it could not separate, it did not need to.
TEST(OtherArms, LmRecoversTheTruthExactlyWithoutNoise) {
  for (OtherArm arm : test::kOtherArms) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      RigidTransform base;
      const RobotModel truth = simulate(arm, 1000 * seed + static_cast<std::uint64_t>(arm), 120, 0.0, &base);
      Status status = Status::ok;
      EXPECT_NO_HEAP(status = calibrate_lm(start_of(arm), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace,
                                           &lm().result));
      ASSERT_EQ(status, Status::ok) << test::other_arm_name(arm) << " seed " << seed << ": " << status_message(status);
      const double worst_m = worst_fresh_error_m(truth, base, lm().result);
      EXPECT_LE(worst_m, 1e-9) << test::other_arm_name(arm) << " seed " << seed;
      if (seed == 1) {
        std::printf("%s: %d of %d estimated, worst fresh error %.3g m\n", test::other_arm_name(arm),
                    lm().result.identifiability.kept_count(), mask_count(lm().result.identifiability.free_mask),
                    worst_m);
      }
    }
  }
}

// With 10 um noise the calibrated arm predicts the true points within the noise.
TEST(OtherArms, LmRecoversTheIdentifiableGeometryWithinNoise) {
  const double noise_m = 1e-5;
  for (OtherArm arm : test::kOtherArms) {
    for (std::uint64_t seed = 11; seed <= 14; ++seed) {
      RigidTransform base;
      const RobotModel truth = simulate(arm, 1000 * seed + static_cast<std::uint64_t>(arm), 200, noise_m, &base);
      ASSERT_EQ(calibrate_lm(start_of(arm), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
                Status::ok);
      const double rms_m = rms_fresh_error_m(truth, base, lm().result);
      EXPECT_LT(rms_m, noise_m) << test::other_arm_name(arm) << " seed " << seed;
      if (seed == 11)
        std::printf("%s: fresh-pose RMS error %.2f um (noise 10 um per axis)\n", test::other_arm_name(arm),
                    rms_m * 1e6);
      EXPECT_NEAR(lm().result.residual_sigma_m, noise_m, 0.2 * noise_m) << test::other_arm_name(arm);
      // and the start was far off: the fit did something
      RigidTransform nominal_base;
      ASSERT_EQ(fit_base_to_tracker(start_of(arm), lm().train.samples(), &nominal_base), Status::ok);
      LmResult nominal;
      nominal.model = start_of(arm);
      nominal.base_to_tracker = nominal_base;
      EXPECT_GT(rms_fresh_error_m(truth, base, nominal), 50.0 * rms_m);
    }
  }
}

// Arms described in modified DH, with a base offset (alpha_0, a_0) and the truth perturbed in
// the modified rows: LM on the converted model reproduces the true points exactly.
TEST(OtherArms, LmRecoversModifiedDhTruthsExactly) {
  for (OtherArm arm : test::kOtherArms) {
    ModifiedDhRow nominal[kSixJoints];
    Vec3 tool_m;
    test::other_arm_modified(arm, ModifiedDhBase{0.02, -0.015}, nominal, &tool_m);
    Random random(500 + static_cast<std::uint64_t>(arm));
    ModifiedDhRow truth[kSixJoints];
    for (int j = 0; j < kSixJoints; ++j) {
      truth[j] = nominal[j];
      truth[j].theta_offset_rad += 3e-4 * random.normal();
      truth[j].d_m += 3e-4 * random.normal();
      truth[j].a_prev_m += 3e-4 * random.normal();
      if (nominal[j].alpha_prev_rad != 0.0)
        truth[j].alpha_prev_rad += 3e-4 * random.normal();  // parallel stays parallel
    }
    const Vec3 true_tool_m(0.009, 0.006, 0.097);
    const RigidTransform base = test::example_base_to_tracker();
    lm().train.clear();
    lm().fresh.clear();
    for (std::size_t i = 0; i < 320; ++i) {
      const JointVector q = test::other_arm_joints(&random);
      (void)(i < 120 ? lm().train : lm().fresh).add(q, base.apply(test::modified_chain_point(truth, true_tool_m, q)));
    }
    RobotModel start;
    ModifiedDhBase start_base;
    ASSERT_EQ(model_from_modified_dh(nominal, Vec3(0.0, 0.0, 0.1), &start, &start_base), Status::ok);
    Status status = Status::ok;
    EXPECT_NO_HEAP(status =
                       calibrate_lm(start, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
    ASSERT_EQ(status, Status::ok) << test::other_arm_name(arm);
    double worst_m = 0.0;
    for (const Sample& s : lm().fresh.samples()) {
      const Vec3 predicted = lm().result.base_to_tracker.apply(fk_tool_point(lm().result.model, s.q_rad));
      worst_m = std::fmax(worst_m, (predicted - s.point_m).norm());
    }
    std::printf("%s (modified DH, base offset): worst fresh error %.3g m\n", test::other_arm_name(arm), worst_m);
    EXPECT_LE(worst_m, 1e-9) << test::other_arm_name(arm);
  }
}

/// Whether the report dropped one of `a`, `b` with the other in its combination.
bool trades(const IdentifiabilityReport& report, int a, int b) {
  for (int d = 0; d < report.dropped_count; ++d) {
    const DroppedParam& p = report.dropped[d];
    if (p.index != a && p.index != b) continue;
    const int other = p.index == a ? b : a;
    for (int c = 0; c < kNullComponentCount; ++c) {
      if (p.component_index[c] == other) return true;
    }
  }
  return false;
}

// Parallel joints 2 and 3 (every arm here): their d offsets slide along the same axis
// direction, so only their sum is determined; the analysis finds that from the numbers.
TEST(OtherArms, IdentifiabilityFindsTheParallelAxisCombination) {
  for (OtherArm arm : test::kOtherArms) {
    RigidTransform base;
    (void)simulate(arm, 77, 200, 1e-5, &base);
    ASSERT_EQ(calibrate_lm(start_of(arm), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
              Status::ok);
    const IdentifiabilityReport& report = lm().result.identifiability;
    const int d2 = model_param_index(1, DhField::d);
    const int d3 = model_param_index(2, DhField::d);
    EXPECT_TRUE(trades(report, d2, d3)) << test::other_arm_name(arm);
    EXPECT_FALSE(mask_has(report.kept_mask, d2) && mask_has(report.kept_mask, d3)) << test::other_arm_name(arm);
    // d1 trades against the base height on every arm
    EXPECT_FALSE(mask_has(report.kept_mask, model_param_index(0, DhField::d)) &&
                 mask_has(report.kept_mask, base_translation_param_index(kSixJoints, 2)));
    std::printf("%s: dropped", test::other_arm_name(arm));
    for (int d = 0; d < report.dropped_count; ++d)
      std::printf(" %s", full_param_name(report.dropped[d].index, kSixJoints));
    std::printf("\n");
  }
}

using OtherArmWorkspace = CalibrationWorkspace<300, double, 40, 300, 0, kMaxLinkLengths>;

// GSA and ABC on the link lengths of a non-UR arm through the job (Table 1: GSA, ABC, LM):
// both far better than the start, moving nothing but the link lengths (from the baseline).
TEST(OtherArms, GsaAndAbcOnTheLinkLengthsImproveANonUrArm) {
  for (OtherArm arm : test::kOtherArms) {
    Random random(31 + static_cast<std::uint64_t>(arm));
    const RobotModel nominal = test::other_arm_model(arm);
    const LinkLengthSet set = link_length_set(nominal);
    LinkLengths lengths_m = link_lengths(nominal, set);
    for (std::size_t k = 0; k < lengths_m.count; ++k) lengths_m.values_m(k) += 6e-4 * random.normal();
    const RobotModel truth = with_link_lengths(nominal, set, lengths_m.data());
    lm().train.clear();
    test::fill_other_arm(truth, test::example_base_to_tracker(), 200, 1e-5, &random, &lm().train);
    CalibrationOptions options;
    options.method = CalibrationMethod::all;
    options.params = CalibrationParams::paper;
    options.abc_food_sources = 40;
    options.abc_cycles = 150;
    options.gsa_agents = 40;
    options.gsa_iterations = 150;
    static OtherArmWorkspace ws;
    static CalibrationResult r;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate(nominal, &lm().train, options, &ws, &r));
    ASSERT_EQ(status, Status::ok) << test::other_arm_name(arm) << ": " << status_message(status);
    ASSERT_EQ(r.stage_count, 3u);
    ASSERT_EQ(r.stages[0].solver, CalibrationSolver::gsa);
    ASSERT_EQ(r.stages[1].solver, CalibrationSolver::abc);
    const double baseline_m = r.baseline.test.mae(ErrorAxis::norm_3d);
    const double gsa_m = r.stages[0].test.mae(ErrorAxis::norm_3d);
    const double abc_m = r.stages[1].test.mae(ErrorAxis::norm_3d);
    const double lm_m = r.stages[2].test.mae(ErrorAxis::norm_3d);
    std::printf("%s: %zu lengths, test MAE nominal %.1f um, GSA %.1f um, ABC %.1f um, LM %.1f um\n",
                test::other_arm_name(arm), set.count, baseline_m * 1e6, gsa_m * 1e6, abc_m * 1e6, lm_m * 1e6);
    // ABC and GSA search the lengths with the tool the baseline fitted at the nominal lengths
    // (the tool is taken as unknown): that fit's bias bounds them (50-190 um here, the tool
    // being exact in this simulation); LM estimates the tool with the lengths.
    EXPECT_LT(gsa_m, 0.2 * baseline_m) << test::other_arm_name(arm);
    EXPECT_LT(abc_m, 0.2 * baseline_m) << test::other_arm_name(arm);
    EXPECT_LT(lm_m, 3e-5) << test::other_arm_name(arm);
    const ModelParams before = to_params(r.baseline.model);  // nominal joints, the fitted tool
    for (int stage = 0; stage < 2; ++stage) {
      const ModelParams after = to_params(r.stages[stage].model);
      for (int i = 0; i < model_param_count(kSixJoints); ++i) {
        bool length = false;
        for (std::size_t k = 0; k < set.count; ++k) length = length || set.param_index[k] == i;
        if (!length) {
          EXPECT_EQ(after(i), before(i)) << full_param_name(i, kSixJoints);
        }
      }
    }
  }
}

// The precomputed cost on other column layouts (IRB120: four stored columns, the generic
// pass; d1 zero: every length stored; KR6: five, the unrolled pass) equals the generic
// refit cost anywhere in the box, with the same base transform.
TEST(OtherArms, LinkLengthCostEqualsTheGenericRefitCost) {
  RobotModel no_d1 = test::other_arm_model(OtherArm::irb120);
  no_d1.joints[0].d_m = 0.0;
  const RobotModel arms[] = {test::other_arm_model(OtherArm::irb120), no_d1, test::other_arm_model(OtherArm::kr6_r900)};
  static Paper6Cost<300, double, kMaxLinkLengths> cost;
  Random random(606);
  for (const RobotModel& nominal : arms) {
    const RobotModel truth = test::perturbed_keeping_parallel(nominal, &random, 3e-4, 3e-4, Vec3(0.01, 0.0, 0.1));
    lm().train.clear();
    test::fill_other_arm(truth, test::example_base_to_tracker(), 150, 1e-5, &random, &lm().train);
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = cost.build(nominal, lm().train.samples()));
    ASSERT_EQ(status, Status::ok);
    ASSERT_EQ(cost.dimension(), link_length_set(nominal).count);
    LinkLengthBox box;
    ASSERT_EQ(link_length_box(nominal, 2e-3, &box), Status::ok);
    for (int trial = 0; trial < 20; ++trial) {
      LinkLengths lengths_m = link_lengths(nominal);
      for (std::size_t k = 0; k < lengths_m.count && trial > 0; ++k) {
        lengths_m.values_m(k) = random.uniform(box.lower_m[k], box.upper_m[k]);
      }
      double fast_m = 0.0;
      RigidTransform fast_base;
      EXPECT_NO_HEAP(status = cost.evaluate(lengths_m, &fast_m, &fast_base));
      ASSERT_EQ(status, Status::ok);
      double generic_m = 0.0;
      RigidTransform generic_base;
      ASSERT_EQ(evaluate_cost(cost.model_for(lengths_m.data()), lm().train.samples(), CostKind::mean_abs_3d,
                              BaseFrame::refit, &generic_base, &generic_m),
                Status::ok);
      EXPECT_NEAR(fast_m, generic_m, 1e-11 * generic_m) << "trial " << trial << ", " << cost.dimension() << " lengths";
      EXPECT_LT((fast_base.rotation - generic_base.rotation).norm(), 1e-13);
      EXPECT_LT((fast_base.translation_m - generic_base.translation_m).norm(), 1e-12);
    }
    LinkLengths wrong;
    wrong.count = cost.dimension() + 1;
    double mae_m = 0.0;
    EXPECT_EQ(cost.evaluate(wrong, &mae_m, nullptr), Status::invalid_argument);
  }
}

// A firmware-sized workspace (six lengths) refuses an arm with more, with a status.
TEST(OtherArms, SixLengthWorkspaceRefusesMoreLengths) {
  RobotModel seven = test::other_arm_model(OtherArm::kr6_r900);
  seven.joints[4].d_m = 0.01;  // a seventh non-zero length
  ASSERT_EQ(link_length_set(seven).count, 7u);
  Random random(5);
  lm().train.clear();
  test::fill_other_arm(seven, test::example_base_to_tracker(), 60, 0.0, &random, &lm().train);
  static Paper6Cost<300> six;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = six.build(seven, lm().train.samples()));
  EXPECT_EQ(status, Status::dimension_out_of_range);
  static Paper6Cost<300, double, kMaxLinkLengths> any;
  EXPECT_EQ(any.build(seven, lm().train.samples()), Status::ok);
  EXPECT_EQ(any.dimension(), 7u);
}

}  // namespace
}  // namespace hivecal::lm_other_arms_test
