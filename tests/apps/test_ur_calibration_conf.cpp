// Real-controller check: a UR5e's factory calibration and 18 pendant readings
// (../shared/data/ur5e-pendant). Calibrated FK must match the pendant to its rounding;
// nominal FK must not (so the test can fail). Skipped when that data is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/alloc_trap.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::ur_calibration_conf_test {
namespace {

const std::string kDir = std::string(HIVECAL_TEST_DATA_DIR) + "/ur5e-pendant/";

struct PendantReading {
  JointVector q_rad;
  Vec3 tcp_m;
};

std::vector<PendantReading> read_pendant_csv() {
  std::string text;
  EXPECT_TRUE(port::read_whole_file(kDir + "joint-eef-data.csv", port::kMaxTextInputBytes, &text).ok());
  std::vector<PendantReading> readings;
  std::istringstream lines(text);
  std::string line;
  std::getline(lines, line);  // header
  while (std::getline(lines, line)) {
    if (textio::trim(line).empty()) continue;
    std::vector<double> fields;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) {
      double v = 0.0;
      EXPECT_TRUE(textio::parse_double(cell, &v)) << cell;
      fields.push_back(v);
    }
    EXPECT_EQ(fields.size(), 12u);
    PendantReading r;
    for (int j = 0; j < 6; ++j) r.q_rad(j) = fields[j] * M_PI / 180.0;
    r.tcp_m << fields[6] / 1000.0, fields[7] / 1000.0, fields[8] / 1000.0;
    readings.push_back(r);
  }
  return readings;
}

struct ErrorSummary {
  double mean_m = 0.0;
  double max_m = 0.0;
};

ErrorSummary compare(const RobotModel& model, const std::vector<PendantReading>& readings) {
  ErrorSummary s;
  for (const PendantReading& r : readings) {
    const double e = (fk_tool_point(model, r.q_rad) - r.tcp_m).norm();
    s.mean_m += e / static_cast<double>(readings.size());
    s.max_m = std::max(s.max_m, e);
  }
  return s;
}

TEST(Ur5ePendant, CalibratedFkMatchesControllerNominalDoesNot) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const std::vector<PendantReading> readings = read_pendant_csv();
  ASSERT_EQ(readings.size(), 18u);
  UrCalibrationDeltas deltas;
  const port::Error parsed = textio::read_ur_calibration_conf(kDir + "calibration.conf", &deltas);
  ASSERT_TRUE(parsed.ok()) << parsed.message;
  EXPECT_NEAR(deltas.delta_d_m[1], -204.077105406530421, 1e-12);

  const RobotModel nominal = nominal_model(RobotType::ur5e);
  RobotModel calibrated;
  ASSERT_EQ(apply_ur_deltas(nominal, deltas, &calibrated), Status::ok);

  const ErrorSummary with_calibration = compare(calibrated, readings);
  const ErrorSummary without = compare(nominal, readings);
  RecordProperty("calibrated_mean_um", static_cast<int>(with_calibration.mean_m * 1e6));
  EXPECT_LT(with_calibration.max_m, 0.1e-3) << "mean " << with_calibration.mean_m;
  EXPECT_GE(without.mean_m, 0.5e-3);
}

