// Benchmark: hivecal's Levenberg-Marquardt (full model, analytic Jacobian, streaming 33x33
// normal equations) against Ceres' Levenberg-Marquardt (AutoDiffCostFunction, DENSE_QR) on
// the same simulated UR5 session, the same 33 parameters (base as a local rotation vector
// and translation in the base frame), the same fixed set (what our identifiability analysis
// dropped) and the same start. Prints wall times, their ratio, iterations and validation
// MAE on fresh poses. Not a test: figures go to docs/solver-lm.md.
//
//   bench_lm_ceres [samples=300] [noise_um=10] [repeats=20]
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "hivecal/cost.hpp"
#include "hivecal/lm.hpp"
#include "hivecal/metrics.hpp"
#include "lm_test_data.hpp"

namespace {

using hivecal::kDhParamCount;
using hivecal::kJointCount;
using hivecal::kParamsPerJoint;

/// r = R0 Exp(w) FK(q; dh, tool) + t0 + R0 tau - m, templated for Ceres' Jets. Uses std
/// trig (via ADL for Jets): Ceres cannot use hivecal::math, and the bits do not matter here.
struct PointResidual {
  hivecal::JointVector q_rad;
  hivecal::Vec3 point_m;
  hivecal::Mat3 base_rotation;
  hivecal::Vec3 base_translation_m;

  template <typename T>
  bool operator()(const T* dh, const T* tool, const T* rotation, const T* translation, T* residual) const {
    using std::cos;
    using std::sin;
    using std::sqrt;
    T p[3] = {tool[0], tool[1], tool[2]};
    for (int j = kJointCount - 1; j >= 0; --j) {  // innermost first, as fk_tool_point
      const T* joint = dh + j * kParamsPerJoint;  // theta_offset, d, a, alpha
      const T theta = T(q_rad(j)) + joint[0];
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
      T value = T(base_translation_m(i)) - T(point_m(i));
      for (int k = 0; k < 3; ++k) value += T(base_rotation(i, k)) * rotated[k];
      residual[i] = value;
    }
    return true;
  }
};

struct CeresOutcome {
  hivecal::RobotModel model;
  hivecal::RigidTransform base;
  int iterations = 0;
  bool usable = false;
};

/// Ceres on the same parameterisation: dh (24), tool (3), base rotation vector and
/// translation increments (3 + 3) around the start base; dropped parameters held constant.
CeresOutcome run_ceres(const hivecal::RobotModel& start, const hivecal::RigidTransform& start_base,
                       hivecal::Span<const hivecal::Sample> samples, hivecal::ParamMask kept) {
  const hivecal::ModelParams start_params = hivecal::to_params(start);
  double dh[kDhParamCount];
  double tool[3];
  double rotation[3] = {0.0, 0.0, 0.0};
  double translation[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < kDhParamCount; ++i) dh[i] = start_params(i);
  for (int i = 0; i < 3; ++i) tool[i] = start_params(hivecal::tool_param_index(i));
  ceres::Problem problem;
  for (const hivecal::Sample& s : samples) {
    auto* cost = new ceres::AutoDiffCostFunction<PointResidual, 3, kDhParamCount, 3, 3, 3>(
        new PointResidual{s.q_rad, s.point_m, start_base.rotation, start_base.translation_m});
    problem.AddResidualBlock(cost, nullptr, dh, tool, rotation, translation);
  }
  double* blocks[] = {dh, tool, rotation, translation};
  const int sizes[] = {kDhParamCount, 3, 3, 3};
  int first = 0;
  for (int b = 0; b < 4; ++b) {
    std::vector<int> fixed;
    for (int i = 0; i < sizes[b]; ++i) {
      if (!hivecal::mask_has(kept, first + i)) fixed.push_back(i);
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
  options.function_tolerance = 1e-12;  // as our cost_tolerance
  options.parameter_tolerance = 1e-12;
  options.gradient_tolerance = 1e-10;  // as our gradient_tolerance (Ceres: max-norm of the projected gradient)
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (std::getenv("BENCH_VERBOSE") != nullptr) std::printf("%s\n", summary.FullReport().c_str());

  CeresOutcome out;
  out.usable = summary.IsSolutionUsable();
  out.iterations = static_cast<int>(summary.iterations.size()) - 1;  // entry 0 is the start
  hivecal::ModelParams params = start_params;
  for (int i = 0; i < kDhParamCount; ++i) params(i) = dh[i];
  for (int i = 0; i < 3; ++i) params(hivecal::tool_param_index(i)) = tool[i];
  out.model = hivecal::from_params(params);
  out.base.rotation = start_base.rotation * hivecal::rotation_from_vector(hivecal::Vec3(rotation[0], rotation[1], rotation[2]));
  out.base.translation_m = start_base.translation_m + start_base.rotation * hivecal::Vec3(translation[0], translation[1], translation[2]);
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hivecal;
  const std::size_t count = argc > 1 ? static_cast<std::size_t>(std::atoi(argv[1])) : 300;
  const double noise_m = (argc > 2 ? std::atof(argv[2]) : 10.0) * 1e-6;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 20;
  if (count < 12 || count > 2000 || repeats < 1) {
    std::fprintf(stderr, "usage: bench_lm_ceres [samples 12..2000] [noise_um] [repeats]\n");
    return 2;
  }

  // The session: a perturbed UR5 (joints 2-4 parallel), tracker 3 m away, noisy train
  // poses, fresh noisy validation poses and their noise-free points.
  Random random(20261124);
  const RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.012, -0.018, 0.15));
  const RigidTransform tracker = test::example_base_to_tracker();
  static Dataset<2000> train;
  static Dataset<500> fresh;
  static Dataset<500> fresh_exact;
  test::fill_dataset(truth, tracker, count, noise_m, &random, &train);
  Random fresh_random(77);
  Random exact_random(77);
  test::fill_dataset(truth, tracker, 500, noise_m, &fresh_random, &fresh);
  test::fill_dataset(truth, tracker, 500, 0.0, &exact_random, &fresh_exact);  // same poses, no noise

  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.15);
  RigidTransform start_base;
  if (fit_base_to_tracker(start, train.samples(), &start_base) != Status::ok) return 1;

