// Reference cost and metrics against a synthetic truth; the specific errors of bad inputs.
#include <gtest/gtest.h>

#include <limits>

#include "hivecal/model/dataset.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/cost.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::cost_test {
namespace {

struct CostFixture : ::testing::Test {
  static Dataset<256>& dataset() {
    static Dataset<256> d;
    return d;
  }
  RobotModel truth;
  RigidTransform base_to_tracker = test::example_base_to_tracker();
  void SetUp() override {
    Random random(31);
    truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 2e-4, 2e-4);
    truth.tool_m << 0.0, 0.0, 0.1;
    dataset().clear();
    test::fill_dataset(truth, base_to_tracker, 200, 0.0, &random, &dataset());
  }
};

TEST_F(CostFixture, TrueModelHasZeroCostAndRefitFindsTheTracker) {
  double mae = 1.0;
  RigidTransform fitted;
  Status s = Status::ok;
  EXPECT_NO_HEAP(s = evaluate_cost(truth, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &mae));
  ASSERT_EQ(s, Status::ok);
  EXPECT_LT(mae, 1e-12);
  EXPECT_LT((fitted.rotation - base_to_tracker.rotation).norm(), 1e-12);
  EXPECT_LT((fitted.translation_m - base_to_tracker.translation_m).norm(), 1e-12);
  double sos = 1.0;
  EXPECT_NO_HEAP(
      s = evaluate_cost(truth, dataset().samples(), CostKind::sum_squares, BaseFrame::fixed, &base_to_tracker, &sos));
  ASSERT_EQ(s, Status::ok);
  EXPECT_LT(sos, 1e-20);
}

TEST_F(CostFixture, NominalModelCostsWhatTheMetricsSay) {
  RobotModel nominal = nominal_model(RobotType::ur5);
  nominal.tool_m = truth.tool_m;
  RigidTransform fitted;
  double mae = 0.0;
  ASSERT_EQ(evaluate_cost(nominal, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &mae),
            Status::ok);
  EXPECT_GT(mae, 1e-4);
  double sos = 0.0;
  ASSERT_EQ(evaluate_cost(nominal, dataset().samples(), CostKind::sum_squares, BaseFrame::fixed, &fitted, &sos),
            Status::ok);
  ErrorStats stats;
  EXPECT_NO_HEAP(stats = position_error_stats(nominal, fitted, dataset().samples()));
  EXPECT_EQ(stats.count, 200u);
  EXPECT_NEAR(stats.mae(ErrorAxis::norm_3d), mae, 1e-15);
  EXPECT_GT(stats.sigma(ErrorAxis::norm_3d), 0.0);
  EXPECT_GE(stats.max(ErrorAxis::norm_3d), stats.mae(ErrorAxis::norm_3d));
  for (ErrorAxis axis : {ErrorAxis::x, ErrorAxis::y, ErrorAxis::z}) {
    EXPECT_LE(stats.mae(axis), stats.mae(ErrorAxis::norm_3d));
  }
  // RMS from the sum of squares is at least the mean norm.
  EXPECT_GE(std::sqrt(sos / 200.0), mae);
}

TEST_F(CostFixture, AccuracyReportCoversTrainTestOverall) {
  ASSERT_EQ(dataset().split(0.7, 9), Status::ok);
  RobotModel nominal = nominal_model(RobotType::ur5);
  AccuracyReport report;
  EXPECT_NO_HEAP(report = accuracy_report(nominal, base_to_tracker, dataset()));
  EXPECT_EQ(report.train.count, 140u);
  EXPECT_EQ(report.test.count, 60u);
  EXPECT_EQ(report.overall.count, 200u);
  const double weighted = (140 * report.train.mae(ErrorAxis::x) + 60 * report.test.mae(ErrorAxis::x)) / 200;
  EXPECT_NEAR(weighted, report.overall.mae(ErrorAxis::x), 1e-15);
}

TEST_F(CostFixture, BadInputsGetSpecificErrors) {
  RigidTransform fitted;
  double cost = 0.0;
  EXPECT_EQ(evaluate_cost(truth, Span<const Sample>(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &cost),
            Status::dataset_empty);
  EXPECT_EQ(
      evaluate_cost(truth, dataset().samples().subspan(0, 2), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &cost),
      Status::too_few_samples);
  EXPECT_EQ(evaluate_cost(truth, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::refit, nullptr, &cost),
            Status::invalid_argument);
  EXPECT_EQ(evaluate_cost(truth, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::fixed, &fitted, nullptr),
            Status::invalid_argument);
  RobotModel infinite = truth;
  infinite.joints[1].d_m = std::numeric_limits<double>::infinity();
  EXPECT_EQ(evaluate_cost(infinite, dataset().samples(), CostKind::mean_abs_3d, BaseFrame::fixed, &fitted, &cost),
            Status::non_finite_input);
  // All samples at one pose: the base transform is undetermined.
  static Dataset<8> one_pose;
  one_pose.clear();
  for (int i = 0; i < 5; ++i) ASSERT_EQ(one_pose.add(JointVector::Zero(), Vec3(1, 2, 3)), Status::ok);
  EXPECT_EQ(evaluate_cost(truth, one_pose.samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &cost),
            Status::degenerate_geometry);
}

}  // namespace
}  // namespace hivecal::cost_test
