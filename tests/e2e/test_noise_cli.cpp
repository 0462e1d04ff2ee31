// The measurement noise a calibration reports: with repeated readings in the input, what they
// scatter (not the stated figure) is the report's noise level and the residual's yardstick;
// without, the stated --tracker-sigma-um.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"

namespace hivecal::noise_cli_test {
namespace {

/// The number after `"key": ` in `text` (NaN when absent).
double number_after(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\"" + key + "\": ");
  return at == std::string::npos ? std::nan("") : std::strtod(text.c_str() + at + key.size() + 4, nullptr);
}

/// `poses` random poses of a perturbed UR5, each read `repeats` times with `sigma_m` per axis;
/// the reading `blunder_index` (if any) `blunder_m` off in x.
std::string write_set(const test::TempDir& dir, std::size_t poses, int repeats, double sigma_m,
                      std::size_t blunder_index = SIZE_MAX, double blunder_m = 0.0) {
  static Dataset<512> written;
  written.clear();
  Random random(31);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4);
  for (std::size_t p = 0; p < poses; ++p) {
    const JointVector q = test::random_joints(&random);
    const Vec3 point_m = test::example_base_to_tracker().apply(fk_tool_point(truth, q));
    for (int r = 0; r < repeats; ++r) {
      Vec3 measured_m = point_m + sigma_m * Vec3(random.normal(), random.normal(), random.normal());
      if (written.size() == blunder_index) measured_m.x() += blunder_m;
      (void)written.add(q, measured_m);
    }
  }
  return dir.write("set.csv", textio::format_samples_csv(written.samples(), kSixJoints));
}

std::string calibrate(const test::TempDir& dir, const std::string& samples, bool keep_outliers = true) {
  const std::string result = dir.path() + "/result.json";
  std::vector<std::string> args = {"--samples", samples,   "--method",           "lm", "--out",
                                   result,      "--quiet", "--tracker-sigma-um", "10"};
  if (keep_outliers) args.push_back("--keep-outliers");
  const int code = test::run(cli::calibrate_main, args);
  EXPECT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << code;  // warnings: the tool moves far
  std::string text;
  EXPECT_TRUE(port::read_whole_file(result, port::kMaxTextInputBytes, &text).ok());
  return text;
}

TEST(NoiseCli, RepeatedReadingsGiveTheMeasuredNoise) {
  const test::TempDir dir("hivecal_noise");
  ASSERT_FALSE(dir.path().empty());
  const std::string text = calibrate(dir, write_set(dir, 60, 4, 30e-6));  // stated 10 um, true 30 um
  EXPECT_NE(text.find("\"noise_source\": \"repeated readings\""), std::string::npos);
  EXPECT_NE(text.find("240 readings of 60 repeated points scatter"), std::string::npos);
  EXPECT_NE(text.find("the tracker's measured"), std::string::npos);
  const double noise_m = number_after(text, "noise_sigma_m");
  EXPECT_NEAR(noise_m, 30e-6, 0.12 * 30e-6);  // 180 degrees of freedom per axis
}

// A blunder among the readings is not noise: what the blunder search sets aside does not count.
TEST(NoiseCli, ABlunderSetAsideIsNotNoise) {
  const test::TempDir dir("hivecal_noise");
  ASSERT_FALSE(dir.path().empty());
  const std::string text = calibrate(dir, write_set(dir, 60, 4, 30e-6, 101, 5e-3), false);  // 5 mm on one reading
  EXPECT_NE(text.find("\"blunder_verdict\": \"removed\""), std::string::npos);
  EXPECT_NE(text.find("\"noise_source\": \"repeated readings\""), std::string::npos);
  EXPECT_NEAR(number_after(text, "noise_sigma_m"), 30e-6, 0.12 * 30e-6);  // 5 mm would make it ~0.3 mm
}

