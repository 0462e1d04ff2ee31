// A few doubles per operation where the target has double SIMD (SSE2 on x86-64, NEON on
// aarch64), one where it has not (armhf VFP, Cortex-M): GCC/Clang vector types with
// element-wise IEEE operations, so each lane is computed exactly as the scalar code would
// and the bits do not depend on the lane count. Internal to lib/src.
#pragma once

#include <cstring>

namespace hivecal {
namespace lanes {

#if defined(__SSE2__) || defined(__aarch64__)
#define HIVECAL_LANES_ARE_VECTORS 1
/// Doubles per Lane.
constexpr int kLanes = 2;
using Lane = double __attribute__((vector_size(2 * sizeof(double))));
using FloatLane = float __attribute__((vector_size(2 * sizeof(float))));

/// kLanes consecutive doubles from `value` (any alignment).
inline Lane load(const double* value) {
  Lane lane;
  std::memcpy(&lane, value, sizeof lane);
  return lane;
}
/// kLanes consecutive floats from `value`, widened to double (exact).
inline Lane load(const float* value) {
  FloatLane lane;
  std::memcpy(&lane, value, sizeof lane);
  return __builtin_convertvector(lane, Lane);
}
/// Writes the lanes to kLanes consecutive doubles at `value`.
inline void store(double* value, const Lane& lane) {
  std::memcpy(value, &lane, sizeof lane);
}
/// Every lane set to x.
inline Lane broadcast(double x) {
  return Lane{x, x};
}
/// Lane k of a value.
inline double lane_value(const Lane& v, int k) {
  return v[k];
}
#else
constexpr int kLanes = 1;
using Lane = double;
inline Lane load(const double* value) {
  return *value;
}
inline Lane load(const float* value) {
  return static_cast<double>(*value);
}
inline void store(double* value, const Lane& lane) {
  *value = lane;
}
inline Lane broadcast(double x) {
  return x;
}
inline double lane_value(const Lane& v, int) {
  return v;
}
#endif

/// Consecutive doubles from `value` into a lane of any width (a plain double, a GCC vector).
/// memcpy and the built-in vector operators need no target-specific helper, so a kernel
/// written with these can be instantiated for a wider target inside a target("...") function
/// (no vector crosses a call by value: that would change the ABI, -Wpsabi).
template <class AnyLane>
inline void load_any(const double* value, AnyLane* lane) {
  std::memcpy(lane, value, sizeof *lane);
}
/// Writes a lane of any width to consecutive doubles at `value`.
template <class AnyLane>
inline void store_any(double* value, const AnyLane& lane) {
  std::memcpy(value, &lane, sizeof lane);
}
/// A one-double lane: a plain access, which the compiler knows is aligned (a memcpy from a
/// pointer it cannot trace became two unaligned word loads on 32-bit ARM).
inline void load_any(const double* value, double* lane) {
  *lane = *value;
}
inline void store_any(double* value, const double& lane) {
  *value = lane;
}

#if defined(__x86_64__) && defined(__GNUC__)
/// x86-64 machines with AVX2 (most since 2013) add a 4-double lane, chosen at run time
/// (wide_lanes_available) so that the baseline build still runs everywhere. Element-wise
/// IEEE operations and no FMA: the same bits as kLanes or one.
#define HIVECAL_WIDE_LANES 1
/// Doubles per WideLane.
constexpr int kWideLanes = 4;
using WideLane = double __attribute__((vector_size(kWideLanes * sizeof(double))));
/// True when this CPU runs the target("avx2") instances.
inline bool wide_lanes_available() {
  return __builtin_cpu_supports("avx2") != 0;
}
/// Machines with AVX-512F (servers since 2017, Zen 4 and later) add an 8-double lane, chosen
/// the same way, for the loops over contiguous columns (the normal equations' rank update);
/// the Jacobian kernel stays at four: its lanes are scattered to their samples' rows, which
/// eight lanes make slower.
constexpr int kWiderLanes = 8;
using WiderLane = double __attribute__((vector_size(kWiderLanes * sizeof(double))));
/// True when this CPU runs the target("avx512f") instances.
inline bool wider_lanes_available() {
  return __builtin_cpu_supports("avx512f") != 0;
}
#endif

}  // namespace lanes
}  // namespace hivecal
