// The 33-parameter full model: increments, residual Jacobian, streaming normal equations,
// loss and the histogram median.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hivecal/solve/normal_equations.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::normal_equations_test {
namespace {

TEST(FullModel, RotationFromVectorIsRodrigues) {
  Random random(301);
  for (int trial = 0; trial < 200; ++trial) {
    const double scale = trial % 2 == 0 ? 1e-6 : 2.0;  // both the series and the trig branch
    const Vec3 v = scale * test::gaussian_vector(&random);
    Mat3 r;
    EXPECT_NO_HEAP(r = rotation_from_vector(v));
    EXPECT_LT((r * r.transpose() - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-14);
    EXPECT_LT((r * v - v).norm(), 1e-14 * (1.0 + v.norm()));  // the axis is fixed
    const double angle = v.norm();
    const Mat3 reference = Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
    EXPECT_LT((r - reference).norm(), 1e-14);
  }
  Mat3 identity;
  EXPECT_NO_HEAP(identity = rotation_from_vector(Vec3::Zero()));
  EXPECT_EQ(identity, Mat3::Identity());
}

TEST(FullModel, ZeroIncrementChangesNoBit) {
  Random random(302);
  RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  RigidTransform base = test::example_base_to_tracker();
  const RobotModel model_before = model;
  const RigidTransform base_before = base;
  EXPECT_NO_HEAP(apply_full_increment(FullParams::Zero(), &model, &base));
  EXPECT_EQ(to_params(model), to_params(model_before));
  EXPECT_EQ(base.rotation, base_before.rotation);
  EXPECT_EQ(base.translation_m, base_before.translation_m);
}

// Property test: the analytic 3x33 Jacobian equals central differences taken through
// apply_full_increment (so the base columns check the local-increment convention too).
TEST(FullModel, ResidualJacobianMatchesCentralDifferences) {
  Random random(303);
  for (int trial = 0; trial < 100; ++trial) {
    RobotModel model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 5e-3, 5e-3);
    model.tool_m << random.uniform(-0.05, 0.05), random.uniform(-0.05, 0.05), random.uniform(0.0, 0.2);
    RigidTransform base = test::example_base_to_tracker();
    Mat3 turn;
    EXPECT_NO_HEAP(turn = rotation_from_vector(test::gaussian_vector(&random)));
    base.rotation = base.rotation * turn;
    const Sample sample{test::random_joints(&random), test::gaussian_vector(&random)};
    FullJacobian jacobian;
    Vec3 residual;
    EXPECT_NO_HEAP(residual = full_residual_jacobian(model, base, sample, &jacobian));
    EXPECT_LT((residual - (base.apply(fk_tool_point(model, sample.q_rad)) - sample.point_m)).norm(), 1e-14);
    for (int k = 0; k < kFullParamCount; ++k) {
      const double h = 1e-6;
      FullParams step = FullParams::Zero();
      step(k) = h;
      RobotModel plus_model = model;
      RobotModel minus_model = model;
      RigidTransform plus_base = base;
      RigidTransform minus_base = base;
      EXPECT_NO_HEAP(apply_full_increment(step, &plus_model, &plus_base));
      EXPECT_NO_HEAP(apply_full_increment(-step, &minus_model, &minus_base));
      const Vec3 numeric = (plus_base.apply(fk_tool_point(plus_model, sample.q_rad)) -
                            minus_base.apply(fk_tool_point(minus_model, sample.q_rad))) /
                           (2.0 * h);
      EXPECT_LT((numeric - jacobian.col(k)).norm(), 1e-8) << full_param_name(k, kSixJoints) << " trial " << trial;
    }
  }
}

TEST(FullModel, StreamingNormalEquationsEqualTheStackedProducts) {
  Random random(304);
  const RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<20> dataset;
  dataset.clear();
  test::fill_dataset(test::perturbed_model(model, &random, 1e-3, 1e-3), base, 20, 0.0, &random, &dataset);
  const PointLoss huber{2e-3};
  static NormalEquations eq;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = accumulate_normal_equations(model, base, dataset.samples(), huber, &eq));
  ASSERT_EQ(status, Status::ok);
  static NormalMatrix expected_jtwj;
  expected_jtwj.setZero();
  FullParams expected_jtwr = FullParams::Zero();
  double loss_sum = 0.0;
  double squares = 0.0;
  int downweighted = 0;
  for (const Sample& sample : dataset.samples()) {
    FullJacobian j;
    Vec3 r;
    double w = 0.0;
    EXPECT_NO_HEAP(r = full_residual_jacobian(model, base, sample, &j));
    EXPECT_NO_HEAP(w = huber.weight(r.norm()));
    downweighted += w < 1.0;
    for (int a = 0; a < kFullParamCount; ++a) {
      expected_jtwr(a) += w * j.col(a).dot(r);
      for (int b = 0; b < kFullParamCount; ++b) expected_jtwj(a, b) += w * j.col(a).dot(j.col(b));
    }
    loss_sum += huber.rho(r.norm());
    squares += r.squaredNorm();
  }
  EXPECT_GT(downweighted, 0);
  EXPECT_LT(downweighted, 20);
  EXPECT_LT((eq.jtwj - expected_jtwj).cwiseAbs().maxCoeff(), 1e-12 * expected_jtwj.cwiseAbs().maxCoeff());
  EXPECT_LT((eq.jtwr - expected_jtwr).cwiseAbs().maxCoeff(), 1e-12 * expected_jtwr.cwiseAbs().maxCoeff());
  EXPECT_EQ(eq.jtwj, eq.jtwj.transpose());
  EXPECT_NEAR(eq.loss_sum_m2, loss_sum, 1e-15);
  EXPECT_NEAR(eq.squares_sum_m2, squares, 1e-15);
  EXPECT_EQ(eq.count, 20u);
  // The cheap trial evaluation (fk_tool_point) agrees to rounding.
  double trial_loss = 0.0;
  double trial_squares = 0.0;
  EXPECT_NO_HEAP(status = evaluate_point_loss(model, base, dataset.samples(), huber, &trial_loss, &trial_squares));
  ASSERT_EQ(status, Status::ok);
  EXPECT_NEAR(trial_loss, eq.loss_sum_m2, 1e-13 * trial_loss);
  EXPECT_NEAR(trial_squares, eq.squares_sum_m2, 1e-13 * trial_squares);
}

