// The calibration job with a known base and tool (CalibrationOptions::base_known,
// tool_known): a controller's own TCP readings (a pendant export, RTDE actual_TCP_pose) are
// FK(q) * its configured TCP offset in the robot's base frame, so neither is estimated, and
// joint 1's parameters, which a fitted base absorbs, become estimable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/kinematics.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/quick_job.hpp"
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

/// A perturbed UR5 (seeded) read as a controller reports its TCP: base = identity, a plate of
/// three points at kTool_m known exactly; 30 poses with `noise_m` into `dataset`, 20
/// noise-free ones into `fresh`. *start: the nominal UR5 with those tool points. Returns the truth.
RobotModel controller_session(std::uint64_t seed, double noise_m, RobotModel* start) {
  Random random(seed);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
  dataset.clear();
  fresh.clear();
  test::fill_target_dataset(truth, RigidTransform(), 30, 3, noise_m, &random, &dataset);
  test::fill_target_dataset(truth, RigidTransform(), 20, 3, 0.0, &random, &fresh);
  *start = nominal_model(RobotType::ur5);
  for (int t = 0; t < kMaxTargets; ++t) target_tool(start, t) = target_tool(truth, t);
  return truth;
}

// A perturbed UR5 read as a controller reports its TCP (base = identity, the TCP offset and
// two more points of the tool frame known exactly), 30 poses with 10 um noise. With both
// known the job keeps them bit for bit, estimates theta1 and d1 (a fitted base makes them
// unidentifiable) and predicts fresh poses within a few noise sigmas.
TEST(CalibrationKnownFrames, ControllerReadingsEstimateJointOneAndKeepBaseAndTool) {
  const double noise_m = 1e-5;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    RobotModel start;
    const RobotModel truth = controller_session(seed, noise_m, &start);
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
    for (int i = 0; i < 6; ++i)
      EXPECT_FALSE(mask_has(kept, model_param_count(kSixJoints) + i)) << "base parameter " << i;
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

/// Whether the final stages of `a` and `b` hold the same geometry and base, bit for bit.
bool same_final_fit(const CalibrationResult& a, const CalibrationResult& b) {
  const CalibrationStage* x = a.final_stage();
  const CalibrationStage* y = b.final_stage();
  return x != nullptr && y != nullptr && to_params(x->model) == to_params(y->model) &&
         x->base_to_tracker.rotation == y->base_to_tracker.rotation &&
         x->base_to_tracker.translation_m == y->base_to_tracker.translation_m;
}

CalibrationResult reference;

/// The default job (ABC+LM, a short population stage; a 0.7 split) with the frames test, its
/// noise the readings'.
CalibrationOptions detecting(double noise_m) {
  CalibrationOptions options = test::quick_options(CalibrationMethod::abc_lm);
  options.detect_controller_frames = true;
  options.measurement_sigma_m = noise_m;
  return options;
}

/// `options` with the controller's frames given, as --controller-tcp.
CalibrationOptions known_frames(CalibrationOptions options) {
  options.detect_controller_frames = false;
  options.method = CalibrationMethod::lm;
  options.base_known = true;
  options.tool_known = true;
  return options;
}

// Controller readings (base = identity, the tool points known: the start model's) through the
// default job with the frames test: the fitted base falls within the gate, the fit with the
// frames known explains the data to the noise, and the result is bit for bit the job with
// them given (base_known, tool_known, LM), which predicts fresh poses within a few sigmas.
TEST(CalibrationControllerFrames, ControllerReadingsAreRecognisedAndFittedWithTheirFrames) {
  const double noise_m = 1e-5;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    RobotModel start;
    const RobotModel truth = controller_session(seed, noise_m, &start);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &dataset, detecting(noise_m), &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    const ControllerFramesTest& test = result.frames_test;
    std::printf("seed %d: residual sigma %.4f mm, noise %.4f mm, at most %.4f mm\n", static_cast<int>(seed),
                test.residual_sigma_m * 1e3, test.noise_sigma_m * 1e3, test.critical_sigma_m * 1e3);
    EXPECT_TRUE(test.tested) << seed;
    EXPECT_TRUE(test.adopted) << seed;
    EXPECT_EQ(test.status, Status::ok);
    EXPECT_EQ(test.noise_sigma_m, noise_m);
    EXPECT_LT(worst_error_m(truth, fresh.samples()), 5.0 * noise_m) << seed;
    ASSERT_EQ(calibrate(start, &dataset, known_frames(detecting(noise_m)), &workspace, &reference), Status::ok);
    EXPECT_TRUE(same_final_fit(result, reference)) << seed;
    EXPECT_FALSE(reference.frames_test.tested);
    const CalibrationOptions chosen = options_with_chosen_frames(detecting(noise_m), result);
    EXPECT_TRUE(chosen.base_known && chosen.tool_known && chosen.method == CalibrationMethod::lm);
    EXPECT_FALSE(chosen.detect_controller_frames);
  }
}

