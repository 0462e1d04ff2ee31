// The calibration job on small sets and sets with blunders (calibration.hpp): a 0.6 m blunder
// among 18 poses is set aside and gives the bits of the set without it; 12 and 20 poses run
// with fewer parameters, named; cross-validation's folds partition the set and each fold's
// held-out MAE is the one of a calibration of its training part run by hand; the baseline
// fits the tool point; what LM drops stays at its start value.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/target_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::calibration_robust_test {
namespace {

constexpr std::size_t kSamples = 96;
using Workspace = CalibrationWorkspace<kSamples, double, 40, 300>;

Workspace workspace;
CalibrationResult result;
CalibrationResult other;
CrossValidationResult cv;
Dataset<kSamples> dataset;
Dataset<kSamples> by_hand;

bool same_bits(const RobotModel& a, const RobotModel& b) {
  const ModelParams pa = to_params(a);
  const ModelParams pb = to_params(b);
  return std::memcmp(pa.data(), pb.data(), sizeof(double) * model_param_count(kSixJoints)) == 0;
}

bool same_bits(const RigidTransform& a, const RigidTransform& b) {
  return std::memcmp(a.rotation.data(), b.rotation.data(), sizeof(double) * 9) == 0 &&
         std::memcmp(a.translation_m.data(), b.translation_m.data(), sizeof(double) * 3) == 0;
}

const RobotModel& truth() {
  static const RobotModel model = [] {
    Random random(11);
    return test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  }();
  return model;
}

/// The start geometry: nominal UR5 with a tool point guessed 5 mm off the truth's.
RobotModel start() {
  RobotModel model = nominal_model(RobotType::ur5);
  model.tool_m = truth().tool_m + Vec3(0.004, -0.003, 0.0);
  return model;
}

/// `count` poses of the truth seen with 10 um noise (the same poses for the same count).
void fill(std::size_t count, DatasetBase* out) {
  Random random(5);
  out->clear();
  test::fill_dataset(truth(), test::example_base_to_tracker(), count, 10e-6, &random, out);
}

CalibrationOptions options(CalibrationMethod method) {
  CalibrationOptions o;
  o.method = method;
  o.train_fraction = 1.0;
  o.abc_food_sources = 20;
  o.abc_cycles = 20;
  return o;
}

/// The dataset of fill(count) with sample `bad` moved by `offset` (default 0.6 m: a mismatched pose).
void fill_with_blunder(std::size_t count, std::size_t bad, DatasetBase* out,
                       const Vec3& blunder = Vec3(0.35, -0.4, 0.3)) {  // |blunder| = 0.61 m
  Dataset<kSamples> clean;
  fill(count, &clean);
  out->clear();
  for (const Sample& s : clean.samples()) {
    const Vec3 offset = s.index == bad ? blunder : Vec3::Zero();
    ASSERT_EQ(out->add(s.q_rad, s.point_m + offset), Status::ok);
  }
}

/// The same set with sample `bad` never added.
void fill_without(std::size_t count, std::size_t bad, DatasetBase* out) {
  Dataset<kSamples> clean;
  fill(count, &clean);
  out->clear();
  for (const Sample& s : clean.samples()) {
    if (s.index != bad) {
      ASSERT_EQ(out->add(s.q_rad, s.point_m), Status::ok);
    }
  }
}

TEST(CalibrationRobust, ABlunderAmong18PosesGivesTheBitsOfTheSetWithoutIt) {
  // Bitwise: the job always starts from the samples in the order of add() and sets the
  // blunder aside before the split, so its last run sees exactly the 17 samples of the set
  // built without it, in the same order, and runs the same operations on them.
  for (CalibrationMethod method : {CalibrationMethod::lm, CalibrationMethod::abc_lm}) {
    for (double fraction : {1.0, 0.7}) {
      CalibrationOptions o = options(method);
      o.train_fraction = fraction;
      fill_with_blunder(18, 7, &dataset);
      Status status = Status::invalid_argument;
      EXPECT_NO_HEAP(status = calibrate(start(), &dataset, o, &workspace, &result));
      ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
      ASSERT_EQ(result.outlier_count, 1u);
      EXPECT_EQ(result.outliers[0].index, 7u);
      EXPECT_NEAR(result.outliers[0].residual_m, 0.61, 0.05);
      EXPECT_EQ(result.outlier_rounds, 1u);  // screened out, confirmed by the calibration's test: one run
      EXPECT_EQ(dataset.size(), 17u);
      EXPECT_EQ(result.train_count + result.test_count, 17u);

      fill_without(18, 7, &by_hand);
      ASSERT_EQ(calibrate(start(), &by_hand, o, &workspace, &other), Status::ok);
      EXPECT_EQ(other.outlier_count, 0u);
      EXPECT_EQ(other.outlier_rounds, 1u);
      const CalibrationStage& a = result.stages[result.stage_count - 1];
      const CalibrationStage& b = other.stages[other.stage_count - 1];
      EXPECT_TRUE(same_bits(a.model, b.model)) << calibration_method_name(method) << " " << fraction;
      EXPECT_TRUE(same_bits(a.base_to_tracker, b.base_to_tracker));
      EXPECT_TRUE(same_bits(result.baseline.model, other.baseline.model));
      EXPECT_TRUE(same_bits(result.baseline.base_to_tracker, other.baseline.base_to_tracker));
      EXPECT_EQ(a.train.mae(ErrorAxis::norm_3d), b.train.mae(ErrorAxis::norm_3d));
      EXPECT_LT(a.train.mae(ErrorAxis::norm_3d), 100e-6);
    }
  }
}

/// `poses` poses of fill() each read twice (the second reading 10 um of noise off the first),
/// reading `bad` (a position in add() order) moved by 0.6 m unless it is past the end.
void fill_read_twice(std::size_t poses, std::size_t bad, DatasetBase* out) {
  Dataset<kSamples> clean;
  fill(poses, &clean);
  Random random(17);
  out->clear();
  for (const Sample& s : clean.samples()) {
    const Vec3 second_m = s.point_m + 10e-6 * Vec3(random.normal(), random.normal(), random.normal());
    for (const Vec3& reading_m : {s.point_m, second_m}) {
      const Vec3 offset = out->size() == bad ? Vec3(0.35, -0.4, 0.3) : Vec3::Zero();
      ASSERT_EQ(out->add(s.q_rad, reading_m + offset), Status::ok);
    }
  }
}

TEST(CalibrationRobust, TheReadingNoiseIsTheKeptSamplesScatterNotTheBlunders) {
  // 20 poses read twice, one reading 0.6 m off: the job sets it aside and its pose's other
  // reading stands alone, so the noise pools 19 pairs, exactly those of the set without it.
  fill_read_twice(20, 9, &dataset);
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.train_fraction = 0.7;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(start(), &dataset, o, &workspace, &result));
  ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
  ASSERT_EQ(result.outlier_count, 1u);
  EXPECT_EQ(result.outliers[0].index, 9u);
  EXPECT_EQ(result.reading_noise.groups, 19u);
  EXPECT_EQ(result.reading_noise.readings, 38u);
  EXPECT_GT(result.reading_noise.sigma_m, 3e-6);
  EXPECT_LT(result.reading_noise.sigma_m, 15e-6);

