// Several reflectors per pose (issue 11): LM estimates every target's tool point together with
// the geometry, and the orientation information that several targets carry makes parameters
// identifiable that one target cannot determine on the same poses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "hivecal/model/full_params.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/identifiability.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/target_data.hpp"

namespace hivecal::lm_targets_test {
namespace {

/// This file's training and fresh sets, workspace and result.
test::LmTestStorage<600, LmWorkspaceWithTargets>& lm() {
  static test::LmTestStorage<600, LmWorkspaceWithTargets> storage;
  return storage;
}
Dataset<600>& one_target_set() {
  static Dataset<600> dataset;
  return dataset;
}

const Vec3 kTool_m(0.012, -0.006, 0.17);

/// A UR5 truth with three reflectors; `pose_count` training poses with noise_m, 100 fresh ones.
RobotModel simulate(std::uint64_t seed, std::size_t pose_count, double noise_m, RigidTransform* base) {
  Random random(seed);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
  *base = test::example_base_to_tracker();
  lm().train.clear();
  lm().fresh.clear();
  test::fill_target_dataset(truth, *base, pose_count, 3, noise_m, &random, &lm().train);
  test::fill_target_dataset(truth, *base, 100, 3, 0.0, &random, &lm().fresh);
  return truth;
}

/// The nominal UR5 with target 1 guessed on the flange axis; the other targets unknown (0).
RobotModel start_model() {
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.17);
  return start;
}

/// Largest distance [m] between calibrated and true points over the fresh samples (every target).
double worst_fresh_error_m(const RobotModel& truth, const RigidTransform& base, const LmResult& r) {
  double worst_m = 0.0;
  for (const Sample& s : lm().fresh.samples()) {
    const Vec3 predicted = r.base_to_tracker.apply(fk_sample_point(r.model, s));
    worst_m = std::fmax(worst_m, (predicted - base.apply(fk_sample_point(truth, s))).norm());
  }
  return worst_m;
}

/// Largest distance [m] between a target's tool point in frame 5 (what joint 6's parameters
/// and the tool point determine together) of the calibration and of the truth, over q6.
double worst_tool_error_m(const RobotModel& truth, const RobotModel& calibrated, int target) {
  RobotModel a = truth;
  RobotModel b = calibrated;
  a.tool_m = target_tool(truth, target);
  b.tool_m = target_tool(calibrated, target);
  double worst_m = 0.0;
  for (double q6 = -3.0; q6 <= 3.0; q6 += 0.5) {
    worst_m = std::fmax(worst_m, (test::tool_in_frame5(a, q6) - test::tool_in_frame5(b, q6)).norm());
  }
  return worst_m;
}

TEST(SeveralTargets, DatasetKeepsTheTargetAndRefusesOneOutOfRange) {
  Dataset<4> dataset;
  const JointVector q = JointVector::Zero();
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = dataset.add(q, Vec3(1.0, 0.0, 0.0), 2));
  EXPECT_EQ(status, Status::ok);
  EXPECT_EQ(dataset.samples()[0].target, 2);
  EXPECT_EQ(target_count(dataset.samples()), 3);
  EXPECT_EQ(dataset.add(q, Vec3::Zero(), kMaxTargets), Status::invalid_argument);
  EXPECT_EQ(dataset.add(q, Vec3::Zero(), -1), Status::invalid_argument);
  EXPECT_EQ(dataset.size(), 1u);
  EXPECT_EQ(target_count(Span<const Sample>{}), 1);
}

// Target 1 is fk_tool_point bit for bit; the others use their own tool point.
TEST(SeveralTargets, TargetPointUsesTheTargetsToolPoint) {
  Random random(5);
  const RobotModel model = test::with_plate(nominal_model(RobotType::ur10), kTool_m);
  const JointVector q = test::random_joints(&random);
  EXPECT_EQ(fk_target_point(model, q, 0), fk_tool_point(model, q));
  const RigidTransform flange = fk_flange(model, q);
  for (int target = 1; target < 3; ++target) {
    EXPECT_LE((fk_target_point(model, q, target) - flange.apply(target_tool(model, target))).norm(), 1e-14);
    EXPECT_GT((fk_target_point(model, q, target) - fk_tool_point(model, q)).norm(), 0.05);
  }
}

