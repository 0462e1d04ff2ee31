// `hivecal export --format ur-kinematics`: the ROS UR driver's kinematics YAML. Its six frames,
// each followed by the joint's rotation (and the flange offset it cannot hold), must be the
// model's chain to 1e-9 m on random poses; on a real UR5e factory calibration the cancelling
// hundreds of metres of d_2 .. d_4 must be gone; a nominal UR5e gives the published frames.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/core/random.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/shared_data.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/ur_kinematics.hpp"
#include "textio/urdf.hpp"

namespace hivecal::ur_kinematics_export_test {
namespace {

using math::kPi;

/// Worst distance over 200 random poses between the YAML chain's tool point (frames as the
/// YAML writes them: read back from their xyz/rpy) and the model's.
double worst_chain_error_m(const RobotModel& model, textio::UrKinematics* out = nullptr) {
  textio::UrKinematics kinematics;
  std::string why;
  EXPECT_TRUE(textio::ur_kinematics_from_model(model, &kinematics, &why)) << why;
  if (out != nullptr) *out = kinematics;
  Random random(11);
  double worst_m = 0.0;
  for (int pose = 0; pose < 200; ++pose) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-2.0 * kPi, 2.0 * kPi);
    RigidTransform chain;
    for (int i = 0; i < kSixJoints; ++i) {
      const RigidTransform frame = textio::urdf_transform(textio::urdf_origin(kinematics.joint_frames[i]));
      chain = chain.then_after(frame).then_after(RigidTransform{rotation_z(q(i)), Vec3::Zero()});
    }
    const Vec3 tool = chain.then_after(kinematics.flange).apply(model.tool_m);
    worst_m = std::fmax(worst_m, (tool - fk_tool_point(model, q)).norm());
  }
  return worst_m;
}

TEST(UrKinematicsExport, NominalUr5eGivesThePublishedFrames) {
  RobotModel model = nominal_model(RobotType::ur5e);
  textio::UrKinematics k;
  EXPECT_LE(worst_chain_error_m(model, &k), 1e-9);
  EXPECT_NEAR(k.joint_frames[0].translation_m.z(), 0.1625, 1e-12);   // shoulder
  EXPECT_NEAR(k.joint_frames[2].translation_m.x(), -0.425, 1e-12);   // forearm
  EXPECT_NEAR(k.joint_frames[3].translation_m.x(), -0.3922, 1e-12);  // wrist_1
  EXPECT_NEAR(k.joint_frames[3].translation_m.z(), 0.1333, 1e-12);
  EXPECT_NEAR(k.joint_frames[4].translation_m.y(), -0.0997, 1e-12);  // wrist_2
  EXPECT_NEAR(k.joint_frames[5].translation_m.y(), 0.0996, 1e-12);   // wrist_3
  const std::string yaml = textio::format_ur_kinematics_yaml(k, "calib_1");
  EXPECT_NE(yaml.find("kinematics:\n  shoulder:\n    x: 0\n    y: 0\n    z: 0.16250000000000001\n"), std::string::npos)
      << yaml;
  EXPECT_NE(yaml.find("  hash: calib_1\n"), std::string::npos);
}

TEST(UrKinematicsExport, CalibratedArmsAreTheirChains) {
  Random random(21);
  for (int trial = 0; trial < 20; ++trial) {
    RobotModel model = nominal_model(trial % 2 == 0 ? RobotType::ur5 : RobotType::ur10e);
    for (DhJoint& joint : model_joints(&model)) {
      joint.theta_offset_rad += random.uniform(-0.05, 0.05);
      joint.d_m += random.uniform(-0.01, 0.01);
      joint.a_m += random.uniform(-0.01, 0.01);
      joint.alpha_rad += random.uniform(-0.02, 0.02);
    }
    // Cancelling offsets as UR's factory calibrations have them, of either sign, in any quadrant.
    const double shift_m = random.uniform(-500.0, 500.0);
    model.joints[1].d_m += shift_m;
    model.joints[2].d_m -= shift_m + random.uniform(-3.0, 3.0);
    model.joints[1].theta_offset_rad += trial % 4 == 1 ? kPi : 0.0;  // a link pointing the other way
    model.tool_m = Vec3(0.01, 0.02, 0.15);
    textio::UrKinematics k;
    const double worst_m = worst_chain_error_m(model, &k);
    EXPECT_LE(worst_m, 1e-9) << "trial " << trial << " shift " << shift_m;
  }
}

TEST(UrKinematicsExport, RealUr5eFactoryCalibrationLosesItsOffsets) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  UrCalibrationDeltas deltas;
  ASSERT_TRUE(textio::read_ur_calibration_conf(test::shared_data_path("ur5e-pendant/calibration.conf"), &deltas).ok());
  RobotModel model;
  ASSERT_EQ(apply_ur_deltas(nominal_model(RobotType::ur5e), deltas, &model), Status::ok);
  double largest_d_m = 0.0;
  for (const DhJoint& joint : model_joints(model)) largest_d_m = std::fmax(largest_d_m, std::fabs(joint.d_m));
  EXPECT_GT(largest_d_m, 100.0) << "the file's cancelling offsets";
  textio::UrKinematics k;
  const double worst_m = worst_chain_error_m(model, &k);
  EXPECT_LE(worst_m, 1e-9);
  double largest_frame_m = 0.0;
  for (const RigidTransform& frame : k.joint_frames)
    largest_frame_m = std::fmax(largest_frame_m, frame.translation_m.norm());
  EXPECT_LT(largest_frame_m, 0.5);
  std::printf("UR5e factory calibration: largest |d| %.1f m in DH, largest YAML frame %.4f m, chain error %.1e m\n",
              largest_d_m, largest_frame_m, worst_m);
}

TEST(UrKinematicsExport, OtherArmsAreRefused) {
  RobotModel model = nominal_model(RobotType::ur5);
  model.joints[1].alpha_rad = kPi / 2;  // joints 2 and 3 no longer parallel
  textio::UrKinematics k;
  std::string why;
  EXPECT_FALSE(textio::ur_kinematics_from_model(model, &k, &why));
  EXPECT_NE(why.find("not a UR-shaped arm"), std::string::npos) << why;
}

}  // namespace
}  // namespace hivecal::ur_kinematics_export_test
