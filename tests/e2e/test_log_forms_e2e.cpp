// `hivecal calibrate` gives the same calibration from one simulated session whatever form it
// comes in: serial captures, hivecal CSV logs, a UR RTDE log + a mm/ms tracker export, a
// rostopic log (joints in the driver's order) + the export, a ROS 2 bag + the export. The
// export drops the lost-beam rows and rounds mm -> m, so results agree to rounding only.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <sys/stat.h>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/log_forms.hpp"
#include "textio/robot_description.hpp"
#include "textio/logs.hpp"
#include "record/result_json.hpp"

namespace hivecal::log_forms_e2e_test {
namespace {

bool write(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return std::fclose(f) == 0 && ok;
}

/// Calibrates from `robot` and `tracker` into dir/name.json; the result or a failure. LM alone:
/// what differs between the forms is the reading, and the job's population stage would add
/// ~20 s under qemu without reading anything else.
record::CalibrationFile calibrate(const std::string& dir, const std::string& name, const std::string& robot,
                                  const std::string& tracker) {
  const std::string out = dir + "/" + name + ".json";
  EXPECT_EQ(test::run(cli::calibrate_main,
                      {"--robot", robot, "--tracker", tracker, "--method", "lm", "--out", out, "--quiet"}),
            cli::kExitOk)
      << name;
  record::CalibrationFile file;
  const port::Error read = record::read_calibration_json(out, &file);
  EXPECT_TRUE(read.ok()) << name << ": " << read.message;
  return file;
}

void expect_same(const record::CalibrationFile& a, const record::CalibrationFile& b, double tolerance,
                 const char* what) {
  for (int j = 0; j < kSixJoints; ++j) {
    EXPECT_NEAR(a.model.joints[j].a_m, b.model.joints[j].a_m, tolerance) << what << " joint " << j;
    EXPECT_NEAR(a.model.joints[j].d_m, b.model.joints[j].d_m, tolerance) << what << " joint " << j;
    EXPECT_NEAR(a.model.joints[j].theta_offset_rad, b.model.joints[j].theta_offset_rad, tolerance) << what;
    EXPECT_NEAR(a.model.joints[j].alpha_rad, b.model.joints[j].alpha_rad, tolerance) << what;
  }
  EXPECT_NEAR((a.model.tool_m - b.model.tool_m).norm(), 0.0, tolerance) << what;
  EXPECT_NEAR(a.metrics.test.mae_m[3], b.metrics.test.mae_m[3], tolerance) << what;
  EXPECT_EQ(a.metrics.test.count, b.metrics.test.count) << what;
}

TEST(LogFormsEndToEnd, EveryFormOfOneSessionCalibratesTheSame) {
  const std::string dir = test::make_temp_dir("hivecal_forms");
  ASSERT_FALSE(dir.empty());
  ASSERT_EQ(
      test::run(sim::simulate_main, {"--out-dir", dir, "--waypoints", "12", "--duration-s", "150", "--seed", "5"}),
      cli::kExitOk);
  const textio::RobotLog robot = textio::read_robot_log(dir + "/robot_joints.csv");
  const textio::TrackerLog tracker = textio::read_tracker_log(dir + "/tracker.csv");
  ASSERT_TRUE(robot.ok && tracker.ok) << robot.error << tracker.error;
  ASSERT_TRUE(write(dir + "/rtde.csv", test::rtde_log(robot.records)));
  ASSERT_TRUE(write(dir + "/joint_states.csv", test::rostopic_log(robot.records)));
  ASSERT_TRUE(write(dir + "/export.csv", test::tracker_export(tracker.records)));

  const record::CalibrationFile captures = calibrate(dir, "captures", dir + "/robot.cap", dir + "/tracker.cap");
  const record::CalibrationFile csv = calibrate(dir, "csv", dir + "/robot_joints.csv", dir + "/tracker.csv");
  expect_same(captures, csv, 0.0, "hivecal CSV");  // the same records, bit for bit
  const record::CalibrationFile rtde = calibrate(dir, "rtde", dir + "/rtde.csv", dir + "/export.csv");
  expect_same(captures, rtde, 1e-9, "RTDE + export");
  const record::CalibrationFile ros = calibrate(dir, "ros", dir + "/joint_states.csv", dir + "/export.csv");
  expect_same(captures, ros, 1e-9, "rostopic + export");
  EXPECT_EQ(test::run(cli::calibrate_main, {"--robot", dir + "/tracker.cap", "--tracker", dir + "/robot.cap", "--out",
                                            dir + "/swapped.json", "--quiet"}),
            cli::kExitBadInput);
#if HIVECAL_HAVE_SQLITE3
  const std::string bag = dir + "/bag";
  ASSERT_EQ(::mkdir(bag.c_str(), 0755), 0);
  ASSERT_TRUE(test::write_ros2_bag(bag, robot.records));
  const record::CalibrationFile ros2 = calibrate(dir, "ros2", bag, dir + "/export.csv");
  expect_same(captures, ros2, 1e-9, "ROS 2 bag + export");
#endif
  std::system(("rm -rf '" + dir + "'").c_str());
}

}  // namespace
}  // namespace hivecal::log_forms_e2e_test
