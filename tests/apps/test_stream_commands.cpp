// The `simulate`, `extract` and `record` entry points: outputs readable by the project's
// own readers (CSV logs, truth as a robot-calibration/1 document), samples out of the
// simulated captures, usage errors.
#include <gtest/gtest.h>

#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/simulate.hpp"
#include "commands/streams.hpp"
#include "hivecal/model/dataset.hpp"
#include "sim/sim_model.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/shared_data.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/logs.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "record/result_json.hpp"

namespace hivecal::stream_commands_test {
namespace {

using test::make_temp_dir;
using test::run;

TEST(StreamCommands, SimulateWritesReadableOutputsAndExtractPairsThem) {
  const std::string dir = make_temp_dir();
  ASSERT_FALSE(dir.empty());
  ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir, "--waypoints", "12", "--duration-s", "150", "--seed", "3"}),
            cli::kExitOk);

  sim::SimConfig config;
  config.seed = 3;
  config.waypoint_count = 12;
  config.duration_s = 150.0;
  const sim::Session session(config);
  record::CalibrationFile truth;
  const port::Error parsed = record::read_calibration_json(dir + "/truth.json", &truth);
  ASSERT_TRUE(parsed.ok()) << parsed.message;
  EXPECT_NEAR(truth.model.joints[1].a_m, session.truth().model.joints[1].a_m, 1e-15);
  EXPECT_NEAR((truth.base_to_tracker.translation_m - session.truth().base_to_tracker.translation_m).norm(), 0.0, 1e-12);

  const textio::RobotLog robot = textio::read_robot_log(dir + "/robot_joints.csv");
  ASSERT_TRUE(robot.ok) << robot.error;
  const textio::TrackerLog tracker = textio::read_tracker_log(dir + "/tracker.csv");
  ASSERT_TRUE(tracker.ok) << tracker.error;
  EXPECT_EQ(robot.format, textio::LogFormat::hivecal_robot);
  EXPECT_EQ(tracker.format, textio::LogFormat::hivecal_tracker);
  EXPECT_GT(robot.records.size(), 18000u);
  EXPECT_GT(tracker.records.size(), 1450u);
  std::FILE* truth_samples = std::fopen((dir + "/truth_samples.csv").c_str(), "r");
  ASSERT_NE(truth_samples, nullptr);
  std::fclose(truth_samples);

  ASSERT_EQ(run(streams::extract_main,
                {"--robot", dir + "/robot.cap", "--tracker", dir + "/tracker.cap", "--samples", dir + "/samples.csv"}),
            cli::kExitOk);
  static Dataset<4096> samples;
  samples.clear();
  const port::Error read = textio::read_samples_csv(dir + "/samples.csv", &samples);
  ASSERT_TRUE(read.ok()) << read.message;
  EXPECT_GT(samples.size(), 150u);
  for (const char* name : {"robot.cap", "tracker.cap", "robot_joints.csv", "tracker.csv", "truth.json",
                           "truth_samples.csv", "samples.csv"})
    std::remove((dir + "/" + name).c_str());
  ::rmdir(dir.c_str());
}

TEST(StreamCommands, SimulateTakesTheTrueGeometryFromACalibrationConf) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  // A real UR5e factory calibration (shared test data) as the simulated robot's geometry.
  const std::string conf = std::string(HIVECAL_TEST_DATA_DIR) + "/ur5e-pendant/calibration.conf";
  const std::string dir = make_temp_dir();
  ASSERT_FALSE(dir.empty());
  ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir, "--robot-model", "ur5e", "--calibration-conf", conf,
                                     "--waypoints", "3", "--duration-s", "20"}),
            cli::kExitOk);
  UrCalibrationDeltas deltas;
  ASSERT_TRUE(textio::read_ur_calibration_conf(conf, &deltas).ok());
  RobotModel expected;
  ASSERT_EQ(apply_ur_deltas(nominal_model(RobotType::ur5e), deltas, &expected), Status::ok);
  record::CalibrationFile truth;
  ASSERT_TRUE(record::read_calibration_json(dir + "/truth.json", &truth).ok());
  EXPECT_EQ(truth.robot, "ur5e");
  for (int j = 0; j < kSixJoints; ++j) {
    EXPECT_DOUBLE_EQ(truth.model.joints[j].a_m, expected.joints[j].a_m);
    EXPECT_DOUBLE_EQ(truth.model.joints[j].d_m, expected.joints[j].d_m);
    EXPECT_DOUBLE_EQ(truth.model.joints[j].theta_offset_rad, expected.joints[j].theta_offset_rad);
    EXPECT_DOUBLE_EQ(truth.model.joints[j].alpha_rad, expected.joints[j].alpha_rad);
  }
  for (const char* name :
       {"robot.cap", "tracker.cap", "robot_joints.csv", "tracker.csv", "truth.json", "truth_samples.csv"})
    std::remove((dir + "/" + name).c_str());
  ::rmdir(dir.c_str());
}

TEST(StreamCommands, HelpAndUsageErrors) {
  EXPECT_EQ(run(sim::simulate_main, {"--help"}), cli::kExitOk);
  EXPECT_EQ(run(streams::record_main, {"--help"}), cli::kExitOk);
  EXPECT_EQ(run(streams::extract_main, {"--help"}), cli::kExitOk);
  EXPECT_EQ(run(streams::record_main, {}), cli::kExitUsage);  // no port given
  EXPECT_EQ(run(streams::extract_main, {"--robot", "x.cap"}), cli::kExitUsage);
  EXPECT_EQ(run(sim::simulate_main, {"--robot-model", "ur7"}), cli::kExitUsage);
  EXPECT_EQ(run(streams::record_main, {"--robot-port", "/nonexistent/tty"}), cli::kExitBadInput);
  EXPECT_EQ(run(streams::extract_main, {"--robot", "/nonexistent.cap", "--tracker", "/nonexistent.cap"}),
            cli::kExitBadInput);
}

}  // namespace
}  // namespace hivecal::stream_commands_test
