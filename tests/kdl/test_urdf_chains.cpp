// Arms of other than six revolute joints through URDF, checked by ROS's own libraries
// (kdl_parser and orocos KDL, tests/kdl/kdl_chain.hpp): what `hivecal export --format urdf`
// writes for the test kit's perturbed 7-axis arms and its UR10 on a rail (a prismatic joint 1)
// is hivecal's forward kinematics, flange pose and tool points, to a nanometre; and a UR10 on a
// rail written as a cell's URDF (tests/testkit/urdf_arms.hpp), read by hivecal, predicts
// what KDL computes from that file, to a nanometre, over a thousand random joint vectors each.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "kdl/kdl_chain.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/urdf_arms.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/robot_description.hpp"
#include "textio/urdf.hpp"

namespace hivecal::urdf_chains_test {
namespace {

using test::run;

/// Random joint vectors per arm [-].
constexpr int kPoses = 1000;

/// The chain `root` -> `tip` of `urdf` as KDL reads it (a test failure when it does not).
test::KdlChain chain_of(const std::string& urdf, const std::string& root, const std::string& tip) {
  test::KdlChain chain;
  std::string error;
  EXPECT_TRUE(chain.load(urdf, root, tip, &error)) << error;
  return chain;
}

/// Largest difference of two poses: the translation's [m], or a rotation entry's times 1 m.
double pose_difference_m(const RigidTransform& a, const RigidTransform& b) {
  return std::fmax((a.translation_m - b.translation_m).norm(), (a.rotation - b.rotation).cwiseAbs().maxCoeff());
}

// `export --robot-model ARM.json --format urdf` on the perturbed iiwa 14, Franka and UR10 on a
// rail: KDL's flange and tcps are hivecal's (the flange's full pose), and the tracker link of
// a result's URDF is where the result puts the tracker.
TEST(UrdfKdlChains, ExportedSevenJointArmsAreHivecalsForwardKinematicsToANanometre) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_urdf_chains");
  ASSERT_FALSE(dir.path().empty());
  Random random(5301);
  const RigidTransform base_to_tracker{rotation_z(0.7) * rotation_x(-0.2), Vec3(2.5, -0.4, 0.3)};
  for (const test::ManyJointArm arm : test::kManyJointArms) {
    const char* name = test::many_joint_arm_name(arm);
    const textio::RobotDescription robot = test::many_joint_description(arm, &random);
    const std::string description = dir.write(std::string(name) + ".json", textio::format_robot_description(robot));
    const std::string out = dir.path() + "/" + name + ".urdf";
    ASSERT_EQ(run(cli::export_main, {"--robot-model", description, "--format", "urdf", "--out", out}), cli::kExitOk);
    const std::string urdf = test::read_text_file(out);
    const test::KdlChain flange = chain_of(urdf, "base_link", "flange");
    const test::KdlChain tcp = chain_of(urdf, "base_link", "tcp");
    const test::KdlChain tcp_2 = chain_of(urdf, "base_link", "tcp_2");
    ASSERT_EQ(tcp.joints(), 7u) << name;
    const std::string with_tracker = textio::format_urdf(robot, &base_to_tracker);
    const test::KdlChain tracked_tcp = chain_of(with_tracker, "tracker", "tcp");
    double worst_m = 0.0;
    for (int pose = 0; pose < kPoses; ++pose) {
      const JointVector q = test::many_joint_arm_joints(arm, &random);
      const std::vector<double> values = test::joint_values(robot.model, q);
      worst_m = std::fmax(worst_m, pose_difference_m(flange.fk(values), fk_flange(robot.model, q)));
      worst_m = std::fmax(worst_m, (tcp.fk(values).translation_m - fk_tool_point(robot.model, q)).norm());
      worst_m = std::fmax(worst_m, (tcp_2.fk(values).translation_m - fk_target_point(robot.model, q, 1)).norm());
      worst_m = std::fmax(
          worst_m,
          (tracked_tcp.fk(values).translation_m - base_to_tracker.apply(fk_tool_point(robot.model, q))).norm());
    }
    std::printf("%-14s exported URDF, KDL against hivecal's FK over %d poses: worst %.3g m\n", name, kPoses, worst_m);
    EXPECT_LT(worst_m, 1e-9) << name;
  }
}

// The fixture's UR10 on a rail read by hivecal (`--robot-model rail.urdf`): its DH model, in the
// file's root frame, puts the tcp where KDL puts it on that file; and the URDF export writes of
// it again is the same chain to KDL.
TEST(UrdfKdlChains, AUrTenOnARailReadInIsKdlsForwardKinematicsToANanometre) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_urdf_rail");
  ASSERT_FALSE(dir.path().empty());
  const std::string file = dir.write("ur10_on_rail.urdf", test::kRailUr10Urdf);
  textio::RobotDescription robot;
  const port::Error read = textio::robot_description_from_value(file, &robot);
  ASSERT_TRUE(read.ok()) << read.message;
  ASSERT_EQ(robot.model.joint_count, 7);
  ASSERT_EQ(joint_type(robot.model, 0), JointType::prismatic);
  const RigidTransform file_base =
      robot.convention == DhConvention::modified ? robot.modified_base.transform() : RigidTransform{};
  const test::KdlChain fixture = chain_of(test::kRailUr10Urdf, "world", "tcp");
  ASSERT_EQ(fixture.joints(), 7u);
  const std::string out = dir.path() + "/again.urdf";
  ASSERT_EQ(run(cli::export_main, {"--robot-model", file, "--format", "urdf", "--out", out}), cli::kExitOk);
  const test::KdlChain exported = chain_of(test::read_text_file(out), "base_link", "tcp");
  ASSERT_EQ(exported.joints(), 7u);
  Random random(5302);
  double worst_read_m = 0.0;
  double worst_exported_m = 0.0;
  for (int pose = 0; pose < kPoses; ++pose) {
    JointVector q = test::many_joint_arm_joints(test::ManyJointArm::rail_ur10, &random);
    q(0) = random.uniform(test::kRailLower_m, test::kRailUpper_m);  // the fixture's whole rail
    const std::vector<double> values = test::joint_values(robot.model, q);
    const Vec3 kdl_m = fixture.fk(values).translation_m;
    worst_read_m = std::fmax(worst_read_m, (kdl_m - file_base.apply(fk_tool_point(robot.model, q))).norm());
    worst_exported_m = std::fmax(worst_exported_m, (kdl_m - exported.fk(values).translation_m).norm());
  }
  std::printf("UR10 on a rail over %d poses: hivecal's reading against KDL worst %.3g m, its export %.3g m\n", kPoses,
              worst_read_m, worst_exported_m);
  EXPECT_LT(worst_read_m, 1e-9);
  EXPECT_LT(worst_exported_m, 1e-9);
}

}  // namespace
}  // namespace hivecal::urdf_chains_test
