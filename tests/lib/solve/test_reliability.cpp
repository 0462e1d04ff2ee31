// The blunder test of a fit (solve/reliability.hpp): redundancy numbers that add up to the
// fit's degrees of freedom, no rejection on clean sets, a blunder above its minimal
// detectable bias found at the pose it was put on, and uncontrolled poses never removed by
// the job.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/solve/reliability.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/target_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::reliability_test {
namespace {

constexpr std::size_t kCapacity = 128;
LmWorkspaceWithTargets lm_workspace;
LmResult fit;
ReliabilityWorkspace reliability;
Dataset<kCapacity> dataset;

/// Every unit's test, in visiting order.
class Collect final : public UnitTestVisitor {
 public:
  Collect() { units.reserve(kCapacity); }  // no allocation inside the library call
  void on_unit(const UnitTest& t) override { units.push_back(t); }
  std::vector<UnitTest> units;
};

RobotModel truth(std::uint64_t seed) {
  Random random(seed);
  return test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
}

/// LM (full model) on the dataset's samples from the nominal UR5 with the truth's tool point.
Status fit_all(const RobotModel& truth_model) {
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = truth_model.tool_m;
  return calibrate_lm(start, nullptr, dataset.samples(), LmOptions{}, &lm_workspace, &fit);
}

/// The blunder test of `fit` on every sample of the dataset.
BlunderTestSummary test_fit(Collect* collect, ParamMask extra = 0) {
  BlunderTestSummary summary;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = test_for_blunders(fit.model, fit.base_to_tracker, dataset.samples(), Span<const Sample>(),
                                            fit.identifiability.kept_mask | extra, PointLoss{}, BlunderTestOptions{},
                                            &reliability, collect, &summary));
  EXPECT_EQ(status, Status::ok);
  return summary;
}

TEST(Reliability, RedundancyNumbersAddUpToTheDegreesOfFreedom) {
  // trace(I - H) = 3 N - p: the sum of rows * r over the units is the fit's redundancy.
  for (std::size_t count : {9u, 14u, 30u, 80u}) {
    Random random(100 + count);
    const RobotModel model = truth(count);
    dataset.clear();
    test::fill_dataset(model, test::example_base_to_tracker(), count, 10e-6, &random, &dataset);
    ASSERT_EQ(fit_all(model), Status::ok) << count;
    Collect collect;
    const BlunderTestSummary summary = test_fit(&collect);
    double sum = 0.0;
    for (const UnitTest& t : collect.units) {
      EXPECT_GE(t.redundancy, -1e-12);
      EXPECT_LE(t.redundancy, 1.0 + 1e-12);
      sum += 3.0 * t.redundancy;
    }
    EXPECT_EQ(collect.units.size(), count);
    EXPECT_NEAR(sum, summary.dof, 1e-8 * static_cast<double>(count)) << count;
    EXPECT_EQ(summary.dof, 3.0 * static_cast<double>(count) - fit.identifiability.kept_count());
  }
}

TEST(Reliability, SeveralTargetsTestAPoseAsOneUnitAndStillAddUp) {
  const RobotModel model = test::with_plate(truth(3), Vec3(0.01, 0.02, 0.1));
  Random random(8);
  dataset.clear();
  test::fill_target_dataset(model, test::example_base_to_tracker(), 20, 3, 10e-6, &random, &dataset);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = model.tool_m;
  ASSERT_EQ(calibrate_lm(start, nullptr, dataset.samples(), LmOptions{}, &lm_workspace, &fit), Status::ok);
  Collect collect;
  const BlunderTestSummary summary = test_fit(&collect, kOtherTargetTools);
  ASSERT_EQ(collect.units.size(), 20u);  // 60 samples, a unit per pose
  double sum = 0.0;
  for (const UnitTest& t : collect.units) {
    EXPECT_EQ(t.samples, 3u);
    sum += 9.0 * t.redundancy;
  }
  EXPECT_NEAR(sum, summary.dof, 1e-8 * 60.0);
  EXPECT_EQ(summary.dof, 180.0 - fit.identifiability.kept_count() - 6.0);  // two eliminated tool points
}

TEST(Reliability, CleanSetsRejectNoPose) {
  // Gaussian noise only: at alpha = 0.1 % for the whole set, 40 sets lose no pose (the chance
  // of any rejection is about 4 %; these seeds are fixed).
  std::size_t rejected = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    Random random(seed);
    const std::size_t count = 10 + static_cast<std::size_t>(random.below(60));
    const RobotModel model = truth(seed);
    dataset.clear();
    test::fill_dataset(model, test::example_base_to_tracker(), count, 10e-6, &random, &dataset);
    ASSERT_EQ(fit_all(model), Status::ok);
    Collect collect;
    const BlunderTestSummary summary = test_fit(&collect);
    rejected += summary.rejected;
    // The data's sigma, never below the stated 10 um: a fit finer than the tracker tests
    // against the tracker.
    const bool finer = summary.fit_sigma_m < 10e-6;
    EXPECT_EQ(summary.sigma_source, finer ? SigmaSource::tracker : SigmaSource::data) << seed;
    EXPECT_EQ(summary.sigma_m, finer ? 10e-6 : summary.fit_sigma_m) << seed;
    EXPECT_NEAR(summary.fit_sigma_m, 10e-6, 5e-6) << seed;
  }
  EXPECT_EQ(rejected, 0u);
}

