// Logs of real tools (io-formats.md, "Logs written by other tools"): the same simulated
// session written as hivecal CSV, UR RTDE, rostopic (joints in the driver's order), a ROS 2
// bag and a mm/ms semicolon tracker export reads back to the same records (to the rounding
// of the unit conversion); every refusal has its message naming file:line.
#include <gtest/gtest.h>

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "testkit/temp_dir.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/error.hpp"
#include "sim/sim_model.hpp"
#include "testkit/log_forms.hpp"
#include "textio/csv.hpp"
#include "textio/delimited.hpp"
#include "textio/logs.hpp"
#include "textio/ros2_bag.hpp"

namespace hivecal::textio_logs_test {
namespace {

using textio::LogFormat;

struct SessionRecords {
  std::vector<JointStateRecord> joints;
  std::vector<TrackerPointRecord> points;
};

/// A short simulated session's records, as the devices send them.
const SessionRecords& session_records() {
  static const SessionRecords records = [] {
    sim::SimConfig config;
    config.seed = 12;
    config.waypoint_count = 4;
    config.duration_s = 20.0;
    const sim::Session session(config);
    SessionRecords out;
    sim::RobotStream robot(session);
    JointStateRecord joint;
    while (robot.next(&joint)) out.joints.push_back(joint);
    sim::TrackerStream tracker(session);
    TrackerPointRecord point;
    while (tracker.next(&point)) out.points.push_back(point);
    return out;
  }();
  return records;
}

void expect_same_joints(const textio::RobotLog& log, const std::vector<JointStateRecord>& expected) {
  ASSERT_TRUE(log.ok) << log.error;
  ASSERT_EQ(log.records.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(log.records[i].timestamp_us, expected[i].timestamp_us) << i;
    for (int j = 0; j < kSixJoints; ++j) ASSERT_EQ(log.records[i].q_rad[j], expected[i].q_rad[j]) << i << " " << j;
  }
}

TEST(TextLogs, RobotFormsGiveTheSameRecords) {
  const std::vector<JointStateRecord>& joints = session_records().joints;
  ASSERT_GT(joints.size(), 2000u);
  const textio::RobotLog hivecal = textio::parse_robot_log(test::hivecal_robot_csv(joints), "r.csv");
  EXPECT_EQ(hivecal.format, LogFormat::hivecal_robot);
  expect_same_joints(hivecal, joints);
  for (const char separator : {' ', ','}) {
    const textio::RobotLog rtde = textio::parse_robot_log(test::rtde_log(joints, separator), "rtde.csv");
    EXPECT_EQ(rtde.format, LogFormat::ur_rtde);
    expect_same_joints(rtde, joints);  // actual_q, never target_q (offset by 0.01 rad)
  }
  const textio::RobotLog ros = textio::parse_robot_log(test::rostopic_log(joints), "js.csv");
  EXPECT_EQ(ros.format, LogFormat::rostopic);
  expect_same_joints(ros, joints);  // mapped by name from the driver's order
  const int reversed[kSixJoints] = {5, 4, 3, 2, 1, 0};
  expect_same_joints(textio::parse_robot_log(test::rostopic_log(joints, reversed), "js2.csv"), joints);
  EXPECT_EQ(ros.counters.rows, joints.size());
  EXPECT_EQ(ros.counters.records, joints.size());
}

TEST(TextLogs, RostopicJointNamesAreAnArgumentAndExtraJointsAreIgnored) {
  const std::string header =
      "%time,field.header.seq,field.header.stamp,field.header.frame_id,field.name0,field.name1,field.name2,"
      "field.name3,field.name4,field.name5,field.name6,field.position0,field.position1,field.position2,"
      "field.position3,field.position4,field.position5,field.position6\n";
  const std::string text = header +
                           "1000500000,0,1000000000,,j6,j5,gripper,j4,j3,j2,j1,6,5,99,4,3,2,1\n"
                           "1000600000,1,1000100000,,gripper,x,y,z,u,v,w,0,0,0,0,0,0,0\n"
                           "1000700000,2,1000200000,,j1,j2,j3,j4,j5,j6,gripper,1,2,3,4,5,6,7\n";
  textio::RobotLogOptions options;
  ASSERT_TRUE(textio::parse_joint_names("j1, j2,j3,j4,j5,j6", &options));
  const textio::RobotLog log = textio::parse_robot_log(text, "g.csv", options);
  ASSERT_TRUE(log.ok) << log.error;
  ASSERT_EQ(log.records.size(), 2u);
  EXPECT_EQ(log.counters.missing_joints, 1u);  // the gripper-only message
  for (const JointStateRecord& r : log.records) {
    for (int j = 0; j < kSixJoints; ++j) EXPECT_EQ(r.q_rad[j], j + 1.0);
  }
  EXPECT_EQ(log.records[0].timestamp_us, 1000000u);
  // With the UR defaults no row names the joints: the message lists both sides.
  const textio::RobotLog ur = textio::parse_robot_log(text, "g.csv");
  EXPECT_FALSE(ur.ok);
  EXPECT_NE(ur.error.find("no message names all of the joints shoulder_pan_joint"), std::string::npos) << ur.error;
  EXPECT_NE(ur.error.find("'j6, j5, gripper"), std::string::npos) << ur.error;
  EXPECT_FALSE(textio::parse_joint_names("a,b,,d,e,f", &options));
  EXPECT_FALSE(textio::parse_joint_names("a,b,c,a", &options));
  std::string too_many = "j0";
  for (int j = 1; j <= kMaxJoints; ++j) too_many += ",j" + std::to_string(j);
  EXPECT_FALSE(textio::parse_joint_names(too_many, &options));        // kMaxJoints + 1 names
  ASSERT_TRUE(textio::parse_joint_names("a,b,c,d,e,f,g", &options));  // a seven-joint arm's
  EXPECT_EQ(options.joint_names.size(), 7u);
}

/// The options of a seven-revolute-joint arm's logs.
textio::RobotLogOptions seven_joint_options() {
  textio::RobotLogOptions options;
  options.units.joints.count = 7;
  return options;
}

/// A rostopic log of `names` (one message per line of positions 1 .. names.size()).
std::string rostopic_named(const std::vector<std::string>& names) {
  std::string out = "%time,field.header.stamp";
  for (std::size_t k = 0; k < names.size(); ++k) out += ",field.name" + std::to_string(k);
  for (std::size_t k = 0; k < names.size(); ++k) out += ",field.position" + std::to_string(k);
  for (int row = 0; row < 2; ++row) {
    out += "\n1000" + std::to_string(row) + "00000,1000" + std::to_string(row) + "00000";
    for (const std::string& n : names) out += "," + n;
    for (std::size_t k = 0; k < names.size(); ++k) out += "," + std::to_string(0.1 * static_cast<double>(k + 1));
  }
  return out + "\n";
}

TEST(TextLogs, RosLogsCarryTheArmsJointCount) {
  // A seven-joint arm's JointState: its joints in the message's order without names.
  const std::vector<std::string> panda = {"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                          "panda_joint5", "panda_joint6", "panda_joint7"};
  const textio::RobotLog log = textio::parse_robot_log(rostopic_named(panda), "p.csv", seven_joint_options());
  ASSERT_TRUE(log.ok) << log.error;
  ASSERT_EQ(log.records.size(), 2u);
  EXPECT_EQ(log.records[1].joint_count, 7);
  for (int j = 0; j < 7; ++j) EXPECT_DOUBLE_EQ(log.records[1].q_rad[j], 0.1 * (j + 1));
  // By name (--joint-names): the joints picked from a message with the gripper's in another order.
  textio::RobotLogOptions named = seven_joint_options();
  ASSERT_TRUE(textio::parse_joint_names("a7,a6,a5,a4,a3,a2,a1", &named));
  const textio::RobotLog by_name =
      textio::parse_robot_log(rostopic_named({"a1", "a2", "a3", "finger", "a4", "a5", "a6", "a7"}), "n.csv", named);
  ASSERT_TRUE(by_name.ok) << by_name.error;
  EXPECT_EQ(by_name.records[0].joint_count, 7);
  EXPECT_DOUBLE_EQ(by_name.records[0].q_rad[0], 0.8);  // a7
  EXPECT_DOUBLE_EQ(by_name.records[0].q_rad[6], 0.1);  // a1
  // Without names, a message of another joint count is refused naming both counts.
  std::vector<std::string> with_fingers = panda;
  with_fingers.push_back("panda_finger_joint1");
  EXPECT_NE(textio::parse_robot_log(rostopic_named(with_fingers), "f.csv", seven_joint_options())
                .error.find("f.csv:2: it names 8 joints ('panda_joint1, "),
            std::string::npos);
  EXPECT_NE(textio::parse_robot_log(rostopic_named(with_fingers), "f.csv", seven_joint_options())
                .error.find("), but the robot model has 7 joints (q1..q7): the joints of another arm? (--robot-model "
                            "names the arm; --joint-names N1,..,N7 picks the arm's joints by name, in order)"),
            std::string::npos)
      << textio::parse_robot_log(rostopic_named(with_fingers), "f.csv", seven_joint_options()).error;
  // A UR's six joints against the seven-joint arm: refused by the header.
  EXPECT_NE(textio::parse_robot_log(test::rostopic_log(session_records().joints), "u.csv", seven_joint_options())
                .error.find("u.csv:1: rostopic log with 6 joints (field.nameK with field.positionK), but the robot "
                            "model has 7 joints (q1..q7)"),
            std::string::npos);
}

TEST(TextLogs, RtdeLogsAreAUrsAlone) {
  const std::string rtde = test::rtde_log(session_records().joints);
  textio::RobotLogOptions rail;  // a UR on a rail: six revolute joints and a slide
  rail.units.joints.count = 7;
  rail.units.joints.prismatic = 1;
  rail.arm_name = "ur10-rail";
  EXPECT_NE(
      textio::parse_robot_log(rtde, "rtde.txt", rail)
          .error.find(
              "rtde.txt:1: a UR RTDE log (actual_q_0..actual_q_5: a UR controller's six revolute "
              "joints), but the robot model 'ur10-rail' has 7 joints (q1..q7, a prismatic one among them): RTDE is "
              "UR's alone"),
      std::string::npos)
      << textio::parse_robot_log(rtde, "rtde.txt", rail).error;
  textio::RobotLogOptions six_with_slide;
  six_with_slide.units.joints.prismatic = 1;
  EXPECT_FALSE(textio::parse_robot_log(rtde, "rtde.txt", six_with_slide).ok);
  EXPECT_TRUE(textio::parse_robot_log(rtde, "rtde.txt").ok);
}

TEST(TextLogs, RostopicUnixNanosecondsAreExact) {
  const std::string text =
      "%time,field.header.stamp,field.name0,field.name1,field.name2,field.name3,field.name4,field.name5,"
      "field.position0,field.position1,field.position2,field.position3,field.position4,field.position5\n"
      "1732390000123456999,1732390000123456499,shoulder_pan_joint,shoulder_lift_joint,elbow_joint,wrist_1_joint,"
      "wrist_2_joint,wrist_3_joint,0,0,0,0,0,0\n";
  const textio::RobotLog log = textio::parse_robot_log(text, "unix.csv");
  ASSERT_TRUE(log.ok) << log.error;
  EXPECT_EQ(log.records[0].timestamp_us, 1732390000123456u);  // 499 ns rounds down, beyond a double's integers
}

TEST(TextLogs, TrackerFormsGiveTheSamePoints) {
  const std::vector<TrackerPointRecord>& points = session_records().points;
  std::size_t valid = 0;
  for (const TrackerPointRecord& p : points) valid += p.is_valid() ? 1 : 0;
  ASSERT_GT(valid, 150u);
  ASSERT_LT(valid, points.size());  // the simulator loses the beam now and then
  const textio::TrackerLog hivecal = textio::parse_tracker_log(test::hivecal_tracker_csv(points), "t.csv");
  ASSERT_TRUE(hivecal.ok) << hivecal.error;
  EXPECT_EQ(hivecal.format, LogFormat::hivecal_tracker);
  ASSERT_EQ(hivecal.records.size(), points.size());
  EXPECT_EQ(hivecal.counters.not_valid, points.size() - valid);
  const textio::TrackerLog exported = textio::parse_tracker_log(test::tracker_export(points), "export.csv");
  ASSERT_TRUE(exported.ok) << exported.error;
  EXPECT_EQ(exported.format, LogFormat::tracker_export);
  ASSERT_EQ(exported.records.size(), valid);  // lost beams simply absent
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const TrackerPointRecord& h = hivecal.records[i];
    EXPECT_EQ(h.timestamp_us, points[i].timestamp_us);
    EXPECT_EQ(h.status, points[i].status);
    if (!points[i].is_valid()) continue;
    const TrackerPointRecord& e = exported.records[k++];
    EXPECT_EQ(e.timestamp_us, points[i].timestamp_us);
    EXPECT_TRUE(e.is_valid());
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(h.point_m[a], points[i].point_m[a]);
      EXPECT_NEAR(e.point_m[a], points[i].point_m[a], 1e-15 * 4.0);  // mm -> m rounding only
    }
  }
}

TEST(TextLogs, DelimitersUnitsAndColumnOrder) {
  struct Case {
    const char* text;
    double t_s, x_m;
  } cases[] = {
      {"Time [ms];X [mm];Y [mm];Z [mm]\n1500;1000;2;3\n", 1.5, 1.0},
      {"time\tz\ty\tx\n1.5\t3\t2\t1\n", 1.5, 1.0},
      {"  t   x    y   z  \n 1.5   1  2  3 \n", 1.5, 1.0},
      {"Time [s] X [um] Y [um] Z [um]\n1.5 1000000 2 3\n", 1.5, 1.0},  // a lone [unit] after its name
      {"\xEF\xBB\xBF\"timestamp [us]\",\"x [m]\",\"y [m]\",\"z [m]\",extra\r\n1500000,1,2,3,abc\r\n", 1.5, 1.0},
      {"T [NS],X [MM],Y,Z\n1500000000,1000,2,3\n", 1.5, 1.0},
  };
  for (const Case& c : cases) {
    const textio::TrackerLog log = textio::parse_tracker_log(c.text, "c.csv");
    ASSERT_TRUE(log.ok) << c.text << ": " << log.error;
    ASSERT_EQ(log.records.size(), 1u);
    EXPECT_EQ(log.records[0].timestamp_us, static_cast<std::uint64_t>(c.t_s * 1e6)) << c.text;
    EXPECT_NEAR(log.records[0].point_m[0], c.x_m, 1e-12) << c.text;
  }
  const textio::RobotLog deg = textio::parse_robot_log("q3 [deg],q2,q1,t [ms],q4,q5,q6\n180,2,1,8,4,5,6\n", "deg.csv");
  ASSERT_TRUE(deg.ok) << deg.error;
  EXPECT_EQ(deg.records[0].timestamp_us, 8000u);
  EXPECT_DOUBLE_EQ(deg.records[0].q_rad[2], 3.141592653589793);
  EXPECT_EQ(deg.records[0].q_rad[0], 1.0);
}

TEST(TextLogs, TrackerStatusAndLostBeams) {
  const textio::TrackerLog log =
      textio::parse_tracker_log("t,x,y,z,status\n1,1,2,3,0\n2,nan,nan,nan,1\n3,1,2,3,2\n", "s.csv");
  ASSERT_TRUE(log.ok) << log.error;
  ASSERT_EQ(log.records.size(), 3u);
  EXPECT_EQ(log.records[1].status, 1);
  EXPECT_EQ(log.records[2].status, 2);
  EXPECT_EQ(log.counters.not_valid, 2u);
  const textio::TrackerLog no_status = textio::parse_tracker_log("t,x,y,z\n1,1,2,3\n2,NaN,nan,nan\n3;;;\n", "n.csv");
  EXPECT_FALSE(no_status.ok);  // "3;;;" is one field in a comma file
  const textio::TrackerLog lost = textio::parse_tracker_log("t;x;y;z\n1;1;2;3\n2;nan;nan;nan\n3;;;\n", "n.csv");
  ASSERT_TRUE(lost.ok) << lost.error;
  EXPECT_EQ(lost.records[1].status, 1);
  EXPECT_EQ(lost.records[2].status, 1);  // empty coordinates: lost beam
  const textio::TrackerLog repeated =
      textio::parse_tracker_log("t,x,y,z\n1,1,2,3\n1.0000001,1,2,3\n2,1,2,3\n", "r.csv");
  ASSERT_TRUE(repeated.ok) << repeated.error;
  EXPECT_EQ(repeated.records.size(), 2u);
  EXPECT_EQ(repeated.counters.repeated_time, 1u);
}

/// The error of reading `text` as a robot (robot true) or tracker log, "" when it reads.
std::string error_of(const std::string& text, bool robot) {
  return robot ? textio::parse_robot_log(text, "f.csv").error : textio::parse_tracker_log(text, "f.csv").error;
}

TEST(TextLogs, EveryRefusalIsNamed) {
  const std::string q = "t,q1,q2,q3,q4,q5,q6\n";
  const struct {
    std::string text;
    bool robot;
    std::string expected;
  } cases[] = {
      {"", true, "f.csv: empty file (no header line)"},
      {"\n \n", false, "f.csv: empty file"},
      {q, true, "f.csv: no data rows"},
      {"t,x,y,z\n", false, "f.csv: no data rows"},
      {q + "1,0,0,0,0,0\n", true, "f.csv:2: 6 fields where the header has 7 (comma-separated)"},
      {q + "1,0,0,abc,0,0,0\n", true, "f.csv:2: column 'q3': not a number: 'abc'"},
      {q + "1,0,0,nan,0,0,0\n", true, "f.csv:2: joint 3: NaN or Inf"},
      {q + "2,0,0,0,0,0,0\n1,0,0,0,0,0,0\n", true, "f.csv:3: timestamp 1 s does not increase (previous 2 s)"},
      {q + "-1,0,0,0,0,0,0\n", true, "f.csv:2: timestamp -1 s outside 0 .. 1.8e13 s"},
      {"Time [ms];X [mm];Y [mm];Z [mm]\n1500;1.000,5;2;3\n", false, "f.csv:2: column 'x': not a number: '1.000,5'"},
      {"t,x,y,z\n1,1,2,3\n2,1,5,2,3\n", false,
       "f.csv:3: 5 fields where the header has 4 (comma-separated): a comma used as decimal separator?"},
      {std::string("t,x,y,z\n1,1,2,3\n2,1,\0,3\n", 24), false,
       "f.csv:3: binary byte 0x00 at byte 5 of the line: not a text log"},
      {"t,x,y,z\n1,1,2\x01,3\n", false, "f.csv:2: binary byte 0x01"},
      {"t,x,y,z,status\n1,nan,0,0,0\n", false, "f.csv:2: NaN or Inf in x, y or z of a valid point"},
      {"t,x,y,z,status\n1,0,0,0,1.5\n", false, "f.csv:2: status must be an integer 0..255"},
      {"t,x,y,z,status\n1,0,0,0,300\n", false, "f.csv:2: status must be an integer 0..255"},
      {"t [min],x,y,z\n1,0,0,0\n", false, "f.csv:1: column 't': unit '[min]' is not one of [s], [ms], [us], [ns]"},
      {"t,x [deg],y,z\n1,0,0,0\n", false, "f.csv:1: column 'x': unit '[deg]' is not one of [m], [mm], [um]"},
      {"Time [ms];X [mm];Y [mm];Z [mm]\n", true,
       "f.csv:1: a tracker log (time, x, y, z), not a robot joint log: --robot and --tracker swapped?"},
      {q + "1,0,0,0,0,0,0\n", false, "f.csv:1: a robot joint log, not a tracker log: --robot and --tracker swapped?"},
      {"timestamp target_q_0 target_q_1 target_q_2 target_q_3 target_q_4 target_q_5\n1 0 0 0 0 0 0\n", true,
       "f.csv:1: UR RTDE log without timestamp and actual_q_0..actual_q_5: target_q_k are the commanded positions"},
      {"Zeit;Achse 1;Achse 2\n1;2;3\n", true,
       "f.csv:1: not a robot joint log: expected t,q1..qN (hivecal), timestamp + actual_q_0..actual_q_5 (UR RTDE "
       "recorder) or field.header.stamp + field.nameK + field.positionK (rostopic echo -p /joint_states); found "
       "'Zeit;Achse 1;Achse 2' (semicolon-separated, 3 columns)"},
      {"a,b\n1,2\n", false,
       "f.csv:1: not a tracker log: expected a time column (t, time or timestamp) and x, y, z, units in brackets "
       "allowed; found 'a,b' (comma-separated, 2 columns)"},
      {"%time,field.header.stamp,field.name0,field.position0\n1,1,a,0\n", true,
       "f.csv:1: rostopic log with 1 joints (field.nameK with field.positionK), but the robot model has 6 joints "
       "(q1..q6): the joints of another arm?"},
  };
  for (const auto& c : cases) {
    const std::string error = error_of(c.text, c.robot);
    EXPECT_EQ(error.substr(0, c.expected.size()), c.expected) << "for " << port::quoted(c.text);
  }
  // Messages cut long text and escape control bytes.
  const std::string junk = "\x1b[31m" + std::string(500, 'A') + "\x7f;b\n";
  const std::string error = error_of(junk, false);
  EXPECT_NE(error.find("binary byte 0x1b"), std::string::npos) << error;
  const std::string wide = error_of(std::string(300, 'h') + ";b\n1;2\n", false);
  EXPECT_LT(wide.size(), 400u) << wide;
  EXPECT_NE(wide.find("hhh...[302 bytes]'"), std::string::npos) << wide;
}

TEST(TextLogs, LinesAndFieldsAreBounded) {
  const std::string long_line = "t,x,y,z\n1,1,2," + std::string(textio::kMaxLineBytes, '3') + "\n";
  EXPECT_NE(error_of(long_line, false).find("f.csv:2: line longer than 65536 bytes"), std::string::npos);
  std::string many = "t";
  for (std::size_t k = 0; k < textio::kMaxColumns + 5; ++k) many += ",c" + std::to_string(k);
  EXPECT_NE(error_of(many + "\n", false).find("f.csv:1: more than 1024 fields in a line"), std::string::npos);
  // The file reader crosses its buffer boundary mid-line without losing a byte.
  const test::TempDir dir("hivecal_logs");
  std::vector<JointStateRecord> joints = session_records().joints;
  const std::size_t once = joints.size();
  for (int copy = 1; copy < 3; ++copy) {  // ~2.7 MB: more than two buffer fills
    for (std::size_t i = 0; i < once; ++i) {
      joints.push_back(joints[i]);
      joints.back().timestamp_us += static_cast<std::uint64_t>(copy) * 100000000u;
    }
  }
  const std::string path = dir.write("rtde.txt", test::rtde_log(joints));
  const textio::RobotLog from_file = textio::read_robot_log(path);
  EXPECT_EQ(from_file.format, LogFormat::ur_rtde);
  expect_same_joints(from_file, joints);
  EXPECT_GT(from_file.bytes_read, 2 * 16 * textio::kMaxLineBytes);  // several buffer fills
}

TEST(TextLogs, DetectionByContent) {
  const test::TempDir dir("hivecal_logs");
  using textio::StreamFileKind;
  EXPECT_EQ(textio::detect_stream_file(dir.write("a.csv", "t,x,y,z\n1,2,3,4\n")), StreamFileKind::text_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("b.csv", "\xEF\xBB\xBFt,q1\r\n")), StreamFileKind::text_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("c.csv", "Time [ms];X [mm]\n")), StreamFileKind::text_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("r.txt", "timestamp actual_q_0\n")), StreamFileKind::text_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("d.bin", std::string("\x03\x01\x02\x00\x05", 5))),
            StreamFileKind::capture);
  EXPECT_EQ(textio::detect_stream_file(dir.write("e.bin", "")), StreamFileKind::capture);
  EXPECT_EQ(textio::detect_stream_file(dir.path() + "/missing"), StreamFileKind::capture);
  EXPECT_EQ(textio::detect_stream_file(dir.path()), StreamFileKind::ros2_bag);
  EXPECT_EQ(textio::detect_stream_file(dir.write("m.mcap", std::string("\x89MCAP0\r\n\x01\x02", 10))),
            StreamFileKind::mcap);
  const textio::RobotLog mcap = textio::read_robot_log(dir.path() + "/m.mcap");
  EXPECT_NE(mcap.error.find("MCAP storage is not read (no Debian package reads it)"), std::string::npos) << mcap.error;
  // Random bytes without any 0x00 (the worst case for a capture) are never taken for text.
  Random random(99);
  for (int trial = 0; trial < 300; ++trial) {
    std::string noise(600, '\0');
    for (char& c : noise) c = static_cast<char>(1 + random.below(255));
    ASSERT_EQ(textio::detect_stream_file(dir.write("noise.cap", noise)), StreamFileKind::capture) << trial;
  }
}

