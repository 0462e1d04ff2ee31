// The job's LM+compliance stage (docs/compliance.md) on simulated sessions whose deflection has
// ANOTHER form than the calibration's basis: the second session generator's gravity
// deflection (other_session.hpp), and the simulator's joint compliance (apps/sim, restated
// here) plus a payload at the tool. Validation is on fresh poses, against the rigid full LM of
// the same job and split, and against the noise floor (the same session without compliance).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/metrics.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/other_session.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::calibration_compliance_test {
namespace {

constexpr std::size_t kSamples = 256;
using Workspace = CalibrationWorkspace<kSamples, double, 20, 300>;

Workspace workspace;
CalibrationResult result;
Dataset<kSamples> dataset;
Dataset<kSamples> fresh;

/// How the true arm bends: dq [rad] at joint readings q.
enum class Bending { none, other_session, simulator_and_payload };

/// The simulator's joint compliance (apps/sim/sim_model.cpp, Session::compliance, default
/// config): joint 2 by the horizontal reach of upper arm + forearm, joint 3 by the forearm's.
JointVector simulator_deflection(const RobotModel& truth, const JointVector& q) {
  const double a2_m = std::fabs(truth.joints[1].a_m);
  const double a3_m = std::fabs(truth.joints[2].a_m);
  const double forearm = std::cos(q(1) + q(2));
  JointVector d = JointVector::Zero();
  d(1) = 60e-6 * (a2_m * std::cos(q(1)) + a3_m * forearm) / (a2_m + a3_m);
  d(2) = 30e-6 * forearm;
  return d;
}

/// A 2 kg payload 0.1 m beyond the tool point (along the flange z) on joints 2 and 3, as
/// compliances of 12 and 15 urad per kg m: the gravity torque from the frames of fk_flange
/// of chains cut after each joint (not the library's basis code).
JointVector payload_deflection(const RobotModel& truth, const JointVector& q) {
  const RigidTransform flange = fk_flange(truth, q);
  const Vec3 payload_m = flange.apply(truth.tool_m + Vec3(0.0, 0.0, 0.1));
  const double compliance[kSixJoints] = {0.0, 12e-6, 15e-6, 0.0, 0.0, 0.0};
  JointVector d = JointVector::Zero();
  for (int j = 1; j <= 2; ++j) {
    RobotModel cut = truth;
    JointVector q_cut = q;
    for (int k = j; k < kSixJoints; ++k) {
      cut.joints[k] = DhJoint{};
      q_cut(k) = 0.0;
    }
    const RigidTransform frame = fk_flange(cut, q_cut);  // DH frame j: joint j + 1 turns about its z
    const Vec3 lever_m = payload_m - frame.translation_m;
    const double torque = frame.rotation.col(2).dot(lever_m.cross(Vec3(0.0, 0.0, -2.0)));
    d(j) = compliance[j] * torque;
  }
  return d;
}

JointVector true_joints(Bending bending, const RobotModel& truth, const JointVector& q) {
  switch (bending) {
    case Bending::other_session: return test::other_session_detail::deflected(q);
    case Bending::simulator_and_payload: return q + simulator_deflection(truth, q) + payload_deflection(truth, q);
    case Bending::none: break;
  }
  return q;
}

/// The truth of every session: a perturbed UR5 with a tool off the flange axis.
RobotModel truth_model() {
  Random random(1601);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  truth.tool_m << 0.02, -0.015, 0.12;
  return truth;
}

/// `count` samples at random poses with 15 um tracker noise.
void fill(Bending bending, std::uint64_t seed, std::size_t count, DatasetBase* out) {
  const RobotModel truth = truth_model();
  const RigidTransform base = test::example_base_to_tracker();
  Random random(seed);
  out->clear();
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = test::random_joints(&random);
    const Vec3 noise = test::gaussian_vector(&random);
    (void)out->add(q, base.apply(fk_tool_point(truth, true_joints(bending, truth, q))) + 15e-6 * noise);
  }
}

CalibrationOptions compliance_options() {
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.compliance.enabled = true;
  return options;
}

struct Validation {
  double rigid_m = 0.0;      ///< 3-D MAE of the rigid full LM on fresh poses [m]
  double compliant_m = 0.0;  ///< the same for LM+compliance [m]
};

