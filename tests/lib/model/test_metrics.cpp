// Accuracy figures (model/metrics.hpp): MAE, sample sigma and max per axis and in 3D against
// hand-computed values and a plain two-pass loop, each sample's own target, the empty and
// one-sample cases, and the train / test / overall parts of accuracy_report; the noise of
// repeated readings against hand-computed values and a simulated tracker of known sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "hivecal/core/random.hpp"
#include "hivecal/model/metrics.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::metrics_test {
namespace {

Dataset<64> dataset;
Dataset<8> small;

/// The statistics by a plain two-pass loop: errors of base * FK(q) * tool - measured.
struct PlainStats {
  double mae[kErrorAxisCount] = {};
  double sigma[kErrorAxisCount] = {};
  double max[kErrorAxisCount] = {};
};

double abs_error(const RobotModel& model, const RigidTransform& base, const Sample& s, int axis) {
  const Vec3 predicted = base.apply(fk_target_point(model, s.q_rad, s.target));
  const Vec3 e = predicted - s.point_m;
  return axis < 3 ? std::fabs(e(axis)) : std::sqrt(e.x() * e.x() + e.y() * e.y() + e.z() * e.z());
}

PlainStats plain_stats(const RobotModel& model, const RigidTransform& base, Span<const Sample> samples) {
  PlainStats out;
  const double n = static_cast<double>(samples.size());
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    double sum = 0.0;
    for (const Sample& s : samples) {
      const double v = abs_error(model, base, s, axis);
      sum += v;
      if (v > out.max[axis]) out.max[axis] = v;
    }
    out.mae[axis] = samples.empty() ? 0.0 : sum / n;
    double squares = 0.0;
    for (const Sample& s : samples) {
      const double d = abs_error(model, base, s, axis) - out.mae[axis];
      squares += d * d;
    }
    out.sigma[axis] = samples.size() > 1 ? std::sqrt(squares / (n - 1.0)) : 0.0;
  }
  return out;
}

void expect_matches_plain(const ErrorStats& stats, const PlainStats& plain, std::size_t count, const char* what) {
  EXPECT_EQ(stats.count, count) << what;
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    const double scale = 1e-12 * (plain.max[axis] + 1e-9);
    EXPECT_NEAR(stats.mae_m[axis], plain.mae[axis], scale) << what << " axis " << axis;
    EXPECT_NEAR(stats.sigma_m[axis], plain.sigma[axis], scale) << what << " axis " << axis;
    EXPECT_NEAR(stats.max_m[axis], plain.max[axis], scale) << what << " axis " << axis;
  }
}

/// A sample of target `target` at joints `q` whose measured point is `measured`.
Sample sample_at(const JointVector& q, const Vec3& measured, int target = 0) {
  Sample s;
  s.q_rad = q;
  s.point_m = measured;
  s.target = target;
  return s;
}

// An all-zero geometry puts the tool point at the base origin, so the prediction is the base
// translation and each error is chosen by hand: (3, 4, 0), (-6, 0, 8), (0, -2, 0) mm.
TEST(ErrorStats, HandComputedMaeSigmaAndMax) {
  const RobotModel zero;  // every DH length and angle 0, tool at the flange origin
  RigidTransform base;
  base.translation_m << 1.0, 2.0, 3.0;
  const Vec3 errors[3] = {Vec3(3e-3, 4e-3, 0.0), Vec3(-6e-3, 0.0, 8e-3), Vec3(0.0, -2e-3, 0.0)};
  Sample samples[3];
  Random random(601);
  for (int i = 0; i < 3; ++i) samples[i] = sample_at(test::random_joints(&random), base.translation_m - errors[i]);
  ErrorStats stats;
  EXPECT_NO_HEAP(stats = position_error_stats(zero, base, Span<const Sample>(samples)));
  EXPECT_EQ(stats.count, 3u);
  // |x| = 3, 6, 0 mm: mean 3, deviations 0, 3, -3 -> variance 18 / 2.
  EXPECT_NEAR(stats.mae(ErrorAxis::x), 3e-3, 1e-15);
  EXPECT_NEAR(stats.sigma(ErrorAxis::x), 3e-3, 1e-15);
  EXPECT_NEAR(stats.max(ErrorAxis::x), 6e-3, 1e-15);
  // |y| = 4, 0, 2 mm: mean 2, deviations 2, -2, 0 -> variance 8 / 2.
  EXPECT_NEAR(stats.mae(ErrorAxis::y), 2e-3, 1e-15);
  EXPECT_NEAR(stats.sigma(ErrorAxis::y), 2e-3, 1e-15);
  EXPECT_NEAR(stats.max(ErrorAxis::y), 4e-3, 1e-15);
  // |z| = 0, 8, 0 mm: mean 8/3, squared deviations (64 + 256 + 64) / 9 -> variance 192 / 9.
  EXPECT_NEAR(stats.mae(ErrorAxis::z), 8e-3 / 3.0, 1e-15);
  EXPECT_NEAR(stats.sigma(ErrorAxis::z), std::sqrt(192.0 / 9.0) * 1e-3, 1e-15);
  EXPECT_NEAR(stats.max(ErrorAxis::z), 8e-3, 1e-15);
  // |e| = 5, 10, 2 mm: mean 17/3, squared deviations (4 + 169 + 121) / 9 -> variance 147 / 9.
  EXPECT_NEAR(stats.mae(ErrorAxis::norm_3d), 17e-3 / 3.0, 1e-15);
  EXPECT_NEAR(stats.sigma(ErrorAxis::norm_3d), std::sqrt(147.0 / 9.0) * 1e-3, 1e-15);
  EXPECT_NEAR(stats.max(ErrorAxis::norm_3d), 10e-3, 1e-15);
}

