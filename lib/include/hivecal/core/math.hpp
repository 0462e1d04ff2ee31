// Elementary functions of the library's own, so results do not depend on the
// platform's libm (glibc, newlib and musl round sin/cos/exp/log differently).
// Only +, -, *, / and sqrt (all correctly rounded by IEEE-754) are used, so with
// -ffp-contract=off every target computes the same bits.
#pragma once

#include <cstdint>
#include <cstring>

namespace hivecal::math {

// These are the library's own definitions (hivecal::math::sin etc.), not libm's: the names
// match the standard ones on purpose so that formulas read as usual.

/// pi to double precision.
inline constexpr double kPi = 3.14159265358979311600;
inline constexpr double kRadPerDeg = kPi / 180.0;  ///< degrees -> radians [rad/deg]
inline constexpr double kDegPerRad = 180.0 / kPi;  ///< radians -> degrees [deg/rad]
inline constexpr double kUsPerS = 1e6;             ///< seconds -> microseconds [us/s]
/// pi/2 to double precision.
inline constexpr double kHalfPi = 1.57079632679489655800;
/// Largest |x| [rad] for which sin/cos reduce the argument accurately; beyond it they return NaN.
inline constexpr double kTrigMaxArgument_rad = 1647099.3291652855;  // 2^20 * pi/2

/// Sine of x [rad]; error <= 1 ulp for |x| <= kTrigMaxArgument_rad, NaN beyond or for NaN/Inf.
double sin(double x);  // the library's own, not libm's
/// Cosine of x [rad]; error <= 1 ulp for |x| <= kTrigMaxArgument_rad, NaN beyond or for NaN/Inf.
double cos(double x);  // the library's own, not libm's
/// Sine and cosine of x [rad] with one argument reduction; same accuracy as sin/cos.
void sincos(double x, double* sin_out, double* cos_out);
/// e^x; error < 1 ulp; +Inf above ~709.78, 0 below ~-745.13.
double exp(double x);
/// Natural logarithm; error < 1 ulp; -Inf at 0, NaN for x < 0.
double log(double x);
/// Arc tangent of y/x in (-pi, pi] [rad], quadrant from the signs; error < 2 ulp.
double atan2(double y, double x);  // the library's own, not libm's
/// Arc cosine [rad] of x clamped to [-1, 1].
double acos_clamped(double x);
/// The IEEE-754 bits of x (copied, not converted: NaN payloads and signed zeros survive).
inline std::uint64_t bits_of(double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}
/// The double whose IEEE-754 bits are `bits`.
inline double from_bits(std::uint64_t bits) {
  double x = 0.0;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}
/// True when x is neither NaN nor Inf (exponent bit test: immune to -ffast-math). Inline:
/// it guards every entry of the 33x33 matrices.
inline bool is_finite(double x) {
  return ((bits_of(x) >> 52) & 0x7ffU) != 0x7ffU;
}

}  // namespace hivecal::math