// Identical repeated readings (rounded, or simulated without noise) say nothing of the tracker:
// the stated noise, and a line that says why.
TEST(NoiseCli, IdenticalRepeatsGiveTheStatedNoise) {
  const test::TempDir dir("hivecal_noise");
  ASSERT_FALSE(dir.path().empty());
  const std::string text = calibrate(dir, write_set(dir, 60, 4, 0.0));
  EXPECT_EQ(text.find("noise_source"), std::string::npos);
  EXPECT_NE(text.find("240 readings of 60 repeated points are identical"), std::string::npos);
  EXPECT_DOUBLE_EQ(number_after(text, "noise_sigma_m"), 10e-6);
}

TEST(NoiseCli, WithoutRepeatsTheStatedNoise) {
  const test::TempDir dir("hivecal_noise");
  ASSERT_FALSE(dir.path().empty());
  const std::string text = calibrate(dir, write_set(dir, 120, 1, 30e-6));
  EXPECT_EQ(text.find("noise_source"), std::string::npos);
  EXPECT_NE(text.find("the tracker's stated"), std::string::npos);
  EXPECT_DOUBLE_EQ(number_after(text, "noise_sigma_m"), 10e-6);
}

// Joints written to 0.01 deg (as a UR pendant exports them) are read with that rounding's noise,
// sigma = 0.01 deg / sqrt(12): through a UR5's reach ~20-30 um at the tool, far above a 1 um
// tracker. The measurement noise takes it in, and the fit's residual is then at the noise (1x), not
// "unmodelled effects" at 20x the tracker's.
TEST(NoiseCli, JointsWrittenRoundedAddTheirNoise) {
  const test::TempDir dir("hivecal_noise");
  ASSERT_FALSE(dir.path().empty());
  Random random(47);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4);
  std::string text = "q1 [deg],q2 [deg],q3 [deg],q4 [deg],q5 [deg],q6 [deg],x,y,z\n";
  for (int p = 0; p < 200; ++p) {
    const JointVector q = test::random_joints(&random);
    const Vec3 point_m = test::example_base_to_tracker().apply(fk_tool_point(truth, q)) +
                         1e-6 * Vec3(random.normal(), random.normal(), random.normal());
    char row[256];
    std::snprintf(row, sizeof row, "%.2f,%.2f,%.2f,%.2f,%.2f,%.2f,%.17g,%.17g,%.17g\n", q(0) * 180 / M_PI,
                  q(1) * 180 / M_PI, q(2) * 180 / M_PI, q(3) * 180 / M_PI, q(4) * 180 / M_PI, q(5) * 180 / M_PI,
                  point_m.x(), point_m.y(), point_m.z());
    text += row;
  }
  const std::string result = dir.path() + "/result.json";
  const int code =
      test::run(cli::calibrate_main, {"--samples", dir.write("rounded.csv", text), "--method", "lm", "--out", result,
                                      "--quiet", "--tracker-sigma-um", "1", "--keep-outliers"});
  EXPECT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << code;
  std::string json;
  ASSERT_TRUE(port::read_whole_file(result, port::kMaxTextInputBytes, &json).ok());
  EXPECT_NE(json.find("\"noise_source\": \"stated, with the joints' reading\""), std::string::npos);
  EXPECT_NE(json.find("joint noise: the joints, written to 0.01 deg (a rounding: sigma 0.0029 deg)"),
            std::string::npos);
  const double noise_m = number_after(json, "noise_sigma_m");
  const double fit_m = number_after(json, "fit_sigma_m");
  std::printf("joints written to 0.01 deg: measurement noise %.4f mm per axis, the fit's residual %.4f mm\n",
              noise_m * 1e3, fit_m * 1e3);
  EXPECT_GT(noise_m, 10e-6);  // the joints', not the tracker's 1 um
  EXPECT_NEAR(fit_m / noise_m, 1.0, 0.25);
  EXPECT_NE(json.find("the model explains the data to the measurement noise"), std::string::npos);
}

}  // namespace
}  // namespace hivecal::noise_cli_test