TEST(ErrorStats, EachSampleIsPredictedForItsOwnTarget) {
  RobotModel zero;
  zero.other_tools_m[0] << 0.0, 0.0, 0.01;  // target 2 sits 10 mm above the flange
  zero.other_tools_m[1] << 0.0, 0.02, 0.0;  // target 3 20 mm beside it
  const RigidTransform base;                // identity
  // At zero joints the flange frame is the base frame: each target's point is its tool point.
  const Sample samples[3] = {sample_at(JointVector::Zero(), Vec3::Zero(), 0),
                             sample_at(JointVector::Zero(), Vec3::Zero(), 1),
                             sample_at(JointVector::Zero(), Vec3::Zero(), 2)};
  ErrorStats stats;
  EXPECT_NO_HEAP(stats = position_error_stats(zero, base, Span<const Sample>(samples)));
  EXPECT_NEAR(stats.mae(ErrorAxis::norm_3d), 0.03 / 3.0, 1e-16);
  EXPECT_NEAR(stats.max(ErrorAxis::norm_3d), 0.02, 1e-17);
  EXPECT_NEAR(stats.mae(ErrorAxis::x), 0.0, 1e-17);
  EXPECT_NEAR(stats.max(ErrorAxis::y), 0.02, 1e-17);
  EXPECT_NEAR(stats.max(ErrorAxis::z), 0.01, 1e-17);
}

TEST(ErrorStats, EmptyAndSingleSample) {
  const RobotModel model = nominal_model(RobotType::ur5);
  const RigidTransform base = test::example_base_to_tracker();
  ErrorStats empty;
  empty.count = 99;
  empty.mae_m[2] = 1.0;
  EXPECT_NO_HEAP(empty = position_error_stats(model, base, Span<const Sample>()));
  EXPECT_EQ(empty.count, 0u);
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    EXPECT_EQ(empty.mae_m[axis], 0.0);
    EXPECT_EQ(empty.sigma_m[axis], 0.0);
    EXPECT_EQ(empty.max_m[axis], 0.0);
  }
  // One sample: the sample sigma is undefined and reported as 0; MAE and max are its error.
  const JointVector q = (JointVector() << 0.3, -1.2, 1.5, -1.0, -1.6, 0.4).finished();
  const Vec3 offset(1e-3, -2e-3, 2e-3);  // |offset| = 3 mm
  const Sample one[1] = {sample_at(q, base.apply(fk_tool_point(model, q)) - offset)};
  ErrorStats stats;
  EXPECT_NO_HEAP(stats = position_error_stats(model, base, Span<const Sample>(one)));
  EXPECT_EQ(stats.count, 1u);
  EXPECT_NEAR(stats.mae(ErrorAxis::norm_3d), 3e-3, 1e-14);
  EXPECT_NEAR(stats.max(ErrorAxis::norm_3d), 3e-3, 1e-14);
  EXPECT_NEAR(stats.mae(ErrorAxis::y), 2e-3, 1e-14);
  for (int axis = 0; axis < kErrorAxisCount; ++axis) EXPECT_EQ(stats.sigma_m[axis], 0.0);
}

