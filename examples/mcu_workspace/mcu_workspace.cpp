// Runs the Levenberg-Marquardt calibration the way a microcontroller would: every byte it
// needs is a static object of known size (no heap: operator new is disabled below), the
// samples sit in a fixed-capacity dataset, and the solver's scratch is a static workspace.
// The arm's upper-arm and forearm lengths are off by a known amount; the paper's six-length
// parameter set must find it. docs/firmware.md has the same job on a Cortex-M7.
#include <cstdio>
#include <cstdlib>
#include <new>

#include "hivecal/hivecal.hpp"  // the whole library; single headers build faster

// A firmware build links no allocator; here any C++ allocation would stop the program.
void* operator new(std::size_t) {
  std::abort();
}
void* operator new[](std::size_t) {
  std::abort();
}
void operator delete(void*) noexcept {}
void operator delete[](void*) noexcept {}
void operator delete(void*, std::size_t) noexcept {}
void operator delete[](void*, std::size_t) noexcept {}

namespace {

using namespace hivecal;

constexpr std::size_t kSampleCount = 64;

// The whole memory plan: fixed at link time, reported by the linker map on a target.
Dataset<kSampleCount> g_dataset;       ///< paired samples
JointTrig g_joint_trig[kSampleCount];  ///< per-sample sin/cos, computed once (optional)
LmWorkspace g_workspace;               ///< normal equations, factorisation, identifiability
LmResult g_result;                     ///< calibrated model, sigmas, identifiability report

/// Tool points of `truth` at a deterministic spread of poses, seen from a tracker at the base.
void measure(const RobotModel& truth) {
  for (std::size_t i = 0; i < kSampleCount; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(kSampleCount);
    JointVector q_rad;
    q_rad << -3.0 + 6.0 * s, -2.4 + 1.7 * s * s, 2.2 - 4.2 * s, -2.8 + 2.6 * (1.0 - s), -2.6 + 2.2 * s,
        6.0 * s * (1.0 - s);
    (void)g_dataset.add(q_rad, fk_tool_point(truth, q_rad));
  }
}

}  // namespace

int main() {
  RobotModel nominal = nominal_model(RobotType::ur5);
  nominal.tool_m << 0.0, 0.0, 0.1;
  RobotModel truth = nominal;
  truth.joints[1].a_m += 5e-4;  // upper arm 0.5 mm longer
  truth.joints[2].a_m -= 3e-4;  // forearm 0.3 mm shorter
  measure(truth);

  std::printf("static memory: dataset %zu B, joint trig %zu B, workspace %zu B, result %zu B\n", sizeof g_dataset,
              sizeof g_joint_trig, sizeof g_workspace, sizeof g_result);

  LmOptions options;
  options.params = LmParamSet::link_lengths;
  g_workspace.joint_trig = Span<JointTrig>(g_joint_trig);
  const RigidTransform at_base;  // the tracker sits at the robot base
  const Status status = calibrate_lm(nominal, &at_base, g_dataset.samples(), options, &g_workspace, &g_result);
  if (status != Status::ok) {
    std::printf("calibration failed: %s\n", status_message(status));
    return 1;
  }
  const double a2_error_m = g_result.model.joints[1].a_m - truth.joints[1].a_m;
  const double a3_error_m = g_result.model.joints[2].a_m - truth.joints[2].a_m;
  std::printf("%d iterations, RMS %.3g um; a2 off by %.3g um, a3 by %.3g um\n", g_result.iterations,
              g_result.rms_m * 1e6, a2_error_m * 1e6, a3_error_m * 1e6);
  // Noise-free data: the lengths must come back to well under a micrometre.
  return std::abs(a2_error_m) < 1e-6 && std::abs(a3_error_m) < 1e-6 ? 0 : 1;
}
