// Non-UR 6-axis arms for the "any arm" tests: nominal tables of an ABB IRB120-, a KUKA
// KR6 R900-like and a Fanuc LR Mate 200iD-like arm in standard DH (with their modified-DH
// descriptions from model/dh_convention.hpp), perturbed truths that keep parallel axes
// parallel, and simulated sessions (own PRNG: the same on every target).
//
// Values: the IRB120 table is the one of ../shared/spec/io-formats.md ("Robot description").
// The KR6 R900 and LR Mate 200iD tables are plausible ones built from the datasheets' link
// dimensions (a shoulder offset a1, upper arm a2, elbow offset a3, forearm d4, flange d6), not
// the vendors' own calibration tables: what matters here is their structure (offsets, joints
// 2-3 parallel, non-zero theta offsets), which differs from a UR's (joints 2-4 parallel, no a1).
#pragma once

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
/// row), independent of dh_convention.hpp [m].
inline Vec3 modified_chain_point(const ModifiedDhRow (&rows)[kSixJoints], const Vec3& tool_m,
                                 const JointVector& q_rad) {
  RigidTransform t;
  for (int j = 0; j < kSixJoints; ++j) {
    t = t.then_after(RigidTransform{rotation_x(rows[j].alpha_prev_rad), Vec3(rows[j].a_prev_m, 0.0, 0.0)});
    t = t.then_after(RigidTransform{rotation_z(q_rad(j) + rows[j].theta_offset_rad), Vec3(0.0, 0.0, rows[j].d_m)});
  }
  return t.apply(tool_m);
}

/// `nominal` perturbed by length_sigma_m / angle_sigma_rad (Gaussian) with every twist that
/// is zero in the nominal kept zero (parallel axes stay parallel: a tilt between them is
/// not a DH parameter), and `tool_m`.
inline RobotModel perturbed_keeping_parallel(const RobotModel& nominal, Random* random, double length_sigma_m,
                                             double angle_sigma_rad, const Vec3& tool_m) {
  RobotModel model = perturbed_model(nominal, random, length_sigma_m, angle_sigma_rad);
  for (int j = 0; j < kSixJoints; ++j) {
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

}  // namespace hivecal::test
