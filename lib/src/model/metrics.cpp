#include "hivecal/model/metrics.hpp"

#include <cmath>

namespace hivecal {
namespace {

/// Welford's running mean and variance: one pass, no stored samples.
struct RunningStats {
  std::size_t count = 0;
  double mean = 0.0;
  double m2 = 0.0;
  double max = 0.0;

  void add(double value) {
    ++count;
    const double delta = value - mean;
    mean += delta / static_cast<double>(count);
    m2 += delta * (value - mean);
    if (value > max) max = value;
  }
  double sample_sigma() const { return count > 1 ? std::sqrt(m2 / static_cast<double>(count - 1)) : 0.0; }
};

}  // namespace

ErrorStats position_error_stats(const RobotModel& model, const RigidTransform& base_to_tracker,
                                Span<const Sample> samples) {
  RunningStats axes[kErrorAxisCount];
  for (const Sample& sample : samples) {
    const Vec3 error_m = base_to_tracker.apply(fk_sample_point(model, sample)) - sample.point_m;
    for (int axis = 0; axis < 3; ++axis) axes[axis].add(std::fabs(error_m(axis)));
    axes[static_cast<int>(ErrorAxis::norm_3d)].add(error_m.norm());
  }
  ErrorStats stats;
  stats.count = samples.size();
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    stats.mae_m[axis] = axes[axis].mean;
    stats.sigma_m[axis] = axes[axis].sample_sigma();
    stats.max_m[axis] = axes[axis].max;
  }
  return stats;
}

AccuracyReport accuracy_report(const RobotModel& model, const RigidTransform& base_to_tracker,
                               const DatasetBase& dataset) {
  AccuracyReport report;
  report.train = position_error_stats(model, base_to_tracker, dataset.train());
  report.test = position_error_stats(model, base_to_tracker, dataset.test());
  report.overall = position_error_stats(model, base_to_tracker, dataset.samples());
  return report;
}

RepeatedReadingNoise repeated_reading_noise(Span<const Sample> samples) {
  RepeatedReadingNoise noise;
  double squares_m2[3] = {};
  for (std::size_t begin = 0; begin < samples.size();) {
    const std::size_t end = pose_run_end(samples, begin);
    for (int target = 0; target < kMaxTargets; ++target) {
      Vec3 sum_m = Vec3::Zero();
      std::size_t count = 0;
      for (std::size_t i = begin; i < end; ++i) {
        if (samples[i].target != target) continue;
        sum_m += samples[i].point_m;
        ++count;
      }
      if (count < 2) continue;
      const Vec3 mean_m = sum_m / static_cast<double>(count);
      for (std::size_t i = begin; i < end; ++i) {
        if (samples[i].target != target) continue;
        const Vec3 d_m = samples[i].point_m - mean_m;
        for (int axis = 0; axis < 3; ++axis) squares_m2[axis] += d_m(axis) * d_m(axis);
      }
      ++noise.groups;
      noise.readings += count;
    }
    begin = end;
  }
  if (noise.groups == 0) return noise;
  const double dof = static_cast<double>(noise.readings - noise.groups);
  for (int axis = 0; axis < 3; ++axis) noise.sigma_axis_m[axis] = std::sqrt(squares_m2[axis] / dof);
  noise.sigma_m = std::sqrt((squares_m2[0] + squares_m2[1] + squares_m2[2]) / (3.0 * dof));
  return noise;
}

}  // namespace hivecal
