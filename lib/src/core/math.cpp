// Own elementary functions. The polynomial kernels and reduction constants are the
// classic fdlibm minimax sets (Sun Microsystems, freely usable); the code is ours.
// Everything here relies on -ffp-contract=off: an FMA inside a compensated step
// changes the rounding and so the bits.
#include "hivecal/core/math.hpp"

#include <cstdint>

namespace hivecal::math {
namespace {

/// Biased exponent field of x (0..2047).
int exponent_field(double x) {
  return static_cast<int>((bits_of(x) >> 52) & 0x7ffU);
}

double quiet_nan() {
  return from_bits(0x7ff8000000000000ULL);
}

double abs_value(double x) {
  return from_bits(bits_of(x) & 0x7fffffffffffffffULL);
}

/// Round to nearest integer, ties away from zero, for |x| < 2^31.
std::int32_t round_to_int(double x) {
  return static_cast<std::int32_t>(x < 0.0 ? x - 0.5 : x + 0.5);
}

/// x * 2^k exactly (including the subnormal range), k in [-2100, 2100].
double scale_by_power_of_two(double x, int k) {
  while (k > 1023) {
    x *= from_bits(0x7fe0000000000000ULL);  // 2^1023
    k -= 1023;
  }
  while (k < -1022) {
    // 2^-969 keeps one rounding at most (the final one into the subnormals).
    x *= from_bits(static_cast<std::uint64_t>(1023 - 969) << 52);
    k += 969;
  }
  return x * from_bits(static_cast<std::uint64_t>(1023 + k) << 52);
}

// --- sin / cos -------------------------------------------------------------------

/// sin(x + tail) for |x| <= pi/4, tail a correction much smaller than x.
double kernel_sin(double x, double tail, bool has_tail) {
  constexpr double S1 = -1.66666666666666324348e-01;
  constexpr double S2 = 8.33333333332248946124e-03;
  constexpr double S3 = -1.98412698298579493134e-04;
  constexpr double S4 = 2.75573137070700676789e-06;
  constexpr double S5 = -2.50507602534068634195e-08;
  constexpr double S6 = 1.58969099521155010221e-10;
  const double z = x * x;
  const double w = z * z;
  const double r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
  const double v = z * x;
  if (!has_tail) return x + v * (S1 + z * r);
  return x - ((z * (0.5 * tail - v * r) - tail) - v * S1);
}

/// cos(x + tail) for |x| <= pi/4.
double kernel_cos(double x, double tail) {
  constexpr double C1 = 4.16666666666666019037e-02;
  constexpr double C2 = -1.38888888888741095749e-03;
  constexpr double C3 = 2.48015872894767294178e-05;
  constexpr double C4 = -2.75573143513906633035e-07;
  constexpr double C5 = 2.08757232129817482790e-09;
  constexpr double C6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double w = z * z;
  const double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
  const double half_z = 0.5 * z;
  const double one_minus = 1.0 - half_z;
  return one_minus + (((1.0 - one_minus) - half_z) + (z * r - x * tail));
}

/// x = n*pi/2 + (head + tail) with |head + tail| <= ~pi/4; Cody-Waite with pi/2 split in
/// three 33-bit pieces, so n*piece is exact for |n| < 2^20.
struct Reduced {
  std::int32_t quadrant;
  double head;
  double tail;
};

Reduced reduce_half_pi(double x) {
  constexpr double kInvHalfPi = 6.36619772367581382433e-01;
  constexpr double kPio2Part1 = 1.57079632673412561417e+00;
  constexpr double kPio2Part1Tail = 6.07710050650619224932e-11;
  constexpr double kPio2Part2 = 6.07710050630396597660e-11;
  constexpr double kPio2Part2Tail = 2.02226624879595063154e-21;
  constexpr double kPio2Part3 = 2.02226624871116645580e-21;
  constexpr double kPio2Part3Tail = 8.47842766036889956997e-32;

  const std::int32_t n = round_to_int(x * kInvHalfPi);
  const double fn = static_cast<double>(n);
  double r = x - fn * kPio2Part1;
  double w = fn * kPio2Part1Tail;
  double head = r - w;
  const int exponent_x = exponent_field(x);
  if (exponent_x - exponent_field(head) > 16) {  // cancellation: second step (118 bits)
    double t = r;
    w = fn * kPio2Part2;
    r = t - w;
    w = fn * kPio2Part2Tail - ((t - r) - w);
    head = r - w;
    if (exponent_x - exponent_field(head) > 49) {  // third step (151 bits)
      t = r;
      w = fn * kPio2Part3;
      r = t - w;
      w = fn * kPio2Part3Tail - ((t - r) - w);
      head = r - w;
    }
  }
  return Reduced{n, head, (r - head) - w};
}

bool trig_argument_ok(double x) {
  return abs_value(x) <= kTrigMaxArgument_rad;
}
bool within_quarter_pi(double x) {
  return abs_value(x) <= 7.85398163397448278999e-01;
}

// --- atan ------------------------------------------------------------------------

/// atan(x) for finite x.
double atan(double x) {
  constexpr double kAtanHi[] = {4.63647609000806093515e-01, 7.85398163397448278999e-01, 9.82793723247329054082e-01,
                                1.57079632679489655800e+00};
  constexpr double kAtanLo[] = {2.26987774529616870924e-17, 3.06161699786838301793e-17, 1.39033110312309984516e-17,
                                6.12323399573676603587e-17};
  constexpr double kAT[] = {3.33333333333329318027e-01,  -1.99999999998764832476e-01, 1.42857142725034663711e-01,
                            -1.11111104054623557880e-01, 9.09088713343650656196e-02,  -7.69187620504482999495e-02,
                            6.66107313738753120669e-02,  -5.83357013379057348645e-02, 4.97687799461593236017e-02,
                            -3.65315727442169155270e-02, 1.62858201153657823623e-02};
  const bool negative = x < 0.0;
  double a = abs_value(x);
  if (a >= 7.378697629483821e19) {  // 2^66: atan is pi/2 to double precision
    const double z = kAtanHi[3] + kAtanLo[3];
    return negative ? -z : z;
  }
  int id = -1;
  if (a < 0.4375) {
    if (a < 7.450580596923828e-09) return x;  // 2^-27
  } else if (a < 1.1875) {
    if (a < 0.6875) {
      id = 0;
      a = (2.0 * a - 1.0) / (2.0 + a);
    } else {
      id = 1;
      a = (a - 1.0) / (a + 1.0);
    }
  } else if (a < 2.4375) {
    id = 2;
    a = (a - 1.5) / (1.0 + 1.5 * a);
  } else {
    id = 3;
    a = -1.0 / a;
  }
  const double xr = id < 0 ? x : a;
  const double z = xr * xr;
  const double w = z * z;
  const double s1 = z * (kAT[0] + w * (kAT[2] + w * (kAT[4] + w * (kAT[6] + w * (kAT[8] + w * kAT[10])))));
  const double s2 = w * (kAT[1] + w * (kAT[3] + w * (kAT[5] + w * (kAT[7] + w * kAT[9]))));
  if (id < 0) return xr - xr * (s1 + s2);
  const auto i = static_cast<unsigned>(id);
  const double result = kAtanHi[i] - ((xr * (s1 + s2) - kAtanLo[i]) - xr);
  return negative ? -result : result;
}

}  // namespace

void sincos(double x, double* sin_out, double* cos_out) {
  if (!is_finite(x) || !trig_argument_ok(x)) {
    *sin_out = quiet_nan();
    *cos_out = quiet_nan();
    return;
  }
  if (within_quarter_pi(x)) {
    *sin_out = kernel_sin(x, 0.0, false);
    *cos_out = kernel_cos(x, 0.0);
    return;
  }
  const Reduced red = reduce_half_pi(x);
  const double s = kernel_sin(red.head, red.tail, true);
  const double c = kernel_cos(red.head, red.tail);
  switch (red.quadrant & 3) {
    case 0:
      *sin_out = s;
      *cos_out = c;
      break;
    case 1:
      *sin_out = c;
      *cos_out = -s;
      break;
    case 2:
      *sin_out = -s;
      *cos_out = -c;
      break;
    default:
      *sin_out = -c;
      *cos_out = s;
      break;
  }
}

double sin(double x) {  // hivecal::math::sin, the library's own (libm differs between CPUs)
  double s = 0.0;
  double c = 0.0;
  sincos(x, &s, &c);
  return s;
}

double cos(double x) {  // hivecal::math::cos, the library's own (libm differs between CPUs)
  double s = 0.0;
  double c = 0.0;
  sincos(x, &s, &c);
  return c;
}

double exp(double x) {
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  constexpr double P1 = 1.66666666666666019037e-01;
  constexpr double P2 = -2.77777777770155933842e-03;
  constexpr double P3 = 6.61375632143793436117e-05;
  constexpr double P4 = -1.65339022054652515390e-06;
  constexpr double P5 = 4.13813679705723846039e-08;
  if (x != x) return x;
  if (x > 7.09782712893383973096e+02) return from_bits(0x7ff0000000000000ULL);
  if (x < -7.45133219101941108420e+02) return 0.0;
  if (abs_value(x) < 3.725290298461914e-09) return 1.0 + x;  // 2^-28
  const std::int32_t k = round_to_int(x * kInvLn2);
  const double fk = static_cast<double>(k);
  const double hi = x - fk * kLn2Hi;  // exact: k*kLn2Hi has trailing zero bits
  const double lo = fk * kLn2Lo;
  const double r = hi - lo;
  const double t = r * r;
  const double c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
  const double y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
  return scale_by_power_of_two(y, k);
}

double log(double x) {
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double Lg1 = 6.666666666666735130e-01;
  constexpr double Lg2 = 3.999999999940941908e-01;
  constexpr double Lg3 = 2.857142874366239149e-01;
  constexpr double Lg4 = 2.222219843214978396e-01;
  constexpr double Lg5 = 1.818357216161805012e-01;
  constexpr double Lg6 = 1.531383769920937332e-01;
  constexpr double Lg7 = 1.479819860511658591e-01;
  if (x != x) return x;
  if (x < 0.0) return quiet_nan();
  if (x == 0.0) return -from_bits(0x7ff0000000000000ULL);
  if (!is_finite(x)) return x;
  int k = 0;
  if (exponent_field(x) == 0) {  // subnormal: scale into the normal range
    x *= 18014398509481984.0;    // 2^54
    k -= 54;
  }
  std::uint64_t u = bits_of(x);
  k += static_cast<int>((u >> 52) & 0x7ffU) - 1023;
  u &= 0x000fffffffffffffULL;
  double m = from_bits(u | 0x3ff0000000000000ULL);  // m in [1, 2)
  if (m > 1.4142135623730951) {                     // keep m in (sqrt(2)/2, sqrt(2)]
    m *= 0.5;
    k += 1;
  }
  const double f = m - 1.0;
  const double s = f / (2.0 + f);
  const double z = s * s;
  const double w = z * z;
  const double t1 = w * (Lg2 + w * (Lg4 + w * Lg6));
  const double t2 = z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7)));
  const double r = t2 + t1;
  const double half_f_squared = 0.5 * f * f;
  const double dk = static_cast<double>(k);
  return dk * kLn2Hi - ((half_f_squared - (s * (half_f_squared + r) + dk * kLn2Lo)) - f);
}

