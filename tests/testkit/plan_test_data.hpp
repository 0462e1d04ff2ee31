// The planner tests' model, tracker and options, and the digest of a plan (lib/plan tests and
// their golden digest).
#pragma once

#include <cstdint>

#include "hivecal/core/digest.hpp"
#include "hivecal/plan/pose_plan.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// The reflector 5 cm along the flange axis.
inline const Vec3 kNominalTool(0.0, 0.0, 0.05);

/// The nominal UR5 with that reflector: the model every plan test plans for.
inline RobotModel planning_model() {
  RobotModel model = nominal_model(RobotType::ur5);
  model.tool_m = kNominalTool;
  return model;
}

/// The tracker of the simulated sessions, and its position in the robot base frame.
inline RigidTransform tracker_base() {
  return test::example_base_to_tracker();
}
inline Vec3 tracker_position() {
  return tracker_base().inverse().translation_m;
}

/// UR5 limits, the tracker above, `candidates` drawn poses [-], `poses` planned [-], `seed`.
inline PlanOptions small_options(std::size_t candidates, std::size_t poses, std::uint64_t seed) {
  PlanOptions options;
  options.constraints.limits = default_joint_limits(RobotType::ur5);
  options.constraints.tracker_m = tracker_position();
  options.candidate_count = candidates;
  options.pose_count = poses;
  options.seed = seed;
  return options;
}

/// Digest of a plan's poses, criterion, rigid sigmas and path time.
inline std::uint64_t digest_of(const PlanResult& r) {
  Digest digest;
  for (std::size_t i = 0; i < r.pose_count; ++i) digest.add(r.poses[i].head(kSixJoints));
  digest.add(r.planned.log_det);
  digest.add(
      r.planned.sigma.head<rigid_param_count(kSixJoints)>());  // the rigid 33, as before the compliance coefficients
  digest.add(r.travel_s);
  return digest.value();
}

}  // namespace hivecal::test