  fill_read_twice(20, 2 * 20, &by_hand);  // no blunder
  Dataset<kSamples> kept;
  for (const Sample& s : by_hand.samples()) {
    if (s.index != 9) {
      ASSERT_EQ(kept.add(s.q_rad, s.point_m), Status::ok);
    }
  }
  const RepeatedReadingNoise expected = repeated_reading_noise(kept.samples());
  EXPECT_EQ(std::memcmp(&result.reading_noise.sigma_m, &expected.sigma_m, sizeof(double)), 0);

  o.keep_outliers = true;  // kept, the blunder is counted as noise: it is the user's choice
  fill_read_twice(20, 9, &dataset);
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  EXPECT_EQ(result.reading_noise.groups, 20u);
  EXPECT_GT(result.reading_noise.sigma_m, 0.05);
}

TEST(CalibrationRobust, ASmallBlunderTheScreenMissesIsFoundByTheCalibrationsTest) {
  // 6 mm: below the start geometry's screen floor (10 mm), far above the calibrated residuals.
  fill_with_blunder(18, 11, &dataset, Vec3(0.004, 0.004, -0.002));
  const CalibrationOptions o = options(CalibrationMethod::lm);
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  ASSERT_EQ(result.outlier_count, 1u);
  EXPECT_EQ(result.outliers[0].index, 11u);
  EXPECT_EQ(result.outlier_rounds, 2u);  // the first run kept it, its residual test set it aside
  EXPECT_NEAR(result.outliers[0].residual_m, 0.006, 0.002);
  fill_without(18, 11, &by_hand);
  ASSERT_EQ(calibrate(start(), &by_hand, o, &workspace, &other), Status::ok);
  EXPECT_TRUE(same_bits(result.stages[0].model, other.stages[0].model));
}

