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
      {"{\"dh\": [{}], \"tool\": [0, 0, 0.1]}", "\"dh\"[0]: missing \"theta_offset\""},
      {"{\"dh\": [], \"tool\": [0, 0, 0.1]}", "\"dh\" must be an array of 1 to " + std::to_string(kMaxJoints)},
      {"{\"dh\": " + rows.substr(0, rows.size() - 1) + ", " + rows.substr(1, rows.size() - 1) +
           ", \"tool\": [0, 0, 0.1]}",
       "joint objects, one per joint (it has 12 rows)"},
      {"{\"dh\": [{\"theta_offset\": 0, \"d\": 0, \"a\": 0, \"alpha\": 0, \"type\": \"linear\"}], \"tool\": [0, 0, 0]}",
       "\"dh\"[0].type must be \"revolute\" (q turns theta) or \"prismatic\" (q moves d)"},
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

// Arms of seven joints and one with a prismatic joint (a UR10 on a rail) are descriptions and
// results like any other: their rows, types, joint limits (a slide's in metres), masses and
// term joints are read per joint and written back to the same bits in either convention; an
// all-revolute arm's rows carry no "type" (a six-joint file is written as before).
TEST(RobotDescription, ArmsOfAnyJointCountRoundTripWithTheirJointTypes) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  for (const test::ManyJointArm arm : test::kManyJointArms) {
    for (const DhConvention convention : {DhConvention::standard, DhConvention::modified}) {
      Random random(17 + static_cast<std::uint64_t>(arm));
      record::CalibrationFile file;
      file.robot = test::many_joint_arm_name(arm);
      file.convention = convention;
      if (convention == DhConvention::modified) file.modified_base = ModifiedDhBase{0.013, -0.021};
      file.model = test::many_joint_arm_truth(arm, &random);
      file.base_to_tracker = test::example_base_to_tracker();
      file.has_joint_limits = true;
      for (int j = 0; j < 7; ++j) {
        file.lower_rad(j) = joint_type(file.model, j) == JointType::prismatic ? 0.0 : -2.9 + 0.1 * j;
        file.upper_rad(j) = joint_type(file.model, j) == JointType::prismatic ? 2.0 : 2.9 - 0.1 * j;
      }
      ComplianceModel& compliance = file.model.compliance;
      compliance.load = ComplianceLoad::arm_masses;
      compliance.term_count = 2;
      compliance.terms[0] = ComplianceTerm{1, 0, JointTermKind::gravity, 0};
      compliance.terms[1] = ComplianceTerm{6, 0, JointTermKind::harmonic_sin, 1};
      compliance.coefficient[0] = 2e-6;
      compliance.coefficient[1] = 3e-5;
      for (int j = 0; j < 7; ++j) {
        compliance.masses.link_mass_kg[j] = 1.0 + j;
        compliance.masses.link_com_m[j] = Vec3(0.01 * j, 0.0, -0.02);
      }
      const std::string text = record::format_calibration_json(file);
      record::CalibrationFile back;
      const port::Error r = record::parse_calibration_json(text, "r.json", &back);
      ASSERT_TRUE(r.ok()) << r.message;
      const char* name = test::many_joint_arm_name(arm);
      EXPECT_EQ(back.model.joint_count, 7) << name;
      EXPECT_EQ(back.model.prismatic_joints, file.model.prismatic_joints) << name;
      EXPECT_EQ(text.find("\"type\"") != std::string::npos, arm == test::ManyJointArm::rail_ur10) << name;
      EXPECT_EQ(text.find("\"ur_deltas\""), std::string::npos) << name;  // a controller file of UR arms only
      EXPECT_TRUE(back.lower_rad == file.lower_rad) << name;
      EXPECT_TRUE(back.upper_rad == file.upper_rad) << name;
      EXPECT_EQ(back.model.compliance.masses.link_mass_kg[6], 7.0) << name;
      EXPECT_EQ(back.model.compliance.terms[1].joint, 6) << name;
      record::CalibrationFile again;
      ASSERT_TRUE(record::parse_calibration_json(record::format_calibration_json(back), "r2.json", &again).ok());
      EXPECT_EQ(to_params(again.model), to_params(back.model)) << name;
      if (convention == DhConvention::standard) {
        EXPECT_EQ(to_params(back.model), to_params(file.model)) << name;
      }
      // The same points (modified DH: of the rigid chain; the fold of a7, alpha7 into the tool
      // moves frame 7, in which link 7's centre of mass is given, by a7).
      RobotModel read = back.model;
      RobotModel written = file.model;
      if (convention == DhConvention::modified) read.compliance = written.compliance = ComplianceModel{};
      for (int i = 0; i < 50; ++i) {
        const JointVector q = test::many_joint_arm_joints(arm, &random);
        EXPECT_LE((fk_tool_point(read, q) - fk_tool_point(written, q)).norm(), 1e-12) << name;
      }
    }
  }
}