TEST(Ur5ePendant, FitOnTwelvePosesPredictsTheOtherSix) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  // The issue's real small set: the first 12 readings train (--split 1), the last 6 are
  // predicted. The pendant reports the TCP (= flange) in the base frame; the start is the
  // nominal UR5e with the tool at the flange. scipy's full least-squares fit: 0.066 mm.
  const std::vector<PendantReading> readings = read_pendant_csv();
  ASSERT_EQ(readings.size(), 18u);
  static Dataset<32> fit;
  fit.clear();
  for (std::size_t i = 0; i < 12; ++i) ASSERT_EQ(fit.add(readings[i].q_rad, readings[i].tcp_m), Status::ok);
  static CalibrationWorkspace<32, double, 150, 300> workspace;
  static CalibrationResult result;
  CalibrationOptions options;  // the command line's defaults: ABC+LM, full model
  options.train_fraction = 1.0;
  const RobotModel start = nominal_model(RobotType::ur5e);
  ASSERT_EQ(calibrate(start, &fit, options, &workspace, &result), Status::ok) << calibration_step_name(result.step);
  EXPECT_EQ(result.train_count, 12u);
  EXPECT_EQ(result.test_count, 0u);
  EXPECT_EQ(result.outlier_count, 0u);
  EXPECT_GT(result.lm.identifiability.dropped_count, 0);
  const CalibrationStage& final_stage = result.stages[result.stage_count - 1];
  double mae_m = 0.0;
  double baseline_mae_m = 0.0;
  for (std::size_t i = 12; i < 18; ++i) {
    const Vec3 predicted = final_stage.base_to_tracker.apply(fk_tool_point(final_stage.model, readings[i].q_rad));
    const Vec3 nominal = result.baseline.base_to_tracker.apply(fk_tool_point(result.baseline.model, readings[i].q_rad));
    mae_m += (predicted - readings[i].tcp_m).norm() / 6.0;
    baseline_mae_m += (nominal - readings[i].tcp_m).norm() / 6.0;
  }
  RecordProperty("predicted_mae_um", static_cast<int>(mae_m * 1e6));
  std::printf("UR5e pendant: 12 poses fitted, 6 predicted: MAE %.4f mm (baseline %.4f mm)\n", mae_m * 1e3,
              baseline_mae_m * 1e3);
  // The issue asks for 0.08 mm (scipy: 0.066 mm); with base and tool fitted as for a tracker
  // this job reaches 0.116 mm on this split (known, with orientation: 0.0745 mm, ControllerTcp* below)
  // (0.138 mm without the significance test; 3-fold CV over 5 seeds on all 18: 0.083-0.106 mm,
  // docs/robust.md). The bound pins what it does so that a change for the worse fails.
  EXPECT_LT(mae_m, 0.12e-3);
  EXPECT_GT(baseline_mae_m, 0.5e-3);
}

/// Fits the pendant poses `train` (the file read as it is, Base (°) .. RZ (rad): each pose's
/// rotation vector adds targets 2 and 3 at the lever of the noise, as the command line reads
/// it: the rounding of the positions (0.01 mm) and of the rotation vector (0.001 rad), and of
/// the joints (0.01°) propagated through the nominal arm, ~94 mm; chosen from the pendant's
/// rounding, not on held-out poses) with the command line's defaults and --split 1; returns
/// the MAE [m] of predicting the poses `test`.
/// `joint_step_rad` > 0: the joints' rounding enters as joint reading noise (LmOptions::joint_sigma_rad
/// in the same step units as the positions' 0.01 mm, textio::kDefaultPositionSigma_m).
/// `controller_tcp`: as `--controller-tcp`, the base (identity) and the tool points are known, LM only.
/// `largest_set_aside_w_ratio`, when given, receives the largest w / critical w of a pose the
/// blunder test set aside (0: none); without it none may be set aside.
double predict_with_orientation(const std::vector<std::size_t>& train, const std::vector<std::size_t>& test,
                                double joint_step_rad = 0.0, bool controller_tcp = false,
                                double* largest_set_aside_w_ratio = nullptr) {
  static Dataset<64> all;
  all.clear();
  textio::OrientationRead found;
  RobotModel arm = nominal_model(RobotType::ur5e);  // the command line's: nominal, --tool 0,0,0
  arm.tool_m = Vec3::Zero();
  textio::OrientationInput orientation;
  orientation.arm = &arm;
  port::Error read = textio::read_samples_csv(kDir + "joint-eef-data.csv", &all, {}, nullptr, orientation, &found);
  EXPECT_TRUE(read.ok()) << read.message;
  EXPECT_EQ(found.poses, 18u);
  EXPECT_EQ(found.joint_sigma_rad, 0.01 * math::kRadPerDeg);  // the joints' written resolution
  EXPECT_NEAR(found.lever_m, 0.095, 0.005);
  const std::vector<PendantReading> readings = read_pendant_csv();
  // The command line reads the training poses only: their lever.
  std::vector<JointVector> train_poses;
  for (std::size_t pose : train) train_poses.push_back(readings[pose].q_rad);
  orientation.lever_m =
      textio::noise_lever_m(orientation.position_sigma_m, orientation.angle_sigma_rad, found.joint_sigma_rad, arm,
                            Span<const JointVector>(train_poses.data(), train_poses.size()));
  all.clear();
  read = textio::read_samples_csv(kDir + "joint-eef-data.csv", &all, {}, nullptr, orientation, &found);
  EXPECT_TRUE(read.ok()) << read.message;
  EXPECT_EQ(all.size(), 54u);
  static Dataset<64> fit;
  fit.clear();
  for (std::size_t pose : train) {
    for (std::size_t k = 0; k < 3; ++k) {
      const Sample& s = all.samples()[3 * pose + k];
      EXPECT_EQ(s.target, static_cast<int>(k));
      if (k == 0) {
        EXPECT_LE((s.point_m - readings[pose].tcp_m).norm(), 1e-15);
      }
      EXPECT_EQ(fit.add(s.q_rad, s.point_m, s.target), Status::ok);
    }
  }
  static CalibrationWorkspace<64, double, 150, 300> workspace;
  static CalibrationResult result;
  CalibrationOptions options;  // the command line's defaults: ABC+LM, full model
  options.train_fraction = 1.0;
  options.lm.joint_sigma_rad = joint_step_rad;
  options.lm.position_sigma_m = textio::kDefaultPositionSigma_m;
  if (controller_tcp) {
    options.method = CalibrationMethod::lm;
    options.base_known = true;
    options.tool_known = true;
  }
  RobotModel start = nominal_model(RobotType::ur5e);
  start.tool_m = Vec3::Zero();
  textio::start_orientation_targets(found, &start);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(start, &fit, options, &workspace, &result));
  EXPECT_EQ(status, Status::ok) << calibration_step_name(result.step);
  if (largest_set_aside_w_ratio == nullptr) {
    EXPECT_EQ(result.train_count, 3 * train.size());
    EXPECT_EQ(result.outlier_count, 0u);
  } else {
    *largest_set_aside_w_ratio = 0.0;
    for (const CalibrationOutlier& o : result.outlier_list())
      *largest_set_aside_w_ratio = std::max(*largest_set_aside_w_ratio, o.w / o.critical_w);
  }
  const CalibrationStage& final_stage = result.stages[result.stage_count - 1];
  if (controller_tcp) {  // kept bit for bit
    EXPECT_TRUE(final_stage.base_to_tracker.translation_m == Vec3::Zero());
    EXPECT_TRUE(final_stage.base_to_tracker.rotation == Mat3::Identity());
    for (int t = 0; t < kMaxTargets; ++t) EXPECT_TRUE(target_tool(final_stage.model, t) == target_tool(start, t));
  }
  double mae_m = 0.0;
  for (std::size_t pose : test) {
    const Vec3 predicted = final_stage.base_to_tracker.apply(fk_tool_point(final_stage.model, readings[pose].q_rad));
    mae_m += (predicted - readings[pose].tcp_m).norm() / static_cast<double>(test.size());
  }
  return mae_m;
}

