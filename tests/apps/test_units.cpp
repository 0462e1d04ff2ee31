// Units and plausibility of text inputs (issue 11): --length-unit / --angle-unit on every text
// input kind give the SI input's values; a header unit and a disagreeing option are an error;
// degrees and millimetres read as SI are refused with the hint; an implausible UR
// calibration.conf is refused; a fit that moves too far or loses to the baseline warns.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "commands/fit_checks.hpp"
#include "report/report.hpp"
#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"
#include "textio/logs.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::units_test {
namespace {

constexpr double kDegPerRad = 57.29577951308232;
constexpr double kSame = 1e-12;  // SI input vs the same values in mm / deg [m] or [rad]

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// Ten random samples of a UR5 session, SI.
const Dataset<16>& session() {
  static Dataset<16> data;
  if (data.size() == 0) {
    Random random(11);
    test::fill_dataset(nominal_model(RobotType::ur5), test::example_base_to_tracker(), 10, 1e-5, &random, &data);
  }
  return data;
}

/// The session as a samples CSV: `header` and the values scaled by 1/angle_scale, 1/length_scale.
std::string samples_text(const std::string& header, double angle_scale, double length_scale) {
  std::string out = header + "\n";
  for (const Sample& s : session().samples()) {
    for (int j = 0; j < kSixJoints; ++j) out += g17(s.q_rad(j) / angle_scale) + ",";
    out += g17(s.point_m.x() / length_scale) + "," + g17(s.point_m.y() / length_scale) + "," +
           g17(s.point_m.z() / length_scale) + "\n";
  }
  return out;
}

void expect_session(const DatasetBase& read, const char* what) {
  ASSERT_EQ(read.size(), session().size()) << what;
  for (std::size_t i = 0; i < read.size(); ++i) {
    EXPECT_LE((read.samples()[i].q_rad - session().samples()[i].q_rad).cwiseAbs().maxCoeff(), kSame) << what;
    EXPECT_LE((read.samples()[i].point_m - session().samples()[i].point_m).cwiseAbs().maxCoeff(), kSame) << what;
  }
}

port::Error read_samples(const std::string& path, const textio::InputUnits& units, DatasetBase* out) {
  static_cast<Dataset<16>*>(out)->clear();
  return textio::read_samples_csv(path, out, units);
}

const char* const kPlainHeader = "q1,q2,q3,q4,q5,q6,x,y,z";
const textio::InputUnits kMmDeg{"mm", "deg"};

TEST(Units, SamplesInMillimetresAndDegreesReadAsSi) {
  const test::TempDir dir;
  static Dataset<16> read;
  ASSERT_TRUE(read_samples(dir.write("si.csv", samples_text(kPlainHeader, 1.0, 1.0)), {}, &read).ok());
  expect_session(read, "SI");
  // By the options.
  const std::string flagged = dir.write("mmdeg.csv", samples_text(kPlainHeader, 1.0 / kDegPerRad, 1e-3));
  const port::Error by_options = read_samples(flagged, kMmDeg, &read);
  ASSERT_TRUE(by_options.ok()) << by_options.message;
  expect_session(read, "--length-unit mm --angle-unit deg");
  // By the header (no option), and by both when they agree.
  const std::string header = "q1 [deg],q2 [deg],q3 [deg],q4 [deg],q5 [deg],q6 [deg],x [mm],y [mm],z [mm]";
  const std::string headed = dir.write("headed.csv", samples_text(header, 1.0 / kDegPerRad, 1e-3));
  ASSERT_TRUE(read_samples(headed, {}, &read).ok());
  expect_session(read, "header units");
  ASSERT_TRUE(read_samples(headed, kMmDeg, &read).ok());
  expect_session(read, "header units and the same options");
  // Units in parentheses and the degree sign, as pendants write them.
  const std::string pendant =
      "q1 (\xC2\xB0),q2 (\xC2\xB0),q3 (\xC2\xB0),q4 [\xC2\xB0],q5 (deg),q6 (DEG),x (mm),y (mm),z (mm)";
  ASSERT_TRUE(read_samples(dir.write("pendant.csv", samples_text(pendant, 1.0 / kDegPerRad, 1e-3)), {}, &read).ok());
  expect_session(read, "pendant-style header units");
  // One option alone.
  const std::string mm_only = dir.write("mm.csv", samples_text(kPlainHeader, 1.0, 1e-3));
  ASSERT_TRUE(read_samples(mm_only, {"mm", ""}, &read).ok());
  expect_session(read, "--length-unit mm");
  ASSERT_TRUE(read_samples(dir.write("m.csv", samples_text(kPlainHeader, 1.0, 1.0)), {"m", "rad"}, &read).ok());
  expect_session(read, "--length-unit m --angle-unit rad");
}

TEST(Units, HeaderUnitAndADisagreeingOptionAreAnError) {
  const test::TempDir dir;
  static Dataset<16> read;
  const std::string header = "q1,q2,q3,q4,q5,q6,x [mm],y [mm],z [mm]";
  const std::string path = dir.write("h.csv", samples_text(header, 1.0, 1e-3));
  port::Error r = read_samples(path, {"m", ""}, &read);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.fault, port::Fault::input);
  EXPECT_NE(r.message.find("h.csv:1: column 'x' is in [mm] by its header, but --length-unit m was given"),
            std::string::npos)
      << r.message;
  const std::string deg_header = "q1 [deg],q2,q3,q4,q5,q6,x,y,z";
  r = read_samples(dir.write("d.csv", samples_text(deg_header, 1.0, 1.0)), {"", "rad"}, &read);
  EXPECT_NE(r.message.find("column 'q1' is in [deg] by its header, but --angle-unit rad was given"), std::string::npos)
      << r.message;
  // A unit of the wrong quantity in a samples header.
  r = read_samples(dir.write("w.csv", samples_text("q1,q2,q3,q4,q5,q6,x [deg],y,z", 1.0, 1.0)), {}, &read);
  EXPECT_NE(r.message.find("column 'x': unit '[deg]' is not one of [m], [mm], [um]"), std::string::npos) << r.message;
}

