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
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &dataset, options, &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    const bool tool_x_pruned = mask_has(result.lm_pruned_mask, tool_param_index(0));
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

}  // namespace
}  // namespace hivecal::calibration_targets_test