TEST(CalibrationRobust, ThreeBlundersOfEveryScaleAmong30PosesGiveTheBitsOfTheSetWithoutThem) {
  Dataset<kSamples> clean;
  fill(30, &clean);
  const std::uint32_t bad[3] = {3, 17, 26};
  const Vec3 offsets[3] = {Vec3(0.0, 0.6, 0.0), Vec3(0.03, -0.04, 0.0), Vec3(0.0, 0.0, 0.005)};  // 0.6 m, 50 mm, 5 mm
  dataset.clear();
  by_hand.clear();
  for (const Sample& s : clean.samples()) {
    Vec3 offset = Vec3::Zero();
    for (int k = 0; k < 3; ++k) offset += s.index == bad[k] ? offsets[k] : Vec3::Zero();
    ASSERT_EQ(dataset.add(s.q_rad, s.point_m + offset), Status::ok);
    if (offset.isZero()) {
      ASSERT_EQ(by_hand.add(s.q_rad, s.point_m), Status::ok);
    }
  }
  CalibrationOptions o = options(CalibrationMethod::abc_lm);
  o.train_fraction = 0.7;
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  ASSERT_EQ(result.outlier_count, 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(result.outliers[k].index, bad[k]);
    EXPECT_NEAR(result.outliers[k].residual_m, offsets[k].norm(), 0.2 * offsets[k].norm());
  }
  ASSERT_EQ(calibrate(start(), &by_hand, o, &workspace, &other), Status::ok);
  EXPECT_EQ(other.outlier_count, 0u);
  EXPECT_TRUE(same_bits(result.stages[1].model, other.stages[1].model));
  EXPECT_TRUE(same_bits(result.stages[1].base_to_tracker, other.stages[1].base_to_tracker));
  EXPECT_EQ(result.stages[1].test.mae(ErrorAxis::norm_3d), other.stages[1].test.mae(ErrorAxis::norm_3d));
}

TEST(CalibrationRobust, KeepOutliersUsesTheBlunderAndIsDraggedByIt) {
  fill_with_blunder(18, 7, &dataset);
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.keep_outliers = true;
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  EXPECT_EQ(result.outlier_count, 0u);
  EXPECT_EQ(result.outlier_rounds, 0u);
  EXPECT_EQ(result.train_count, 18u);
  EXPECT_GT(result.baseline.train.mae(ErrorAxis::norm_3d), 10e-3);  // the blunder drags the base fit
}

TEST(CalibrationRobust, ACleanSetLosesNoSample) {
  for (std::size_t count : {12u, 20u, 60u}) {
    fill(count, &dataset);
    ASSERT_EQ(calibrate(start(), &dataset, options(CalibrationMethod::abc_lm), &workspace, &result), Status::ok);
    EXPECT_EQ(result.outlier_count, 0u) << count;
    EXPECT_EQ(result.train_count, count);
    EXPECT_GT(result.blunder_test.sigma_m, 0.0);
  }
}

TEST(CalibrationRobust, TwelveAndTwentyPosesRunWithFewerParametersNamed) {
  int kept[2] = {};
  const std::size_t counts[2] = {12, 20};
  for (int k = 0; k < 2; ++k) {
    fill(counts[k], &dataset);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start(), &dataset, options(CalibrationMethod::abc_lm), &workspace, &result));
    ASSERT_EQ(status, Status::ok) << counts[k] << ": " << calibration_step_name(result.step);
    ASSERT_TRUE(result.has_lm);
    const IdentifiabilityReport& id = result.lm.identifiability;
    kept[k] = id.kept_count();
    EXPECT_EQ(id.dropped_count, mask_count(id.free_mask) - id.kept_count());  // each one named, with its reason
    EXPECT_GT(id.dropped_count, 0);
    EXPECT_LT(3 * static_cast<int>(counts[k]), 3 * 20 + 1);
    const CalibrationStage& lm = result.stages[result.stage_count - 1];
    EXPECT_LT(lm.train.mae(ErrorAxis::norm_3d), result.baseline.train.mae(ErrorAxis::norm_3d));
  }
  // Fewer samples never identify more; the 12-pose fit must leave out more than the
  // structural 9 of a UR arm (3 N = 36 equations for 33 candidates).
  EXPECT_LE(kept[0], kept[1]);
  EXPECT_LT(kept[0] + kBaseParamCount, 3 * 12);
}