TEST(Units, PosesToPredictInDegrees) {
  const test::TempDir dir;
  std::vector<JointVector> si;
  std::vector<JointVector> deg;
  std::string si_text = "t,q1,q2,q3,q4,q5,q6\n";
  std::string deg_text = si_text;
  for (const Sample& s : session().samples()) {
    si_text += "0";
    deg_text += "0";
    for (int j = 0; j < kSixJoints; ++j) {
      si_text += "," + g17(s.q_rad(j));
      deg_text += "," + g17(s.q_rad(j) * kDegPerRad);
    }
    si_text += "\n";
    deg_text += "\n";
  }
  ASSERT_TRUE(textio::read_joints_csv(dir.write("si.csv", si_text), &si).ok());
  const port::Error r = textio::read_joints_csv(dir.write("deg.csv", deg_text), &deg, {"", "deg"});
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(si.size(), deg.size());
  for (std::size_t i = 0; i < si.size(); ++i) EXPECT_LE((si[i] - deg[i]).cwiseAbs().maxCoeff(), kSame);
  // Without the option: the hint, naming the first joint beyond one turn and its line.
  std::vector<JointVector> refused;
  const port::Error hint = textio::read_joints_csv(dir.path() + "/deg.csv", &refused);
  ASSERT_FALSE(hint.ok());
  EXPECT_NE(hint.message.find("deg.csv:2: joint q"), std::string::npos) << hint.message;
  EXPECT_NE(hint.message.find("looks like degrees: use --angle-unit deg"), std::string::npos) << hint.message;
}

/// A robot log of the session's joints: `header`, then t and the six joints times `scale`,
/// separated by `separator`.
std::string robot_log(const std::string& header, char separator, double scale) {
  std::string out = header + "\n";
  double t = 1.0;
  for (const Sample& s : session().samples()) {
    out += g17(t);
    t += 0.008;
    for (int j = 0; j < kSixJoints; ++j) out += separator + g17(s.q_rad(j) * scale);
    out += "\n";
  }
  return out;
}

void expect_joints(const textio::RobotLog& log, const char* what) {
  ASSERT_TRUE(log.ok) << what << ": " << log.error;
  ASSERT_EQ(log.records.size(), session().size()) << what;
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    for (int j = 0; j < kSixJoints; ++j) {
      EXPECT_NEAR(log.records[i].q_rad[j], session().samples()[i].q_rad(j), kSame) << what;
    }
  }
}

