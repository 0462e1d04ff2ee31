// Text formats of io-formats.md: every bad input gets a clear message naming file and line.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "test_data.hpp"
#include "textio/calibration_json.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"

namespace hivecal {
namespace {

class TempDir {
 public:
  TempDir() {
    char pattern[] = "/tmp/hivecal-test-XXXXXX";
    path_ = mkdtemp(pattern);
  }
  ~TempDir() { std::system(("rm -rf '" + path_ + "'").c_str()); }
  std::string write(const std::string& name, const std::string& content) const {
    const std::string file = path_ + "/" + name;
    std::FILE* f = std::fopen(file.c_str(), "wb");
    std::fwrite(content.data(), 1, content.size(), f);
    std::fclose(f);
    return file;
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string robot_log_error(const TempDir& dir, const std::string& content) {
  const port::Error r = textio::read_robot_log(dir.write("robot.csv", content), [](const textio::RobotLogRow&) {});
  return r.ok() ? "" : r.message;
}

TEST(TextCsv, RobotLogReadsSpecExampleAndExtraColumns) {
  TempDir dir;
  std::vector<textio::RobotLogRow> rows;
  const std::string path = dir.write("r.csv",
                                     "t,q1,q2,q3,q4,q5,q6,extra\r\n"
                                     "12.008,0.0,-1.5707963267948966,1.5707963267948966,-1.5707963267948966,-1.5707963267948966,0.0,7\r\n"
                                     "12.016,0.1,-1.5,1.5,-1.5,-1.5,0.2,8\r\n");
  const port::Error r = textio::read_robot_log(path, [&](const textio::RobotLogRow& row) { rows.push_back(row); });
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].t_s, 12.008);
  EXPECT_EQ(rows[0].q_rad(1), -1.5707963267948966);
  EXPECT_EQ(rows[1].q_rad(5), 0.2);
}

TEST(TextCsv, BadRobotLogsAreNamed) {
  TempDir dir;
  const std::string header = "t,q1,q2,q3,q4,q5,q6\n";
  const struct {
    std::string content;
    std::string expected;
  } cases[] = {
      {"", "empty file"},
      {"\n\n", "empty file"},
      {header, "no data rows"},
      {"time,a,b\n1,2,3\n", "unexpected header 'time,a,b'"},
      {header + "1,0,0,0,0,0\n", ":2: expected at least 7 columns, found 6"},
      {header + "1,0,0,abc,0,0,0\n", ":2: not a number: 'abc'"},
      {header + "1,0,0,nan,0,0,0\n", ":2: NaN or Inf"},
      {header + "1,0,0,inf,0,0,0\n", ":2: NaN or Inf"},
      {header + "2,0,0,0,0,0,0\n1,0,0,0,0,0,0\n", ":3: timestamp 1 s does not increase"},
      {header + "2,0,0,0,0,0,0\n2,0,0,0,0,0,0\n", ":3: timestamp 2 s does not increase"},
  };
  for (const auto& c : cases) {
    const std::string message = robot_log_error(dir, c.content);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "got: " << message;
  }
  const port::Error missing = textio::read_robot_log("/nonexistent/r.csv", [](const textio::RobotLogRow&) {});
  EXPECT_NE(missing.message.find("cannot open"), std::string::npos);
}

TEST(TextCsv, TrackerLogStatusOptionalAndNaNOnlyWhenInvalid) {
  TempDir dir;
  std::vector<textio::TrackerLogRow> rows;
  auto collect = [&](const textio::TrackerLogRow& row) { rows.push_back(row); };
  ASSERT_TRUE(textio::read_tracker_log(dir.write("a.csv", "t,x,y,z\n3.1,1.25,-0.5,0.75\n"), collect).ok());
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].status, 0);
  EXPECT_EQ(rows[0].point_m, Vec3(1.25, -0.5, 0.75));
  rows.clear();
  const port::Error r =
      textio::read_tracker_log(dir.write("b.csv", "t,x,y,z,status\n3.1,1.25,-0.5,0.75,0\n3.2,nan,nan,nan,1\n"), collect);
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].status, 1);
  EXPECT_FALSE(textio::read_tracker_log(dir.write("c.csv", "t,x,y,z,status\n3.1,nan,0,0,0\n"), collect).ok());
  // Without the status column a row of three NaN is a lost beam, as on the wire; a partly
  // non-finite row is still refused.
  rows.clear();
  ASSERT_TRUE(textio::read_tracker_log(dir.write("f.csv", "t,x,y,z\n3.1,1.25,-0.5,0.75\n3.2,nan,NaN,nan\n"), collect).ok());
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].status, 0);
  EXPECT_EQ(rows[1].status, 1);
  EXPECT_FALSE(textio::read_tracker_log(dir.write("g.csv", "t,x,y,z\n3.1,nan,nan,0\n"), collect).ok());
  EXPECT_FALSE(textio::read_tracker_log(dir.write("h.csv", "t,x,y,z\n3.1,inf,inf,inf\n"), collect).ok());
  EXPECT_FALSE(textio::read_tracker_log(dir.write("d.csv", "t,x,y,z,status\n3.1,0,0,0,1.5\n"), collect).ok());
  EXPECT_FALSE(textio::read_tracker_log(dir.write("e.csv", "t,x,y,z,status\n3.1,0,0,0,300\n"), collect).ok());
}

