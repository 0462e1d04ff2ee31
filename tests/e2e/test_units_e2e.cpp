// Units and plausibility through the whole command (issue 11): one simulated session written in
// millimetres and degrees (no unit in any header) calibrates, with --length-unit mm
// --angle-unit deg, to the SI session's result within 1e-12, from logs and from paired samples;
// predict and extract take the options too; without them the hint; an implausible
// calibration.conf is refused; a fit beyond the change bounds writes its result and exits 5.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/streams.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/log_forms.hpp"
#include "textio/robot_description.hpp"
#include "textio/logs.hpp"
#include "record/result_json.hpp"

namespace hivecal::units_e2e_test {
namespace {

constexpr double kDegPerRad = 57.29577951308232;

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// A CSV with every numeric field of the columns in [first, last] multiplied by `scale`
/// (the header kept as it is: no unit in it).
std::string scaled_csv(const std::string& text, std::size_t first, std::size_t last, double scale) {
  std::string out;
  std::size_t start = 0;
  bool header = true;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    if (header || line.empty()) {
      out += line + "\n";
      header = false;
      continue;
    }
    std::size_t column = 0;
    std::size_t at = 0;
    std::string row;
    for (;;) {
      const std::size_t comma = std::min(line.find(',', at), line.size());
      const std::string field = line.substr(at, comma - at);
      row += (column == 0 ? "" : ",") +
             (column >= first && column <= last ? g17(std::strtod(field.c_str(), nullptr) * scale) : field);
      ++column;
      if (comma == line.size()) break;
      at = comma + 1;
    }
    out += row + "\n";
  }
  return out;
}

bool write(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return std::fclose(f) == 0 && ok;
}

record::CalibrationFile result_of(const std::string& path) {
  record::CalibrationFile file;
  const port::Error read = record::read_calibration_json(path, &file);
  EXPECT_TRUE(read.ok()) << path << ": " << read.message;
  return file;
}

void expect_same(const record::CalibrationFile& a, const record::CalibrationFile& b, double tolerance,
                 const char* what) {
  const ModelParams pa = to_params(a.model);
  const ModelParams pb = to_params(b.model);
  EXPECT_LE((pa - pb).cwiseAbs().maxCoeff(), tolerance) << what;
  EXPECT_LE((a.base_to_tracker.translation_m - b.base_to_tracker.translation_m).cwiseAbs().maxCoeff(), tolerance)
      << what;
  EXPECT_NEAR(a.metrics.test.mae_m[3], b.metrics.test.mae_m[3], tolerance) << what;
  EXPECT_EQ(a.metrics.test.count, b.metrics.test.count) << what;
}

class UnitsEndToEnd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(test::make_temp_dir("hivecal_units"));
    ASSERT_EQ(
        test::run(sim::simulate_main, {"--out-dir", *dir_, "--waypoints", "12", "--duration-s", "150", "--seed", "5"}),
        cli::kExitOk);
    // The same session with joints in degrees and points in millimetres, no unit in the headers.
    ASSERT_TRUE(write(*dir_ + "/robot_deg.csv",
                      scaled_csv(test::read_text_file(*dir_ + "/robot_joints.csv"), 1, 6, kDegPerRad)));
    ASSERT_TRUE(write(*dir_ + "/tracker_mm.csv", scaled_csv(test::read_text_file(*dir_ + "/tracker.csv"), 1, 3, 1e3)));
  }
  static void TearDownTestSuite() {
    std::system(("rm -rf '" + *dir_ + "'").c_str());
    delete dir_;
  }
  static std::string path(const std::string& name) { return *dir_ + "/" + name; }
  /// calibrate with `args`, LM alone unless they name a method (the units are read before any
  /// fit; the population stage would only add time).
  static int calibrate(std::vector<std::string> args) {
    if (std::find(args.begin(), args.end(), "--method") == args.end()) args.insert(args.end(), {"--method", "lm"});
    args.push_back("--quiet");
    return test::run(cli::calibrate_main, args);
  }
  static std::string* dir_;
};
std::string* UnitsEndToEnd::dir_ = nullptr;

