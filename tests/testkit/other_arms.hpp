// Non-UR arms for the "any arm" tests: nominal tables of an ABB IRB120-, a KUKA KR6 R900-like
// and a Fanuc LR Mate 200iD-like 6-axis arm in standard DH (with their modified-DH descriptions
// from model/dh_convention.hpp); arms of other joint counts (ManyJointArm: a KUKA LBR iiwa 14-
// like and a Franka-like 7-axis arm, a UR10 on a linear rail: a prismatic first joint);
// perturbed truths that keep parallel axes parallel, and simulated sessions (own PRNG: the same
// on every target).
//
// Values: the IRB120 table is the one of ../shared/spec/io-formats.md ("Robot description").
// The KR6 R900 and LR Mate 200iD tables are plausible ones built from the datasheets' link
// dimensions (a shoulder offset a1, upper arm a2, elbow offset a3, forearm d4, flange d6), not
// the vendors' own calibration tables: what matters here is their structure (offsets, joints
// 2-3 parallel, non-zero theta offsets), which differs from a UR's (joints 2-4 parallel, no a1).
#pragma once

#include <cmath>
#include <cstdint>

#include "hivecal/core/math.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/kinematics.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// The non-UR arms the tests know.
enum class OtherArm : int { irb120, kr6_r900, lrmate200id };
/// Every OtherArm, for loops.
inline constexpr OtherArm kOtherArms[] = {OtherArm::irb120, OtherArm::kr6_r900, OtherArm::lrmate200id};

/// Lower-case name ("abb-irb120", "kuka-kr6-r900", "fanuc-lrmate200id").
inline const char* other_arm_name(OtherArm arm) {
  switch (arm) {
    case OtherArm::irb120: return "abb-irb120";
    case OtherArm::kr6_r900: return "kuka-kr6-r900";
    case OtherArm::lrmate200id: return "fanuc-lrmate200id";
  }
  return "?";
}

/// What differs between the arms here: all have joints 2-3 parallel and a spherical wrist.
struct OtherArmDimensions {
  double d1_m;        ///< shoulder height [m]
  double a1_m;        ///< shoulder offset [m]
  double a2_m;        ///< upper arm [m]
  double a3_m;        ///< elbow offset [m]
  double d4_m;        ///< forearm [m]
  double d6_m;        ///< flange [m]
  double theta2_rad;  ///< joint 2's zero offset [rad]
  double theta3_rad;  ///< joint 3's zero offset [rad]
  double theta6_rad;  ///< joint 6's zero offset [rad]
};

/// Nominal standard-DH table of an arm, tool point 100 mm out on the flange axis.
inline RobotModel other_arm_model(OtherArm arm) {
  constexpr double h = math::kHalfPi;
  constexpr OtherArmDimensions kArms[] = {
      {0.290, 0.0, 0.270, 0.070, 0.302, 0.072, -h, 0.0, math::kPi},  // irb120
      {0.400, 0.025, 0.455, 0.035, 0.420, 0.080, 0.0, -h, 0.0},      // kr6_r900
      {0.330, 0.050, 0.330, 0.035, 0.335, 0.080, -h, 0.0, 0.0},      // lrmate200id
  };
  const OtherArmDimensions& a = kArms[static_cast<int>(arm)];
  RobotModel m;
  m.joints[0] = DhJoint{0.0, a.d1_m, a.a1_m, -h};
  m.joints[1] = DhJoint{a.theta2_rad, 0.0, a.a2_m, 0.0};
  m.joints[2] = DhJoint{a.theta3_rad, 0.0, a.a3_m, -h};
  m.joints[3] = DhJoint{0.0, a.d4_m, 0.0, h};
  m.joints[4] = DhJoint{0.0, 0.0, 0.0, -h};
  m.joints[5] = DhJoint{a.theta6_rad, a.d6_m, 0.0, 0.0};
  m.tool_m = Vec3(0.0, 0.0, 0.100);
  return m;
}

/// The same arm as modified-DH (Craig) rows and tool, with a base offset in front of joint 1
/// (alpha_0, a_0: zero for the vendors' tables; the tests also use a non-zero one).
inline void other_arm_modified(OtherArm arm, const ModifiedDhBase& base, ModifiedDhRow (&rows)[kSixJoints],
                               Vec3* tool_m) {
  modified_dh_from_model(other_arm_model(arm), base, rows, tool_m);
}

/// A modified-DH tool point from the definition (Rx(alpha_prev) Tx(a_prev) Rz(theta) Tz(d) per
/// row, q adding to theta, or to d for the joints whose bit is set in `prismatic_joints`),
/// independent of dh_convention.hpp [m].
inline Vec3 modified_chain_point(Span<const ModifiedDhRow> rows, const Vec3& tool_m, const JointVector& q_rad,
                                 std::uint32_t prismatic_joints = 0) {
  RigidTransform t;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const ModifiedDhRow& row = rows[j];
    const double q = q_rad(static_cast<Eigen::Index>(j));
    const bool prismatic = (prismatic_joints >> j & 1U) != 0;
    t = t.then_after(RigidTransform{rotation_x(row.alpha_prev_rad), Vec3(row.a_prev_m, 0.0, 0.0)});
    t = t.then_after(RigidTransform{rotation_z(row.theta_offset_rad + (prismatic ? 0.0 : q)),
                                    Vec3(0.0, 0.0, row.d_m + (prismatic ? q : 0.0))});
  }
  return t.apply(tool_m);
}