TEST(TextCsv, SamplesAndJointsRoundTripAndCapacity) {
  TempDir dir;
  Random random(5);
  static Dataset<16> written;
  written.clear();
  test::fill_dataset(nominal_model(RobotType::ur5), test::example_base_to_tracker(), 10, 1e-5, &random, &written);
  const std::string path = dir.write("s.csv", textio::format_samples_csv(written.samples()));
  static Dataset<16> read_back;
  read_back.clear();
  ASSERT_TRUE(textio::read_samples_csv(path, &read_back).ok());
  ASSERT_EQ(read_back.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(read_back.samples()[i].q_rad, written.samples()[i].q_rad);  // bit-exact round trip
    EXPECT_EQ(read_back.samples()[i].point_m, written.samples()[i].point_m);
  }
  static Dataset<4> small;
  small.clear();
  const port::Error full = textio::read_samples_csv(path, &small);
  EXPECT_FALSE(full.ok());
  EXPECT_NE(full.message.find("dataset over capacity (4 samples max)"), std::string::npos) << full.message;

  std::vector<JointVector> poses;
  ASSERT_TRUE(textio::read_joints_csv(dir.write("j.csv", "t,q1,q2,q3,q4,q5,q6\n0,1,2,3,4,5,6\n"), &poses).ok());
  ASSERT_TRUE(textio::read_joints_csv(dir.write("k.csv", "q1,q2,q3,q4,q5,q6\n1,2,3,4,5,6\n"), &poses).ok());
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0], poses[1]);
}

TEST(TextCsv, StreamFileKindByContent) {
  TempDir dir;
  using textio::StreamFileKind;
  EXPECT_EQ(textio::detect_stream_file(dir.write("a.csv", "t,x,y,z\n1,2,3,4\n")), StreamFileKind::csv_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("b.csv", "\xEF\xBB\xBFt,q1\r\n")), StreamFileKind::csv_log);
  EXPECT_EQ(textio::detect_stream_file(dir.write("c.csv", "time;x;y;z\n")), StreamFileKind::capture);  // no comma
  EXPECT_EQ(textio::detect_stream_file(dir.write("d.bin", std::string("\x03\x01\x02\x00\x05", 5))),
            StreamFileKind::capture);
  EXPECT_EQ(textio::detect_stream_file(dir.write("e.bin", "")), StreamFileKind::capture);
  EXPECT_EQ(textio::detect_stream_file(dir.path() + "/missing"), StreamFileKind::capture);
  // Random bytes without any 0x00 (the worst case for a capture) are never taken for text:
  // CI once met a noise file whose first line was "printable" under a looser rule.
  Random random(99);
  for (int trial = 0; trial < 300; ++trial) {
    std::string noise(600, '\0');
    for (char& c : noise) c = static_cast<char>(1 + random.below(255));
    ASSERT_EQ(textio::detect_stream_file(dir.write("noise.cap", noise)), StreamFileKind::capture) << trial;
  }
}