// Without noise, from the nominal table and no idea of targets 2 and 3: every target's
// points reproduced to 1e-9 m on fresh poses, every tool point (in frame 5) to 1e-9 m.
TEST(SeveralTargets, LmRecoversEveryToolPointExactlyWithoutNoise) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    RigidTransform base;
    const RobotModel truth = simulate(seed, 40, 0.0, &base);
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate_lm(start_model(), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace,
                                         &lm().result));
    ASSERT_EQ(status, Status::ok) << "seed " << seed << ": " << status_message(status);
    const double worst_m = worst_fresh_error_m(truth, base, lm().result);
    EXPECT_LE(worst_m, 1e-9) << "seed " << seed;
    for (int target = 0; target < 3; ++target) {
      EXPECT_LE(worst_tool_error_m(truth, lm().result.model, target), 1e-9)
          << "seed " << seed << " target " << target + 1;
    }
    if (seed == 1) {
      std::printf("3 targets x 40 poses: %d of 33 estimated + 6 tool coordinates, %d iterations, worst %.3g m\n",
                  lm().result.identifiability.kept_count(), lm().result.iterations, worst_m);
    }
  }
}

// With 10 um noise: the points within the noise, the other targets' tool points with sigmas
// that cover their error.
TEST(SeveralTargets, LmRecoversEveryToolPointWithinNoise) {
  const double noise_m = 1e-5;
  for (std::uint64_t seed = 11; seed <= 13; ++seed) {
    RigidTransform base;
    const RobotModel truth = simulate(seed, 80, noise_m, &base);
    ASSERT_EQ(calibrate_lm(start_model(), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
              Status::ok);
    const double worst_m = worst_fresh_error_m(truth, base, lm().result);
    EXPECT_LE(worst_m, 3.0 * noise_m) << "seed " << seed;
    EXPECT_NEAR(lm().result.residual_sigma_m, noise_m, 0.15 * noise_m) << "seed " << seed;
    for (int target = 1; target < 3; ++target) {
      const Vec3& sigma = lm().result.other_tools_sigma_m[target - 1];
      EXPECT_GT(sigma.minCoeff(), 0.0);
      EXPECT_LT(sigma.maxCoeff(), 10.0 * noise_m);
      EXPECT_LE(worst_tool_error_m(truth, lm().result.model, target), 5.0 * noise_m) << "seed " << seed;
    }
    if (seed == 11) {
      std::printf("noise 10 um: worst fresh %.3g m, sigma tool2 %.3g %.3g %.3g m\n", worst_m,
                  lm().result.other_tools_sigma_m[0].x(), lm().result.other_tools_sigma_m[0].y(),
                  lm().result.other_tools_sigma_m[0].z());
    }
  }
}

// The other targets' sigmas are what they claim: over 40 noise draws on the same poses (joint
// 6 at its nominal values, so that the tool points themselves are the identifiable ones), the
// RMS error of each tool coordinate is its mean sigma within the spread of 40 draws.
TEST(SeveralTargets, ToolPointSigmasMatchTheirScatter) {
  const double noise_m = 1e-5;
  Random random(41);
  RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
  truth.joints[5] = nominal_model(RobotType::ur5).joints[5];
  const RigidTransform base = test::example_base_to_tracker();
  JointVector poses[30];
  for (JointVector& q : poses) q = test::random_joints(&random);
  constexpr int kDraws = 40;
  Vec3 squared_error_m2[2] = {Vec3::Zero(), Vec3::Zero()};
  Vec3 sigma_sum_m[2] = {Vec3::Zero(), Vec3::Zero()};
  for (int draw = 0; draw < kDraws; ++draw) {
    Random noise(1000 + static_cast<std::uint64_t>(draw));
    lm().train.clear();
    for (const JointVector& q : poses) {
      for (int target = 0; target < 3; ++target) {
        const Vec3 point_m = base.apply(fk_target_point(truth, q, target)) + noise_m * test::gaussian_vector(&noise);
        ASSERT_EQ(lm().train.add(q, point_m, target), Status::ok);
      }
    }
    ASSERT_EQ(calibrate_lm(start_model(), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
              Status::ok);
    for (int k = 0; k < 2; ++k) {
      squared_error_m2[k] += (lm().result.model.other_tools_m[k] - truth.other_tools_m[k]).cwiseAbs2();
      sigma_sum_m[k] += lm().result.other_tools_sigma_m[k];
    }
  }
  for (int k = 0; k < 2; ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      const double rms_m = std::sqrt(squared_error_m2[k](axis) / kDraws);
      const double sigma_m = sigma_sum_m[k](axis) / kDraws;
      std::printf("%s: RMS error %.3g m, mean sigma %.3g m\n", other_tool_param_name(k + 1, axis), rms_m, sigma_m);
      EXPECT_GT(rms_m, 0.6 * sigma_m) << other_tool_param_name(k + 1, axis);
      EXPECT_LT(rms_m, 1.5 * sigma_m) << other_tool_param_name(k + 1, axis);
    }
  }
}

/// The identifiability report of `samples` at the truth, every parameter free.
IdentifiabilityReport report_at(const RobotModel& truth, const RigidTransform& base, Span<const Sample> samples) {
  static NormalEquations eq;
  static TargetBlock blocks[kMaxTargets - 1];
  eq.targets = Span<TargetBlock>(blocks, kMaxTargets - 1);
  static IdentifiabilityWorkspace ws;
  IdentifiabilityReport report;
  EXPECT_EQ(accumulate_normal_equations(truth, base, samples, PointLoss{}, &eq), Status::ok);
  EXPECT_EQ(
      analyze_identifiability(eq.jtwj, rigid_params_mask(kSixJoints), kDefaultIdentifiabilityThreshold, &ws, &report),
      Status::ok);
  return report;
}

std::string names_of(ParamMask mask) {
  std::string names;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(mask, i)) names += std::string(names.empty() ? "" : " ") + full_param_name(i, kSixJoints);
  }
  return names;
}

