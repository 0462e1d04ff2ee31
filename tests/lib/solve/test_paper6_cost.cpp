// The precomputed paper-6 cost against the generic evaluate_cost, its streaming build, its
// errors, and the fast (QCP) rotation it uses against the SVD one.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hivecal/core/trace.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/paper6_data.hpp"

namespace hivecal::paper6_cost_test {
namespace {

// The generic path itself rounds at ~1e-16 m per predicted point, i.e. a few 1e-12 of a
// 10-20 um MAE; both paths agree to that.
constexpr double kRelativeTolerance = 1e-11;

struct Paper6CostTest : ::testing::Test {
  static Dataset<256>& dataset() {
    static Dataset<256> d;
    return d;
  }
  static Paper6Cost<256>& cost() {
    static Paper6Cost<256> c;
    return c;
  }
  test::Paper6Cell cell;
  void SetUp() override {
    Random random(404);
    cell = test::paper6_cell(&random, test::Paper6Truth::six_lengths);
    dataset().clear();
    test::fill_tool_down(cell, 200, 1e-5, &random, &dataset());
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = cost().build(cell.nominal, dataset().samples()));
    ASSERT_EQ(s, Status::ok);
  }
};

TEST_F(Paper6CostTest, EqualsTheGenericRefitCostAnywhereInTheBox) {
  LinkLengthBox box;
  ASSERT_EQ(link_length_box(cell.nominal, kPaper6DefaultHalfWidth_m, &box), Status::ok);
  Random random(405);
  for (int trial = 0; trial < 60; ++trial) {
    LinkLengths lengths_m = link_lengths(cell.nominal);
    if (trial == 1) lengths_m = link_lengths(cell.truth);
    for (int k = 0; k < 6 && trial > 1; ++k) lengths_m.values_m(k) = random.uniform(box.lower_m[k], box.upper_m[k]);
    double fast_m = 0.0;
    RigidTransform fast_base;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = cost().evaluate(lengths_m, &fast_m, &fast_base));
    ASSERT_EQ(s, Status::ok);
    double generic_m = 0.0;
    RigidTransform generic_base;
    ASSERT_EQ(evaluate_cost(cost().model_for(lengths_m.data()), dataset().samples(), CostKind::mean_abs_3d,
                            BaseFrame::refit, &generic_base, &generic_m),
              Status::ok);
    EXPECT_NEAR(fast_m, generic_m, kRelativeTolerance * generic_m) << "trial " << trial;
    EXPECT_LT((fast_base.rotation - generic_base.rotation).norm(), 1e-13);
    EXPECT_LT((fast_base.translation_m - generic_base.translation_m).norm(), 1e-12);
    EXPECT_EQ(cost().evaluate(lengths_m.data()), fast_m);  // the Objective path is the same number
  }
}

TEST_F(Paper6CostTest, AtTheExpansionPointItIsTheNominalCost) {
  const LinkLengths nominal_m = link_lengths(cell.nominal);
  double generic_m = 0.0;
  RigidTransform base;
  ASSERT_EQ(
      evaluate_cost(cell.nominal, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::refit, &base, &generic_m),
      Status::ok);
  EXPECT_NEAR(cost().evaluate(nominal_m.data()), generic_m, kRelativeTolerance * generic_m);
  EXPECT_GT(generic_m, 1e-4);  // the perturbation is visible
}

TEST_F(Paper6CostTest, D1IsAbsorbedByTheBaseTranslation) {
  // d1 moves every predicted point along the base z axis: the refitted base takes it up.
  LinkLengths lengths_m = link_lengths(cell.truth);
  const double before_m = cost().evaluate(lengths_m.data());
  RigidTransform base_before;
  double ignored_m = 0.0;
  ASSERT_EQ(cost().evaluate(lengths_m, &ignored_m, &base_before), Status::ok);
  lengths_m.values_m(0) += 1.5e-3;
  RigidTransform base_after;
  ASSERT_EQ(cost().evaluate(lengths_m, &ignored_m, &base_after), Status::ok);
  EXPECT_EQ(cost().evaluate(lengths_m.data()), before_m);
  const Vec3 shift_m = base_before.translation_m - base_after.translation_m;
  EXPECT_LT((shift_m - base_before.rotation * Vec3(0.0, 0.0, 1.5e-3)).norm(), 1e-12);
}

