// `hivecal export --format urdf`: the chain written is the model. The URDF is read back here
// with a reader of its own (joint origins xyz/rpy composed as URDF defines them, revolute joints
// turning about their axis, prismatic ones sliding along it) and must put every tcp where the
// library's FK puts it, to 1e-9 m, on random poses: nominal arms, large random calibrations,
// modified DH, a real UR5e factory calibration (its cancelling +-204 m offsets), 7-axis arms and
// a UR10 on a rail, and the tracker frame where the result has it.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/urdf_arms.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/robot_description.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/ur_kinematics.hpp"
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
    } else if (joint.type == "prismatic") {
      pose = pose.then_after(RigidTransform{Mat3::Identity(), q(movable) * joint.axis.normalized()});
      ++movable;
    }
  }
  if (movable_before != nullptr) *movable_before = movable;
  return pose;
}

/// Worst distance over 200 random poses (revolute joints +-2 pi rad, prismatic ones +-2 m)
/// between each target's point by the library's FK (in the description's base frame) and the
/// URDF link `tools[k]` composed by this file's reader.
double worst_tool_error_m(const textio::RobotDescription& robot, const std::map<std::string, ReadJoint>& joints,
                          const std::vector<std::string>& tools) {
  const RigidTransform file_base =
      robot.convention == DhConvention::modified ? robot.modified_base.transform() : RigidTransform{};
  Random random(17);
  double worst_m = 0.0;
  for (int pose = 0; pose < 200; ++pose) {
    JointVector q;
    for (int j = 0; j < robot.model.joint_count; ++j)
      q(j) = joint_type(robot.model, j) == JointType::prismatic ? random.uniform(-2.0, 2.0)
                                                                : random.uniform(-2.0 * kPi, 2.0 * kPi);
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
  ASSERT_EQ(joints.size(), static_cast<std::size_t>(robot.model.joint_count + 1 + robot.target_count)) << label;
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
  // An IRB120-like arm written in Craig's convention, and a Franka-like arm of seven joints.
  const ModifiedDhRow irb120[kSixJoints] = {{0.0, 0.0, 0.0, 0.29},    {-kPi / 2, 0.0, -kPi / 2, 0.0},
                                            {0.0, 0.27, 0.0, 0.0},    {-kPi / 2, 0.07, 0.0, 0.302},
                                            {kPi / 2, 0.0, 0.0, 0.0}, {-kPi / 2, 0.0, kPi, 0.072}};
  ModifiedDhRow franka[7];
  test::franka_rows(franka);
  const Span<const ModifiedDhRow> arms[] = {irb120, franka};
  for (const Span<const ModifiedDhRow> rows : arms) {
    if (rows.size() > static_cast<std::size_t>(kMaxJoints)) continue;  // a build of six joints
    textio::RobotDescription robot;
    robot.convention = DhConvention::modified;
    ASSERT_EQ(model_from_modified_dh(rows, Vec3(0.0, 0.0, 0.1), &robot.model, &robot.modified_base), Status::ok);
    robot.modified_base.alpha0_rad = 0.01;  // a base offset that is not the identity
    robot.modified_base.a0_m = 0.02;
    expect_chain_equals_model(robot, rows.size() == 7 ? "modified-DH Franka-like" : "modified-DH IRB120-like");
  }
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

TEST(UrdfImport, WhatIsNoSerialArmIsRefusedByLine) {
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
  const std::string floating = replaced(good, "type=\"revolute\"", "type=\"floating\"");
  const std::string planar = replaced(good, "type=\"revolute\"", "type=\"planar\"");
  std::string fixed_only = good;
  for (std::size_t at = fixed_only.find("\"revolute\""); at != std::string::npos; at = fixed_only.find("\"revolute\""))
    fixed_only.replace(at, 10, "\"fixed\"");
  const std::string loop = replaced(good, "<child link=\"flange\"/>", "<child link=\"link_3\"/>");
  const std::string skew_base = replaced(good, "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>");
  const Case cases[] = {
      {floating,
       "arm.urdf:13: joint 'joint_1' is 'floating' (a free body, six degrees of freedom): only revolute, continuous, "
       "prismatic and fixed joints make a serial arm hivecal models"},
      {planar, "arm.urdf:13: joint 'joint_1' is 'planar' (a motion in a plane, three degrees of freedom): only"},
      {fixed_only, "arm.urdf: no movable joint: an arm has 1 to "},
      {loop,
       "joint 'flange_joint': link 'link_3' already has a parent joint, 'joint_3' of line 27 (a loop, or not a tree)"},
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

// --- what a hostile file may hold: many links, deep nesting -------------------------------

/// The nominal UR5 as hivecal exports it, with `extra` inserted before </robot>.
std::string ur5_urdf_with(const std::string& extra) {
  textio::RobotDescription ur5;
  ur5.model = nominal_model(RobotType::ur5);
  std::string urdf = textio::format_urdf(ur5, nullptr);
  return urdf.insert(urdf.rfind("</robot>"), extra);
}

/// Seconds `parse` takes on `urdf`, with its error.
double seconds_to_read(const std::string& urdf, textio::RobotDescription* robot, port::Error* error) {
  const auto start = std::chrono::steady_clock::now();
  *error = textio::parse_urdf_description(urdf, "arm.urdf", robot);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// 200,000 fixed links in a line after the tcp, and 200,000 fixed children of link_6: read in
// linear time and without recursion (they overflowed the stack and took minutes). Not a timing
// test: the bound only tells a hang from a read (~1 s here, emulated targets several times that;
// the quadratic walk took ~2 minutes for the children natively).
TEST(UrdfImport, ManyFixedLinksReadInLinearTimeWithoutRecursion) {
  constexpr int kLinks = 200000;
  std::string line;
  std::string parent = "tcp";
  for (int i = 0; i < kLinks; ++i) {
    const std::string link = "x" + std::to_string(i);
    line += "<link name=\"" + link + "\"/><joint name=\"j" + link + "\" type=\"fixed\"><parent link=\"" + parent +
            "\"/><child link=\"" + link + "\"/><origin xyz=\"0 0 0.000001\"/></joint>\n";
    parent = link;
  }
  line += "<link name=\"tool0\"/><joint name=\"jt\" type=\"fixed\"><parent link=\"" + parent +
          "\"/><child link=\"tool0\"/></joint>\n";
  std::string children;
  for (int i = 0; i < kLinks; ++i) {
    const std::string link = "c" + std::to_string(i);
    children += "<link name=\"" + link + "\"/><joint name=\"j" + link +
                "\" type=\"fixed\"><parent link=\"link_6\"/><child link=\"" + link + "\"/></joint>\n";
  }
  const RobotModel ur5 = nominal_model(RobotType::ur5);
  for (const std::string* extra : {&line, &children}) {
    textio::RobotDescription robot;
    port::Error error;
    const double seconds = seconds_to_read(ur5_urdf_with(*extra), &robot, &error);
    ASSERT_TRUE(error.ok()) << error.message;
    EXPECT_LT(seconds, 30.0);
    for (int i = 0; i < kSixJoints; ++i) EXPECT_NEAR(robot.model.joints[i].a_m, ur5.joints[i].a_m, 1e-12) << i;
    // The line's tool0 is 200,000 x 1 um beyond the tcp; the children leave the tcp where it is.
    EXPECT_NEAR(robot.model.tool_m.z(), extra == &line ? kLinks * 1e-6 : 0.0, 1e-9);
    std::printf("%d fixed links (%s): read in %.2f s\n", kLinks, extra == &line ? "a line" : "children", seconds);
  }
}

TEST(UrdfImport, DeepNestingIsRefusedByLine) {
  std::string nested;
  for (int i = 0; i < 100000; ++i) nested += "<a>\n";
  textio::RobotDescription robot;
  port::Error error;
  seconds_to_read(ur5_urdf_with(nested), &robot, &error);
  EXPECT_NE(error.message.find("elements nested deeper than 64: not a URDF"), std::string::npos) << error.message;
  EXPECT_EQ(error.message.rfind("arm.urdf:", 0), 0u) << error.message;
}

/// The 1-based line of the first `needle` in `text`.
int line_of(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

/// `text` with the first `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  return text.replace(text.find(from), from.size(), to);
}

void expect_refused(const std::string& urdf, const std::string& message) {
  textio::RobotDescription robot;
  const port::Error read = textio::parse_urdf_description(urdf, "arm.urdf", &robot);
  EXPECT_FALSE(read.ok()) << message;
  EXPECT_NE(read.message.find(message), std::string::npos) << read.message << "\nwanted: " << message;
}

// Names given twice, a joint that is its own parent, a joint that follows another (mimic) in the
// arm, two <robot> elements: each refused by line, saying what it is.
TEST(UrdfImport, TwiceNamedLoopsMimicAndTwoRobotsAreRefusedByLine) {
  const std::string good = ur5_urdf_with("");
  const std::string link_twice = ur5_urdf_with("  <link name=\"link_3\"/>\n");
  expect_refused(link_twice, "arm.urdf:" + std::to_string(line_of(link_twice, "</robot>") - 1) +
                                 ": a second link named 'link_3' (the first at line " +
                                 std::to_string(line_of(good, "<link name=\"link_3\"")) +
                                 "): each link needs a name of its own");
  const std::string joint_twice = replaced(good, "<joint name=\"joint_4\"", "<joint name=\"joint_3\"");
  expect_refused(joint_twice, "arm.urdf:" + std::to_string(line_of(good, "<joint name=\"joint_4\"")) +
                                  ": a second joint named 'joint_3' (the first at line " +
                                  std::to_string(line_of(good, "<joint name=\"joint_3\"")) + ")");
  const std::string self_loop = ur5_urdf_with(
      "  <link name=\"spinner\"/>\n  <joint name=\"spin\" type=\"fixed\"><parent link=\"spinner\"/><child "
      "link=\"spinner\"/></joint>\n");
  expect_refused(self_loop, "arm.urdf:" + std::to_string(line_of(self_loop, "<joint name=\"spin\"")) +
                                ": joint 'spin' has link 'spinner' as its parent and its child: a loop");
  const std::string mimic =
      replaced(good, "<child link=\"link_4\"/>", "<child link=\"link_4\"/>\n<mimic joint=\"joint_3\"/>");
  expect_refused(mimic,
                 "arm.urdf:" + std::to_string(line_of(mimic, "<mimic")) +
                     ": joint 'joint_4' follows joint 'joint_3' (<mimic>): each joint of the arm must move on its own");
  const std::string two_robots = good + good.substr(good.find("<robot"));
  expect_refused(two_robots, "arm.urdf:" + std::to_string(line_of(two_robots, "</robot>") + 1) +
                                 ": a second top-level element <robot> after the <robot> of line " +
                                 std::to_string(line_of(good, "<robot")) + ": a URDF is one <robot> element");
}

// Text of the file quoted in a message is cut after 80 bytes (docs/cli.md), whatever its length.
TEST(UrdfImport, QuotesOfTheFileAreCutAt80Bytes) {
  const std::string long_text(4000, 'x');
  const std::string good = ur5_urdf_with("");
  std::string no_tcp = good;  // the tcp renamed, and a second tip with a long name
  for (std::size_t at = no_tcp.find("\"tcp\""); at != std::string::npos; at = no_tcp.find("\"tcp\""))
    no_tcp.replace(at, 5, "\"tip\"");
  no_tcp.insert(no_tcp.rfind("</robot>"), "<link name=\"" + long_text +
                                              "\"/><joint name=\"j\" type=\"fixed\"><parent "
                                              "link=\"link_6\"/><child link=\"" +
                                              long_text + "\"/></joint>\n");
  for (const std::string& urdf : {replaced(good, "type=\"revolute\"", "type=\"" + long_text + "\""),
                                  replaced(good, "<origin xyz=\"0 0 0\"", "<origin xyz=\"" + long_text + "\""),
                                  replaced(replaced(good, "name=\"joint_4\"", "name=\"" + long_text + "\""),
                                           "name=\"joint_5\"", "name=\"" + long_text + "\""),
                                  no_tcp}) {
    textio::RobotDescription robot;
    const port::Error read = textio::parse_urdf_description(urdf, "arm.urdf", &robot);
    ASSERT_FALSE(read.ok());
    EXPECT_LT(read.message.size(), 300u) << read.message;
    EXPECT_NE(read.message.find("...[4000 bytes]"), std::string::npos) << read.message;
  }
}

// Frame 6 is placed at the 'flange' fixed to the arm's end only: a link of that name elsewhere
// (here a mounting flange 1.9 m above the base) leaves the model as it is without it.
TEST(UrdfImport, OnlyTheArmsOwnFlangePlacesFrame6) {
  std::string arm = ur5_urdf_with("");
  for (std::size_t at = arm.find("\"flange\""); at != std::string::npos; at = arm.find("\"flange\""))
    arm.replace(at, 8, "\"wrist_plate\"");
  const std::string mounted = replaced(arm, "</robot>",
                                       "  <link name=\"flange\"/>\n  <joint name=\"mount\" type=\"fixed\"><parent "
                                       "link=\"base_link\"/><child link=\"flange\"/><origin xyz=\"0 0 1.9\"/></joint>\n"
                                       "</robot>");
  textio::RobotDescription alone;
  textio::RobotDescription with_mount;
  ASSERT_TRUE(textio::parse_urdf_description(arm, "arm.urdf", &alone).ok());
  const port::Error read = textio::parse_urdf_description(mounted, "arm.urdf", &with_mount);
  ASSERT_TRUE(read.ok()) << read.message;
  for (int i = 0; i < kSixJoints; ++i) {
    EXPECT_EQ(with_mount.model.joints[i].d_m, alone.model.joints[i].d_m) << i;
    EXPECT_EQ(with_mount.model.joints[i].a_m, alone.model.joints[i].a_m) << i;
    EXPECT_EQ(with_mount.model.joints[i].alpha_rad, alone.model.joints[i].alpha_rad) << i;
    EXPECT_EQ(with_mount.model.joints[i].theta_offset_rad, alone.model.joints[i].theta_offset_rad) << i;
  }
  EXPECT_EQ(with_mount.model.tool_m, alone.model.tool_m);
  EXPECT_EQ(with_mount.model.joints[5].d_m, 0.0);  // frame 6 at joint 6's child, the tool point 82.3 mm along z
}

// The robot description's bounds hold for a URDF too (one place: textio::beyond_bound): on each
// origin by line, on the DH table it makes and on its tool points.
TEST(UrdfImport, TheDescriptionsBoundsHoldByLine) {
  const std::string good = ur5_urdf_with("");
  const std::string far = replaced(good, "<origin xyz=\"-0.42499999999999999 0 0\"", "<origin xyz=\"-1000000 0 0\"");
  expect_refused(far, "arm.urdf:" + std::to_string(line_of(far, "-1000000")) +
                          ": joint 'joint_3' <origin xyz>, x = -1000000 m is beyond 1000 m: not a robot");
  const std::string degrees = replaced(good, "rpy=\"1.5707963267948966 0 0\"", "rpy=\"90 0 0\"");
  expect_refused(degrees, "arm.urdf:" + std::to_string(line_of(degrees, "\"90 0 0\"")) +
                              ": joint 'joint_2' <origin rpy>, roll = 90 rad is beyond 12.566370614359172 rad (two "
                              "turns): degrees?");
  const std::string long_tool = replaced(good, "<child link=\"tcp\"/>\n    <origin xyz=\"0 0 0\"",
                                         "<child link=\"tcp\"/>\n    <origin xyz=\"0 0 50\"");
  expect_refused(long_tool, "arm.urdf: tool point 1 (flange frame), z = 49.9999");
  // Joint 3 tilted by 1 urad towards joint 2: the axes meet 425 km away, and so would its d.
  std::string nearly_parallel = good;
  const std::size_t axis = nearly_parallel.find("<axis", nearly_parallel.find("<joint name=\"joint_3\""));
  nearly_parallel.replace(axis, std::string("<axis xyz=\"0 0 1\"/>").size(), "<axis xyz=\"0.000001 0 1\"/>");
  expect_refused(nearly_parallel, "arm.urdf: its DH table, row 2: d = ");
}

// --- a ROS ur_description URDF ----------------------------------------------------------

/// An origin element of `transform` (xyz/rpy to the bit).
std::string origin_of(const RigidTransform& transform) {
  const textio::UrdfOrigin origin = textio::urdf_origin(transform);
  const auto triple = [](const Vec3& v) {
    return textio::format_double(v.x() + 0.0) + " " + textio::format_double(v.y() + 0.0) + " " +
           textio::format_double(v.z() + 0.0);
  };
  return "<origin xyz=\"" + triple(origin.xyz_m) + "\" rpy=\"" + triple(origin.rpy_rad) + "\"/>";
}

/// `model` (a UR table) in the shape of ROS's ur_description (ur_macro.xacro): base_link (REP-103:
/// x forward) -> base_link_inertia turned by pi about z (UR's own base: x backward) -> the six
/// joints at the kinematics YAML's frames (shoulder_link .. wrist_3_link) -> flange (ROS-Industrial:
/// x out of the flange) -> tool0 (z out of the flange: UR's tool flange frame); base_link -> base
/// (UR's base again, turned by pi).
std::string ros_ur_description(const RobotModel& model) {
  textio::UrKinematics kinematics;
  std::string why;
  EXPECT_TRUE(textio::ur_kinematics_from_model(model, &kinematics, &why)) << why;
  const char* const links[] = {"shoulder_link", "upper_arm_link", "forearm_link",
                               "wrist_1_link",  "wrist_2_link",   "wrist_3_link"};
  const char* const joints[] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  const auto fixed = [](const std::string& name, const std::string& parent, const std::string& child,
                        const std::string& rpy) {
    return "  <joint name=\"" + name + "\" type=\"fixed\">\n    <parent link=\"" + parent + "\"/>\n    <child link=\"" +
           child + "\"/>\n    <origin xyz=\"0 0 0\" rpy=\"" + rpy + "\"/>\n  </joint>\n";
  };
  std::string urdf =
      "<?xml version=\"1.0\"?>\n<robot name=\"ur5\">\n  <link name=\"base_link\"/>\n"
      "  <link name=\"base_link_inertia\"/>\n";
  for (const char* link : links) urdf += "  <link name=\"" + std::string(link) + "\"/>\n";
  urdf += "  <link name=\"base\"/>\n  <link name=\"flange\"/>\n  <link name=\"tool0\"/>\n";
  urdf += fixed("base_link-base_link_inertia", "base_link", "base_link_inertia", "0 0 3.141592653589793");
  std::string parent = "base_link_inertia";
  for (int i = 0; i < kSixJoints; ++i) {
    urdf += "  <joint name=\"" + std::string(joints[i]) + "\" type=\"revolute\">\n    <parent link=\"" + parent +
            "\"/>\n    <child link=\"" + links[i] + "\"/>\n    " + origin_of(kinematics.joint_frames[i]) +
            "\n    <axis xyz=\"0 0 1\"/>\n    <limit lower=\"-6.283185307179586\" upper=\"6.283185307179586\" "
            "effort=\"150\" velocity=\"3.15\"/>\n  </joint>\n";
    parent = links[i];
  }
  urdf += fixed("base_link-base_fixed_joint", "base_link", "base", "0 0 3.141592653589793");
  urdf += fixed("wrist_3-flange", "wrist_3_link", "flange", "0 -1.5707963267948966 -1.5707963267948966");
  urdf += fixed("flange-tool0", "flange", "tool0", "1.5707963267948966 0 1.5707963267948966");
  return urdf + "</robot>\n";
}

/// Rz(pi), exactly: UR's base in ROS's base_link.
const RigidTransform kTurnedByPi{Vec3(-1.0, -1.0, 1.0).asDiagonal(), Vec3::Zero()};

/// Worst distance over 1,000 random joint vectors between link `tool` of `urdf` (by this file's
/// own reader) and `model`'s tool point turned by pi (UR's base in the URDF's root).
double worst_turned_error_m(const std::string& urdf, const std::string& tool, const RobotModel& model) {
  const std::map<std::string, ReadJoint> joints = read_joints(urdf);
  Random random(5);
  double worst_m = 0.0;
  for (int pose = 0; pose < 1000; ++pose) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-2.0 * kPi, 2.0 * kPi);
    const Vec3 expected = kTurnedByPi.apply(fk_tool_point(model, q));
    worst_m = std::fmax(worst_m, (link_pose(joints, tool, q).translation_m - expected).norm());
  }
  return worst_m;
}

/// `model` with its tool point at (0.01, 0.02, 0.15) m.
RobotModel with_probe(RobotModel model) {
  model.tool_m = Vec3(0.01, 0.02, 0.15);
  return model;
}

/// The ROS description of `model` with a tcp 10, 20, 150 mm from tool0 (UR's TCP on the tool flange).
std::string ros_ur_description_with_tcp(const RobotModel& model) {
  return replaced(ros_ur_description(model), "</robot>",
                  "  <link name=\"tcp\"/>\n  <joint name=\"tool0-tcp\" type=\"fixed\"><parent link=\"tool0\"/><child "
                  "link=\"tcp\"/><origin xyz=\"0.01 0.02 0.15\"/></joint>\n</robot>");
}

// ROS's ur_description (base_link turned by pi from UR's base, a ROS-Industrial flange with x out
// of it) is read as UR's own table in UR's base: the same chain exactly (1e-12 m by FK on random
// joints), with the tcp where UR's TCP is, in the tool flange frame. It read as alpha_1 = -90 deg,
// a_2 = +425 mm, a_3 = +392.25 mm and alpha_6 = 90 deg: UR's deltas and YAML came out turned.
TEST(UrdfImport, RosUrDescriptionIsReadAsUrsOwnTable) {
  const RobotModel ur5 = nominal_model(RobotType::ur5);
  const std::string urdf = ros_ur_description_with_tcp(ur5);
  textio::RobotDescription robot;
  const port::Error read = textio::parse_urdf_description(urdf, "ur5.urdf", &robot);
  ASSERT_TRUE(read.ok()) << read.message;
  EXPECT_TRUE(robot.base_turned_by_pi);
  EXPECT_EQ(robot.convention, DhConvention::standard);
  for (int i = 0; i < kSixJoints; ++i) {
    EXPECT_NEAR(robot.model.joints[i].theta_offset_rad, ur5.joints[i].theta_offset_rad, 1e-12) << i;
    EXPECT_NEAR(robot.model.joints[i].d_m, ur5.joints[i].d_m, 1e-12) << i;
    EXPECT_NEAR(robot.model.joints[i].a_m, ur5.joints[i].a_m, 1e-12) << i;
    EXPECT_NEAR(robot.model.joints[i].alpha_rad, ur5.joints[i].alpha_rad, 1e-12) << i;
  }
  EXPECT_LE((robot.model.tool_m - Vec3(0.01, 0.02, 0.15)).norm(), 1e-12);
  const double worst_m = worst_turned_error_m(urdf, "tcp", robot.model);
  EXPECT_LE(worst_m, 1e-12);
  std::printf("ROS ur_description UR5: UR's table, Rz(pi) FK vs URDF worst %.2e m\n", worst_m);
  // Every built-in UR the same way.
  for (const RobotType type :
       {RobotType::ur3, RobotType::ur10, RobotType::ur3e, RobotType::ur5e, RobotType::ur10e, RobotType::ur16e}) {
    const std::string other = ros_ur_description_with_tcp(nominal_model(type));
    textio::RobotDescription back;
    ASSERT_TRUE(textio::parse_urdf_description(other, "ur.urdf", &back).ok()) << robot_type_name(type);
    EXPECT_TRUE(back.base_turned_by_pi && textio::is_ur_table(back.model)) << robot_type_name(type);
    EXPECT_LE(worst_turned_error_m(other, "tcp", back.model), 1e-12) << robot_type_name(type);
    for (int i = 0; i < kSixJoints; ++i)
      EXPECT_NEAR(back.model.joints[i].a_m, nominal_model(type).joints[i].a_m, 1e-12) << robot_type_name(type);
  }
}

// A table turned by pi (as the reader made it of a ROS URDF before, or a description written so)
// is turned back before UR's own formats use it: the same YAML, calibration.conf deltas with UR's
// signs, and a controller's calibration.conf applied with them.
TEST(UrTable, TurnedTablesGiveUrsOwnOutputs) {
  const RobotModel nominal = with_probe(nominal_model(RobotType::ur5e));
  Random random(4);
  RobotModel calibrated = nominal;
  for (DhJoint& joint : calibrated.joints) {
    joint.theta_offset_rad += random.uniform(-1e-3, 1e-3);
    joint.d_m += random.uniform(-1e-3, 1e-3);
    joint.a_m += random.uniform(-1e-3, 1e-3);
    joint.alpha_rad += random.uniform(-1e-3, 1e-3);
  }
  const RobotModel turned = textio::turned_by_pi(calibrated);
  EXPECT_TRUE(textio::is_ur_table(calibrated) && !textio::is_ur_table_turned(calibrated));
  EXPECT_TRUE(textio::is_ur_table_turned(turned));
  double worst_m = 0.0;
  for (int pose = 0; pose < 1000; ++pose) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-2.0 * kPi, 2.0 * kPi);
    worst_m = std::fmax(worst_m, (kTurnedByPi.apply(fk_tool_point(turned, q)) - fk_tool_point(calibrated, q)).norm());
  }
  EXPECT_LE(worst_m, 1e-12);  // the same chain
  const RobotModel back = textio::turned_by_pi(turned);
  for (int i = 0; i < kSixJoints; ++i) {  // turning twice gives the model back, to the bit
    EXPECT_EQ(back.joints[i].a_m, calibrated.joints[i].a_m);
    EXPECT_EQ(back.joints[i].alpha_rad, calibrated.joints[i].alpha_rad);
  }
  textio::UrKinematics own;
  textio::UrKinematics from_turned;
  std::string why;
  ASSERT_TRUE(textio::ur_kinematics_from_model(calibrated, &own, &why));
  ASSERT_TRUE(textio::ur_kinematics_from_model(turned, &from_turned, &why));
  EXPECT_EQ(textio::format_ur_kinematics_yaml(from_turned, "h"), textio::format_ur_kinematics_yaml(own, "h"));
  const UrCalibrationDeltas expected = ur_deltas_between(nominal, calibrated);
  const UrCalibrationDeltas deltas = textio::ur_deltas_in_ur_table(textio::turned_by_pi(nominal), turned);
  EXPECT_EQ(textio::format_ur_calibration_conf(deltas), textio::format_ur_calibration_conf(expected));
  const test::TempDir dir("hivecal_urtable");
  const std::string conf = dir.write("calibration.conf", textio::format_ur_calibration_conf(expected));
  RobotModel applied;
  const port::Error read = textio::read_ur_calibrated_model(conf, textio::turned_by_pi(nominal), "ur5e", &applied);
  ASSERT_TRUE(read.ok()) << read.message;
  RobotModel expected_applied;
  ASSERT_EQ(apply_ur_deltas(nominal, expected, &expected_applied), Status::ok);
  for (int i = 0; i < kSixJoints; ++i) {  // in the turned base still, the deltas applied with UR's signs
    EXPECT_NEAR(applied.joints[i].a_m, textio::turned_by_pi(expected_applied).joints[i].a_m, 1e-15) << i;
    EXPECT_NEAR(applied.joints[i].alpha_rad, textio::turned_by_pi(expected_applied).joints[i].alpha_rad, 1e-15) << i;
    EXPECT_NEAR(applied.joints[i].d_m, expected_applied.joints[i].d_m, 1e-15) << i;
  }
}

/// The numbers of a UR kinematics YAML or calibration.conf, in order.
std::vector<double> numbers_of(const std::string& text) {
  std::vector<double> numbers;
  for (const char* at = text.c_str(); *at != '\0'; ++at) {
    if (!((*at >= '0' && *at <= '9') || *at == '-') || (at > text.c_str() && std::isalnum(at[-1]) != 0)) continue;
    char* end = nullptr;
    const double value = std::strtod(at, &end);
    if (end == at) continue;
    numbers.push_back(value);
    at = end - 1;
  }
  return numbers;
}

void expect_same_numbers(const std::string& a, const std::string& b, double tolerance, const char* what) {
  const std::vector<double> x = numbers_of(a);
  const std::vector<double> y = numbers_of(b);
  ASSERT_EQ(x.size(), y.size()) << what;
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(x[i], y[i], tolerance) << what << " number " << i;
}

// The UR outputs of a ROS ur_description UR5 are the built-in UR5's: calibrate --ur-deltas (they
// had a's and alpha's signs flipped), export --format ur-kinematics (180 deg off) and
// --ur-calibration applied (with the wrong sign).
TEST(UrdfImport, RosUrDescriptionGivesTheBuiltInArmsUrOutputs) {
  const test::TempDir dir("hivecal_rosur");
  ASSERT_FALSE(dir.path().empty());
  const std::string urdf = dir.write("ur5.urdf", ros_ur_description(nominal_model(RobotType::ur5)));
  Random random(54);
  const RobotModel truth =
      test::perturbed_keeping_parallel(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4, Vec3(0.01, 0.02, 0.15));
  static Dataset<150> samples;
  samples.clear();
  test::fill_other_arm(truth, test::example_base_to_tracker(), 150, 1e-6, &random, &samples);
  const std::string csv = dir.write("samples.csv", textio::format_samples_csv(samples.samples(), kSixJoints));
  std::string deltas[2];
  std::string yaml[2];
  std::string applied[2];
  const std::string conf = dir.write(
      "calibration.conf", textio::format_ur_calibration_conf(ur_deltas_between(nominal_model(RobotType::ur5), truth)));
  const std::string models[2] = {urdf, "ur5"};
  for (int k = 0; k < 2; ++k) {
    const std::string at = dir.path() + "/" + std::to_string(k);
    ASSERT_EQ(test::run(cli::calibrate_main,
                        {"--robot-model", models[k], "--samples", csv, "--method", "lm", "--tool", "0.01,0.02,0.15",
                         "--split", "1", "--out", at + ".json", "--ur-deltas", at + ".conf", "--quiet"}),
              cli::kExitOk);
    ASSERT_EQ(test::run(cli::export_main, {"--robot-model", models[k], "--format", "ur-kinematics", "--ur-hash", "h",
                                           "--out", at + ".yaml"}),
              cli::kExitOk);
    ASSERT_EQ(test::run(cli::export_main, {"--robot-model", models[k], "--ur-calibration", conf, "--format",
                                           "robot-json", "--out", at + "-applied.json"}),
              cli::kExitOk);
    deltas[k] = test::read_text_file(at + ".conf");
    yaml[k] = test::read_text_file(at + ".yaml");
    applied[k] = test::read_text_file(at + "-applied.json");
  }
  expect_same_numbers(deltas[0], deltas[1], 1e-9, "--ur-deltas");
  expect_same_numbers(yaml[0], yaml[1], 1e-12, "ur-kinematics YAML");
  applied[0].replace(applied[0].find("\"tool\""), std::string::npos, "");  // the URDF's tool0 is its tool point
  applied[1].replace(applied[1].find("\"tool\""), std::string::npos, "");
  expect_same_numbers(applied[0], applied[1], 1e-12, "--ur-calibration applied");
}

// --- arms of other joint counts: 7-axis arms, a UR10 on a rail ------------------------------

// The test kit's perturbed 7-axis arms (an iiwa 14, a Franka) and its UR10 on a rail go out as
// seven joints, the rail's prismatic with its limits in metres, each the model's chain (the
// Franka in its own modified DH: ModifiedDhArmIsItsChain).
TEST(UrdfExport, SevenAxisArmsAndARailAreTheirChains) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  Random random(53);
  for (const test::ManyJointArm arm : test::kManyJointArms) {
    const textio::RobotDescription robot = test::many_joint_description(arm, &random);
    ASSERT_EQ(robot.model.joint_count, 7);
    expect_chain_equals_model(robot, test::many_joint_arm_name(arm));
    const std::string urdf = textio::format_urdf(robot, nullptr);
    const bool rail = arm == test::ManyJointArm::rail_ur10;
    EXPECT_EQ(urdf.find("<joint name=\"joint_1\" type=\"prismatic\">") != std::string::npos, rail);
    EXPECT_EQ(urdf.find("type=\"prismatic\"", urdf.find("joint_2")), std::string::npos);
    const std::string first_limit = urdf.substr(urdf.find("<limit", urdf.find("joint_1")));
    EXPECT_EQ(first_limit.rfind(rail ? "<limit lower=\"0\" upper=\"2\" effort=\"1000\" velocity=\"1\"/>"
                                     : "<limit lower=\"-2.8999999999999999\" upper=\"2.8999999999999999\"",
                                0),
              0u)
        << first_limit.substr(0, 80);
    EXPECT_NE(urdf.find("<joint name=\"joint_7\" type=\"revolute\">"), std::string::npos);
    EXPECT_EQ(urdf.find("joint_8"), std::string::npos);
  }
}