TEST(Units, RobotLogsInDegrees) {
  textio::RobotLogOptions deg;
  deg.units.angle = "deg";
  const std::string hivecal_header = "t,q1,q2,q3,q4,q5,q6";
  expect_joints(textio::parse_robot_log(robot_log(hivecal_header, ',', 1.0), "si.csv"), "hivecal SI");
  expect_joints(textio::parse_robot_log(robot_log(hivecal_header, ',', kDegPerRad), "deg.csv", deg), "hivecal deg");
  const std::string rtde_header = "timestamp actual_q_0 actual_q_1 actual_q_2 actual_q_3 actual_q_4 actual_q_5";
  expect_joints(textio::parse_robot_log(robot_log(rtde_header, ' ', kDegPerRad), "rtde.csv", deg), "RTDE deg");
  // rostopic echo -p /joint_states, joints named (here in the driver's order 3, 2, 1, 4, 5, 6).
  std::string rostopic = "%time,field.header.seq,field.header.stamp,field.header.frame_id";
  for (int k = 0; k < kSixJoints; ++k) rostopic += ",field.name" + std::to_string(k);
  for (int k = 0; k < kSixJoints; ++k) rostopic += ",field.position" + std::to_string(k);
  rostopic += "\n";
  const int order[kSixJoints] = {2, 1, 0, 3, 4, 5};
  std::uint64_t stamp_ns = 1700000000000000000ULL;
  for (const Sample& s : session().samples()) {
    rostopic += std::to_string(stamp_ns) + ",0," + std::to_string(stamp_ns) + ",base";
    for (const int j : order) rostopic += "," + textio::kUrJointNames[static_cast<std::size_t>(j)];
    for (const int j : order) rostopic += "," + g17(s.q_rad(j) * kDegPerRad);
    rostopic += "\n";
    stamp_ns += 8000000;
  }
  expect_joints(textio::parse_robot_log(rostopic, "js.csv", deg), "rostopic deg");
  const textio::RobotLog rostopic_hint = textio::parse_robot_log(rostopic, "js.csv");
  EXPECT_NE(rostopic_hint.error.find("(column 'field.position"), std::string::npos) << rostopic_hint.error;
  EXPECT_NE(rostopic_hint.error.find("looks like degrees: use --angle-unit deg"), std::string::npos)
      << rostopic_hint.error;
  // The header's unit and the option's agree: fine; disagree: an error.
  const std::string headed = "t;q1 [deg];q2 [deg];q3 [deg];q4 [deg];q5 [deg];q6 [deg]";
  expect_joints(textio::parse_robot_log(robot_log(headed, ';', kDegPerRad), "h.csv", deg), "header deg + option deg");
  textio::RobotLogOptions rad;
  rad.units.angle = "rad";
  const textio::RobotLog conflict = textio::parse_robot_log(robot_log(headed, ';', kDegPerRad), "h.csv", rad);
  EXPECT_FALSE(conflict.ok);
  EXPECT_NE(conflict.error.find("h.csv:1: column 'q1' is in [deg] by its header, but --angle-unit rad was given"),
            std::string::npos)
      << conflict.error;
  // Degrees read as rad: refused with the hint, naming the column of an RTDE log.
  const textio::RobotLog hint = textio::parse_robot_log(robot_log(rtde_header, ' ', kDegPerRad), "rtde.csv");
  EXPECT_FALSE(hint.ok);
  EXPECT_NE(hint.error.find("rtde.csv:2: joint q"), std::string::npos) << hint.error;
  EXPECT_NE(hint.error.find("(column 'actual_q_"), std::string::npos) << hint.error;
  EXPECT_NE(hint.error.find("looks like degrees: use --angle-unit deg"), std::string::npos) << hint.error;
}

TEST(Units, JointOfMoreThanOneTurnInDegreesIsNotAJoint) {
  textio::RobotLogOptions deg;
  deg.units.angle = "deg";
  const textio::RobotLog log =
      textio::parse_robot_log("t,q1,q2,q3,q4,q5,q6\n1,0,0,0,0,0,0\n2,0,0,400.5,0,0,0\n", "x.csv", deg);
  EXPECT_FALSE(log.ok);
  EXPECT_NE(log.error.find("x.csv:3: joint q3 = 400.5 is more than one turn"), std::string::npos) << log.error;
  // Exactly one turn either way is a joint position (UR joints span +-2 pi).
  const textio::RobotLog edge = textio::parse_robot_log("t,q1,q2,q3,q4,q5,q6\n1,360,-360,0,0,0,0\n", "e.csv", deg);
  EXPECT_TRUE(edge.ok) << edge.error;
  const textio::RobotLog in_rad = textio::parse_robot_log(
      "t,q1,q2,q3,q4,q5,q6\n1,6.283185307179586,-6.283185307179586,0,0,0,0\n2,0,0,95.2,0,0,0\n", "r.csv");
  EXPECT_FALSE(in_rad.ok);
  EXPECT_NE(in_rad.error.find("r.csv:3: joint q3 = 95.2 looks like degrees: use --angle-unit deg"), std::string::npos)
      << in_rad.error;
}

