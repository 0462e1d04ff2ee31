#include "report/report.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "report/svg.hpp"
#include "textio/text_util.hpp"

namespace hivecal::report {
namespace {

constexpr const char* kAxisLabels[kErrorAxisCount] = {"X", "Y", "Z", "3D"};

std::string um(double metres) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", metres * 1e6);
  return buf;
}

std::string pad(std::string s, std::size_t width) {
  if (s.size() < width) s.insert(0, width - s.size(), ' ');
  return s;
}

std::string pad_right(std::string s, std::size_t width) {
  if (s.size() < width) s.append(width - s.size(), ' ');
  return s;
}

std::string improvement(double before, double after) {
  if (!(before > 0.0)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1f %%", (after - before) / before * 100.0);
  return buf;
}

std::vector<double> index_axis(std::size_t n) {
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<double>(i + 1);
  return x;
}

std::vector<double> component(const std::vector<Vec3>& points, int axis, double scale) {
  std::vector<double> v;
  for (const Vec3& p : points) v.push_back(p(axis) * scale);
  return v;
}

std::vector<double> error_norms_um(const std::vector<Vec3>& predicted, const std::vector<Vec3>& measured) {
  std::vector<double> v;
  for (std::size_t i = 0; i < predicted.size() && i < measured.size(); ++i) v.push_back((predicted[i] - measured[i]).norm() * 1e6);
  return v;
}

std::string html_table(const std::vector<std::vector<std::string>>& rows) {
  std::string s = "<table>\n";
  for (std::size_t r = 0; r < rows.size(); ++r) {
    s += "<tr>";
    for (const std::string& cell : rows[r]) s += (r == 0 ? "<th>" : "<td>") + xml_escape(cell) + (r == 0 ? "</th>" : "</td>");
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

std::vector<std::vector<std::string>> table1_rows(const ReportData& data) {
  std::vector<std::vector<std::string>> rows = {
      {"method", "parameters", "train MAE [um]", "train sigma [um]", "test MAE [um]", "test sigma [um]",
       "test vs uncalibrated", "time [s]"}};
  const double before = data.methods.empty() ? 0.0 : data.methods.front().test.mae(ErrorAxis::norm_3d);
  for (const MethodRow& m : data.methods) {
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.3f", m.seconds);
    const bool tested = m.test.count > 0;  // --split 1: no test samples, no test cells
    rows.push_back({m.method, m.parameters, um(m.train.mae(ErrorAxis::norm_3d)), um(m.train.sigma(ErrorAxis::norm_3d)),
                    tested ? um(m.test.mae(ErrorAxis::norm_3d)) : "-", tested ? um(m.test.sigma(ErrorAxis::norm_3d)) : "-",
                    &m == &data.methods.front() || !tested ? "" : improvement(before, m.test.mae(ErrorAxis::norm_3d)),
                    m.seconds > 0.0 ? seconds : ""});
  }
  return rows;
}

std::vector<std::vector<std::string>> table2_rows(const ReportData& data) {
  std::vector<std::vector<std::string>> rows = {{"set", "axis", "MAE before [um]", "sigma before [um]", "MAE after [um]",
                                                 "sigma after [um]", "change"}};
  const std::pair<const char*, const ErrorStats AccuracyReport::*> sets[] = {
      {"train", &AccuracyReport::train}, {"test", &AccuracyReport::test}, {"overall", &AccuracyReport::overall}};
  for (const auto& [name, member] : sets) {
    const ErrorStats& before = data.uncalibrated.*member;
    const ErrorStats& after = data.calibrated.*member;
    if (before.count == 0 && after.count == 0) continue;  // no test samples (--split 1)
    for (int axis = 0; axis < kErrorAxisCount; ++axis) {
      rows.push_back({name, kAxisLabels[axis], um(before.mae_m[axis]), um(before.sigma_m[axis]), um(after.mae_m[axis]),
                      um(after.sigma_m[axis]), improvement(before.mae_m[axis], after.mae_m[axis])});
    }
  }
  return rows;
}

std::string text_table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> widths;
  for (const auto& row : rows)
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (widths.size() <= c) widths.push_back(0);
      widths[c] = std::max(widths[c], row[c].size());
    }
  std::string s;
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) s += (c == 0 ? pad_right(row[c], widths[c]) : "  " + pad(row[c], widths[c]));
    s += "\n";
  }
  return s;
}

