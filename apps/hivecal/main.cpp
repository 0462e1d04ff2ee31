// hivecal command-line tool. For now: `hivecal demo`, a small simulated check of the
// core library (nominal vs true geometry seen through a fitted tracker transform).
#include <cstdio>
#include <cstring>

#include "hivecal/cost.hpp"
#include "hivecal/dataset.hpp"
#include "hivecal/kinematics.hpp"
#include "hivecal/metrics.hpp"
#include "hivecal/random.hpp"
#include "commands.hpp"

namespace {

int run_demo() {
  using namespace hivecal;
  Random random(1);
  const RobotModel nominal = nominal_model(RobotType::ur5);
  RobotModel truth = nominal;
  for (DhJoint& joint : truth.joints) {
    joint.d_m += 2e-4 * random.normal();
    joint.a_m += 2e-4 * random.normal();
  }
  RigidTransform tracker_pose;
  tracker_pose.translation_m << 2.5, -1.0, 0.3;
  static Dataset<> dataset;
  for (int i = 0; i < 38; ++i) {
    JointVector q;
    q << random.uniform(-3, 3), random.uniform(-2.5, -0.6), random.uniform(-2.2, 2.2), random.uniform(-3, 0),
        random.uniform(-2.8, -0.3), random.uniform(-3, 3);
    Vec3 noise(random.normal(), random.normal(), random.normal());
    if (dataset.add(q, tracker_pose.apply(fk_tool_point(truth, q)) + 1e-5 * noise) != Status::ok) return 1;
  }
  for (const auto& [name, model] : {std::pair<const char*, RobotModel>{"nominal", nominal}, {"true", truth}}) {
    RigidTransform base;
    const Status fit = fit_base_to_tracker(model, dataset.samples(), &base);
    if (fit != Status::ok) {
      std::fprintf(stderr, "hivecal: base fit failed: %s\n", status_message(fit));
      return 1;
    }
    const ErrorStats stats = position_error_stats(model, base, dataset.samples());
    std::printf("%-8s geometry: MAE 3D %.1f um, sigma %.1f um over %zu samples\n", name,
                stats.mae(ErrorAxis::norm_3d) * 1e6, stats.sigma(ErrorAxis::norm_3d) * 1e6, stats.count);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "demo") == 0) return run_demo();
  if (argc >= 2 && std::strcmp(argv[1], "predict") == 0) return hivecal::cli::predict_main(argc - 2, argv + 2);
  std::fprintf(stderr, "usage: hivecal demo | predict [--help]\n");
  return 2;
}
