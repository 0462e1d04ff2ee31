// The result file from its record (apps/record/result_json.hpp): the optional members appear
// exactly when the record holds them, outliers name their source, and the model reads back
// with the same bits.
#include <gtest/gtest.h>

#include <memory>
#include <string>

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

}  // namespace
}  // namespace hivecal::result_record_test
