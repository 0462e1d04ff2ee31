// Huber loss: 5 % gross tracker errors (millimetres) must not drag the fit.
#include <gtest/gtest.h>

#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::lm_robust_test {
namespace {

struct RobustFixture : ::testing::Test {
  static constexpr double kNoise_m = 1e-5;
  /// The clean samples (train), the fresh poses, the workspace and the result.
  static test::LmTestStorage<300>& lm() {
    static test::LmTestStorage<300> storage;
    return storage;
  }
  /// The clean samples with gross errors in 5 % of them.
  static Dataset<300>& dirty() {
    static Dataset<300> d;
    return d;
  }
  RobotModel truth;
  RigidTransform base = test::example_base_to_tracker();

  void SetUp() override {
    Random random(401);
    truth = test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.012, -0.018, 0.15));
    lm().train.clear();
    lm().fresh.clear();
    test::fill_dataset(truth, base, 300, kNoise_m, &random, &lm().train);
    test::fill_dataset(truth, base, 200, 0.0, &random, &lm().fresh);
    test::copy_with_outliers(lm().train, 20, 7, 1e-3, 5e-3, &random, &dirty());  // every 20th: 5 %
  }

  /// Validation MAE [m] on fresh poses against the noise-free truth after calibrating on `data`.
  double validation_mae(const DatasetBase& data, const LmOptions& options) {
    RobotModel start = nominal_model(RobotType::ur5);
    start.tool_m = Vec3(0.0, 0.0, 0.15);
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate_lm(start, nullptr, data.samples(), options, &lm().workspace, &lm().result));
    EXPECT_EQ(status, Status::ok) << status_message(status);
    ErrorStats stats;
    EXPECT_NO_HEAP(stats = position_error_stats(lm().result.model, lm().result.base_to_tracker, lm().fresh.samples()));
    return stats.mae(ErrorAxis::norm_3d);
  }
};

TEST_F(RobustFixture, HuberIgnoresGrossOutliersLeastSquaresDoesNot) {
  const double clean_mae = validation_mae(lm().train, LmOptions{});
  EXPECT_LT(clean_mae, 0.5 * kNoise_m);

  const double plain_mae = validation_mae(dirty(), LmOptions{});
  EXPECT_GT(plain_mae, 5.0 * kNoise_m);  // dragged by the outliers

  LmOptions automatic;
  automatic.loss = LmLoss::huber;  // threshold from the median residual
  const double auto_mae = validation_mae(dirty(), automatic);
  EXPECT_LT(auto_mae, 0.5 * kNoise_m);
  EXPECT_LT(auto_mae, 1.3 * clean_mae);
  // 3 x the per-axis noise estimated from the median norm (the outliers barely move it).
  EXPECT_NEAR(lm().result.huber_threshold_m, 3.0 * kNoise_m, 0.5 * kNoise_m);

  LmOptions fixed;
  fixed.loss = LmLoss::huber;
  fixed.huber_threshold_m = 3.0 * kNoise_m;
  const double fixed_mae = validation_mae(dirty(), fixed);
  EXPECT_LT(fixed_mae, 0.5 * kNoise_m);
  EXPECT_EQ(lm().result.huber_threshold_m, 3.0 * kNoise_m);
}

TEST_F(RobustFixture, HuberOnCleanDataCostsLittle) {
  const double clean_mae = validation_mae(lm().train, LmOptions{});
  LmOptions automatic;
  automatic.loss = LmLoss::huber;
  EXPECT_LT(validation_mae(lm().train, automatic), 1.2 * clean_mae);
}

}  // namespace
}  // namespace hivecal::lm_robust_test
