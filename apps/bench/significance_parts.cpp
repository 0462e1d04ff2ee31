// Where LM's significance test of the geometry pays, on a real arm: random parts of a tracker
// export (the job's own split: N poses train, the others test), each calibrated by the LM job
// (`--method lm`) three ways: the default (the geometry tested on small sets only), every
// identifiable parameter estimated (significance 0), and the geometry tested on every set
// (significance 2). Prints the mean held-out 3-D MAE per size; the table in docs/robust.md
// ("Where the significance test stops") comes from here.
//
//   significance_parts [export.csv] [sizes=12,20,30,35,40,50,75,100,300,1000] [parts=24]
//
// The export defaults to the shared UR10 T-Mac one (../shared/data/ur10-tmac, positions in mm,
// the probe ~109 mm from the flange), read as it is.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "textio/csv.hpp"

namespace {

using namespace hivecal;

constexpr std::size_t kMaxSamples = 4096;  // samples of the export
Dataset<kMaxSamples> all_samples;
CalibrationWorkspace<kMaxSamples> workspace;
CalibrationResult result;

/// The three ways a part is calibrated.
enum class Mode { by_default, every_parameter, tested_on_every_set };

/// Held-out 3-D MAE of the LM job (mode `mode`) trained on `size` poses of the export that
/// `seed` draws and tested on the others: the job's own split [m]; -1 when the job fails.
double heldout_mae_m(const RobotModel& start, std::size_t size, std::uint64_t seed, Mode mode) {
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.seed = seed;
  options.train_fraction = static_cast<double>(size) / static_cast<double>(all_samples.size());
  if (mode == Mode::every_parameter) options.significance_t = 0.0;
  options.significance_every_set = mode == Mode::tested_on_every_set;
  const Status status = calibrate(start, &all_samples, options, &workspace, &result);
  const CalibrationStage* fit = result.final_stage();
  if (status != Status::ok || fit == nullptr || result.train_count != size) return -1.0;
  return fit->test.mae(ErrorAxis::norm_3d);
}

std::vector<std::size_t> parse_sizes(const char* text) {
  std::vector<std::size_t> sizes;
  for (const char* p = text; *p != '\0';) {
    char* end = nullptr;
    const unsigned long value = std::strtoul(p, &end, 10);
    if (end == p) break;
    sizes.push_back(static_cast<std::size_t>(value));
    p = *end == ',' ? end + 1 : end;
  }
  return sizes;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "../shared/data/ur10-tmac/measurements_joint_configurations.csv";
  const std::vector<std::size_t> sizes = parse_sizes(argc > 2 ? argv[2] : "12,20,30,35,40,50,75,100,300,1000");
  const int parts = argc > 3 ? std::atoi(argv[3]) : 24;
  textio::InputUnits units;
  units.length = "mm";
  units.columns = {{"x", "measurement_x", ""}, {"y", "measurement_y", ""}, {"z", "measurement_z", ""}};
  const port::Error read = textio::read_samples_csv(path, &all_samples, units);
  if (!read.ok()) {
    std::fprintf(stderr, "significance_parts: %s\n", read.message.c_str());
    return 1;
  }
  RobotModel start = nominal_model(RobotType::ur10);
  start.tool_m = Vec3(0.0, 0.0, 0.109);
  const std::size_t count = all_samples.size();
  std::printf("%zu poses of %s; %d random parts per size, each predicting every other pose\n", count, path.c_str(),
              parts);
  std::printf(
      "| poses | default | every parameter | tested on every set | default / tested | default at least as good |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|\n");
  for (const std::size_t size : sizes) {
    if (size < 3 || size >= count) continue;
    double sum_m[3] = {0.0, 0.0, 0.0};
    int at_least_as_good = 0;
    int done = 0;
    for (int k = 1; k <= parts; ++k) {
      double mae_m[3];
      const Mode modes[3] = {Mode::by_default, Mode::every_parameter, Mode::tested_on_every_set};
      bool ok = true;
      for (int m = 0; m < 3; ++m)
        ok = ok && (mae_m[m] = heldout_mae_m(start, size, static_cast<std::uint64_t>(k), modes[m])) >= 0.0;
      if (!ok) continue;
      for (int m = 0; m < 3; ++m) sum_m[m] += mae_m[m];
      if (mae_m[0] <= mae_m[2]) ++at_least_as_good;
      ++done;
    }
    if (done == 0) continue;
    std::printf("| %zu | %.4f | %.4f | %.4f | %.3f | %d of %d |\n", size, sum_m[0] / done * 1e3, sum_m[1] / done * 1e3,
                sum_m[2] / done * 1e3, sum_m[0] / sum_m[2], at_least_as_good, done);
  }
  return 0;
}