TEST_F(UnitsEndToEnd, LogsInMillimetresAndDegreesCalibrateAsSi) {
  ASSERT_EQ(
      calibrate({"--robot", path("robot_joints.csv"), "--tracker", path("tracker.csv"), "--out", path("si.json")}),
      cli::kExitOk);
  ASSERT_EQ(calibrate({"--robot", path("robot_deg.csv"), "--tracker", path("tracker_mm.csv"), "--length-unit", "mm",
                       "--angle-unit", "deg", "--out", path("mmdeg.json")}),
            cli::kExitOk);
  expect_same(result_of(path("si.json")), result_of(path("mmdeg.json")), 1e-12, "logs in mm and deg");
  // Without the options: refused with the hint, no result.
  EXPECT_EQ(calibrate({"--robot", path("robot_deg.csv"), "--tracker", path("tracker.csv"), "--out", path("no1.json")}),
            cli::kExitBadInput);
  EXPECT_EQ(
      calibrate({"--robot", path("robot_joints.csv"), "--tracker", path("tracker_mm.csv"), "--out", path("no2.json")}),
      cli::kExitBadInput);
  struct stat info {};
  EXPECT_NE(::stat(path("no1.json").c_str(), &info), 0);
  EXPECT_NE(::stat(path("no2.json").c_str(), &info), 0);
  EXPECT_EQ(calibrate({"--samples", path("x.csv"), "--length-unit", "cm", "--out", path("no3.json")}), cli::kExitUsage);
  EXPECT_EQ(calibrate({"--samples", path("x.csv"), "--angle-unit", "grad", "--out", path("no3.json")}),
            cli::kExitUsage);
}

TEST_F(UnitsEndToEnd, SamplesInMillimetresAndDegreesCalibrateAsSiAndExtractTakesTheUnits) {
  // extract with the units writes the SI session's samples.
  ASSERT_EQ(test::run(streams::extract_main, {"--robot", path("robot_joints.csv"), "--tracker", path("tracker.csv"),
                                              "--samples", path("samples.csv")}),
            cli::kExitOk);
  ASSERT_EQ(test::run(streams::extract_main,
                      {"--robot", path("robot_deg.csv"), "--tracker", path("tracker_mm.csv"), "--angle-unit", "deg",
                       "--length-unit", "mm", "--samples", path("samples_from_mmdeg.csv")}),
            cli::kExitOk);
  const std::string si = test::read_text_file(path("samples.csv"));
  const std::string from_mmdeg = test::read_text_file(path("samples_from_mmdeg.csv"));
  EXPECT_EQ(std::count(si.begin(), si.end(), '\n'), std::count(from_mmdeg.begin(), from_mmdeg.end(), '\n'));
  // Paired samples in mm and deg.
  std::string mmdeg = scaled_csv(si, 0, 5, kDegPerRad);
  mmdeg = scaled_csv(mmdeg, 6, 8, 1e3);
  ASSERT_TRUE(write(path("samples_mmdeg.csv"), mmdeg));
  ASSERT_EQ(calibrate({"--samples", path("samples.csv"), "--out", path("s_si.json")}), cli::kExitOk);
  ASSERT_EQ(calibrate({"--samples", path("samples_mmdeg.csv"), "--length-unit", "mm", "--angle-unit", "deg", "--out",
                       path("s_mmdeg.json")}),
            cli::kExitOk);
  // The converted values differ from the SI file's by the rounding of the conversion (an ulp);
  // the job's repeated LM runs (blunder and significance tests) carry that to ~3e-11 m, far
  // below anything physical, so the bound here is 1e-10 m.
  expect_same(result_of(path("s_si.json")), result_of(path("s_mmdeg.json")), 1e-10, "samples in mm and deg");
  EXPECT_EQ(calibrate({"--samples", path("samples_mmdeg.csv"), "--angle-unit", "deg", "--out", path("s_no.json")}),
            cli::kExitBadInput);  // points still read as metres
}

