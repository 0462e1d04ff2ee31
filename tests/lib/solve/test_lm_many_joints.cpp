// Arms of other than six revolute joints (testkit/other_arms.hpp: a KUKA LBR iiwa 14- and a
// Franka-like 7-axis arm, a UR10 on a linear rail, whose first joint is prismatic): their forward
// kinematics is the chain of their links, the Jacobian the derivative of it, and LM recovers
// perturbed truths exactly without noise and to the noise with it, over many perturbations (as
// test_lm_other_arms.cpp does for 6-axis arms); the job calibrates them; readings of another
// joint count are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/check_log_gtest.hpp"
#include "testkit/kinematics_checks.hpp"
#include "testkit/other_arms.hpp"

namespace hivecal::lm_many_joints_test {
namespace {

using test::ManyJointArm;

/// This file's training and fresh sets, workspace and result.
test::LmTestStorage<300>& lm() {
  static test::LmTestStorage<300> storage;
  return storage;
}

/// Skips the test in a build that holds six joints.
#define SKIP_WITHOUT_SEVEN_JOINTS() \
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of " << kMaxJoints << " joints holds no seven-joint arm"

/// The nominal table with the reflector guessed on the flange axis.
RobotModel start_of(ManyJointArm arm) {
  RobotModel start = test::many_joint_arm_model(arm);
  start.tool_m = Vec3(0.0, 0.0, start.tool_m.z());
  return start;
}

double fresh_error_m(const RobotModel& truth, const RigidTransform& base, const LmResult& r, bool worst) {
  double worst_m = 0.0;
  double sum_m2 = 0.0;
  for (const Sample& s : lm().fresh.samples()) {
    const Vec3 predicted = r.base_to_tracker.apply(fk_tool_point(r.model, s.q_rad));
    const double error_m = (predicted - base.apply(fk_tool_point(truth, s.q_rad))).norm();
    worst_m = std::fmax(worst_m, error_m);
    sum_m2 += error_m * error_m;
  }
  return worst ? worst_m : std::sqrt(sum_m2 / static_cast<double>(lm().fresh.size()));
}

/// A session of `arm`: truth, `count` training samples with noise_m, 200 noise-free fresh poses.
RobotModel simulate(ManyJointArm arm, std::uint64_t seed, std::size_t count, double noise_m, RigidTransform* base) {
  Random random(seed);
  const RobotModel truth = test::many_joint_arm_truth(arm, &random);
  *base = test::example_base_to_tracker();
  lm().train.clear();
  lm().fresh.clear();
  test::fill_many_joint_arm(arm, truth, *base, count, noise_m, &random, &lm().train);
  test::fill_many_joint_arm(arm, truth, *base, 200, 0.0, &random, &lm().fresh);
  return truth;
}

TEST(ManyJointArms, ForwardKinematicsIsTheChainOfTheirLinks) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  Random random(5301);
  for (ManyJointArm arm : test::kManyJointArms) {
    const RobotModel model = test::many_joint_arm_truth(arm, &random);
    ASSERT_EQ(check_joint_layout(model), Status::ok);
    EXPECT_EQ(model.joint_count, 7);
    EXPECT_EQ(all_revolute(model), arm != ManyJointArm::rail_ur10);
    for (int i = 0; i < 50; ++i) {
      const JointVector q = test::many_joint_arm_joints(arm, &random);
      const Vec3 expected_m = test::standard_chain_point(model, q);
      Vec3 point_m;
      EXPECT_NO_HEAP(point_m = fk_tool_point(model, q));
      EXPECT_LT((point_m - expected_m).norm(), 1e-12) << test::many_joint_arm_name(arm);
      EXPECT_LT((fk_flange(model, q).apply(model.tool_m) - expected_m).norm(), 1e-12);
      ToolPointJacobian jacobian;
      EXPECT_LT((tool_point_jacobian(model, q, &jacobian) - expected_m).norm(), 1e-12);
    }
  }
  // The Franka's nominal model is its modified-DH rows, converted: the same points.
  ModifiedDhRow rows[7];
  test::franka_rows(rows);
  const RobotModel franka = test::many_joint_arm_model(ManyJointArm::franka);
  for (int i = 0; i < 20; ++i) {
    const JointVector q = test::many_joint_arm_joints(ManyJointArm::franka, &random);
    EXPECT_LT((fk_tool_point(franka, q) - test::modified_chain_point(rows, Vec3(0.0, 0.0, 0.207), q)).norm(), 1e-12);
  }
}

TEST(ManyJointArms, JacobianIsTheDerivativeOfTheChain) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  Random random(5302);
  for (ManyJointArm arm : test::kManyJointArms) {
    const RobotModel model = test::many_joint_arm_truth(arm, &random);
    for (int i = 0; i < 10; ++i) {
      const JointVector q = test::many_joint_arm_joints(arm, &random);
      test::CheckLog log;
      test::jacobian_matches_central_differences_at(model, q, &log);
      EXPECT_CHECKS(log) << test::many_joint_arm_name(arm);
      ToolPointJacobian jacobian;
      (void)tool_point_jacobian(model, q, &jacobian);
      // A prismatic joint's reading moves the point as its d does (the column of its variable).
      if (arm == ManyJointArm::rail_ur10) {
        JointVector slid = q;
        slid(0) += 1e-6;
        const Vec3 numeric = (test::standard_chain_point(model, slid) - test::standard_chain_point(model, q)) / 1e-6;
        EXPECT_LT((numeric - jacobian.col(model_param_index(0, DhField::d))).norm(), 1e-7);
      }
    }
  }
}