TEST_F(Paper6CostTest, StreamingEqualsBuildBitForBit) {
  static Paper6Cost<256> streamed;
  Status s = Status::invalid_argument;
  EXPECT_NO_HEAP(s = streamed.reset(cell.nominal, cost().reference()));
  ASSERT_EQ(s, Status::ok);
  for (const Sample& sample : dataset().samples()) {
    EXPECT_NO_HEAP(s = streamed.add(sample.q_rad, sample.point_m));
    ASSERT_EQ(s, Status::ok);
    EXPECT_FALSE(streamed.ready());
  }
  EXPECT_NO_HEAP(s = streamed.finalize());
  ASSERT_EQ(s, Status::ok);
  EXPECT_TRUE(streamed.ready());
  EXPECT_EQ(streamed.size(), dataset().size());
  const LinkLengths lengths_m = link_lengths(cell.truth);
  EXPECT_EQ(streamed.evaluate(lengths_m.data()), cost().evaluate(lengths_m.data()));
}

// A selection holds just its samples: the cost equals the generic refit cost on a copy of
// them (the reference, fitted on every sample, does not change an exact cost).
TEST_F(Paper6CostTest, ASelectionCostsItsSamplesOnly) {
  static Paper6Cost<256> selected;
  static Dataset<256> copy;
  copy.clear();
  std::uint32_t positions[40] = {};
  for (std::uint32_t k = 0; k < 40; ++k) {
    positions[k] = 5 * k + 3;
    const Sample& sample = dataset().samples()[positions[k]];
    ASSERT_EQ(copy.add(sample.q_rad, sample.point_m), Status::ok);
  }
  Status s = Status::invalid_argument;
  EXPECT_NO_HEAP(s = selected.build(cell.nominal, dataset().samples(), Span<const std::uint32_t>(positions)));
  ASSERT_EQ(s, Status::ok);
  EXPECT_EQ(selected.size(), 40u);
  const LinkLengths lengths_m = link_lengths(cell.truth);
  double generic_m = 0.0;
  RigidTransform refitted;
  ASSERT_EQ(evaluate_cost(selected.model_for(lengths_m.data()), copy.samples(), CostKind::mean_abs_3d, BaseFrame::refit,
                          &refitted, &generic_m),
            Status::ok);
  EXPECT_NEAR(selected.evaluate(lengths_m.data()), generic_m, kRelativeTolerance * generic_m);
  EXPECT_NE(selected.evaluate(lengths_m.data()), cost().evaluate(lengths_m.data()));
  positions[39] = static_cast<std::uint32_t>(dataset().size());  // outside the samples
  EXPECT_EQ(selected.build(cell.nominal, dataset().samples(), Span<const std::uint32_t>(positions)),
            Status::invalid_argument);
}

TEST_F(Paper6CostTest, TruthBeatsNominalByFarAndMatchesTheNoise) {
  const LinkLengths truth_m = link_lengths(cell.truth);
  const LinkLengths nominal_m = link_lengths(cell.nominal);
  const double truth_mae_m = cost().evaluate(truth_m.data());
  EXPECT_LT(truth_mae_m, 2.5e-5);  // mean |3D Gaussian| with sigma 10 um is 16 um
  EXPECT_GT(cost().evaluate(nominal_m.data()), 5.0 * truth_mae_m);
}

/// Largest |cost - generic| / generic over the nominal, true and random lengths in the box.
double worst_relative_error(Paper6CostBase& candidate, const test::Paper6Cell& cell, Span<const Sample> samples) {
  LinkLengthBox box;
  EXPECT_EQ(link_length_box(cell.nominal, kPaper6DefaultHalfWidth_m, &box), Status::ok);
  Random random(407);
  double worst = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    LinkLengths lengths_m = trial == 0 ? link_lengths(cell.nominal) : link_lengths(cell.truth);
    for (int k = 0; k < 6 && trial > 1; ++k) lengths_m.values_m(k) = random.uniform(box.lower_m[k], box.upper_m[k]);
    const double generic_m = test::generic_mae(cell.nominal, lengths_m.data(), samples);
    const double relative = std::fabs(candidate.evaluate(lengths_m.data()) - generic_m) / generic_m;
    if (relative > worst) worst = relative;
  }
  return worst;
}

/// A reference 5 mm and ~6 mrad off the nominal fit, as a quick fit of a few poses might be.
RigidTransform rough_reference(const RigidTransform& exact) {
  RigidTransform rough = exact;
  Mat3 tilt;
  tilt << 1.0, -0.004, 0.003, 0.004, 1.0, -0.002, -0.003, 0.002, 1.0;  // small rotation, re-orthonormalised below
  rough.rotation = rotation_from_cross_covariance(tilt.transpose()) * exact.rotation;
  rough.translation_m += Vec3(0.003, -0.004, 0.0);
  return rough;
}

