// Validation of a calibration against a reference geometry on fresh random poses (what
// `hivecal validate` prints; the hosted tests use the same function).
#pragma once

#include <cstdint>

#include "hivecal/model/kinematics.hpp"

namespace hivecal::cli {

/// How far two geometries (each with its own base -> tracker transform) predict the tool apart.
struct ValidationStats {
  long poses = 0;        ///< fresh poses drawn
  double mae_m = 0.0;    ///< mean 3D distance [m]
  double max_m = 0.0;    ///< largest 3D distance [m]
};

/// Draws `poses` random poses (seeded; the workspace the simulator and the paper use: shoulder
/// up, tool down-ish) and compares the tool points predicted by both geometries.
ValidationStats validate_on_fresh_poses(const RobotModel& model, const RigidTransform& base_to_tracker,
                                        const RobotModel& reference, const RigidTransform& reference_base_to_tracker,
                                        long poses, std::uint64_t seed);

}  // namespace hivecal::cli