// Without noise, LM from the nominal table reproduces the true points to 1e-9 m on fresh
// poses, for every perturbation drawn: whatever it could not separate, it did not need to.
TEST(ManyJointArms, LmRecoversPerturbedTruthsExactlyWithoutNoise) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  for (ManyJointArm arm : test::kManyJointArms) {
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      RigidTransform base;
      const RobotModel truth = simulate(arm, 5300 + 100 * seed + static_cast<std::uint64_t>(arm), 150, 0.0, &base);
      Status status = Status::ok;
      EXPECT_NO_HEAP(status = calibrate_lm(start_of(arm), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace,
                                           &lm().result));
      ASSERT_EQ(status, Status::ok) << test::many_joint_arm_name(arm) << " seed " << seed << ": "
                                    << status_message(status);
      EXPECT_EQ(lm().result.model.joint_count, 7);
      EXPECT_EQ(lm().result.model.prismatic_joints, truth.prismatic_joints);
      const double worst_m = fresh_error_m(truth, base, lm().result, true);
      EXPECT_LE(worst_m, 1e-9) << test::many_joint_arm_name(arm) << " seed " << seed;
      if (seed == 1) {
        std::printf("%s: %d of %d estimated, worst fresh error %.3g m\n", test::many_joint_arm_name(arm),
                    lm().result.identifiability.kept_count(), mask_count(lm().result.identifiability.free_mask),
                    worst_m);
      }
    }
  }
}

// With 10 um noise the calibrated arm predicts the true points within the noise, and the
// residual sigma is the noise's, over many perturbations.
TEST(ManyJointArms, LmRecoversTheIdentifiableGeometryToTheNoise) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  const double noise_m = 1e-5;
  for (ManyJointArm arm : test::kManyJointArms) {
    for (std::uint64_t seed = 11; seed <= 18; ++seed) {
      RigidTransform base;
      const RobotModel truth = simulate(arm, 5300 + 100 * seed + static_cast<std::uint64_t>(arm), 250, noise_m, &base);
      ASSERT_EQ(calibrate_lm(start_of(arm), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
                Status::ok);
      const double rms_m = fresh_error_m(truth, base, lm().result, false);
      EXPECT_LT(rms_m, noise_m) << test::many_joint_arm_name(arm) << " seed " << seed;
      EXPECT_NEAR(lm().result.residual_sigma_m, noise_m, 0.2 * noise_m) << test::many_joint_arm_name(arm);
      if (seed == 11) {
        std::printf("%s: fresh-pose RMS error %.2f um (noise 10 um per axis)\n", test::many_joint_arm_name(arm),
                    rms_m * 1e6);
      }
      // and the start was far off: the fit did something
      LmResult nominal;
      nominal.model = start_of(arm);
      ASSERT_EQ(fit_base_to_tracker(nominal.model, lm().train.samples(), &nominal.base_to_tracker), Status::ok);
      EXPECT_GT(fresh_error_m(truth, base, nominal, false), 50.0 * rms_m) << test::many_joint_arm_name(arm);
    }
  }
}

// A prismatic first joint slides the arm along its axis: its theta (a turn about that axis), its
// d (a shift along it) and its a (a shift after it) commute with the slide and are the base's,
// which the analysis finds from the numbers; its alpha, the angle between the rail and the
// arm's first axis, is not.
TEST(ManyJointArms, TheRailsLinkIsTheBasesButForTheAngleToTheArm) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  RigidTransform base;
  (void)simulate(ManyJointArm::rail_ur10, 5399, 200, 1e-5, &base);
  ASSERT_EQ(calibrate_lm(start_of(ManyJointArm::rail_ur10), nullptr, lm().train.samples(), LmOptions{}, &lm().workspace,
                         &lm().result),
            Status::ok);
  const IdentifiabilityReport& report = lm().result.identifiability;
  for (DhField field : {DhField::theta_offset, DhField::d, DhField::a}) {
    EXPECT_FALSE(mask_has(report.kept_mask, model_param_index(0, field))) << static_cast<int>(field);
  }
  EXPECT_TRUE(mask_has(report.kept_mask, model_param_index(0, DhField::alpha)));
  for (int axis = 0; axis < 3; ++axis) {  // the base keeps all six: the rail's direction is the base's
    EXPECT_TRUE(mask_has(report.kept_mask, base_rotation_param_index(lm().result.model, axis)));
    EXPECT_TRUE(mask_has(report.kept_mask, base_translation_param_index(lm().result.model, axis)));
  }
}

