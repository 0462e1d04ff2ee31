// The "compliance" key of a result / robot description (textio/robot_description.hpp,
// docs/formats.md): written only for a model with terms, read back to the same bits in either
// DH convention, and refused with the key named when it cannot be used.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "testkit/other_arms.hpp"
#include "textio/robot_description.hpp"
#include "record/result_json.hpp"

namespace hivecal::compliance_json_test {
namespace {

/// A UR5e result whose joints 2 and 3 bend: the default terms of `load`, made-up coefficients.
record::CalibrationFile compliant_ur5e(ComplianceLoad load, const Vec3& gravity) {
  record::CalibrationFile file;
  file.robot = "ur5e";
  file.model = nominal_model(RobotType::ur5e);
  file.model.tool_m << 0.001, -0.002, 0.17;
  file.base_to_tracker = test::example_base_to_tracker();
  ComplianceModel& c = file.model.compliance;
  if (load == ComplianceLoad::arm_masses) {
    EXPECT_EQ(nominal_arm_masses(RobotType::ur5e, &c.masses), Status::ok);
    c.masses.payload_kg = 1.25;
    c.masses.payload_com_m << 0.0, 0.01, 0.05;
  }
  EXPECT_EQ(default_compliance_terms(file.model, gravity, load, &c), Status::ok);
  for (int t = 0; t < c.term_count; ++t) {
    c.coefficient[t] = (load == ComplianceLoad::point ? 7e-5 : 3e-6) * (1.0 + 0.37 * t);
    file.compliance_sigma[t] = 1e-6 * (t + 1);
  }
  return file;
}

double worst_point_difference_m(const RobotModel& a, const RobotModel& b) {
  Random random(5);
  double worst_m = 0.0;
  for (int i = 0; i < 200; ++i) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(-3.0, 3.0);
    worst_m = std::fmax(worst_m, (fk_tool_point(a, q) - fk_tool_point(b, q)).norm());
  }
  return worst_m;
}

TEST(ComplianceJson, RoundTripsToTheSameBits) {
  for (ComplianceLoad load : {ComplianceLoad::point, ComplianceLoad::arm_masses}) {
    for (const Vec3& gravity : {Vec3(0.0, 0.0, -1.0), Vec3(0.6, 0.0, -0.8)}) {
      const record::CalibrationFile file = compliant_ur5e(load, gravity);
      ASSERT_GT(file.model.compliance.term_count, 0);
      const std::string text = record::format_calibration_json(file);
      EXPECT_NE(text.find(load == ComplianceLoad::point ? "\"kind\": \"basis\"" : "\"kind\": \"masses\""),
                std::string::npos);
      EXPECT_NE(text.find(load == ComplianceLoad::point ? "\"unit\": \"rad/m\"" : "\"unit\": \"rad/(kg m)\""),
                std::string::npos);
      EXPECT_NE(text.find("\"sigma\": 9.9999999999999995e-07"), std::string::npos);  // term 1's sigma, 1e-6
      record::CalibrationFile back;
      const port::Error r = record::parse_calibration_json(text, "r.json", &back);
      ASSERT_TRUE(r.ok()) << r.message;
      // ComplianceModel has no padding: the bytes are the model.
      EXPECT_EQ(std::memcmp(&back.model.compliance, &file.model.compliance, sizeof(ComplianceModel)), 0)
          << textio::compliance_kind_name(load);
      EXPECT_EQ(worst_point_difference_m(back.model, file.model), 0.0);
      RobotModel rigid = file.model;
      rigid.compliance = ComplianceModel{};
      EXPECT_GT(worst_point_difference_m(back.model, rigid), 1e-6);  // the key is not a no-op
    }
  }
}

TEST(ComplianceJson, RigidModelsHaveNoKey) {
  record::CalibrationFile file = compliant_ur5e(ComplianceLoad::point, Vec3(0.0, 0.0, -1.0));
  file.model.compliance = ComplianceModel{};
  const std::string text = record::format_calibration_json(file);
  EXPECT_EQ(text.find("compliance"), std::string::npos);
  record::CalibrationFile back;
  ASSERT_TRUE(record::parse_calibration_json(text, "r.json", &back).ok());
  EXPECT_EQ(back.model.compliance.term_count, 0);
}

// A modified-DH file writes gravity in its own base frame (alpha_0 tilts it) and reads it back.
TEST(ComplianceJson, ModifiedDhFileKeepsGravityInItsOwnBase) {
  record::CalibrationFile file;
  file.robot = "abb-irb120";
  file.convention = DhConvention::modified;
  file.modified_base = ModifiedDhBase{0.2, 0.01};
  file.model = test::other_arm_model(test::OtherArm::irb120);
  file.model.tool_m << 0.0, 0.0, 0.1;
  ASSERT_EQ(default_compliance_terms(file.model, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &file.model.compliance),
            Status::ok);
  for (int t = 0; t < file.model.compliance.term_count; ++t) file.model.compliance.coefficient[t] = 5e-5;
  const std::string text = record::format_calibration_json(file);
  record::CalibrationFile back;
  const port::Error r = record::parse_calibration_json(text, "m.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(text.find("\"gravity_direction\": [0, 0, -1]"), std::string::npos);  // tilted by alpha_0
  EXPECT_LT((back.model.compliance.gravity_direction - file.model.compliance.gravity_direction).norm(), 1e-15);
  EXPECT_LE(worst_point_difference_m(back.model, file.model), 1e-12);
}

