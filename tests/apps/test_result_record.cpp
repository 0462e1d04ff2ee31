// The result file from its record (apps/record/result_json.hpp): the optional members appear
// exactly when the record holds them, outliers name their source, the model reads back with
// the same bits, and so do the covariance and the domain (a malformed one refused by its key);
// a result's members as written (textio's object_member_texts) make the same document again.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hivecal/calibration.hpp"
#include "record/result_json.hpp"
#include "textio/json.hpp"

namespace hivecal::result_record_test {
namespace {

record::CalibrationRecord minimal_record() {
  record::CalibrationRecord r;
  r.file.robot = "ur5";
  r.file.model = nominal_model(RobotType::ur5);
  r.file.model.joints[1].a_m += 1.25e-4;  // not a round number: the bits must survive
  r.file.model.tool_m = Vec3(0.001, -0.002, 0.1695);
  r.file.base_to_tracker.translation_m = Vec3(1.5, -0.25, 0.75);
  r.method = "LM";
  r.params = "full";
  r.seed = 7;
  r.split = 0.7;
  return r;
}

textio::JsonValue parsed(const std::string& text) {
  textio::JsonValue root;
  EXPECT_TRUE(textio::parse_json(text, &root).ok());
  return root;
}

TEST(ResultRecord, OptionalMembersAppearOnlyWhenTheRecordHoldsThem) {
  const record::CalibrationRecord bare = minimal_record();
  const textio::JsonValue root = parsed(record::format_result_json(bare));
  for (const char* key : {"format", "dh", "tool", "base_to_tracker", "method", "params", "seed", "split",
                          "uncalibrated_metrics", "ur_deltas"})
    EXPECT_NE(root.find(key), nullptr) << key;
  for (const char* key : {"metrics", "methods", "identifiability", "outliers", "cross_validation", "warnings", "report",
                          "clock", "orientation", "joint_sigma_rad", "known"})
    EXPECT_EQ(root.find(key), nullptr) << key;
  EXPECT_EQ(root.find("method")->string, "LM");
  EXPECT_EQ(root.find("seed")->number, 7.0);
}

TEST(ResultRecord, OutliersNameTheirSourceAndCrossValidationItsBaseline) {
  auto result = std::make_unique<CalibrationResult>();
  result->outliers[0] = CalibrationOutlier{2, 8.0e-3, 41.5, 4.9};
  result->outlier_count = 1;
  result->outlier_rounds = 2;
  auto cv = std::make_unique<CrossValidationResult>();
  cv->fold_count = 1;
  cv->sample_count = 12;
  cv->mae_3d_m = 6.0e-5;
  cv->baseline_mae_3d_m = 8.7e-4;
  streams::SessionFacts facts;
  facts.sample_sources = {"poses.csv:2", "poses.csv:3", "poses.csv:4"};
  record::CalibrationRecord r = minimal_record();
  r.result = result.get();
  r.cv = cv.get();
  r.facts = &facts;
  r.warnings = {"a warning"};
  const textio::JsonValue root = parsed(record::format_result_json(r));
  ASSERT_NE(root.find("outliers"), nullptr);
  ASSERT_EQ(root.find("outliers")->array.size(), 1u);
  EXPECT_EQ(root.find("outliers")->array[0].find("source")->string, "poses.csv:4");
  EXPECT_TRUE(root.find("outlier_search")->boolean);
  ASSERT_NE(root.find("cross_validation"), nullptr);
  EXPECT_EQ(root.find("cross_validation")->find("baseline_mae_3d_m")->number, 8.7e-4);
  ASSERT_NE(root.find("warnings"), nullptr);
  EXPECT_EQ(root.find("warnings")->array[0].string, "a warning");
  // Without the input's sources a sample is named by its index.
  r.facts = nullptr;
  const textio::JsonValue unnamed = parsed(record::format_result_json(r));
  EXPECT_EQ(unnamed.find("outliers")->array[0].find("source")->string, "sample 2");
}

TEST(ResultRecord, TheModelReadsBackWithTheSameBits) {
  const record::CalibrationRecord r = minimal_record();
  record::CalibrationFile back;
  ASSERT_TRUE(record::parse_calibration_json(record::format_result_json(r), "result.json", &back).ok());
  EXPECT_EQ(back.model.joints[1].a_m, r.file.model.joints[1].a_m);
  EXPECT_EQ(back.model.tool_m, r.file.model.tool_m);
  EXPECT_EQ(back.base_to_tracker.translation_m, r.file.base_to_tracker.translation_m);
}

TEST(ResultRecord, TheCovarianceAndTheDomainReadBackWithTheSameBits) {
  record::CalibrationRecord r = minimal_record();
  record::CalibrationUncertainty& u = r.file.uncertainty;
  NormalMatrix c = NormalMatrix::Zero();
  const int a2 = 6;  // a2, alpha1 and base_tx
  const int alpha1 = 3;
  const int tx = base_translation_param_index(kSixJoints, 0);
  c(a2, a2) = 4.1e-9;
  c(alpha1, alpha1) = 2.3e-8;
  c(tx, tx) = 9.7e-8;
  c(a2, tx) = c(tx, a2) = -1.3e-8;
  u.set_covariance(c);
  u.estimated = param_bit(a2) | param_bit(alpha1) | param_bit(tx);
  u.residual_sigma_m = 1.1e-5;
  u.residual_dof = 40;
  u.has_domain = true;
  u.domain.poses = 30;
  u.domain.joint_min_rad << -1.0, -2.0, -0.5, -3.0, -2.5, -0.1;
  u.domain.joint_max_rad << 1.0, -0.5, 2.0, 0.0, -0.3, 3.0;
  u.domain.tool_axis_mean = Vec3(0.0, 0.6, -0.8);
  u.domain.tool_axis_spread_rad = 0.3;
  u.domain.typical_sigma_m = 2.2e-5;
  u.domain.term_joints = 6;
  const std::string text = record::format_result_json(r);
  const textio::JsonValue root = parsed(text);
  ASSERT_NE(root.find("covariance"), nullptr);
  EXPECT_EQ(root.find("covariance")->find("parameters")->array[0].string, "alpha1");
  record::CalibrationFile back;
  ASSERT_TRUE(record::parse_calibration_json(text, "r.json", &back).ok());
  EXPECT_EQ(back.uncertainty.covariance_matrix(), c);
  EXPECT_EQ(back.uncertainty.estimated, u.estimated);
  EXPECT_EQ(back.uncertainty.residual_dof, 40);
  EXPECT_EQ(back.uncertainty.domain.joint_min_rad, u.domain.joint_min_rad);
  EXPECT_EQ(back.uncertainty.domain.tool_axis_mean, u.domain.tool_axis_mean);
  EXPECT_EQ(back.uncertainty.domain.term_joints, 6u);
  EXPECT_EQ(back.uncertainty.domain.typical_sigma_m, 2.2e-5);
  // A name the model does not have, fewer names than rows: refused by the key.
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"\"alpha1\",", "\"alpha9\","},
                                 std::pair<std::string, std::string>{"\"alpha1\",", ""}}) {
    std::string bad = text;
    const std::size_t at = bad.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    bad.replace(at, from.size(), to);
    const port::Error error = record::parse_calibration_json(bad, "r.json", &back);
    EXPECT_FALSE(error.ok()) << to;
    EXPECT_NE(error.message.find("r.json: \"covariance\""), std::string::npos) << error.message;
  }
}

