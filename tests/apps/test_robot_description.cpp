// Robot descriptions of any 6-axis arm (textio/robot_description.hpp): both conventions read
// and written, round trips, the modified-DH result predicting what the standard one does,
// the --robot-model value (file or built-in name) and errors naming file and key.
#include <gtest/gtest.h>

#include <string>

#include "testkit/log_forms.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/robot_description.hpp"
#include "textio/ur_calibration_conf.hpp"
#include "textio/urdf.hpp"
#include "record/result_json.hpp"

namespace hivecal::robot_description_test {
namespace {

using test::OtherArm;

/// A calibrated-looking result of `arm` in `convention`, base offset (alpha_0, a_0) for modified DH.
record::CalibrationFile arm_result(OtherArm arm, DhConvention convention, std::uint64_t seed) {
  Random random(seed);
  record::CalibrationFile file;
  file.robot = test::other_arm_name(arm);
  file.convention = convention;
  if (convention == DhConvention::modified) file.modified_base = ModifiedDhBase{0.013, -0.021};
  file.model = test::perturbed_model(test::other_arm_model(arm), &random, 1e-3, 1e-3);
  file.model.tool_m << 0.004, -0.003, 0.101;
  file.base_to_tracker = test::example_base_to_tracker();
  return file;
}

/// Largest distance [m] between the tracker-frame points of two results over random poses.
double worst_point_difference_m(const record::CalibrationFile& a, const record::CalibrationFile& b) {
  Random random(3);
  double worst_m = 0.0;
  for (int i = 0; i < 200; ++i) {
    const JointVector q = test::other_arm_joints(&random);
    const Vec3 pa = a.base_to_tracker.apply(fk_tool_point(a.model, q));
    const Vec3 pb = b.base_to_tracker.apply(fk_tool_point(b.model, q));
    worst_m = std::fmax(worst_m, (pa - pb).norm());
  }
  return worst_m;
}

TEST(RobotDescription, ResultsRoundTripInTheirOwnConvention) {
  for (OtherArm arm : test::kOtherArms) {
    for (DhConvention convention : {DhConvention::standard, DhConvention::modified}) {
      const record::CalibrationFile file = arm_result(arm, convention, 40 + static_cast<std::uint64_t>(arm));
      const std::string text = record::format_calibration_json(file);
      record::CalibrationFile back;
      const port::Error r = record::parse_calibration_json(text, "r.json", &back);
      ASSERT_TRUE(r.ok()) << r.message;
      EXPECT_EQ(back.robot, file.robot);
      EXPECT_EQ(back.convention, convention);
      EXPECT_NE(text.find(convention == DhConvention::modified ? "\"modified-dh\"" : "\"standard-dh\""),
                std::string::npos);
      // read -> write -> read: the same model bits (a6/alpha6 were folded into the tool on the
      // first modified-DH write) and the same base to rounding
      record::CalibrationFile again;
      ASSERT_TRUE(record::parse_calibration_json(record::format_calibration_json(back), "r2.json", &again).ok());
      EXPECT_EQ(to_params(again.model), to_params(back.model)) << test::other_arm_name(arm);
      EXPECT_LT((again.base_to_tracker.rotation - back.base_to_tracker.rotation).cwiseAbs().maxCoeff(), 1e-15);
      EXPECT_LT((again.base_to_tracker.translation_m - back.base_to_tracker.translation_m).cwiseAbs().maxCoeff(),
                1e-15);
      EXPECT_LE(worst_point_difference_m(file, back), 1e-12) << test::other_arm_name(arm);
      if (convention == DhConvention::standard) {
        EXPECT_EQ(to_params(back.model), to_params(file.model));
      }
    }
  }
}

// A modified-DH file read as a start model: the same arm as its standard table (the vendors'
// tables here have alpha_0 = a_0 = 0), and a result written from it in modified DH predicts
// what the standard result predicts, to 1e-12 m.
TEST(RobotDescription, ModifiedDhResultPredictsWhatTheStandardOneDoes) {
  for (OtherArm arm : test::kOtherArms) {
    ModifiedDhRow rows[kSixJoints];
    Vec3 tool_m;
    test::other_arm_modified(arm, ModifiedDhBase{}, rows, &tool_m);
    std::string text =
        "{\"robot\": \"" + std::string(test::other_arm_name(arm)) +
        "\", \"convention\": \"modified-dh\", \"vendor\": {\"note\": \"extra keys are allowed\"}, \"dh\": [";
    char buf[256];
    for (int j = 0; j < kSixJoints; ++j) {
      std::snprintf(buf, sizeof buf, "%s{\"alpha\": %.17g, \"a\": %.17g, \"theta_offset\": %.17g, \"d\": %.17g}",
                    j == 0 ? "" : ", ", rows[j].alpha_prev_rad, rows[j].a_prev_m, rows[j].theta_offset_rad,
                    rows[j].d_m);
      text += buf;
    }
    std::snprintf(buf, sizeof buf, "], \"tool\": [%.17g, %.17g, %.17g]}", tool_m.x(), tool_m.y(), tool_m.z());
    text += buf;
    textio::RobotDescription modified;
    const port::Error r = textio::parse_robot_description(text, "arm.json", &modified);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_EQ(modified.convention, DhConvention::modified);
    const RobotModel standard = test::other_arm_model(arm);
    Random random(9);
    for (int i = 0; i < 100; ++i) {
      const JointVector q = test::other_arm_joints(&random);
      EXPECT_LE((fk_tool_point(modified.model, q) - fk_tool_point(standard, q)).norm(), 1e-12);
    }
    // the same calibrated geometry written both ways
    record::CalibrationFile as_modified = arm_result(arm, DhConvention::modified, 7);
    record::CalibrationFile as_standard = as_modified;
    as_standard.convention = DhConvention::standard;
    record::CalibrationFile back_modified;
    record::CalibrationFile back_standard;
    ASSERT_TRUE(
        record::parse_calibration_json(record::format_calibration_json(as_modified), "m.json", &back_modified).ok());
    ASSERT_TRUE(
        record::parse_calibration_json(record::format_calibration_json(as_standard), "s.json", &back_standard).ok());
    EXPECT_LE(worst_point_difference_m(back_modified, back_standard), 1e-12) << test::other_arm_name(arm);
  }
}

TEST(RobotDescription, RobotModelValueIsAFileOrABuiltInName) {
  const test::TempDir dir("hivecal_test");
  const std::string path = dir.write(
      "irb120.json", record::format_calibration_json(arm_result(OtherArm::irb120, DhConvention::standard, 1)));
  textio::RobotDescription description;
  bool from_file = false;
  ASSERT_TRUE(textio::robot_description_from_value(path, &description, &from_file).ok());
  EXPECT_TRUE(from_file);
  EXPECT_EQ(description.robot, "abb-irb120");
  ASSERT_TRUE(textio::robot_description_from_value("ur5e", &description, &from_file).ok());
  EXPECT_FALSE(from_file);
  EXPECT_EQ(description.robot, "ur5e");
  EXPECT_EQ(to_params(description.model), to_params(nominal_model(RobotType::ur5e)));
  const std::string unnamed =
      dir.write("lab-arm.json", "{\"dh\": " + std::string(R"([{"theta_offset": 0, "d": 0.3, "a": 0, "alpha": 0},
      {"theta_offset": 0, "d": 0, "a": 0.2, "alpha": 0}, {"theta_offset": 0, "d": 0, "a": 0.2, "alpha": 0},
      {"theta_offset": 0, "d": 0.1, "a": 0, "alpha": 0}, {"theta_offset": 0, "d": 0, "a": 0, "alpha": 0},
      {"theta_offset": 0, "d": 0.05, "a": 0, "alpha": 0}])") +
                                    ", \"tool\": [0, 0, 0.1]}");
  ASSERT_TRUE(textio::robot_description_from_value(unnamed, &description).ok());
  EXPECT_EQ(description.robot, "lab-arm");  // no "robot": named after the file
  port::Error r = textio::robot_description_from_value("ur7", &description);
  EXPECT_EQ(r.fault, port::Fault::usage);
  EXPECT_NE(r.message.find("unknown robot model 'ur7'"), std::string::npos) << r.message;
  r = textio::robot_description_from_value(dir.path() + "/missing.json", &description);
  EXPECT_EQ(r.fault, port::Fault::input);
  EXPECT_NE(r.message.find("missing.json"), std::string::npos) << r.message;
}

TEST(RobotDescription, BadDescriptionsNameFileAndKey) {
  const std::string rows =
      "[{\"theta_offset\": 0, \"d\": 0.29, \"a\": 0, \"alpha\": -1.5707963267948966}, "
      "{\"theta_offset\": 0, \"d\": 0, \"a\": 0.27, \"alpha\": 0}, "
      "{\"theta_offset\": 0, \"d\": 0, \"a\": 0.07, \"alpha\": -1.5707963267948966}, "
      "{\"theta_offset\": 0, \"d\": 0.302, \"a\": 0, \"alpha\": 1.5707963267948966}, "
      "{\"theta_offset\": 0, \"d\": 0, \"a\": 0, \"alpha\": -1.5707963267948966}, "
      "{\"theta_offset\": 0, \"d\": 0.072, \"a\": 0, \"alpha\": 0}]";
  const struct {
    std::string text;
    std::string expected;
  } cases[] = {
      {"{\"dh\": " + rows + "}", "arm.json: missing \"tool\""},
      {"{\"tool\": [0, 0, 0.1]}", "arm.json: missing \"dh\""},
      {"{\"dh\": [{}], \"tool\": [0, 0, 0.1]}", "\"dh\" must be an array of 6"},
      {"{\"dh\": " + rows.substr(0, rows.rfind(", {")) + "], \"tool\": [0, 0, 0.1]}", "\"dh\" must be an array of 6"},
      {"{\"convention\": \"dh\", \"dh\": " + rows + ", \"tool\": [0, 0, 0.1]}", "unknown \"convention\" 'dh'"},
      {"{\"dh\": " + rows + ", \"tool\": [0, 0]}", "\"tool\" must be [x, y, z]"},
      {"{\"format\": \"x\", \"dh\": " + rows + ", \"tool\": [0, 0, 0.1]}", "\"format\""},
  };
  for (const auto& c : cases) {
    textio::RobotDescription description;
    const port::Error r = textio::parse_robot_description(c.text, "arm.json", &description);
    EXPECT_FALSE(r.ok()) << c.expected;
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message;
  }
  std::string bad = rows;
  bad.replace(bad.find("0.302"), 5, "null");
  textio::RobotDescription description;
  const port::Error r =
      textio::parse_robot_description("{\"dh\": " + bad + ", \"tool\": [0, 0, 0.1]}", "arm.json", &description);
  EXPECT_NE(r.message.find("arm.json: \"dh\"[3].d must be a number"), std::string::npos) << r.message;
  EXPECT_TRUE(
      textio::parse_robot_description("{\"dh\": " + rows + ", \"tool\": [0, 0, 0.1]}", "arm.json", &description).ok());
  EXPECT_EQ(description.convention, DhConvention::standard);
}

// A robot file with a UTF-8 byte order mark reads as without it; UTF-16 and UTF-32 are refused
// with what to do, and what is neither JSON nor XML is not called malformed JSON.
TEST(RobotDescription, ByteOrderMarksAndOtherEncodingsAreNamed) {
  const test::TempDir dir("hivecal_test");
  textio::RobotDescription ur5;
  ur5.model = nominal_model(RobotType::ur5);
  const std::string urdf = textio::format_urdf(ur5, nullptr);
  const std::string json = textio::format_robot_description(ur5);
  for (const std::string& text : {urdf, json}) {
    textio::RobotDescription plain;
    textio::RobotDescription marked;
    const std::string name = text == urdf ? "arm.urdf" : "arm.json";
    ASSERT_TRUE(textio::read_robot_description(dir.write(name, text), &plain).ok());
    const port::Error read = textio::read_robot_description(dir.write("bom-" + name, "\xEF\xBB\xBF" + text), &marked);
    ASSERT_TRUE(read.ok()) << read.message;
    EXPECT_EQ(to_params(marked.model), to_params(plain.model));
  }
  const struct {
    std::string text;
    const char* expected;
  } cases[] = {
      {test::wide_text(urdf, 2, false, "\xFF\xFE"), "wide.urdf: UTF-16 text (little-endian): save it as UTF-8"},
      {test::wide_text(urdf, 2, false, ""), "wide.urdf: UTF-16 text (little-endian): save it as UTF-8"},
      {test::wide_text(urdf, 2, true, "\xFE\xFF"), "wide.urdf: UTF-16 text (big-endian): save it as UTF-8"},
      {test::wide_text(json, 2, true, ""), "wide.urdf: UTF-16 text (big-endian): save it as UTF-8"},
      {test::wide_text(urdf, 4, false, std::string("\xFF\xFE\0\0", 4)),
       "wide.urdf: UTF-32 text (little-endian): save it as UTF-8"},
      {"robot arm:\n" + urdf,
       "wide.urdf: not a robot description: a JSON description starts with '{', a URDF with '<'; this file starts "
       "with 'robot arm:\\x0a<?xml ver...["},
  };
  for (const auto& c : cases) {
    textio::RobotDescription description;
    const port::Error r = textio::read_robot_description(dir.write("wide.urdf", c.text), &description);
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message << "\nwanted: " << c.expected;
    EXPECT_EQ(r.message.find("JSON:"), std::string::npos) << r.message;
  }
  // A result and a calibration.conf alike.
  record::CalibrationFile result;
  const std::string wide_result = dir.write(
      "result.json",
      test::wide_text(record::format_calibration_json(arm_result(OtherArm::irb120, DhConvention::standard, 1)), 2,
                      false, "\xFF\xFE"));
  port::Error r = record::read_calibration_json(wide_result, &result);
  EXPECT_NE(r.message.find("result.json: UTF-16 text (little-endian): save it as UTF-8"), std::string::npos)
      << r.message;
  UrCalibrationDeltas deltas;
  r = textio::read_ur_calibration_conf(
      dir.write("calibration.conf",
                test::wide_text("[mounting]\ndelta_theta = [0, 0, 0, 0, 0, 0]\n", 2, false, "\xFF\xFE")),
      &deltas);
  EXPECT_NE(r.message.find("calibration.conf: UTF-16 text (little-endian): save it as UTF-8"), std::string::npos)
      << r.message;
}

// Text of the file quoted in a message is cut after 80 bytes (docs/cli.md), as port::quoted cuts
// it: a 4,000-byte convention or calibration.conf value is not echoed whole.
TEST(RobotDescription, QuotesOfTheFileAreCutAt80Bytes) {
  const std::string long_text(4000, 'x');
  textio::RobotDescription description;
  const port::Error convention = textio::parse_robot_description(
      "{\"convention\": \"" + long_text + "\", \"dh\": [], \"tool\": [0, 0, 0]}", "arm.json", &description);
  UrCalibrationDeltas deltas;
  const port::Error conf = textio::parse_ur_calibration_conf(
      "[mounting]\ndelta_theta = [" + long_text + ", 0, 0, 0, 0, 0]\n", "calibration.conf", &deltas);
  for (const port::Error& error : {convention, conf}) {
    EXPECT_FALSE(error.ok());
    EXPECT_LT(error.message.size(), 250u) << error.message;
    EXPECT_NE(error.message.find("...[4000 bytes]'"), std::string::npos) << error.message;
  }
}

}  // namespace
}  // namespace hivecal::robot_description_test
