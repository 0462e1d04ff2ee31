// A calibration beyond its session, end to end on a lab-style export (';' separated, mm, named
// columns): calibrate writes the covariance (its diagonal the sigmas) and the domain;
// `calibrate --fit base` carries the result to a moved tracker, every other member byte for
// byte; `validate --samples` gives the figures predict plus one's own error computation gives
// (to 1 um), with and without --fit; predict writes sigma_m and flags poses outside the domain;
// and what --fit and validate refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/metrics.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"

namespace hivecal::registration_cli_test {
namespace {

using test::run;

const char* const kHeader =
    "Timestamp;shoulder_pan_joint;shoulder_lift_joint;elbow_joint;wrist_1_joint;wrist_2_joint;wrist_3_joint;"
    "measurement_x;measurement_y;measurement_z";
const std::vector<std::string> kReader = {"--length-unit", "mm", "--columns",
                                          "x=measurement_x,y=measurement_y,z=measurement_z"};

/// The simulated arm: a UR10 off its nominal table, a tool off the flange axis.
RobotModel truth_arm() {
  Random random(17);
  return test::perturbed_parallel_model(RobotType::ur10, &random, 1e-3, 1e-3, Vec3(0.004, -0.006, 0.109));
}

/// The tracker set up anew: turned 30 deg about z, tilted, moved by metres.
RigidTransform moved(const RigidTransform& base) {
  RigidTransform t = base;
  t.rotation = rotation_from_vector(Vec3(0.01, 0.0, 0.52)) * base.rotation;
  t.translation_m += Vec3(0.8, -1.2, 0.15);
  return t;
}

/// A lab export of `poses` (mm, ';', 10 um noise) of `arm` seen from `base`.
std::string export_text(const RobotModel& arm, const RigidTransform& base, const std::vector<JointVector>& poses,
                        Random* random) {
  std::string text = std::string(kHeader) + "\n";
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Vec3 p_mm = 1e3 * (base.apply(fk_tool_point(arm, poses[k])) + 1e-5 * test::gaussian_vector(random));
    text += std::to_string(k);
    for (int j = 0; j < kSixJoints; ++j) text += ";" + textio::format_double(poses[k](j));
    for (int a = 0; a < 3; ++a) text += ";" + textio::format_double(p_mm(a));
    text += "\n";
  }
  return text;
}

/// The joints CSV predict reads.
std::string joints_text(const std::vector<JointVector>& poses) {
  std::string text = "q1,q2,q3,q4,q5,q6\n";
  for (const JointVector& q : poses) {
    for (int j = 0; j < kSixJoints; ++j) text += (j == 0 ? "" : ",") + textio::format_double(q(j));
    text += "\n";
  }
  return text;
}

/// The numbers of every data row of a delimited text (after its header line, into *header).
std::vector<std::vector<double>> rows_of(const std::string& text, char separator, std::string* header) {
  *header = text.substr(0, text.find('\n'));
  std::vector<std::vector<double>> rows;
  for (std::size_t at = text.find('\n') + 1; at < text.size();) {
    const std::size_t end = text.find('\n', at);
    std::vector<double> row;
    for (std::size_t field = at; field <= end;) {
      const std::size_t next = std::min(text.find(separator, field), end);
      double v = 0.0;
      EXPECT_TRUE(textio::parse_double(text.substr(field, next - field), &v));
      row.push_back(v);
      field = next + 1;
    }
    rows.push_back(row);
    at = end + 1;
  }
  return rows;
}

/// Rows of a CSV predict wrote: every column of every data row.
std::vector<std::vector<double>> csv_rows(const std::string& path, std::string* header) {
  return rows_of(test::read_text_file(path), ',', header);
}

/// The header and the first `rows` data rows of a text.
std::string first_rows(const std::string& text, int rows) {
  std::size_t cut = 0;
  for (int line = 0; line <= rows; ++line) cut = text.find('\n', cut) + 1;
  return text.substr(0, cut);
}

/// Random joints within a narrower band than a UR's whole range (the calibration's domain).
std::vector<JointVector> random_poses(std::size_t count, Random* random) {
  std::vector<JointVector> poses;
  for (std::size_t k = 0; k < count; ++k) poses.push_back(test::random_joints(random));
  return poses;
}

/// The statistics one computes oneself from predicted points and measured ones [m].
ErrorStats own_stats(const std::vector<Vec3>& predicted, const std::vector<Vec3>& measured) {
  ErrorStats s;
  s.count = predicted.size();
  const double n = static_cast<double>(s.count);
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    std::vector<double> e;
    for (std::size_t k = 0; k < predicted.size(); ++k) {
      const Vec3 d = predicted[k] - measured[k];
      e.push_back(axis < 3 ? std::fabs(d(axis)) : d.norm());
    }
    double sum = 0.0;
    for (double v : e) sum += v;
    s.mae_m[axis] = sum / n;
    double squares = 0.0;
    for (double v : e) {
      squares += (v - s.mae_m[axis]) * (v - s.mae_m[axis]);
      s.max_m[axis] = std::fmax(s.max_m[axis], v);
    }
    s.sigma_m[axis] = std::sqrt(squares / (n - 1.0));
  }
  return s;
}

