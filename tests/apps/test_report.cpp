// The HTML report must be well formed, self-contained, and show what it claims.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/kinematics.hpp"
#include "report/report.hpp"
#include "record/report_json.hpp"
#include "report/svg.hpp"

namespace hivecal::report_test {
namespace {

/// Checks tag balance of an HTML document with inline SVG; returns "" or the first problem.
std::string check_well_formed(const std::string& html) {
  const std::vector<std::string> void_elements = {"meta", "br", "img", "input", "link", "hr", "!DOCTYPE"};
  std::vector<std::string> open;
  std::size_t pos = 0;
  while ((pos = html.find('<', pos)) != std::string::npos) {
    const std::size_t end = html.find('>', pos);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(pos);
    std::string tag = html.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    const bool closing = !tag.empty() && tag[0] == '/';
    const bool self_closing = !tag.empty() && tag.back() == '/';
    std::string name = tag.substr(closing ? 1 : 0);
    name = name.substr(0, name.find_first_of(" \t\n/"));
    // Attribute quotes must balance.
    std::size_t quotes = 0;
    for (char c : tag) quotes += c == '\'' ? 1 : 0;
    if (quotes % 2 != 0) return "unbalanced quotes in <" + tag + ">";
    if (self_closing) continue;
    bool is_void = false;
    for (const std::string& v : void_elements) is_void = is_void || v == name;
    if (is_void) continue;
    if (!closing) {
      open.push_back(name);
    } else {
      if (open.empty() || open.back() != name)
        return "</" + name + "> closes <" + (open.empty() ? "" : open.back()) + ">";
      open.pop_back();
    }
  }
  return open.empty() ? "" : "unclosed <" + open.back() + ">";
}

report::ReportData example() {
  report::ReportData data;
  data.title = "Calibration <UR5> & tracker";
  data.input_lines = {"input: robot.cap, tracker.cap"};
  data.info_lines = {"samples kept: 38", "clock offset: 1.234 s"};
  report::MethodRow before;
  before.method = "uncalibrated";
  before.test.mae_m[3] = 75.4e-6;
  before.test.count = 4;
  report::MethodRow abc;
  abc.method = "ABC";
  abc.parameters = "paper-6";
  abc.test.mae_m[3] = 60.1e-6;
  abc.test.count = 4;
  abc.seconds = 0.05;
  data.methods = {before, abc};
  data.uncalibrated.test.count = 12;
  data.uncalibrated.test.mae_m[0] = 40e-6;
  data.calibrated.test.count = 12;
  data.calibrated.test.mae_m[0] = 30e-6;
  data.convergence = {{"ABC", false, {1e-4, 8e-5, 7e-5, 6.01e-5}},
                      {"GSA", false, {1e-4, 9e-5, 6.5e-5}},
                      {"LM", true, {7e-5, 6e-5, 5.9e-5}}};
  // The ABC model predicts every sample 60 um off in y, the uncalibrated one 70 um off in x.
  const RobotModel model = nominal_model(RobotType::ur5);
  for (int i = 0; i < 12; ++i) {
    report::SampleRow row;
    for (int j = 0; j < 6; ++j) row.q_rad[j] = 0.1 * i - 0.2 * j;
    JointVector q;
    for (int j = 0; j < 6; ++j) q(j) = row.q_rad[j];
    row.measured_m = fk_tool_point(model, q) - Vec3(0, 6e-5, 0);
    row.test = i % 3 == 0;
    data.samples.push_back(row);
  }
  RigidTransform shifted;
  shifted.translation_m = Vec3(7e-5, -6e-5, 0);
  data.predictions = {report::predict_samples("uncalibrated", model, shifted, data.samples),
                      report::predict_samples("ABC", model, RigidTransform{}, data.samples)};
  data.noise_sigma_m = 10e-6;
  data.identifiability.present = true;
  data.identifiability.free_count = 3;
  data.identifiability.estimated = {"a2", "d1"};
  data.identifiability.dropped = {{"d4", "not separable", 1e-9, "+0.707*d2 -0.707*d4"}};
  data.parameters = {{"d1", false, 0.089159, 0.0891602, 1.2e-6, "tool_z", -0.97}};
  return data;
}

TEST(Report, HtmlIsWellFormedAndSelfContained) {
  const std::string html = report::render_html(example());
  EXPECT_EQ(check_well_formed(html), "");
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("href="), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_NE(html.find("Calibration &lt;UR5&gt; &amp; tracker"), std::string::npos);
  std::size_t svgs = 0;
  for (std::size_t p = 0; (p = html.find("<svg", p)) != std::string::npos; ++p) ++svgs;
  // sorted errors (3D, x, y, z), vectors x-y and x-z, CDF, histogram, convergence (global,
  // LM), residual vs six joints; no stream figure for samples input.
  EXPECT_EQ(svgs, 4u + 2u + 2u + 2u + 6u);
  EXPECT_EQ(report::figure_ids(example()).size(), svgs);
  EXPECT_NE(html.find("not separable"), std::string::npos);
  EXPECT_NE(html.find("+0.707*d2 -0.707*d4"), std::string::npos);
  EXPECT_NE(html.find("correlation -0.970 with tool_z"), std::string::npos);
  EXPECT_NE(html.find("-20.3 %"), std::string::npos);  // 75.4 -> 60.1 um
}

// Every text of the page goes through the messages' filter (port::printable), not only the
// title: a file's name, a column's or a robot's with control bytes (a window title, a clear
// screen, a NUL) reaches the page escaped, and UTF-8 (µm, °) as written.
TEST(Report, NamesFromInputFilesReachThePageEscapedAndUtf8AsWritten) {
  report::ReportData data = example();
  data.input_lines = {"input: pa\x1b]0;evil\x07ired.csv (12 paired samples)"};
  data.info_lines.push_back("columns: x=x_t\x1b[2J[\xc2\xb5m], q1=joint_1[\xc2\xb0]");
  data.parameters[0].name = std::string("d1\0tail", 7);
  const std::string html = report::render_html(data);
  EXPECT_EQ(check_well_formed(html), "");
  for (const char c : html) ASSERT_TRUE(static_cast<unsigned char>(c) >= 0x20 || c == '\n') << int(c);
  EXPECT_NE(html.find("<li>input: pa\\x1b]0;evil\\x07ired.csv (12 paired samples)</li>"), std::string::npos);
  EXPECT_NE(html.find("<li>columns: x=x_t\\x1b[2J[\xc2\xb5m], q1=joint_1[\xc2\xb0]</li>"), std::string::npos);
  EXPECT_NE(html.find("<td>d1\\x00tail</td>"), std::string::npos);
}

// A prismatic joint's reading is a length: its residual figure's axis is in mm, a revolute
// joint's in degrees.
TEST(Report, APrismaticJointsFigureIsDrawnInMillimetres) {
  report::ReportData data = example();
  set_joint_type(&data.predictions.back().model, 0, JointType::prismatic);
  const std::string html = report::render_html(data);
  EXPECT_NE(html.find("q1 [mm]"), std::string::npos);
  EXPECT_EQ(html.find("q1 [deg]"), std::string::npos);
  EXPECT_NE(html.find("q2 [deg]"), std::string::npos);
  const std::string revolute = report::render_html(example());
  EXPECT_NE(revolute.find("q1 [deg]"), std::string::npos);
}

TEST(Report, WithoutTestSetNoTestColumnsAndTrainingFigures) {
  report::ReportData data = example();
  for (report::MethodRow& m : data.methods) m.test = ErrorStats{};
  data.uncalibrated.test = ErrorStats{};
  data.calibrated.test = ErrorStats{};
  for (report::SampleRow& s : data.samples) s.test = false;
  const std::string html = report::render_html(data);
  EXPECT_EQ(check_well_formed(html), "");
  EXPECT_EQ(html.find("test MAE"), std::string::npos);
  EXPECT_EQ(html.find("<td>test</td>"), std::string::npos);  // Table 2: training rows only
  EXPECT_NE(html.find("3D error per training sample"), std::string::npos);
  EXPECT_EQ(html.find("test sample"), std::string::npos);
}

TEST(Report, StageTimesOnlyWhenTimed) {
  report::ReportData data = example();
  EXPECT_NE(report::render_html(data).find("time [s]"), std::string::npos);
  for (report::MethodRow& m : data.methods) m.seconds = 0.0;
  const std::string html = report::render_html(data);
  EXPECT_EQ(html.find("time [s]"), std::string::npos);
  EXPECT_NE(html.find("not kept in result.json"), std::string::npos);
}

/// `data` as result.json holds it ("report"), parsed back into a JSON value.
textio::JsonValue written_report(const report::ReportData& data) {
  textio::JsonWriter json;
  record::write_report_data(json, data);
  textio::JsonValue value;
  EXPECT_TRUE(textio::parse_json(json.text(), &value).ok());
  return value;
}

/// `data` without what result.json never holds (stage times, the input lines): what reading
/// it back can give at best.
report::ReportData as_written(report::ReportData data) {
  for (report::MethodRow& m : data.methods) m.seconds = 0.0;
  data.input_lines.clear();
  return data;
}

TEST(Report, DataRoundTripsThroughResultJson) {
  report::ReportData data = example();
  data.has_stream = true;
  data.drops = {{"kept", 12}, {"beam_lost", 3}};
  data.timeline = {14.5, {"kept", "beam_lost"}, {{4, 0, 8}, {0, 3, 0}}};
  const std::vector<std::string> without = report::figure_ids(data);  // no clock profiles: no clock figure
  EXPECT_EQ(std::count(without.begin(), without.end(), "fig-clock-speeds"), 0);
  const std::vector<ClockMatchBin> bins = {{0.05, 0.1 + 0.2, 1.0 / 3.0, 1e-5 / 3.0, 3},
                                           {7.25, 0.0, 2e-4, 2e-4 - 1.0001 * 0.0, 5},
                                           {14.45, 0.12, 0.119, -7e-4, 2}};
  data.clock_match = report::clock_match_series(bins, 1.0001);
  data.identifiability.condition_before = std::numeric_limits<double>::infinity();  // stored as null
  textio::JsonValue value = written_report(data);
  report::ReportData back;
  const port::Error r = record::parse_report_data(value, "result.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_EQ(report::render_html(back), report::render_html(as_written(data)));
  // The clock-sync profiles come back bit for bit.
  EXPECT_EQ(back.clock_match.speed_gain, 1.0001);
  ASSERT_EQ(back.clock_match.t_s.size(), bins.size());
  for (std::size_t k = 0; k < bins.size(); ++k) {
    EXPECT_EQ(back.clock_match.t_s[k], bins[k].tracker_s);
    EXPECT_EQ(back.clock_match.robot_speed_m_s[k], bins[k].robot_speed_m_s);
    EXPECT_EQ(back.clock_match.tracker_speed_m_s[k], bins[k].tracker_speed_m_s);
    EXPECT_EQ(back.clock_match.residual_m_s[k], bins[k].residual_m_s);
  }
  const std::vector<std::string> ids = report::figure_ids(back);
  ASSERT_GE(ids.size(), 4u);
  EXPECT_EQ(ids[ids.size() - 4], "fig-clock-speeds");
  EXPECT_EQ(ids[ids.size() - 3], "fig-clock-residual");
  EXPECT_EQ(ids[ids.size() - 2], "fig-drop-timeline");
  EXPECT_EQ(ids.back(), "fig-drops");
  EXPECT_NE(report::render_html(back).find("robot tool x 1.0001"), std::string::npos);
  // A clock_match column of another length is refused.
  textio::JsonValue short_column = value;
  short_column.object["clock_match"].object["residual_m_s"].array.pop_back();
  const port::Error uneven = record::parse_report_data(short_column, "result.json", &back);
  EXPECT_FALSE(uneven.ok());
  EXPECT_NE(uneven.message.find("\"clock_match\""), std::string::npos) << uneven.message;
  EXPECT_NE(report::render_html(back).find("beam_lost (3)"), std::string::npos);
  // A damaged document is refused with the key at fault.
  value.object["samples"].array[0].object.erase("q_rad");
  const port::Error damaged = record::parse_report_data(value, "result.json", &back);
  EXPECT_FALSE(damaged.ok());
  EXPECT_NE(damaged.message.find("\"samples\""), std::string::npos) << damaged.message;
  // Points, joints and frames beyond the text inputs' bounds (100 m, two turns) are no session.
  textio::JsonValue far = written_report(data);
  far.object["samples"].array[0].object["measured_m"].array[0].number = 1e300;
  EXPECT_NE(record::parse_report_data(far, "result.json", &back).message.find("\"samples\""), std::string::npos);
  far = written_report(data);
  far.object["samples"].array[0].object["q_rad"].array[0].number = 100.0;
  EXPECT_NE(record::parse_report_data(far, "result.json", &back).message.find("\"samples\""), std::string::npos);
  far = written_report(data);
  far.object["predictions"].array[0].object["translation_m"].array[0].number = 1e300;
  EXPECT_NE(record::parse_report_data(far, "result.json", &back).message.find("\"predictions\""), std::string::npos);
}

/// The <svg> of figure `id` in `html` ("" if absent).
std::string figure_svg(const std::string& html, const std::string& id) {
  const std::size_t at = html.find("<svg xmlns='http://www.w3.org/2000/svg' id='" + id + "'");
  if (at == std::string::npos) return "";
  return html.substr(at, html.find("</svg>", at) - at);
}

/// example() with a blunder set aside (4.2 mm, w 31.5 against the threshold 4.56), an
/// uncontrolled pose, a 3-fold cross-validation and a parameter fixed by the significance test.
report::ReportData with_blunder_and_folds() {
  report::ReportData data = example();
  data.outliers.searched = true;
  data.outliers.verdict = "removed";
  data.outliers.critical_w = 4.56;
  data.outliers.alpha = 1e-3;
  data.outliers.sigma_source = "data";
  data.outliers.sigma_m = 0.05e-3;
  data.outliers.rows = {{"samples.csv:7", 4.2e-3, 31.5}};
  data.outliers.uncontrolled = {"samples.csv:3"};
  data.outliers.kept_w = {0.5, 1.25, 2.0};
  data.cross_validation.baseline_mae_3d_m = 512.0e-6;
  data.cross_validation.present = true;
  data.cross_validation.sample_count = 12;
  data.cross_validation.mae_3d_m = 61.3e-6;
  data.cross_validation.held_out_of = "lines of samples.csv";
  data.cross_validation.folds = {
      {8, 4, 50.5e-6, 58.0e-6, "2-4, 13"}, {8, 4, 49.0e-6, 71.5e-6, "5-8"}, {8, 4, 51.0e-6, 54.25e-6, "9-12"}};
  data.identifiability.fixed = {"alpha2"};
  data.identifiability.significance_t = 2.0;
  return data;
}

TEST(Report, BlundersAndCrossValidationAreShown) {
  const report::ReportData data = with_blunder_and_folds();
  const std::vector<std::string> ids = report::figure_ids(data);
  const auto q6 = std::find(ids.begin(), ids.end(), "fig-residual-q6");
  ASSERT_NE(q6, ids.end());
  ASSERT_GE(ids.end() - q6, 3);
  EXPECT_EQ(*(q6 + 1), "fig-outliers");
  EXPECT_EQ(*(q6 + 2), "fig-cv-folds");
  const std::string html = report::render_html(data);
  EXPECT_EQ(check_well_formed(html), "");
  // The outlier table and figure: the blunder by source, residual [mm], w and the threshold.
  EXPECT_NE(html.find("<td>samples.csv:7</td><td>4.200</td><td>31.50</td><td>4.56</td>"), std::string::npos);
  EXPECT_NE(html.find("threshold w = 4.56, sigma 0.050 mm (from the fit's residuals)"), std::string::npos)
      << html.substr(html.find("<h2>Blunders"), 600);
  EXPECT_NE(html.find("1 pose(s) uncontrolled"), std::string::npos);
  EXPECT_NE(html.find("samples.csv:3"), std::string::npos);
  const std::string outliers = figure_svg(html, "fig-outliers");
  ASSERT_NE(outliers, "");
  EXPECT_NE(outliers.find("data-series='set aside'"), std::string::npos);
  EXPECT_NE(outliers.find("data-series='kept'"), std::string::npos);
  EXPECT_NE(outliers.find("data-series='blunder threshold'"), std::string::npos);
  // The folds: a row per fold with the file lines it held out (as the console and result.json
  // say them), and the overall held-out MAE as the figure's line.
  EXPECT_NE(html.find("<th>held-out MAE [um]</th><th>held out (lines of samples.csv)</th>"), std::string::npos);
  EXPECT_NE(html.find("<td>2</td><td>8</td><td>4</td><td>49.0</td><td>71.5</td><td>5-8</td>"), std::string::npos);
  EXPECT_NE(html.find("3D MAE over every held-out sample 61.3 um (uncalibrated: 512.0 um)"), std::string::npos);
  const std::string folds = figure_svg(html, "fig-cv-folds");
  ASSERT_NE(folds, "");
  EXPECT_NE(folds.find("data-series='held-out MAE'"), std::string::npos);
  EXPECT_NE(folds.find("data-series='overall held-out'"), std::string::npos);
  // Table 3 lists the parameter the significance test fixed.
  EXPECT_NE(html.find("<td>alpha2</td><td>not significant (&lt; 2 sigma)</td>"), std::string::npos);
}

TEST(Report, BlunderSectionSaysWhatTheSearchDid) {
  report::ReportData data = with_blunder_and_folds();
  data.outliers.rows.clear();  // searched, none set aside: the figure without a "set aside" series
  std::string html = report::render_html(data);
  EXPECT_NE(html.find("None set aside."), std::string::npos);
  const std::string outliers = figure_svg(html, "fig-outliers");
  ASSERT_NE(outliers, "");
  EXPECT_EQ(outliers.find("set aside"), std::string::npos);
  data.outliers.searched = false;                          // --keep-outliers: no figure, a line
  data.cross_validation = report::CrossValidationTable{};  // no --cv: no figure, no table
  html = report::render_html(data);
  EXPECT_NE(html.find("No blunder search ran (--keep-outliers)"), std::string::npos);
  EXPECT_EQ(figure_svg(html, "fig-outliers"), "");
  EXPECT_EQ(figure_svg(html, "fig-cv-folds"), "");
  EXPECT_EQ(html.find("Cross-validation"), std::string::npos);
  const std::vector<std::string> ids = report::figure_ids(data);
  EXPECT_EQ(std::count(ids.begin(), ids.end(), "fig-outliers") + std::count(ids.begin(), ids.end(), "fig-cv-folds"), 0);
}

TEST(Report, BlundersAndFoldsRoundTripThroughResultJson) {
  const report::ReportData data = with_blunder_and_folds();
  textio::JsonValue value = written_report(data);
  report::ReportData back;
  const port::Error r = record::parse_report_data(value, "result.json", &back);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(back.outliers.searched);
  EXPECT_EQ(back.outliers.critical_w, 4.56);
  EXPECT_EQ(back.outliers.verdict, "removed");
  EXPECT_EQ(back.outliers.sigma_source, "data");
  EXPECT_FALSE(back.outliers.pooled_correlation);
  EXPECT_EQ(back.outliers.kept_w, data.outliers.kept_w);
  EXPECT_EQ(back.outliers.uncontrolled, data.outliers.uncontrolled);
  ASSERT_EQ(back.outliers.rows.size(), 1u);
  EXPECT_EQ(back.outliers.rows[0].source, "samples.csv:7");
  EXPECT_EQ(back.outliers.rows[0].residual_m, 4.2e-3);
  EXPECT_EQ(back.outliers.rows[0].w, 31.5);
  EXPECT_EQ(back.cross_validation.baseline_mae_3d_m, 512.0e-6);
  ASSERT_TRUE(back.cross_validation.present);
  EXPECT_EQ(back.cross_validation.sample_count, 12u);
  EXPECT_EQ(back.cross_validation.mae_3d_m, 61.3e-6);
  ASSERT_EQ(back.cross_validation.folds.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.cross_validation.folds[k].train_count, data.cross_validation.folds[k].train_count);
    EXPECT_EQ(back.cross_validation.folds[k].test_count, data.cross_validation.folds[k].test_count);
    EXPECT_EQ(back.cross_validation.folds[k].train_mae_m, data.cross_validation.folds[k].train_mae_m);
    EXPECT_EQ(back.cross_validation.folds[k].test_mae_m, data.cross_validation.folds[k].test_mae_m);
    EXPECT_EQ(back.cross_validation.folds[k].held_out, data.cross_validation.folds[k].held_out);
  }
  EXPECT_EQ(back.cross_validation.held_out_of, "lines of samples.csv");
  // A result written before the folds named their lines: read, the table without that column.
  textio::JsonValue older = value;
  older.object["cross_validation"].object.erase("held_out_of");
  for (textio::JsonValue& fold : older.object["cross_validation"].object["folds"].array) fold.object.erase("held_out");
  report::ReportData older_back;
  ASSERT_TRUE(record::parse_report_data(older, "result.json", &older_back).ok());
  EXPECT_EQ(older_back.cross_validation.folds.size(), 3u);
  EXPECT_EQ(report::render_html(older_back).find("held out ("), std::string::npos);
  EXPECT_EQ(back.identifiability.fixed, std::vector<std::string>{"alpha2"});
  EXPECT_EQ(back.identifiability.significance_t, 2.0);
  EXPECT_EQ(report::render_html(back), report::render_html(as_written(data)));
  // Without --cv and without a search, the keys say so and come back absent.
  report::ReportData plain = example();
  textio::JsonWriter plain_json;
  record::write_report_data(plain_json, plain);
  EXPECT_EQ(plain_json.text().find("\"cross_validation\""), std::string::npos);
  textio::JsonValue plain_value;
  ASSERT_TRUE(textio::parse_json(plain_json.text(), &plain_value).ok());
  ASSERT_TRUE(record::parse_report_data(plain_value, "result.json", &back).ok());
  EXPECT_FALSE(back.outliers.searched);
  EXPECT_FALSE(back.cross_validation.present);
  // A damaged fold is refused with the key at fault.
  value.object["cross_validation"].object["folds"].array[1].object.erase("test_mae_3d_m");
  const port::Error damaged = record::parse_report_data(value, "result.json", &back);
  EXPECT_FALSE(damaged.ok());
  EXPECT_NE(damaged.message.find("\"cross_validation\""), std::string::npos) << damaged.message;
}

TEST(Report, ErrorVectorsCarryTheirScale) {
  const report::ReportData data = example();
  // Largest error 70 um; the extent of the test samples is their largest per-axis range.
  Vec3 lo = Vec3::Constant(1e9);
  Vec3 hi = -lo;
  for (const report::SampleRow& s : data.samples) {
    if (!s.test) continue;
    lo = lo.cwiseMin(s.measured_m * 1e3);
    hi = hi.cwiseMax(s.measured_m * 1e3);
  }
  const double extent_mm = (hi - lo).maxCoeff();
  const std::string html = report::render_html(data);
  const std::size_t at = html.find("1 mm arrow = ");
  ASSERT_NE(at, std::string::npos);
  const double um_per_mm = std::stod(html.substr(at + 13));  // a round number of um
  EXPECT_DOUBLE_EQ(report::nice_step(um_per_mm), um_per_mm);
  EXPECT_GE(70.0 / um_per_mm, extent_mm / 6.0) << extent_mm;  // the longest arrow is visible
  EXPECT_LE(70.0 / um_per_mm, extent_mm / 3.0) << extent_mm;
}

TEST(Report, PredictionsAreTheModelsOwn) {
  const report::ReportData data = example();
  ASSERT_EQ(data.predictions[0].points_m.size(), data.samples.size());
  for (std::size_t i = 0; i < data.samples.size(); ++i) {
    EXPECT_NEAR((data.predictions[0].points_m[i] - data.samples[i].measured_m - Vec3(7e-5, 0, 0)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((data.predictions[1].points_m[i] - data.samples[i].measured_m - Vec3(0, 6e-5, 0)).norm(), 0.0, 1e-12);
  }
}

TEST(Report, CheckerCatchesBrokenMarkup) {
  EXPECT_NE(check_well_formed("<div><span></div>"), "");
  EXPECT_NE(check_well_formed("<div a='1>x</div>"), "");
  EXPECT_NE(check_well_formed("<svg>"), "");
}

TEST(Report, TextTablesShowBothTables) {
  const std::string text = report::format_tables_text(example());
  EXPECT_NE(text.find("Table 1"), std::string::npos);
  EXPECT_NE(text.find("Table 2"), std::string::npos);
  EXPECT_NE(text.find("75.4"), std::string::npos);
  EXPECT_NE(text.find("60.1"), std::string::npos);
}

// A row without a sigma says why: after LM, a parameter that was not estimated either kept its
// start or kept what a stage before LM made of it (the tool point fitted with the start geometry,
// ABC's lengths); after a method without sigmas (ABC, GSA) every row is an estimate.
TEST(Report, ParameterNotesSayWhereAValueWithoutSigmaComesFrom) {
  report::ReportData data = example();
  data.parameters = {{"a4", false, 0.0, 0.0, 0.0, "", 0.0},
                     {"tool_z", false, 0.109, 0.0931202, 0.0, "", 0.0},
                     {"a2", false, -0.425, -0.4251, 1e-6, "", 0.0}};
  const auto line_of = [](const std::vector<std::string>& lines, const std::string& name) {
    for (const std::string& line : lines) {
      const std::size_t first = line.find_first_not_of(' ');
      if (first != std::string::npos && line.compare(first, name.size() + 1, name + " ") == 0) return line;
    }
    return std::string("(no line for " + name + ")");
  };
  const std::vector<std::string> after_lm = report::format_parameters_text(data);
  EXPECT_NE(line_of(after_lm, "a4").find("not estimated"), std::string::npos);
  EXPECT_EQ(line_of(after_lm, "a4").find("before LM"), std::string::npos);
  EXPECT_NE(line_of(after_lm, "tool_z").find("not estimated by LM: kept at the value fitted before it"),
            std::string::npos);
  EXPECT_EQ(line_of(after_lm, "a2").find("estimated"), std::string::npos);
  data.identifiability = report::IdentifiabilityTable{};  // the parameters of an ABC or GSA result
  const std::vector<std::string> after_abc = report::format_parameters_text(data);
  for (const char* name : {"a4", "tool_z"}) {
    EXPECT_NE(line_of(after_abc, name).find("no sigma (not an LM fit)"), std::string::npos) << name;
    EXPECT_EQ(line_of(after_abc, name).find("not estimated"), std::string::npos) << name;
  }
}

TEST(Report, EmptyAndDegenerateSeriesStillRender) {
  report::ReportData data;
  data.title = "empty";
  data.convergence = {{"flat", false, {1e-5, 1e-5}}, {"none", true, {}}};
  EXPECT_EQ(check_well_formed(report::render_html(data)), "");
  EXPECT_EQ(check_well_formed(report::svg_histogram(report::ChartSpec{"h", "x", "y"}, {"a"}, {{}}, 10)), "");
}

TEST(Report, PooledReadingsCorrelationIsSaidAndRoundTrips) {
  // Several readings per pose tested with their pooled correlation: the key is written only
  // then (other results keep their bytes), read back, and the page says it.
  report::ReportData data = with_blunder_and_folds();
  const std::string before = report::render_html(data);
  EXPECT_EQ(before.find("share their error"), std::string::npos);
  textio::JsonWriter plain;
  record::write_report_data(plain, data);
  EXPECT_EQ(plain.text().find("pooled_correlation"), std::string::npos);
  data.outliers.pooled_correlation = true;
  EXPECT_NE(report::render_html(data).find("The readings of a pose share their error"), std::string::npos);
  textio::JsonValue value = written_report(data);
  report::ReportData back;
  ASSERT_TRUE(record::parse_report_data(value, "result.json", &back).ok());
  EXPECT_TRUE(back.outliers.pooled_correlation);
  value.object["outliers"].object["pooled_correlation"] = value.object["outliers"].object["alpha"];  // not a bool
  EXPECT_FALSE(record::parse_report_data(value, "result.json", &back).ok());
}

/// A run of `count` samples (70 % training, training first, as calibrate orders them) with
/// the uncalibrated and a calibrated prediction, a tracker noise and every pose's w.
report::ReportData large_run(std::size_t count) {
  report::ReportData data = with_blunder_and_folds();
  data.samples.clear();
  data.outliers.kept_w.clear();
  const RobotModel model = nominal_model(RobotType::ur5);
  Random random(12000);
  for (std::size_t i = 0; i < count; ++i) {
    report::SampleRow row;
    JointVector q;
    for (int j = 0; j < 6; ++j) q(j) = row.q_rad[j] = random.uniform(-2.5, 2.5);
    row.measured_m = fk_tool_point(model, q) + Vec3(random.normal(), random.normal(), random.normal()) * 1e-5;
    row.test = i >= count * 7 / 10;
    data.samples.push_back(row);
    data.outliers.kept_w.push_back(std::fabs(random.normal()));
  }
  RigidTransform shifted;
  shifted.translation_m = Vec3(7e-5, -6e-5, 0);
  data.predictions = {report::predict_samples("uncalibrated", model, shifted, data.samples),
                      report::predict_samples("ABC+LM", model, RigidTransform{}, data.samples)};
  data.calibrated.train.count = count * 7 / 10;
  data.calibrated.test.count = count - count * 7 / 10;
  data.noise_sigma_m = 10e-6;
  return data;
}

/// Elements of `svg` that carry a series (the markers, lines and arrows drawn).
std::size_t drawn_elements(const std::string& svg) {
  std::size_t n = 0;
  for (const char* tag : {"<circle data-series=", "<line data-series=", "<polyline data-series="}) {
    for (std::size_t at = svg.find(tag); at != std::string::npos; at = svg.find(tag, at + 1)) ++n;
  }
  return n;
}

// A run of 12,000 samples drew every one of them (12,000 markers per joint panel, solid
// blocks; 10.4 MB that took 11 s to open): each figure draws an evenly spaced subset within its
// cap, and its caption says how many.
TEST(Report, LargeRunsDrawAtMostTheFiguresCaps) {
  const report::ReportData data = large_run(5000);
  const std::string html = report::render_html(data);
  EXPECT_EQ(check_well_formed(html), "");
  for (int j = 1; j <= 6; ++j) {
    const std::string svg = figure_svg(html, "fig-residual-q" + std::to_string(j));
    ASSERT_FALSE(svg.empty()) << j;
    EXPECT_EQ(drawn_elements(svg), 1000u) << j;
  }
  EXPECT_NE(html.find("1,000 of 5,000 samples drawn, evenly spaced."), std::string::npos);
  EXPECT_EQ(drawn_elements(figure_svg(html, "fig-vectors-xy")), 2 * 400u);
  EXPECT_NE(html.find("400 of 1,500 samples&#39; arrows drawn, evenly spaced."), std::string::npos);
  // The kept poses' w at 1,000 ranks and the set-aside one; the curves through 1,000 ranks.
  EXPECT_EQ(drawn_elements(figure_svg(html, "fig-outliers")), 1000u + 1u + 1u);  // + the threshold line
  const std::string error_3d = figure_svg(html, "fig-error-3d");
  const std::size_t polyline = error_3d.find("<polyline");
  ASSERT_NE(polyline, std::string::npos);
  const std::string points = error_3d.substr(polyline, error_3d.find("/>", polyline) - polyline);
  EXPECT_EQ(std::count(points.begin(), points.end(), ','), 1000);
  EXPECT_LT(html.size(), 1200000u);
}

// The report keeps at most kReportSampleCap samples and kept w, evenly spaced, so that the
// result of any run stays readable by every command (10^6 samples wrote a 271 MiB result that
// predict, export and report refused); the page redrawn from it is the same.
TEST(Report, LargeRunsKeepAnEvenlySpacedSubset) {
  report::ReportData data = large_run(20000);
  const std::vector<report::SampleRow> all = data.samples;
  const std::vector<double> all_w = data.outliers.kept_w;
  report::keep_at_most(report::kReportSampleCap, &data);
  ASSERT_EQ(data.samples.size(), report::kReportSampleCap);
  EXPECT_EQ(data.sample_total, 20000u);
  const auto test_count = std::count_if(data.samples.begin(), data.samples.end(), [](const auto& s) { return s.test; });
  EXPECT_EQ(test_count, 1500);  // the test samples' share, 30 %
  // Every kept sample is one of the run's, in order, with its own predictions.
  std::size_t from = 0;
  for (std::size_t i = 0; i < data.samples.size(); ++i) {
    while (from < all.size() && all[from].measured_m != data.samples[i].measured_m) ++from;
    ASSERT_LT(from, all.size()) << i;
  }
  for (const report::PredictionSet& set : data.predictions) {
    const report::PredictionSet again =
        report::predict_samples(set.method, set.model, set.base_to_tracker, data.samples);
    EXPECT_EQ(set.points_m, again.points_m) << set.method;
  }
  // The w at spanning ranks: the smallest and the largest among them.
  ASSERT_EQ(data.outliers.kept_w.size(), report::kReportSampleCap);
  EXPECT_EQ(data.outliers.kept_total, 20000u);
  EXPECT_EQ(data.outliers.kept_w.front(), *std::min_element(all_w.begin(), all_w.end()));
  EXPECT_EQ(data.outliers.kept_w.back(), *std::max_element(all_w.begin(), all_w.end()));
  // Its JSON is a quarter of the run's, and reads back to the same page.
  textio::JsonWriter json;
  record::write_report_data(json, data);
  EXPECT_LT(json.text().size(), 1700000u);
  report::ReportData back;
  ASSERT_TRUE(record::parse_report_data(written_report(data), "result.json", &back).ok());
  EXPECT_EQ(back.sample_total, 20000u);
  EXPECT_EQ(back.outliers.kept_total, 20000u);
  EXPECT_EQ(report::render_html(back), report::render_html(as_written(data)));
  EXPECT_NE(report::render_html(back).find("The report keeps 5,000 of the run's 20,000 samples"), std::string::npos);
  // A run within the cap is kept whole, and its JSON has no totals (earlier results keep their bytes).
  report::ReportData small = large_run(300);
  report::keep_at_most(report::kReportSampleCap, &small);
  EXPECT_EQ(small.samples.size(), 300u);
  EXPECT_EQ(small.sample_total, 0u);
  textio::JsonWriter small_json;
  record::write_report_data(small_json, small);
  EXPECT_EQ(small_json.text().find("sample_total"), std::string::npos);
  EXPECT_EQ(small_json.text().find("kept_total"), std::string::npos);
  // A total below the samples held is refused.
  textio::JsonValue value = written_report(data);
  value.object["sample_total"].number = 10.0;
  EXPECT_FALSE(record::parse_report_data(value, "result.json", &back).ok());
}

}  // namespace
}  // namespace hivecal::report_test

namespace hivecal::report::report_test {
namespace {

/// The text of every element of `svg` with class `cls`.
std::vector<std::string> texts_of_class(const std::string& svg, const std::string& cls) {
  std::vector<std::string> out;
  const std::string key = "class='" + cls + "'";
  for (std::size_t at = svg.find(key); at != std::string::npos; at = svg.find(key, at + 1)) {
    const std::size_t open = svg.find('>', at);
    const std::size_t close = svg.find('<', open);
    out.push_back(svg.substr(open + 1, close - open - 1));
  }
  return out;
}

TEST(Svg, SignificantDigitsOfLabels) {
  EXPECT_EQ(significant_digits("231.25"), 5);
  EXPECT_EQ(significant_digits("1250"), 3);
  EXPECT_EQ(significant_digits("0.025"), 2);
  EXPECT_EQ(significant_digits("-40"), 1);
  EXPECT_EQ(significant_digits("0"), 1);
  EXPECT_EQ(significant_digits("2.50"), 3);
}

TEST(Svg, TicksAreRoundNumbersWithAtMostThreeSignificantDigits) {
  const std::vector<std::pair<double, double>> ranges = {{-10.96, 231.2},  {-9.32, 269.3},     {0.0, 1.0},
                                                         {3.1e-6, 7.7e-6}, {12345.0, 12399.0}, {-0.004, 0.0031},
                                                         {42.0, 42.0}};
  for (const auto& [lo, hi] : ranges) {
    Series s{"data", {lo, hi}, {hi, lo}, false};
    const std::string svg = svg_chart(ChartSpec{"t", "x", "y"}, {s});
    const std::vector<std::string> ticks = texts_of_class(svg, "tick");
    ASSERT_GE(ticks.size(), 6u) << lo << " " << hi;
    for (const std::string& t : ticks) {
      if (t.find('e') != std::string::npos) continue;  // %.3g form: three digits by construction
      EXPECT_LE(significant_digits(t), 3) << "'" << t << "' for range " << lo << " .. " << hi;
    }
  }
}

TEST(Svg, LegendListsOnlySeriesThatDrewSomething) {
  Series drawn{"calibrated", {0, 1, 2}, {1, 2, 3}, false};
  Series empty{"measured", {}, {}, false};
  Series all_nan{"nan", {0.0}, {std::nan("")}, true};
  const std::string svg = svg_chart(ChartSpec{"t", "x", "y"}, {empty, drawn, all_nan});
  const std::vector<std::string> legend = texts_of_class(svg, "legend");
  ASSERT_EQ(legend.size(), 1u);
  EXPECT_EQ(legend[0], "calibrated");
}

// "measurement noise (stated)" ran past the panel's right edge in the four error figures: a
// long legend label wraps at a space, and the legend column is as wide as its widest line.
TEST(Svg, LegendFitsInsideThePanel) {
  ChartSpec spec{"t", "x", "y"};
  spec.y_line = 1.0;
  spec.y_line_label = "measurement noise (stated, with the joints' reading)";
  const std::string svg = svg_chart(spec, {Series{"uncalibrated", {0, 1}, {1, 2}, false}});
  const std::size_t at = svg.find("class='legend' data-series='measurement noise");
  ASSERT_NE(at, std::string::npos);
  const std::size_t x_at = svg.find("x='", at) + 3;
  const double x_px = std::stod(svg.substr(x_at));
  const std::string text = svg.substr(svg.find('>', at) + 1, svg.find("</text>", at) - svg.find('>', at) - 1);
  std::size_t widest = 0;  // characters of the longest line
  for (std::size_t begin = 0, end = 0; begin < text.size(); begin = end + 1) {
    const std::size_t open = text.find('>', begin);
    if (text.compare(begin, 6, "<tspan") != 0 || open == std::string::npos) break;
    end = text.find("</tspan>", open);
    std::string line = text.substr(open + 1, end - open - 1);
    for (std::size_t quote = line.find("&#39;"); quote != std::string::npos; quote = line.find("&#39;"))
      line.replace(quote, 5, "'");
    widest = std::max(widest, line.size());
    end += 7;
  }
  EXPECT_GE(std::count(text.begin(), text.end(), '<'), 4) << text;  // two lines or more
  EXPECT_LE(x_px + 7.0 * static_cast<double>(widest), spec.width_px) << text;
}

TEST(Svg, HistogramAxesStartAtZero) {
  const std::string svg =
      svg_histogram(ChartSpec{"t", "error [um]", "count"}, {"a", "b"}, {{1.5, 2.5, 9.0}, {3.0, 4.0}}, 10);
  const std::vector<std::string> ticks = texts_of_class(svg, "tick");
  ASSERT_FALSE(ticks.empty());
  EXPECT_EQ(ticks.front(), "0");
  for (const std::string& t : ticks) EXPECT_GE(std::stod(t), 0.0) << t;
}

}  // namespace
}  // namespace hivecal::report::report_test
