// The Ceres side of bench_lm_ceres, in its own translation unit: compiled with Eigen's and
// GCC's default vectorisation, as Ceres' users compile it, not with hivecal's determinism
// flags (EIGEN_DONT_VECTORIZE, no SLP vectorisation), which would slow Ceres' Jets down and
// flatter the ratio. Plain arrays cross the boundary: no Eigen type whose layout depends on
// the alignment settings does.
#pragma once

#include <cstddef>

namespace ceres_peer {

constexpr int kJoints = 6;
constexpr int kDhParams = 24;  ///< theta_offset, d, a, alpha per joint [rad, m, m, rad]
constexpr int kParams = 33;    ///< dh (24), tool (3), base rotation vector (3), base translation (3)

/// One calibration problem in the full model's parameterisation (docs/solver-lm.md).
struct Problem {
  const double* q_rad = nullptr;      ///< joint angles, kJoints per sample [rad]
  const double* point_m = nullptr;    ///< tracker points, 3 per sample [m]
  std::size_t count = 0;              ///< samples
  double base_rotation[9] = {};       ///< start base -> tracker rotation, row-major [-]
  double base_translation_m[3] = {};  ///< start base -> tracker translation [m]
  double start[kParams] = {};         ///< start values; the base increments are 0 [m, rad]
  bool fixed[kParams] = {};           ///< parameters held at their start value
};

/// What Ceres returned.
struct Outcome {
  double params[kParams] = {};  ///< final values, same order as Problem::start [m, rad]
  int iterations = 0;           ///< iterations after the start
  bool usable = false;          ///< Summary::IsSolutionUsable()
};

/// Levenberg-Marquardt with AutoDiffCostFunction and DENSE_QR, one thread, tolerances as
/// hivecal's LmOptions defaults. Prints Ceres' full report when `verbose`.
Outcome solve(const Problem& problem, bool verbose);

}  // namespace ceres_peer
