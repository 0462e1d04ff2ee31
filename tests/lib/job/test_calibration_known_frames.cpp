// The calibration job with a known base and tool (CalibrationOptions::base_known,
// tool_known): a controller's own TCP readings (a pendant export, RTDE actual_TCP_pose) are
// FK(q) * its configured TCP offset in the robot's base frame, so neither is estimated, and
// joint 1's parameters, which a fitted base absorbs, become estimable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/target_data.hpp"

namespace hivecal::calibration_known_frames_test {
namespace {

constexpr std::size_t kSamples = 90;
using Workspace = CalibrationWorkspace<kSamples, double, 40, 300>;

Workspace workspace;
CalibrationResult result;
Dataset<kSamples> dataset;
Dataset<kSamples> fresh;

const Vec3 kTool_m(0.0, 0.0, 0.05);

/// Largest distance between the truth's and the final stage's points of `samples` in the base frame [m].
double worst_error_m(const RobotModel& truth, const Span<const Sample> samples) {
  const CalibrationStage& stage = result.stages[result.stage_count - 1];
  double worst_m = 0.0;
  for (const Sample& s : samples) {
    const Vec3 predicted = stage.base_to_tracker.apply(fk_sample_point(stage.model, s));
    worst_m = std::fmax(worst_m, (predicted - fk_sample_point(truth, s)).norm());
  }
  return worst_m;
}

// A perturbed UR5 read as a controller reports its TCP (base = identity, the TCP offset and
// two more points of the tool frame known exactly), 30 poses with 10 um noise. With both
// known the job keeps them bit for bit, estimates theta1 and d1 (a fitted base makes them
// unidentifiable) and predicts fresh poses within a few noise sigmas.
TEST(CalibrationKnownFrames, ControllerReadingsEstimateJointOneAndKeepBaseAndTool) {
  const double noise_m = 1e-5;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Random random(seed);
    const RobotModel truth =
        test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
    const RigidTransform identity;
    dataset.clear();
    fresh.clear();
    test::fill_target_dataset(truth, identity, 30, 3, noise_m, &random, &dataset);
    test::fill_target_dataset(truth, identity, 20, 3, 0.0, &random, &fresh);
    RobotModel start = nominal_model(RobotType::ur5);
    start.tool_m = truth.tool_m;
    for (int t = 1; t < kMaxTargets; ++t) target_tool(&start, t) = target_tool(truth, t);
    CalibrationOptions options;
    options.method = CalibrationMethod::lm;
    options.train_fraction = 1.0;
    options.base_known = true;
    options.tool_known = true;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &dataset, options, &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    const CalibrationStage& stage = result.stages[result.stage_count - 1];
    EXPECT_TRUE(stage.base_to_tracker.rotation == Mat3::Identity());
    EXPECT_TRUE(stage.base_to_tracker.translation_m == Vec3::Zero());
    for (int t = 0; t < kMaxTargets; ++t) EXPECT_TRUE(target_tool(stage.model, t) == target_tool(start, t)) << t;
    const ParamMask kept = result.lm.identifiability.kept_mask;
    EXPECT_TRUE(mask_has(kept, model_param_index(0, DhField::theta_offset)));
    EXPECT_TRUE(mask_has(kept, model_param_index(0, DhField::d)));
    for (int i = 0; i < 6; ++i) EXPECT_FALSE(mask_has(kept, kModelParamCount + i)) << "base parameter " << i;
    const double joint1_d_error_m = std::fabs(stage.model.joints[0].d_m - truth.joints[0].d_m);
    const double worst_m = worst_error_m(truth, fresh.samples());
    std::printf("seed %d: %d estimated, d1 error %.4f mm, worst fresh error %.4f mm\n", static_cast<int>(seed),
                result.lm.identifiability.kept_count(), joint1_d_error_m * 1e3, worst_m * 1e3);
    EXPECT_LT(joint1_d_error_m, 5.0 * noise_m) << "seed " << seed;
    EXPECT_LT(worst_m, 5.0 * noise_m) << "seed " << seed;

    // The same readings with the base fitted, as for a tracker: joint 1's theta and d go into
    // the base, not into the model.
    options.base_known = false;
    options.tool_known = false;
    ASSERT_EQ(calibrate(start, &dataset, options, &workspace, &result), Status::ok);
    EXPECT_FALSE(mask_has(result.lm.identifiability.kept_mask, model_param_index(0, DhField::d)));
  }
}

// ABC and GSA fit their own base (the paper's cost): a known frame with them is refused.
TEST(CalibrationKnownFrames, PopulationMethodsRefuseAKnownFrame) {
  Random random(7);
  const RobotModel truth = nominal_model(RobotType::ur5);
  dataset.clear();
  test::fill_target_dataset(truth, RigidTransform(), 30, 1, 1e-5, &random, &dataset);
  for (CalibrationMethod method : {CalibrationMethod::abc_lm, CalibrationMethod::abc, CalibrationMethod::gsa,
                                   CalibrationMethod::gsa_lm, CalibrationMethod::all}) {
    for (int which = 0; which < 2; ++which) {
      CalibrationOptions options;
      options.method = method;
      options.base_known = which == 0;
      options.tool_known = which == 1;
      EXPECT_EQ(calibrate(truth, &dataset, options, &workspace, &result), Status::invalid_argument)
          << calibration_method_name(method);
      EXPECT_EQ(result.step, CalibrationStep::input);
    }
  }
}

}  // namespace
}  // namespace hivecal::calibration_known_frames_test
