// Registration without recalibration (hivecal/registration.hpp): a calibrated arm with joint
// terms carried to a moved tracker from 3 points up, the rest of the model untouched; the
// frames fit's tool points; a weak registration named (nearly collinear, small spread); a
// blunder among the registration's poses set aside; and the calibration's covariance carried
// through the registration: its gain against registrations of slightly moved models.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/core/random.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/registration.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/target_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::registration_test {
namespace {

RegistrationWorkspace workspace;
RegistrationResult result;
RegistrationResult moved_result;
Dataset<128> dataset;
NormalMatrix carried;
NormalMatrix unit_variance;

/// A calibrated UR10 with gravity compliance and first-order harmonics (coefficients of a real
/// arm's size), and a tool point off the flange axis.
RobotModel calibrated_arm(Random* random) {
  RobotModel model = test::perturbed_parallel_model(RobotType::ur10, random, 1e-3, 1e-3, Vec3(0.01, -0.02, 0.11));
  EXPECT_EQ(default_compliance_terms(model, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &model.compliance),
            Status::ok);
  EXPECT_EQ(append_harmonic_terms(1, model, &model.compliance), Status::ok);
  for (int t = 0; t < model.compliance.term_count; ++t) model.compliance.coefficient[t] = 3e-5 * random->normal();
  return model;
}

/// A tracker set up anew: another yaw, height and distance than test::example_base_to_tracker().
RigidTransform moved_tracker() {
  RigidTransform base = test::example_base_to_tracker();
  base.rotation = rotation_from_vector(Vec3(0.02, -0.01, 1.9)) * base.rotation;
  base.translation_m += Vec3(-1.3, 2.2, 0.35);
  return base;
}

/// Samples of `model` at `count` random poses seen from `base` with noise.
void fill(const RobotModel& model, const RigidTransform& base, std::size_t count, double noise_m, Random* random) {
  dataset.clear();
  test::fill_dataset(model, base, count, noise_m, random, &dataset);
}

Span<Sample> all_samples() {  // the dataset's samples, for the registration to reorder
  return Span<Sample>(const_cast<Sample*>(dataset.samples().data()), dataset.size());
}

TEST(Registration, ThreePointsCarryACalibrationWithItsTermsToAMovedTracker) {
  Random random(5);
  const RobotModel arm = calibrated_arm(&random);
  const RigidTransform truth = moved_tracker();
  fill(arm, truth, 3, 0.0, &random);
  RegistrationOptions options;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = register_frames(arm, all_samples(), options, &workspace, &result));
  ASSERT_EQ(status, Status::ok);
  EXPECT_LT((result.base_to_tracker.translation_m - truth.translation_m).norm(), 1e-9);
  EXPECT_LT((result.base_to_tracker.rotation - truth.rotation).norm(), 1e-9);
  EXPECT_EQ(to_params(result.model), to_params(arm));  // the arm, tool and terms as calibrated
  for (int t = 0; t < arm.compliance.term_count; ++t)
    EXPECT_EQ(result.model.compliance.coefficient[t], arm.compliance.coefficient[t]);
  EXPECT_EQ(result.fitted_poses, 3u);
  EXPECT_EQ(result.residual_dof, 3);
  EXPECT_TRUE(result.weakness & kRegistrationFewResiduals);
  EXPECT_EQ(result.fit, RegistrationFit::base);
  // The terms are applied: the same arm registered without them misses the points.
  RobotModel rigid = arm;
  rigid.compliance = ComplianceModel{};
  fill(arm, truth, 12, 0.0, &random);
  ASSERT_EQ(register_frames(rigid, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_GT(result.rms_m, 1e-5);
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_LT(result.rms_m, 1e-9);
}

TEST(Registration, TheFramesFitAlsoFindsAReflectorSetAnew) {
  Random random(6);
  const RobotModel arm = calibrated_arm(&random);
  RobotModel remounted = arm;
  remounted.tool_m += Vec3(0.004, -0.003, 0.006);
  const RigidTransform truth = moved_tracker();
  fill(remounted, truth, 25, 10e-6, &random);
  RegistrationOptions options;
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_GT(result.rms_m, 1e-3);  // the base alone cannot take a tool moved by 8 mm
  fill(remounted, truth, 25, 10e-6, &random);
  options.fit = RegistrationFit::frames;
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_LT((result.model.tool_m - remounted.tool_m).norm(), 1e-4);
  EXPECT_LT((result.base_to_tracker.translation_m - truth.translation_m).norm(), 2e-4);
  EXPECT_LT(result.rms_m, 3e-5);
  EXPECT_GT(result.tool_sigma_m.minCoeff(), 0.0);
  EXPECT_EQ(result.verdict, RegistrationBlunderVerdict::none);
  ModelParams arm_without_tool = to_params(arm);
  ModelParams result_without_tool = to_params(result.model);
  arm_without_tool.segment<3>(tool_param_index(arm, 0)).setZero();
  result_without_tool.segment<3>(tool_param_index(arm, 0)).setZero();
  EXPECT_EQ(arm_without_tool, result_without_tool);  // DH untouched
}

TEST(Registration, ItsSigmasFollowTheNoiseAndItsWeaknessIsNamed) {
  Random random(7);
  const RobotModel arm = calibrated_arm(&random);
  const RigidTransform truth = moved_tracker();
  fill(arm, truth, 20, 10e-6, &random);
  RegistrationOptions options;
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_EQ(result.weakness, 0u);
  EXPECT_GT(result.residual_sigma_m, 6e-6);
  EXPECT_LT(result.residual_sigma_m, 14e-6);
  EXPECT_GT(result.translation_sigma_m.minCoeff(), 1e-6);  // a few um at the base origin
  EXPECT_LT(result.translation_sigma_m.maxCoeff(), 3e-5);
  EXPECT_LT(result.rotation_sigma_rad.maxCoeff(), 3e-5);
  EXPECT_GT(result.point_sigma_m, 1e-6);
  EXPECT_LT(result.point_sigma_m, 10e-6);  // about sigma sqrt(6 / (3 N)) at the points
  EXPECT_GT(result.condition, 1.0);
  EXPECT_LT((result.base_to_tracker.translation_m - truth.translation_m).norm(), 1e-4);
  // Joint 2 moved by a few hundredths of a radian only: an arc of ~3 cm, nearly a line.
  dataset.clear();
  for (int k = 0; k < 6; ++k) {
    JointVector q;
    q << 0.4, -1.2 + 0.006 * k, 1.0 + 0.0003 * k * k, -1.5, -1.4, 0.3;
    ASSERT_EQ(dataset.add(q, truth.apply(fk_tool_point(arm, q)) + 1e-5 * test::gaussian_vector(&random)), Status::ok);
  }
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_TRUE(result.weakness & kRegistrationSmallSpread);
  EXPECT_TRUE(result.weakness & kRegistrationNearlyCollinear) << result.collinearity;
  EXPECT_GT(result.rotation_sigma_rad.maxCoeff(), 1e-3);
}

TEST(Registration, RefusesWhatCannotPlaceTheBase) {
  Random random(9);
  const RobotModel arm = calibrated_arm(&random);
  fill(arm, moved_tracker(), 2, 0.0, &random);
  RegistrationOptions options;
  EXPECT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::too_few_samples);
  // Joint 6 alone turning a tool on its axis (the nominal arm: a6 = alpha6 = 0): one point.
  RobotModel on_axis = nominal_model(RobotType::ur10);
  on_axis.tool_m = Vec3(0.0, 0.0, 0.1);
  dataset.clear();
  for (int k = 0; k < 4; ++k) {
    JointVector q;
    q << 0.0, -1.2, 1.0, -1.5, -1.4, 0.5 * k;
    ASSERT_EQ(dataset.add(q, moved_tracker().apply(fk_tool_point(on_axis, q))), Status::ok);
  }
  EXPECT_EQ(register_frames(on_axis, all_samples(), options, &workspace, &result), Status::degenerate_geometry);
  EXPECT_EQ(register_frames(arm, Span<Sample>(), options, &workspace, &result), Status::dataset_empty);
}

TEST(Registration, ABlunderAmongItsPosesIsSetAsideAndNamed) {
  Random random(11);
  const RobotModel arm = calibrated_arm(&random);
  const RigidTransform truth = moved_tracker();
  fill(arm, truth, 30, 10e-6, &random);
  Span<Sample> samples = all_samples();
  samples[7].point_m += Vec3(0.0, 0.002, 0.0);
  RegistrationOptions options;
  ASSERT_EQ(register_frames(arm, samples, options, &workspace, &result), Status::ok);
  EXPECT_EQ(result.verdict, RegistrationBlunderVerdict::set_aside);
  ASSERT_EQ(result.blunder_count, 1u);
  EXPECT_EQ(result.blunders[0].index, 7u);
  EXPECT_GT(result.blunders[0].w, result.blunders[0].critical_w);
  EXPECT_EQ(result.fitted_samples, 29u);
  EXPECT_EQ(samples[29].index, 7u);  // behind the fitted ones
  EXPECT_LT(result.rms_m, 3e-5);
  options.find_blunders = false;
  fill(arm, truth, 30, 10e-6, &random);
  all_samples()[7].point_m += Vec3(0.0, 0.002, 0.0);
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  EXPECT_EQ(result.fitted_samples, 30u);
  EXPECT_EQ(result.verdict, RegistrationBlunderVerdict::not_tested);
}

/// The base increment (rotation vector, translation; full_params.hpp's convention) that takes
/// `from` to `to`, for small moves [rad], [m].
Eigen::Matrix<double, 6, 1> base_increment(const RigidTransform& from, const RigidTransform& to) {
  const Mat3 r = from.rotation.transpose() * to.rotation;
  Eigen::Matrix<double, 6, 1> d;
  d << 0.5 * (r(2, 1) - r(1, 2)), 0.5 * (r(0, 2) - r(2, 0)), 0.5 * (r(1, 0) - r(0, 1)),
      from.rotation.transpose() * (to.translation_m - from.translation_m);
  return d;
}

TEST(Registration, TheCalibrationsCovarianceIsCarriedByTheRegistrationsGain) {
  Random random(13);
  const RobotModel arm = calibrated_arm(&random);
  const RigidTransform truth = moved_tracker();
  fill(arm, truth, 20, 0.0, &random);
  RegistrationOptions options;
  options.find_blunders = false;
  ASSERT_EQ(register_frames(arm, all_samples(), options, &workspace, &result), Status::ok);
  // Unit variance on one arm parameter at a time: the carried covariance's base rows are then
  // the registration's gain G, the base's move per unit move of that parameter.
  for (const int k : {0, 4, 7, 13}) {  // theta1, d2, a2, alpha4
    unit_variance.setZero();
    unit_variance(k, k) = 1.0;
    ParamMask estimated = 0;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = carry_covariance(result, dataset.samples(), param_bit(k), unit_variance,
                                             &workspace.covariance, &carried, &estimated));
    ASSERT_EQ(status, Status::ok);
    EXPECT_EQ(estimated, param_bit(k) | registration_mask(RegistrationFit::base, arm));
    EXPECT_EQ(carried(k, k), 1.0);
    constexpr double kStep = 1e-6;
    ModelParams p = to_params(arm);
    p(k) += kStep;
    RobotModel moved = arm;
    set_model_params(p, &moved);
    ASSERT_EQ(register_frames(moved, all_samples(), options, &workspace, &moved_result), Status::ok);
    const Eigen::Matrix<double, 6, 1> d = base_increment(result.base_to_tracker, moved_result.base_to_tracker);
    for (int b = 0; b < kBaseParamCount; ++b) {
      EXPECT_NEAR(carried(model_param_count(kSixJoints) + b, k) * kStep, d(b), 1e-3 * kStep)
          << full_param_name(k, kSixJoints) << " " << b;
    }
  }
  // theta1 is taken by base_rz whole: it no longer moves a prediction; d2 still does.
  for (const int k : {0, 4}) {
    unit_variance.setZero();
    unit_variance(k, k) = 1e-6;
    ParamMask estimated = 0;
    ASSERT_EQ(carry_covariance(result, dataset.samples(), param_bit(k), unit_variance, &workspace.covariance, &carried,
                               &estimated),
              Status::ok);
    // The registration's own noise is zero here (a noise-free fit): only the carried part counts.
    JointVector q;
    q << 1.0, -1.0, 1.2, -1.6, -1.2, 0.4;
    const double sigma = prediction_sigma_m(arm, result.base_to_tracker, q, 0, carried, estimated);
    if (k == 0) {
      EXPECT_LT(sigma, 1e-8);
    } else {
      EXPECT_GT(sigma, 1e-4);
    }
  }
}

}  // namespace
}  // namespace hivecal::registration_test