TEST(FullModel, HuberLossIsContinuousWithBoundedInfluence) {
  const PointLoss squares{};
  const PointLoss huber{1e-3};
  double v[9] = {};
  EXPECT_NO_HEAP(v[0] = squares.rho(2.0); v[1] = squares.weight(2.0); v[2] = huber.rho(1e-3);
                 v[3] = huber.rho(1e-3 * (1.0 + 1e-12)); v[4] = huber.rho(3e-3); v[5] = huber.weight(5e-4);
                 v[6] = huber.weight(4e-3); v[7] = huber.weight(10.0));
  EXPECT_EQ(v[0], 4.0);
  EXPECT_EQ(v[1], 1.0);
  EXPECT_DOUBLE_EQ(v[2], 1e-6);
  EXPECT_DOUBLE_EQ(v[3], 1e-6 * (1.0 + 2e-12));
  EXPECT_DOUBLE_EQ(v[4], 2.0 * 1e-3 * 3e-3 - 1e-6);
  EXPECT_EQ(v[5], 1.0);
  EXPECT_DOUBLE_EQ(v[6], 0.25);
  EXPECT_DOUBLE_EQ(2.0 * v[7] * 10.0, 2.0 * 1e-3);  // rho' stays 2k
}

TEST(FullModel, HistogramMedianIsWithinOnePercent) {
  Random random(305);
  for (double noise_m : {1e-6, 1e-5, 3e-3}) {
    static Dataset<301> dataset;
    dataset.clear();
    const RobotModel model = nominal_model(RobotType::ur5);
    const RigidTransform base = test::example_base_to_tracker();
    test::fill_dataset(model, base, 301, noise_m, &random, &dataset);
    double norms[301];
    for (std::size_t i = 0; i < dataset.size(); ++i) {
      norms[i] = (base.apply(fk_tool_point(model, dataset.samples()[i].q_rad)) - dataset.samples()[i].point_m).norm();
    }
    std::nth_element(norms, norms + 150, norms + 301);
    double median = 0.0;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = median_residual_norm(model, base, dataset.samples(), &median));
    ASSERT_EQ(status, Status::ok);
    EXPECT_NEAR(median, norms[150], 0.01 * norms[150]) << noise_m;
    EXPECT_NEAR(median, 1.538 * noise_m, 0.15 * 1.538 * noise_m);  // chi(3) median
  }
  double median = 0.0;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = median_residual_norm(nominal_model(RobotType::ur5), RigidTransform{}, {}, &median));
  EXPECT_EQ(status, Status::dataset_empty);
}

// The LM's steps scale only the kept block (scale_kept_block): its entries and the scale are
// scale_normal_matrix's to the bit, and every other entry is left as it was.
TEST(FullModel, ScalingTheKeptBlockWritesItAndNothingElse) {
  Random random(90);
  NormalMatrix jtwj = NormalMatrix::Zero();
  for (int b = 0; b < kFullParamCount; ++b) {
    for (int a = 0; a <= b; ++a) jtwj(a, b) = jtwj(b, a) = random.uniform(-1.0, 1.0);
    jtwj(b, b) = 2.0 + random.uniform(0.0, 100.0);
  }
  ParamMask mask = 0;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (random.uniform(0.0, 1.0) < 0.6) mask |= param_bit(i);
  }
  NormalMatrix full;
  FullParams full_scale;
  scale_normal_matrix(jtwj, mask, -1.0, &full, &full_scale);
  const double sentinel = 123.25;
  NormalMatrix block = NormalMatrix::Constant(sentinel);
  FullParams block_scale = FullParams::Constant(sentinel);
  EXPECT_NO_HEAP(scale_kept_block(jtwj, mask, &block, &block_scale));
  for (int b = 0; b < kFullParamCount; ++b) {
    EXPECT_EQ(block_scale(b), full_scale(b)) << b;
    for (int a = 0; a < kFullParamCount; ++a) {
      const bool kept = mask_has(mask, a) && mask_has(mask, b);
      EXPECT_EQ(block(a, b), kept ? full(a, b) : sentinel) << a << ", " << b;
    }
  }
}

}  // namespace
}  // namespace hivecal::normal_equations_test
