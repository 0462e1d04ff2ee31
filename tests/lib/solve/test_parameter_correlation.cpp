// Parameter correlations and covariance at a fit's result (solve/parameter_correlation.hpp):
// the matrix of a fit on random poses against an independent inversion of the kept block, its
// shape (unit diagonal, symmetric, zero outside the kept parameters), the covariance's diagonal
// against LM's sigmas (one target, and three with their tool points eliminated), the partner
// search, and errors.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "hivecal/core/random.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/target_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::parameter_correlation_test {
namespace {

Dataset<64> dataset;
LmWorkspace lm_workspace;
LmResult fit;
CorrelationScratch scratch;
NormalMatrix correlation;
NormalEquations reference_equations;
NormalMatrix covariance;
LmWorkspaceWithTargets targets_workspace;

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

/// Covariance against LM's sigmas and the correlations at `fit` on `dataset` over `kept`.
void expect_covariance_matches_fit(ParamMask kept, const char* what) {
  Status status = Status::invalid_argument;
  int dof = 0;
  EXPECT_NO_HEAP(status = parameter_covariance(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{}, kept,
                                               &scratch, &covariance, &dof));
  ASSERT_EQ(status, Status::ok) << what;
  EXPECT_EQ(dof, fit.residual_dof) << what;
  ASSERT_EQ(parameter_correlations(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{}, kept, &scratch,
                                   &correlation),
            Status::ok);
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(kept, i)) {
      EXPECT_EQ(covariance.row(i).squaredNorm() + covariance.col(i).squaredNorm(), 0.0) << what << " " << i;
      continue;
    }
    const double sigma = std::sqrt(covariance(i, i));
    EXPECT_NEAR(sigma, fit.sigma(i), 1e-9 * fit.sigma(i)) << what << " " << full_param_name(i, kSixJoints);
    for (int j = 0; j < kFullParamCount; ++j) {
      if (!mask_has(kept, j)) continue;
      EXPECT_NEAR(covariance(i, j), covariance(j, i), 1e-12 * std::fabs(covariance(i, i) + covariance(j, j)));
      const double expected = correlation(i, j) * sigma * std::sqrt(covariance(j, j));
      EXPECT_NEAR(covariance(i, j), expected, 1e-9 * fit.sigma(i) * fit.sigma(j)) << what << " " << i << " " << j;
    }
  }
}

TEST(ParameterCovariance, DiagonalIsLmsSigmasSquaredAndOffDiagonalItsCorrelations) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    fit_random_set(seed, 25 + 5 * seed);
    expect_covariance_matches_fit(fit.identifiability.kept_mask, "one target");
  }
}

TEST(ParameterCovariance, ThreeTargetsAreEliminatedAsLmDoes) {
  Random random(21);
  const Vec3 tool_m(0.012, -0.006, 0.17);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m), tool_m);
  dataset.clear();
  test::fill_target_dataset(truth, test::example_base_to_tracker(), 20, 3, 10e-6, &random, &dataset);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.17);
  ASSERT_EQ(calibrate_lm(start, nullptr, dataset.samples(), LmOptions{}, &targets_workspace, &fit), Status::ok);
  ASSERT_GT(fit.other_tools_sigma_m[0].norm(), 0.0);
  expect_covariance_matches_fit(fit.identifiability.kept_mask | kOtherTargetTools, "three targets");
}

TEST(ParameterCovariance, RefusesASetWithoutResidualDegreesOfFreedom) {
  fit_random_set(4, 30);
  // The base alone on two samples: 6 equations, 6 parameters.
  ParamMask base = 0;
  for (int axis = 0; axis < 3; ++axis)
    base |= param_bit(base_rotation_param_index(kSixJoints, axis)) |
            param_bit(base_translation_param_index(kSixJoints, axis));
  const Span<const Sample> two(dataset.samples().data(), 2);
  EXPECT_EQ(parameter_covariance(fit.model, fit.base_to_tracker, two, PointLoss{}, base, &scratch, &covariance),
            Status::too_few_samples);
  EXPECT_EQ(
      parameter_covariance(fit.model, fit.base_to_tracker, dataset.samples(), PointLoss{}, base, nullptr, &covariance),
      Status::invalid_argument);
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