TEST(Ur5ePendant, OrientationTooPredictsTheOtherSixBetter) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const double mae_m = predict_with_orientation({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, {12, 13, 14, 15, 16, 17});
  RecordProperty("predicted_mae_um", static_cast<int>(mae_m * 1e6));
  std::printf("UR5e pendant with orientation (lever from the noise): 12 poses fitted, 6 predicted: MAE %.4f mm\n",
              mae_m * 1e3);
  // Measured 0.0725 mm (at the sigmas' lever of 10 mm, without the joints' noise: 0.0887 mm;
  // positions only: 0.116 mm, the test above): better than every position-only scipy fit of this
  // split (0.139-0.292 mm, docs/robust.md), short of the issue's 0.070 mm. Pinned so that a
  // change for the worse fails.
  EXPECT_LT(mae_m, 0.075e-3);
}

// A split on which the significance test fixed tool_x, and with it (LM estimated the other
// targets' tool points only while tool_x was free) targets 2 and 3 at their start: 5.97 mm
// then; 0.078 mm while the job kept tool_x free with several targets; 0.0805 mm since LM
// estimates them whenever the stage estimates the tool point (positions only: 0.080); 0.0785 mm
// at the lever from the noise.
TEST(Ur5ePendant, OrientationSplitWhereTheSignificanceTestFroze2And3) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const double mae_m = predict_with_orientation({4, 16, 5, 2, 3, 12, 17, 13, 11, 1, 0, 8}, {15, 10, 14, 9, 6, 7});
  std::printf("UR5e pendant with orientation, another split: MAE %.4f mm\n", mae_m * 1e3);
  EXPECT_LT(mae_m, 0.085e-3);
}

