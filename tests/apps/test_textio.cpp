// Text formats of io-formats.md: every bad input gets a clear message naming file and line.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <unistd.h>
#include <vector>

#include "testkit/temp_dir.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/test_data.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::textio_test {
namespace {

TEST(TextCsv, SamplesAndJointsRoundTripAndCapacity) {
  const test::TempDir dir("hivecal_test");
  Random random(5);
  static Dataset<16> written;
  written.clear();
  test::fill_dataset(nominal_model(RobotType::ur5), test::example_base_to_tracker(), 10, 1e-5, &random, &written);
  const std::string path = dir.write("s.csv", textio::format_samples_csv(written.samples(), kSixJoints));
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

record::CalibrationFile example_calibration() {
  Random random(8);
  record::CalibrationFile file;
  file.robot = "ur10";
  file.model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  file.model.tool_m << 0.001, -0.002, 0.1695;
  file.base_to_tracker = test::example_base_to_tracker();
  file.has_metrics = true;
  file.metrics.test.count = 12;
  file.metrics.test.mae_m[3] = 6.01e-5;
  return file;
}

// Every number a result, a CSV or a report writes goes through format_double: its characters
// are printf's "%.17g" (io-formats.md) and it reads back to the same bits, over random bit
// patterns (every exponent, subnormals, NaN, Inf) and the values a calibration writes.
TEST(TextNumbers, FormatDoubleWritesPrintfsDigitsAndReadsBackExactly) {
  Random random(17);
  const auto check = [](double value) {
    char expected[40];
    std::snprintf(expected, sizeof expected, "%.17g", value);
    const std::string written = textio::format_double(value);
    ASSERT_EQ(written, expected);
    double back = 0.0;
    if (value == value) {  // not NaN
      ASSERT_TRUE(textio::parse_double(written, &back)) << written;
      ASSERT_EQ(std::memcmp(&back, &value, sizeof value), 0) << written;
    }
  };
  for (int i = 0; i < 200000; ++i) {
    const std::uint64_t bits = random.next();
    double value = 0.0;
    std::memcpy(&value, &bits, sizeof value);
    check(value);
    check(random.uniform(-2.0, 2.0));
    check(random.uniform(-1.0, 1.0) * 1e-6);
  }
  for (double value : {0.0, -0.0, 1.0, 0.1, 1e16, 1e17, 4.9406564584124654e-324, 1.7976931348623157e308,
                       std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()})
    check(value);
}

TEST(TextJson, CalibrationRoundTripsBitExactly) {
  const record::CalibrationFile file = example_calibration();
  const std::string text =
      record::format_calibration_json(file, [](textio::JsonWriter& json) { json.key("method").value("lm"); });
  record::CalibrationFile back;
  const port::Error r = record::parse_calibration_json(text, "result.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(back.robot, "ur10");
  EXPECT_EQ(to_params(back.model), to_params(file.model));
  EXPECT_LT((back.base_to_tracker.rotation - file.base_to_tracker.rotation).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(back.base_to_tracker.translation_m, file.base_to_tracker.translation_m);
  textio::JsonValue root;
  ASSERT_TRUE(textio::parse_json(text, &root).ok());
  EXPECT_EQ(root.find("method")->string, "lm");
  EXPECT_EQ(root.find("metrics")->find("test")->find("mae_m")->find("3d")->number, 6.01e-5);
  EXPECT_EQ(root.find("convention")->string, "standard-dh");
}

TEST(TextJson, AByteOrderMarkIsNotPartOfTheDocument) {
  const std::string text = record::format_calibration_json(example_calibration(), nullptr);
  record::CalibrationFile back;
  const port::Error r = record::parse_calibration_json("\xEF\xBB\xBF" + text, "result.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(to_params(back.model), to_params(example_calibration().model));
  textio::JsonValue root;
  EXPECT_FALSE(textio::parse_json("\xEF\xBB" + text, &root).ok());  // half a mark is junk
}

// \u escapes are code points written as UTF-8 (a surrogate pair is one code point); half a pair
// is no text and is refused. They read as "?" before.
TEST(TextJson, UnicodeEscapesBecomeUtf8) {
  textio::JsonValue root;
  ASSERT_TRUE(
      textio::parse_json(R"({"robot": "\u0420\u043e\u0431\u043e\u0442 \u00b5 \u20ac \ud83e\udd16 A\u0000"})", &root)
          .ok());
  EXPECT_EQ(root.find("robot")->string, std::string("\xd0\xa0\xd0\xbe\xd0\xb1\xd0\xbe\xd1\x82 \xc2\xb5 \xe2\x82\xac "
                                                    "\xf0\x9f\xa4\x96 A\0",
                                                    25));
  for (const char* lone :
       {R"({"r": "\ud83e"})", R"({"r": "\ud83e\u0041"})", R"({"r": "\udd16"})", R"({"r": "\ud83e\"})"}) {
    const port::Error error = textio::parse_json(lone, &root);
    EXPECT_NE(error.message.find("surrogate"), std::string::npos) << lone << ": " << error.message;
  }
  // A name so written survives a result's round trip.
  record::CalibrationFile file = example_calibration();
  ASSERT_TRUE(textio::parse_json(R"({"r": "\u0420\ud83e\udd16"})", &root).ok());
  file.robot = root.find("r")->string;
  record::CalibrationFile back;
  ASSERT_TRUE(record::parse_calibration_json(record::format_calibration_json(file), "result.json", &back).ok());
  EXPECT_EQ(back.robot, file.robot);
}

TEST(TextJson, MalformedResultsAreNamed) {
  const std::string good = record::format_calibration_json(example_calibration());
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
      {replaced("\"standard-dh\"", "\"dh-2\""), "result.json: unknown \"convention\" 'dh-2'"},
      {replaced("\"ur10\"", "7"), "\"robot\" must be a string"},
      {replaced("\"dh\"", "\"dh_rows\""), "missing \"dh\""},
      {replaced("\"d\": ", "\"d\": \"x\", \"e\": "), "\"dh\"[0].d must be a number"},
      {replaced("\"theta_offset\"", "\"theta\""), "\"dh\"[0]"},
      {replaced("\"tool\": [", "\"tool\": [1, "), "\"tool\""},
      {replaced("[0, 0, 0, 1]", "[0, 0, 1, 1]"), "not a proper rigid transform"},
      {good + "x", "unexpected text after the document"},
  };
  for (const auto& c : cases) {
    record::CalibrationFile file;
    const port::Error r = record::parse_calibration_json(c.text, "result.json", &file);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message;
  }
  // A base beyond the 100 m a text input allows a point: not a tracker's frame (it predicted
  // 1e300 m and scored "MAE inf" before).
  record::CalibrationFile far = example_calibration();
  for (const double x_m : {1e300, 101.0}) {
    far.base_to_tracker.translation_m.x() = x_m;
    record::CalibrationFile file;
    const port::Error r = record::parse_calibration_json(record::format_calibration_json(far), "result.json", &file);
    EXPECT_NE(r.message.find("result.json: \"base_to_tracker\" puts the robot's base "), std::string::npos)
        << r.message;
    EXPECT_NE(r.message.find(" m from the tracker, beyond 100 m: not a tracker's frame"), std::string::npos)
        << r.message;
  }
  far.base_to_tracker.translation_m.x() = 99.0;
  record::CalibrationFile file;
  EXPECT_TRUE(record::parse_calibration_json(record::format_calibration_json(far), "result.json", &file).ok());
}

TEST(TextFiles, AtomicWriteReplacesOrLeavesNothing) {
  const test::TempDir dir("hivecal_test");
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
}  // namespace hivecal::textio_test
