// Core footprint probe: a product-like image (no test harness) holding a 512-sample dataset and
// running one core workload, for scripts/footprint.sh to measure flash, static RAM, stack and
// executed instructions. The workload and repeat count come from the semihosting command line:
//   run-qemu-mps2.sh <machine> hivecal_firmware_core.elf [workload [repeats]]
// Workloads (each starts by filling the dataset, so `fill` is the baseline to subtract):
//   fill      only fill the 512-sample dataset (synthetic UR5 + tracker, own PRNG)
//   sincos    + repeats x 512 x 6 math::sincos (the trig inside one FK per sample, half of it)
//   fk        + repeats x 512 fk_tool_point
//   jacobian  + repeats x 512 tool_point_jacobian
//   cost      + repeats x evaluate_cost(mean_abs_3d, refit) over 512 samples  (a solver's inner call)
//   cost_358  + repeats x the same over the 358 training samples of a 70/30 split
//   cost_fixed+ repeats x evaluate_cost(sum_squares, fixed base) over 512 samples
//   metrics   + repeats x accuracy_report after a 70/30 split
//   all       every workload once (the default; what CTest runs)
#include <cstdint>
#include <cstring>

#include "baremetal/board.h"
#include "hivecal/core/digest.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/cost.hpp"
#include "testkit/test_data.hpp"

namespace hivecal {
namespace {

constexpr std::size_t kSampleCount = 512;

/// The dataset the calibration budget is stated for (512 samples x 72 bytes = 36 KiB).
Dataset<kSampleCount> g_dataset;

struct Scene {
  RobotModel truth;
  RobotModel nominal;
  RigidTransform base_to_tracker;
};

Scene fill_dataset() {
  Random random(512);
  Scene scene;
  scene.truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4);
  scene.truth.tool_m << 0.002, -0.001, 0.1695;
  scene.nominal = nominal_model(RobotType::ur5);
  scene.nominal.tool_m = scene.truth.tool_m;
  scene.base_to_tracker = test::example_base_to_tracker();
  g_dataset.clear();
  test::fill_dataset(scene.truth, scene.base_to_tracker, kSampleCount, 1e-5, &random, &g_dataset);
  return scene;
}

/// Result sink: keeps the work observable so the compiler cannot drop it.
Digest g_sink;
bool g_ok = true;

void expect_ok(Status status) {
  g_sink.add_u64(static_cast<std::uint64_t>(status));
  g_ok = g_ok && status == Status::ok;
}

void run_fk(const Scene& scene, unsigned repeats) {
  for (unsigned r = 0; r < repeats; ++r)
    for (const Sample& s : g_dataset.samples()) g_sink.add(fk_tool_point(scene.nominal, s.q_rad));
}

void run_sincos(unsigned repeats) {
  double sum = 0.0;
  for (unsigned r = 0; r < repeats; ++r) {
    for (const Sample& s : g_dataset.samples()) {
      for (int j = 0; j < kSixJoints; ++j) {
        double sine = 0.0;
        double cosine = 0.0;
        math::sincos(s.q_rad(j), &sine, &cosine);
        sum += sine + cosine;
      }
    }
  }
  g_sink.add(sum);
}

void run_jacobian(const Scene& scene, unsigned repeats) {
  ToolPointJacobian jacobian;
  for (unsigned r = 0; r < repeats; ++r)
    for (const Sample& s : g_dataset.samples()) g_sink.add(tool_point_jacobian(scene.nominal, s.q_rad, &jacobian));
  g_sink.add(jacobian);
}

void run_cost(const Scene& scene, unsigned repeats, Span<const Sample> samples, CostKind kind, BaseFrame frame) {
  for (unsigned r = 0; r < repeats; ++r) {
    RigidTransform base = scene.base_to_tracker;
    double cost = 0.0;
    expect_ok(evaluate_cost(scene.nominal, samples, kind, frame, &base, &cost));
    g_sink.add(cost);
  }
}

void run_metrics(const Scene& scene, unsigned repeats) {
  expect_ok(g_dataset.split(kDefaultTrainFraction, 7));
  for (unsigned r = 0; r < repeats; ++r) {
    const AccuracyReport report = accuracy_report(scene.nominal, scene.base_to_tracker, g_dataset);
    g_sink.add(report.test.mae(ErrorAxis::norm_3d));
  }
}

/// The training part of a 70/30 split: what a solver evaluates its cost on.
Span<const Sample> training_samples() {
  expect_ok(g_dataset.split(kDefaultTrainFraction, 7));
  return g_dataset.train();
}

bool run_workload(const char* name, unsigned repeats, const Scene& scene) {
  const auto is = [name](const char* candidate) { return std::strcmp(name, candidate) == 0; };
  const bool all = is("all");
  if (all || is("sincos")) run_sincos(repeats);
  if (all || is("fk")) run_fk(scene, repeats);
  if (all || is("jacobian")) run_jacobian(scene, repeats);
  if (all || is("cost")) run_cost(scene, repeats, g_dataset.samples(), CostKind::mean_abs_3d, BaseFrame::refit);
  if (all || is("cost_fixed")) run_cost(scene, repeats, g_dataset.samples(), CostKind::sum_squares, BaseFrame::fixed);
  if (all || is("cost_358")) run_cost(scene, repeats, training_samples(), CostKind::mean_abs_3d, BaseFrame::refit);
  if (all || is("metrics")) run_metrics(scene, repeats);
  return all || is("fill") || is("sincos") || is("fk") || is("jacobian") || is("cost") || is("cost_fixed") ||
         is("cost_358") || is("metrics");
}

void print_unsigned(std::uint64_t value) {
  char buffer[24];
  char* p = buffer + sizeof buffer;
  *--p = '\0';
  do {
    *--p = static_cast<char>('0' + value % 10U);
    value /= 10U;
  } while (value != 0);
  board_write(p);
}

void print_hex(std::uint64_t value) {
  char buffer[17];
  for (int i = 15; i >= 0; --i) {
    buffer[i] = "0123456789abcdef"[value & 0xFU];
    value >>= 4U;
  }
  buffer[16] = '\0';
  board_write("0x");
  board_write(buffer);
}

/// Splits "workload repeats" from the command line; defaults: all, 1.
void parse_command_line(char* workload, std::size_t capacity, unsigned* repeats) {
  const char* line = board_command_line();
  std::size_t n = 0;
  while (line[n] != '\0' && line[n] != ' ' && n + 1 < capacity) {
    workload[n] = line[n];
    ++n;
  }
  workload[n] = '\0';
  if (n == 0) std::strcpy(workload, "all");
  const char* digits = line + n;
  while (*digits == ' ') ++digits;
  *repeats = 0;
  for (; *digits >= '0' && *digits <= '9'; ++digits) *repeats = *repeats * 10U + static_cast<unsigned>(*digits - '0');
  if (*repeats == 0) *repeats = 1;
}

}  // namespace
}  // namespace hivecal

int main() {
  using namespace hivecal;
  char workload[16];
  unsigned repeats = 1;
  parse_command_line(workload, sizeof workload, &repeats);
  const Scene scene = fill_dataset();
  if (!run_workload(workload, repeats, scene)) {
    board_write("core probe: unknown workload\n");
    return 1;
  }
  board_write("core probe: ");
  board_write(workload);
  board_write(" x");
  print_unsigned(repeats);
  board_write(", result digest ");
  print_hex(g_sink.value());
  board_write(", stack high-water ");
  print_unsigned(board_stack_used_bytes());
  board_write(" of ");
  print_unsigned(board_stack_size_bytes());
  board_write(" bytes\n");
  return g_ok ? 0 : 1;
}
