// The core golden digest: FK, Jacobian, transform fit, cost and metrics over a fixed synthetic
// data set, hashed over their raw bits. Shared by the GoogleTest suite (tests/lib/solve/test_golden_core.cpp)
// and the bare-metal firmware (tests/firmware/test_golden.cpp), so both compute exactly the same
// thing and compare it with the same committed value. Heap-free, exception-free.
#pragma once

#include <cstdint>

#include "hivecal/core/digest.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/cost.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// The committed value: every target and optimisation level must reproduce it.
inline constexpr std::uint64_t kCoreGoldenDigest = 0xea24abedaf4fcffbULL;

/// Computes the core digest (300 samples; the data set is static: 21.6 KB, not on the stack).
inline std::uint64_t core_golden_digest() {
  Random random(20261122);
  RobotModel truth = perturbed_model(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4);
  truth.tool_m << 0.002, -0.001, 0.1695;
  static Dataset<300> dataset;
  dataset.clear();
  fill_dataset(truth, example_base_to_tracker(), 300, 1e-5, &random, &dataset);
  Digest digest;
  for (const Sample& s : dataset.samples()) {
    digest.add(s.q_rad.head(kSixJoints));
    digest.add(s.point_m);
    const RigidTransform flange = fk_flange(truth, s.q_rad);
    digest.add(flange.rotation);
    digest.add(flange.translation_m);
    ToolPointJacobian jacobian;
    digest.add(tool_point_jacobian(truth, s.q_rad, &jacobian));
    digest.add(jacobian.leftCols(model_param_count(truth)));
  }
  RobotModel nominal = nominal_model(RobotType::ur5);
  nominal.tool_m = truth.tool_m;
  RigidTransform base;
  digest.add_u64(static_cast<std::uint64_t>(fit_base_to_tracker(nominal, dataset.samples(), &base)));
  digest.add(base.rotation);
  digest.add(base.translation_m);
  for (CostKind kind : {CostKind::mean_abs_3d, CostKind::sum_squares}) {
    double cost = 0.0;
    RigidTransform refit;
    digest.add_u64(
        static_cast<std::uint64_t>(evaluate_cost(nominal, dataset.samples(), kind, BaseFrame::refit, &refit, &cost)));
    digest.add(cost);
  }
  digest.add_u64(static_cast<std::uint64_t>(dataset.split(0.7, 3)));
  const AccuracyReport report = accuracy_report(nominal, base, dataset);
  for (const ErrorStats* stats : {&report.train, &report.test, &report.overall}) {
    for (int axis = 0; axis < kErrorAxisCount; ++axis) {
      digest.add(stats->mae_m[axis]);
      digest.add(stats->sigma_m[axis]);
      digest.add(stats->max_m[axis]);
    }
  }
  return digest.value();
}

}  // namespace hivecal::test