// The 20 random 12/6 splits of docs/robust.md (numpy default_rng(0) permutations: the first 12
// train, the last 6 are predicted).
const std::size_t kTwentySplits[20][18] = {
    {2, 10, 3, 12, 0, 4, 7, 5, 16, 13, 14, 11, 6, 9, 17, 8, 1, 15},
    {4, 16, 5, 2, 3, 12, 17, 13, 11, 1, 0, 8, 15, 10, 14, 9, 6, 7},
    {4, 16, 2, 15, 8, 7, 9, 11, 1, 17, 10, 0, 12, 6, 14, 3, 13, 5},
    {16, 0, 6, 8, 7, 1, 5, 4, 14, 15, 10, 2, 9, 3, 17, 13, 11, 12},
    {10, 5, 17, 7, 1, 9, 14, 0, 15, 11, 13, 3, 8, 6, 16, 12, 2, 4},
    {12, 5, 17, 1, 13, 3, 0, 15, 8, 11, 6, 14, 16, 7, 4, 9, 2, 10},
    {0, 10, 7, 6, 17, 9, 5, 4, 15, 14, 3, 2, 8, 12, 1, 13, 16, 11},
    {1, 10, 4, 16, 7, 2, 17, 6, 3, 15, 9, 11, 12, 8, 5, 0, 13, 14},
    {8, 17, 13, 10, 12, 11, 15, 1, 6, 5, 4, 2, 14, 7, 16, 3, 0, 9},
    {0, 14, 13, 9, 6, 2, 10, 16, 17, 4, 7, 3, 1, 12, 5, 8, 11, 15},
    {11, 9, 17, 4, 12, 0, 16, 15, 8, 1, 7, 13, 5, 2, 3, 14, 6, 10},
    {17, 11, 10, 1, 7, 8, 14, 6, 16, 0, 3, 12, 5, 13, 9, 15, 2, 4},
    {14, 15, 3, 17, 6, 12, 13, 0, 10, 11, 7, 2, 1, 9, 16, 8, 5, 4},
    {3, 13, 2, 4, 16, 5, 14, 8, 12, 9, 0, 1, 10, 17, 11, 15, 7, 6},
    {1, 3, 13, 7, 17, 6, 12, 11, 0, 14, 10, 5, 2, 15, 8, 9, 16, 4},
    {3, 12, 11, 6, 8, 0, 7, 14, 1, 5, 9, 2, 13, 17, 15, 4, 10, 16},
    {3, 15, 0, 13, 4, 5, 11, 10, 9, 12, 14, 8, 2, 6, 1, 7, 17, 16},
    {9, 4, 8, 16, 17, 6, 11, 5, 14, 7, 15, 1, 2, 13, 12, 10, 0, 3},
    {11, 16, 13, 3, 7, 0, 8, 15, 5, 17, 9, 12, 10, 1, 4, 14, 6, 2},
    {6, 4, 3, 7, 2, 16, 10, 9, 8, 17, 5, 15, 11, 12, 1, 0, 14, 13},
};

struct SplitFigures {
  double median_m = 0.0;  ///< median held-out MAE over the 20 splits [m]
  double mean_m = 0.0;    ///< mean [m]
  double worst_m = 0.0;   ///< largest [m]
};

/// predict_with_orientation over the 20 splits; `set_aside`, when given, counts the splits on
/// which the blunder test set a pose aside and `largest_w_ratio` receives the largest w / critical w
/// of those (without them none may be set aside).
SplitFigures twenty_splits(double joint_step_rad, bool controller_tcp = false, int* set_aside = nullptr,
                           double* largest_w_ratio = nullptr) {
  std::vector<double> mae_m;
  for (const auto& permutation : kTwentySplits) {
    const std::vector<std::size_t> train(permutation, permutation + 12);
    const std::vector<std::size_t> test(permutation + 12, permutation + 18);
    double ratio = 0.0;
    mae_m.push_back(
        predict_with_orientation(train, test, joint_step_rad, controller_tcp, set_aside != nullptr ? &ratio : nullptr));
    if (set_aside != nullptr && ratio > 0.0) {
      ++*set_aside;
      *largest_w_ratio = std::max(*largest_w_ratio, ratio);
    }
    std::printf(" %.4f", mae_m.back() * 1e3);
  }
  std::printf("\n");
  SplitFigures f;
  for (double m : mae_m) f.mean_m += m / static_cast<double>(mae_m.size());
  std::sort(mae_m.begin(), mae_m.end());
  f.median_m = 0.5 * (mae_m[9] + mae_m[10]);
  f.worst_m = mae_m[19];
  return f;
}