// The same poses, measured on one target or on three. With the tool points free, three
// reflectors fix the flange pose (6 numbers) where one fixes a point (3): 7 poses give one
// target 21 equations, too few for the 25 parameters a UR5 identifies, and three targets 63
// - 6 tool coordinates. What one target cannot determine there: named below and asserted.
TEST(SeveralTargets, SeveralTargetsIdentifyMoreOnTheSamePoses) {
  RigidTransform base;
  const RobotModel truth = simulate(21, 7, 0.0, &base);
  test::copy_target_one(lm().train, &one_target_set());
  ASSERT_EQ(one_target_set().size(), 7u);
  IdentifiabilityReport one;
  IdentifiabilityReport three;
  EXPECT_NO_HEAP(one = report_at(truth, base, one_target_set().samples()));
  EXPECT_NO_HEAP(three = report_at(truth, base, lm().train.samples()));
  const ParamMask gained = three.kept_mask & ~one.kept_mask;
  std::printf("7 poses: 1 target keeps %d, 3 targets keep %d; gained: %s; lost: %s\n", one.kept_count(),
              three.kept_count(), names_of(gained).c_str(), names_of(one.kept_mask & ~three.kept_mask).c_str());
  EXPECT_LE(one.kept_count(), 21);
  EXPECT_EQ(three.kept_count(), 25);  // every parameter 40 poses of one target identify (above)
  EXPECT_EQ(one.kept_mask & ~three.kept_mask, 0u);
  EXPECT_EQ(names_of(gained), "a1 theta2 theta3 theta5");  // dropped for one target, estimated for three
  // Tool-down poses (joint 6 vertical) hide one more combination, for one target and for
  // three alike: free tool points absorb any flange rotation, so no orientation is gained there.
  lm().train.clear();
  Random random(22);
  test::fill_target_dataset(truth, base, 40, 3, 0.0, &random, &lm().train, true);
  test::copy_target_one(lm().train, &one_target_set());
  EXPECT_NO_HEAP(one = report_at(truth, base, one_target_set().samples()));
  EXPECT_NO_HEAP(three = report_at(truth, base, lm().train.samples()));
  std::printf("40 tool-down poses: 1 target keeps %d (%s dropped), 3 targets keep %d\n", one.kept_count(),
              names_of(rigid_params_mask(kSixJoints) & ~one.kept_mask).c_str(), three.kept_count());
  EXPECT_EQ(three.kept_mask, one.kept_mask);
}