  static LmWorkspace workspace;
  static LmResult ours;
  if (calibrate_lm(start, &start_base, train.samples(), LmOptions{}, &workspace, &ours) != Status::ok) {
    std::fprintf(stderr, "hivecal LM failed\n");
    return 1;
  }
  const ParamMask kept = ours.identifiability.kept_mask;
  CeresOutcome theirs = run_ceres(start, start_base, train.samples(), kept);
  if (!theirs.usable) {
    std::fprintf(stderr, "Ceres found no usable solution\n");
    return 1;
  }
  // Interleaved, so that both see the same machine load; the minimum is the least disturbed
  // run, the median the typical one.
  std::vector<double> our_times;
  std::vector<double> ceres_times;
  for (int r = 0; r < repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    (void)calibrate_lm(start, &start_base, train.samples(), LmOptions{}, &workspace, &ours);
    our_times.push_back(seconds_since(t0));
    t0 = std::chrono::steady_clock::now();
    theirs = run_ceres(start, start_base, train.samples(), kept);
    ceres_times.push_back(seconds_since(t0));
  }
  const double our_time = *std::min_element(our_times.begin(), our_times.end());
  const double ceres_time = *std::min_element(ceres_times.begin(), ceres_times.end());
  const auto mae = [](const RobotModel& m, const RigidTransform& b, const DatasetBase& d) {
    return position_error_stats(m, b, d.samples()).mae(ErrorAxis::norm_3d);
  };
  const double our_mae = mae(ours.model, ours.base_to_tracker, fresh);
  const double ceres_mae = mae(theirs.model, theirs.base, fresh);
  std::printf("UR5, %zu samples, noise %.1f um/axis, %d free parameters of 33 (%d dropped by identifiability)\n",
              count, noise_m * 1e6, ours.identifiability.kept_count(), ours.identifiability.dropped_count);
  std::printf("%-22s %14s %14s %10s %20s %20s\n", "solver", "min time [ms]", "median [ms]", "iterations",
              "valid. MAE [um]", "vs noise-free [um]");
  std::printf("%-22s %14.3f %14.3f %10d %20.4f %20.4f\n", "hivecal LM", our_time * 1e3, median(our_times) * 1e3,
              ours.iterations, our_mae * 1e6, mae(ours.model, ours.base_to_tracker, fresh_exact) * 1e6);
  std::printf("%-22s %14.3f %14.3f %10d %20.4f %20.4f\n", "Ceres LM (DENSE_QR)", ceres_time * 1e3,
              median(ceres_times) * 1e3, theirs.iterations, ceres_mae * 1e6,
              mae(theirs.model, theirs.base, fresh_exact) * 1e6);
  std::printf("speed-up: %.1fx on the minimum, %.1fx on the median (target >= 20x); MAE difference: %.3f %% "
              "(target <= 1 %%)\n",
              ceres_time / our_time, median(ceres_times) / median(our_times), 100.0 * (our_mae - ceres_mae) / ceres_mae);
  std::printf("max prediction gap between the two calibrations: %.3g um\n",
              test::max_prediction_gap(ours.model, ours.base_to_tracker, theirs.model, theirs.base,
                                       fresh.samples()) * 1e6);
  return 0;
}
