// A measured orientation end to end: the UR5e pendant export as it is (Base (°) .. RZ (rad)),
// first 12 poses calibrated with --split 1, the other 6 predicted by `predict` (target 1):
// the result says the orientation was used, and the held-out error is the job's
// (tests/apps/test_ur_calibration_conf.cpp); compliance and harmonics on those 12 poses are
// rejected on left-out poses. Skipped without ../shared/data/ur5e-pendant.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"

namespace hivecal::orientation_cli_test {
namespace {

using test::run;

/// The first `count` comma-separated fields of `line`, joined by commas.
std::string first_fields(const std::string& line, int count) {
  std::size_t end = 0;
  for (int k = 0; k < count && end != std::string::npos; ++k) end = line.find(',', end == 0 ? 0 : end + 1);
  return line.substr(0, end);
}

/// MAE [m] of `predict`'s output (x,y,z[,sigma_m,extrapolated] rows after a header) against
/// `truth_m`; 1 m when a row does not parse or the count differs.
double held_out_mae_m(const std::string& csv, const std::vector<Vec3>& truth_m) {
  std::vector<Vec3> points;
  std::istringstream rows(csv);
  std::string row;
  std::getline(rows, row);  // x,y,z,sigma_m,extrapolated
  while (std::getline(rows, row)) {
    std::vector<double> v;
    std::istringstream cells(row);
    for (std::string cell; std::getline(cells, cell, ',');) {
      double x = 0.0;
      if (!textio::parse_double(cell, &x)) return 1.0;
      v.push_back(x);
    }
    if (v.size() != 3u && v.size() != 5u) return 1.0;
    points.emplace_back(v[0], v[1], v[2]);
  }
  if (points.size() != truth_m.size() || points.empty()) return 1.0;
  double mae_m = 0.0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    mae_m += (points[k] - truth_m[k]).norm() / static_cast<double>(points.size());
  }
  return mae_m;
}

/// The pendant export split as the tests use it: the first 12 poses to calibrate on (the
/// export's header and rows as they are), the other 6 poses' joints to predict, their positions.
struct PendantSplit {
  std::string train;          ///< CSV: the header and the first 12 rows
  std::string held_out;       ///< CSV: the six joint columns of the other 6 rows
  std::vector<Vec3> truth_m;  ///< their measured positions [m]
};

void split_pendant_export(PendantSplit* split) {
  const std::string file = test::read_text_file(test::shared_data_path("ur5e-pendant/joint-eef-data.csv"));
  std::vector<std::string> lines;
  std::istringstream in(file);
  for (std::string line; std::getline(in, line);) {
    if (!textio::trim(line).empty()) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 19u);
  split->train = lines[0] + "\n";
  split->held_out = first_fields(lines[0], 6) + "\n";  // the six joint columns
  for (std::size_t i = 1; i <= 18; ++i) {
    if (i <= 12) {
      split->train += lines[i] + "\n";
      continue;
    }
    std::vector<double> v;
    std::istringstream cells(lines[i]);
    for (std::string cell; std::getline(cells, cell, ',');) {
      double x = 0.0;
      ASSERT_TRUE(textio::parse_double(cell, &x)) << cell;
      v.push_back(x);
    }
    ASSERT_EQ(v.size(), 12u);
    split->held_out += first_fields(lines[i], 6) + "\n";
    split->truth_m.push_back(Vec3(v[6], v[7], v[8]) * 1e-3);
  }
}

TEST(OrientationCli, PendantExportCalibratesWithItsOrientationAndSaysSo) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  PendantSplit split;
  ASSERT_NO_FATAL_FAILURE(split_pendant_export(&split));
  const std::vector<Vec3>& truth_m = split.truth_m;
  const test::TempDir dir("hivecal_orientation");
  ASSERT_FALSE(dir.path().empty());
  const std::string samples = dir.write("train.csv", split.train);
  const std::string joints = dir.write("held_out.csv", split.held_out);
  const std::string result = dir.path() + "/result.json";
  const std::string positions = dir.path() + "/result_positions.json";
  const std::string predicted = dir.path() + "/predicted.csv";
  // The frames fitted, as for a tracker: the default recognises the controller's readings
  // (PendantExportIsRecognisedAsTheControllersReadings, below).
  const std::vector<std::string> common = {"--samples", samples, "--robot-model", "ur5e",     "--tool", "0,0,0",
                                           "--split",   "1",     "--quiet",       "--frames", "fitted"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--out", result});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  const std::string json = test::read_text_file(result);
  EXPECT_NE(json.find("\"orientation\": {"), std::string::npos);
  EXPECT_NE(json.find("\"poses\": 12"), std::string::npos);
  // The lever from the noise: the joints written to 0.01 deg move the point far more than they
  // turn the tool, ~0.09 m instead of the sigmas' 0.01 m (textio::noise_lever_m).
  EXPECT_NE(json.find("\"lever_m\": 0.09"), std::string::npos);
  EXPECT_NE(json.find("\"lever_joint_sigma_rad\": 0.00017453292519943"), std::string::npos);
  EXPECT_NE(json.find("lever of 0.09"), std::string::npos);  // the console's and the report's line
  EXPECT_NE(json.find("joints read to 0.000175 rad through the arm"), std::string::npos);
  EXPECT_NE(json.find("orientation used: 12 poses with rx, ry, rz"), std::string::npos);  // the report's input lines
  EXPECT_NE(json.find("\"tools\""), std::string::npos);

  ASSERT_EQ(run(cli::predict_main, {"--calibration", result, "--joints", joints, "--out", predicted}), 0);
  const double mae_m = held_out_mae_m(test::read_text_file(predicted), truth_m);
  std::printf("calibrate + predict on the pendant export, with orientation: held-out MAE %.4f mm\n", mae_m * 1e3);
  EXPECT_LT(mae_m, 0.075e-3);  // the job's 0.0725 mm (0.0887 mm at the sigmas' 0.01 m, below)

  // A lever given is used as given: 0.01 m, the stated sigmas' ratio (the job's 0.0887 mm).
  const std::string at_sigmas = dir.path() + "/result_sigmas.json";
  args = common;
  args.insert(args.end(), {"--out", at_sigmas, "--orientation-lever-m", "0.01"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  EXPECT_NE(test::read_text_file(at_sigmas).find("\"lever_m\": 0.01,"), std::string::npos);
  EXPECT_EQ(test::read_text_file(at_sigmas).find("lever_joint_sigma_rad"), std::string::npos);
  ASSERT_EQ(run(cli::predict_main, {"--calibration", at_sigmas, "--joints", joints, "--out", predicted}), 0);
  const double sigmas_mae_m = held_out_mae_m(test::read_text_file(predicted), truth_m);
  std::printf("the same at the sigmas' lever of 0.01 m: held-out MAE %.4f mm\n", sigmas_mae_m * 1e3);
  EXPECT_GT(sigmas_mae_m, mae_m);

  // --orientation-lever-m 0: positions only (the job's 0.116 mm), nothing said of an orientation.
  args = common;
  args.insert(args.end(), {"--out", positions, "--orientation-lever-m", "0"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  EXPECT_EQ(test::read_text_file(positions).find("\"orientation\""), std::string::npos);
  // Stated sigmas must be positive.
  args = common;
  args.insert(args.end(), {"--out", positions, "--angle-sigma-rad", "0"});
  EXPECT_EQ(run(cli::calibrate_main, args), 2);
  EXPECT_EQ(json.find("\"joint_sigma_rad\""), std::string::npos);  // off unless given

  // The joints' rounding as joint reading noise: a different fit (the job's 0.0935 mm), said so.
  const std::string whitened = dir.path() + "/result_joint_noise.json";
  args = common;
  args.insert(args.end(), {"--out", whitened, "--joint-sigma-deg", "0.01"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  const std::string whitened_json = test::read_text_file(whitened);
  EXPECT_NE(whitened_json.find("\"joint_sigma_rad\": 0.000174532925199"), std::string::npos);
  EXPECT_NE(whitened_json, json);
  for (const char* bad : {"-0.01", "60"}) {
    args = common;
    args.insert(args.end(), {"--out", whitened, "--joint-sigma-deg", bad});
    EXPECT_EQ(run(cli::calibrate_main, args), 2) << bad;
  }
  args = common;
  args.insert(args.end(), {"--out", whitened, "--joint-sigma-deg", "0.01", "--joint-sigma-rad", "1e-4"});
  EXPECT_EQ(run(cli::calibrate_main, args), 2);
  EXPECT_EQ(json.find("\"known\""), std::string::npos);

  // The controller's own TCP readings: base and tool known, LM only (the job's 0.0629 mm).
  const std::vector<std::string> unsaid_frames(common.begin(), common.end() - 2);
  const std::string tcp = dir.path() + "/result_controller_tcp.json";
  args = unsaid_frames;
  args.insert(args.end(), {"--out", tcp, "--controller-tcp"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  const std::string tcp_json = test::read_text_file(tcp);
  EXPECT_NE(tcp_json.find("\"known\": \"base (identity) and tool points"), std::string::npos);
  EXPECT_NE(tcp_json.find("known (--controller-tcp): the base (identity)"),
            std::string::npos);  // the report's info lines
  ASSERT_EQ(run(cli::predict_main, {"--calibration", tcp, "--joints", joints, "--out", predicted}), 0);
  const double tcp_mae_m = held_out_mae_m(test::read_text_file(predicted), truth_m);
  std::printf("calibrate --controller-tcp + predict on the pendant export: held-out MAE %.4f mm\n", tcp_mae_m * 1e3);
  EXPECT_LT(tcp_mae_m, 0.065e-3);
  for (const char* method : {"abc+lm", "abc", "gsa+lm", "all"}) {
    args = unsaid_frames;
    args.insert(args.end(), {"--out", tcp, "--controller-tcp", "--method", method});
    EXPECT_EQ(run(cli::calibrate_main, args), 2) << method;
  }
}

// The default command on the pendant's first 12 poses (issue 23's benchmark: no --method, no
// --controller-tcp): the fitted base is the identity within 0.3 mm, the fit with the
// controller's frames explains the readings to their noise (0.027 against 0.029 mm), so the job
// keeps it, says so, and predicts the other 6 to 0.0629 mm (the frames fitted: 0.0725 mm); its
// result is --controller-tcp's. --frames controller is --controller-tcp; --frames fitted fits.
TEST(OrientationCli, PendantExportIsRecognisedAsTheControllersReadings) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  PendantSplit split;
  ASSERT_NO_FATAL_FAILURE(split_pendant_export(&split));
  const test::TempDir dir("hivecal_pendant_frames");
  ASSERT_FALSE(dir.path().empty());
  const std::string samples = dir.write("train.csv", split.train);
  const std::string joints = dir.write("held_out.csv", split.held_out);
  const std::string predicted = dir.path() + "/predicted.csv";
  const std::vector<std::string> common = {"--samples", samples, "--robot-model", "ur5e",
                                           "--tool",    "0,0,0", "--split",       "1"};
  const auto calibrate = [&](const std::string& name, std::vector<std::string> extra, std::string* console) {
    std::vector<std::string> args = common;
    const std::string out = dir.path() + "/" + name;
    args.insert(args.end(), {"--out", out});
    args.insert(args.end(), extra.begin(), extra.end());
    testing::internal::CaptureStdout();
    const int code = run(cli::calibrate_main, args);
    *console = testing::internal::GetCapturedStdout();
    EXPECT_EQ(code, 0) << name;
    return out;
  };
  const auto held_out_m = [&](const std::string& result) {
    EXPECT_EQ(run(cli::predict_main, {"--calibration", result, "--joints", joints, "--out", predicted}), 0);
    return held_out_mae_m(test::read_text_file(predicted), split.truth_m);
  };
  std::string console;
  const std::string detected = calibrate("default.json", {}, &console);
  EXPECT_NE(console.find("frames: the fitted base is within 10 mm and 10 mrad of the identity, and with the base "
                         "(identity) and the tool points (--tool) known the fit's residual sigma is 0.027 mm"),
            std::string::npos)
      << console;
  EXPECT_NE(console.find("the points are the controller's own TCP readings"), std::string::npos);
  const std::string json = test::read_text_file(detected);
  EXPECT_NE(json.find("\"frames_test\": {\n    \"adopted\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("(--frames auto)"), std::string::npos);
  const double detected_m = held_out_m(detected);
  std::printf("the default command on the pendant's first 12: held-out MAE %.4f mm\n", detected_m * 1e3);
  EXPECT_LT(detected_m, 0.065e-3);

  const std::string given = calibrate("controller.json", {"--frames", "controller"}, &console);
  EXPECT_EQ(held_out_m(given), detected_m);  // the same fit: the same predictions, bit for bit
  EXPECT_EQ(test::read_text_file(given).find("\"frames_test\""), std::string::npos);

  const std::string fitted = calibrate("fitted.json", {"--frames", "fitted"}, &console);
  EXPECT_EQ(console.find("frames:"), std::string::npos);
  EXPECT_EQ(test::read_text_file(fitted).find("\"known\""), std::string::npos);
  EXPECT_GT(held_out_m(fitted), detected_m);

  // A population method asked for keeps the frames fitted unless --frames auto is given too;
  // the paper's comparison (--method all) always does.
  for (const std::vector<std::string>& extra :
       std::vector<std::vector<std::string>>{{"--method", "abc+lm"},
                                             {"--method", "abc+lm", "--frames", "auto"},
                                             {"--method", "all", "--frames", "auto"}}) {
    const std::string asked = calibrate("method.json", extra, &console);
    const bool detected_asked = extra.size() == 4 && extra[1] == "abc+lm";
    EXPECT_EQ(test::read_text_file(asked).find("\"frames_test\"") != std::string::npos, detected_asked) << extra[1];
  }

  for (const std::vector<std::string>& bad :
       std::vector<std::vector<std::string>>{{"--frames", "tracker"}, {"--frames", "fitted", "--controller-tcp"}}) {
    std::vector<std::string> args = common;
    args.insert(args.end(), bad.begin(), bad.end());
    EXPECT_EQ(run(cli::calibrate_main, args), 2) << bad[1];
  }
}

// The UR10 T-Mac export with its orientation through the command line: a bad row is named
// once by its line, with the samples it made (its point and targets 2, 3), and the console
// says that the readings of a pose were tested as sharing their error.
// The whole export with the job's own split in halves: a fit of 9 poses predicts its 9 test
// poses to ~0.1 mm, far above the pendant's 0.01 mm rounding, so the test rejects most of them.
// Set aside as blunders, they left 3 poses of 18 (3.55 mm held out on seed 3); as the model's
// error (more failing than a blunder explains), none is set aside and the fit predicts them to
// ~0.13 mm. That is with the frames fitted, as for a tracker; the default, which recognises the
// controller's readings (base and tool known), keeps every pose too.
TEST(OrientationCli, PendantExportSplitInHalvesKeepsEveryPose) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const std::string samples = test::shared_data_path("ur5e-pendant/joint-eef-data.csv");
  const test::TempDir dir("hivecal_pendant_halves");
  ASSERT_FALSE(dir.path().empty());
  const std::string result = dir.path() + "/result.json";
  for (const char* seed : {"1", "2", "3"}) {
    ASSERT_EQ(run(cli::calibrate_main, {"--samples", samples, "--robot-model", "ur5e", "--tool", "0,0,0", "--split",
                                        "0.5", "--seed", seed, "--quiet", "--out", result, "--frames", "fitted"}),
              0)
        << seed;
    const std::string json = test::read_text_file(result);
    EXPECT_NE(json.find("\"outliers\": []"), std::string::npos) << seed;
    EXPECT_NE(json.find("\"blunder_verdict\": \"prediction_error\""), std::string::npos) << seed;
    EXPECT_NE(json.find("\"overall\": {\n      \"count\": 54"), std::string::npos) << seed;
    ASSERT_EQ(run(cli::calibrate_main, {"--samples", samples, "--robot-model", "ur5e", "--tool", "0,0,0", "--split",
                                        "0.5", "--seed", seed, "--quiet", "--out", result}),
              0)
        << seed;
    const std::string detected = test::read_text_file(result);
    EXPECT_NE(detected.find("\"outliers\": []"), std::string::npos) << seed;
    EXPECT_NE(detected.find("\"adopted\": true"), std::string::npos) << seed;
  }
}

TEST(OrientationCli, TMacBadRowsAreNamedOncePerLine) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur10-tmac/measurements_joint_configurations.csv");
  const std::string export_path = test::shared_data_path("ur10-tmac/measurements_joint_configurations.csv");
  const test::TempDir dir("hivecal_tmac_cli");
  ASSERT_FALSE(dir.path().empty());
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(
      run(cli::calibrate_main, {"--samples", export_path, "--robot-model", "ur10", "--tool", "0,0,0.109", "--columns",
                                "x=measurement_x[mm],y=measurement_y[mm],z=measurement_z[mm],rx=measurement_rx[deg],"
                                "ry=measurement_ry[deg],rz=measurement_rz[deg]",
                                "--orientation-form", "euler-xyz", "--quiet", "--out", result}),
      0);
  const std::string json = test::read_text_file(result);
  const auto count = [&json](const std::string& text) {
    std::size_t n = 0;
    for (std::size_t at = json.find(text); at != std::string::npos; at = json.find(text, at + 1)) ++n;
    return n;
  };
  for (const char* line : {"534", "856", "857"}) {
    const std::string named = "measurements_joint_configurations.csv:" + std::string(line);
    EXPECT_EQ(count("set aside as a blunder: " + export_path + ":" + line + " (3 samples), residual "), 1u) << line;
    EXPECT_EQ(count(named + " (3 samples)\""), 1u) << line;  // the report's table: one row
  }
  EXPECT_EQ(json.find("csv:1065"), std::string::npos);  // a pose as far off as its neighbours stays
  EXPECT_NE(json.find("blunder test: the readings of a pose share their error"), std::string::npos);
  EXPECT_NE(json.find("\"pooled_correlation\": true"), std::string::npos);
}

// Compliance and harmonics on 12 poses of an arm whose readings are its controller's rigid FK:
// the significance test keeps gravity terms that fit the pendant's rounding, and they predict each
// joint's range ends worse than the rigid fit (blocked folds); 12 poses turn no joint but the last
// through three quarters of a harmonic's period, and its terms do not pass their test. Every term
// is rejected, and the result predicts as the rigid fit does, to the byte. (Before the blocked
// folds, the check on left-out poses rejected them.)
TEST(OrientationCli, PendantExportRejectsEveryJointTermOnLeftOutPoses) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  if (4 * kSixJoints > kMaxComplianceTerms)
    GTEST_SKIP() << "this build holds " << kMaxComplianceTerms << " joint terms";
  PendantSplit split;
  ASSERT_NO_FATAL_FAILURE(split_pendant_export(&split));
  const test::TempDir dir("hivecal_pendant_terms");
  ASSERT_FALSE(dir.path().empty());
  const std::string samples = dir.write("train.csv", split.train);
  const std::string joints = dir.write("held_out.csv", split.held_out);
  const std::vector<std::string> common = {"--samples", samples, "--robot-model", "ur5e", "--tool", "0,0,0",
                                           "--split",   "1",     "--quiet"};
  std::vector<std::string> args = common;
  args.insert(args.end(), {"--out", dir.path() + "/rigid.json"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  args = common;
  args.insert(args.end(), {"--out", dir.path() + "/terms.json", "--compliance", "--harmonics", "2"});
  ASSERT_EQ(run(cli::calibrate_main, args), 0);
  const std::string json = test::read_text_file(dir.path() + "/terms.json");
  EXPECT_NE(json.find("compliance: the terms that passed the significance test do not hold beyond the training "
                      "poses' joint ranges: the rigid fit is kept"),
            std::string::npos);
  EXPECT_NE(json.find("harmonics: not admitted: h_j1_sin1"), std::string::npos);
  EXPECT_NE(json.find("harmonics: no term passed"), std::string::npos);
  const textio::JsonValue root = test::read_json_file(dir.path() + "/terms.json");
  const textio::JsonValue* terms =
      root.find("compliance") != nullptr ? root.find("compliance")->find("terms") : nullptr;
  ASSERT_NE(terms, nullptr);
  EXPECT_EQ(terms->array.size(), 28u);  // 4 gravity terms, 24 harmonics
  for (const textio::JsonValue& term : terms->array) {
    EXPECT_EQ(term.find("coefficient")->number, 0.0) << term.find("name")->string;
  }
  std::string rigid_points;
  for (const char* name : {"rigid", "terms"}) {
    const std::string predicted = dir.path() + "/" + name + ".csv";
    ASSERT_EQ(run(cli::predict_main,
                  {"--calibration", dir.path() + "/" + name + ".json", "--joints", joints, "--out", predicted}),
              0);
    const std::string points = test::read_text_file(predicted);
    if (rigid_points.empty()) {
      rigid_points = points;
      std::printf("pendant export, 12 poses, rigid: held-out MAE %.4f mm\n",
                  held_out_mae_m(points, split.truth_m) * 1e3);
    } else {
      EXPECT_EQ(points, rigid_points);
    }
  }
}

}  // namespace
}  // namespace hivecal::orientation_cli_test