TEST(ResultRecord, ItsMembersAsWrittenMakeTheSameDocumentAgain) {
  const std::string text = record::format_result_json(minimal_record());
  std::vector<textio::JsonMemberText> members;
  ASSERT_TRUE(textio::object_member_texts(text, &members));
  ASSERT_GT(members.size(), 8u);
  EXPECT_EQ(members[0].key, "format");
  EXPECT_EQ(members[0].text.substr(0, 9), "\"format\":");
  EXPECT_EQ(textio::object_document(members), text);
  // Strings with brackets, commas and escaped quotes inside, nested arrays, a member spelled
  // with an escape: each member whole.
  const std::string odd = "{ \"a\" : \"x, ] } \\\" y\",\"b\":[[1,2],{\"c\":\"}\"}] ,\"d\\u0041\":-1.5e3}";
  ASSERT_TRUE(textio::object_member_texts(odd, &members));
  ASSERT_EQ(members.size(), 3u);
  EXPECT_EQ(members[0].text, "\"a\" : \"x, ] } \\\" y\"");
  EXPECT_EQ(members[1].text, "\"b\":[[1,2],{\"c\":\"}\"}]");
  EXPECT_EQ(members[2].key, "dA");
  EXPECT_EQ(members[2].text, "\"d\\u0041\":-1.5e3");
  EXPECT_FALSE(textio::object_member_texts("[1, 2]", &members));
}

}  // namespace
}  // namespace hivecal::result_record_test