std::string figures(const ReportData& data) {
  std::string s;
  if (!data.convergence.empty()) {
    std::vector<Series> series;
    for (const ConvergenceSeries& c : data.convergence) {
      std::vector<double> y;
      for (double v : c.best_cost_m) y.push_back(v * 1e6);
      series.push_back(Series{c.method, index_axis(y.size()), y, false});
    }
    s += "<h2>Convergence (Figs 4-5)</h2>\n" +
         svg_chart(ChartSpec{"Best cost per iteration", "iteration", "cost [um]", true}, series);
  }
  const std::size_t n = data.test_measured_m.size();
  if (n > 0) {
    // Positions differ by tens of micrometres on a metre scale: plot them relative to the
    // measurement so that the three sets can be told apart.
    s += "<h2>Test samples per axis: measured vs uncalibrated vs calibrated (Fig 6)</h2>\n";
    const char* names[] = {"x", "y", "z"};
    for (int axis = 0; axis < 3; ++axis) {
      const std::vector<double> measured = component(data.test_measured_m, axis, 1e6);
      std::vector<double> uncalibrated = component(data.test_uncalibrated_m, axis, 1e6);
      std::vector<double> calibrated = component(data.test_calibrated_m, axis, 1e6);
      for (std::size_t i = 0; i < n; ++i) {
        uncalibrated[i] -= measured[i];
        calibrated[i] -= measured[i];
      }
      s += svg_chart(ChartSpec{std::string("Test samples: ") + names[axis] + " relative to the measurement", "sample",
                               std::string("predicted - measured ") + names[axis] + " [um]"},
                     {Series{"measured", index_axis(n), std::vector<double>(n, 0.0), false},
                      Series{"uncalibrated", index_axis(n), uncalibrated, true},
                      Series{"calibrated", index_axis(n), calibrated, true}});
    }
    s += "<h2>Validation in the x-y and x-z planes (Fig 7)</h2>\n";
    for (int axis : {1, 2}) {
      s += svg_chart(ChartSpec{std::string("x-") + names[axis] + " plane", "x [mm]", std::string(names[axis]) + " [mm]"},
                     {Series{"measured", component(data.test_measured_m, 0, 1e3), component(data.test_measured_m, axis, 1e3), true},
                      Series{"calibrated", component(data.test_calibrated_m, 0, 1e3),
                             component(data.test_calibrated_m, axis, 1e3), true}});
    }
    s += "<h2>Error distribution on the test samples (Fig 8)</h2>\n" +
         svg_histogram(ChartSpec{"3D error histogram", "error [um]", "samples"}, {"uncalibrated", "calibrated"},
                       {error_norms_um(data.test_uncalibrated_m, data.test_measured_m),
                        error_norms_um(data.test_calibrated_m, data.test_measured_m)},
                       20);
  }
  return s;
}

}  // namespace

std::string format_tables_text(const ReportData& data) {
  return "Table 1: accuracy per method (3D)\n" + text_table(table1_rows(data)) +
         "\nTable 2: accuracy per axis, uncalibrated vs calibrated\n" + text_table(table2_rows(data));
}

std::string render_html(const ReportData& data) {
  std::string s =
      "<!DOCTYPE html>\n<html lang='en'>\n<head>\n<meta charset='utf-8'>\n<title>" + xml_escape(data.title) +
      "</title>\n<style>body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em}"
      "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
      "th{background:#eee}svg{margin:4px;border:1px solid #eee}pre{background:#f6f6f6;padding:8px}</style>\n"
      "</head>\n<body>\n<h1>" +
      xml_escape(data.title) + "</h1>\n<ul>\n";
  for (const std::string& line : data.info_lines) s += "<li>" + xml_escape(line) + "</li>\n";
  s += "</ul>\n<h2>Table 1: accuracy per method</h2>\n" + html_table(table1_rows(data)) +
       "<h2>Table 2: accuracy per axis</h2>\n" + html_table(table2_rows(data)) + figures(data);
  if (!data.parameter_lines.empty()) {
    s += "<h2>Calibrated parameters</h2>\n<pre>";
    for (const std::string& line : data.parameter_lines) s += xml_escape(line) + "\n";
    s += "</pre>\n";
  }
  return s + "</body>\n</html>\n";
}


}  // namespace hivecal::report