/// The job with compliance on a session of `bending`, validated on 300 fresh poses.
Validation validate(Bending bending) {
  fill(bending, 11, 120, &dataset);
  fill(bending, 12, 300, &fresh);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status =
                     calibrate(nominal_model(RobotType::ur5), &dataset, compliance_options(), &workspace, &result));
  EXPECT_EQ(status, Status::ok);
  EXPECT_EQ(result.stage_count, 2u);
  if (result.stage_count != 2) return {};
  EXPECT_STREQ(result.stage_name(0), "LM");
  EXPECT_STREQ(result.stage_name(1), "LM+compliance");
  EXPECT_EQ(result.stages[0].model.compliance.term_count, 0);
  EXPECT_EQ(result.stages[1].model.compliance.term_count, 4);
  Validation v;
  for (int k = 0; k < 2; ++k) {
    const CalibrationStage& stage = result.stages[k];
    const double mae_m =
        position_error_stats(stage.model, stage.base_to_tracker, fresh.samples()).mae(ErrorAxis::norm_3d);
    (k == 0 ? v.rigid_m : v.compliant_m) = mae_m;
  }
  std::printf("  test MAE rigid %.2f um, LM+compliance %.2f um; coefficients",
              1e6 * result.stages[0].test.mae(ErrorAxis::norm_3d), 1e6 * result.stages[1].test.mae(ErrorAxis::norm_3d));
  const ComplianceModel& c = result.stages[1].model.compliance;
  for (int t = 0; t < c.term_count; ++t) std::printf(" %s %.3g", compliance_term_name(c, t), c.coefficient[t]);
  std::printf("\n  fresh-pose MAE rigid %.2f um, LM+compliance %.2f um (ratio %.3f)\n", 1e6 * v.rigid_m,
              1e6 * v.compliant_m, v.compliant_m / v.rigid_m);
  return v;
}

/// The noise floor: the same session and job without any bending.
double noise_floor_m() {
  fill(Bending::none, 11, 120, &dataset);
  fill(Bending::none, 12, 300, &fresh);
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, compliance_options(), &workspace, &result), Status::ok);
  const CalibrationStage& stage = result.stages[0];
  const double floor_m =
      position_error_stats(stage.model, stage.base_to_tracker, fresh.samples()).mae(ErrorAxis::norm_3d);
  std::printf("  noise floor (no bending, rigid full LM) %.2f um\n", 1e6 * floor_m);
  return floor_m;
}

// Measured (x86-64): noise floor 24.95 um; rigid 30.38 um, LM+compliance 25.29 um (0.833 x,
// 6 % of the rigid fit's excess over the floor left; c_j3_tool fixed by the 3-sigma test). The bending is small against
// the noise here, so the floor itself is 0.82 x the rigid fit: the ratio's bar is 0.85, the excess's 0.2.
TEST(CalibrationCompliance, OtherSessionDeflectionValidatesAtTheNoiseFloor) {
  const double floor_m = noise_floor_m();
  const Validation v = validate(Bending::other_session);
  EXPECT_LE(v.compliant_m, 0.85 * v.rigid_m);
  EXPECT_LE(v.compliant_m - floor_m, 0.2 * (v.rigid_m - floor_m));
}

// Measured (x86-64): rigid 36.40 um, LM+compliance 25.08 um (0.689 x), floor 24.95 um (1 % of
// the excess left), although the payload's lever to the shoulder is not among the terms.
TEST(CalibrationCompliance, SimulatorCompliancePlusPayloadValidatesAtTheNoiseFloor) {
  const double floor_m = noise_floor_m();
  const Validation v = validate(Bending::simulator_and_payload);
  EXPECT_LE(v.compliant_m, 0.75 * v.rigid_m);
  EXPECT_LE(v.compliant_m - floor_m, 0.2 * (v.rigid_m - floor_m));
}

// An arm that does not bend: the compliance terms must not pass the significance test (3 sigma
// for a new model term, CalibrationCompliance::significance_t), so the compliant fit is the
// rigid one. At the geometry's 2 sigma, a spurious term (2.4 sigma, correlated -0.92 with
// theta3) made the demo's unbent session validate at 12.6 um instead of 4.5 um.
TEST(CalibrationCompliance, AnArmThatDoesNotBendKeepsTheRigidFit) {
  const Validation v = validate(Bending::none);
  const ComplianceModel& c = result.stages[1].model.compliance;
  for (int t = 0; t < c.term_count; ++t) EXPECT_EQ(c.coefficient[t], 0.0) << compliance_term_name(c, t);
  // No term passed: the stage is the rigid fit, bit for bit (the rigid stage was run again).
  EXPECT_TRUE(result.stages[1].rigid_kept);
  EXPECT_FALSE(result.stages[0].rigid_kept);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    EXPECT_EQ(to_params(result.stages[1].model)(i), to_params(result.stages[0].model)(i))
        << full_param_name(i, kSixJoints);
  }
  EXPECT_TRUE(result.stages[1].base_to_tracker.translation_m == result.stages[0].base_to_tracker.translation_m);
  EXPECT_EQ(v.compliant_m, v.rigid_m);
}