// With orientation, measured: median 0.0785 mm, mean 0.0870 mm, worst 0.190 mm, no pose set
// aside (at the sigmas' lever of 10 mm, without the joints' noise: 0.0853 / 0.0994 / 0.200 mm;
// 4-8 mm on 4 splits when fixing tool_x froze targets 2 and 3).
TEST(Ur5ePendant, OrientationTwentySplits) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const SplitFigures f = twenty_splits(0.0);
  std::printf("UR5e pendant with orientation, 20 splits: median %.4f mm, mean %.4f mm, worst %.4f mm\n",
              f.median_m * 1e3, f.mean_m * 1e3, f.worst_m * 1e3);
  EXPECT_LT(f.median_m, 0.080e-3);
  EXPECT_LT(f.mean_m, 0.090e-3);
  EXPECT_LT(f.worst_m, 0.20e-3);  // no split with targets 2 and 3 frozen (4-8 mm)
}

// The joints' 0.01 deg rounding also as joint reading noise of each sample (LmOptions::joint_sigma_rad,
// docs/robust.md): measured first-12 0.0973 mm (0.0725 without), 20 splits median 0.0868 mm
// (0.0785), mean 0.0889 mm (0.0870), worst 0.183 mm (0.190): worse. Not the default.
TEST(Ur5ePendant, JointNoiseOnTheTwentySplits) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const double step_rad = 0.01 * M_PI / 180.0;
  const double first12_m =
      predict_with_orientation({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, {12, 13, 14, 15, 16, 17}, step_rad);
  const SplitFigures f = twenty_splits(step_rad);
  std::printf(
      "UR5e pendant with orientation and joint noise 0.01 deg: first 12 %.4f mm; 20 splits: median %.4f mm, "
      "mean %.4f mm, worst %.4f mm\n",
      first12_m * 1e3, f.median_m * 1e3, f.mean_m * 1e3, f.worst_m * 1e3);
  EXPECT_LT(first12_m, 0.10e-3);
  EXPECT_LT(f.median_m, 0.090e-3);
  EXPECT_LT(f.mean_m, 0.092e-3);
  EXPECT_LT(f.worst_m, 0.19e-3);
}

// The pendant's readings are the controller's own TCP: in the base frame, at the configured
// TCP offset (here the flange). With both known (--controller-tcp) LM estimates joint 1
// instead of a base. Measured: first-12 split 0.0629 mm (the issue's 0.070 mm, scipy's
// 0.066 mm); 0.0725 mm with base and tool fitted.
TEST(Ur5ePendant, ControllerTcpMeetsTheIssuesTargetOnTheFirstTwelve) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  const double mae_m =
      predict_with_orientation({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, {12, 13, 14, 15, 16, 17}, 0.0, true);
  RecordProperty("predicted_mae_um", static_cast<int>(mae_m * 1e6));
  std::printf("UR5e pendant, controller TCP (base and tool known): 12 poses fitted, 6 predicted: MAE %.4f mm\n",
              mae_m * 1e3);
  EXPECT_LT(mae_m, 0.065e-3);
}

// Measured: median 0.0660 mm, mean 0.0663 mm, worst 0.0893 mm (base and tool fitted: 0.0785 /
// 0.0870 / 0.190 mm, OrientationTwentySplits). On one split the blunder test sets one pose aside
// at w 6.05 against 5.98 (1 % over): a stretched arm (elbow at 30 deg) whose virtual targets
// share its position error, which the pose's test counts as three independent points
// (docs/robust.md). No other pose on any split.
TEST(Ur5ePendant, ControllerTcpTwentySplits) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  int set_aside = 0;
  double largest_w_ratio = 0.0;
  const SplitFigures f = twenty_splits(0.0, true, &set_aside, &largest_w_ratio);
  std::printf(
      "UR5e pendant, controller TCP, 20 splits: median %.4f mm, mean %.4f mm, worst %.4f mm; a pose set aside on %d "
      "split(s), largest w / critical %.3f\n",
      f.median_m * 1e3, f.mean_m * 1e3, f.worst_m * 1e3, set_aside, largest_w_ratio);
  EXPECT_LT(f.median_m, 0.068e-3);
  EXPECT_LT(f.mean_m, 0.068e-3);
  EXPECT_LT(f.worst_m, 0.095e-3);
  EXPECT_LE(set_aside, 1);
  EXPECT_LT(largest_w_ratio, 1.02);
}

