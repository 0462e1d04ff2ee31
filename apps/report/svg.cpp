#include "report/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hivecal::report {
namespace {

const char* const kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"};

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

/// Linear or log mapping of data values onto a pixel range.
struct Axis {
  double lo = 0.0;
  double hi = 1.0;
  bool log = false;
  double px_lo = 0.0;
  double px_hi = 1.0;

  double value(double v) const { return log ? std::log10(v) : v; }
  double to_px(double v) const { return px_lo + (value(v) - lo) / (hi - lo) * (px_hi - px_lo); }
};

Axis make_axis(const std::vector<const std::vector<double>*>& data, bool log, double px_lo, double px_hi) {
  Axis axis;
  axis.log = log;
  axis.px_lo = px_lo;
  axis.px_hi = px_hi;
  bool any = false;
  for (const auto* values : data) {
    for (double v : *values) {
      if (!std::isfinite(v) || (log && v <= 0.0)) continue;
      const double m = log ? std::log10(v) : v;
      axis.lo = any ? std::min(axis.lo, m) : m;
      axis.hi = any ? std::max(axis.hi, m) : m;
      any = true;
    }
  }
  if (!any) {
    axis.lo = 0.0;
    axis.hi = 1.0;
  }
  if (axis.hi - axis.lo < 1e-300) {
    axis.lo -= 0.5;
    axis.hi += 0.5;
  }
  const double pad = 0.04 * (axis.hi - axis.lo);
  axis.lo -= pad;
  axis.hi += pad;
  return axis;
}

std::string tick_label(const Axis& axis, double m) {
  const double v = axis.log ? std::pow(10.0, m) : m;
  return fmt(std::fabs(v) >= 1e4 || (std::fabs(v) < 1e-2 && v != 0.0) ? "%.3g" : "%.4g", v);
}

std::string frame(const ChartSpec& spec, const Axis& x, const Axis& y) {
  std::string s;
  const double left = x.px_lo;
  const double right = x.px_hi;
  const double top = y.px_hi;
  const double bottom = y.px_lo;
  s += "<rect x='" + fmt("%.1f", left) + "' y='" + fmt("%.1f", top) + "' width='" + fmt("%.1f", right - left) +
       "' height='" + fmt("%.1f", bottom - top) + "' fill='none' stroke='#444'/>\n";
  for (int i = 0; i <= 4; ++i) {
    const double mx = x.lo + (x.hi - x.lo) * i / 4.0;
    const double px = left + (right - left) * i / 4.0;
    s += "<text x='" + fmt("%.1f", px) + "' y='" + fmt("%.1f", bottom + 14) + "' text-anchor='middle'>" +
         tick_label(x, mx) + "</text>\n";
    const double my = y.lo + (y.hi - y.lo) * i / 4.0;
    const double py = bottom + (top - bottom) * i / 4.0;
    s += "<line x1='" + fmt("%.1f", left) + "' x2='" + fmt("%.1f", right) + "' y1='" + fmt("%.1f", py) + "' y2='" +
         fmt("%.1f", py) + "' stroke='#ddd'/>\n";
    s += "<text x='" + fmt("%.1f", left - 4) + "' y='" + fmt("%.1f", py + 4) + "' text-anchor='end'>" +
         tick_label(y, my) + "</text>\n";
  }
  s += "<text x='" + fmt("%.1f", (left + right) / 2) + "' y='16' text-anchor='middle' font-weight='bold'>" +
       xml_escape(spec.title) + "</text>\n";
  s += "<text x='" + fmt("%.1f", (left + right) / 2) + "' y='" + fmt("%.1f", bottom + 30) +
       "' text-anchor='middle'>" + xml_escape(spec.x_label) + "</text>\n";
  s += "<text transform='translate(14," + fmt("%.1f", (top + bottom) / 2) + ") rotate(-90)' text-anchor='middle'>" +
       xml_escape(spec.y_label) + "</text>\n";
  return s;
}

std::string legend(const std::vector<std::string>& names, double x, double y) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const double row = y + 14.0 * static_cast<double>(i);
    s += "<rect x='" + fmt("%.1f", x) + "' y='" + fmt("%.1f", row - 8) + "' width='10' height='10' fill='" +
         kColours[i % 6] + "'/>\n";
    s += "<text x='" + fmt("%.1f", x + 14) + "' y='" + fmt("%.1f", row + 1) + "'>" + xml_escape(names[i]) + "</text>\n";
  }
  return s;
}