TEST(TextCsv, PullReaderGivesRowsOneAtATime) {
  TempDir dir;
  textio::TrackerLogReader reader;
  ASSERT_TRUE(reader.open(dir.write("t.csv", "t,x,y,z\n\n1,2,3,4\n2,5,6,7\n")).ok());
  textio::TrackerLogRow row;
  bool got = false;
  ASSERT_TRUE(reader.next(&row, &got).ok());
  ASSERT_TRUE(got);
  EXPECT_EQ(row.t_s, 1.0);
  EXPECT_EQ(row.status, 0);
  ASSERT_TRUE(reader.next(&row, &got).ok());
  ASSERT_TRUE(got);
  EXPECT_EQ(row.point_m, Vec3(5.0, 6.0, 7.0));
  ASSERT_TRUE(reader.next(&row, &got).ok());
  EXPECT_FALSE(got);
  textio::RobotLogReader robot;
  ASSERT_TRUE(robot.open(dir.write("r.csv", "t,q1,q2,q3,q4,q5,q6\n")).ok());
  const port::Error none = robot.next(nullptr, &got);
  EXPECT_FALSE(none.ok());
  EXPECT_NE(none.message.find("no data rows"), std::string::npos) << none.message;
}

textio::CalibrationFile example_calibration() {
  Random random(8);
  textio::CalibrationFile file;
  file.robot = RobotType::ur10;
  file.model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  file.model.tool_m << 0.001, -0.002, 0.1695;
  file.base_to_tracker = test::example_base_to_tracker();
  file.has_metrics = true;
  file.metrics.test.count = 12;
  file.metrics.test.mae_m[3] = 6.01e-5;
  return file;
}

TEST(TextJson, CalibrationRoundTripsBitExactly) {
  const textio::CalibrationFile file = example_calibration();
  const std::string text = textio::format_calibration_json(file, [](textio::JsonWriter& json) {
    json.key("method").value("lm");
  });
  textio::CalibrationFile back;
  const port::Error r = textio::parse_calibration_json(text, "result.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(back.robot, RobotType::ur10);
  EXPECT_EQ(to_params(back.model), to_params(file.model));
  EXPECT_LT((back.base_to_tracker.rotation - file.base_to_tracker.rotation).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(back.base_to_tracker.translation_m, file.base_to_tracker.translation_m);
  textio::JsonValue root;
  ASSERT_TRUE(textio::parse_json(text, &root).ok());
  EXPECT_EQ(root.find("method")->string, "lm");
  EXPECT_EQ(root.find("metrics")->find("test")->find("mae_m")->find("3d")->number, 6.01e-5);
  EXPECT_EQ(root.find("convention")->string, "standard-dh");
}

TEST(TextJson, MalformedResultsAreNamed) {
  const std::string good = textio::format_calibration_json(example_calibration());
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const std::size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const struct {
    std::string text;
    std::string expected;
  } cases[] = {
      {"", "malformed JSON"},
      {"{", "malformed JSON"},
      {"[1,2]", "top level must be an object"},
      {replaced("robot-calibration/1", "other/2"), "\"format\""},
      {replaced("\"ur10\"", "\"kuka\""), "unknown robot model 'kuka'"},
      {replaced("\"theta_offset\"", "\"theta\""), "\"dh\"[0]"},
      {replaced("\"tool\": [", "\"tool\": [1, "), "\"tool\""},
      {replaced("[0, 0, 0, 1]", "[0, 0, 1, 1]"), "not a proper rigid transform"},
      {good + "x", "unexpected text after the document"},
  };
  for (const auto& c : cases) {
    textio::CalibrationFile file;
    const port::Error r = textio::parse_calibration_json(c.text, "result.json", &file);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message;
  }
}

TEST(TextFiles, AtomicWriteReplacesOrLeavesNothing) {
  TempDir dir;
  const std::string path = dir.path() + "/out.json";
  ASSERT_TRUE(textio::write_text_file(path, "first").ok());
  ASSERT_TRUE(textio::write_text_file(path, "second").ok());
  std::string text;
  ASSERT_TRUE(port::read_whole_file(path, port::kMaxTextInputBytes, &text).ok());
  EXPECT_EQ(text, "second");
  const port::Error error = textio::write_text_file(dir.path() + "/no/such/dir/out.json", "x");
  EXPECT_EQ(error.fault, port::Fault::output);
  EXPECT_NE(error.message.find("does not exist"), std::string::npos);
}

}  // namespace
}  // namespace hivecal