using ManyJointWorkspace = CalibrationWorkspace<300, double, 40, 300, 0, kMaxLinkLengths>;

// The whole job (split, blunder test, ABC on the link lengths, LM) on a 7-axis arm and the rail.
TEST(ManyJointArms, TheJobCalibratesThem) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  static ManyJointWorkspace ws;
  static CalibrationResult r;
  for (ManyJointArm arm : {ManyJointArm::iiwa14, ManyJointArm::rail_ur10}) {
    RigidTransform base;
    (void)simulate(arm, 5377, 220, 1e-5, &base);
    CalibrationOptions options;
    options.abc_food_sources = 20;
    options.abc_cycles = 60;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate(start_of(arm), &lm().train, options, &ws, &r));
    ASSERT_EQ(status, Status::ok) << test::many_joint_arm_name(arm) << ": " << status_message(status);
    ASSERT_GT(r.stage_count, 0u);
    const CalibrationStage& last = r.stages[r.stage_count - 1];
    const double test_m = last.test.mae(ErrorAxis::norm_3d);
    std::printf("%s: test MAE uncalibrated %.1f um, %s %.1f um\n", test::many_joint_arm_name(arm),
                r.baseline.test.mae(ErrorAxis::norm_3d) * 1e6, r.stage_name(r.stage_count - 1), test_m * 1e6);
    EXPECT_LT(test_m, 3e-5) << test::many_joint_arm_name(arm);
    EXPECT_EQ(last.model.joint_count, 7);
  }
}

// Samples that read more joints than the model has are another arm's: refused, never cut.
TEST(ManyJointArms, ReadingsOfMoreJointsThanTheModelAreRefused) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  RigidTransform base;
  (void)simulate(ManyJointArm::iiwa14, 5388, 60, 0.0, &base);
  RobotModel six = nominal_model(RobotType::ur5);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(six, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result));
  EXPECT_EQ(status, Status::joint_count_mismatch);
  static ManyJointWorkspace ws;
  static CalibrationResult r;
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  EXPECT_EQ(calibrate(six, &lm().train, options, &ws, &r), Status::joint_count_mismatch);
  EXPECT_EQ(r.step, CalibrationStep::input);
  // A model of more joints than the build holds is no model.
  RobotModel bad = start_of(ManyJointArm::iiwa14);
  bad.joint_count = kMaxJoints + 1;
  EXPECT_EQ(calibrate_lm(bad, nullptr, lm().train.samples(), LmOptions{}, &lm().workspace, &lm().result),
            Status::invalid_argument);
}

// The joint terms' columns: d(point)/d(coefficient) is the column of the term's joint variable
// (theta of a revolute joint, d of a prismatic one) times its basis, as a central difference of
// the compliant FK says.
TEST(ManyJointArms, JointTermColumnsAreTheirJointsVariablesColumns) {
  SKIP_WITHOUT_SEVEN_JOINTS();
  RobotModel model = test::many_joint_arm_model(ManyJointArm::rail_ur10);
  model.tool_m = Vec3(0.01, -0.02, 0.12);
  ComplianceModel& c = model.compliance;
  c.gravity_direction = Vec3(0.0, 0.0, -1.0);  // along the rail: a vertical lift
  c.term_count = 2;
  c.terms[0] = ComplianceTerm{0, kToolLoadFrame};                     // the lift, loaded at the tool
  c.terms[1] = ComplianceTerm{2, 0, JointTermKind::harmonic_sin, 1};  // the UR10's shoulder
  c.coefficient[0] = 2e-5;
  c.coefficient[1] = 1e-4;
  ASSERT_EQ(check_compliance(c, model), Status::ok);
  const RigidTransform base = test::example_base_to_tracker();
  Random random(5310);
  for (int i = 0; i < 10; ++i) {
    Sample sample;
    sample.q_rad = test::many_joint_arm_joints(ManyJointArm::rail_ur10, &random);
    sample.point_m = base.apply(fk_tool_point(model, sample.q_rad));
    FullJacobian jacobian;
    (void)local_residual_jacobian(model, base, sample, &jacobian);
    for (int t = 0; t < c.term_count; ++t) {
      const double h = 1e-7;
      RobotModel plus = model;
      RobotModel minus = model;
      plus.compliance.coefficient[t] += h;
      minus.compliance.coefficient[t] -= h;
      const Vec3 numeric = (fk_tool_point(plus, sample.q_rad) - fk_tool_point(minus, sample.q_rad)) / (2.0 * h);
      EXPECT_LT((numeric - jacobian.col(compliance_param_index(model, t))).norm(), 1e-6 * numeric.norm()) << t;
    }
  }
}

}  // namespace
}  // namespace hivecal::lm_many_joints_test