TEST(Reliability, AFitFinerThanTheTrackerIsTestedAgainstTheTracker) {
  // Noise-free readings: the fit's residuals are rounding (sigma ~1e-12 m); against them every
  // pose would be a blunder. The stated 10 um is the floor: no pose is rejected.
  Random random(3);
  const RobotModel model = truth(3);
  dataset.clear();
  test::fill_dataset(model, test::example_base_to_tracker(), 40, 0.0, &random, &dataset);
  ASSERT_EQ(fit_all(model), Status::ok);
  Collect collect;
  const BlunderTestSummary summary = test_fit(&collect);
  EXPECT_LT(summary.fit_sigma_m, 1e-9);
  EXPECT_EQ(summary.sigma_source, SigmaSource::tracker);
  EXPECT_EQ(summary.sigma_m, BlunderTestOptions{}.tracker_sigma_m);
  EXPECT_EQ(summary.rejected, 0u);
}

TEST(Reliability, ABlunderAboveItsDetectableBiasIsTheWorstPose) {
  // A bias of twice the pose's MDB, in a random direction, on a controlled pose of a clean set.
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    Random random(50 + seed);
    const RobotModel model = truth(seed);
    dataset.clear();
    test::fill_dataset(model, test::example_base_to_tracker(), 40, 10e-6, &random, &dataset);
    ASSERT_EQ(fit_all(model), Status::ok);
    Collect clean;
    test_fit(&clean);
    const std::size_t bad = static_cast<std::size_t>(random.below(40));
    ASSERT_TRUE(clean.units[bad].controlled);
    const double mdb_m = clean.units[bad].mdb_m;
    EXPECT_GT(mdb_m, 10e-6);
    EXPECT_LT(mdb_m, 0.5e-3);
    Vec3 direction(random.normal(), random.normal(), random.normal());
    Dataset<kCapacity> copy;
    for (const Sample& s : dataset.samples()) {
      const Vec3 offset = s.index == bad ? Vec3(2.0 * mdb_m * direction.normalized()) : Vec3(Vec3::Zero());
      ASSERT_EQ(copy.add(s.q_rad, s.point_m + offset), Status::ok);
    }
    dataset.clear();
    for (const Sample& s : copy.samples()) ASSERT_EQ(dataset.add(s.q_rad, s.point_m), Status::ok);
    ASSERT_EQ(fit_all(model), Status::ok);
    Collect blundered;
    test_fit(&blundered);
    std::size_t worst = 0;
    for (std::size_t k = 0; k < blundered.units.size(); ++k) {
      if (blundered.units[k].w > blundered.units[worst].w) worst = k;
    }
    EXPECT_EQ(worst, bad) << seed;
    EXPECT_TRUE(blundered.units[bad].rejected())
        << seed << ": w " << blundered.units[bad].w << " critical " << blundered.units[bad].critical_w;
  }
}

/// `poses` poses of three reflectors on a plate, each pose moved as a whole by an error of
/// `shared_m` per axis (what an unmodelled effect does to every reflector of a pose alike) and
/// each reading by the tracker's 10 um; `blunder_m` added to reading `blunder_target` of pose
/// `blunder_pose` (all three when -1). LM fits them, tool points included.
Dataset<600> plate_dataset;
void fit_shared_error_set(std::uint64_t seed, std::size_t poses, double shared_m, std::size_t blunder_pose = 0,
                          int blunder_target = 0, double blunder_m = 0.0) {
  const RobotModel model = test::with_plate(truth(seed), Vec3(0.01, 0.02, 0.1));
  Random random(900 + seed);
  plate_dataset.clear();
  for (std::size_t i = 0; i < poses; ++i) {
    const JointVector q = test::random_joints(&random);
    const Vec3 shared = shared_m * test::gaussian_vector(&random);
    for (int target = 0; target < 3; ++target) {
      Vec3 point = test::example_base_to_tracker().apply(fk_target_point(model, q, target)) + shared +
                   10e-6 * test::gaussian_vector(&random);
      if (i == blunder_pose && (blunder_target < 0 || blunder_target == target))
        point += Vec3(0.6, -0.8, 0.0) * blunder_m;
      ASSERT_EQ(plate_dataset.add(q, point, target), Status::ok);
    }
  }
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = model.tool_m;
  ASSERT_EQ(calibrate_lm(start, nullptr, plate_dataset.samples(), LmOptions{}, &lm_workspace, &fit), Status::ok);
}

BlunderTestSummary test_plate_fit(Collect* collect) {
  BlunderTestSummary summary;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = test_for_blunders(fit.model, fit.base_to_tracker, plate_dataset.samples(),
                                            Span<const Sample>(), fit.identifiability.kept_mask | kOtherTargetTools,
                                            PointLoss{}, BlunderTestOptions{}, &reliability, collect, &summary));
  EXPECT_EQ(status, Status::ok);
  return summary;
}