// Every text reader sees the encoding the way the robot files do (textio::utf8_text): a UTF-8
// byte order mark is read past, UTF-16 and UTF-32 are refused with "save it as UTF-8". A log in
// UTF-16 was "binary byte 0x00" or, as --robot/--tracker, read as a capture ("no valid frame");
// a capture that starts with an idle 0x00 stays a capture.
TEST(TextLogs, Utf16AndUtf32TextIsNamedByEveryReader) {
  const test::TempDir dir("hivecal_logs");
  using textio::StreamFileKind;
  const std::string robot = "t,q1,q2,q3,q4,q5,q6\n0.1,1,2,3,4,5,6\n0.2,1,2,3,4,5,6\n";
  const std::string tracker = "Time [ms];X [mm];Y [mm];Z [mm]\n100;1;2;3\n200;1;2;3\n";
  const std::string pendant = "\"Base (\xc2\xb0)\",\"Shoulder (\xc2\xb0)\"\n1,2\n";  // a unit beyond ASCII
  const struct {
    std::string text;
    const char* encoding;
  } wide[] = {
      {test::wide_text(robot, 2, false, "\xFF\xFE"), "UTF-16 text (little-endian)"},
      {test::wide_text(robot, 2, false, ""), "UTF-16 text (little-endian)"},
      {test::wide_text(robot, 2, true, "\xFE\xFF"), "UTF-16 text (big-endian)"},
      {test::wide_text(robot, 4, false, std::string("\xFF\xFE\0\0", 4)), "UTF-32 text (little-endian)"},
      {test::wide_text(robot, 4, true, ""), "UTF-32 text (big-endian)"},
  };
  for (const auto& w : wide) {
    const std::string path = dir.write("robot.csv", w.text);
    EXPECT_EQ(textio::detect_stream_file(path), StreamFileKind::text_log) << w.encoding;
    const textio::RobotLog log = textio::read_robot_log(path);
    EXPECT_EQ(log.error, path + ": " + w.encoding + ": save it as UTF-8");
    std::vector<JointVector> poses;
    const port::Error joints = textio::read_joints_csv(path, &poses);
    EXPECT_NE(joints.message.find(path + ": " + w.encoding + ": save it as UTF-8"), std::string::npos)
        << joints.message;
  }
  const std::string wide_tracker = dir.write("tracker.csv", test::wide_text(tracker, 2, false, "\xFF\xFE"));
  EXPECT_EQ(textio::read_tracker_log(wide_tracker).error,
            wide_tracker + ": UTF-16 text (little-endian): save it as UTF-8");
  std::string wide_pendant = "\xFF\xFE";  // UTF-16 of the degree sign: 0xB0 0x00
  for (const char c : pendant) wide_pendant += c == '\xc2' ? std::string() : std::string{c, '\0'};
  EXPECT_EQ(textio::detect_stream_file(dir.write("pendant.csv", wide_pendant)), StreamFileKind::text_log);
  // A UTF-8 byte order mark is read past by every reader, in a file and in memory.
  const std::string marked = dir.write("marked.csv", "\xEF\xBB\xBF" + robot);
  EXPECT_EQ(textio::read_robot_log(marked).records.size(), 2u);
  EXPECT_EQ(textio::parse_robot_log("\xEF\xBB\xBF" + robot, "memory").records.size(), 2u);
  std::vector<JointVector> poses;
  EXPECT_TRUE(textio::read_joints_csv(marked, &poses).ok());
  EXPECT_EQ(poses.size(), 2u);
  // Captures, also one that starts with idle 0x00 bytes, are captures still.
  std::string capture = std::string(4, '\0') + "\x05\x01\x02\x03\x04";
  for (int k = 0; k < 40; ++k) capture += std::string("\x0b\x01\x02\x0c\x9a\xf0\x11\x22\x33\x44", 10) + '\0';
  EXPECT_EQ(textio::detect_stream_file(dir.write("idle.cap", capture)), StreamFileKind::capture);
}