double atan2(double y, double x) {  // hivecal::math::atan2, the library's own, not libm
  constexpr double kPiLo = 1.2246467991473531772e-16;
  if (x != x || y != y) return x + y;
  const bool y_negative = (bits_of(y) >> 63) != 0;
  const bool x_negative = (bits_of(x) >> 63) != 0;
  if (y == 0.0) {
    if (!x_negative) return y;
    return y_negative ? -kPi : kPi;
  }
  if (x == 0.0) return y_negative ? -kHalfPi : kHalfPi;
  if (!is_finite(x) || !is_finite(y)) {
    const double ay = is_finite(y) ? 0.0 : 1.0;
    const double ax = is_finite(x) ? 0.0 : 1.0;
    double z = 0.0;
    if (ay > 0.0 && ax > 0.0)
      z = x_negative ? 3.0 * kPi / 4.0 : kPi / 4.0;
    else if (ay > 0.0)
      z = kHalfPi;
    else
      z = x_negative ? kPi : 0.0;
    return y_negative ? -z : z;
  }
  const int exponent_gap = exponent_field(y) - exponent_field(x);
  double z = 0.0;
  if (exponent_gap > 60) {
    z = kHalfPi + 0.5 * kPiLo;
  } else if (x_negative && exponent_gap < -60) {
    z = 0.0;
  } else {
    z = atan(abs_value(y / x));
  }
  if (!x_negative) return y_negative ? -z : z;
  const double reflected = kPi - (z - kPiLo);
  return y_negative ? -reflected : reflected;
}

double acos_clamped(double x) {
  if (x != x) return x;
  if (x >= 1.0) return 0.0;
  if (x <= -1.0) return kPi;
  // sqrt is IEEE correctly rounded on every target (the one libm function allowed); atan2 is ours.
  return atan2(__builtin_sqrt((1.0 - x) * (1.0 + x)), x);  // math::atan2 (ours) + IEEE sqrt
}

}  // namespace hivecal::math