TEST(Ur5ePendant, FloatFkIsNotGoodEnough) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/joint-eef-data.csv");
  // Why the library is double: the same chain in float is off by more than half the tracker noise.
  UrCalibrationDeltas deltas;
  ASSERT_TRUE(textio::read_ur_calibration_conf(kDir + "calibration.conf", &deltas).ok());
  RobotModel calibrated;
  ASSERT_EQ(apply_ur_deltas(nominal_model(RobotType::ur5e), deltas, &calibrated), Status::ok);
  double worst_m = 0.0;
  for (const PendantReading& r : read_pendant_csv()) {
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
    for (int j = 0; j < 6; ++j) {
      const DhJoint& dh = calibrated.joints[j];
      const float t = static_cast<float>(r.q_rad(j) + dh.theta_offset_rad);
      const float al = static_cast<float>(dh.alpha_rad);
      Eigen::Matrix4f a;
      a << std::cos(t), -std::sin(t) * std::cos(al), std::sin(t) * std::sin(al),
          static_cast<float>(dh.a_m) * std::cos(t), std::sin(t), std::cos(t) * std::cos(al),
          -std::cos(t) * std::sin(al), static_cast<float>(dh.a_m) * std::sin(t), 0.f, std::sin(al), std::cos(al),
          static_cast<float>(dh.d_m), 0.f, 0.f, 0.f, 1.f;
      pose = pose * a;
    }
    const Vec3 p = pose.block<3, 1>(0, 3).cast<double>();
    worst_m = std::max(worst_m, (p - fk_tool_point(calibrated, r.q_rad)).norm());
  }
  EXPECT_GT(worst_m, 5e-6);  // half the tracker's noise: float is not a calibration-grade type
}

TEST(UrCalibrationConf, MalformedInputsAreNamed) {
  UrCalibrationDeltas d;
  const std::string good_rows = "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\ndelta_d = [0,0,0,0,0,0]\n";
  EXPECT_TRUE(
      textio::parse_ur_calibration_conf("[mounting]\n" + good_rows + "delta_alpha = [0,0,0,0,0,0]\n", "x", &d).ok());
  const struct {
    std::string text;
    std::string expected;
  } cases[] = {
      {"", "no [mounting] section"},
      {"[mounting]\n" + good_rows, "no delta_alpha"},
      {"[mounting]\n" + good_rows + "delta_alpha = [0,0,0,0,0]\n", "expected 6 values"},
      {"[mounting]\n" + good_rows + "delta_alpha = [0,0,0,0,0,0,0]\n", "more than 6"},
      {"[mounting]\n" + good_rows + "delta_alpha = [0,0,x,0,0,0]\n", "not a number: 'x'"},
      {"[mounting]\n" + good_rows + "delta_alpha = [0,0,nan,0,0,0]\n", "NaN or Inf"},
      {"[mounting]\n" + good_rows + "delta_alpha = 0,0,0,0,0,0\n", "expected [v1"},
      {"[mounting]\n" + good_rows + "delta_a = [0,0,0,0,0,0]\n", "given twice"},
  };
  for (const auto& c : cases) {
    const port::Error r = textio::parse_ur_calibration_conf(c.text, "conf", &d);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message;
  }
  EXPECT_FALSE(textio::read_ur_calibration_conf("/nonexistent/calibration.conf", &d).ok());
}

TEST(UrCalibrationConf, AByteOrderMarkAndASectionNameInCapitalsAreRead) {
  UrCalibrationDeltas d;
  const std::string rows =
      "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0.5,0,0,0,0]\ndelta_d = [0,0,0,0,0,0]\n"
      "delta_alpha = [0,0,0,0,0,0]\n";
  const port::Error r = textio::parse_ur_calibration_conf("\xEF\xBB\xBF[Mounting]\n" + rows, "conf", &d);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(d.delta_a_m[1], 0.5);
}

TEST(UrCalibrationConf, FormatReadsBackToTheSameBits) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  UrCalibrationDeltas d;
  ASSERT_TRUE(textio::read_ur_calibration_conf(kDir + "calibration.conf", &d).ok());
  UrCalibrationDeltas back;
  ASSERT_TRUE(textio::parse_ur_calibration_conf(textio::format_ur_calibration_conf(d), "out", &back).ok());
  EXPECT_EQ(0, std::memcmp(&d, &back, sizeof d));
}

}  // namespace
}  // namespace hivecal::ur_calibration_conf_test
