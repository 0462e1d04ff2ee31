// Tail quantiles of the chi-square and F distributions (core/distributions.hpp) against
// reference values (scipy.stats 1.10, isf), and the functions under them.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/core/distributions.hpp"

namespace hivecal::distributions_test {
namespace {

TEST(Distributions, LogGammaMatchesLibm) {
  for (double x : {0.5, 1.0, 1.5, 2.0, 4.5, 10.0, 150.0, 1500.0}) {
    EXPECT_NEAR(math::log_gamma(x), std::lgamma(x), 1e-12 * std::fmax(1.0, std::fabs(std::lgamma(x)))) << x;
  }
}

TEST(Distributions, IncompleteFunctionsMatchReferences) {
  EXPECT_NEAR(math::incomplete_beta(0.3, 2.5, 4.0), 0.3521975859067672, 1e-13);
  EXPECT_NEAR(math::gamma_upper_tail(1.5, 20.0), 1.065509033425585e-08, 1e-20);
  EXPECT_EQ(math::incomplete_beta(0.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(math::incomplete_beta(1.0, 2.0, 3.0), 1.0);
  EXPECT_TRUE(std::isnan(math::incomplete_beta(1.5, 2.0, 3.0)));
}

TEST(Distributions, ChiSquareTailQuantilesMatchReferences) {
  EXPECT_NEAR(math::chi_square_upper_quantile(1e-3, 3.0), 16.26623619623813, 1e-9);
  EXPECT_NEAR(math::chi_square_upper_quantile(1e-6, 9.0), 44.81093787068782, 1e-9);
  EXPECT_NEAR(math::chi_square_upper_quantile(0.5, 1.0), 0.4549364231195724, 1e-9);
  EXPECT_TRUE(std::isnan(math::chi_square_upper_quantile(0.0, 3.0)));
  EXPECT_TRUE(std::isnan(math::chi_square_upper_quantile(0.5, -1.0)));
}

TEST(Distributions, FTailQuantilesMatchReferences) {
  EXPECT_NEAR(math::f_upper_quantile(1e-3 / 18.0, 3.0, 30.0), 10.817090011317875, 1e-8);
  EXPECT_NEAR(math::f_upper_quantile(1e-5, 9.0, 100.0), 5.146646502712863, 1e-9);
  EXPECT_NEAR(math::f_upper_quantile(0.05, 1.0, 5.0), 6.607890973703367, 1e-9);
  EXPECT_NEAR(math::f_upper_quantile(1e-7, 3.0, 3000.0), 11.86984682961594, 1e-7);
  EXPECT_TRUE(std::isnan(math::f_upper_quantile(1.0, 3.0, 30.0)));
}

TEST(Distributions, DetectableNoncentralityIsBaardasLambda0) {
  // One dof at alpha 0.1 %: Baarda's lambda0 = (3.29 + 0.84)^2 = 17.07; the normal
  // approximation gives 16.9.
  const double lambda = math::detectable_noncentrality(math::chi_square_upper_quantile(1e-3, 1.0), 1.0);
  EXPECT_NEAR(lambda, 17.07, 0.3);
  // More dof, the same alpha: a larger bias is needed.
  EXPECT_GT(math::detectable_noncentrality(math::chi_square_upper_quantile(1e-3, 3.0), 3.0), lambda);
}

}  // namespace
}  // namespace hivecal::distributions_test
