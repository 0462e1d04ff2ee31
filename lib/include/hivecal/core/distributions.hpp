// Tail quantiles of the chi-square and F distributions for the statistical tests of the job
// (the blunder test, docs/robust.md). Built on the library's own exp/log (core/math.hpp), so
// every target computes the same bits; bisection, not Newton, so the result does not depend
// on how close a first guess was.
#pragma once

namespace hivecal::math {

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, 9 terms); relative error < 1e-14 [-].
double log_gamma(double x);
/// Upper tail Q(a, x) = 1 - P(a, x) of the regularized incomplete gamma function, a > 0, x >= 0 [-].
double gamma_upper_tail(double a, double x);
/// Regularized incomplete beta I_x(a, b), a, b > 0, x in [0, 1] [-].
double incomplete_beta(double x, double a, double b);

/// x with P(X > x) = upper_tail for X ~ chi-square with `dof` degrees of freedom; NaN for
/// arguments outside upper_tail in (0, 1), dof > 0 [-].
double chi_square_upper_quantile(double upper_tail, double dof);
/// x with P(X > x) = upper_tail for X ~ F(d1, d2); NaN outside upper_tail in (0, 1), d1, d2 > 0 [-].
double f_upper_quantile(double upper_tail, double d1, double d2);
/// Power of the blunder test at the minimal detectable bias (Baarda's beta = 80 %) [-].
inline constexpr double kDetectionPower = 0.8;
/// Non-centrality lambda0 at which a chi-square test with `dof` degrees of freedom and
/// critical value `critical` detects with probability kDetectionPower (the non-central
/// chi-square taken as normal with mean dof + lambda and variance 2 (dof + 2 lambda); 1 dof,
/// alpha 0.1 %: 16.9 against the exact 17.1): a bias of sigma sqrt(lambda0 / r) is the
/// minimal detectable one [-].
double detectable_noncentrality(double critical, double dof);

}  // namespace hivecal::math