/// The same for a standard-DH model, link by link from the definition (Rz(theta) Tz(d) Tx(a)
/// Rx(alpha)), independent of kinematics.cpp [m].
inline Vec3 standard_chain_point(const RobotModel& model, const JointVector& q_rad) {
  RigidTransform t;
  for (int j = 0; j < model.joint_count; ++j) {
    const DhJoint& joint = model.joints[j];
    const bool prismatic = joint_type(model, j) == JointType::prismatic;
    const double theta = joint.theta_offset_rad + (prismatic ? 0.0 : q_rad(j));
    const double d = joint.d_m + (prismatic ? q_rad(j) : 0.0);
    t = t.then_after(RigidTransform{rotation_z(theta), Vec3(0.0, 0.0, d)});
    t = t.then_after(RigidTransform{rotation_x(joint.alpha_rad), Vec3(joint.a_m, 0.0, 0.0)});
  }
  return t.apply(model.tool_m);
}

/// `nominal` perturbed by length_sigma_m / angle_sigma_rad (Gaussian) with every twist that
/// is zero in the nominal kept zero (parallel axes stay parallel: a tilt between them is
/// not a DH parameter), and `tool_m`.
inline RobotModel perturbed_keeping_parallel(const RobotModel& nominal, Random* random, double length_sigma_m,
                                             double angle_sigma_rad, const Vec3& tool_m) {
  RobotModel model = perturbed_model(nominal, random, length_sigma_m, angle_sigma_rad);
  for (int j = 0; j < model.joint_count; ++j) {
    if (nominal.joints[j].alpha_rad == 0.0) model.joints[j].alpha_rad = 0.0;
  }
  model.tool_m = tool_m;
  return model;
}

/// Joint positions over a general 6-axis arm's workspace, away from the wrist singularity [rad].
inline JointVector other_arm_joints(Random* random) {
  JointVector q;
  q << random->uniform(-2.5, 2.5), random->uniform(-1.2, 1.2), random->uniform(-1.2, 1.2), random->uniform(-2.5, 2.5),
      random->uniform(0.3, 1.8), random->uniform(-2.5, 2.5);
  if (random->uniform(0.0, 1.0) < 0.5) q(4) = -q(4);
  return q;
}

/// Adds `count` samples of `truth` seen at `base_to_tracker` with isotropic noise_m per axis.
inline void fill_other_arm(const RobotModel& truth, const RigidTransform& base_to_tracker, std::size_t count,
                           double noise_m, Random* random, DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = other_arm_joints(random);
    const Vec3 noise = gaussian_vector(random);
    (void)dataset->add(q, base_to_tracker.apply(fk_tool_point(truth, q)) + noise_m * noise);
  }
}

/// A true arm: nominal perturbed by 0.3 mm / 0.3 mrad, reflector off the flange axis.
inline RobotModel other_arm_truth(OtherArm arm, Random* random) {
  return perturbed_keeping_parallel(other_arm_model(arm), random, 3e-4, 3e-4, Vec3(0.011, -0.007, 0.104));
}

// ---------------------------------------------------------------------------------------------
// Arms of other joint counts.

/// The arms of other than six revolute joints the tests know.
enum class ManyJointArm : int { iiwa14, franka, rail_ur10 };
/// Every ManyJointArm, for loops.
inline constexpr ManyJointArm kManyJointArms[] = {ManyJointArm::iiwa14, ManyJointArm::franka, ManyJointArm::rail_ur10};

/// Lower-case name ("kuka-iiwa14", "franka", "ur10-on-rail").
inline const char* many_joint_arm_name(ManyJointArm arm) {
  switch (arm) {
    case ManyJointArm::iiwa14: return "kuka-iiwa14";
    case ManyJointArm::franka: return "franka";
    case ManyJointArm::rail_ur10: return "ur10-on-rail";
  }
  return "?";
}

/// The Franka-like arm's seven modified-DH (Craig) rows: the published layout (d1 0.333, d3 0.316,
/// a3 = -a4 = 0.0825, d5 0.384, a6 0.088; the flange's 0.107 is in the tool point).
inline void franka_rows(ModifiedDhRow (&rows)[7]) {
  constexpr double h = math::kHalfPi;
  const ModifiedDhRow table[7] = {{0.0, 0.0, 0.0, 0.333}, {-h, 0.0, 0.0, 0.0},       {h, 0.0, 0.0, 0.316},
                                  {h, 0.0825, 0.0, 0.0},  {-h, -0.0825, 0.0, 0.384}, {h, 0.0, 0.0, 0.0},
                                  {h, 0.088, 0.0, 0.0}};
  for (int j = 0; j < 7; ++j) rows[j] = table[j];
}

