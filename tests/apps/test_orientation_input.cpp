// Samples with a measured orientation (rx, ry, rz: the tool frame's rotation vector in the
// tracker frame, as a UR pendant or a 6-DOF tracker probe reports it): the reader turns each
// such row into targets 1, 2, 3 (the point, and the point moved by the lever along the measured
// x and y axes), and the job estimates targets 2 and 3's tool points like real reflectors'.
// Format checks, and a simulated 6-DOF session on which the orientation identifies parameters
// that the positions alone cannot.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/model/full_params.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"

namespace hivecal::orientation_input_test {
namespace {

std::string number(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

/// One CSV row: joints, point and rotation vector each scaled by the given factors.
std::string row(const JointVector& q, const Vec3& p, const Vec3& r, double q_scale = 1.0, double p_scale = 1.0,
                double r_scale = 1.0) {
  std::string out;
  for (int j = 0; j < kSixJoints; ++j) out += number(q(j) * q_scale) + ",";
  for (int k = 0; k < 3; ++k) out += number(p(k) * p_scale) + ",";
  for (int k = 0; k < 3; ++k) out += number(r(k) * r_scale) + (k < 2 ? "," : "\n");
  return out;
}

/// Rotation vector of a rotation matrix [rad] (test data only: Eigen's angle-axis).
Vec3 rotation_vector_of(const Mat3& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

const JointVector kQ = (JointVector() << 0.1, -1.2, 1.0, -0.5, 1.4, 0.3).finished();
const Vec3 kPoint_m(0.4, -0.2, 0.6);
const Vec3 kRotation_rad(0.2, -2.9, 0.4);
const char* const kRadHeader = "q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n";

TEST(OrientationInput, RowBecomesThreeTargetsAtTheLever) {
  test::TempDir dir;
  const std::string path =
      dir.write("s.csv", std::string(kRadHeader) + row(kQ, kPoint_m, kRotation_rad) + row(kQ, kPoint_m, Vec3::Zero()));
  Dataset<8> samples;
  std::vector<std::size_t> lines;
  textio::OrientationRead found;
  ASSERT_TRUE(textio::read_samples_csv(path, &samples, {}, &lines, {}, &found).ok());
  EXPECT_EQ(found.poses, 2u);
  EXPECT_EQ(found.lever_m, textio::kDefaultPositionSigma_m / textio::kDefaultAngleSigma_rad);
  ASSERT_EQ(samples.size(), 6u);
  EXPECT_EQ(lines, (std::vector<std::size_t>{2, 2, 2, 3, 3, 3}));
  const Mat3 rotation = rotation_from_vector(kRotation_rad);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(samples.samples()[k].target, k);
    EXPECT_EQ(samples.samples()[k].q_rad, kQ);
  }
  EXPECT_EQ(samples.samples()[0].point_m, kPoint_m);
  EXPECT_LE((samples.samples()[1].point_m - (kPoint_m + 0.01 * rotation.col(0))).norm(), 1e-15);
  EXPECT_LE((samples.samples()[2].point_m - (kPoint_m + 0.01 * rotation.col(1))).norm(), 1e-15);
  EXPECT_LE((samples.samples()[4].point_m - (kPoint_m + Vec3(0.01, 0.0, 0.0))).norm(), 1e-15);
  EXPECT_LE((samples.samples()[5].point_m - (kPoint_m + Vec3(0.0, 0.01, 0.0))).norm(), 1e-15);

  // Lever 0: the columns are read and checked, not used. Another lever, given or from sigmas.
  textio::OrientationInput off;
  off.lever_m = 0.0;
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(path, &samples, {}, nullptr, off, &found).ok());
  EXPECT_EQ(samples.size(), 2u);
  EXPECT_EQ(found.poses, 0u);
  textio::OrientationInput probe;
  probe.position_sigma_m = 2e-5;
  probe.angle_sigma_rad = 2e-4;  // a 6-DOF tracker probe: 0.1 m
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(path, &samples, {}, nullptr, probe, &found).ok());
  EXPECT_NEAR(found.lever_m, 0.1, 1e-15);
  EXPECT_NEAR((samples.samples()[4].point_m - kPoint_m).norm(), 0.1, 1e-15);
}

TEST(OrientationInput, WrittenResolutionOfANumber) {
  const struct {
    const char* field;
    int exponent;
  } cases[] = {{"20.72", -2}, {"-115", 0},    {"+0.5", -1},       {"104.5", -1},
               {"20,72", -2}, {"1.5e-3", -4}, {"2,02011E+13", 8}, {"-1.5707963267948966", -16},
               {"7e2", 2},    {".25", -2}};
  for (const auto& c : cases) {
    int exponent = 99;
    EXPECT_TRUE(textio::written_resolution_exponent(c.field, &exponent)) << c.field;
    EXPECT_EQ(exponent, c.exponent) << c.field;
  }
  for (const char* bad : {"", "nan", "inf", "-", "1.2.3", "0x1p3", "1e", "e5", "1.5e-3x"}) {
    int exponent = 99;
    EXPECT_FALSE(textio::written_resolution_exponent(bad, &exponent)) << bad;
  }
}

// The lever from the noise: the joints' reading noise moves the point by J dq, |J| ~ the reach,
// and turns the tool by dq about each axis; with sigma_q = 0 it is the sigmas' ratio.
TEST(OrientationInput, TheLeverFromTheNoiseTakesTheJointsIn) {
  const RobotModel arm = nominal_model(RobotType::ur5e);
  const JointVector poses[2] = {kQ, (JointVector() << 0.3, -1.2, 1.4, -1.0, -1.57, 0.2).finished()};
  const Span<const JointVector> both(poses, 2);
  EXPECT_EQ(textio::noise_lever_m(1e-5, 1e-3, 0.0, arm, both), 0.01);
  EXPECT_EQ(textio::noise_lever_m(1e-5, 1e-3, 1e-4, arm, Span<const JointVector>()), 0.01);
  // Reference: the Jacobian's columns z_j x (p - o_j) from the joint frames, not differences.
  double norm2 = 0.0;
  for (const JointVector& q : poses) {
    const Vec3 p = fk_tool_point(arm, q);
    RigidTransform frame;  // base frame of joint 1: its axis is z, its origin 0
    for (int j = 0; j < kSixJoints; ++j) {
      norm2 += frame.rotation.col(2).cross(p - frame.translation_m).squaredNorm();
      const DhJoint& dh = arm.joints[j];
      const double theta = q(j) + dh.theta_offset_rad;
      const Mat3 link_rotation = rotation_z(theta) * rotation_x(dh.alpha_rad);
      const Vec3 link_origin_m(dh.a_m * std::cos(theta), dh.a_m * std::sin(theta), dh.d_m);
      frame.translation_m += frame.rotation * link_origin_m;
      frame.rotation = frame.rotation * link_rotation;
    }
  }
  const double sq = 0.01 * M_PI / 180.0;  // a pendant's 0.01 deg
  const double expected = std::sqrt((1e-10 + sq * sq * norm2 / 2.0 / 3.0) / (1e-6 + 2.0 * sq * sq));
  const double lever = textio::noise_lever_m(1e-5, 1e-3, sq, arm, both);
  EXPECT_NEAR(lever, expected, 1e-7 * expected);
  EXPECT_GT(lever, 0.05);  // the joints' noise dominates the position's at a UR5e's reach
  // Noise-free joints cannot weigh the orientation down: more joint noise, a longer lever.
  EXPECT_GT(textio::noise_lever_m(1e-5, 1e-3, 2.0 * sq, arm, both), lever);
}

// The reader takes the joints' noise from their written resolution (a pendant's two decimals in
// degrees; a log's full digits: none to speak of) when it is given the arm.
TEST(OrientationInput, TheJointsWrittenResolutionEntersTheLever) {
  test::TempDir dir;
  const RobotModel arm = nominal_model(RobotType::ur5e);
  textio::OrientationInput with_arm;
  with_arm.arm = &arm;
  textio::OrientationRead found;
  Dataset<16> samples;
  const std::string pendant = dir.write(
      "pendant.csv",
      "\"Base (°)\",\"Shoulder (°)\",\"Elbow (°)\",\"Wrist 1 (°)\",\"Wrist 2 (°)\",\"Wrist 3 (°)\",\"X (mm)\","
      "\"Y (mm)\",\"Z (mm)\",\"RX (rad)\",\"RY (rad)\",\"RZ (rad)\"\n"
      "20.72,-114.77,87.42,-62.33,-89.47,-68.88,-205.16,-220.39,628.03,0.018,3.137,-0.002\n"
      "104.5,-99.06,129.93,-111.24,-91.05,12.93,215.05,-306.8,265.58,0.048,-3.068,-0.239\n");
  ASSERT_TRUE(textio::read_samples_csv(pendant, &samples, {}, nullptr, with_arm, &found).ok());
  EXPECT_NEAR(found.joint_sigma_rad, 0.01 * M_PI / 180.0, 1e-18);  // "104.5" is 104.50: the finest
  std::vector<JointVector> poses;
  for (const Sample& s : samples.samples())
    if (s.target == 0) poses.push_back(s.q_rad);
  EXPECT_EQ(found.lever_m,
            textio::noise_lever_m(1e-5, 1e-3, found.joint_sigma_rad, arm, Span<const JointVector>(poses.data(), 2)));
  EXPECT_LE((samples.samples()[1].point_m - samples.samples()[0].point_m).norm() - found.lever_m, 1e-15);
  // Given joint noise wins; a lever given is used as given; no arm: the sigmas' ratio.
  textio::OrientationInput given = with_arm;
  given.joint_sigma_rad = 1e-3;
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(pendant, &samples, {}, nullptr, given, &found).ok());
  EXPECT_EQ(found.joint_sigma_rad, 1e-3);
  given.lever_m = 0.02;
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(pendant, &samples, {}, nullptr, given, &found).ok());
  EXPECT_EQ(found.lever_m, 0.02);
  EXPECT_EQ(found.joint_sigma_rad, 0.0);
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(pendant, &samples, {}, nullptr, {}, &found).ok());
  EXPECT_EQ(found.lever_m, 0.01);
  // Full digits (some values short: "-1.2"): the finest is ~1e-17 rad, the lever the sigmas' ratio.
  const std::string full = dir.write("full.csv", std::string(kRadHeader) + row(kQ, kPoint_m, kRotation_rad));
  samples.clear();
  ASSERT_TRUE(textio::read_samples_csv(full, &samples, {}, nullptr, with_arm, &found).ok());
  EXPECT_LT(found.joint_sigma_rad, 1e-15);
  EXPECT_NEAR(found.lever_m, 0.01, 1e-15);
}

