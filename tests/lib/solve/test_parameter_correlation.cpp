// Parameter correlations at a fit's result (solve/parameter_correlation.hpp): the matrix of a
// fit on random poses against an independent inversion of the kept block, its shape (unit
// diagonal, symmetric, zero outside the kept parameters), the partner search, and errors.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "hivecal/core/random.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::parameter_correlation_test {
namespace {

Dataset<64> dataset;
LmWorkspace lm_workspace;
LmResult fit;
CorrelationScratch scratch;
NormalMatrix correlation;
NormalEquations reference_equations;

/// LM on `count` simulated poses of a perturbed UR5 (full model, tool point known).
void fit_random_set(std::uint64_t seed, std::size_t count) {
  Random random(seed);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  dataset.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), count, 10e-6, &random, &dataset);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = truth.tool_m;
  ASSERT_EQ(calibrate_lm(start, nullptr, dataset.samples(), LmOptions{}, &lm_workspace, &fit), Status::ok);
}

TEST(ParameterCorrelation, EqualsTheNormalisedInverseOfTheKeptBlockOnRandomSets) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    fit_random_set(seed, 20 + 7 * seed);
    const ParamMask kept = fit.identifiability.kept_mask;
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = parameter_correlations(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{}, kept,
                                                   &scratch, &correlation));
    ASSERT_EQ(status, Status::ok) << seed;
    // Reference: the kept block of J^T J, unscaled, inverted by LU (correlation is scale-free).
    reference_equations.targets = Span<TargetBlock>();
    ASSERT_EQ(accumulate_normal_equations(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{},
                                          &reference_equations, kept),
              Status::ok);
    int index[kFullParamCount];
    int n = 0;
    for (int i = 0; i < kFullParamCount; ++i)
      if (mask_has(kept, i)) index[n++] = i;
    ASSERT_GT(n, 20) << seed;
    NormalMatrix block = NormalMatrix::Identity();
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) block(a, b) = reference_equations.jtwj(index[a], index[b]);
    const NormalMatrix inverse = block.fullPivLu().inverse();
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) {
        const double expected = inverse(a, b) / std::sqrt(inverse(a, a) * inverse(b, b));
        EXPECT_NEAR(correlation(index[a], index[b]), expected, 1e-6) << seed << " " << index[a] << " " << index[b];
      }
    }
    for (int i = 0; i < kFullParamCount; ++i) {
      for (int j = 0; j < kFullParamCount; ++j) {
        EXPECT_NEAR(correlation(i, j), correlation(j, i), 1e-12);
        EXPECT_LE(std::fabs(correlation(i, j)), 1.0 + 1e-12);
        if (!mask_has(kept, i) || !mask_has(kept, j)) {
          EXPECT_EQ(correlation(i, j), 0.0) << i << " " << j;
        }
      }
      if (mask_has(kept, i)) {
        EXPECT_NEAR(correlation(i, i), 1.0, 1e-12);
      }
    }
  }
}

TEST(ParameterCorrelation, StrongestPartnerIsTheLargestMagnitudeOffTheDiagonal) {
  NormalMatrix c = NormalMatrix::Zero();
  c.diagonal().setOnes();
  EXPECT_EQ(strongest_correlation(c, 3).index, -1);
  c(3, 7) = c(7, 3) = 0.4;
  c(3, 12) = c(12, 3) = -0.97;
  c(3, 20) = c(20, 3) = 0.96;
  const CorrelationPartner partner = strongest_correlation(c, 3);
  EXPECT_EQ(partner.index, 12);
  EXPECT_EQ(partner.correlation, -0.97);
  EXPECT_EQ(strongest_correlation(c, 7).index, 3);
}

TEST(ParameterCorrelation, RefusesWhatItCannotInvert) {
  fit_random_set(11, 30);
  // Every rigid parameter at once: the base and the first joint's offsets are not separable.
  EXPECT_EQ(parameter_correlations(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{},
                                   rigid_params_mask(kSixJoints), &scratch, &correlation),
            Status::singular_system);
  EXPECT_EQ(parameter_correlations(fit.model, fit.base_to_tracker, Span<const Sample>(), PointLoss{},
                                   fit.identifiability.kept_mask, &scratch, &correlation),
            Status::dataset_empty);
  EXPECT_EQ(parameter_correlations(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{},
                                   fit.identifiability.kept_mask, nullptr, &correlation),
            Status::invalid_argument);
}

}  // namespace
}  // namespace hivecal::parameter_correlation_test