TEST(CalibrationRobust, AbcOnTheSixLengthsRunsOnAHandfulOfPoses) {
  // The paper's set (6 lengths + base) on 6 poses: the base fit is determined, so it runs.
  for (CalibrationMethod method : {CalibrationMethod::abc, CalibrationMethod::abc_lm}) {
    fill(6, &dataset);
    CalibrationOptions o = options(method);
    o.params = CalibrationParams::paper;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start(), &dataset, o, &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_method_name(method) << ": " << calibration_step_name(result.step);
    EXPECT_EQ(result.train_count, 6u);
    EXPECT_EQ(result.outlier_count, 0u);  // 18 equations for 12 parameters: no sample looks like a blunder
    EXPECT_LE(result.stages[0].train.mae(ErrorAxis::norm_3d), result.baseline.train.mae(ErrorAxis::norm_3d));
  }
}

TEST(CalibrationRobust, ParametersWithoutSignificantChangeAreFixedAtTheirStartValues) {
  fill(12, &dataset);
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.significance_t = 0.0;
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &other), Status::ok);
  EXPECT_EQ(other.lm_pruned_mask, 0u);
  fill(12, &dataset);
  o.significance_t = 2.0;
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  ASSERT_NE(result.lm_pruned_mask, 0u);
  EXPECT_LT(result.lm.identifiability.kept_count(), other.lm.identifiability.kept_count());
  const ModelParams fitted = to_params(result.stages[0].model);
  const ModelParams from = to_params(result.baseline.model);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(result.lm_pruned_mask, i)) continue;
    EXPECT_EQ(fitted(i), from(i)) << full_param_name(i, kSixJoints);
    EXPECT_FALSE(mask_has(result.lm.identifiability.kept_mask, i));
  }
  // Every parameter still estimated moved by at least 2 sigma.
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(result.lm.identifiability.kept_mask, i)) continue;
    EXPECT_GE(std::fabs(fitted(i) - from(i)), 2.0 * result.lm.sigma(i)) << full_param_name(i, kSixJoints);
  }
}

// The geometry's significance test runs on small sets only: on every count of poses it ran
// exactly when there were fewer than kSignificancePosesPerParam poses per estimated rigid
// parameter; where it did not, nothing rigid is fixed and the fit is the one without the test,
// bit for bit. The start is the truth with the tool point guessed off, so every geometry change
// is noise and the test, where it runs, fixes some.
TEST(CalibrationRobust, TheGeometrysSignificanceTestRunsOnSmallSetsOnly) {
  RobotModel from = truth();
  from.tool_m += Vec3(0.004, -0.003, 0.0);
  int tested = 0;
  int untested = 0;
  for (std::size_t count = 12; count <= 64; count += 4) {
    fill(count, &dataset);
    const CalibrationOptions o = options(CalibrationMethod::lm);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(from, &dataset, o, &workspace, &result));
    ASSERT_EQ(status, Status::ok) << count;
    EXPECT_EQ(result.significance_poses, count);
    const bool small =
        static_cast<double>(count) < kSignificancePosesPerParam * static_cast<double>(result.significance_params);
    EXPECT_EQ(result.geometry_tested, small) << count << " poses, " << result.significance_params << " parameters";
    if (small) {
      ++tested;
      EXPECT_NE(result.lm_pruned_mask & rigid_params_mask(kSixJoints), 0u) << count;
      continue;
    }
    ++untested;
    EXPECT_EQ(result.lm_pruned_mask, 0u) << count;
    fill(count, &dataset);
    CalibrationOptions off = o;
    off.significance_t = 0.0;
    ASSERT_EQ(calibrate(from, &dataset, off, &workspace, &other), Status::ok);
    EXPECT_TRUE(same_bits(result.stages[0].model, other.stages[0].model)) << count;
    // Asked for every set, the test runs here too.
    fill(count, &dataset);
    CalibrationOptions every = o;
    every.significance_every_set = true;
    ASSERT_EQ(calibrate(from, &dataset, every, &workspace, &other), Status::ok);
    EXPECT_TRUE(other.geometry_tested);
    EXPECT_NE(other.lm_pruned_mask & rigid_params_mask(kSixJoints), 0u) << count;
  }
  EXPECT_GT(tested, 0);
  EXPECT_GT(untested, 0);
}