TEST(TextLogs, CdrJointStateDecodesAndRefusesJunk) {
  const std::vector<std::uint8_t> cdr = test::joint_state_cdr(1234567890123456u, {"a", "bb", "ccc"}, {1.0, 2.0, 3.0});
  textio::JointStateMessage message;
  std::string error;
  ASSERT_TRUE(textio::decode_joint_state_cdr(cdr.data(), cdr.size(), &message, &error)) << error;
  EXPECT_EQ(message.stamp_us, 1234567890123456u);
  ASSERT_EQ(message.names.size(), 3u);
  EXPECT_EQ(message.names[2], "ccc");
  EXPECT_EQ(message.positions_rad[1], 2.0);
  for (std::size_t cut = 0; cut < cdr.size() - 40; ++cut) {  // velocity and effort may be cut
    EXPECT_FALSE(textio::decode_joint_state_cdr(cdr.data(), cut, &message, &error)) << cut;
  }
}

#if HIVECAL_HAVE_SQLITE3
TEST(TextLogs, Ros2BagCarriesTheArmsJointCount) {
  std::vector<JointStateRecord> records(3);
  for (std::size_t i = 0; i < records.size(); ++i) {
    records[i].timestamp_us = 1000 + 8000 * i;
    records[i].joint_count = 7;
    for (int j = 0; j < 7; ++j) records[i].q_rad[j] = 0.01 * static_cast<double>(i) + 0.1 * j;
  }
  const std::vector<std::string> iiwa = {"iiwa_joint_1", "iiwa_joint_2", "iiwa_joint_3", "iiwa_joint_4",
                                         "iiwa_joint_5", "iiwa_joint_6", "iiwa_joint_7"};
  const test::TempDir dir("hivecal_logs7");
  ASSERT_TRUE(test::write_ros2_bag_joints(dir.path(), records, iiwa, {0, 1, 2, 3, 4, 5, 6}));
  const textio::RobotLog bag = textio::read_robot_log(dir.path(), seven_joint_options());
  ASSERT_TRUE(bag.ok) << bag.error;
  ASSERT_EQ(bag.records.size(), 3u);
  for (std::size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(bag.records[i].joint_count, 7);
    for (int j = 0; j < 7; ++j) EXPECT_EQ(bag.records[i].q_rad[j], records[i].q_rad[j]) << i << " " << j;
  }
  // Named in another order: mapped by name.
  textio::RobotLogOptions named = seven_joint_options();
  ASSERT_TRUE(
      textio::parse_joint_names("iiwa_joint_7,iiwa_joint_6,iiwa_joint_5,iiwa_joint_4,iiwa_joint_3,"
                                "iiwa_joint_2,iiwa_joint_1",
                                &named));
  const textio::RobotLog reversed = textio::read_robot_log(dir.path(), named);
  ASSERT_TRUE(reversed.ok) << reversed.error;
  EXPECT_EQ(reversed.records[2].q_rad[0], records[2].q_rad[6]);
  // The same bag for a UR: UR's names are not in it; for an eight-joint arm: another count.
  EXPECT_NE(textio::read_robot_log(dir.path()).error.find("no message names all of the joints shoulder_pan_joint"),
            std::string::npos);
  textio::RobotLogOptions eight;
  eight.units.joints.count = 8;
  const std::string error = textio::read_robot_log(dir.path(), eight).error;
  EXPECT_NE(error.find("bag_0.db3: /joint_states message 1: it names 7 joints ('iiwa_joint_1, "), std::string::npos)
      << error;
  EXPECT_NE(error.find("but the robot model has 8 joints (q1..q8)"), std::string::npos) << error;
}

