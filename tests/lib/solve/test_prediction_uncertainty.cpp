// Prediction sigma, the calibration's domain and extrapolation (solve/prediction_uncertainty.hpp):
// the sigma against J C J^T built from full_residual_jacobian, a translation's variance seen
// whole in the tracker frame and not at all in the base frame, the other targets' tool sigma,
// the domain's ranges, spread and typical sigma against direct sums, and the two reasons for
// an extrapolation.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/core/random.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::prediction_uncertainty_test {
namespace {

NormalMatrix covariance;
Dataset<64> dataset;

/// A random symmetric positive semi-definite covariance over `mask` (0 elsewhere) [m^2 ...].
void random_covariance(ParamMask mask, Random* random) {
  NormalMatrix a = NormalMatrix::Zero();
  for (int i = 0; i < kFullParamCount; ++i)
    for (int j = 0; j < kFullParamCount; ++j)
      if (mask_has(mask, i)) a(i, j) = 1e-4 * random->normal();
  covariance = a * a.transpose();
}

TEST(PredictionSigma, IsTheRootOfTheMeanAxisVarianceOfJCJt) {
  Random random(3);
  const RobotModel model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  const RigidTransform base = test::example_base_to_tracker();
  const ParamMask mask = rigid_params_mask(kSixJoints) & ~param_bit(3);  // one left out: its column must not count
  random_covariance(mask, &random);
  for (int k = 0; k < 5; ++k) {
    Sample sample;
    sample.q_rad = test::random_joints(&random);
    FullJacobian jacobian;
    (void)full_residual_jacobian(model, base, sample, &jacobian);
    jacobian.col(3).setZero();
    const double expected = std::sqrt((jacobian * covariance * jacobian.transpose()).trace() / 3.0);
    double sigma = 0.0;
    EXPECT_NO_HEAP(sigma = prediction_sigma_m(model, base, sample.q_rad, 0, covariance, mask));
    EXPECT_NEAR(sigma, expected, 1e-12 * expected);
  }
}

TEST(PredictionSigma, TheBaseCountsInTheTrackerFrameOnly) {
  const RobotModel model = nominal_model(RobotType::ur5);
  covariance.setZero();
  const int tx = base_translation_param_index(kSixJoints, 0);
  covariance(tx, tx) = 9e-8;  // 0.3 mm along the base's x
  JointVector q;
  q << 0.3, -1.2, 1.1, -1.4, -1.5, 0.2;
  EXPECT_NEAR(prediction_sigma_m(model, test::example_base_to_tracker(), q, 0, covariance, param_bit(tx)),
              3e-4 / std::sqrt(3.0), 1e-15);
  EXPECT_EQ(prediction_sigma_m(model, test::example_base_to_tracker(), q, 0, covariance, param_bit(tx),
                               PredictionFrame::base),
            0.0);
}

TEST(PredictionSigma, AnotherTargetTakesItsOwnToolSigmaNotTargetOnes) {
  RobotModel model = nominal_model(RobotType::ur5);
  model.other_tools_m[0] = Vec3(0.05, 0.0, 0.1);
  covariance.setZero();
  const int tool_x = tool_param_index(kSixJoints, 0);
  covariance(tool_x, tool_x) = 1e-6;
  JointVector q;
  q << 0.3, -1.2, 1.1, -1.4, -1.5, 0.2;
  const RigidTransform base = test::example_base_to_tracker();
  EXPECT_NEAR(prediction_sigma_m(model, base, q, 0, covariance, param_bit(tool_x)), 1e-3 / std::sqrt(3.0), 1e-15);
  EXPECT_EQ(prediction_sigma_m(model, base, q, 1, covariance, param_bit(tool_x)), 0.0);
  EXPECT_NEAR(prediction_sigma_m(model, base, q, 1, covariance, param_bit(tool_x), PredictionFrame::tracker,
                                 Vec3(3e-4, 0.0, 4e-4)),
              5e-4 / std::sqrt(3.0), 1e-15);
}

TEST(CalibrationDomain, RangesSpreadAndTypicalSigmaOfThePoses) {
  Random random(8);
  const RobotModel model = nominal_model(RobotType::ur5);
  const RigidTransform base = test::example_base_to_tracker();
  dataset.clear();
  test::fill_dataset(model, base, 40, 0.0, &random, &dataset);
  random_covariance(rigid_params_mask(kSixJoints), &random);
  const Vec3 no_tools[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  CalibrationDomain domain;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibration_domain(model, base, dataset.samples(), covariance, rigid_params_mask(kSixJoints),
                                             no_tools, &domain));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(domain.poses, 40u);
  JointVector low = dataset.samples()[0].q_rad;
  JointVector high = low;
  Vec3 axis_sum = Vec3::Zero();
  double squares = 0.0;
  double largest = 0.0;
  for (const Sample& s : dataset.samples()) {
    low = low.cwiseMin(s.q_rad);
    high = high.cwiseMax(s.q_rad);
    axis_sum += fk_flange(model, s.q_rad).rotation.col(2);
    const double sigma = prediction_sigma_m(model, base, s.q_rad, 0, covariance, rigid_params_mask(kSixJoints));
    squares += sigma * sigma;
    largest = std::fmax(largest, sigma);
  }
  EXPECT_EQ(domain.joint_min_rad, low);
  EXPECT_EQ(domain.joint_max_rad, high);
  EXPECT_NEAR(domain.typical_sigma_m, std::sqrt(squares / 40.0), 1e-12 * domain.typical_sigma_m);
  EXPECT_EQ(domain.max_sigma_m, largest);
  double spread = 0.0;
  for (const Sample& s : dataset.samples()) {
    const Vec3 axis = fk_flange(model, s.q_rad).rotation.col(2);
    spread = std::fmax(spread, std::acos(std::fmin(1.0, axis.dot(axis_sum.normalized()))));
  }
  EXPECT_NEAR(domain.tool_axis_spread_rad, spread, 1e-6);
  EXPECT_GT(domain.tool_axis_spread_rad, domain.tool_axis_rms_rad);
  EXPECT_EQ(calibration_domain(model, base, Span<const Sample>(), covariance, rigid_params_mask(kSixJoints), no_tools,
                               &domain),
            Status::dataset_empty);
}

TEST(CalibrationDomain, ALargeSetsSigmasAreThoseOfEvenlySpacedPoses) {
  static Dataset<3000> large;
  Random random(9);
  const RobotModel model = nominal_model(RobotType::ur10);
  const RigidTransform base = test::example_base_to_tracker();
  large.clear();
  test::fill_dataset(model, base, 3000, 0.0, &random, &large);
  random_covariance(rigid_params_mask(kSixJoints), &random);
  const Vec3 no_tools[kMaxTargets - 1] = {Vec3::Zero(), Vec3::Zero()};
  CalibrationDomain domain;
  ASSERT_EQ(
      calibration_domain(model, base, large.samples(), covariance, rigid_params_mask(kSixJoints), no_tools, &domain),
      Status::ok);
  EXPECT_EQ(domain.poses, 3000u);
  double squares = 0.0;
  for (const Sample& s : large.samples()) {
    const double sigma = prediction_sigma_m(model, base, s.q_rad, 0, covariance, rigid_params_mask(kSixJoints));
    squares += sigma * sigma;
  }
  EXPECT_NEAR(domain.typical_sigma_m, std::sqrt(squares / 3000.0), 0.03 * domain.typical_sigma_m);
  EXPECT_NE(domain.typical_sigma_m, std::sqrt(squares / 3000.0));  // a subset: not every pose
}

TEST(Extrapolation, ASigmaBeyondItsMultipleOrATermJointBeyondItsMargin) {
  const RobotModel model = nominal_model(RobotType::ur5);
  CalibrationDomain domain;
  domain.joint_min_rad.setConstant(-1.0);
  domain.joint_max_rad.setConstant(1.0);
  domain.typical_sigma_m = 1e-5;
  domain.term_joints = 0x3F;
  JointVector q = JointVector::Zero();
  EXPECT_FALSE(extrapolation(domain, model, q, 2.9e-5).extrapolated());
  EXPECT_TRUE(extrapolation(domain, model, q, 3.1e-5).sigma_beyond);
  q(2) = 1.0 + 0.9 * kExtrapolationJointMargin_rad;
  EXPECT_FALSE(extrapolation(domain, model, q, 1e-5).extrapolated());
  q(4) = -1.0 - 1.5 * kExtrapolationJointMargin_rad;
  q(2) = 1.0 + 1.1 * kExtrapolationJointMargin_rad;
  Extrapolation e = extrapolation(domain, model, q, 1e-5);
  EXPECT_TRUE(e.extrapolated());
  EXPECT_FALSE(e.sigma_beyond);
  EXPECT_EQ(e.joint, 4);  // the furthest beyond
  EXPECT_NEAR(e.joint_beyond_rad, 1.5 * kExtrapolationJointMargin_rad, 1e-15);
  domain.term_joints = 1U << 2;  // only joint 3 has terms: joint 5 beyond its range does not count
  e = extrapolation(domain, model, q, 1e-5);
  EXPECT_EQ(e.joint, 2);
  domain.term_joints = 0;  // a rigid chain holds at any reading
  EXPECT_FALSE(extrapolation(domain, model, q, 1e-5).extrapolated());
  domain.typical_sigma_m = 0.0;  // no covariance: no sigma test
  EXPECT_FALSE(extrapolation(domain, model, JointVector::Zero(), 1.0).extrapolated());
}

TEST(Extrapolation, AToolAxisBeyondTheTrainingSpread) {
  const RobotModel model = nominal_model(RobotType::ur5);
  JointVector q;
  q << 0.3, -1.2, 1.1, -1.4, -1.5, 0.2;
  CalibrationDomain domain;
  domain.joint_min_rad.setConstant(-3.0);
  domain.joint_max_rad.setConstant(3.0);
  domain.tool_axis_mean = fk_flange(model, q).rotation.col(2);
  domain.tool_axis_spread_rad = 0.1;
  JointVector tilted = q;
  tilted(4) += 0.1 + 0.9 * kExtrapolationToolAxisMargin_rad;  // wrist 2 tilts the axis by as much
  Extrapolation e = extrapolation(domain, model, tilted, 0.0);
  EXPECT_FALSE(e.extrapolated());
  EXPECT_NEAR(e.tool_axis_angle_rad, 0.1 + 0.9 * kExtrapolationToolAxisMargin_rad, 1e-9);
  tilted(4) = q(4) + 0.1 + 1.1 * kExtrapolationToolAxisMargin_rad;
  e = extrapolation(domain, model, tilted, 0.0);
  EXPECT_TRUE(e.tool_axis_beyond);
  EXPECT_TRUE(e.extrapolated());
  JointVector turned = q;
  turned(5) += 2.0;  // wrist 3 turns about the axis: not a new direction
  EXPECT_FALSE(extrapolation(domain, model, turned, 0.0).extrapolated());
}

TEST(TermJointMask, TheJointsTheTermsDependOn) {
  Random random(4);
  RobotModel model = nominal_model(RobotType::ur5);
  model.tool_m = Vec3(0.0, 0.0, 0.1);
  dataset.clear();
  test::fill_dataset(model, test::example_base_to_tracker(), 20, 0.0, &random, &dataset);
  EXPECT_EQ(term_joint_mask(model, dataset.samples()), 0u);  // rigid
  ASSERT_EQ(default_compliance_terms(model, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &model.compliance),
            Status::ok);
  ASSERT_EQ(append_harmonic_terms(1, model, &model.compliance), Status::ok);
  EXPECT_EQ(term_joint_mask(model, dataset.samples()), 0u);  // every coefficient 0
  for (int t = 0; t < model.compliance.term_count; ++t) {
    const ComplianceTerm& term = model.compliance.terms[t];
    if (is_harmonic(term) && term.joint == 0) model.compliance.coefficient[t] = 1e-5;  // joint 1's harmonic
  }
  EXPECT_EQ(term_joint_mask(model, dataset.samples()), 1u);
  for (int t = 0; t < model.compliance.term_count; ++t)
    if (!is_harmonic(model.compliance.terms[t])) model.compliance.coefficient[t] = 1e-5;
  unsigned mask = 0;
  EXPECT_NO_HEAP(mask = term_joint_mask(model, dataset.samples()));
  // Gravity along joint 1's axis: turning it changes no torque; the shoulder and elbow do.
  EXPECT_EQ(mask & 1u, 1u);  // from the harmonic
  EXPECT_NE(mask & 2u, 0u);
  EXPECT_NE(mask & 4u, 0u);
  model.compliance.coefficient[0] = 0.0;
  for (int t = 0; t < model.compliance.term_count; ++t)
    if (is_harmonic(model.compliance.terms[t])) model.compliance.coefficient[t] = 0.0;
  EXPECT_EQ(term_joint_mask(model, dataset.samples()) & 1u, 0u);
}

}  // namespace
}  // namespace hivecal::prediction_uncertainty_test