TEST_F(UnitsEndToEnd, PredictTakesJointsInDegrees) {
  ASSERT_EQ(calibrate({"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--out", path("p.json")}),
            cli::kExitOk);
  // The first ten robot rows as poses (t,q1..q6), in rad and in degrees.
  const std::string robot = test::read_text_file(path("robot_joints.csv"));
  std::size_t cut = 0;
  for (int line = 0; line < 11; ++line) cut = robot.find('\n', cut) + 1;
  ASSERT_TRUE(write(path("poses.csv"), robot.substr(0, cut)));
  ASSERT_TRUE(write(path("poses_deg.csv"), scaled_csv(robot.substr(0, cut), 1, 6, kDegPerRad)));
  ASSERT_EQ(test::run(cli::predict_main,
                      {"--calibration", path("p.json"), "--joints", path("poses.csv"), "--out", path("pred_si.csv")}),
            cli::kExitOk);
  ASSERT_EQ(test::run(cli::predict_main, {"--calibration", path("p.json"), "--joints", path("poses_deg.csv"),
                                          "--angle-unit", "deg", "--out", path("pred_deg.csv")}),
            cli::kExitOk);
  const std::string a = test::read_text_file(path("pred_si.csv"));
  const std::string b = test::read_text_file(path("pred_deg.csv"));
  ASSERT_EQ(std::count(a.begin(), a.end(), '\n'), 11);
  double worst = 0.0;
  std::size_t ia = a.find('\n') + 1;
  std::size_t ib = b.find('\n') + 1;
  while (ia < a.size() && ib < b.size()) {
    char* ea = nullptr;
    char* eb = nullptr;
    worst = std::max(worst, std::fabs(std::strtod(a.c_str() + ia, &ea) - std::strtod(b.c_str() + ib, &eb)));
    ia = static_cast<std::size_t>(ea - a.c_str()) + 1;
    ib = static_cast<std::size_t>(eb - b.c_str()) + 1;
  }
  EXPECT_LE(worst, 1e-12);
  EXPECT_EQ(test::run(cli::predict_main, {"--calibration", path("p.json"), "--joints", path("poses_deg.csv"), "--out",
                                          path("pred_no.csv")}),
            cli::kExitBadInput);
}

TEST_F(UnitsEndToEnd, FitBeyondTheBoundsWritesItsResultAndExitsFive) {
  // The simulated truth is tens of micrometres from nominal: a 1 um bound is exceeded.
  ASSERT_EQ(calibrate({"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--method", "lm",
                       "--max-change-mm", "0.001", "--out", path("warned.json")}),
            cli::kExitWarnings);
  const std::string json = test::read_text_file(path("warned.json"));
  EXPECT_NE(json.find("\"warnings\""), std::string::npos);
  EXPECT_NE(json.find("more than 0.001 mm (--max-change-mm)"), std::string::npos);
  (void)result_of(path("warned.json"));  // a complete, readable result
  ASSERT_EQ(calibrate({"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--method", "lm", "--out",
                       path("quiet.json")}),
            cli::kExitOk);
  EXPECT_EQ(test::read_text_file(path("quiet.json")).find("\"warnings\""), std::string::npos);
  EXPECT_EQ(calibrate({"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--max-change-deg", "0", "--out",
                       path("bad.json")}),
            cli::kExitUsage);
}

TEST_F(UnitsEndToEnd, ImplausibleUrCalibrationIsRefused) {
  ASSERT_TRUE(write(path("other.conf"),
                    "[mounting]\ndelta_theta = [0, 0, 0, 0, 0, 0]\ndelta_a = [0, 0.2, -0.1, 0, 0, 0]\n"
                    "delta_d = [0, 0, 0, 0, 0, 0]\ndelta_alpha = [0, 0, 0, 0, 0, 0]\n"));
  EXPECT_EQ(calibrate({"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--ur-calibration",
                       path("other.conf"), "--out", path("conf.json")}),
            cli::kExitBadInput);
  struct stat info {};
  EXPECT_NE(::stat(path("conf.json").c_str(), &info), 0);
}

#if HIVECAL_HAVE_SQLITE3
TEST_F(UnitsEndToEnd, BagJointsAreRadians) {
  const textio::RobotLog robot = textio::read_robot_log(path("robot_joints.csv"));
  ASSERT_TRUE(robot.ok) << robot.error;
  const std::string bag = path("bag");
  ASSERT_EQ(::mkdir(bag.c_str(), 0755), 0);
  ASSERT_TRUE(test::write_ros2_bag(bag, robot.records));
  textio::RobotLogOptions deg;
  deg.units.angle = "deg";
  const textio::RobotLog refused = textio::read_robot_log(bag, deg);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.error.find("joint positions are in rad (sensor_msgs/JointState): --angle-unit deg does not apply"),
            std::string::npos)
      << refused.error;
  textio::RobotLogOptions rad;
  rad.units.angle = "rad";
  EXPECT_TRUE(textio::read_robot_log(bag, rad).ok);
}
#endif

}  // namespace
}  // namespace hivecal::units_e2e_test