std::string open_svg(const ChartSpec& spec) {
  return "<svg xmlns='http://www.w3.org/2000/svg' width='" + std::to_string(spec.width_px) + "' height='" +
         std::to_string(spec.height_px) + "' font-family='sans-serif' font-size='11'>\n";
}

}  // namespace

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '\'': out += "&#39;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string svg_chart(const ChartSpec& spec, const std::vector<Series>& series) {
  std::vector<const std::vector<double>*> xs;
  std::vector<const std::vector<double>*> ys;
  std::vector<std::string> names;
  for (const Series& s : series) {
    xs.push_back(&s.x);
    ys.push_back(&s.y);
    names.push_back(s.name);
  }
  const Axis x = make_axis(xs, false, 70.0, spec.width_px - 130.0);
  const Axis y = make_axis(ys, spec.log_y, spec.height_px - 45.0, 28.0);
  std::string out = open_svg(spec) + frame(spec, x, y);
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    const char* colour = kColours[k % 6];
    std::string points;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (spec.log_y && s.y[i] <= 0.0)) continue;
      const double px = x.to_px(s.x[i]);
      const double py = y.to_px(s.y[i]);
      if (s.markers) {
        out += "<circle cx='" + fmt("%.1f", px) + "' cy='" + fmt("%.1f", py) + "' r='2.5' fill='none' stroke='" +
               colour + "'/>\n";
      } else {
        points += fmt("%.1f", px) + "," + fmt("%.1f", py) + " ";
      }
    }
    if (!s.markers && !points.empty()) {
      out += "<polyline fill='none' stroke='" + std::string(colour) + "' stroke-width='1.5' points='" + points + "'/>\n";
    }
  }
  out += legend(names, spec.width_px - 120.0, 40.0);
  return out + "</svg>\n";
}

std::string svg_histogram(const ChartSpec& spec, const std::vector<std::string>& names,
                          const std::vector<std::vector<double>>& value_sets, int bins) {
  double max_value = 0.0;
  for (const auto& set : value_sets)
    for (double v : set)
      if (std::isfinite(v)) max_value = std::max(max_value, v);
  if (max_value <= 0.0) max_value = 1.0;
  std::vector<std::vector<double>> counts(value_sets.size(), std::vector<double>(static_cast<std::size_t>(bins), 0.0));
  double max_count = 1.0;
  for (std::size_t k = 0; k < value_sets.size(); ++k) {
    for (double v : value_sets[k]) {
      if (!std::isfinite(v)) continue;
      auto bin = static_cast<std::size_t>(v / max_value * bins);
      bin = std::min(bin, static_cast<std::size_t>(bins - 1));
      counts[k][bin] += 1.0;
      max_count = std::max(max_count, counts[k][bin]);
    }
  }
  const std::vector<double> x_range = {0.0, max_value};
  const std::vector<double> y_range = {0.0, max_count};
  const Axis x = make_axis({&x_range}, false, 70.0, spec.width_px - 130.0);
  const Axis y = make_axis({&y_range}, false, spec.height_px - 45.0, 28.0);
  std::string out = open_svg(spec) + frame(spec, x, y);
  const double bin_width = max_value / bins;
  const double group = static_cast<double>(value_sets.size());
  for (std::size_t k = 0; k < counts.size(); ++k) {
    for (int b = 0; b < bins; ++b) {
      const double x0 = x.to_px(bin_width * (b + static_cast<double>(k) / group));
      const double x1 = x.to_px(bin_width * (b + (static_cast<double>(k) + 1.0) / group));
      const double top = y.to_px(counts[k][static_cast<std::size_t>(b)]);
      const double base = y.to_px(0.0);
      out += "<rect x='" + fmt("%.1f", x0) + "' y='" + fmt("%.1f", top) + "' width='" + fmt("%.1f", x1 - x0) +
             "' height='" + fmt("%.1f", base - top) + "' fill='" + kColours[k % 6] + "' fill-opacity='0.8'/>\n";
    }
  }
  out += legend(names, spec.width_px - 120.0, 40.0);
  return out + "</svg>\n";
}

}  // namespace hivecal::report