void expect_metrics(const textio::JsonValue& metrics, const ErrorStats& own, double tolerance_m) {
  ASSERT_NE(metrics.find("count"), nullptr);
  EXPECT_EQ(metrics.find("count")->number, static_cast<double>(own.count));
  for (const record::ErrorStatsField& field : record::kErrorStatsFields) {
    for (int axis = 0; axis < kErrorAxisCount; ++axis) {
      const textio::JsonValue* value = metrics.find(field.key)->find(record::kErrorAxisKeys[axis]);
      ASSERT_NE(value, nullptr) << field.key;
      EXPECT_NEAR(value->number, (own.*field.values)[axis], tolerance_m) << field.key << " " << axis;
    }
  }
}

/// One session: a calibration on 150 poses, 120 other poses seen from a moved tracker.
struct Session {
  test::TempDir dir{"hivecal_registration"};
  RobotModel arm = truth_arm();
  RigidTransform base = test::example_base_to_tracker();
  std::vector<JointVector> train;
  std::vector<JointVector> other;
  std::string result;        // calibrate's result
  std::string moved_export;  // the other poses from the moved tracker
  Session() {
    Random random(23);
    train = random_poses(150, &random);
    other = random_poses(120, &random);
    const std::string train_csv = dir.write("train.csv", export_text(arm, base, train, &random));
    moved_export = dir.write("moved.csv", export_text(arm, moved(base), other, &random));
    result = dir.path() + "/r.json";
    std::vector<std::string> args = {"--samples", train_csv, "--robot-model", "ur10", "--tool", "0,0,0.109",
                                     "--method",  "lm",      "--split",       "1",    "--out",  result};
    args.insert(args.end(), kReader.begin(), kReader.end());
    testing::internal::CaptureStdout();
    EXPECT_EQ(run(cli::calibrate_main, args), cli::kExitOk);
    testing::internal::GetCapturedStdout();
  }
};

Session& session() {
  static Session s;
  return s;
}

TEST(ResultUncertainty, TheCovarianceIsTheSigmasSquaredAndTheDomainTheTrainingPoses) {
  const textio::JsonValue root = test::read_json_file(session().result);
  const textio::JsonValue* covariance = root.find("covariance");
  const textio::JsonValue* sigma = root.find("sigma");
  ASSERT_NE(covariance, nullptr);
  ASSERT_NE(sigma, nullptr);
  const std::vector<textio::JsonValue>& names = covariance->find("parameters")->array;
  const std::vector<textio::JsonValue>& rows = covariance->find("matrix")->array;
  ASSERT_EQ(names.size(), sigma->object.size());
  for (std::size_t a = 0; a < names.size(); ++a) {
    const double s = sigma->find(names[a].string)->number;
    EXPECT_NEAR(std::sqrt(rows[a].array[a].number), s, 1e-9 * s) << names[a].string;
  }
  const textio::JsonValue* domain = root.find("domain");
  ASSERT_NE(domain, nullptr);
  EXPECT_EQ(domain->find("poses")->number, 150.0);
  for (int j = 0; j < kSixJoints; ++j) {
    double low = 10.0;
    for (const JointVector& q : session().train) low = std::fmin(low, q(j));
    EXPECT_EQ(domain->find("joint_min_rad")->array[static_cast<std::size_t>(j)].number, low);
  }
  EXPECT_GT(domain->find("typical_sigma_m")->number, 0.0);
  EXPECT_EQ(domain->find("term_joints")->number, 0.0);  // a rigid fit: no joint's range counts
}

