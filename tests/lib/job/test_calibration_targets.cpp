// The calibration job on several targets (issue 11): when the significance test fixes target
// 1's tool_x, LM still estimates the other targets' tool points (they used to stay at their
// start values, 4-8 mm off on the pendant split with orientation).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/target_data.hpp"

namespace hivecal::calibration_targets_test {
namespace {

constexpr std::size_t kSamples = 120;
using Workspace = CalibrationWorkspace<kSamples, double, 40, 300>;

Workspace workspace;
CalibrationResult result;
Dataset<kSamples> dataset;
Dataset<kSamples> fresh;

const Vec3 kTool_m(0.012, -0.006, 0.17);

// A UR5 truth with three reflectors, 40 poses with 10 um noise; the start is the truth's
// geometry with target 1's tool_x exact (so its change is noise and the significance test
// fixes it), its y and z 2-3 mm off, and nothing of targets 2 and 3 (0). After the job every fresh point of every
// target is within a few noise sigmas: targets 2 and 3 were estimated.
TEST(CalibrationTargets, TargetsTwoAndThreeAreEstimatedWhenTheSignificanceTestFixesToolX) {
  const double noise_m = 1e-5;
  int pruned_runs = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Random random(seed);
    const RobotModel truth =
        test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
    const RigidTransform base = test::example_base_to_tracker();
    dataset.clear();
    fresh.clear();
    test::fill_target_dataset(truth, base, 40, 3, noise_m, &random, &dataset);
    test::fill_target_dataset(truth, base, 30, 3, 0.0, &random, &fresh);
    RobotModel start = truth;
    start.tool_m = Vec3(truth.tool_m.x(), truth.tool_m.y() + 0.003, truth.tool_m.z() - 0.002);
    for (Vec3& tool : start.other_tools_m) tool.setZero();
    CalibrationOptions options;
    options.method = CalibrationMethod::lm;
    options.train_fraction = 1.0;
    options.significance_every_set = true;  // 40 poses: by default, too many for the geometry's test
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &dataset, options, &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    const bool tool_x_pruned = mask_has(result.lm_pruned_mask, tool_param_index(kSixJoints, 0));
    const CalibrationStage& stage = result.stages[result.stage_count - 1];
    double worst_m = 0.0;
    for (const Sample& s : fresh.samples()) {
      const Vec3 predicted = stage.base_to_tracker.apply(fk_sample_point(stage.model, s));
      worst_m = std::fmax(worst_m, (predicted - base.apply(fk_sample_point(truth, s))).norm());
    }
    std::printf("seed %d: %d fixed, tool_x %s, worst fresh error %.4f mm\n", static_cast<int>(seed),
                mask_count(result.lm_pruned_mask), tool_x_pruned ? "fixed" : "estimated", worst_m * 1e3);
    if (tool_x_pruned) ++pruned_runs;
    EXPECT_LT(worst_m, 5.0 * noise_m) << "seed " << seed;
  }
  // The case this test is about happened (it is not a test of the significance level).
  EXPECT_GE(pruned_runs, 2);
}

// Three reflectors on an arm whose joints carry what the rigid model cannot take (an elbow
// and a wrist that turn up to 0.5 mrad more than they read, once and twice per turn): after the
// rigid fit each pose keeps ~0.1 mm per axis of error that moves its three reflectors alike. That
// is model error, not blunders: the default job sets no pose aside, and still names a 3 mm
// blunder. As independent readings (checked) the test found more than 5 % of the poses failing
// on seed 1, called the model wrong, and with that set nothing aside: the 3 mm blunder too.
constexpr std::size_t kPlatePoses = 100;
Dataset<3 * kPlatePoses> plate;
CalibrationWorkspace<3 * kPlatePoses> plate_workspace;

void fill_plate_with_model_error(std::uint64_t seed, std::size_t blunder_pose, double blunder_m) {
  plate.clear();
  test::fill_plate_with_joint_errors(seed, kPlatePoses, kTool_m, blunder_pose, blunder_m, &plate);
}

TEST(CalibrationTargets, ModelErrorSharedByAPosesReflectorsIsNotABlunder) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    fill_plate_with_model_error(seed, kPlatePoses, 0.0);
    RobotModel start = nominal_model(RobotType::ur5);
    start.tool_m = kTool_m;
    const CalibrationOptions options;  // the command line's defaults: ABC+LM, 70/30 split
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &plate, options, &plate_workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    std::printf("seed %d: fit sigma %.4f mm, %s, %zu set aside\n", static_cast<int>(seed),
                result.blunder_test.fit_sigma_m * 1e3,
                result.blunder_test.pooled_correlation ? "pooled" : "independent", result.outlier_count);
    EXPECT_GT(result.blunder_test.fit_sigma_m, 5e-5) << seed;  // the model error dominates the 10 um noise
    EXPECT_TRUE(result.blunder_test.pooled_correlation) << seed;
    EXPECT_EQ(result.outlier_count, 0u) << seed;
    // Seed 2 has a pose at the threshold (the test below); the others none.
    EXPECT_EQ(result.blunder_verdict, seed == 2 ? BlunderVerdict::at_threshold : BlunderVerdict::clean) << seed;

    fill_plate_with_model_error(seed, 17, 3e-3);
    ASSERT_EQ(calibrate(start, &plate, options, &plate_workspace, &result), Status::ok);
    ASSERT_EQ(result.outlier_count, 3u) << seed;  // the pose: its three samples
    for (const CalibrationOutlier& o : result.outlier_list()) EXPECT_EQ(o.index / 3, 17u) << seed;
  }
}

/// Each pose's test under the final calibration, by its first sample's index.
class FailingPoses final : public UnitTestVisitor {
 public:
  void on_unit(const UnitTest& t) override {
    if (t.rejected()) failing[failing_count++ % 8] = t;
  }
  UnitTest failing[8];
  std::size_t failing_count = 0;
};

// A pose whose w is just above its threshold while fitted (8.69 against 8.62) and below it when
// left out: setting it aside moves the 70/30 split of the others, and the next run flags it
// again. The job used to stop after 4 such runs with the pose set aside though its last test
// had not flagged it (w reported 0). Now what the last two tests did not both flag is kept, the
// final run is of that set, and the verdict says so: nothing set aside, the pose named by the
// final test as a kept one above its threshold.
TEST(CalibrationTargets, APoseAtTheThresholdIsKeptAndSaidSo) {
  fill_plate_with_model_error(2, kPlatePoses, 0.0);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = kTool_m;
  const CalibrationOptions options;
  ASSERT_EQ(calibrate(start, &plate, options, &plate_workspace, &result), Status::ok);
  EXPECT_EQ(result.blunder_verdict, BlunderVerdict::at_threshold);
  EXPECT_EQ(result.outlier_count, 0u);
  EXPECT_GT(result.outlier_rounds, 4u);  // the runs that did not agree, and the final one
  static ReliabilityWorkspace reliability;
  FailingPoses failing;
  BlunderTestSummary summary;
  ASSERT_EQ(test_final_calibration(result, plate, options, &reliability, &failing, &summary), Status::ok);
  ASSERT_EQ(failing.failing_count, 1u);
  EXPECT_TRUE(failing.failing[0].fitted);
  EXPECT_EQ(failing.failing[0].index, 243u);  // pose 81, its three samples
  EXPECT_EQ(failing.failing[0].samples, 3u);
  EXPECT_LT(failing.failing[0].w, 1.02 * failing.failing[0].critical_w);
}

}  // namespace
}  // namespace hivecal::calibration_targets_test