TEST_F(Paper6CostTest, CompactFloatLayoutStaysWithinAMillionth) {
  static Paper6Cost<256, float> compact;
  Status s = Status::invalid_argument;
  EXPECT_NO_HEAP(s = compact.build(cell.nominal, dataset().samples()));
  ASSERT_EQ(s, Status::ok);
  const double built = worst_relative_error(compact, cell, dataset().samples());
  // Streamed against a rough reference: the residuals it stores are then mm, not um.
  ASSERT_EQ(compact.reset(cell.nominal, rough_reference(cost().reference())), Status::ok);
  for (const Sample& sample : dataset().samples()) ASSERT_EQ(compact.add(sample.q_rad, sample.point_m), Status::ok);
  ASSERT_EQ(compact.finalize(), Status::ok);
  const double streamed = worst_relative_error(compact, cell, dataset().samples());
  std::printf("compact layout, worst relative error: built %.2e, rough reference %.2e (exact layout %.2e)\n", built,
              streamed, worst_relative_error(cost(), cell, dataset().samples()));
  EXPECT_LT(built, 1e-6);
  EXPECT_LT(streamed, 1e-5);
}

TEST_F(Paper6CostTest, ExactLayoutIsExactForAnyReference) {
  static Paper6Cost<256> streamed;
  for (const RigidTransform& reference : {RigidTransform(), rough_reference(cost().reference())}) {
    ASSERT_EQ(streamed.reset(cell.nominal, reference), Status::ok);
    for (const Sample& sample : dataset().samples()) ASSERT_EQ(streamed.add(sample.q_rad, sample.point_m), Status::ok);
    ASSERT_EQ(streamed.finalize(), Status::ok);
    EXPECT_LT(worst_relative_error(streamed, cell, dataset().samples()), 2 * kRelativeTolerance);
    RigidTransform base;
    double mae_m = 0.0;
    ASSERT_EQ(streamed.evaluate(link_lengths(cell.truth), &mae_m, &base), Status::ok);
    EXPECT_LT((base.rotation - cell.base_to_tracker.rotation).norm(), 1e-5);  // the truth, to the noise
    EXPECT_LT((base.translation_m - cell.base_to_tracker.translation_m).norm(), 1e-5);
  }
}

TEST(Paper6Cost, FirmwareLayoutFitsIn64KiB) {
  // 512 poses, the paper's ABC (150 x 6) and its 300-cycle trace in static RAM.
  EXPECT_EQ(kPaper6ValuesPerSample * sizeof(double), 168u);
  EXPECT_EQ(kPaper6ValuesPerSample * sizeof(float), 84u);
  const std::size_t total =
      sizeof(Paper6Cost<512, float>) + sizeof(AbcSolver<150, kPaper6Dimension>) + sizeof(Trace<300>);
  std::printf("firmware static RAM: cost %zu + ABC %zu + trace %zu = %zu bytes\n", sizeof(Paper6Cost<512, float>),
              sizeof(AbcSolver<150, kPaper6Dimension>), sizeof(Trace<300>), total);
  EXPECT_LE(total, 64u * 1024u);
  EXPECT_GT(sizeof(Paper6Cost<512, double>) + sizeof(AbcSolver<150, kPaper6Dimension>), 64u * 1024u);
}

