#include "ceres_peer.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cstdio>
#include <vector>

namespace ceres_peer {
namespace {

/// r = R0 Exp(w) FK(q; dh, tool) + t0 + R0 tau - m, templated for Ceres' Jets, with std trig.
struct PointResidual {
  const double* q_rad;
  const double* point_m;
  const double* base_rotation;
  const double* base_translation_m;

  template <typename T>
  bool operator()(const T* dh, const T* tool, const T* rotation, const T* translation, T* residual) const {
    using std::cos;
    using std::sin;
    T p[3] = {tool[0], tool[1], tool[2]};
    for (int j = kJoints - 1; j >= 0; --j) {  // innermost first, as hivecal's fk_tool_point
      const T* joint = dh + 4 * j;            // theta_offset, d, a, alpha
      const T theta = T(q_rad[j]) + joint[0];
      const T ct = cos(theta), st = sin(theta), ca = cos(joint[3]), sa = sin(joint[3]);
      const T x = ct * p[0] - st * ca * p[1] + st * sa * p[2] + joint[2] * ct;
      const T y = st * p[0] + ct * ca * p[1] - ct * sa * p[2] + joint[2] * st;
      const T z = sa * p[1] + ca * p[2] + joint[1];
      p[0] = x;
      p[1] = y;
      p[2] = z;
    }
    T rotated[3];
    ceres::AngleAxisRotatePoint(rotation, p, rotated);
    for (int i = 0; i < 3; ++i) rotated[i] += translation[i];
    for (int i = 0; i < 3; ++i) {
      T value = T(base_translation_m[i]) - T(point_m[i]);
      for (int k = 0; k < 3; ++k) value += T(base_rotation[3 * i + k]) * rotated[k];
      residual[i] = value;
    }
    return true;
  }
};

}  // namespace

Outcome solve(const Problem& input, bool verbose) {
  Outcome out;
  for (int i = 0; i < kParams; ++i) out.params[i] = input.start[i];
  for (int i = kDhParams + 3; i < kParams; ++i) out.params[i] = 0.0;  // base increments start at 0
  double* dh = out.params;
  double* tool = out.params + kDhParams;
  double* rotation = tool + 3;
  double* translation = rotation + 3;
  ceres::Problem problem;
  for (std::size_t s = 0; s < input.count; ++s) {
    auto* cost = new ceres::AutoDiffCostFunction<PointResidual, 3, kDhParams, 3, 3, 3>(new PointResidual{
        input.q_rad + kJoints * s, input.point_m + 3 * s, input.base_rotation, input.base_translation_m});
    problem.AddResidualBlock(cost, nullptr, dh, tool, rotation, translation);
  }
  double* blocks[] = {dh, tool, rotation, translation};
  const int sizes[] = {kDhParams, 3, 3, 3};
  int first = 0;
  for (int b = 0; b < 4; ++b) {
    std::vector<int> fixed;
    for (int i = 0; i < sizes[b]; ++i) {
      if (input.fixed[first + i]) fixed.push_back(i);
    }
    if (static_cast<int>(fixed.size()) == sizes[b]) {
      problem.SetParameterBlockConstant(blocks[b]);
    } else if (!fixed.empty()) {
      problem.SetManifold(blocks[b], new ceres::SubsetManifold(sizes[b], fixed));
    }
    first += sizes[b];
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.num_threads = 1;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-12;  // as LmOptions::cost_tolerance
  options.parameter_tolerance = 1e-12;
  options.gradient_tolerance = 1e-10;  // as LmOptions::gradient_tolerance (Ceres: max-norm of the projected gradient)
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (verbose) std::printf("%s\n", summary.FullReport().c_str());
  out.usable = summary.IsSolutionUsable();
  out.iterations = static_cast<int>(summary.iterations.size()) - 1;  // entry 0 is the start
  return out;
}

}  // namespace ceres_peer