TEST(CalibrateFit, CarriesTheCalibrationToAMovedTrackerAndEveryOtherMemberAsWritten) {
  Session& s = session();
  // Register on the first 20 poses of the moved export.
  const std::string twenty = s.dir.write("twenty.csv", first_rows(test::read_text_file(s.moved_export), 20));
  const std::string registered = s.dir.path() + "/registered.json";
  std::vector<std::string> args = {"--fit",     "base", "--robot-model", s.result,
                                   "--samples", twenty, "--out",         registered};
  args.insert(args.end(), kReader.begin(), kReader.end());
  testing::internal::CaptureStdout();
  ASSERT_EQ(run(cli::calibrate_main, args), cli::kExitOk);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("registration: base fitted on 20 poses"), std::string::npos) << out;
  EXPECT_NE(out.find("domain: made on 150 poses"), std::string::npos) << out;
  // Every member but the registered ones as RESULT wrote it.
  std::vector<textio::JsonMemberText> before;
  std::vector<textio::JsonMemberText> after;
  ASSERT_TRUE(textio::object_member_texts(test::read_text_file(s.result), &before));
  ASSERT_TRUE(textio::object_member_texts(test::read_text_file(registered), &after));
  for (const textio::JsonMemberText& m : before) {
    if (m.key == "base_to_tracker" || m.key == "metrics" || m.key == "covariance" || m.key == "domain") continue;
    bool same = false;
    for (const textio::JsonMemberText& n : after) same = same || (n.key == m.key && n.text == m.text);
    EXPECT_TRUE(same) << m.key;
  }
  const textio::JsonValue root = test::read_json_file(registered);
  EXPECT_EQ(root.find("fitted")->string, "base");
  EXPECT_EQ(root.find("registration")->find("poses")->number, 20.0);
  ASSERT_NE(root.find("calibration_metrics"), nullptr);
  // It predicts the other poses where the moved tracker sees them.
  const std::string joints = s.dir.write("other_joints.csv", joints_text(s.other));
  const std::string predicted = s.dir.path() + "/predicted.csv";
  std::string err;
  ASSERT_EQ(test::run_capturing_stderr(cli::predict_main,
                                       {"--calibration", registered, "--joints", joints, "--out", predicted}, &err),
            cli::kExitOk);
  EXPECT_NE(err.find("of 120 poses extrapolated"), std::string::npos) << err;
  std::string header;
  const std::vector<std::vector<double>> rows = csv_rows(predicted, &header);
  EXPECT_EQ(header, "x,y,z,sigma_m,extrapolated");
  ASSERT_EQ(rows.size(), 120u);
  double worst_m = 0.0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Vec3 truth = moved(s.base).apply(fk_tool_point(s.arm, s.other[k]));
    worst_m = std::fmax(worst_m, (Vec3(rows[k][0], rows[k][1], rows[k][2]) - truth).norm());
    EXPECT_GT(rows[k][3], 0.0);
  }
  EXPECT_LT(worst_m, 1e-4);
}

