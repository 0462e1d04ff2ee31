#include "hivecal/core/distributions.hpp"

#include <cmath>
#include <limits>

#include "hivecal/core/math.hpp"

namespace hivecal::math {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTiny = 1e-300;          // Lentz's guard against a zero denominator
constexpr double kSeriesEpsilon = 1e-16;  // relative size of the last term kept [-]
constexpr int kMaxSeriesTerms = 1000;
constexpr int kBisectionSteps = 200;  // halves a bracket below one ulp

/// Lentz's continued fraction of the incomplete beta (Numerical Recipes' betacf).
double beta_fraction(double x, double a, double b) {
  const double qab = a + b;
  const double qap = a + 1.0;
  const double qam = a - 1.0;
  double c = 1.0;
  double d = 1.0 - qab * x / qap;
  if (std::fabs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= kMaxSeriesTerms; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < kSeriesEpsilon) break;
  }
  return h;
}

/// The x in [low, high] where decreasing(x) crosses `target`, by bisection.
template <typename Function>
double bisect_decreasing(Function decreasing, double target, double low, double high) {
  for (int step = 0; step < kBisectionSteps; ++step) {
    const double middle = 0.5 * (low + high);
    if (middle <= low || middle >= high) break;
    if (decreasing(middle) > target) {
      low = middle;
    } else {
      high = middle;
    }
  }
  return 0.5 * (low + high);
}

}  // namespace

double log_gamma(double x) {
  static constexpr double kLanczos[9] = {0.99999999999980993,  676.5203681218851,     -1259.1392167224028,
                                         771.32342877765313,   -176.61502916214059,   12.507343278686905,
                                         -0.13857109526572012, 9.9843695780195716e-6, 1.5056327351493116e-7};
  const double z = x - 1.0;
  double sum = kLanczos[0];
  for (int k = 1; k < 9; ++k) sum += kLanczos[k] / (z + k);
  const double t = z + 7.5;
  return 0.91893853320467274178 + (z + 0.5) * log(t) - t + log(sum);  // ln sqrt(2 pi) first
}

double gamma_upper_tail(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0)) return kNaN;
  if (x == 0.0) return 1.0;
  const double prefactor = exp(-x + a * log(x) - log_gamma(a));
  if (x < a + 1.0) {  // the series of P converges fast here
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n <= kMaxSeriesTerms; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::fabs(term) < std::fabs(sum) * kSeriesEpsilon) break;
    }
    return 1.0 - sum * prefactor;
  }
  // Lentz's continued fraction of Q (Numerical Recipes' gcf): accurate for a small tail.
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i <= kMaxSeriesTerms; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::fabs(del - 1.0) < kSeriesEpsilon) break;
  }
  return prefactor * h;
}

double incomplete_beta(double x, double a, double b) {
  if (!(a > 0.0) || !(b > 0.0) || !(x >= 0.0 && x <= 1.0)) return kNaN;
  if (x == 0.0 || x == 1.0) return x;
  const double front = exp(log_gamma(a + b) - log_gamma(a) - log_gamma(b) + a * log(x) + b * log(1.0 - x));
  // The continued fraction converges for x < (a + 1) / (a + b + 2); else by symmetry.
  if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_fraction(x, a, b) / a;
  return 1.0 - front * beta_fraction(1.0 - x, b, a) / b;
}

double chi_square_upper_quantile(double upper_tail, double dof) {
  if (!(upper_tail > 0.0 && upper_tail < 1.0) || !(dof > 0.0)) return kNaN;
  const auto tail = [dof](double x) { return gamma_upper_tail(0.5 * dof, 0.5 * x); };
  double high = dof + 10.0;
  while (tail(high) > upper_tail) high *= 2.0;
  return bisect_decreasing(tail, upper_tail, 0.0, high);
}

double f_upper_quantile(double upper_tail, double d1, double d2) {
  if (!(upper_tail > 0.0 && upper_tail < 1.0) || !(d1 > 0.0) || !(d2 > 0.0)) return kNaN;
  // P(F > f) = I_y(d2 / 2, d1 / 2) with y = d2 / (d2 + d1 f), decreasing in f: solve for y.
  const auto tail_of_y = [d1, d2](double y) { return -incomplete_beta(y, 0.5 * d2, 0.5 * d1); };
  const double y = bisect_decreasing(tail_of_y, -upper_tail, 0.0, 1.0);
  return d2 * (1.0 - y) / (d1 * y);
}

double detectable_noncentrality(double critical, double dof) {
  // dof + lambda - z sqrt(2 (dof + 2 lambda)) = critical, solved for s = sqrt(2 (dof + 2 lambda)).
  constexpr double kPowerQuantile = 0.8416212335729143;  // standard normal at kDetectionPower
  const double s = 2.0 * kPowerQuantile + 2.0 * std::sqrt(kPowerQuantile * kPowerQuantile + critical - 0.5 * dof);
  return 0.25 * s * s - 0.5 * dof;
}

}  // namespace hivecal::math