TEST(OrientationInput, UnitsOfTheHeaderOrOptionsAndThePendantHeader) {
  test::TempDir dir;
  Dataset<8> reference;
  ASSERT_TRUE(textio::read_samples_csv(dir.write("rad.csv", std::string(kRadHeader) + row(kQ, kPoint_m, kRotation_rad)),
                                       &reference)
                  .ok());
  const double deg = 180.0 / M_PI;
  const struct {
    std::string text;
    textio::InputUnits units;
  } forms[] = {
      {"q1 [deg],q2 [deg],q3 [deg],q4 [deg],q5 [deg],q6 [deg],x [mm],y [mm],z [mm],rx [deg],ry [deg],rz [deg]\n" +
           row(kQ, kPoint_m, kRotation_rad, deg, 1e3, deg),
       {}},
      {std::string(kRadHeader) + row(kQ, kPoint_m, kRotation_rad, deg, 1e3, deg), {"mm", "deg"}},
      {"\"Base (\xC2\xB0)\",\"Shoulder (\xC2\xB0)\",\"Elbow (\xC2\xB0)\",\"Wrist 1 (\xC2\xB0)\",\"Wrist 2 (\xC2\xB0)\","
       "\"Wrist 3 (\xC2\xB0)\",\"X (mm)\",\"Y (mm)\",\"Z (mm)\",\"RX (rad)\",\"RY (rad)\",\"RZ (rad)\"\n" +
           row(kQ, kPoint_m, kRotation_rad, deg, 1e3, 1.0),
       {}},
  };
  for (const auto& form : forms) {
    Dataset<8> samples;
    const port::Error read = textio::read_samples_csv(dir.write("form.csv", form.text), &samples, form.units);
    ASSERT_TRUE(read.ok()) << read.message;
    ASSERT_EQ(samples.size(), 3u) << form.text;
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_LE((samples.samples()[k].q_rad - reference.samples()[k].q_rad).norm(), 1e-14) << form.text;
      EXPECT_LE((samples.samples()[k].point_m - reference.samples()[k].point_m).norm(), 1e-14) << form.text;
    }
  }
}