TEST(CalibrationCompliance, OffByDefaultAndRefusedWithoutLm) {
  fill(Bending::other_session, 11, 120, &dataset);
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  ASSERT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result), Status::ok);
  EXPECT_EQ(result.stage_count, 1u);
  options = compliance_options();
  options.method = CalibrationMethod::abc;
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result), Status::invalid_argument);
  EXPECT_EQ(result.step, CalibrationStep::input);
  options = compliance_options();
  options.compliance.model.gravity_direction = Vec3::Zero();  // no default terms without gravity
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result), Status::invalid_argument);
  options = compliance_options();
  options.compliance.model.term_count = 1;
  options.compliance.model.terms[0] = ComplianceTerm{2, 1};  // a load before its joint
  EXPECT_EQ(calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result), Status::invalid_argument);
}

TEST(CalibrationCompliance, ArmMassesBasisAlsoBeatsTheRigidFit) {
  fill(Bending::simulator_and_payload, 11, 120, &dataset);
  fill(Bending::simulator_and_payload, 12, 300, &fresh);
  CalibrationOptions options = compliance_options();
  options.compliance.model.load = ComplianceLoad::arm_masses;
  // The UR5e's published masses on a UR5 (the CB3 tables are not in the library): the basis
  // only needs the right shape, the coefficients absorb the scale.
  ASSERT_EQ(nominal_arm_masses(RobotType::ur5e, &options.compliance.model.masses), Status::ok);
  options.compliance.model.masses.payload_kg = 2.0;
  options.compliance.model.masses.payload_com_m << 0.0, 0.0, 0.2;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(result.stage_count, 2u);
  EXPECT_EQ(result.stages[1].model.compliance.term_count, 3);
  double mae_m[2];
  for (int k = 0; k < 2; ++k) {
    mae_m[k] = position_error_stats(result.stages[k].model, result.stages[k].base_to_tracker, fresh.samples())
                   .mae(ErrorAxis::norm_3d);
  }
  std::printf("  arm masses: fresh-pose MAE rigid %.2f um, LM+compliance %.2f um (ratio %.3f)\n", 1e6 * mae_m[0],
              1e6 * mae_m[1], mae_m[1] / mae_m[0]);
  EXPECT_LE(mae_m[1], 0.75 * mae_m[0]);  // measured 0.691 (36.40 -> 25.17 um)
}

// A start model 10 mm / 20 mrad off the arm: the prior's tolerances widen in the rigid fit and
// again in the joint-term stage, each stage records its factor (CalibrationStage::
// prior_tolerances), and the blocked folds and eliminations that predict from a stage hold
// that stage's tolerances (job_lm_prior with its factor), not the stated ones.
TEST(CalibrationCompliance, AStartFarOffNominalWidensThePriorInEveryStageAndItsFoldsHoldIt) {
  fill(Bending::other_session, 11, 120, &dataset);
  fill(Bending::other_session, 12, 300, &fresh);
  Random random(5301);
  const RobotModel far_start = test::perturbed_model(truth_model(), &random, 10e-3, 20e-3);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(far_start, &dataset, compliance_options(), &workspace, &result));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(result.stage_count, 2u);
  const CalibrationOptions stated = compliance_options();
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(result.stages[k].prior_tolerances.dh_length_m, 1.5 * stated.prior.dh_length_m) << k;
    EXPECT_GT(result.stages[k].prior_tolerances.dh_angle_rad, 1.5 * stated.prior.dh_angle_rad) << k;
  }
  EXPECT_TRUE(result.stages[1].folds.checked);
  EXPECT_EQ(result.stages[1].prior_tolerances.dh_length_m, result.lm.prior_tolerances.dh_length_m);
  EXPECT_EQ(result.stages[1].prior_tolerances.dh_angle_rad, result.lm.prior_tolerances.dh_angle_rad);
  double mae_m[2];
  for (int k = 0; k < 2; ++k) {
    mae_m[k] = position_error_stats(result.stages[k].model, result.stages[k].base_to_tracker, fresh.samples())
                   .mae(ErrorAxis::norm_3d);
  }
  std::printf("  far start: tolerances %.3g mm / %.3g mrad; fresh-pose MAE rigid %.2f um, LM+compliance %.2f um\n",
              result.lm.prior_tolerances.dh_length_m * 1e3, result.lm.prior_tolerances.dh_angle_rad * 1e3,
              1e6 * mae_m[0], 1e6 * mae_m[1]);
  EXPECT_LE(mae_m[1], 0.85 * mae_m[0]);
}

}  // namespace
}  // namespace hivecal::calibration_compliance_test