TEST(CalibrationRobust, AnAutomaticSignificanceLevelIsOneOfTheGridAndGivesThatLevelsBits) {
  for (std::size_t count : {12u, 20u}) {
    fill(count, &dataset);
    CalibrationOptions o = options(CalibrationMethod::abc_lm);
    o.significance_t = -1.0;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start(), &dataset, o, &workspace, &result));
    ASSERT_EQ(status, Status::ok);
    const double chosen = result.significance_t;
    EXPECT_TRUE(chosen == 0.0 || chosen == 1.0 || chosen == 2.0 || chosen == 3.0) << chosen;
    // The leave-one-out fits swap samples back: the final fit is the one of the fixed level.
    fill(count, &dataset);
    o.significance_t = chosen;
    ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &other), Status::ok);
    EXPECT_TRUE(same_bits(result.stages[1].model, other.stages[1].model)) << count;
    EXPECT_EQ(result.lm_pruned_mask, other.lm_pruned_mask);
  }
  // Three reflectors per pose: the search leaves each pose out with all its targets (a target
  // left out beside its twins would be predicted by a fit of its own pose); every pose comes
  // back to its place, so the final fit is the fixed level's, bit for bit.
  Random random(9);
  dataset.clear();
  test::fill_target_dataset(test::with_plate(truth(), truth().tool_m), test::example_base_to_tracker(), 10, 3, 10e-6,
                            &random, &dataset);
  CalibrationOptions three = options(CalibrationMethod::lm);
  three.significance_t = -1.0;
  ASSERT_EQ(calibrate(start(), &dataset, three, &workspace, &result), Status::ok);
  const double chosen = result.significance_t;
  EXPECT_TRUE(chosen == 0.0 || chosen == 1.0 || chosen == 2.0 || chosen == 3.0) << chosen;
  three.significance_t = chosen;
  ASSERT_EQ(calibrate(start(), &dataset, three, &workspace, &other), Status::ok);
  EXPECT_TRUE(same_bits(result.stages[0].model, other.stages[0].model));
  EXPECT_EQ(result.lm_pruned_mask, other.lm_pruned_mask);
  fill(kAutoSignificanceMaxSamples + 1, &dataset);  // a large set: the default level, no search
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.significance_t = -1.0;
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  EXPECT_EQ(result.significance_t, kDefaultSignificance);
}

TEST(CalibrationRobust, TheBaselineFitsTheToolPoint) {
  fill(40, &dataset);
  ASSERT_EQ(calibrate(start(), &dataset, options(CalibrationMethod::lm), &workspace, &result), Status::ok);
  EXPECT_TRUE(result.baseline.tool_fitted);
  // The 5 mm tool guess is corrected; the rest is the nominal joints' error (about 1 mm).
  const Vec3 fitted = result.baseline.model.tool_m;
  EXPECT_LT((fitted - truth().tool_m).norm(), (start().tool_m - truth().tool_m).norm());
  RigidTransform base_only;
  ASSERT_EQ(fit_base_to_tracker(start(), dataset.train(), &base_only), Status::ok);
  const ErrorStats guess = position_error_stats(start(), base_only, dataset.train());
  EXPECT_LT(result.baseline.train.mae(ErrorAxis::norm_3d), guess.mae(ErrorAxis::norm_3d));
}

TEST(CalibrationRobust, WhatLmDropsStaysAtItsStartValue) {
  fill(40, &dataset);
  CalibrationOptions o = options(CalibrationMethod::abc_lm);
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  const ModelParams abc = to_params(result.stages[0].model);
  const ModelParams lm = to_params(result.stages[1].model);
  const ModelParams from = to_params(result.baseline.model);  // the start joints, the fitted tool
  const IdentifiabilityReport& id = result.lm.identifiability;
  int moved_by_abc = 0;
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (mask_has(id.kept_mask, i)) continue;
    EXPECT_EQ(lm(i), from(i)) << full_param_name(i, kSixJoints);
    if (abc(i) != from(i)) ++moved_by_abc;
  }
  EXPECT_GT(moved_by_abc, 0) << "ABC moved none of the dropped lengths: the check would pass without the reset";
}

TEST(CalibrationRobust, SetsThatDetermineNothingAreRefused) {
  fill(2, &dataset);
  EXPECT_EQ(calibrate(start(), &dataset, options(CalibrationMethod::lm), &workspace, &result), Status::too_few_samples);
  EXPECT_EQ(result.step, CalibrationStep::baseline);
  dataset.clear();
  JointVector q;
  q << 0.3, 0.3, 0.3, 0.3, 0.3, 0.3;
  for (int i = 0; i < 6; ++i) {  // one joint position, six readings: one point
    ASSERT_EQ(dataset.add(q, Vec3(1.0, 0.5, 0.2)), Status::ok);
  }
  EXPECT_EQ(calibrate(start(), &dataset, options(CalibrationMethod::lm), &workspace, &result),
            Status::degenerate_geometry);
  EXPECT_EQ(result.step, CalibrationStep::baseline);
}

