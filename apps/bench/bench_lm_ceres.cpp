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

#include "ceres_peer.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/lm_test_data.hpp"

namespace {

using hivecal::kJointCount;

static_assert(ceres_peer::kJoints == kJointCount && ceres_peer::kDhParams == hivecal::kDhParamCount,
              "ceres_peer mirrors the model layout");

struct CeresOutcome {
  hivecal::RobotModel model;
  hivecal::RigidTransform base;
  int iterations = 0;
  bool usable = false;
};

/// The session in ceres_peer's plain arrays (built once, outside the timed runs).
struct CeresInput {
  std::vector<double> q_rad;
  std::vector<double> point_m;
  ceres_peer::Problem problem;
};

/// The same parameterisation as ours: dh (24), tool (3), base rotation vector and translation
/// increments (3 + 3) around the start base; the parameters our analysis dropped held fixed.
void prepare_ceres(const hivecal::RobotModel& start, const hivecal::RigidTransform& start_base,
                   hivecal::Span<const hivecal::Sample> samples, hivecal::ParamMask kept, CeresInput* in) {
  for (const hivecal::Sample& s : samples) {
    for (int j = 0; j < kJointCount; ++j) in->q_rad.push_back(s.q_rad(j));
    for (int i = 0; i < 3; ++i) in->point_m.push_back(s.point_m(i));
  }
  ceres_peer::Problem& p = in->problem;
  p.q_rad = in->q_rad.data();
  p.point_m = in->point_m.data();
  p.count = samples.size();
  for (int i = 0; i < 3; ++i) {
    p.base_translation_m[i] = start_base.translation_m(i);
    for (int k = 0; k < 3; ++k) p.base_rotation[3 * i + k] = start_base.rotation(i, k);
  }
  const hivecal::ModelParams start_params = hivecal::to_params(start);
  for (int i = 0; i < hivecal::kModelParamCount; ++i) p.start[i] = start_params(i);
  for (int i = 0; i < ceres_peer::kParams; ++i) p.fixed[i] = !hivecal::mask_has(kept, i);
}

CeresOutcome run_ceres(const hivecal::RigidTransform& start_base, const CeresInput& in) {
  static_assert(ceres_peer::kParams == hivecal::kRigidParamCount, "same parameter vector (the rigid 33)");
  const ceres_peer::Outcome solved = ceres_peer::solve(in.problem, std::getenv("BENCH_VERBOSE") != nullptr);
  CeresOutcome out;
  out.usable = solved.usable;
  out.iterations = solved.iterations;
  hivecal::ModelParams params;
  for (int i = 0; i < hivecal::kModelParamCount; ++i) params(i) = solved.params[i];
  out.model = hivecal::from_params(params);
  const double* rotation = solved.params + hivecal::base_rotation_param_index(0);
  const double* translation = solved.params + hivecal::base_translation_param_index(0);
  out.base.rotation =
      start_base.rotation * hivecal::rotation_from_vector(hivecal::Vec3(rotation[0], rotation[1], rotation[2]));
  out.base.translation_m =
      start_base.translation_m + start_base.rotation * hivecal::Vec3(translation[0], translation[1], translation[2]);
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
  CeresInput ceres_input;
  prepare_ceres(start, start_base, train.samples(), kept, &ceres_input);
  CeresOutcome theirs = run_ceres(start_base, ceres_input);
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
    theirs = run_ceres(start_base, ceres_input);
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
