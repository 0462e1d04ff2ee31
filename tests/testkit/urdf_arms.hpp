// Arms of other joint counts for the URDF tests: the test kit's perturbed 7-axis arms and UR10
// on a rail as robot descriptions with limits; and a test fixture, a UR10 on a linear rail as a
// cell's URDF writes it: world -> the rail's bed -> rail_joint (prismatic along the world's y,
// 0 .. 3 m) -> the carriage -> the UR10 turned by 90 deg on a 0.25 m riser, written as ROS's
// ur_description writes a UR10 (ur_macro.xacro: base_link -> base_link_inertia turned by pi, the
// six joints at the frames of its default_kinematics.yaml, with their rounded twists and 1e-11 m
// offsets, a ROS-Industrial flange, tool0) and a probe 'tcp' 150 mm out of tool0. Visual and
// inertial elements as such files carry them, for the readers to skip.
#pragma once

#include "hivecal/core/random.hpp"
#include "testkit/other_arms.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::test {

/// `arm`'s true geometry (many_joint_arm_truth) as a description with two targets and a limit
/// pair per joint: a slide's 0 .. 2 m, a turn's +-2.9 rad.
inline textio::RobotDescription many_joint_description(ManyJointArm arm, Random* random) {
  textio::RobotDescription robot;
  robot.robot = many_joint_arm_name(arm);
  robot.model = many_joint_arm_truth(arm, random);
  robot.target_count = 2;
  robot.model.other_tools_m[0] = Vec3(-0.04, 0.03, 0.12);
  robot.has_joint_limits = true;
  for (int j = 0; j < robot.model.joint_count; ++j) {
    const bool slides = joint_type(robot.model, j) == JointType::prismatic;
    robot.lower_rad(j) = slides ? 0.0 : -2.9;
    robot.upper_rad(j) = slides ? 2.0 : 2.9;
  }
  return robot;
}

/// The rail's joint: joint 1 of the arm, its limits [m].
inline constexpr double kRailLower_m = 0.0;
inline constexpr double kRailUpper_m = 3.0;

/// The document (its lines matter: the tests that break it name them).
inline constexpr const char* kRailUr10Urdf = R"(<?xml version="1.0"?>
<!-- A UR10 on a 3 m linear rail (hivecal test fixture) -->
<robot name="ur10_on_rail">
  <link name="world"/>
  <link name="rail">
    <visual>
      <origin xyz="0 1.5 -0.05" rpy="0 0 0"/>
      <geometry><box size="0.3 3.4 0.1"/></geometry>
    </visual>
  </link>
  <link name="carriage">
    <inertial><mass value="40"/><origin xyz="0 0 0.1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <link name="base_link"/>
  <link name="base_link_inertia"/>
  <link name="shoulder_link"/>
  <link name="upper_arm_link"/>
  <link name="forearm_link"/>
  <link name="wrist_1_link"/>
  <link name="wrist_2_link"/>
  <link name="wrist_3_link"/>
  <link name="base"/>
  <link name="flange"/>
  <link name="tool0"/>
  <link name="tcp"/>
  <joint name="world-rail" type="fixed">
    <parent link="world"/>
    <child link="rail"/>
    <origin xyz="0.8 -1.2 0.05" rpy="0 0 0"/>
  </joint>
  <joint name="rail_joint" type="prismatic">
    <parent link="rail"/>
    <child link="carriage"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="0" upper="3" effort="2000" velocity="1.5"/>
  </joint>
  <joint name="carriage-base_link" type="fixed">
    <parent link="carriage"/>
    <child link="base_link"/>
    <origin xyz="0.05 0 0.25" rpy="0 0 1.5707963267948966"/>
  </joint>
  <joint name="base_link-base_link_inertia" type="fixed">
    <parent link="base_link"/>
    <child link="base_link_inertia"/>
    <origin xyz="0 0 0" rpy="0 0 3.141592653589793"/>
  </joint>
  <joint name="shoulder_pan_joint" type="revolute">
    <parent link="base_link_inertia"/>
    <child link="shoulder_link"/>
    <origin xyz="0 0 0.1273" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-6.283185307179586" upper="6.283185307179586" effort="330" velocity="2.0943951023931953"/>
  </joint>
  <joint name="shoulder_lift_joint" type="revolute">
    <parent link="shoulder_link"/>
    <child link="upper_arm_link"/>
    <origin xyz="0 0 0" rpy="1.570796327 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-6.283185307179586" upper="6.283185307179586" effort="330" velocity="2.0943951023931953"/>
  </joint>
  <joint name="elbow_joint" type="revolute">
    <parent link="upper_arm_link"/>
    <child link="forearm_link"/>
    <origin xyz="-0.612 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3.141592653589793" upper="3.141592653589793" effort="150" velocity="3.141592653589793"/>
  </joint>
  <joint name="wrist_1_joint" type="revolute">
    <parent link="forearm_link"/>
    <child link="wrist_1_link"/>
    <origin xyz="-0.5723 0 0.163941" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-6.283185307179586" upper="6.283185307179586" effort="56" velocity="3.141592653589793"/>
  </joint>
  <joint name="wrist_2_joint" type="revolute">
    <parent link="wrist_1_link"/>
    <child link="wrist_2_link"/>
    <origin xyz="0 -0.1157 -2.373046667922381e-11" rpy="1.570796327 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-6.283185307179586" upper="6.283185307179586" effort="56" velocity="3.141592653589793"/>
  </joint>
  <joint name="wrist_3_joint" type="revolute">
    <parent link="wrist_2_link"/>
    <child link="wrist_3_link"/>
    <origin xyz="0 0.0922 -1.891053610911353e-11" rpy="1.570796326589793 3.141592653589793 3.141592653589793"/>
    <axis xyz="0 0 1"/>
    <limit lower="-6.283185307179586" upper="6.283185307179586" effort="56" velocity="3.141592653589793"/>
  </joint>
  <joint name="base_link-base_fixed_joint" type="fixed">
    <parent link="base_link"/>
    <child link="base"/>
    <origin xyz="0 0 0" rpy="0 0 3.141592653589793"/>
  </joint>
  <joint name="wrist_3-flange" type="fixed">
    <parent link="wrist_3_link"/>
    <child link="flange"/>
    <origin xyz="0 0 0" rpy="0 -1.5707963267948966 -1.5707963267948966"/>
  </joint>
  <joint name="flange-tool0" type="fixed">
    <parent link="flange"/>
    <child link="tool0"/>
    <origin xyz="0 0 0" rpy="1.5707963267948966 0 1.5707963267948966"/>
  </joint>
  <joint name="tool0-tcp" type="fixed">
    <parent link="tool0"/>
    <child link="tcp"/>
    <origin xyz="0.01 0.02 0.15" rpy="0 0 0"/>
  </joint>
</robot>
)";

}  // namespace hivecal::test