/// Nominal standard-DH model of an arm, tool point 100 mm out on the flange axis (the Franka's
/// from its modified rows, 107 mm of flange more). The KUKA LBR iiwa 14's published chain: d1
/// 0.36, d3 0.42, d5 0.40, d7 0.126, twists -+ pi/2. The UR10 on a rail: a prismatic joint 1
/// along the rail (the base frame's z, horizontal), its carriage turning the UR10's first axis
/// up (alpha -pi/2) and raising it 0.25 m, then the UR10's six joints.
inline RobotModel many_joint_arm_model(ManyJointArm arm) {
  constexpr double h = math::kHalfPi;
  RobotModel m;
  if (kMaxJoints < 7) return m;  // a build of six joints holds none of them
  switch (arm) {
    case ManyJointArm::iiwa14: {
      m.joint_count = 7;
      const double d[7] = {0.36, 0.0, 0.42, 0.0, 0.40, 0.0, 0.126};
      const double alpha[7] = {-h, h, h, -h, -h, h, 0.0};
      for (int j = 0; j < 7; ++j) m.joints[j] = DhJoint{0.0, d[j], 0.0, alpha[j]};
      m.tool_m = Vec3(0.0, 0.0, 0.100);
      break;
    }
    case ManyJointArm::franka: {
      ModifiedDhRow rows[7];
      franka_rows(rows);
      ModifiedDhBase base;
      (void)model_from_modified_dh(rows, Vec3(0.0, 0.0, 0.207), &m, &base);
      break;
    }
    case ManyJointArm::rail_ur10: {
      const RobotModel ur10 = nominal_model(RobotType::ur10);
      m.joint_count = 7;
      set_joint_type(&m, 0, JointType::prismatic);
      m.joints[0] = DhJoint{0.0, 0.0, 0.0, -h};
      for (int j = 0; j < kSixJoints; ++j) m.joints[j + 1] = ur10.joints[j];
      m.joints[1].d_m += 0.25;
      m.tool_m = Vec3(0.0, 0.0, 0.100);
      break;
    }
  }
  return m;
}

/// Joint positions over an arm's workspace: the 7-axis arms within 90 % of their published
/// limits, away from straight elbows; the rail's carriage anywhere on 2 m and the UR10 as
/// random_joints [rad] or [m].
inline JointVector many_joint_arm_joints(ManyJointArm arm, Random* random) {
  JointVector q;
  if (arm == ManyJointArm::rail_ur10) {
    q << random->uniform(0.0, 2.0), random->uniform(-3.0, 3.0), random->uniform(-2.6, -0.5), random->uniform(-2.4, 2.4),
        random->uniform(-3.0, 0.0), random->uniform(-2.8, -0.3), random->uniform(-3.0, 3.0);
    return q;
  }
  // iiwa 14: +-170, 120, 170, 120, 170, 120, 175 deg; the Franka's are narrower, its joint 4
  // negative (-176 .. -4 deg): the same spread, joint 4 shifted.
  const double limit_rad[7] = {2.67, 1.88, 2.67, 1.88, 2.67, 1.88, 2.74};
  q << random->uniform(-limit_rad[0], limit_rad[0]), random->uniform(-limit_rad[1], limit_rad[1]),
      random->uniform(-limit_rad[2], limit_rad[2]), random->uniform(0.3, limit_rad[3]),
      random->uniform(-limit_rad[4], limit_rad[4]), random->uniform(0.3, limit_rad[5]),
      random->uniform(-limit_rad[6], limit_rad[6]);
  if (random->uniform(0.0, 1.0) < 0.5) q(3) = -q(3);
  if (arm == ManyJointArm::franka) q(3) = -std::fabs(q(3));
  return q;
}

/// Adds `count` samples of `truth` (an `arm`) seen at `base_to_tracker` with isotropic noise_m per axis.
inline void fill_many_joint_arm(ManyJointArm arm, const RobotModel& truth, const RigidTransform& base_to_tracker,
                                std::size_t count, double noise_m, Random* random, DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = many_joint_arm_joints(arm, random);
    const Vec3 noise = gaussian_vector(random);
    (void)dataset->add(q, base_to_tracker.apply(fk_tool_point(truth, q)) + noise_m * noise);
  }
}

/// A true arm: nominal perturbed by 0.3 mm / 0.3 mrad (the slide offset of a prismatic joint
/// as a length), reflector off the flange axis.
inline RobotModel many_joint_arm_truth(ManyJointArm arm, Random* random) {
  return perturbed_keeping_parallel(many_joint_arm_model(arm), random, 3e-4, 3e-4, Vec3(0.011, -0.007, 0.104));
}

}  // namespace hivecal::test
