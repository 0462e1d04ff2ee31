// Prints what the LM calibration's identifiability analysis drops, and why, on two simulated
// UR5 sessions: generic poses, and poses that keep the tool pointing straight down. The
// figures in docs/solver-lm.md come from here.
//
//   lm_identifiability_report [samples=300] [noise_um=10]
#include <cstdio>
#include <cstdlib>

#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/lm_test_data.hpp"

namespace {

using namespace hivecal;

void print_spectrum(const char* title, const double* values, int count, double condition) {
  std::printf("  %s (%d, sigma / sigma_max):", title, count);
  for (int k = 0; k < count; ++k) std::printf("%s%.2g", k % 11 == 0 ? "\n    " : " ", values[k] / values[0]);
  std::printf("\n    condition number %.3g\n", condition);
}

void print_report(const char* title, const LmResult& r, Status status, const DatasetBase& fresh,
                  const RobotModel& truth, const RigidTransform& tracker) {
  const IdentifiabilityReport& report = r.identifiability;
  std::printf("%s: %s, %d iterations (%s), RMS %.2f um, kept %d of %d\n", title, status_message(status), r.iterations,
              lm_termination_name(r.termination), r.rms_m * 1e6, report.kept_count(), mask_count(report.free_mask));
  for (int d = 0; d < report.dropped_count; ++d) {
    const DroppedParam& e = report.dropped[d];
    std::printf("  drop %-8s %-16s sigma ratio %8.1e   ", full_param_name(e.index, r.model),
                unidentifiable_reason_name(e.reason), e.singular_ratio);
    for (int c = 0; c < kNullComponentCount && e.component_index[c] >= 0; ++c) {
      std::printf(" %+.3f %s", e.component[c], full_param_name(e.component_index[c], r.model));
    }
    std::printf("\n");
  }
  print_spectrum("singular values before", report.singular_values_before, report.singular_count_before,
                 report.condition_before);
  print_spectrum("singular values after", report.singular_values_after, report.singular_count_after,
                 report.condition_after);
  std::printf("  fresh poses of the same kind: max gap to the noise-free truth %.2f um\n\n",
              test::max_prediction_gap(r.model, r.base_to_tracker, truth, tracker, fresh.samples()) * 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t count = argc > 1 ? static_cast<std::size_t>(std::atoi(argv[1])) : 300;
  const double noise_m = (argc > 2 ? std::atof(argv[2]) : 10.0) * 1e-6;
  if (count < 12 || count > 1000) {
    std::fprintf(stderr, "usage: lm_identifiability_report [samples 12..1000] [noise_um]\n");
    return 2;
  }
  Random random(20261124);
  const RobotModel truth =
      test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.012, -0.018, 0.15));
  const RigidTransform tracker = test::example_base_to_tracker();
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.15);
  static Dataset<1000> train;
  static Dataset<200> fresh;
  static LmWorkspace workspace;
  static LmResult result;

  test::fill_dataset(truth, tracker, count, noise_m, &random, &train);
  test::fill_dataset(truth, tracker, 200, 0.0, &random, &fresh);
  Status status = calibrate_lm(start, nullptr, train.samples(), LmOptions{}, &workspace, &result);
  std::printf("UR5, %zu samples, %.1f um noise per axis, start: nominal, tool guess on the flange axis\n\n", count,
              noise_m * 1e6);
  print_report("generic poses", result, status, fresh, truth, tracker);

  train.clear();
  fresh.clear();
  test::fill_tool_down_dataset(truth, tracker, count, noise_m, &random, &train);
  test::fill_tool_down_dataset(truth, tracker, 200, 0.0, &random, &fresh);
  status = calibrate_lm(start, nullptr, train.samples(), LmOptions{}, &workspace, &result);
  print_report("tool always pointing down (both wrist branches)", result, status, fresh, truth, tracker);
  return 0;
}
