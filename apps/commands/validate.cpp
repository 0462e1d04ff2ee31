// hivecal validate: a calibration against a reference geometry (e.g. the simulator's
// noise-free truth.json) on fresh random poses: how far apart do they predict the tool?
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/validation.hpp"
#include "hivecal/core/random.hpp"
#include "textio/calibration_json.hpp"
#include "textio/text_util.hpp"

namespace hivecal::cli {

ValidationStats validate_on_fresh_poses(const RobotModel& model, const RigidTransform& base_to_tracker,
                                        const RobotModel& reference, const RigidTransform& reference_base_to_tracker,
                                        long poses, std::uint64_t seed) {
  Random random(seed);
  ValidationStats stats;
  double sum_m = 0.0;
  for (long i = 0; i < poses; ++i) {
    JointVector q;  // the workspace the simulator and the paper use: shoulder up, tool down-ish
    q << random.uniform(-3.0, 3.0), random.uniform(-2.6, -0.5), random.uniform(-2.4, 2.4), random.uniform(-3.0, 0.0),
        random.uniform(-2.8, -0.3), random.uniform(-3.0, 3.0);
    const Vec3 a = base_to_tracker.apply(fk_tool_point(model, q));
    const Vec3 b = reference_base_to_tracker.apply(fk_tool_point(reference, q));
    const double e = (a - b).norm();
    sum_m += e;
    stats.max_m = std::max(stats.max_m, e);
  }
  stats.poses = poses;
  stats.mae_m = poses > 0 ? sum_m / static_cast<double>(poses) : 0.0;
  return stats;
}

int validate_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result to check (robot-calibration/1 JSON)", ""},
      {"truth", "FILE", "reference geometry (robot-calibration/1 JSON, e.g. the simulator's truth.json)", ""},
      {"poses", "N", "number of fresh random poses", "1000"},
      {"seed", "N", "seed of the poses", "7"},
  };
  Options options;
  const int parsed = parse_options("validate",
                                   "Predicts the tool point of fresh random poses with both geometries (each with its\n"
                                   "own base -> tracker transform) and reports how far apart they are.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  if (options.get("calibration").empty() || options.get("truth").empty()) {
    return exit_with("validate", Error::usage("--calibration and --truth are required (see --help)"));
  }
  double poses = 0.0;
  double seed = 0.0;
  if (!textio::parse_double(options.get("poses"), &poses) || poses < 1.0 || poses > 1e7 ||
      !textio::parse_double(options.get("seed"), &seed) || seed < 0.0) {
    return exit_with("validate", Error::usage("--poses must be 1..1e7 and --seed a non-negative integer"));
  }
  textio::CalibrationFile calibration;
  textio::CalibrationFile truth;
  for (auto [path, file] : {std::pair{options.get("calibration"), &calibration}, std::pair{options.get("truth"), &truth}}) {
    const port::Error r = textio::read_calibration_json(path, file);
    if (!r.ok()) return exit_with("validate", r);
  }
  const ValidationStats stats = validate_on_fresh_poses(calibration.model, calibration.base_to_tracker, truth.model,
                                                       truth.base_to_tracker, static_cast<long>(poses),
                                                       static_cast<std::uint64_t>(seed));
  std::printf("validation on %ld fresh poses vs %s: MAE 3D %.2f um, max %.2f um\n", stats.poses,
              options.get("truth").c_str(), stats.mae_m * 1e6, stats.max_m * 1e6);
  return kExitOk;
}

}  // namespace hivecal::cli
