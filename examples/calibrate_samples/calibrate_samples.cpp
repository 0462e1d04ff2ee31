// Calibrates a UR5 from paired samples (joint positions + tracker point) with the library's
// Levenberg-Marquardt solver and prints the held-out accuracy before and after.
// The samples are simulated here (a UR5 whose geometry is off by ~0.3 mm / 0.3 mrad, seen by
// a tracker 3 m away with 10 um noise); real ones come from `hivecal extract` or your own code.
#include <cstdio>

#include "hivecal/hivecal.hpp"  // the whole library; single headers build faster

namespace {

using namespace hivecal;

/// The arm as it really is: nominal UR5 plus Gaussian errors on every DH value.
RobotModel simulated_truth(Random* random) {
  RobotModel truth = nominal_model(RobotType::ur5);
  for (DhJoint& joint : truth.joints) {
    joint.d_m += 3e-4 * random->normal();
    joint.a_m += 3e-4 * random->normal();
    joint.theta_offset_rad += 3e-4 * random->normal();
  }
  truth.tool_m << 0.001, -0.002, 0.15;
  return truth;
}

/// `count` poses spread over the workspace, measured by a tracker at `tracker` [m].
void simulate_samples(const RobotModel& truth, const RigidTransform& tracker, int count, Random* random,
                      DatasetBase* dataset) {
  for (int i = 0; i < count; ++i) {
    JointVector q_rad;
    q_rad << random->uniform(-3.0, 3.0), random->uniform(-2.6, -0.5), random->uniform(-2.4, 2.4),
        random->uniform(-3.0, 0.0), random->uniform(-2.8, -0.3), random->uniform(-3.0, 3.0);
    Vec3 noise_m;
    noise_m << random->normal(), random->normal(), random->normal();
    (void)dataset->add(q_rad, tracker.apply(fk_tool_point(truth, q_rad)) + 1e-5 * noise_m);
  }
}

}  // namespace

int main() {
  Random random(7);
  const RobotModel truth = simulated_truth(&random);
  RigidTransform tracker;
  tracker.translation_m << 2.5, -1.2, 0.4;

  static Dataset<200> dataset;  // 14 kB: static, like the solver's workspace
  simulate_samples(truth, tracker, 200, &random, &dataset);
  if (dataset.split(0.7, 1) != Status::ok) return 1;

  // Start from the datasheet geometry with the tool as designed.
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m << 0.0, 0.0, 0.15;
  RigidTransform start_base;
  Status status = fit_base_to_tracker(start, dataset.train(), &start_base);
  if (status != Status::ok) {
    std::printf("base fit failed: %s\n", status_message(status));
    return 1;
  }

  static LmWorkspace workspace;  // 37 kB of scratch: never on a small stack
  LmResult result;
  status = calibrate_lm(start, &start_base, dataset.train(), LmOptions(), &workspace, &result);
  if (status != Status::ok) {
    std::printf("calibration failed: %s\n", status_message(status));
    return 1;
  }

  const ErrorStats before = position_error_stats(start, start_base, dataset.test());
  const ErrorStats after = position_error_stats(result.model, result.base_to_tracker, dataset.test());
  std::printf("%zu train / %zu test samples, %d LM iterations (%s), %d of %d parameters estimated\n",
              dataset.train().size(), dataset.test().size(), result.iterations, lm_termination_name(result.termination),
              result.identifiability.kept_count(), kFullParamCount);
  std::printf("test MAE: nominal %.1f um -> calibrated %.1f um\n", before.mae(ErrorAxis::norm_3d) * 1e6,
              after.mae(ErrorAxis::norm_3d) * 1e6);
  // The calibration must at least halve the error on samples it never saw.
  return after.mae(ErrorAxis::norm_3d) < 0.5 * before.mae(ErrorAxis::norm_3d) ? 0 : 1;
}
