// The Ceres peer (ceres_peer.hpp) on hivecal's types: a calibration problem from samples, a
// start and the parameters to estimate, and Ceres' solution as a model and base. Shared by the
// in-process benchmark (bench_lm_ceres) and the whole-process one (ceres_calibrate).
#pragma once

#include <vector>

#include "ceres_peer.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"

namespace ceres_fit {

/// One problem in ceres_peer's plain arrays. `problem` points into the vectors: prepare it in
/// place and do not copy it.
struct Input {
  std::vector<double> q_rad;    ///< kJoints per sample [rad]
  std::vector<double> point_m;  ///< 3 per sample [m]
  ceres_peer::Problem problem;  ///< over the vectors above
};

/// The same parameterisation as hivecal's LM: dh (24), tool (3), base rotation vector and
/// translation increments (3 + 3) around `start_base`; the parameters outside `estimated` held
/// at their start values.
void prepare(const hivecal::RobotModel& start, const hivecal::RigidTransform& start_base,
             hivecal::Span<const hivecal::Sample> samples, hivecal::ParamMask estimated, Input* in);

/// What Ceres found, as a model and base.
struct Outcome {
  hivecal::RobotModel model;     ///< calibrated geometry and tool point
  hivecal::RigidTransform base;  ///< calibrated base -> tracker
  int iterations = 0;            ///< Ceres' iterations after the start
  bool usable = false;           ///< Summary::IsSolutionUsable()
};

/// Ceres' Levenberg-Marquardt on a prepared problem (Ceres' full report on stderr when `verbose`).
Outcome solve(const hivecal::RigidTransform& start_base, const Input& in, bool verbose);

}  // namespace ceres_fit