TEST(ErrorStats, MaeAndSigmaEqualAPlainLoop) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Random random(610 + seed);
    const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
    const RobotModel model = test::perturbed_model(truth, &random, 5e-4, 5e-4);
    small.clear();
    test::fill_dataset(truth, test::example_base_to_tracker(), 2 + seed % 7, 20e-6, &random, &small);
    const RigidTransform base = test::example_base_to_tracker();
    ErrorStats stats;
    EXPECT_NO_HEAP(stats = position_error_stats(model, base, small.samples()));
    expect_matches_plain(stats, plain_stats(model, base, small.samples()), small.size(), "random set");
    // Properties of any error set: the 3D error bounds each axis and is bounded by their sum.
    double axis_sum = 0.0;
    for (ErrorAxis axis : {ErrorAxis::x, ErrorAxis::y, ErrorAxis::z}) {
      EXPECT_LE(stats.mae(axis), stats.mae(ErrorAxis::norm_3d));
      EXPECT_LE(stats.max(axis), stats.max(ErrorAxis::norm_3d));
      axis_sum += stats.mae(axis);
    }
    EXPECT_LE(stats.mae(ErrorAxis::norm_3d), axis_sum * (1.0 + 1e-15));
    EXPECT_GT(stats.sigma(ErrorAxis::norm_3d), 0.0);
  }
}

TEST(ErrorStats, NormStatisticsDoNotDependOnTheTrackerFrame) {
  Random random(620);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  const RobotModel model = nominal_model(RobotType::ur5);
  small.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), 8, 0.0, &random, &small);
  const RigidTransform base = test::example_base_to_tracker();
  RigidTransform move;
  move.rotation = test::random_rotation(&random);
  move.translation_m << 0.5, -2.0, 1.0;
  Sample moved[8];
  for (std::size_t i = 0; i < 8; ++i) {
    moved[i] = small.samples()[i];
    moved[i].point_m = move.apply(moved[i].point_m);
  }
  const ErrorStats before = position_error_stats(model, base, small.samples());
  ErrorStats after;
  EXPECT_NO_HEAP(after = position_error_stats(model, move.then_after(base), Span<const Sample>(moved)));
  const int n3 = static_cast<int>(ErrorAxis::norm_3d);
  EXPECT_NEAR(after.mae_m[n3], before.mae_m[n3], 1e-15);
  EXPECT_NEAR(after.sigma_m[n3], before.sigma_m[n3], 1e-15);
  EXPECT_NEAR(after.max_m[n3], before.max_m[n3], 1e-15);
  EXPECT_GT(before.mae_m[n3], 1e-4);  // the nominal model is off by about a millimetre
  // The components are frame-dependent: a random rotation changes them.
  EXPECT_GT(std::fabs(after.mae(ErrorAxis::x) - before.mae(ErrorAxis::x)), 1e-9);
}

TEST(AccuracyReport, EachPartEqualsAPlainLoopOverItsSamples) {
  Random random(630);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5e), &random, 1e-3, 1e-3);
  const RobotModel model = test::perturbed_model(truth, &random, 3e-4, 3e-4);
  const RigidTransform base = test::example_base_to_tracker();
  dataset.clear();
  test::fill_dataset(truth, base, 40, 10e-6, &random, &dataset);
  AccuracyReport report;
  // Before a split every sample is training: no test part.
  EXPECT_NO_HEAP(report = accuracy_report(model, base, dataset));
  EXPECT_EQ(report.test.count, 0u);
  EXPECT_EQ(report.test.mae(ErrorAxis::norm_3d), 0.0);
  expect_matches_plain(report.train, plain_stats(model, base, dataset.samples()), 40, "train, unsplit");
  expect_matches_plain(report.overall, plain_stats(model, base, dataset.samples()), 40, "overall, unsplit");

  ASSERT_EQ(dataset.split(0.75, 3), Status::ok);
  EXPECT_NO_HEAP(report = accuracy_report(model, base, dataset));
  expect_matches_plain(report.train, plain_stats(model, base, dataset.train()), 30, "train");
  expect_matches_plain(report.test, plain_stats(model, base, dataset.test()), 10, "test");
  expect_matches_plain(report.overall, plain_stats(model, base, dataset.samples()), 40, "overall");
  EXPECT_NE(report.train.mae(ErrorAxis::norm_3d), report.test.mae(ErrorAxis::norm_3d));

  // Samples set aside are in no part.
  const std::uint32_t aside[] = {0, 5, 6, 17};
  dataset.set_aside(Span<const std::uint32_t>(aside));
  ASSERT_EQ(dataset.split(0.5, 4), Status::ok);
  EXPECT_NO_HEAP(report = accuracy_report(model, base, dataset));
  EXPECT_EQ(report.train.count + report.test.count, 36u);
  expect_matches_plain(report.overall, plain_stats(model, base, dataset.samples()), 36, "overall, 4 aside");
  expect_matches_plain(report.test, plain_stats(model, base, dataset.test()), 18, "test, 4 aside");
}

