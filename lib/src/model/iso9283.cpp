#include "hivecal/model/iso9283.hpp"

#include <cmath>

namespace hivecal {

Status pose_accuracy(Span<const Vec3> measured_m, const Vec3& commanded_m, PoseAccuracy* result) {
  const std::size_t n = measured_m.size();
  if (n < 2) return Status::invalid_argument;
  if (!all_finite(commanded_m)) return Status::non_finite_input;
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : measured_m) {
    if (!all_finite(p)) return Status::non_finite_input;
    sum += p;
  }
  PoseAccuracy r;
  r.cycles = n;
  r.barycentre_m = sum / static_cast<double>(n);
  r.accuracy_m = r.barycentre_m - commanded_m;
  r.accuracy_norm_m = r.accuracy_m.norm();
  double distance_sum_m = 0.0;
  for (const Vec3& p : measured_m) distance_sum_m += (p - r.barycentre_m).norm();
  r.mean_distance_m = distance_sum_m / static_cast<double>(n);
  double squares_m2 = 0.0;
  for (const Vec3& p : measured_m) {
    const double deviation_m = (p - r.barycentre_m).norm() - r.mean_distance_m;
    squares_m2 += deviation_m * deviation_m;
  }
  r.distance_sigma_m = std::sqrt(squares_m2 / static_cast<double>(n - 1));
  r.repeatability_m = r.mean_distance_m + 3.0 * r.distance_sigma_m;
  *result = r;
  return Status::ok;
}

}  // namespace hivecal