TEST(Paper6Cost, ErrorsAreSpecific) {
  static Paper6Cost<4> small;
  const RobotModel nominal = nominal_model(RobotType::ur5);
  EXPECT_EQ(small.build(nominal, Span<const Sample>()), Status::dataset_empty);
  EXPECT_FALSE(small.ready());
  EXPECT_TRUE(std::isnan(small.evaluate(link_lengths(nominal).data())));
  double mae_m = 0.0;
  EXPECT_EQ(small.evaluate(link_lengths(nominal), &mae_m, nullptr), Status::invalid_argument);

  RobotModel broken = nominal;
  broken.joints[2].a_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(small.reset(broken, RigidTransform()), Status::non_finite_input);
  RigidTransform bad_reference;
  bad_reference.translation_m(1) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(small.reset(nominal, bad_reference), Status::non_finite_input);

  ASSERT_EQ(small.reset(nominal, RigidTransform()), Status::ok);
  JointVector q = JointVector::Zero();
  q(4) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(small.add(q, Vec3::Zero()), Status::non_finite_input);
  EXPECT_EQ(small.add(JointVector::Zero(), Vec3(0.0, std::numeric_limits<double>::quiet_NaN(), 0.0)),
            Status::non_finite_input);
  EXPECT_EQ(small.size(), 0u);
  Random random(7);
  for (int i = 0; i < 2; ++i) ASSERT_EQ(small.add(test::random_joints_tool_down(&random), Vec3(i, 0, 0)), Status::ok);
  EXPECT_EQ(small.finalize(), Status::too_few_samples);
  ASSERT_EQ(small.add(test::random_joints_tool_down(&random), Vec3(2, 0, 0)), Status::ok);
  EXPECT_EQ(small.finalize(), Status::degenerate_geometry);  // measured points on a line
  ASSERT_EQ(small.add(test::random_joints_tool_down(&random), Vec3(0, 1, 0)), Status::ok);
  EXPECT_EQ(small.add(test::random_joints_tool_down(&random), Vec3(0, 0, 1)), Status::dataset_full);
  EXPECT_EQ(small.finalize(), Status::ok);
  LinkLengths lengths_m = link_lengths(nominal);
  lengths_m.values_m(3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(small.evaluate(lengths_m, &mae_m, nullptr), Status::non_finite_input);
  EXPECT_EQ(small.capacity(), 4u);
}

TEST(Paper6Cost, LengthsRoundTripAndBoxIsNominalPlusMinusHalfWidth) {
  const RobotModel nominal = nominal_model(RobotType::ur5);
  const LinkLengths lengths_m = link_lengths(nominal);
  const ModelParams params = to_params(nominal);
  const int paper6[kPaper6Dimension] = {model_param_index(0, DhField::d), model_param_index(1, DhField::a),
                                        model_param_index(2, DhField::a), model_param_index(3, DhField::d),
                                        model_param_index(4, DhField::d), model_param_index(5, DhField::d)};
  const LinkLengthSet set = link_length_set(nominal);
  ASSERT_EQ(set.count, kPaper6Dimension);  // a UR arm's link lengths are the paper's six, in order
  for (std::size_t k = 0; k < kPaper6Dimension; ++k) {
    EXPECT_EQ(set.param_index[k], paper6[k]);
    EXPECT_EQ(lengths_m.values_m(static_cast<int>(k)), params(paper6[k]));
  }
  EXPECT_EQ(lengths_m.values_m(1), -0.425);  // a2 of the UR5
  const double moved_m[6] = {0.1, -0.4, -0.4, 0.11, 0.095, 0.08};
  const RobotModel moved = with_link_lengths(nominal, link_length_set(nominal), moved_m);
  const LinkLengths moved_lengths_m = link_lengths(moved);
  ASSERT_EQ(moved_lengths_m.count, 6u);
  EXPECT_EQ(moved_lengths_m.values_m.head<6>(), (Eigen::Map<const Eigen::Matrix<double, 6, 1>>(moved_m)));
  EXPECT_TRUE(moved_lengths_m.values_m.tail<6>().isZero(0.0));  // zeros after the count
  EXPECT_EQ(moved.joints[1].alpha_rad, nominal.joints[1].alpha_rad);

  LinkLengthBox box;
  ASSERT_EQ(link_length_box(nominal, 1e-3, &box), Status::ok);
  for (std::size_t k = 0; k < kPaper6Dimension; ++k) {
    EXPECT_DOUBLE_EQ(box.lower_m[k], lengths_m.values_m(static_cast<int>(k)) - 1e-3);
    EXPECT_DOUBLE_EQ(box.upper_m[k], lengths_m.values_m(static_cast<int>(k)) + 1e-3);
  }
  EXPECT_EQ(box.view().lower.size(), kPaper6Dimension);
  EXPECT_EQ(validate_search_box(box.view(), kPaper6Dimension, kPaper6Dimension), Status::ok);
  EXPECT_EQ(link_length_box(nominal, 0.0, &box), Status::invalid_argument);
  EXPECT_EQ(link_length_box(nominal, std::numeric_limits<double>::quiet_NaN(), &box), Status::invalid_argument);
}

TEST(QcpRotation, AgreesWithTheSvdRotation) {
  Random random(406);
  for (int trial = 0; trial < 3000; ++trial) {
    Mat3 cross;
    if (trial % 2 == 0) {  // like calibration data: a scatter seen through a rotation, plus noise
      Mat3 a;
      for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = random.uniform(-1.0, 1.0);
      cross = a * a.transpose() * test::random_rotation(&random).transpose() + 1e-3 * a;
    } else {  // anything, reflections included
      for (int i = 0; i < 9; ++i) cross(i / 3, i % 3) = random.uniform(-1.0, 1.0);
    }
    Mat3 fast;
    EXPECT_NO_HEAP(fast = rotation_from_cross_covariance_qcp(cross));
    const Mat3 reference = rotation_from_cross_covariance(cross);
    EXPECT_LT((fast - reference).norm(), 1e-12) << "trial " << trial;
    EXPECT_LT((fast * fast.transpose() - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(fast.determinant(), 1.0, 1e-14);
  }
}

TEST(QcpRotation, DegenerateInputsFallBackToTheSvd) {
  const Mat3 zero = Mat3::Zero();
  EXPECT_EQ(rotation_from_cross_covariance_qcp(zero), rotation_from_cross_covariance(zero));
  Mat3 rank_one = Vec3(1, 2, 3) * Vec3(-1, 0.5, 2).transpose();  // collinear points
  EXPECT_EQ(rotation_from_cross_covariance_qcp(rank_one), rotation_from_cross_covariance(rank_one));
}

}  // namespace
}  // namespace hivecal::paper6_cost_test
