// Dataset limits and split, cost and metrics agreeing with each other, specific errors.
#include <cmath>
#include <cstring>
#include <limits>

#include "harness.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/cost.hpp"
#include "testkit/test_data.hpp"

namespace hivecal {
namespace {

FW_TEST(Dataset, ReportsFullInsteadOfDropping) {
  static Dataset<4> dataset;
  dataset.clear();
  FW_CHECK_EQ(dataset.capacity(), 4u);
  for (int i = 0; i < 4; ++i) FW_CHECK_EQ(dataset.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
  FW_CHECK(dataset.full());
  FW_CHECK_EQ(dataset.add(JointVector::Zero(), Vec3::Zero()), Status::dataset_full);
  FW_CHECK_EQ(dataset.size(), 4u);
}

FW_TEST(Dataset, RejectsNonFiniteSamples) {
  static Dataset<8> dataset;
  dataset.clear();
  JointVector q = JointVector::Zero();
  q(3) = std::numeric_limits<double>::quiet_NaN();
  FW_CHECK_EQ(dataset.add(q, Vec3::Zero()), Status::non_finite_input);
  FW_CHECK_EQ(dataset.add(JointVector::Zero(), Vec3(0, std::numeric_limits<double>::infinity(), 0)),
              Status::non_finite_input);
  FW_CHECK_EQ(dataset.size(), 0u);
}

FW_TEST(Dataset, SplitIsSeededPermutationWithRequestedShare) {
  static Dataset<100> a;
  static Dataset<100> b;
  a.clear();
  b.clear();
  for (int i = 0; i < 100; ++i) {
    FW_ASSERT_EQ(a.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
    FW_ASSERT_EQ(b.add(JointVector::Constant(i), Vec3::Constant(i)), Status::ok);
  }
  FW_CHECK_EQ(a.train().size(), 100u);
  FW_CHECK_EQ(a.test().size(), 0u);
  FW_ASSERT_EQ(a.split(kDefaultTrainFraction, 5), Status::ok);
  FW_ASSERT_EQ(b.split(kDefaultTrainFraction, 5), Status::ok);
  FW_CHECK_EQ(a.train().size(), 70u);
  FW_CHECK_EQ(a.test().size(), 30u);
  bool seen[100] = {};
  bool same_order = true;
  bool moved = false;
  for (std::size_t i = 0; i < 100; ++i) {
    const double x = a.samples()[i].point_m.x();
    same_order = same_order && a.samples()[i].point_m == b.samples()[i].point_m;
    seen[static_cast<std::size_t>(x)] = true;
    moved = moved || x != static_cast<double>(i);
  }
  std::size_t distinct = 0;
  for (bool s : seen) distinct += s ? 1u : 0u;
  FW_CHECK(same_order);         // same seed, same order
  FW_CHECK_EQ(distinct, 100u);  // a permutation: nothing lost or duplicated
  FW_CHECK(moved);
  FW_ASSERT_EQ(b.split(kDefaultTrainFraction, 6), Status::ok);
  FW_CHECK(a.samples()[0].point_m != b.samples()[0].point_m);
}

FW_TEST(Dataset, SplitErrors) {
  static Dataset<8> dataset;
  dataset.clear();
  FW_CHECK_EQ(dataset.split(0.7, 1), Status::dataset_empty);
  FW_ASSERT_EQ(dataset.add(JointVector::Zero(), Vec3::Zero()), Status::ok);
  FW_CHECK_EQ(dataset.split(0.0, 1), Status::invalid_argument);
  FW_CHECK_EQ(dataset.split(1.5, 1), Status::invalid_argument);
  FW_CHECK_EQ(dataset.split(std::numeric_limits<double>::quiet_NaN(), 1), Status::invalid_argument);
  FW_CHECK_EQ(dataset.split(0.2, 1), Status::invalid_argument);  // rounds to zero training samples
  FW_CHECK_EQ(dataset.split(1.0, 1), Status::ok);
}

/// 200 noise-free samples of a perturbed UR5 seen from the example tracker placement.
struct CostScene {
  RobotModel truth;
  RigidTransform base_to_tracker = test::example_base_to_tracker();
  Dataset<256>& dataset = storage();

  CostScene() {
    Random random(31);
    truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 2e-4, 2e-4);
    truth.tool_m << 0.0, 0.0, 0.1;
    dataset.clear();
    test::fill_dataset(truth, base_to_tracker, 200, 0.0, &random, &dataset);
  }
  static Dataset<256>& storage() {
    static Dataset<256> d;
    return d;
  }
};

FW_TEST(Cost, TrueModelHasZeroCostAndRefitFindsTheTracker) {
  CostScene scene;
  double mae = 1.0;
  RigidTransform fitted;
  FW_ASSERT_EQ(
      evaluate_cost(scene.truth, scene.dataset.samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &mae),
      Status::ok);
  FW_CHECK_LT(mae, 1e-12);
  FW_CHECK_LT((fitted.rotation - scene.base_to_tracker.rotation).norm(), 1e-12);
  FW_CHECK_LT((fitted.translation_m - scene.base_to_tracker.translation_m).norm(), 1e-12);
  double sos = 1.0;
  FW_ASSERT_EQ(evaluate_cost(scene.truth, scene.dataset.samples(), CostKind::sum_squares, BaseFrame::fixed,
                             &scene.base_to_tracker, &sos),
               Status::ok);
  FW_CHECK_LT(sos, 1e-20);
}

FW_TEST(Cost, NominalModelCostsWhatTheMetricsSay) {
  CostScene scene;
  RobotModel nominal = nominal_model(RobotType::ur5);
  nominal.tool_m = scene.truth.tool_m;
  RigidTransform fitted;
  double mae = 0.0;
  FW_ASSERT_EQ(evaluate_cost(nominal, scene.dataset.samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &mae),
               Status::ok);
  FW_CHECK_GT(mae, 1e-4);
  double sos = 0.0;
  FW_ASSERT_EQ(evaluate_cost(nominal, scene.dataset.samples(), CostKind::sum_squares, BaseFrame::fixed, &fitted, &sos),
               Status::ok);
  const ErrorStats stats = position_error_stats(nominal, fitted, scene.dataset.samples());
  FW_CHECK_EQ(stats.count, 200u);
  FW_CHECK_NEAR(stats.mae(ErrorAxis::norm_3d), mae, 1e-15);
  FW_CHECK_GT(stats.sigma(ErrorAxis::norm_3d), 0.0);
  FW_CHECK_GE(stats.max(ErrorAxis::norm_3d), stats.mae(ErrorAxis::norm_3d));
  for (ErrorAxis axis : {ErrorAxis::x, ErrorAxis::y, ErrorAxis::z}) {
    FW_CHECK_LE(stats.mae(axis), stats.mae(ErrorAxis::norm_3d));
  }
  FW_CHECK_GE(std::sqrt(sos / 200.0), mae);  // RMS is at least the mean norm
}

FW_TEST(Cost, AccuracyReportCoversTrainTestOverall) {
  CostScene scene;
  FW_ASSERT_EQ(scene.dataset.split(0.7, 9), Status::ok);
  const AccuracyReport report = accuracy_report(nominal_model(RobotType::ur5), scene.base_to_tracker, scene.dataset);
  FW_CHECK_EQ(report.train.count, 140u);
  FW_CHECK_EQ(report.test.count, 60u);
  FW_CHECK_EQ(report.overall.count, 200u);
  const double weighted = (140 * report.train.mae(ErrorAxis::x) + 60 * report.test.mae(ErrorAxis::x)) / 200;
  FW_CHECK_NEAR(weighted, report.overall.mae(ErrorAxis::x), 1e-15);
}

FW_TEST(Cost, BadInputsGetSpecificErrors) {
  CostScene scene;
  RigidTransform fitted;
  double cost = 0.0;
  FW_CHECK_EQ(evaluate_cost(scene.truth, Span<const Sample>(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &cost),
              Status::dataset_empty);
  FW_CHECK_EQ(evaluate_cost(scene.truth, scene.dataset.samples().subspan(0, 2), CostKind::mean_abs_3d, BaseFrame::refit,
                            &fitted, &cost),
              Status::too_few_samples);
  RobotModel infinite = scene.truth;
  infinite.joints[1].d_m = std::numeric_limits<double>::infinity();
  FW_CHECK_EQ(evaluate_cost(infinite, scene.dataset.samples(), CostKind::mean_abs_3d, BaseFrame::fixed, &fitted, &cost),
              Status::non_finite_input);
  static Dataset<8> one_pose;  // all samples at one pose: the base transform is undetermined
  one_pose.clear();
  for (int i = 0; i < 5; ++i) FW_ASSERT_EQ(one_pose.add(JointVector::Zero(), Vec3(1, 2, 3)), Status::ok);
  FW_CHECK_EQ(evaluate_cost(scene.truth, one_pose.samples(), CostKind::mean_abs_3d, BaseFrame::refit, &fitted, &cost),
              Status::degenerate_geometry);
}

FW_TEST(Status, EveryCodeHasAMessage) {
  bool all_named = true;
  for (int code = 0; code <= static_cast<int>(Status::read_failed); ++code) {
    const char* message = status_message(static_cast<Status>(code));
    all_named = all_named && message[0] != '\0' && std::strcmp(message, "unknown status") != 0;
  }
  FW_CHECK(all_named);
}

}  // namespace
}  // namespace hivecal
