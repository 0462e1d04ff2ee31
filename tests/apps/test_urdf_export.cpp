// `hivecal export --format urdf`: the chain written is the model. The URDF is read back here
// with a reader of its own (joint origins xyz/rpy composed as URDF defines them, revolute joints
// turning about their axis) and must put every tcp where the library's FK puts it, to 1e-9 m,
// on random poses: nominal arms, large random calibrations, modified DH, a real UR5e factory
// calibration (its cancelling +-204 m offsets), and the tracker frame where the result has it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/shared_data.hpp"
#include "textio/robot_description.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/urdf.hpp"

namespace hivecal::urdf_export_test {
namespace {

using math::kPi;

/// One joint of a URDF document as written.
struct ReadJoint {
  std::string type, parent, child;
  RigidTransform origin;
  Vec3 axis = Vec3::UnitX();
};

std::string attribute(const std::string& element, const std::string& name) {
  const std::size_t at = element.find(" " + name + "=\"");
  if (at == std::string::npos) return "";
  const std::size_t begin = at + name.size() + 3;
  return element.substr(begin, element.find('"', begin) - begin);
}

Vec3 triple(const std::string& text) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  const double y = std::strtod(end, &end);
  const double z = std::strtod(end, &end);
  return Vec3(x, y, z);
}

/// The joints of `urdf` by child link name.
std::map<std::string, ReadJoint> read_joints(const std::string& urdf) {
  std::map<std::string, ReadJoint> joints;
  for (std::size_t at = urdf.find("<joint "); at != std::string::npos; at = urdf.find("<joint ", at + 1)) {
    const std::string block = urdf.substr(at, urdf.find("</joint>", at) - at);
    ReadJoint joint;
    joint.type = attribute(block, "type");
    joint.parent = attribute(block.substr(block.find("<parent")), "link");
    joint.child = attribute(block.substr(block.find("<child")), "link");
    if (block.find("<origin") != std::string::npos) {
      const std::string origin = block.substr(block.find("<origin"));
      textio::UrdfOrigin xyz_rpy;
      xyz_rpy.xyz_m = triple(attribute(origin, "xyz"));
      xyz_rpy.rpy_rad = triple(attribute(origin, "rpy"));
      joint.origin = textio::urdf_transform(xyz_rpy);
    }
    joint.axis = Vec3::UnitX();  // URDF's default
    if (block.find("<axis") != std::string::npos)
      joint.axis = triple(attribute(block.substr(block.find("<axis")), "xyz"));
    joints[joint.child] = joint;
  }
  return joints;
}

/// Rotation by `angle` about unit `axis` (Rodrigues).
Mat3 about_axis(const Vec3& axis, double angle) {
  Mat3 k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Mat3::Identity() + std::sin(angle) * k + (1.0 - std::cos(angle)) * k * k;
}

/// Pose of `link` in the root at joints q (the movable joints in chain order), composed from
/// the URDF's joints.
RigidTransform link_pose(const std::map<std::string, ReadJoint>& joints, const std::string& link, const JointVector& q,
                         int* movable_before = nullptr) {
  int movable = 0;
  RigidTransform pose;
  if (joints.count(link) != 0) {
    const ReadJoint& joint = joints.at(link);
    pose = link_pose(joints, joint.parent, q, &movable).then_after(joint.origin);
    if (joint.type == "revolute" || joint.type == "continuous") {
      pose = pose.then_after(RigidTransform{about_axis(joint.axis.normalized(), q(movable)), Vec3::Zero()});
      ++movable;
    }
  }
  if (movable_before != nullptr) *movable_before = movable;
  return pose;
}

/// Worst distance over 200 random poses between each target's point by the library's FK (in
/// the description's base frame) and the URDF link `tools[k]` composed by this file's reader.
double worst_tool_error_m(const textio::RobotDescription& robot, const std::map<std::string, ReadJoint>& joints,
                          const std::vector<std::string>& tools) {
  const RigidTransform file_base =
      robot.convention == DhConvention::modified ? robot.modified_base.transform() : RigidTransform{};
  Random random(17);
  double worst_m = 0.0;
  for (int pose = 0; pose < 200; ++pose) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-2.0 * kPi, 2.0 * kPi);
    for (std::size_t k = 0; k < tools.size(); ++k) {
      const Vec3 expected = file_base.apply(fk_target_point(robot.model, q, static_cast<int>(k)));
      worst_m = std::fmax(worst_m, (link_pose(joints, tools[k], q).translation_m - expected).norm());
    }
  }
  return worst_m;
}