// What export writes for them reads back as the same arm: seven joints, the same types and
// limits, every tool point where the URDF has it.
TEST(UrdfImport, ExportedSevenAxisArmsAndARailReadBackAsTheSameArm) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  Random random(54);
  for (const test::ManyJointArm arm : test::kManyJointArms) {
    const textio::RobotDescription robot = test::many_joint_description(arm, &random);
    const textio::RobotDescription back =
        expect_read_exactly(textio::format_urdf(robot, nullptr), {"tcp", "tcp_2"}, test::many_joint_arm_name(arm));
    EXPECT_EQ(back.model.joint_count, 7) << test::many_joint_arm_name(arm);
    EXPECT_EQ(back.model.prismatic_joints, robot.model.prismatic_joints) << test::many_joint_arm_name(arm);
    EXPECT_TRUE(back.has_joint_limits);
    EXPECT_EQ(back.lower_rad.head(7), robot.lower_rad.head(7)) << test::many_joint_arm_name(arm);
    EXPECT_EQ(back.upper_rad.head(7), robot.upper_rad.head(7)) << test::many_joint_arm_name(arm);
    EXPECT_EQ(check_joint_layout(back.model), Status::ok);
  }
}

// The test fixture: a UR10 as ROS's ur_description writes it, on a rail along the world's y.
// Joint 1 is the rail (prismatic, 0 .. 3 m), joints 2 .. 7 the UR10's; the DH model is exact.
TEST(UrdfImport, UrTenOnARailReadsAsSevenJointsTheRailFirst) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const textio::RobotDescription robot = expect_read_exactly(test::kRailUr10Urdf, {"tcp"}, "UR10 on a rail");
  EXPECT_EQ(robot.robot, "ur10_on_rail");
  ASSERT_EQ(robot.model.joint_count, 7);
  EXPECT_EQ(robot.model.prismatic_joints, 1u);          // the rail, and only it
  EXPECT_EQ(robot.convention, DhConvention::modified);  // the rail along y: a base Rx(-pi/2)
  EXPECT_FALSE(robot.base_turned_by_pi);                // not a six-joint UR arm
  EXPECT_TRUE(robot.has_joint_limits);
  EXPECT_EQ(robot.lower_rad(0), test::kRailLower_m);
  EXPECT_EQ(robot.upper_rad(0), test::kRailUpper_m);
  EXPECT_EQ(robot.lower_rad(3), -kPi);  // the elbow's +-180 deg
  EXPECT_EQ(robot.upper_rad(3), kPi);
  const RobotModel ur10 = nominal_model(RobotType::ur10);
  EXPECT_NEAR(std::fabs(robot.model.joints[2].a_m), std::fabs(ur10.joints[1].a_m), 1e-9);  // upper arm
  EXPECT_NEAR(std::fabs(robot.model.joints[3].a_m), std::fabs(ur10.joints[2].a_m), 1e-9);  // forearm
}