TEST(OrientationInput, BadOrientationsAreRefusedWithFileAndLine) {
  test::TempDir dir;
  const std::string good = row(kQ, kPoint_m, kRotation_rad);
  const struct {
    std::string text;
    textio::InputUnits units;
    std::string expected;
  } cases[] = {
      {"q1,q2,q3,q4,q5,q6,x,y,z,rx,ry\n0,0,0,0,0,0,1,2,3,0,0\n", {}, "bad.csv:1: header has 2 of the columns rx,ry,rz"},
      {std::string(kRadHeader) + good + "0,0,0,0,0,0,1,2,3,0,abc,0\n", {}, "bad.csv:3: column 'ry': not a number"},
      {std::string(kRadHeader) + good + "0,0,0,0,0,0,1,2,3,0,nan,0\n",
       {},
       "bad.csv:3: NaN or Inf in the rotation vector"},
      {std::string(kRadHeader) + "0,0,0,0,0,0,1,2,3,0,180,0\n",
       {},
       "bad.csv:2: rotation vector rx,ry,rz = 0, 180, 0 looks like degrees: use --angle-unit deg"},
      {std::string(kRadHeader) + "0,0,0,0,0,0,1,2,3,0,180,0\n", {"", "rad"}, "turns more than once"},
      {"q1,q2,q3,q4,q5,q6,x,y,z,rx [m],ry,rz\n" + good,
       {},
       "bad.csv:1: column 'rx': unit '[m]' is not one of [rad], [deg]"},
      {"q1,q2,q3,q4,q5,q6,x,y,z,target,rx,ry,rz\n0,0,0,0,0,0,1,2,3,1,0,0,0\n",
       {},
       "bad.csv:2: a measured orientation (rx, ry, rz) and a target column together"},
  };
  for (const auto& c : cases) {
    Dataset<8> samples;
    const port::Error read = textio::read_samples_csv(dir.write("bad.csv", c.text), &samples, c.units);
    EXPECT_FALSE(read.ok()) << c.text;
    EXPECT_NE(read.message.find(c.expected), std::string::npos) << read.message;
  }
  textio::OrientationInput bad;
  bad.angle_sigma_rad = 0.0;
  Dataset<8> samples;
  EXPECT_FALSE(
      textio::read_samples_csv(dir.write("ok.csv", std::string(kRadHeader) + good), &samples, {}, nullptr, bad).ok());
}