TEST(TextLogs, Ros2BagGivesTheSameRecords) {
  const test::TempDir dir("hivecal_logs");
  const std::vector<JointStateRecord>& joints = session_records().joints;
  ASSERT_TRUE(test::write_ros2_bag(dir.path(), joints));
  const textio::RobotLog bag = textio::read_robot_log(dir.path());
  EXPECT_EQ(bag.format, LogFormat::ros2_bag);
  expect_same_joints(bag, joints);
  EXPECT_EQ(bag.counters.other_messages, (joints.size() + 9) / 10);  // /tf ignored
  const textio::RobotLog db3 = textio::read_robot_log(dir.path() + "/bag_0.db3");
  expect_same_joints(db3, joints);
  const textio::TrackerLog swapped = textio::read_tracker_log(dir.path());
  EXPECT_NE(swapped.error.find("--robot and --tracker swapped?"), std::string::npos) << swapped.error;
  // A bag without /joint_states, and one with a message that is not a JointState.
  const std::string db3_path = dir.path() + "/bag_0.db3";
  auto exec = [&](const char* sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(db3_path.c_str(), &db), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
  };
  exec("INSERT INTO messages(topic_id, timestamp, data) VALUES(2, 99999999999999, x'00010000ffff');");
  EXPECT_NE(textio::read_robot_log(dir.path())
                .error.find("bag_0.db3: /joint_states message " + std::to_string(joints.size() + 1) +
                            ": not a CDR sensor_msgs/msg/JointState (truncated or malformed)"),
            std::string::npos)
      << textio::read_robot_log(dir.path()).error;
  exec("UPDATE topics SET type = 'std_msgs/msg/String' WHERE id = 2;");
  EXPECT_NE(textio::read_robot_log(dir.path())
                .error.find(
                    "bag_0.db3: /joint_states is std_msgs/msg/String (cdr), expected sensor_msgs/msg/JointState (cdr)"),
            std::string::npos);
  exec("DELETE FROM topics WHERE id = 2;");
  EXPECT_NE(textio::read_robot_log(dir.path()).error.find("bag_0.db3: no /joint_states topic (topics: /tf)"),
            std::string::npos);
  const test::TempDir empty("hivecal_logs");
  EXPECT_NE(textio::read_robot_log(empty.path()).error.find("a folder without metadata.yaml: not a ROS 2 bag"),
            std::string::npos);
  empty.write("metadata.yaml", "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n");
  EXPECT_NE(textio::read_robot_log(empty.path()).error.find("no .db3 file (sqlite3 storage) in the bag"),
            std::string::npos);
  empty.write("metadata.yaml", "rosbag2_bagfile_information:\n  storage_identifier: mcap\n");
  EXPECT_NE(textio::read_robot_log(empty.path()).error.find("MCAP storage is not read"), std::string::npos);
}
#endif

