#include "hivecal/model/spanning_subset.hpp"

#include <algorithm>

#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {

/// `angle_rad` moved into (-pi, pi] by whole turns (joint readings span a few turns at most).
double wrapped_rad(double angle_rad) {
  while (angle_rad > math::kPi) angle_rad -= 2.0 * math::kPi;
  while (angle_rad <= -math::kPi) angle_rad += 2.0 * math::kPi;
  return angle_rad;
}

}  // namespace

double pose_distance_sq(const Sample& a, const Sample& b) {
  double sum_rad2 = a.target == b.target ? 0.0 : math::kPi * math::kPi;
  for (int j = 0; j < kJointCount; ++j) {
    const double difference_rad = wrapped_rad(a.q_rad[j] - b.q_rad[j]);
    sum_rad2 += difference_rad * difference_rad;
  }
  return sum_rad2;
}

std::size_t spanning_subset(Span<const Sample> samples, Span<double> scratch, Span<std::uint32_t> chosen) {
  const std::size_t count = std::min(samples.size(), chosen.size());
  if (count == 0 || scratch.size() < samples.size()) return 0;
  std::size_t latest = 0;  // the first sample starts the set
  chosen[0] = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) scratch[i] = pose_distance_sq(samples[i], samples[0]);
  scratch[0] = -1.0;  // chosen: never again (distances are >= 0)
  for (std::size_t k = 1; k < count; ++k) {
    if (k > 1) {
      for (std::size_t i = 0; i < samples.size(); ++i) {
        scratch[i] = std::min(scratch[i], pose_distance_sq(samples[i], samples[latest]));
      }
    }
    latest = 0;
    for (std::size_t i = 1; i < samples.size(); ++i) {
      if (scratch[i] > scratch[latest]) latest = i;  // strict: ties keep the lower position
    }
    chosen[k] = static_cast<std::uint32_t>(latest);
    scratch[latest] = -1.0;  // chosen: never again (distances are >= 0)
  }
  std::sort(chosen.data(), chosen.data() + count);
  return count;
}

}  // namespace hivecal