TEST(ComplianceJson, UnusableKeysAreRefusedByName) {
  const std::string good = record::format_calibration_json(compliant_ur5e(ComplianceLoad::point, Vec3(0.0, 0.0, -1.0)));
  struct Case {
    const char* from;
    const char* to;
    const char* message;
  };
  const Case cases[] = {
      {"\"kind\": \"basis\"", "\"kind\": \"springs\"", "\"compliance\": must be an object with \"kind\""},
      {"\"load\": \"frame 2\"", "\"load\": \"elbow\"", "\"terms\"[0].load must be \"frame K\""},
      {"\"load\": \"frame 2\"", "\"load\": \"frame 1\"", "not a usable compliance model"},  // at the joint, not beyond
      {"\"unit\": \"rad/m\"", "\"unit\": \"urad/m\"", "\"terms\"[0].unit must be \"rad/m\""},
      {"\"joint\": 2", "\"joint\": 7", "\"terms\"[0].joint must be a joint number 1 .. 6"},
      {"\"gravity_direction\": [0, 0, -1]", "\"gravity_direction\": [0, 0, -2]", "not a usable compliance model"},
      {"\"gravity_direction\": [0, 0, -1]", "\"gravity_direction\": [0, -1]", "\"gravity_direction\" must be"},
      {"\"coefficient\": ", "\"coefficient\": \"x\", \"was\": ", "\"terms\"[0].coefficient must be a number"},
      // A coefficient no joint has (1e10 rad/m) predicted nonsense with exit 0 before:
      {"\"coefficient\": ", "\"coefficient\": 1e10, \"was\": ",
       "\"terms\"[0].coefficient must be a number within +/-0.01"},
  };
  for (const Case& c : cases) {
    std::string text = good;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, std::strlen(c.from), c.to);
    record::CalibrationFile back;
    const port::Error r = record::parse_calibration_json(text, "r.json", &back);
    EXPECT_FALSE(r.ok()) << c.to;
    EXPECT_NE(r.message.find("r.json: \"compliance\": "), std::string::npos) << r.message;
    EXPECT_NE(r.message.find(c.message), std::string::npos) << r.message;
  }
}

/// The point terms of compliant_ur5e followed by the harmonics of orders 1 .. 2 of every joint.
record::CalibrationFile harmonic_ur5e() {
  record::CalibrationFile file = compliant_ur5e(ComplianceLoad::point, Vec3(0.0, 0.0, -1.0));
  ComplianceModel& c = file.model.compliance;
  EXPECT_EQ(append_harmonic_terms(2, file.model, &c), Status::ok);
  for (int t = 4; t < c.term_count; ++t) {
    c.coefficient[t] = 3e-5 * (t % 2 == 0 ? 1.0 : -0.7) / (t - 3);
    file.compliance_sigma[t] = 2e-6;
  }
  return file;
}

TEST(ComplianceJson, HarmonicTermsRoundTripToTheSameBits) {
  if (4 + 4 * kSixJoints > kMaxComplianceTerms) GTEST_SKIP() << "this build holds " << kMaxComplianceTerms << " terms";
  const record::CalibrationFile file = harmonic_ur5e();
  const std::string text = record::format_calibration_json(file);
  const std::size_t term = text.find("\"name\": \"h_j3_cos2\"");
  ASSERT_NE(term, std::string::npos) << text;
  EXPECT_LT(text.find("\"harmonic\": \"cos 2\"", term), text.find('}', term));
  EXPECT_LT(text.find("\"unit\": \"rad\"", term), text.find('}', term));
  EXPECT_NE(text.find("\"load\": \"frame 2\""), std::string::npos);  // the gravity terms keep theirs
  record::CalibrationFile back;
  const port::Error r = record::parse_calibration_json(text, "r.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(std::memcmp(&back.model.compliance, &file.model.compliance, sizeof(ComplianceModel)), 0);
  EXPECT_EQ(worst_point_difference_m(back.model, file.model), 0.0);
  record::CalibrationFile gravity_only = file;
  gravity_only.model.compliance.term_count = 4;
  EXPECT_GT(worst_point_difference_m(back.model, gravity_only.model), 1e-6);  // the harmonics are not a no-op
}

TEST(ComplianceJson, UnusableHarmonicsAreRefusedByName) {
  if (4 + 4 * kSixJoints > kMaxComplianceTerms) GTEST_SKIP() << "this build holds " << kMaxComplianceTerms << " terms";
  const std::string good = record::format_calibration_json(harmonic_ur5e());
  struct Case {
    const char* from;  ///< replaced at its first place after the first harmonic term (terms[4])
    const char* to;
    const char* message;
  };
  const Case cases[] = {
      {"\"harmonic\": \"sin 1\"", "\"harmonic\": \"tan 1\"", "\"terms\"[4].harmonic must be \"sin K\" or \"cos K\""},
      {"\"harmonic\": \"sin 1\"", "\"harmonic\": \"sin 4\"", "\"terms\"[4].harmonic must be"},
      {"\"harmonic\": \"sin 1\"", "\"harmonic\": 1", "\"terms\"[4].harmonic must be"},
      {"\"unit\": \"rad\"", "\"unit\": \"rad/m\"", "\"terms\"[4].unit must be \"rad\" for a harmonic"},
  };
  for (const Case& c : cases) {
    std::string text = good;
    const std::size_t at = text.find(c.from, text.find("\"name\": \"h_j1_sin1\""));
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, std::strlen(c.from), c.to);
    record::CalibrationFile back;
    const port::Error r = record::parse_calibration_json(text, "r.json", &back);
    EXPECT_FALSE(r.ok()) << c.to;
    EXPECT_NE(r.message.find(c.message), std::string::npos) << r.message;
  }
}

}  // namespace
}  // namespace hivecal::compliance_json_test