// Tracker points already in the robot's frame (a lab registered them) but with the tool point
// guessed a millimetre off, as a tracker's user gives it: the base is within the gate, the
// fit with the guessed tool fixed is far above the noise, and the job keeps the frames fitted,
// bit for bit the job without the test. A base registered through the nominal geometry (its
// error absorbed: 0.3 mm, 0.5 mrad) with the tool right fails the same way.
TEST(CalibrationControllerFrames, TrackerPointsInTheRobotFrameKeepTheirFramesFitted) {
  const double noise_m = 1e-5;
  for (int registered = 0; registered < 2; ++registered) {
    Random random(11 + static_cast<std::uint64_t>(registered));
    const RobotModel truth =
        test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m), kTool_m);
    RigidTransform frame;  // where the points are: the robot's base, or a registration close to it
    if (registered == 1) {
      frame.rotation = Eigen::AngleAxisd(5e-4, Vec3(0.6, 0.8, 0.0)).toRotationMatrix();
      frame.translation_m = Vec3(3e-4, -2e-4, 1e-4);
    }
    dataset.clear();
    test::fill_target_dataset(truth, frame, 30, 3, noise_m, &random, &dataset);
    RobotModel start = nominal_model(RobotType::ur5);
    for (int t = 0; t < kMaxTargets; ++t) target_tool(&start, t) = target_tool(truth, t);
    if (registered == 0) {
      for (int t = 0; t < kMaxTargets; ++t) target_tool(&start, t) += Vec3(1e-3, -1e-3, 0.5e-3);
    }
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start, &dataset, detecting(noise_m), &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_step_name(result.step);
    const ControllerFramesTest& test = result.frames_test;
    std::printf("%s: residual sigma %.4f mm against at most %.4f mm\n", registered ? "registered base" : "guessed tool",
                test.residual_sigma_m * 1e3, test.critical_sigma_m * 1e3);
    EXPECT_TRUE(test.tested) << registered;
    EXPECT_FALSE(test.adopted) << registered;
    EXPECT_GT(test.residual_sigma_m, 3.0 * test.critical_sigma_m) << registered;
    CalibrationOptions fitted = detecting(noise_m);
    fitted.detect_controller_frames = false;
    ASSERT_EQ(calibrate(start, &dataset, fitted, &workspace, &reference), Status::ok);
    EXPECT_TRUE(same_final_fit(result, reference)) << registered;
    EXPECT_FALSE(options_with_chosen_frames(detecting(noise_m), result).base_known);
  }
}

// A tracker's own frame, metres from the base, is never tested: one run, the same bits.
TEST(CalibrationControllerFrames, ATrackerFrameIsNotTested) {
  Random random(5);
  const RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, kTool_m);
  dataset.clear();
  test::fill_target_dataset(truth, test::example_base_to_tracker(), 30, 1, 1e-5, &random, &dataset);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = kTool_m;
  ASSERT_EQ(calibrate(start, &dataset, detecting(1e-5), &workspace, &result), Status::ok);
  EXPECT_FALSE(result.frames_test.tested);
  CalibrationOptions fitted = detecting(1e-5);
  fitted.detect_controller_frames = false;
  ASSERT_EQ(calibrate(start, &dataset, fitted, &workspace, &reference), Status::ok);
  EXPECT_TRUE(same_final_fit(result, reference));
}

// Cross-validation with the test: the folds keep the frames the whole job chose (here the
// controller's), fold for fold the cross-validation with them given.
TEST(CalibrationControllerFrames, CrossValidationFoldsKeepTheDetectedFrames) {
  const double noise_m = 1e-5;
  RobotModel start;
  (void)controller_session(3, noise_m, &start);
  static CrossValidationResult detected;
  static CrossValidationResult given;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = cross_validate(start, &dataset, detecting(noise_m), 5, &workspace, &result, &detected));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(cross_validate(start, &dataset, known_frames(detecting(noise_m)), 5, &workspace, &result, &given),
            Status::ok);
  ASSERT_EQ(detected.fold_count, given.fold_count);
  for (std::size_t f = 0; f < detected.fold_count; ++f) {
    EXPECT_EQ(detected.folds[f].test.mae(ErrorAxis::norm_3d), given.folds[f].test.mae(ErrorAxis::norm_3d)) << f;
  }
  EXPECT_EQ(detected.mae_3d_m, given.mae_3d_m);
}

}  // namespace
}  // namespace hivecal::calibration_known_frames_test