std::string names_of(ParamMask mask) {
  std::string names;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(mask, i)) names += std::string(names.empty() ? "" : " ") + full_param_name(i, kSixJoints);
  }
  return names;
}

// A simulated 6-DOF session (no noise): a perturbed UR5 whose tool frame is turned against the
// flange (unknown to the reader: its start assumes the flange's axes), 7 poses measured as
// point and rotation vector, written as a CSV and calibrated by the job twice: positions only
// (--orientation-lever-m 0) and with the orientation. 7 points give 21 equations for the 25
// parameters a UR5 identifies; the orientation adds 42 (minus 6 tool coordinates).
TEST(OrientationInput, OrientationIdentifiesWhatPositionsAloneCannot) {
  Random random(21);
  const Vec3 tool_m(0.012, -0.006, 0.17);
  RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m);
  const Mat3 tool_rotation = rotation_from_vector(Vec3(0.3, -0.2, 0.5));  // tool frame in the flange frame
  const RigidTransform base = test::example_base_to_tracker();
  std::string text = kRadHeader;
  for (int pose = 0; pose < 7; ++pose) {
    const JointVector q = test::random_joints(&random);
    const RigidTransform flange = fk_flange(truth, q);
    text +=
        row(q, base.apply(flange.apply(tool_m)), rotation_vector_of(base.rotation * flange.rotation * tool_rotation));
  }
  test::TempDir dir;
  const std::string path = dir.write("six_dof.csv", text);
  static Dataset<32> positions;
  static Dataset<32> oriented;
  positions.clear();
  oriented.clear();
  textio::OrientationInput off;
  off.lever_m = 0.0;
  textio::OrientationRead found;
  ASSERT_TRUE(textio::read_samples_csv(path, &positions, {}, nullptr, off).ok());
  ASSERT_TRUE(textio::read_samples_csv(path, &oriented, {}, nullptr, {}, &found).ok());
  ASSERT_EQ(oriented.size(), 21u);

  static CalibrationWorkspace<32, double, 150, 300> workspace;
  static CalibrationResult one;
  static CalibrationResult three;
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.train_fraction = 1.0;
  options.significance_t = 0.0;  // no noise: every change is significant
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.17);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(start, &positions, options, &workspace, &one));
  ASSERT_EQ(status, Status::ok) << calibration_step_name(one.step);
  textio::start_orientation_targets(found, &start);
  EXPECT_NO_HEAP(status = calibrate(start, &oriented, options, &workspace, &three));
  ASSERT_EQ(status, Status::ok) << calibration_step_name(three.step);

  const ParamMask kept_one = one.lm.identifiability.kept_mask;
  const ParamMask kept_three = three.lm.identifiability.kept_mask;
  std::printf("7 poses: positions keep %d, with orientation %d; gained: %s\n", one.lm.identifiability.kept_count(),
              three.lm.identifiability.kept_count(), names_of(kept_three & ~kept_one).c_str());
  EXPECT_LE(one.lm.identifiability.kept_count(), 21);
  EXPECT_EQ(kept_one & ~kept_three, 0u);
  EXPECT_EQ(three.lm.identifiability.kept_count(), 25);
  EXPECT_EQ(names_of(kept_three & ~kept_one), "a1 theta3 theta4 theta5 d5");  // measured on these poses

  // On fresh poses: with the orientation every point to 1e-9 m (no noise); positions alone
  // guess the parameters they could not determine and miss by more.
  double worst_one_m = 0.0;
  double worst_three_m = 0.0;
  const CalibrationStage& s1 = one.stages[one.stage_count - 1];
  const CalibrationStage& s3 = three.stages[three.stage_count - 1];
  for (int k = 0; k < 50; ++k) {
    const JointVector q = test::random_joints(&random);
    const Vec3 measured = base.apply(fk_tool_point(truth, q));
    worst_one_m = std::fmax(worst_one_m, (s1.base_to_tracker.apply(fk_tool_point(s1.model, q)) - measured).norm());
    worst_three_m = std::fmax(worst_three_m, (s3.base_to_tracker.apply(fk_tool_point(s3.model, q)) - measured).norm());
  }
  std::printf("fresh poses, worst: positions only %.3g m, with orientation %.3g m\n", worst_one_m, worst_three_m);
  EXPECT_LE(worst_three_m, 1e-9);
  EXPECT_GT(worst_one_m, 1e-5);
}

}  // namespace
}  // namespace hivecal::orientation_input_test