// What a description of N joints must give per joint is refused naming the counts: limits
// (a slide's within 100 m: millimetres?), masses, a term's joint.
TEST(RobotDescription, PerJointMembersFollowTheRows) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  textio::RobotDescription rail;
  rail.robot = "rail";
  rail.model = test::many_joint_arm_model(test::ManyJointArm::rail_ur10);
  const std::string text = textio::format_robot_description(rail);
  const std::string head = text.substr(0, text.rfind('}'));
  const std::string six_pairs = "[[0, 2], [-3, 3], [-3, 3], [-3, 3], [-3, 3], [-3, 3]]";
  const struct {
    std::string members;
    std::string expected;
  } cases[] = {
      {", \"joint_limits\": " + six_pairs,
       "\"joint_limits\" must be one [lower, upper] pair per joint (6 pairs for 7 joints in \"dh\")"},
      {", \"joint_limits\": [[0, 2000], " + six_pairs.substr(1),
       "\"joint_limits\"[0] = [0, 2000] m: lower must be below upper, both within 100 m (a prismatic joint; "
       "millimetres?)"},
      {", \"compliance\": {\"kind\": \"basis\", \"gravity_direction\": [0, 0, -1], \"terms\": [{\"joint\": 8, "
       "\"load\": \"tool\", \"coefficient\": 1e-6}]}",
       "\"terms\"[0].joint must be a joint number 1 .. 7"},
      {", \"compliance\": {\"kind\": \"basis\", \"gravity_direction\": [0, 0, -1], \"terms\": [{\"joint\": 2, "
       "\"load\": \"frame 8\", \"coefficient\": 1e-6}]}",
       "\"terms\"[0].load must be \"frame K\" (K = 1 .. 7) or \"tool\""},
      {", \"compliance\": {\"kind\": \"masses\", \"gravity_direction\": [0, 0, -1], \"terms\": [{\"joint\": 2, "
       "\"load\": \"arm masses\", \"coefficient\": 1e-6}], \"masses\": {\"link_mass_kg\": [1, 1, 1, 1, 1, 1], "
       "\"link_com_m\": [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]], \"payload_kg\": 0, "
       "\"payload_com_m\": [0, 0, 0]}}",
       "\"masses\" must hold link_mass_kg (7 numbers, one per joint), link_com_m (7 x [x, y, z])"},
  };
  for (const auto& c : cases) {
    textio::RobotDescription description;
    const port::Error r = textio::parse_robot_description(head + c.members + "}", "rail.json", &description);
    EXPECT_FALSE(r.ok()) << c.expected;
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message << "\nwanted: " << c.expected;
  }
  textio::RobotDescription limited;
  const port::Error r = textio::parse_robot_description(
      head + ", \"joint_limits\": [[0, 2], " + six_pairs.substr(1) + "}", "rail.json", &limited);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(limited.upper_rad(0), 2.0);
  EXPECT_EQ(limited.upper_rad(6), 3.0);
  EXPECT_EQ(limited.model.prismatic_joints, 1U);
  // UR's controller files refuse the arm with what it is.
  RobotModel calibrated;
  const port::Error conf = textio::read_ur_calibrated_model("no-such.conf", rail.model, "rail", &calibrated);
  EXPECT_EQ(conf.fault, port::Fault::usage);
  EXPECT_NE(conf.message.find("a calibration.conf is a Universal Robots controller's (six revolute joints); rail "
                              "has 7 joints, joint 1 prismatic"),
            std::string::npos)
      << conf.message;
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
