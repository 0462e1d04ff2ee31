// A real seven-axis arm (issue 53): the shared Barrett WAM grid (216 poses, tracker, joints in
// degrees, measured = target + difference in mm) calibrated by `hivecal calibrate` with the
// seven-row description examples/barrett-wam.json, scored on the held-out 30 % against a careful
// least-squares fit of the rigid model (LM with tight tolerances from several starts on the same
// training poses). Skips without ../shared/data. Figures: docs/results.md, "A seven-axis arm".
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/solve/lm.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::wam_grid_cli_test {
namespace {

const char* const kGrid = "wam-grid/3D_WAM_uncalibrated_grid_cleaned.csv";
const char* const kColumns =
    "x=x_t+x_dif[mm],y=y_t+y_dif[mm],z=z_t+z_dif[mm],q1=joint_1[deg],q2=joint_2[deg],q3=joint_3[deg],"
    "q4=joint_4[deg],q5=joint_5[deg],q6=joint_6[deg],q7=joint_7[deg]";

std::string description_path() {
  return std::string(HIVECAL_EXAMPLES_DIR) + "/barrett-wam.json";
}

/// Mean 3-D distance of `model` seen through `base` from the samples' points [m].
double mae_m(const RobotModel& model, const RigidTransform& base, Span<const Sample> samples) {
  double sum_m = 0.0;
  for (const Sample& s : samples) sum_m += (base.apply(fk_tool_point(model, s.q_rad)) - s.point_m).norm();
  return sum_m / static_cast<double>(samples.size());
}

/// The careful least-squares fit of the rigid model: LM without prior, tight tolerances, from
/// the nominal and from four starts 5 mm / 5 mrad off it, the lowest training cost kept; its MAE
/// on the held-out samples of the job's split (train 0.7, seed `seed`, calibrate's --seed) [m].
double least_squares_test_mae_m(const RobotModel& nominal, DatasetBase* grid, std::uint64_t seed = 1,
                                bool quiet = false) {
  EXPECT_EQ(grid->split(0.7, seed), Status::ok);
  static LmWorkspace workspace;
  static LmResult result;
  LmOptions options;
  options.max_iterations = 1000;
  options.cost_tolerance = 1e-15;
  options.step_tolerance_m = 1e-15;
  options.gradient_tolerance = 1e-14;
  Random random(53);
  double best_rms_m = 1.0;
  double best_test_m = 0.0;
  for (int start = 0; start < 5; ++start) {
    RobotModel from = nominal;
    ModelParams params = to_params(nominal);
    for (int i = 0; start > 0 && i < model_param_count(nominal); ++i) params(i) += random.uniform(-5e-3, 5e-3);
    set_model_params(params, &from);
    const Status status = calibrate_lm(from, nullptr, grid->train(), options, &workspace, &result);
    EXPECT_TRUE(status == Status::ok || status == Status::not_converged) << status_message(status);
    if (!quiet) std::printf("least squares from start %d: training RMS %.6f mm\n", start, result.rms_m * 1e3);
    if (result.rms_m < best_rms_m) {
      best_rms_m = result.rms_m;
      best_test_m = mae_m(result.model, result.base_to_tracker, grid->test());
    }
  }
  return best_test_m;
}

/// The test MAE [m] of `calibrate` with the grid, the description and `extra` options (exit
/// `code`: 5 when the fit moves parameters implausibly, the result written; -1: either).
double calibrate_test_mae_m(const test::TempDir& dir, const std::string& name, std::vector<std::string> extra,
                            int code = cli::kExitOk) {
  const std::string out = dir.path() + "/" + name + ".json";
  std::vector<std::string> args = {"--samples",     test::shared_data_path(kGrid),
                                   "--robot-model", description_path(),
                                   "--columns",     kColumns,
                                   "--out",         out,
                                   "--quiet"};
  args.insert(args.end(), extra.begin(), extra.end());
  std::string err;
  const int exit_code = test::run_capturing_stderr(cli::calibrate_main, args, &err);
  if (code >= 0) {
    EXPECT_EQ(exit_code, code) << err;
  } else {
    EXPECT_TRUE(exit_code == cli::kExitOk || exit_code == cli::kExitWarnings) << exit_code << ": " << err;
  }
  record::CalibrationFile file;
  EXPECT_TRUE(record::read_calibration_json(out, &file).ok());
  EXPECT_EQ(file.model.joint_count, 7);
  const textio::JsonValue root = test::read_json_file(out);
  const textio::JsonValue* test_metrics = root.find("metrics") ? root.find("metrics")->find("test") : nullptr;
  EXPECT_NE(test_metrics, nullptr) << out;
  return test_metrics == nullptr ? 0.0 : test_metrics->find("mae_m")->find("3d")->number;
}

TEST(WamGridCli, CalibratesTheRealSevenAxisArmAsACarefulLeastSquaresFitDoes) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA(kGrid);
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_wam");
  textio::RobotDescription wam;
  ASSERT_TRUE(textio::read_robot_description(description_path(), &wam).ok());
  ASSERT_EQ(wam.model.joint_count, 7);
  textio::InputUnits units;
  units.joints = textio::input_joints(wam.model);
  ASSERT_EQ(textio::parse_column_aliases(kColumns, &units.columns), "");
  static Dataset<256> grid;
  grid.clear();
  ASSERT_TRUE(textio::read_samples_csv(test::shared_data_path(kGrid), &grid, units).ok());
  ASSERT_EQ(grid.size(), 216u);
  const double reference_m = least_squares_test_mae_m(wam.model, &grid);

  // The default widens the prior's tolerances (its chi-square beyond the 5 % quantile; lengths to
  // 1.72 mm, angles to 16.6 mrad) and estimates alpha5 -2.43 deg off nominal (least squares
  // -2.99 deg, sigma 0.3 deg: the grid determines it), beyond --max-change-deg's 2 deg: exit 5,
  // the warning names it.
  const double default_m = calibrate_test_mae_m(dir, "default", {}, cli::kExitWarnings);
  // Plain least squares moves what the grid hardly determines by centimetres (d6 -29 mm, alpha6
  // -11 deg, correlated 0.999): exit 5, its warnings, the result written.
  const double plain_m = calibrate_test_mae_m(dir, "plain", {"--prior", "off"}, cli::kExitWarnings);
  const double terms_m = calibrate_test_mae_m(dir, "terms", {"--compliance", "--harmonics", "2"}, cli::kExitWarnings);
  const double plain_terms_m = calibrate_test_mae_m(
      dir, "plain-terms", {"--compliance", "--harmonics", "2", "--prior", "off"}, cli::kExitWarnings);
  std::printf(
      "held-out 3-D MAE: least squares %.4f mm; calibrate %.4f mm (--prior off %.4f), --compliance --harmonics 2 "
      "%.4f mm (--prior off %.4f)\n",
      reference_m * 1e3, default_m * 1e3, plain_m * 1e3, terms_m * 1e3, plain_terms_m * 1e3);
  // Plain least squares is the careful fit's optimum. The default's prior (1 mm, 5 mrad) is
  // checked against the data: its chi-square is beyond what the tolerances allow, they widen
  // and the fit comes within 1.6 % on this split (2.098 mm, +4.5 %, at the stated tolerances;
  // the twenty splits below: +0.81 % on average); what the grid determines only weakly (d6,
  // alpha6) still stays within millimetres of nominal.
  EXPECT_LE(plain_m, 1.01 * reference_m);
  EXPECT_LE(default_m, 1.02 * reference_m);
  // The joint terms, each admitted by its significance and the blocked folds, predict held-out
  // poses better than the rigid fit.
  EXPECT_LT(terms_m, default_m);
  EXPECT_LT(plain_terms_m, plain_m);
  EXPECT_LT(terms_m, 2.9e-3);
}

/// The grid and the seven-row description, read as the test above reads them.
struct WamGrid {
  textio::RobotDescription wam;
  Dataset<256> grid;
};

bool read_wam_grid(WamGrid* out) {
  if (!textio::read_robot_description(description_path(), &out->wam).ok()) return false;
  textio::InputUnits units;
  units.joints = textio::input_joints(out->wam.model);
  if (!textio::parse_column_aliases(kColumns, &units.columns).empty()) return false;
  out->grid.clear();
  return textio::read_samples_csv(test::shared_data_path(kGrid), &out->grid, units).ok() && out->grid.size() == 216;
}

// One split is one draw: on the split above the default is 1.6 % above least squares, on others
// below it (the grid's weak directions, which least squares moves by centimetres, help some
// held-out sets and hurt others). Over twenty splits (calibrate's --seed 1..20, 70/30) the mean of
// default / least squares is the figure of issue 53's "within 1 %": measured 1.0081 (range
// 0.955-1.065; docs/results.md). Host presets only (tests/CMakeLists.txt: forty runs of the tool).
TEST(WamGridCli, OverTwentySplitsTheDefaultIsWithinOnePercentOfLeastSquaresOnAverage) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA(kGrid);
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_wam_splits");
  static WamGrid data;
  constexpr int kSplits = 20;
  double ratio_sum = 0.0;
  double worst = 0.0;
  for (int seed = 1; seed <= kSplits; ++seed) {
    ASSERT_TRUE(read_wam_grid(&data));  // in the file's order: a split permutes the samples in place
    const double reference_m =
        least_squares_test_mae_m(data.wam.model, &data.grid, static_cast<std::uint64_t>(seed), true);
    const double default_m =
        calibrate_test_mae_m(dir, "split" + std::to_string(seed), {"--seed", std::to_string(seed)}, -1);
    const double ratio = default_m / reference_m;
    std::printf("split %2d: least squares %.4f mm, calibrate %.4f mm (%.4f)\n", seed, reference_m * 1e3,
                default_m * 1e3, ratio);
    ratio_sum += ratio;
    worst = std::fmax(worst, ratio);
  }
  const double mean = ratio_sum / kSplits;
  std::printf("default / least squares over %d splits: mean %.4f, worst %.4f\n", kSplits, mean, worst);
  EXPECT_LE(mean, 1.01);
  EXPECT_LE(worst, 1.08);
}

}  // namespace
}  // namespace hivecal::wam_grid_cli_test
