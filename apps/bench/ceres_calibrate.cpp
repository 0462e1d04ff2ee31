// The whole-process peer of `hivecal calibrate --samples S --method lm` (scripts/bench-process.sh):
// what an engineer writes with Ceres for the same fit. It reads paired samples (`q1..q6,x,y,z`
// in rad and m, one header line: make_samples' output), starts from the nominal UR5 with the
// base fitted in closed form (hivecal's fit_base_to_tracker, as hivecal's LM starts), estimates
// the parameters it is told to (the names hivecal's result.json lists under "identifiability"
// / "estimated"; an engineer fixes the unidentifiable ones by hand) with Ceres' LM
// (ceres_peer: AutoDiffCostFunction, DENSE_QR, hivecal's tolerances) and writes the calibrated
// DH table, tool point and base as robot-calibration/1 JSON, which `hivecal predict` reads.
// Not a test: its figures go to docs/solver-lm.md.
//
//   ceres_calibrate SAMPLES.csv NAME[,NAME...] OUT.json
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "ceres_fit.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/rigid_fit.hpp"

namespace {

/// The samples of a `q1..q6,x,y,z` file; false on a row that is not nine numbers.
bool read_samples(const char* path, std::vector<hivecal::Sample>* samples) {
  std::FILE* file = std::fopen(path, "r");
  if (file == nullptr) return false;
  char line[1024];
  bool ok = std::fgets(line, sizeof line, file) != nullptr;  // the header
  while (ok && std::fgets(line, sizeof line, file) != nullptr) {
    hivecal::Sample s;
    double v[9];
    ok = std::sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                     &v[7], &v[8]) == 9;
    for (int k = 0; k < 6; ++k) s.q_rad(k) = v[k];
    s.point_m = hivecal::Vec3(v[6], v[7], v[8]);
    samples->push_back(s);
  }
  std::fclose(file);
  return ok && !samples->empty();
}

/// The mask of the comma-separated parameter names (hivecal's names: theta1, d1, ..., base_tz);
/// false on a name that is not one of the 33.
bool parse_estimated(const char* list, hivecal::ParamMask* mask) {
  *mask = 0;
  const std::string names = list;
  std::size_t begin = 0;
  while (begin <= names.size()) {
    const std::size_t end = std::min(names.find(',', begin), names.size());
    const std::string name = names.substr(begin, end - begin);
    int found = -1;
    for (int k = 0; k < hivecal::rigid_param_count(hivecal::kSixJoints); ++k) {
      if (name == hivecal::full_param_name(k, hivecal::kSixJoints)) found = k;
    }
    if (found < 0) return false;
    *mask |= hivecal::param_bit(found);
    begin = end + 1;
  }
  return true;
}

void write_result(std::FILE* out, const hivecal::RobotModel& model, const hivecal::RigidTransform& base) {
  std::fprintf(out, "{\n  \"format\": \"robot-calibration/1\",\n  \"robot\": \"ur5\",\n");
  std::fprintf(out, "  \"convention\": \"standard-dh\",\n  \"dh\": [\n");
  for (int j = 0; j < hivecal::kSixJoints; ++j) {
    const hivecal::DhJoint& dh = model.joints[j];
    std::fprintf(out, "    {\"theta_offset\": %.17g, \"d\": %.17g, \"a\": %.17g, \"alpha\": %.17g}%s\n",
                 dh.theta_offset_rad, dh.d_m, dh.a_m, dh.alpha_rad, j + 1 < hivecal::kSixJoints ? "," : "");
  }
  std::fprintf(out, "  ],\n  \"tool\": [%.17g, %.17g, %.17g],\n  \"base_to_tracker\": [\n", model.tool_m.x(),
               model.tool_m.y(), model.tool_m.z());
  for (int i = 0; i < 3; ++i) {
    std::fprintf(out, "    [%.17g, %.17g, %.17g, %.17g],\n", base.rotation(i, 0), base.rotation(i, 1),
                 base.rotation(i, 2), base.translation_m(i));
  }
  std::fprintf(out, "    [0, 0, 0, 1]\n  ],\n  \"metrics\": {}\n}\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hivecal;
  std::vector<Sample> samples;
  ParamMask estimated = 0;
  if (argc != 4 || !parse_estimated(argv[2], &estimated)) {
    std::fprintf(stderr, "usage: ceres_calibrate SAMPLES.csv NAME[,NAME...] OUT.json   (names: theta1 .. base_tz)\n");
    return 2;
  }
  if (!read_samples(argv[1], &samples)) {
    std::fprintf(stderr, "ceres_calibrate: %s: not a q1..q6,x,y,z file\n", argv[1]);
    return 3;
  }
  const Span<const Sample> span(samples.data(), samples.size());
  const RobotModel start = nominal_model(RobotType::ur5);
  RigidTransform start_base;
  if (fit_base_to_tracker(start, span, &start_base) != Status::ok) {
    std::fprintf(stderr, "ceres_calibrate: no start base\n");
    return 1;
  }
  ceres_fit::Input input;
  ceres_fit::prepare(start, start_base, span, estimated, &input);
  const ceres_fit::Outcome solved = ceres_fit::solve(start_base, input, false);
  if (!solved.usable) {
    std::fprintf(stderr, "ceres_calibrate: Ceres found no usable solution\n");
    return 1;
  }
  std::FILE* out = std::fopen(argv[3], "w");
  if (out == nullptr) return 3;
  write_result(out, solved.model, solved.base);
  std::printf("ceres_calibrate: %zu samples, %d parameters, %d iterations\n", samples.size(), mask_count(estimated),
              solved.iterations);
  return std::fclose(out) == 0 ? 0 : 3;
}