TEST(Reliability, ReadingsOfAPoseThatShareTheirErrorAreNotBlundersTogether) {
  // A real arm's residual is mostly model error, and it moves every reflector of a pose alike
  // (and the points a measured orientation adds): the pose's 9 rows are then one error three
  // times, whose statistic is 3 chi2(3), not chi2(9). Tested as independent rows, 0.2 mm per
  // axis set aside 1-2 of the 120 poses on 3 of these 8 seeds (checked); with the readings'
  // correlation pooled over the poses, none.
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    fit_shared_error_set(seed, 120, 0.2e-3);
    Collect collect;
    const BlunderTestSummary summary = test_plate_fit(&collect);
    EXPECT_TRUE(summary.pooled_correlation) << seed;
    EXPECT_EQ(summary.sigma_source, SigmaSource::data) << seed;
    EXPECT_EQ(summary.rejected, 0u) << seed;
    ASSERT_EQ(collect.units.size(), 120u);
    // The threshold of 3 chi2(3) at alpha / n = 8.3e-6, sqrt(3 x 26.5) = 8.9, not chi2(9)'s 6.4.
    EXPECT_GT(collect.units[0].critical_w, 8.7) << seed;
    EXPECT_LT(collect.units[0].critical_w, 9.2) << seed;
  }
}

TEST(Reliability, ReadingsWithTheirOwnErrorsKeepTheIndependentTest) {
  // Tracker noise only: the pooled correlation is ~0 (+- 1/sqrt(n)), and the threshold that of
  // 9 independent rows, sqrt(9 F(9, dof - 9)) at alpha / n = 8.3e-6: 6.4.
  fit_shared_error_set(3, 120, 0.0);
  Collect collect;
  const BlunderTestSummary summary = test_plate_fit(&collect);
  EXPECT_TRUE(summary.pooled_correlation);
  EXPECT_EQ(summary.rejected, 0u);
  EXPECT_GT(collect.units[0].critical_w, 6.3);
  EXPECT_LT(collect.units[0].critical_w, 6.5);
}

TEST(Reliability, ABlunderAmongPosesThatShareTheirErrorIsFound) {
  // 0.2 mm of shared error per axis: a 3 mm blunder on the whole pose, or on one of its
  // reflectors, is the worst pose and rejected.
  for (int target : {-1, 0, 2}) {
    fit_shared_error_set(5, 120, 0.2e-3, 37, target, 3e-3);
    Collect collect;
    const BlunderTestSummary summary = test_plate_fit(&collect);
    std::size_t worst = 0;
    for (std::size_t k = 0; k < collect.units.size(); ++k) {
      if (collect.units[k].w > collect.units[worst].w) worst = k;
    }
    EXPECT_EQ(worst, 37u) << target;
    EXPECT_TRUE(collect.units[37].rejected())
        << target << ": w " << collect.units[37].w << " critical " << collect.units[37].critical_w;
    EXPECT_EQ(summary.rejected, 1u) << target;
  }
}

TEST(Reliability, FewPosesOfSeveralReadingsAreTestedAsIndependent) {
  // Below kMinPooledPoses poses a correlation is too uncertain to pool: the rows as independent.
  fit_shared_error_set(2, kMinPooledPoses - 1, 0.2e-3);
  Collect collect;
  const BlunderTestSummary summary = test_plate_fit(&collect);
  EXPECT_FALSE(summary.pooled_correlation);
}

TEST(Reliability, TooLittleRedundancyUsesTheTrackersSigma) {
  Random random(3);
  const RobotModel model = truth(3);
  dataset.clear();
  test::fill_dataset(model, test::example_base_to_tracker(), 8, 10e-6, &random, &dataset);  // 24 rows
  ASSERT_EQ(fit_all(model), Status::ok);
  Collect collect;
  const BlunderTestSummary summary = test_fit(&collect);
  ASSERT_LT(summary.dof, 4.0);
  EXPECT_EQ(summary.sigma_source, SigmaSource::tracker);
  EXPECT_EQ(summary.sigma_m, BlunderTestOptions{}.tracker_sigma_m);
}

TEST(Reliability, BadArgumentsAreRefused) {
  BlunderTestSummary summary;
  BlunderTestOptions options;
  options.alpha = 0.0;
  EXPECT_EQ(test_for_blunders(fit.model, fit.base_to_tracker, dataset.samples(), {}, rigid_params_mask(kSixJoints),
                              PointLoss{}, options, &reliability, nullptr, &summary),
            Status::invalid_argument);
  EXPECT_EQ(test_for_blunders(fit.model, fit.base_to_tracker, Span<const Sample>(), {}, rigid_params_mask(kSixJoints),
                              PointLoss{}, BlunderTestOptions{}, &reliability, nullptr, &summary),
            Status::dataset_empty);
}

}  // namespace
}  // namespace hivecal::reliability_test
