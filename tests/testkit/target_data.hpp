// Several reflectors on one tool plate (issue 11): a truth with a tool point per target and
// paired samples of every target at each pose (own PRNG: the same on every target).
#pragma once

#include <cmath>

#include "testkit/lm_test_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// Offsets of targets 2 and 3 from target 1 on the plate [m]: 50-100 mm in different directions.
inline const Vec3 kPlateOffsets_m[2] = {Vec3(0.08, 0.0, -0.02), Vec3(-0.03, 0.07, -0.05)};

/// `truth` with target 1 at `tool_m` and targets 2, 3 at the plate offsets from it.
inline RobotModel with_plate(RobotModel truth, const Vec3& tool_m) {
  truth.tool_m = tool_m;
  truth.other_tools_m[0] = tool_m + kPlateOffsets_m[0];
  truth.other_tools_m[1] = tool_m + kPlateOffsets_m[1];
  return truth;
}

/// `pose_count` random poses (with `tool_down`, joint 6's axis pointing down, alternating
/// wrist branches), each measured on targets 1 .. target_count (one sample per target, in
/// target order), with isotropic Gaussian noise_m.
inline void fill_target_dataset(const RobotModel& truth, const RigidTransform& base_to_tracker, std::size_t pose_count,
                                int target_count, double noise_m, Random* random, DatasetBase* dataset,
                                bool tool_down = false) {
  for (std::size_t i = 0; i < pose_count; ++i) {
    const JointVector q = tool_down ? tool_down_joints(truth, i % 2 == 1, random) : random_joints(random);
    for (int target = 0; target < target_count; ++target) {
      const Vec3 noise = gaussian_vector(random);
      (void)dataset->add(q, base_to_tracker.apply(fk_target_point(truth, q, target)) + noise_m * noise, target);
    }
  }
}

/// `poses` poses of a UR5 (perturbed, seeded) with three reflectors on a plate at `tool_m`
/// whose elbow and wrist 1 turn up to 0.5 mrad more than they read (once and twice per turn:
/// what a rigid model cannot take, ~0.1 mm per axis that moves the pose's reflectors alike),
/// 10 um tracker noise, and `blunder_m` along z on every reading of pose `blunder_pose`.
inline void fill_plate_with_joint_errors(std::uint64_t seed, std::size_t poses, const Vec3& tool_m,
                                         std::size_t blunder_pose, double blunder_m, DatasetBase* dataset) {
  Random random(seed);
  const RobotModel truth = with_plate(perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m), tool_m);
  const RigidTransform base = example_base_to_tracker();
  for (std::size_t i = 0; i < poses; ++i) {
    const JointVector q = random_joints(&random);
    JointVector turned = q;  // libm here, not the library's: the truth is the simulator's
    turned(2) += 5e-4 * std::sin(q(2)) + 3e-4 * std::cos(2.0 * q(2));
    turned(3) += 4e-4 * std::cos(q(3));
    for (int target = 0; target < 3; ++target) {
      Vec3 point = base.apply(fk_target_point(truth, turned, target)) + 1e-5 * gaussian_vector(&random);
      if (i == blunder_pose) point += Vec3(0.0, 0.0, blunder_m);
      (void)dataset->add(q, point, target);
    }
  }
}

/// Target 1's samples of `source` only (the same poses as one reflector would give).
inline void copy_target_one(const DatasetBase& source, DatasetBase* target) {
  target->clear();
  for (const Sample& s : source.samples()) {
    if (s.target == 0) (void)target->add(s.q_rad, s.point_m);
  }
}

}  // namespace hivecal::test
