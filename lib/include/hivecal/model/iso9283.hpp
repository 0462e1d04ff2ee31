// ISO 9283 pose accuracy and repeatability of positions (docs/iso9283.md): one commanded pose
// reached `n` times, each reached position measured. With the barycentre
//   xb = (1/n) sum x_i  (likewise y, z),
//   AP_P = |barycentre - commanded|,   AP_x = xb - x_c (likewise y, z),
//   l_i  = |x_i - barycentre|,  lb = (1/n) sum l_i,  S_l = sqrt(sum (l_i - lb)^2 / (n - 1)),
//   RP_l = lb + 3 S_l.
#pragma once

#include <cstddef>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// Accuracy and repeatability of one pose.
struct PoseAccuracy {
  std::size_t cycles = 0;            ///< measured reaches n [-]
  Vec3 barycentre_m = Vec3::Zero();  ///< mean measured position [m]
  Vec3 accuracy_m = Vec3::Zero();    ///< AP_x, AP_y, AP_z: barycentre - commanded [m]
  double accuracy_norm_m = 0.0;      ///< AP_P [m]
  double mean_distance_m = 0.0;      ///< lb: mean distance of a reach from the barycentre [m]
  double distance_sigma_m = 0.0;     ///< S_l [m]
  double repeatability_m = 0.0;      ///< RP_l = lb + 3 S_l [m]
};

/// AP and RP of the `measured_m` reaches of one pose commanded at `commanded_m` (same frame).
/// Errors: invalid_argument (fewer than 2 reaches), non_finite_input.
Status pose_accuracy(Span<const Vec3> measured_m, const Vec3& commanded_m, PoseAccuracy* result);

}  // namespace hivecal
