// The HTML report must be well formed, self-contained, and show what it claims.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "report/report.hpp"
#include "report/svg.hpp"

namespace hivecal {
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
      if (open.empty() || open.back() != name) return "</" + name + "> closes <" + (open.empty() ? "" : open.back()) + ">";
      open.pop_back();
    }
  }
  return open.empty() ? "" : "unclosed <" + open.back() + ">";
}

report::ReportData example() {
  report::ReportData data;
  data.title = "Calibration <UR5> & tracker";
  data.info_lines = {"samples kept: 38", "clock offset: 1.234 s"};
  report::MethodRow before;
  before.method = "uncalibrated";
  before.test.count = 12;  // a table without test samples (--split 1) shows no test cells
  before.test.mae_m[3] = 75.4e-6;
  report::MethodRow abc;
  abc.method = "ABC";
  abc.parameters = "paper-6";
  abc.test.count = 12;
  abc.test.mae_m[3] = 60.1e-6;
  abc.seconds = 0.05;
  data.methods = {before, abc};
  data.uncalibrated.test.count = 12;
  data.uncalibrated.test.mae_m[0] = 40e-6;
  data.calibrated.test.count = 12;
  data.calibrated.test.mae_m[0] = 30e-6;
  data.convergence = {{"ABC", {1e-4, 8e-5, 7e-5, 6.01e-5}}, {"GSA", {1e-4, 9e-5, 6.5e-5}}};
  for (int i = 0; i < 12; ++i) {
    const Vec3 p(0.5 + 0.01 * i, -0.2 + 0.02 * i, 0.3);
    data.test_measured_m.push_back(p);
    data.test_uncalibrated_m.push_back(p + Vec3(7e-5, 0, 0));
    data.test_calibrated_m.push_back(p + Vec3(0, 6e-5, 0));
  }
  data.parameter_lines = {"d1 = 0.089159 m +- 1.2e-6"};
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
  EXPECT_EQ(svgs, 1u + 3u + 2u + 1u);  // convergence, 3 axes, x-y and x-z, histogram
  EXPECT_NE(html.find("-20.3 %"), std::string::npos);  // 75.4 -> 60.1 um
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

TEST(Report, EmptyAndDegenerateSeriesStillRender) {
  report::ReportData data;
  data.title = "empty";
  data.convergence = {{"flat", {1e-5, 1e-5}}, {"none", {}}};
  EXPECT_EQ(check_well_formed(report::render_html(data)), "");
  EXPECT_EQ(check_well_formed(report::svg_histogram(report::ChartSpec{"h", "x", "y"}, {"a"}, {{}}, 10)), "");
}

}  // namespace
}  // namespace hivecal

namespace hivecal::report {
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
  const std::vector<std::pair<double, double>> ranges = {
      {-10.96, 231.2}, {-9.32, 269.3}, {0.0, 1.0}, {3.1e-6, 7.7e-6}, {12345.0, 12399.0}, {-0.004, 0.0031}, {42.0, 42.0}};
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

TEST(Svg, HistogramAxesStartAtZero) {
  const std::string svg = svg_histogram(ChartSpec{"t", "error [um]", "count"}, {"a", "b"}, {{1.5, 2.5, 9.0}, {3.0, 4.0}}, 10);
  const std::vector<std::string> ticks = texts_of_class(svg, "tick");
  ASSERT_FALSE(ticks.empty());
  EXPECT_EQ(ticks.front(), "0");
  for (const std::string& t : ticks) EXPECT_GE(std::stod(t), 0.0) << t;
}

}  // namespace
}  // namespace hivecal::report