std::string tracker_log(const std::string& header, char separator, double scale) {
  std::string out = header + "\n";
  double t = 1.0;
  for (const Sample& s : session().samples()) {
    out += g17(t);
    t += 0.01;
    for (int k = 0; k < 3; ++k) out += separator + g17(s.point_m(k) * scale);
    out += "\n";
  }
  return out;
}

void expect_points(const textio::TrackerLog& log, const char* what) {
  ASSERT_TRUE(log.ok) << what << ": " << log.error;
  ASSERT_EQ(log.records.size(), session().size()) << what;
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(log.records[i].point_m[k], session().samples()[i].point_m(k), kSame) << what;
  }
}

TEST(Units, TrackerLogsInMillimetres) {
  expect_points(textio::parse_tracker_log(tracker_log("t,x,y,z", ',', 1.0), "si.csv"), "hivecal SI");
  expect_points(textio::parse_tracker_log(tracker_log("t,x,y,z", ',', 1e3), "mm.csv", {"mm", ""}), "hivecal mm");
  expect_points(textio::parse_tracker_log(tracker_log("Time;X;Y;Z", ';', 1e3), "e.csv", {"mm", ""}), "export mm");
  expect_points(textio::parse_tracker_log(tracker_log("Time;X [mm];Y [mm];Z [mm]", ';', 1e3), "e.csv", {"mm", ""}),
                "export [mm] + option mm");
  expect_points(textio::parse_tracker_log(tracker_log("Time (s);X (mm);Y (mm);Z (mm)", ';', 1e3), "p.csv"),
                "export (mm)");
  const textio::TrackerLog conflict =
      textio::parse_tracker_log(tracker_log("Time;X [mm];Y [mm];Z [mm]", ';', 1e3), "e.csv", {"m", ""});
  EXPECT_FALSE(conflict.ok);
  EXPECT_NE(conflict.error.find("e.csv:1: column 'x' is in [mm] by its header, but --length-unit m was given"),
            std::string::npos)
      << conflict.error;
  // Millimetres read as metres: the hint.
  const textio::TrackerLog hint = textio::parse_tracker_log(tracker_log("t,x,y,z", ',', 1e3), "mm.csv");
  EXPECT_FALSE(hint.ok);
  EXPECT_NE(hint.error.find("mm.csv:2: point x,y,z = "), std::string::npos) << hint.error;
  EXPECT_NE(hint.error.find("looks like millimetres: use --length-unit mm"), std::string::npos) << hint.error;
  // A point over 100 m in a declared unit is no measurement; a lost beam's NaN is still fine.
  const textio::TrackerLog far =
      textio::parse_tracker_log("t,x [mm],y [mm],z [mm]\n1,1,2,3\n2,150000,0,0\n", "far.csv");
  EXPECT_FALSE(far.ok);
  EXPECT_NE(far.error.find("far.csv:3: point x,y,z = 150000, 0, 0 is 150 m from the origin"), std::string::npos)
      << far.error;
  EXPECT_NE(far.error.find("not a measured point"), std::string::npos) << far.error;
  const textio::TrackerLog lost = textio::parse_tracker_log("t,x,y,z\n1,1,2,3\n2,nan,nan,nan\n3,99,0,0\n", "lost.csv");
  EXPECT_TRUE(lost.ok) << lost.error;
}

TEST(Units, SamplePointsInMillimetresGetTheHint) {
  const test::TempDir dir;
  static Dataset<16> read;
  const port::Error r = read_samples(dir.write("mm.csv", samples_text(kPlainHeader, 1.0, 1e-3)), {}, &read);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message.find("mm.csv:2: point x,y,z = "), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("looks like millimetres: use --length-unit mm"), std::string::npos) << r.message;
  const port::Error deg =
      read_samples(dir.write("deg.csv", samples_text(kPlainHeader, 1.0 / kDegPerRad, 1.0)), {}, &read);
  ASSERT_FALSE(deg.ok());
  EXPECT_NE(deg.message.find("looks like degrees: use --angle-unit deg"), std::string::npos) << deg.message;
}