/// A sample at `q` (joint 1 set to `q1_rad`, the others fixed) measuring `point_m` with `target`.
Sample reading(double q1_rad, const Vec3& point_m, int target = 0) {
  Sample s;
  s.q_rad << q1_rad, -1.0, 1.2, -0.4, 1.5, 0.3;
  s.point_m = point_m;
  s.target = target;
  return s;
}

TEST(RepeatedReadingNoise, HandComputedGroupsAndPooledSigma) {
  // Pose A read twice by target 0 (x differs by 2 um) and once by target 1; pose B (joint 1 a
  // tenth of a radian away) read twice by target 0 (z differs by 4 um); pose C read once.
  const Sample samples[] = {
      reading(0.0, Vec3(1.0, 0.0, 0.0)),        reading(0.0, Vec3(0.3, 0.0, 0.0), 1),
      reading(0.0, Vec3(1.0 + 2e-6, 0.0, 0.0)), reading(0.1, Vec3(0.0, 0.0, 1.0)),
      reading(0.1, Vec3(0.0, 0.0, 1.0 + 4e-6)), reading(0.2, Vec3(5.0, 5.0, 5.0)),
  };
  RepeatedReadingNoise noise;
  EXPECT_NO_HEAP(noise = repeated_reading_noise(Span<const Sample>(samples, 6)));
  EXPECT_EQ(noise.groups, 2u);
  EXPECT_EQ(noise.readings, 4u);
  // Each group: two readings, one degree of freedom; squares (1e-6)^2 * 2 in x, (2e-6)^2 * 2 in z.
  EXPECT_NEAR(noise.sigma_axis_m[0], std::sqrt(2e-12 / 2.0), 1e-15);
  EXPECT_EQ(noise.sigma_axis_m[1], 0.0);
  EXPECT_NEAR(noise.sigma_axis_m[2], std::sqrt(8e-12 / 2.0), 1e-15);
  EXPECT_NEAR(noise.sigma_m, std::sqrt(10e-12 / 6.0), 1e-15);
}

TEST(RepeatedReadingNoise, NoRepeatNoEstimate) {
  const Sample samples[] = {reading(0.0, Vec3(1.0, 0.0, 0.0)), reading(0.0, Vec3(0.3, 0.0, 0.0), 1),
                            reading(0.5, Vec3(1.0, 0.0, 0.0)), reading(0.0, Vec3(1.0, 1e-3, 0.0)),
                            reading(1e-5, Vec3(1.0, 2e-3, 0.0))};
  // The fourth is at pose A's joints again but not next to it: another stop of the robot; the
  // fifth follows it with joint 1 crept by 1e-5 rad: a moved point, not a repeated reading.
  const RepeatedReadingNoise noise = repeated_reading_noise(Span<const Sample>(samples, 5));
  EXPECT_EQ(noise.groups, 0u);
  EXPECT_EQ(noise.readings, 0u);
  EXPECT_EQ(noise.sigma_m, 0.0);
  EXPECT_EQ(repeated_reading_noise(Span<const Sample>()).groups, 0u);
}

TEST(RepeatedReadingNoise, RecoversTheTrackerSigmaWhateverTheModelError) {
  // 40 poses, three reflectors each read 5 times with 10 um noise per axis; the points
  // themselves are far from any model (a model error changes nothing).
  static Sample samples[600];
  Random random(2024);
  const double sigma_m = 10e-6;
  std::size_t n = 0;
  for (int stop = 0; stop < 40; ++stop) {
    const Vec3 centre_m(random.uniform(-1.0, 1.0), random.uniform(-1.0, 1.0), random.uniform(0.0, 1.0));
    for (int repeat = 0; repeat < 5; ++repeat) {
      for (int target = 0; target < 3; ++target) {
        const Vec3 truth_m = centre_m + Vec3(0.05 * target, 0.0, 0.0);
        const Vec3 noise_m(random.normal(), random.normal(), random.normal());
        samples[n] = reading(0.05 * stop, truth_m + sigma_m * noise_m, target);
        ++n;
      }
    }
  }
  const RepeatedReadingNoise noise = repeated_reading_noise(Span<const Sample>(samples, n));
  EXPECT_EQ(noise.groups, 120u);
  EXPECT_EQ(noise.readings, 600u);
  // 480 degrees of freedom per axis: the estimate's relative standard error is ~3 %.
  EXPECT_NEAR(noise.sigma_m, sigma_m, 0.06 * sigma_m);
  for (double axis_m : noise.sigma_axis_m) EXPECT_NEAR(axis_m, sigma_m, 0.12 * sigma_m);
}

}  // namespace
}  // namespace hivecal::metrics_test