TEST(TextLogs, TenMinuteRtdeLogParsesFast) {
  // 10 min at 500 Hz (e-Series): 300,000 rows of timestamp, target_q, actual_q, TCP pose.
  // The time is printed, not asserted: CPU time under emulation (qemu) or sanitizers says
  // nothing about the tool; the figure in docs/formats.md is from the host -O3 build.
  std::vector<JointStateRecord> joints(300000);
  for (std::size_t i = 0; i < joints.size(); ++i) {
    joints[i].timestamp_us = 1000000 + 2000 * i;
    for (int j = 0; j < kSixJoints; ++j) joints[i].q_rad[j] = 0.1 * j + 1e-6 * static_cast<double>(i % 977);
  }
  const test::TempDir dir("hivecal_logs");
  const std::string path = dir.write("rtde.csv", test::rtde_log(joints));
  const std::clock_t cpu_start = std::clock();
  const auto start = std::chrono::steady_clock::now();
  const textio::RobotLog log = textio::read_robot_log(path);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  expect_same_joints(log, joints);
  std::printf("10-minute 500 Hz RTDE log: %zu rows, %.1f MB, parsed in %.3f s CPU (%.3f s wall)\n", joints.size(),
              static_cast<double>(log.bytes_read) * 1e-6, cpu_s, seconds);
}

}  // namespace
}  // namespace hivecal::textio_logs_test