/// Every target's tcp from the URDF against the library's FK (in the description's base frame).
void expect_chain_equals_model(const textio::RobotDescription& robot, const char* label) {
  const std::map<std::string, ReadJoint> joints = read_joints(textio::format_urdf(robot, nullptr));
  ASSERT_EQ(joints.size(), 7u + static_cast<std::size_t>(robot.target_count)) << label;
  std::vector<std::string> tools;
  for (int k = 0; k < robot.target_count; ++k) tools.push_back(k == 0 ? "tcp" : "tcp_" + std::to_string(k + 1));
  const double worst_m = worst_tool_error_m(robot, joints, tools);
  EXPECT_LE(worst_m, 1e-9) << label;
  std::printf("%-40s URDF vs FK worst %.2e m over 200 poses\n", label, worst_m);
}

TEST(UrdfExport, RpyIsRzRyRxAndSurvivesGimbalLock) {
  Random random(3);
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    Mat3 r = rotation_z(random.uniform(-kPi, kPi)) * rotation_x(random.uniform(-kPi, kPi)) *
             rotation_z(random.uniform(-kPi, kPi));
    if (k % 4 == 0)
      r = rotation_z(random.uniform(-kPi, kPi)) * rotation_x(kPi / 2) * rotation_z(kPi / 2);  // pitch +-90 deg
    const RigidTransform t{r, Vec3(1.0, -2.0, 3.0)};
    const RigidTransform back = textio::urdf_transform(textio::urdf_origin(t));
    worst = std::fmax(worst, (back.rotation - r).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-12);
  // URDF's convention itself: rpy (0.1, 0.2, 0.3) is Rz(0.3) Ry(0.2) Rx(0.1), fixed axes.
  const textio::UrdfOrigin o{Vec3::Zero(), Vec3(0.1, 0.2, 0.3)};
  const Mat3 ry = (Mat3() << std::cos(0.2), 0, std::sin(0.2), 0, 1, 0, -std::sin(0.2), 0, std::cos(0.2)).finished();
  EXPECT_LT((textio::urdf_transform(o).rotation - rotation_z(0.3) * ry * rotation_x(0.1)).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(UrdfExport, NominalAndCalibratedArmsAreTheirChains) {
  for (RobotType type : {RobotType::ur5, RobotType::ur10e}) {
    textio::RobotDescription robot;
    robot.robot = robot_type_name(type);
    robot.model = nominal_model(type);
    robot.model.tool_m = Vec3(0.01, -0.02, 0.17);
    expect_chain_equals_model(robot, robot_type_name(type));
  }
  // Large random calibrations: offsets up to +-pi (pitch +-90 deg origins), lengths +-5 cm,
  // three targets.
  Random random(5);
  for (int trial = 0; trial < 5; ++trial) {
    textio::RobotDescription robot;
    robot.model = nominal_model(RobotType::ur5);
    for (DhJoint& joint : model_joints(&robot.model)) {
      joint.theta_offset_rad += trial == 0 ? kPi / 2 : random.uniform(-kPi, kPi);
      joint.d_m += random.uniform(-0.05, 0.05);
      joint.a_m += random.uniform(-0.05, 0.05);
      joint.alpha_rad += random.uniform(-0.1, 0.1);
    }
    robot.target_count = 3;
    robot.model.tool_m = Vec3(0.05, 0.0, 0.2);
    robot.model.other_tools_m[0] = Vec3(-0.05, 0.03, 0.2);
    robot.model.other_tools_m[1] = Vec3(0.0, -0.06, 0.25);
    expect_chain_equals_model(robot, "random calibrated UR5, 3 targets");
  }
}

TEST(UrdfExport, ModifiedDhArmIsItsChain) {
  // An IRB120-like arm written in Craig's convention.
  const ModifiedDhRow rows[kSixJoints] = {{0.0, 0.0, 0.0, 0.29},    {-kPi / 2, 0.0, -kPi / 2, 0.0},
                                          {0.0, 0.27, 0.0, 0.0},    {-kPi / 2, 0.07, 0.0, 0.302},
                                          {kPi / 2, 0.0, 0.0, 0.0}, {-kPi / 2, 0.0, kPi, 0.072}};
  textio::RobotDescription robot;
  robot.convention = DhConvention::modified;
  ASSERT_EQ(model_from_modified_dh(rows, Vec3(0.0, 0.0, 0.1), &robot.model, &robot.modified_base), Status::ok);
  robot.modified_base.alpha0_rad = 0.01;  // a base offset that is not the identity
  robot.modified_base.a0_m = 0.02;
  expect_chain_equals_model(robot, "modified-DH IRB120-like");
}

TEST(UrdfExport, RealUr5eFactoryCalibrationIsItsChain) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  UrCalibrationDeltas deltas;
  ASSERT_TRUE(textio::read_ur_calibration_conf(test::shared_data_path("ur5e-pendant/calibration.conf"), &deltas).ok());
  textio::RobotDescription robot;
  robot.robot = "ur5e";
  ASSERT_EQ(apply_ur_deltas(nominal_model(RobotType::ur5e), deltas, &robot.model), Status::ok);
  expect_chain_equals_model(robot, "UR5e factory calibration.conf");
}

TEST(UrdfExport, TrackerFrameIsWhereTheResultPutsIt) {
  textio::RobotDescription robot;
  robot.model = nominal_model(RobotType::ur5);
  const RigidTransform base_to_tracker{rotation_z(0.7) * rotation_x(-0.2), Vec3(2.5, -0.4, 0.3)};
  const std::map<std::string, ReadJoint> joints = read_joints(textio::format_urdf(robot, &base_to_tracker));
  const RigidTransform tracker = link_pose(joints, "tracker", JointVector::Zero());
  const JointVector q = (JointVector() << 0.3, -1.2, 1.4, -0.5, 0.9, 0.1).finished();
  const Vec3 in_base = link_pose(joints, "tcp", q).translation_m;
  EXPECT_LT((tracker.inverse().apply(in_base) - base_to_tracker.apply(fk_tool_point(robot.model, q))).norm(), 1e-9);
}

TEST(UrdfExport, RobotJsonReadsBackAsTheSameArm) {
  textio::RobotDescription robot;
  robot.robot = "calibrated-ur5";
  robot.model = nominal_model(RobotType::ur5);
  robot.model.joints[2].a_m += 3.1e-4;
  robot.model.tool_m = Vec3(0.001, 0.002, 0.17);
  robot.has_joint_limits = true;  // J6 beyond one turn, as real arms allow
  robot.lower_rad << -6.28, -1.92, -2.6, -6.28, -6.28, -6.98;
  robot.upper_rad << 6.28, 1.92, 2.6, 6.28, 6.28, 6.98;
  textio::RobotDescription back;
  ASSERT_TRUE(textio::parse_robot_description(textio::format_robot_description(robot), "r.json", &back).ok());
  EXPECT_TRUE(back.has_joint_limits);
  EXPECT_EQ(back.lower_rad.head(kSixJoints),
            robot.lower_rad.head(kSixJoints));  // the joints beyond the arm's are not read
  EXPECT_EQ(back.upper_rad.head(kSixJoints), robot.upper_rad.head(kSixJoints));
  // And through URDF: the limits are the joints' <limit>.
  textio::RobotDescription from_urdf;
  ASSERT_TRUE(textio::parse_urdf_description(textio::format_urdf(robot, nullptr), "r.urdf", &from_urdf).ok());
  EXPECT_TRUE(from_urdf.has_joint_limits);
  EXPECT_EQ(from_urdf.lower_rad.head(kSixJoints), robot.lower_rad.head(kSixJoints));
  EXPECT_EQ(from_urdf.upper_rad.head(kSixJoints), robot.upper_rad.head(kSixJoints));
  EXPECT_EQ(back.robot, robot.robot);
  EXPECT_EQ(back.model.joints[2].a_m, robot.model.joints[2].a_m);
  EXPECT_EQ(back.model.tool_m, robot.model.tool_m);
}

// --- URDF in: --robot-model FILE.urdf ------------------------------------------------------

/// The arm `urdf` describes, read by hivecal; its tool points must be where the URDF (read by
/// this file's own reader) puts the links `tools`, to 1e-9 m on random poses.
textio::RobotDescription expect_read_exactly(const std::string& urdf, const std::vector<std::string>& tools,
                                             const char* label) {
  textio::RobotDescription robot;
  const port::Error read = textio::parse_urdf_description(urdf, "arm.urdf", &robot);
  EXPECT_TRUE(read.ok()) << label << ": " << read.message;
  if (!read.ok()) return robot;
  EXPECT_EQ(robot.target_count, static_cast<int>(tools.size())) << label;
  const double worst_m = worst_tool_error_m(robot, read_joints(urdf), tools);
  EXPECT_LE(worst_m, 1e-9) << label;
  std::printf("%-40s read back: DH vs URDF worst %.2e m\n", label, worst_m);
  return robot;
}

TEST(UrdfImport, ExportedArmsReadBackAsTheSameModel) {
  textio::RobotDescription ur5;
  ur5.robot = "ur5";
  ur5.model = nominal_model(RobotType::ur5);
  ur5.model.tool_m = Vec3(0.0, 0.0, 0.1695);
  const textio::RobotDescription back = expect_read_exactly(textio::format_urdf(ur5, nullptr), {"tcp"}, "UR5 URDF");
  for (int i = 0; i < kSixJoints; ++i) {  // the robot's own table, not an equivalent one turned by pi
    EXPECT_NEAR(back.model.joints[i].a_m, ur5.model.joints[i].a_m, 1e-12) << i;
    EXPECT_NEAR(back.model.joints[i].d_m, ur5.model.joints[i].d_m, 1e-12) << i;
    EXPECT_NEAR(back.model.joints[i].alpha_rad, ur5.model.joints[i].alpha_rad, 1e-12) << i;
    EXPECT_NEAR(back.model.joints[i].theta_offset_rad, ur5.model.joints[i].theta_offset_rad, 1e-12) << i;
  }
  Random random(8);
  for (int trial = 0; trial < 10; ++trial) {
    textio::RobotDescription robot;
    robot.model = nominal_model(RobotType::ur10e);
    for (DhJoint& joint : model_joints(&robot.model)) {
      joint.theta_offset_rad += random.uniform(-0.5, 0.5);
      joint.d_m += random.uniform(-0.05, 0.05);
      joint.a_m += random.uniform(-0.05, 0.05);
      joint.alpha_rad += random.uniform(-0.3, 0.3);  // no two axes parallel or meeting
    }
    robot.target_count = 2;
    robot.model.tool_m = Vec3(0.05, 0.0, 0.2);
    robot.model.other_tools_m[0] = Vec3(-0.05, 0.03, 0.2);
    const RigidTransform base_to_tracker{rotation_z(0.3),
                                         Vec3(2.0, 0.0, 0.5)};  // a tracker link is no joint of the arm
    expect_read_exactly(textio::format_urdf(robot, &base_to_tracker), {"tcp", "tcp_2"}, "random skew-axis arm, 2 tcps");
  }
}

// A URDF written by hand the way robot vendors write them: joint frames not at the DH places,
// axes along -z, y and -x, fixed joints between, a visual origin that must be ignored, a flange
// and a tool0, comments; joint 1 about -z (a modified-DH base Rx(pi)).
TEST(UrdfImport, AnyAxesAndFixedJointsBetween) {
  const std::string urdf = R"(<?xml version="1.0"?>
<!-- a 6R arm -->
<robot name="vendor_arm">
  <link name="base"><visual><origin xyz="9 9 9" rpy="1 2 3"/></visual></link>
  <link name="l1"/><link name="l2"/><link name="l2b"/><link name="l3"/><link name="l4"/><link name="l5"/>
  <link name="l6"/><link name="flange"/><link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 -1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0.02 0.1" rpy="0.1 0 0"/><axis xyz="0 1 0"/></joint>
  <joint name="j2_fixed" type="fixed"><parent link="l2"/><child link="l2b"/>
    <origin xyz="0 0 0.4" rpy="0.05 -0.02 0.3"/></joint>
  <joint name="j3" type="continuous"><parent link="l2b"/><child link="l3"/>
    <origin xyz="0.01 0 0.02"/><axis xyz="0 1 0.01"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.35 0 0.03" rpy="0 0.1 0"/><axis xyz="-1 0 0"/></joint>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0.05 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/>
    <origin xyz="0.08 0 0"/><axis xyz="1 0 0"/></joint>
  <joint name="j6_flange" type="fixed"><parent link="l6"/><child link="flange"/>
    <origin xyz="0.02 0 0" rpy="0 1.5707963267948966 0"/></joint>
  <joint name="flange_tool" type="fixed"><parent link="flange"/><child link="tool0"/>
    <origin xyz="0.01 0.02 0.15"/></joint>
</robot>
)";
  const textio::RobotDescription robot = expect_read_exactly(urdf, {"tool0"}, "vendor arm: any axes, fixed joints");
  EXPECT_EQ(robot.robot, "vendor_arm");
  EXPECT_EQ(robot.convention, DhConvention::modified);  // joint 1 about -z: base Rx(pi)
}