TEST(ValidateSamples, ItsFiguresArePredictPlusOnesOwnErrorsToAMicrometre) {
  Session& s = session();
  // Without a registration: the calibration as it is, on the moved export (far off: the tracker moved).
  for (const bool fit : {false, true}) {
    const std::string v_json = s.dir.path() + (fit ? "/v_fit.json" : "/v.json");
    std::vector<std::string> args = {"--calibration", s.result, "--samples", s.moved_export, "--out", v_json};
    if (fit) args.insert(args.end(), {"--fit", "base", "--fit-poses", "20"});
    args.insert(args.end(), kReader.begin(), kReader.end());
    testing::internal::CaptureStdout();
    ASSERT_EQ(run(cli::validate_main, args), cli::kExitOk) << fit;
    const std::string out = testing::internal::GetCapturedStdout();
    EXPECT_NE(out.find(fit ? "scored on the other 100" : "120 samples scored"), std::string::npos) << out;
    EXPECT_NE(out.find(fit ? "moved.csv:22 " : "moved.csv:2 "), std::string::npos) << out;  // by file line
    // predict through the same calibration (registered by calibrate --fit on the same 20 poses).
    std::string calibration = s.result;
    std::size_t first = 0;
    if (fit) {
      calibration = s.dir.path() + "/registered20.json";
      std::vector<std::string> reg = {
          "--fit",  "base",      "--robot-model",
          s.result, "--samples", s.dir.write("first20.csv", first_rows(test::read_text_file(s.moved_export), 20)),
          "--out",  calibration};
      reg.insert(reg.end(), kReader.begin(), kReader.end());
      testing::internal::CaptureStdout();
      ASSERT_EQ(run(cli::calibrate_main, reg), cli::kExitOk);
      testing::internal::GetCapturedStdout();
      first = 20;
    }
    const std::vector<JointVector> scored(s.other.begin() + static_cast<long>(first), s.other.end());
    const std::string predicted = s.dir.path() + "/p.csv";
    std::string err;
    ASSERT_EQ(test::run_capturing_stderr(cli::predict_main,
                                         {"--calibration", calibration, "--joints",
                                          s.dir.write("scored.csv", joints_text(scored)), "--out", predicted},
                                         &err),
              cli::kExitOk);
    std::string header;
    const std::vector<std::vector<double>> rows = csv_rows(predicted, &header);
    // The measured points as the export holds them (mm), read back by hand.
    std::vector<Vec3> measured;
    const std::vector<std::vector<double>> exported = rows_of(test::read_text_file(s.moved_export), ';', &header);
    for (std::size_t line = first; line < exported.size(); ++line) {
      measured.push_back(1e-3 * Vec3(exported[line][7], exported[line][8], exported[line][9]));
    }
    std::vector<Vec3> points;
    for (const std::vector<double>& r : rows) points.push_back(Vec3(r[0], r[1], r[2]));
    ASSERT_EQ(points.size(), measured.size());
    const textio::JsonValue v = test::read_json_file(v_json);
    expect_metrics(*v.find("metrics"), own_stats(points, measured), 1e-6);
    const std::vector<textio::JsonValue>& poses = v.find("poses")->array;
    ASSERT_EQ(poses.size(), points.size());
    for (std::size_t k = 0; k < poses.size(); ++k) {
      EXPECT_NEAR(poses[k].find("sigma_m")->number, rows[k][3], 1e-9);
      EXPECT_EQ(poses[k].find("extrapolated")->boolean, rows[k][4] == 1.0);
    }
    EXPECT_EQ(v.find("same_poses") != nullptr, fit);
    if (fit) {
      EXPECT_FALSE(v.find("same_poses")->boolean);
    }
  }
}

TEST(PredictDomain, APoseWithTheToolTurnedAwayIsFlagged) {
  Session& s = session();
  // Training poses stay inside; the tool axis turned beyond the training spread does not.
  const textio::JsonValue root = test::read_json_file(s.result);
  const double spread_rad = root.find("domain")->find("tool_axis_spread_rad")->number;
  std::vector<JointVector> poses(s.train.begin(), s.train.begin() + 10);
  const std::string predicted = s.dir.path() + "/inside_predicted.csv";
  std::string err;
  ASSERT_EQ(test::run_capturing_stderr(cli::predict_main,
                                       {"--calibration", s.result, "--joints",
                                        s.dir.write("inside.csv", joints_text(poses)), "--out", predicted},
                                       &err),
            cli::kExitOk);
  EXPECT_NE(err.find("0 of 10 poses extrapolated"), std::string::npos) << err;
  EXPECT_LT(spread_rad, math::kPi);
  // A narrow calibration: 40 poses with the tool pointing down (one tool orientation), then
  // random poses of every orientation.
  Random random(29);
  std::vector<JointVector> narrow;
  for (std::size_t k = 0; k < 40; ++k) narrow.push_back(test::tool_down_joints(s.arm, false, &random));
  const std::string narrow_result = s.dir.path() + "/narrow.json";
  std::vector<std::string> args = {
      "--samples",     s.dir.write("narrow.csv", export_text(s.arm, s.base, narrow, &random)),
      "--robot-model", "ur10",
      "--tool",        "0,0,0.109",
      "--method",      "lm",
      "--split",       "1",
      "--out",         narrow_result};
  args.insert(args.end(), kReader.begin(), kReader.end());
  testing::internal::CaptureStdout();
  const int code = run(cli::calibrate_main, args);
  const std::string out = testing::internal::GetCapturedStdout();
  ASSERT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << out;
  EXPECT_NE(out.find("nearly one tool orientation"), std::string::npos) << out;
  ASSERT_EQ(test::run_capturing_stderr(cli::predict_main,
                                       {"--calibration", narrow_result, "--joints",
                                        s.dir.write("all.csv", joints_text(s.other)), "--out", predicted},
                                       &err),
            cli::kExitOk);
  std::string header;
  std::size_t flagged = 0;
  for (const std::vector<double>& row : csv_rows(predicted, &header)) flagged += row[4] == 1.0 ? 1 : 0;
  EXPECT_GT(flagged, 100u) << err;  // of 120 random poses
  unsigned by_tool_axis = 0;        // the reason: a direction the tool axis never took
  ASSERT_EQ(std::sscanf(err.c_str() + err.find("the tool axis "), "the tool axis %u", &by_tool_axis), 1) << err;
  EXPECT_GT(by_tool_axis, 100u) << err;
}