TEST(CalibrationRobust, CrossValidationFoldsPartitionTheSetAndMatchAManualRun) {
  const std::size_t n = 30;
  const std::size_t k = 5;
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.seed = 3;
  // The folds: every sample held out exactly once.
  fill(n, &dataset);
  int held_out[kSamples] = {};
  for (std::size_t f = 0; f < k; ++f) {
    ASSERT_EQ(dataset.split_fold(f, k, o.seed), Status::ok);
    EXPECT_EQ(dataset.test().size(), n / k);
    for (const Sample& s : dataset.test()) ++held_out[s.index];
  }
  for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(held_out[i], 1) << i;

  fill(n, &dataset);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = cross_validate(start(), &dataset, o, k, &workspace, &result, &cv));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(cv.fold_count, k);
  EXPECT_EQ(cv.sample_count, n);
  double pooled_m = 0.0;
  for (std::size_t f = 0; f < k; ++f) {
    // By hand: the fold's training samples calibrated alone, its held-out ones predicted.
    fill(n, &dataset);
    ASSERT_EQ(dataset.split_fold(f, k, o.seed), Status::ok);
    by_hand.clear();
    for (const Sample& s : dataset.train()) ASSERT_EQ(by_hand.add(s.q_rad, s.point_m), Status::ok);
    CalibrationOptions alone = o;
    alone.keep_outliers = true;
    ASSERT_EQ(calibrate(start(), &by_hand, alone, &workspace, &other), Status::ok);
    const CalibrationStage& fit = other.stages[other.stage_count - 1];
    const ErrorStats held = position_error_stats(fit.model, fit.base_to_tracker, dataset.test());
    // Not bitwise: the job shuffles the training part once more (split 1.0), so LM sums in
    // another order; the same minimum to rounding.
    EXPECT_NEAR(cv.folds[f].test.mae(ErrorAxis::norm_3d), held.mae(ErrorAxis::norm_3d), 1e-9) << f;
    EXPECT_EQ(cv.folds[f].test.count, n / k);
    EXPECT_EQ(cv.folds[f].train_count, n - n / k);
    pooled_m += held.mae(ErrorAxis::norm_3d) * static_cast<double>(held.count) / static_cast<double>(n);
  }
  EXPECT_NEAR(cv.mae_3d_m, pooled_m, 1e-9);
  EXPECT_LT(cv.mae_3d_m, 100e-6);
  EXPECT_GE(cv.fold_mae_3d_max_m, cv.fold_mae_3d_mean_m);
}

TEST(CalibrationRobust, LeaveOneOutLeavesTheBlunderOut) {
  fill_with_blunder(18, 4, &dataset);
  ASSERT_EQ(cross_validate(start(), &dataset, options(CalibrationMethod::lm), 0, &workspace, &result, &cv), Status::ok);
  EXPECT_EQ(cv.fold_count, 17u);
  EXPECT_EQ(cv.sample_count, 17u);
  for (std::size_t f = 0; f < cv.fold_count; ++f) EXPECT_EQ(cv.folds[f].test.count, 1u);
  EXPECT_LT(cv.mae_3d_m, 1e-3);
  EXPECT_EQ(cross_validate(start(), &dataset, options(CalibrationMethod::lm), 1, &workspace, &result, &cv),
            Status::invalid_argument);
}

}  // namespace
}  // namespace hivecal::calibration_robust_test

