// Benchmark: hivecal's Levenberg-Marquardt (full model, analytic Jacobian, streaming 33x33
// normal equations) against Ceres' Levenberg-Marquardt (AutoDiffCostFunction, DENSE_QR) on
// the same simulated UR5 session, the same 33 parameters (base as a local rotation vector
// and translation in the base frame), the same fixed set (what our identifiability analysis
// dropped) and the same start. Prints wall times, their ratio, iterations and validation
// MAE on fresh poses. Not a test: figures go to docs/solver-lm.md.
//
//   bench_lm_ceres [samples=300] [noise_um=10] [repeats=20]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "ceres_fit.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/lm_test_data.hpp"

namespace {

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
  const RobotModel truth =
      test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.012, -0.018, 0.15));
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
  static JointTrig joint_trig_storage[2000];
  workspace.joint_trig = joint_trig_storage;
  static LmResult ours;
  if (calibrate_lm(start, &start_base, train.samples(), LmOptions{}, &workspace, &ours) != Status::ok) {
    std::fprintf(stderr, "hivecal LM failed\n");
    return 1;
  }
  const ParamMask kept = ours.identifiability.kept_mask;
  const bool verbose = std::getenv("BENCH_VERBOSE") != nullptr;
  ceres_fit::Input ceres_input;
  ceres_fit::prepare(start, start_base, train.samples(), kept, &ceres_input);
  ceres_fit::Outcome theirs = ceres_fit::solve(start_base, ceres_input, verbose);
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
    theirs = ceres_fit::solve(start_base, ceres_input, verbose);
    ceres_times.push_back(seconds_since(t0));
  }
  const double our_time = *std::min_element(our_times.begin(), our_times.end());
  const double ceres_time = *std::min_element(ceres_times.begin(), ceres_times.end());
  const auto mae = [](const RobotModel& m, const RigidTransform& b, const DatasetBase& d) {
    return position_error_stats(m, b, d.samples()).mae(ErrorAxis::norm_3d);
  };
  const double our_mae = mae(ours.model, ours.base_to_tracker, fresh);
  const double ceres_mae = mae(theirs.model, theirs.base, fresh);
  std::printf("UR5, %zu samples, noise %.1f um/axis, %d free parameters of 33 (%d dropped by identifiability)\n", count,
              noise_m * 1e6, ours.identifiability.kept_count(), ours.identifiability.dropped_count);
  std::printf("%-22s %14s %14s %10s %20s %20s\n", "solver", "min time [ms]", "median [ms]", "iterations",
              "valid. MAE [um]", "vs noise-free [um]");
  std::printf("%-22s %14.3f %14.3f %10d %20.4f %20.4f\n", "hivecal LM", our_time * 1e3, median(our_times) * 1e3,
              ours.iterations, our_mae * 1e6, mae(ours.model, ours.base_to_tracker, fresh_exact) * 1e6);
  std::printf("%-22s %14.3f %14.3f %10d %20.4f %20.4f\n", "Ceres LM (DENSE_QR)", ceres_time * 1e3,
              median(ceres_times) * 1e3, theirs.iterations, ceres_mae * 1e6,
              mae(theirs.model, theirs.base, fresh_exact) * 1e6);
  std::printf(
      "speed-up: %.1fx on the minimum, %.1fx on the median (target >= 25x); MAE difference: %.3f %% "
      "(target <= 1 %%)\n",
      ceres_time / our_time, median(ceres_times) / median(our_times), 100.0 * (our_mae - ceres_mae) / ceres_mae);
  std::printf(
      "max prediction gap between the two calibrations: %.3g um\n",
      test::max_prediction_gap(ours.model, ours.base_to_tracker, theirs.model, theirs.base, fresh.samples()) * 1e6);
  return 0;
}