TEST(PredictColumns, ReadsTheJointsOfAnExportByTheNamesGiven) {
  Session& s = session();
  // The lab export itself, its joints under other names: the same points as the joints CSV.
  std::string text = test::read_text_file(s.moved_export);
  const std::string renamed = "Timestamp;j1;j2;j3;j4;j5;j6" + text.substr(text.find(";measurement_x"));
  const std::string by_name = s.dir.path() + "/by_name.csv";
  const std::string plain = s.dir.path() + "/plain.csv";
  std::string err;
  ASSERT_EQ(
      test::run_capturing_stderr(cli::predict_main,
                                 {"--calibration", s.result, "--joints", s.dir.write("renamed.csv", renamed),
                                  "--columns", "q1=j1,q2=j2,q3=j3,q4=j4,q5=j5,q6=j6,x=measurement_x", "--out", by_name},
                                 &err),
      cli::kExitOk)
      << err;
  ASSERT_EQ(test::run_capturing_stderr(cli::predict_main,
                                       {"--calibration", s.result, "--joints",
                                        s.dir.write("other_joints.csv", joints_text(s.other)), "--out", plain},
                                       &err),
            cli::kExitOk);
  EXPECT_EQ(test::read_text_file(by_name), test::read_text_file(plain));
}

TEST(RegistrationRefusals, WhatBelongsToACalibrationAndWhatCannotScore) {
  Session& s = session();
  const std::vector<std::string> fit = {"--fit",         "base",
                                        "--robot-model", s.result,
                                        "--samples",     s.moved_export,
                                        "--length-unit", "mm",
                                        "--columns",     "x=measurement_x,y=measurement_y,z=measurement_z",
                                        "--out",         s.dir.path() + "/x.json"};
  test::expect_refusals(cli::calibrate_main, fit,
                        {{{"--method", "lm"}, "--method belongs to a calibration"},
                         {{"--harmonics", "2"}, "--harmonics belongs to a calibration"},
                         {{"--cv", "5"}, "--cv belongs to a calibration"},
                         {{"--report", s.dir.path() + "/rep"}, "--report belongs to a calibration"}});
  std::string err;
  EXPECT_EQ(
      test::run_capturing_stderr(cli::calibrate_main,
                                 {"--fit", "sideways", "--robot-model", s.result, "--samples", s.moved_export}, &err),
      cli::kExitUsage);
  EXPECT_NE(err.find("--fit must be 'base'"), std::string::npos) << err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--fit", "base", "--robot-model", "ur10", "--samples", s.moved_export}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("must be a result.json"), std::string::npos) << err;
  const std::vector<std::string> validate = {
      "--calibration", s.result, "--samples", s.moved_export,
      "--length-unit", "mm",     "--columns", "x=measurement_x,y=measurement_y,z=measurement_z"};
  test::expect_refusals(cli::validate_main, validate,
                        {{{"--fit-poses", "20"}, "--fit-poses N needs --fit"},
                         {{"--fit", "base", "--fit-poses", "120"}, "leaves none of the 120 poses to score"},
                         {{"--truth", s.result}, "give --truth (fresh random poses) or --samples"}});
}

}  // namespace
}  // namespace hivecal::registration_cli_test