// ABC/GSA's precomputed link-length cost with each sample's own target tool (fixed in that
// stage) equals the generic refit cost, and the other tool points survive model_for.
TEST(SeveralTargets, LinkLengthCostUsesEachSamplesToolPoint) {
  RigidTransform base;
  const RobotModel truth = simulate(31, 40, 1e-5, &base);
  static Paper6Cost<300> cost;
  RobotModel start = nominal_model(RobotType::ur5);
  for (int target = 0; target < 3; ++target) target_tool(&start, target) = target_tool(truth, target);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = cost.build(start, lm().train.samples()));
  ASSERT_EQ(status, Status::ok);
  Random random(32);
  for (int trial = 0; trial < 20; ++trial) {
    LinkLengths lengths_m = link_lengths(trial == 0 ? truth : start, link_length_set(start));
    for (std::size_t k = 0; k < lengths_m.count && trial > 1; ++k) lengths_m.values_m(k) += random.uniform(-2e-3, 2e-3);
    double fast_m = 0.0;
    RigidTransform fast_base;
    EXPECT_NO_HEAP(status = cost.evaluate(lengths_m, &fast_m, &fast_base));
    ASSERT_EQ(status, Status::ok);
    const RobotModel model = cost.model_for(lengths_m.data());
    EXPECT_EQ(model.other_tools_m[1], truth.other_tools_m[1]);
    double generic_m = 0.0;
    RigidTransform generic_base;
    ASSERT_EQ(
        evaluate_cost(model, lm().train.samples(), CostKind::mean_abs_3d, BaseFrame::refit, &generic_base, &generic_m),
        Status::ok);
    EXPECT_NEAR(fast_m, generic_m, 1e-11 * generic_m) << "trial " << trial;
  }
}

}  // namespace
// A workspace without target blocks (the firmware's: one reflector) refuses a set of several
// targets whose tool points are to be estimated, instead of writing past its storage; a
// normal-equation sum without blocks refuses it too.
TEST(LmTargets, AWorkspaceWithoutTargetBlocksRefusesSeveralTargets) {
  RigidTransform base;
  const RobotModel truth = simulate(77, 20, 0.0, &base);
  static LmWorkspace bare;  // no target_blocks
  const LmOptions options;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(start_model(), &base, lm().train.samples(), options, &bare, &lm().result));
  EXPECT_EQ(status, Status::dimension_out_of_range);
  static NormalEquations eq;
  eq.targets = Span<TargetBlock>();
  EXPECT_NO_HEAP(status = accumulate_normal_equations(truth, base, lm().train.samples(), PointLoss{}, &eq));
  EXPECT_EQ(status, Status::dimension_out_of_range);
  // With the blocks it runs.
  EXPECT_NO_HEAP(status =
                     calibrate_lm(start_model(), &base, lm().train.samples(), options, &lm().workspace, &lm().result));
  EXPECT_EQ(status, Status::ok);
}

}  // namespace hivecal::lm_targets_test
