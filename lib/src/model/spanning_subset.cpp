#include "hivecal/model/spanning_subset.hpp"

#include <algorithm>
#include <limits>

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

double pose_distance_sq(const Sample& a, const Sample& b, int joint_count) {
  double sum_rad2 = a.target == b.target ? 0.0 : math::kPi * math::kPi;
  for (int j = 0; j < joint_count; ++j) {
    const double difference_rad = wrapped_rad(a.q_rad[j] - b.q_rad[j]);
    sum_rad2 += difference_rad * difference_rad;
  }
  return sum_rad2;
}

std::size_t spanning_subset(Span<const Sample> samples, int joint_count, Span<double> scratch,
                            Span<std::uint32_t> chosen) {
  const std::size_t count = std::min(samples.size(), chosen.size());
  if (count == 0 || scratch.size() < samples.size()) return 0;
  constexpr double kChosen = -1.0;  // below every distance: never chosen again
  for (std::size_t i = 0; i < samples.size(); ++i) scratch[i] = std::numeric_limits<double>::infinity();
  std::size_t latest = 0;  // the first sample starts the set
  chosen[0] = 0;
  scratch[0] = kChosen;
  for (std::size_t k = 1; k < count; ++k) {
    // One pass: each sample's distance to the set (now with `latest`) and the farthest of them.
    std::size_t farthest = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (scratch[i] != kChosen)
        scratch[i] = std::min(scratch[i], pose_distance_sq(samples[i], samples[latest], joint_count));
      if (scratch[i] > scratch[farthest]) farthest = i;  // strict: ties keep the lower position
    }
    chosen[k] = static_cast<std::uint32_t>(farthest);
    scratch[farthest] = kChosen;
    latest = farthest;
  }
  std::sort(chosen.data(), chosen.data() + count);
  return count;
}

}  // namespace hivecal