TEST(UrdfImport, WhatIsNoSixJointSerialArmIsRefusedByLine) {
  textio::RobotDescription ur5;
  ur5.model = nominal_model(RobotType::ur5);
  const std::string good = textio::format_urdf(ur5, nullptr);
  struct Case {
    std::string urdf;
    const char* message;
  };
  const auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  const std::string prismatic = replaced(good, "type=\"revolute\"", "type=\"prismatic\"");
  const std::string seven = replaced(good, "type=\"fixed\"", "type=\"revolute\"");  // the flange joint moves too
  const std::string loop = replaced(good, "<child link=\"flange\"/>", "<child link=\"link_3\"/>");
  const std::string skew_base = replaced(good, "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>");
  const Case cases[] = {
      {prismatic, "arm.urdf:13: joint 'joint_1' is 'prismatic': only revolute, continuous and fixed joints"},
      {seven, "arm.urdf: 7 movable joints: hivecal models arms of exactly 6 revolute joints"},
      {loop, "link 'link_3' already has a parent joint (a loop, or not a tree)"},
      {skew_base, "joint 1's axis is not perpendicular to the root link's x axis"},
      {"<robot name=\"x\">\n<joint name=\"a\" type=\"fixed\">\n</robot>",
       "arm.urdf:3: </robot> closes <joint> of line 2"},
      {"{\"dh\": []}", ""},  // not XML: the JSON reader's business, not tried here
      {"<robot><joint name=\"j\" type=\"revolute\"><origin xyz=\"1 2\"/></joint></robot>",
       "arm.urdf:1: <origin xyz> must be three numbers, not '1 2'"},
  };
  for (const Case& c : cases) {
    if (c.message[0] == '\0') continue;
    textio::RobotDescription robot;
    const port::Error read = textio::parse_urdf_description(c.urdf, "arm.urdf", &robot);
    EXPECT_FALSE(read.ok()) << c.message;
    EXPECT_NE(read.message.find(c.message), std::string::npos) << read.message << "\nwanted: " << c.message;
  }
}

}  // namespace
}  // namespace hivecal::urdf_export_test