// What is no serial arm in the fixture is refused by line: a joint that follows another, a
// link with two parents, joints going round above the arm, a floating or planar joint; and an
// arm of more joints than the build holds, at the first joint beyond them.
TEST(UrdfImport, RailArmFaultsAndTooManyJointsAreRefusedByLine) {
  const std::string good = test::kRailUr10Urdf;
  const std::string mimic = replaced(good, "<child link=\"forearm_link\"/>",
                                     "<child link=\"forearm_link\"/>\n    <mimic joint=\"shoulder_lift_joint\"/>");
  expect_refused(mimic,
                 "arm.urdf:" + std::to_string(line_of(mimic, "<mimic")) +
                     ": joint 'elbow_joint' follows joint 'shoulder_lift_joint' (<mimic>): each joint of the arm "
                     "must move on its own");
  const std::string second_parent = replaced(good, "<child link=\"tcp\"/>", "<child link=\"carriage\"/>");
  expect_refused(second_parent, "arm.urdf:" + std::to_string(line_of(good, "<joint name=\"tool0-tcp\"")) +
                                    ": joint 'tool0-tcp': link 'carriage' already has a parent joint, 'rail_joint' of "
                                    "line " +
                                    std::to_string(line_of(good, "<joint name=\"rail_joint\"")) +
                                    " (a loop, or not a tree)");
  const std::string round = replaced(good, "<parent link=\"world\"/>", "<parent link=\"tcp\"/>");
  expect_refused(round, "arm.urdf:");
  expect_refused(round, ": the joints above link 'wrist_3_link' go round in a loop: no root link");
  const std::string floating =
      replaced(good, "\"carriage-base_link\" type=\"fixed\"", "\"carriage-base_link\" type=\"floating\"");
  expect_refused(floating, "arm.urdf:" + std::to_string(line_of(good, "<joint name=\"carriage-base_link\"")) +
                               ": joint 'carriage-base_link' is 'floating' (a free body, six degrees of freedom)");
  const std::string planar = replaced(good, "type=\"prismatic\"", "type=\"planar\"");
  expect_refused(planar, "arm.urdf:" + std::to_string(line_of(good, "<joint name=\"rail_joint\"")) +
                             ": joint 'rail_joint' is 'planar' (a motion in a plane, three degrees of freedom)");
  // kMaxJoints joints read; one more (the flange joint turning too) is refused at that joint.
  textio::RobotDescription longest;
  longest.model.joint_count = kMaxJoints;
  for (int j = 0; j < kMaxJoints; ++j) longest.model.joints[j] = DhJoint{0.1 * j, 0.2, 0.1, j % 2 == 0 ? 1.2 : -0.7};
  const std::string most = textio::format_urdf(longest, nullptr);
  textio::RobotDescription read;
  ASSERT_TRUE(textio::parse_urdf_description(most, "arm.urdf", &read).ok());
  EXPECT_EQ(read.model.joint_count, kMaxJoints);
  const std::string too_many = replaced(most, "\"flange_joint\" type=\"fixed\"", "\"flange_joint\" type=\"revolute\"");
  expect_refused(too_many, "arm.urdf:" + std::to_string(line_of(too_many, "<joint name=\"flange_joint\"")) +
                               ": joint 'flange_joint' is movable joint " + std::to_string(kMaxJoints + 1) +
                               ": hivecal models arms of 1 to " + std::to_string(kMaxJoints) +
                               " joints (this build's capacity)");
}

}  // namespace
}  // namespace hivecal::urdf_export_test
