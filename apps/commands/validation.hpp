// Validation of a calibration: against a reference geometry on fresh random poses (what
// `hivecal validate --truth` prints; the hosted tests use the same function), or on measured
// samples (`validate --samples`).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal::cli {

/// How far two geometries (each with its own base -> tracker transform) predict the tool apart.
struct ValidationStats {
  long poses = 0;      ///< fresh poses drawn
  double mae_m = 0.0;  ///< mean 3D distance [m]
  double max_m = 0.0;  ///< largest 3D distance [m]
};

/// The simulator's joint compliance of a reference (truth.json's "simulation"."compliance";
/// sim::simulated_compliance): zero for a rigid reference.
struct ReferenceCompliance {
  double joint2_rad = 0.0;  ///< joint 2 deflection at full horizontal reach [rad]
  double joint3_rad = 0.0;  ///< joint 3 deflection with the forearm horizontal [rad]
};

/// Draws `poses` random poses (seeded; the workspace the simulator and the paper use: shoulder
/// up, tool down-ish; a 7th .. joint within +-1.5 rad, a slide on its first half metre) and compares the tool points
/// predicted by both geometries (each with its own compliance model, if any; the reference bent by
/// `reference_compliance` too).
ValidationStats validate_on_fresh_poses(const RobotModel& model, const RigidTransform& base_to_tracker,
                                        const RobotModel& reference, const RigidTransform& reference_base_to_tracker,
                                        long poses, std::uint64_t seed,
                                        const ReferenceCompliance& reference_compliance = {});

/// `validate --samples`: the calibration scored on measured samples, after registering it on
/// them with --fit (validate_samples.cpp); *warnings: the registration's (exit 5).
Error validate_on_samples(const Options& options, std::vector<std::string>* warnings);

}  // namespace hivecal::cli