namespace hivecal::calibration_robust_test {
namespace {

constexpr std::size_t kLargeSamples = 1024;
CalibrationWorkspace<kLargeSamples, double, 2, 100> large_workspace;
Dataset<kLargeSamples> large;

TEST(CalibrationBlunders, A2mmBlunderAmong1000PosesIsFoundAndNamed) {
  // Far below the screen's 10 mm floor: only the w-test of the calibration can find it.
  Random random(21);
  large.clear();
  test::fill_dataset(truth(), test::example_base_to_tracker(), 1000, 10e-6, &random, &large);
  Dataset<kLargeSamples>& with_blunder = large;
  static Dataset<kLargeSamples> copy;
  copy.clear();
  for (const Sample& s : with_blunder.samples()) {
    ASSERT_EQ(copy.add(s.q_rad, s.point_m + (s.index == 637 ? Vec3(0.0012, -0.0012, 0.0011) : Vec3::Zero())),
              Status::ok);
  }
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.train_fraction = 0.8;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(start(), &copy, o, &large_workspace, &result));
  ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
  ASSERT_EQ(result.outlier_count, 1u);
  EXPECT_EQ(result.outliers[0].index, 637u);
  EXPECT_GT(result.outliers[0].w, result.outliers[0].critical_w);
  EXPECT_EQ(result.blunder_verdict, BlunderVerdict::removed);
  EXPECT_NEAR(result.blunder_test.fit_sigma_m, 10e-6, 2e-6);
  EXPECT_EQ(result.blunder_test.sigma_m, std::fmax(result.blunder_test.fit_sigma_m, 10e-6));  // never below the stated
  // The final calibration's test as a report sees it: every pose once, the blunder (set
  // aside, predicted) the only one above its threshold.
  struct Count final : UnitTestVisitor {
    void on_unit(const UnitTest& t) override {
      ++units;
      if (t.rejected()) rejected_index = t.index, ++rejected;
    }
    std::size_t units = 0, rejected = 0;
    std::uint32_t rejected_index = 0;
  } count;
  static ReliabilityWorkspace reliability;
  BlunderTestSummary summary;
  ASSERT_EQ(test_final_calibration(result, copy, o, &reliability, &count, &summary), Status::ok);
  EXPECT_EQ(count.units, 1000u);
  EXPECT_EQ(count.rejected, 1u);
  EXPECT_EQ(count.rejected_index, 637u);
  EXPECT_EQ(summary.sigma_m, result.blunder_test.sigma_m);
}

TEST(CalibrationBlunders, ManyFailingPosesAreTheModelNotBlundersAndNoneIsRemoved) {
  // A fifth of the poses 30x noisier: a residual pattern, not a blunder. More than
  // max_blunder_share would go, so the job removes none and says why.
  Random random(22);
  Dataset<kSamples> clean;
  fill(90, &clean);
  dataset.clear();
  for (const Sample& s : clean.samples()) {
    const Vec3 extra =
        s.index % 5 == 0 ? Vec3(300e-6 * Vec3(random.normal(), random.normal(), random.normal())) : Vec3(Vec3::Zero());
    ASSERT_EQ(dataset.add(s.q_rad, s.point_m + extra), Status::ok);
  }
  CalibrationOptions o = options(CalibrationMethod::lm);
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok);
  EXPECT_EQ(result.blunder_verdict, BlunderVerdict::model_error);
  EXPECT_EQ(result.outlier_count, 0u);
  EXPECT_EQ(result.train_count, 90u);
  EXPECT_EQ(result.blunder_limit, 4u);  // 5 % of 90
  // The search refitted fewer poses before it gave up; the result's LM details (sigmas,
  // identifiability, iterations) are the final calibration's again, not its last refit's.
  ASSERT_GT(result.stage_count, 0u);
  const CalibrationStage& final_stage = result.stages[result.stage_count - 1];
  EXPECT_EQ(result.lm.iterations, static_cast<int>(final_stage.iterations));
  EXPECT_EQ(result.lm.rms_m, final_stage.best_cost_m);
  EXPECT_TRUE(to_params(result.lm.model) == to_params(final_stage.model));
}

/// `count` poses of the truth with unmodelled effects (test::fill_with_unmodelled_effect).
void fill_with_model_error(std::size_t count, std::uint64_t seed, DatasetBase* out) {
  Random random(seed);
  out->clear();
  test::fill_with_unmodelled_effect(truth(), test::example_base_to_tracker(), count, &random, out);
}