// --- UR calibration.conf --------------------------------------------------------------------

TEST(UrDeltasPlausibility, SmallDeltasPassLargeOnesAreRefusedByName) {
  const RobotModel nominal = nominal_model(RobotType::ur5);
  UrCalibrationDeltas small;
  small.delta_a_m[1] = 1e-3;
  small.delta_theta_rad[2] = 1e-3;
  const double small_shift_m = textio::ur_deltas_tool_shift_m(nominal, small);
  EXPECT_GT(small_shift_m, 0.5e-3);  // measured, not assumed: the deltas do move the tool
  EXPECT_LT(small_shift_m, 5e-3);
  EXPECT_TRUE(textio::check_ur_deltas_plausible(nominal, small, "c.conf", "ur5").ok());
  UrCalibrationDeltas large = small;
  large.delta_a_m[1] = 0.1;  // another arm's upper arm
  const port::Error refused = textio::check_ur_deltas_plausible(nominal, large, "other.conf", "ur5");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.fault, port::Fault::input);
  EXPECT_NE(refused.message.find("other.conf: its deltas move the tool of the nominal ur5 by up to"), std::string::npos)
      << refused.message;
  EXPECT_NE(refused.message.find("not a calibration of this robot model?"), std::string::npos) << refused.message;
  // The cancelling metre-sized delta_d of parallel joints (as UR writes them) move nothing.
  UrCalibrationDeltas cancelling;
  cancelling.delta_d_m[1] = -200.0;
  cancelling.delta_d_m[2] = 200.0;
  EXPECT_LT(textio::ur_deltas_tool_shift_m(nominal, cancelling), 1e-9);
  cancelling.delta_d_m[2] = 199.9;  // ... unless they do not cancel
  EXPECT_NEAR(textio::ur_deltas_tool_shift_m(nominal, cancelling), 0.1, 1e-9);
}

TEST(UrDeltasPlausibility, RealUr5eCalibrationPasses) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur5e-pendant/calibration.conf");
  UrCalibrationDeltas deltas;
  const std::string path = std::string(HIVECAL_TEST_DATA_DIR) + "/ur5e-pendant/calibration.conf";
  ASSERT_TRUE(textio::read_ur_calibration_conf(path, &deltas).ok());
  const double shift_m = textio::ur_deltas_tool_shift_m(nominal_model(RobotType::ur5e), deltas);
  RecordProperty("ur5e_shift_um", static_cast<int>(shift_m * 1e6));
  EXPECT_GT(shift_m, 0.5e-3);
  EXPECT_LT(shift_m, 10e-3);
  EXPECT_TRUE(textio::check_ur_deltas_plausible(nominal_model(RobotType::ur5e), deltas, path, "ur5e").ok());
}

// --- warnings after a fit ---------------------------------------------------------------------

CalibrationResult fitted(const RobotModel& before, const RobotModel& after, double baseline_test_mae_m,
                         double final_test_mae_m) {
  CalibrationResult result;
  result.baseline.model = before;
  result.baseline.test.count = 10;
  result.baseline.test.mae_m[3] = baseline_test_mae_m;
  result.stage_count = 1;
  result.stages[0].model = after;
  result.stages[0].test.count = 10;
  result.stages[0].test.mae_m[3] = final_test_mae_m;
  return result;
}

