// hivecal demo: a small simulated check of the core library (nominal vs true geometry
// seen through a fitted tracker transform). The full session is `hivecal session`.
#include <cstdio>
#include <memory>
#include <utility>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/solve/cost.hpp"

namespace hivecal::cli {

int demo_main(int argc, char** argv) {
  Options options;
  const int parsed = parse_options(kDemoCommand,
                                   "Simulates 38 poses of a perturbed UR5 and compares the fit of the\n"
                                   "nominal and the true geometry.",
                                   {}, argc, argv, &options);
  if (parsed >= 0) return parsed;
  Random random(1);
  const RobotModel nominal = nominal_model(RobotType::ur5);
  RobotModel truth = nominal;
  for (DhJoint& joint : model_joints(&truth)) {
    joint.d_m += 2e-4 * random.normal();
    joint.a_m += 2e-4 * random.normal();
  }
  RigidTransform tracker_pose;
  tracker_pose.translation_m << 2.5, -1.0, 0.3;
  const auto storage = std::make_unique<Dataset<>>();  // a fresh set for each run, off the stack
  Dataset<>& dataset = *storage;
  for (int i = 0; i < 38; ++i) {
    JointVector q;
    q << random.uniform(-3, 3), random.uniform(-2.5, -0.6), random.uniform(-2.2, 2.2), random.uniform(-3, 0),
        random.uniform(-2.8, -0.3), random.uniform(-3, 3);
    Vec3 noise;
    noise << random.normal(), random.normal(), random.normal();  // defined draw order
    if (dataset.add(q, tracker_pose.apply(fk_tool_point(truth, q)) + 1e-5 * noise) != Status::ok) {
      return exit_with(kDemoCommand, Error::failure("a simulated sample does not fit the dataset"));
    }
  }
  for (const auto& [name, model] : {std::pair<const char*, RobotModel>{"nominal", nominal}, {"true", truth}}) {
    RigidTransform base;
    const Status fit = fit_base_to_tracker(model, dataset.samples(), &base);
    if (fit != Status::ok)
      return exit_with(kDemoCommand, Error::failure(std::string("base fit failed: ") + status_message(fit)));
    const ErrorStats stats = position_error_stats(model, base, dataset.samples());
    std::printf("%-8s geometry: MAE 3D %.1f um, sigma %.1f um over %zu samples\n", name,
                stats.mae(ErrorAxis::norm_3d) * 1e6, stats.sigma(ErrorAxis::norm_3d) * 1e6, stats.count);
  }
  return kExitOk;
}

}  // namespace hivecal::cli