TEST(CalibrationBlunders, TestPosesThatAFewPosesCannotPredictAreNotBlunders) {
  // Few poses of an arm with unmodelled effects: the fit of the 6 training poses predicts its 2
  // test poses no better than the effects, and the w-test rejects both. Set aside, test poses
  // shrink the next run's set, whose own test poses fail in turn (8 poses of the UR10 export
  // went down to 2 training poses, and the base frame could not be fitted; here the runs did
  // not agree in 5). More failing test poses than max_blunder_share are the model's error:
  // none is set aside, in the first run. Plain least squares: with the default prior the fit
  // of 6 poses stays near the nominal model where they do not determine it and predicts its
  // test poses (the verdict is clean).
  fill_with_model_error(8, 41, &dataset);
  CalibrationOptions o = options(CalibrationMethod::lm);
  o.train_fraction = 0.7;
  o.prior = LmPriorTolerances{};
  ASSERT_EQ(calibrate(start(), &dataset, o, &workspace, &result), Status::ok) << calibration_step_name(result.step);
  EXPECT_EQ(result.blunder_verdict, BlunderVerdict::prediction_error);
  EXPECT_EQ(result.outlier_count, 0u);
  EXPECT_EQ(result.train_count + result.test_count, 8u);
  EXPECT_EQ(result.test_blunder_limit, 1u);
  EXPECT_EQ(result.outlier_rounds, 1u);
}

TEST(CalibrationBlunders, SmallSetsWithModelErrorAndATestSplitFinishAndSetNothingAside) {
  // Property over random small sets (8 to 20 poses) with unmodelled effects and a 0.7 split:
  // the job finishes, every sample is trained on or tested, and none is set aside (there is no
  // blunder). Before the test poses obeyed the share rule, 12 poses ended as 3 trained, 1
  // tested and 8 "blunders" (seed 2).
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    Random sizes(700 + seed);
    const std::size_t count = 8 + static_cast<std::size_t>(sizes.below(13));
    fill_with_model_error(count, 900 + seed, &dataset);
    CalibrationOptions o = options(CalibrationMethod::lm);
    o.train_fraction = 0.7;
    const Status status = calibrate(start(), &dataset, o, &workspace, &result);
    ASSERT_EQ(status, Status::ok) << seed << " (" << count << " poses): " << status_message(status) << " at "
                                  << calibration_step_name(result.step);
    EXPECT_EQ(result.train_count + result.test_count + result.outlier_count, count) << seed;
    EXPECT_EQ(result.outlier_count, 0u) << seed << " (" << count
                                        << " poses): no blunder in the set, none may be made up";
    // The samples are left in the order of the job's last run (the blunder search's removals
    // undone): what is reported of the run is summed in it.
    std::vector<std::uint32_t> left;
    for (const Sample& s : dataset.samples()) left.push_back(s.index);
    dataset.set_aside(Span<const std::uint32_t>());  // the order of add(), nothing set aside: as the job's runs start
    ASSERT_EQ(dataset.split(o.train_fraction, o.seed), Status::ok);
    std::vector<std::uint32_t> run;
    for (const Sample& s : dataset.samples()) run.push_back(s.index);
    EXPECT_EQ(left, run) << seed;
  }
}

TEST(CalibrationBlunders, SmallAndDegenerateSetsFinishAndDropNothingSilently) {
  // Property over random small sets (5 to 16 poses, some of them repeated poses): the default
  // job (ABC+LM, --split 1) and its leave-one-out finish, or say why at the baseline step;
  // every sample is either trained on or listed as set aside.
  for (std::uint64_t seed = 1; seed <= 48; ++seed) {
    Random random(300 + seed);
    const std::size_t count = 5 + static_cast<std::size_t>(random.below(12));
    Dataset<kSamples> clean;
    clean.clear();
    test::fill_dataset(truth(), test::example_base_to_tracker(), count, 10e-6, &random, &clean);
    dataset.clear();
    for (const Sample& s : clean.samples()) {
      const Sample& source = seed % 3 == 0 && s.index % 2 == 1 ? clean.samples()[s.index - 1] : s;  // repeated poses
      ASSERT_EQ(dataset.add(source.q_rad, s.point_m), Status::ok);
    }
    CalibrationOptions o = options(CalibrationMethod::abc_lm);
    const Status status = calibrate(start(), &dataset, o, &workspace, &result);
    EXPECT_TRUE(status == Status::ok || result.step == CalibrationStep::baseline)
        << seed << " (" << count << " poses): " << status_message(status) << " at "
        << calibration_step_name(result.step);
    if (status == Status::ok) {
      EXPECT_EQ(result.train_count + result.outlier_count, count) << seed;
      // Leave-one-out on the same set finishes too from 8 poses on (a fold of 4 samples can
      // be too few even for the base and the tool point: too_few_samples, said so).
      if (count < 8) continue;
      const Status folds = cross_validate(start(), &dataset, o, 0, &workspace, &other, &cv);
      EXPECT_EQ(folds, Status::ok) << seed << " (" << count << " poses): " << status_message(folds);
    }
  }
}

}  // namespace
}  // namespace hivecal::calibration_robust_test