TEST(FitWarnings, ParametersBeyondTheBoundsAndAWorseTestErrorAreNamed) {
  const RobotModel before = nominal_model(RobotType::ur5);
  RobotModel after = before;
  after.joints[2].a_m += 0.005;                   // within 20 mm
  after.joints[1].alpha_rad += 1.0 / kDegPerRad;  // within 2 deg
  EXPECT_TRUE(cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), cli::FitBounds{}).empty());
  after.joints[2].a_m += 0.020;                   // 25 mm in all
  after.joints[1].alpha_rad += 2.0 / kDegPerRad;  // 3 deg in all
  std::vector<std::string> warnings = cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), cli::FitBounds{});
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("alpha2 moved +3.000 deg"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find("a3 moved +25.000 mm (-0.392250 -> -0.367250 m), more than 20 mm"), std::string::npos)
      << warnings[1];
  // Tighter bounds name more; looser ones none.
  cli::FitBounds tight;
  tight.max_length_change_m = 1e-3;
  EXPECT_EQ(cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), tight).size(), 2u);
  cli::FitBounds loose;
  loose.max_length_change_m = 0.030;
  loose.max_angle_change_rad = 4.0 / kDegPerRad;
  EXPECT_TRUE(cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), loose).empty());
  // A test error worse than the baseline's.
  warnings = cli::fit_warnings(fitted(before, before, 1e-3, 1.5e-3), cli::FitBounds{});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("test error 1.5000 mm (MAE 3D) is worse than the uncalibrated baseline's 1.0000 mm"),
            std::string::npos)
      << warnings[0];
  // Equal up to rounding (a start model the fit leaves as it was) is not worse.
  EXPECT_TRUE(cli::fit_warnings(fitted(before, before, 1e-3, 1.005e-3), cli::FitBounds{}).empty());
  // Without test samples (--split 1) there is nothing to compare.
  CalibrationResult no_test = fitted(before, before, 0.0, 0.0);
  no_test.baseline.test.count = 0;
  no_test.stages[0].test.count = 0;
  EXPECT_TRUE(cli::fit_warnings(no_test, cli::FitBounds{}).empty());
  // The tool point is a length too.
  after = before;
  after.tool_m.z() += 0.030;
  warnings = cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), cli::FitBounds{});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("tool_z moved +30.000 mm"), std::string::npos) << warnings[0];
}

// A moved parameter that the data cannot tell from another (|rho| > 0.95 in Table 4) says
// so and what would separate them; a weaker correlation, or one of another parameter, does not.
TEST(FitWarnings, AMoveOfAStronglyCorrelatedParameterNamesItsPartner) {
  const RobotModel before = nominal_model(RobotType::ur5);
  RobotModel after = before;
  after.joints[4].theta_offset_rad += 2.3 / kDegPerRad;  // theta5
  report::ParameterRow theta5;
  theta5.name = "theta5";
  theta5.angle = true;
  theta5.correlated_with = "a5";
  theta5.correlation = 0.997;
  report::ParameterRow a3;
  a3.name = "a3";
  a3.correlated_with = "theta5";
  a3.correlation = -0.999;
  std::vector<std::string> warnings =
      cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), cli::FitBounds{}, {a3, theta5});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("theta5 moved +2.300 deg"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("strongly correlated with a5 (rho = 0.997): the data cannot separate the two"),
            std::string::npos)
      << warnings[0];
  EXPECT_NE(warnings[0].find("a second reflector would separate them"), std::string::npos) << warnings[0];
  theta5.correlation = -0.93;  // below 0.95: the move is the warning's whole story
  warnings = cli::fit_warnings(fitted(before, after, 1e-3, 1e-4), cli::FitBounds{}, {a3, theta5});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].find("correlated"), std::string::npos) << warnings[0];
}

// A fit whose data widened the prior's tolerances (LmResult::prior_tolerances) says to what and
// by how much per kind, and its held lines weigh each sigma against the widened tolerance.
TEST(PriorLines, WidenedTolerancesAreSaidAndHeldAgainst) {
  const LmPriorTolerances widened{2.0 * kDefaultPriorTolerances.dh_length_m, 3.0 * kDefaultPriorTolerances.dh_angle_rad,
                                  2.0 * kDefaultPriorTolerances.tool_m};
  EXPECT_TRUE(tolerances_widened(kDefaultPriorTolerances, widened));
  EXPECT_FALSE(tolerances_widened(kDefaultPriorTolerances, kDefaultPriorTolerances));
  const std::string line = cli::prior_widened_line(kDefaultPriorTolerances, widened);
  EXPECT_NE(line.find("widened to 2 mm per DH length (x2.00), 15 mrad per DH angle (x3.00), 40 mm per tool "
                      "coordinate (x2.00)"),
            std::string::npos)
      << line;
  static LmResult lm;
  lm.model = nominal_model(RobotType::ur5);
  const int d4 = model_param_index(3, DhField::d);
  lm.identifiability.kept_mask = param_bit(d4);
  lm.sigma.setZero();
  lm.sigma(d4) = 1.5e-3;
  const std::vector<std::string> held = cli::prior_held_lines(lm, widened, {});
  ASSERT_EQ(held.size(), 1u);
  EXPECT_NE(held[0].find("sigma 1.5 mm of its 2 mm tolerance"), std::string::npos) << held[0];
}

}  // namespace
}  // namespace hivecal::units_test
