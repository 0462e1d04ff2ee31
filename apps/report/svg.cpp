#include "report/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hivecal/port/error.hpp"

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

/// Ticks in axis units (log10 units on a log axis) and the labels they carry.
struct Ticks {
  std::vector<double> at;           ///< tick positions in axis units
  std::vector<std::string> labels;  ///< one label per tick
  std::string offset;               ///< subtracted from the labels ("" when none), for the axis title
};

/// Label of a linear tick: as few decimals as the step needs, at most three significant digits.
std::string linear_label(double v, double step) {
  if (std::fabs(v) < 1e-9 * step) return "0";
  const double magnitude = std::fabs(v);
  if (magnitude >= 1e5 || magnitude < 1e-3) return fmt("%.3g", v);
  const int decimals =
      std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)) +
                      (std::fabs(step / std::pow(10.0, std::floor(std::log10(step))) - 2.5) < 1e-9 ? 1 : 0));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

Axis make_axis(const std::vector<const std::vector<double>*>& data, bool log, double px_lo, double px_hi,
               bool from_zero = false) {
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
  if (from_zero && !log) {
    axis.lo = std::min(axis.lo, 0.0);
    axis.hi = std::max(axis.hi, 0.0);
  }
  if (axis.hi - axis.lo < 1e-300) {
    axis.lo -= log ? 0.5 : (axis.lo != 0.0 ? 0.1 * std::fabs(axis.lo) : 0.5);
    axis.hi += log ? 0.5 : (axis.hi != 0.0 ? 0.1 * std::fabs(axis.hi) : 0.5);
  }
  if (log) {  // whole decades
    axis.lo = std::floor(axis.lo + 1e-9);
    axis.hi = std::ceil(axis.hi - 1e-9);
    if (axis.hi <= axis.lo) axis.hi = axis.lo + 1.0;
  } else {  // round ends, on the tick grid
    const double step = nice_step((axis.hi - axis.lo) / 4.0);
    axis.lo = std::floor(axis.lo / step + 1e-9) * step;
    axis.hi = std::ceil(axis.hi / step - 1e-9) * step;
  }
  return axis;
}

Ticks ticks_of(const Axis& axis) {
  Ticks t;
  if (axis.log) {
    const int decades = static_cast<int>(std::lround(axis.hi - axis.lo));
    const int every = std::max(1, decades / 6);
    for (int d = 0; d <= decades; d += every) {
      const double e = axis.lo + d;
      t.at.push_back(e);
      t.labels.push_back(fmt("%g", std::pow(10.0, e)));
    }
    return t;
  }
  const double step = nice_step((axis.hi - axis.lo) / 4.0);
  // The first multiple of the step inside the axis (its ends are on the grid, except for a
  // range widened to an equal aspect ratio).
  const double first = std::ceil(axis.lo / step - 1e-9) * step;
  const auto count = static_cast<int>(std::floor((axis.hi - first) / step + 1e-9));
  bool too_long = false;
  for (int i = 0; i <= count; ++i) {
    const double v = first + step * i;
    t.at.push_back(v);
    t.labels.push_back(linear_label(v, step));
    too_long = too_long || significant_digits(t.labels.back()) > 3;
  }
  if (too_long) {  // a narrow range far from 0: label the distance from the first tick
    t.offset = fmt("%.10g", first);
    for (int i = 0; i <= count; ++i) t.labels[static_cast<std::size_t>(i)] = linear_label(step * i, step);
  }
  return t;
}

std::string frame(const ChartSpec& spec, const Axis& x, const Axis& y) {
  std::string s;
  const double left = x.px_lo;
  const double right = x.px_hi;
  const double top = y.px_hi;
  const double bottom = y.px_lo;
  s += "<rect x='" + fmt("%.1f", left) + "' y='" + fmt("%.1f", top) + "' width='" + fmt("%.1f", right - left) +
       "' height='" + fmt("%.1f", bottom - top) + "' fill='none' stroke='#444'/>\n";
  const Ticks xt = ticks_of(x);
  for (std::size_t i = 0; i < xt.at.size(); ++i) {
    const double px = left + (xt.at[i] - x.lo) / (x.hi - x.lo) * (right - left);
    s += "<text class='tick' x='" + fmt("%.1f", px) + "' y='" + fmt("%.1f", bottom + 14) + "' text-anchor='middle'>" +
         xt.labels[i] + "</text>\n";
  }
  const Ticks yt = ticks_of(y);
  for (std::size_t i = 0; i < yt.at.size(); ++i) {
    const double py = bottom + (yt.at[i] - y.lo) / (y.hi - y.lo) * (top - bottom);
    s += "<line x1='" + fmt("%.1f", left) + "' x2='" + fmt("%.1f", right) + "' y1='" + fmt("%.1f", py) + "' y2='" +
         fmt("%.1f", py) + "' stroke='#ddd'/>\n";
    s += "<text class='tick' x='" + fmt("%.1f", left - 4) + "' y='" + fmt("%.1f", py + 4) + "' text-anchor='end'>" +
         yt.labels[i] + "</text>\n";
  }
  s += "<text x='" + fmt("%.1f", (left + right) / 2) + "' y='16' text-anchor='middle' font-weight='bold'>" +
       xml_escape(spec.title) + "</text>\n";
  const std::string x_title = xt.offset.empty() ? spec.x_label : spec.x_label + " \u2212 " + xt.offset;
  const std::string y_title = yt.offset.empty() ? spec.y_label : spec.y_label + " \u2212 " + yt.offset;
  s += "<text x='" + fmt("%.1f", (left + right) / 2) + "' y='" + fmt("%.1f", bottom + 30) + "' text-anchor='middle'>" +
       xml_escape(x_title) + "</text>\n";
  s += "<text transform='translate(14," + fmt("%.1f", (top + bottom) / 2) + ") rotate(-90)' text-anchor='middle'>" +
       xml_escape(y_title) + "</text>\n";
  return s;
}

/// A legend entry: label and colour.
struct LegendEntry {
  std::string name;    ///< label ("" for none)
  std::string colour;  ///< fill of its swatch
};

// The legend column right of the plot: a swatch, a gap, the label in lines of at most
// kLegendLineChars characters (broken at spaces), the widest line estimated at
// kCharWidth_px a character: Chromium's default sans-serif on Debian (DejaVu Sans) averages
// ~6.3 px at the charts' 11 px, its widest capitals ~8 px; the render test measures it.
constexpr double kCharWidth_px = 7.0;
constexpr std::size_t kLegendLineChars = 22;
constexpr double kSwatchAndGap_px = 14.0;
constexpr double kLegendMargin_px = 10.0;
/// The least legend column: the plot's right edge as it always was for short labels [px].
constexpr double kMinLegendColumn_px = 120.0;

/// Characters of UTF-8 `text` (continuation bytes not counted).
std::size_t characters(const std::string& text) {
  std::size_t n = 0;
  for (const char c : text) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80 ? 1 : 0;
  return n;
}

/// `name` in lines of at most kLegendLineChars characters, broken at spaces (a longer word
/// stays whole).
std::vector<std::string> legend_lines(const std::string& name) {
  std::vector<std::string> lines;
  std::string line;
  for (std::size_t at = 0; at < name.size();) {
    const std::size_t end = std::min(name.find(' ', at), name.size());
    const std::string word = name.substr(at, end - at);
    if (!line.empty() && characters(line) + 1 + characters(word) > kLegendLineChars) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    at = end + 1;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

/// Width of the legend column for `names` (the plot ends where it begins) [px].
double legend_column_px(const std::vector<std::string>& names) {
  double widest_px = 0.0;
  for (const std::string& name : names)
    for (const std::string& line : legend_lines(name))
      widest_px = std::max(widest_px, kCharWidth_px * static_cast<double>(characters(line)));
  return std::max(kMinLegendColumn_px, kSwatchAndGap_px + widest_px + kLegendMargin_px);
}

/// Legend rows for the non-empty names, from (x, y); a long name takes several lines. Each
/// carries data-series so that a checker can find the element it stands for.
std::string legend(const std::vector<LegendEntry>& entries, double x, double y) {
  std::string s;
  double row = y - 14.0;
  for (const LegendEntry& e : entries) {
    if (e.name.empty()) continue;
    row += 14.0;
    s += "<rect class='swatch' x='" + fmt("%.1f", x) + "' y='" + fmt("%.1f", row - 8) +
         "' width='10' height='10' fill='" + e.colour + "'/>\n";
    const std::vector<std::string> lines = legend_lines(e.name);
    s += "<text class='legend' data-series='" + xml_escape(e.name) + "' x='" + fmt("%.1f", x + kSwatchAndGap_px) +
         "' y='" + fmt("%.1f", row + 1) + "'>";
    for (std::size_t k = 0; k < lines.size(); ++k) {
      s += lines.size() == 1 ? xml_escape(lines[k])
                             : "<tspan x='" + fmt("%.1f", x + kSwatchAndGap_px) + "' dy='" + (k == 0 ? "0" : "13") +
                                   "'>" + xml_escape(lines[k]) + "</tspan>";
    }
    s += "</text>\n";
    row += 13.0 * static_cast<double>(lines.size() - 1);
  }
  return s;
}

std::string open_svg(const ChartSpec& spec) {
  return "<svg xmlns='http://www.w3.org/2000/svg'" +
         (spec.id.empty() ? std::string() : " id='" + xml_escape(spec.id) + "'") + " width='" +
         std::to_string(spec.width_px) + "' height='" + std::to_string(spec.height_px) +
         "' font-family='sans-serif' font-size='11'>\n";
}

std::string series_attr(const std::string& name) {
  return " data-series='" + xml_escape(name) + "'";
}

/// The dashed reference line of spec (when it has a label and lies inside the y axis).
std::string reference_line(const ChartSpec& spec, const Axis& x, const Axis& y, std::vector<LegendEntry>* entries) {
  if (spec.y_line_label.empty() || (y.log && spec.y_line <= 0.0)) return "";
  const double py = y.to_px(spec.y_line);
  entries->push_back({spec.y_line_label, "#555"});
  return "<line" + series_attr(spec.y_line_label) + " x1='" + fmt("%.1f", x.px_lo) + "' x2='" + fmt("%.1f", x.px_hi) +
         "' y1='" + fmt("%.1f", py) + "' y2='" + fmt("%.1f", py) + "' stroke='#555' stroke-dasharray='5,3'/>\n";
}

/// Widens one axis about its centre so that a unit is as many pixels on x as on y (arrows
/// keep their direction).
void equal_aspect(Axis* x, Axis* y) {
  const double x_px_per_unit = std::fabs(x->px_hi - x->px_lo) / (x->hi - x->lo);
  const double y_px_per_unit = std::fabs(y->px_hi - y->px_lo) / (y->hi - y->lo);
  Axis* wider = x_px_per_unit > y_px_per_unit ? x : y;
  const double px_per_unit = std::min(x_px_per_unit, y_px_per_unit);
  const double half = std::fabs(wider->px_hi - wider->px_lo) / px_per_unit / 2.0;
  const double centre = (wider->lo + wider->hi) / 2.0;
  wider->lo = centre - half;
  wider->hi = centre + half;
}

}  // namespace

double nice_step(double raw) {
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * power >= raw * (1.0 - 1e-9)) return m * power;
  return 10.0 * power;
}

int significant_digits(const std::string& label) {
  std::string digits;
  for (char c : label)
    if (c >= '0' && c <= '9') digits += c;
  const std::size_t first = digits.find_first_not_of('0');
  if (first == std::string::npos) return 1;
  std::size_t last = digits.size();
  if (label.find('.') == std::string::npos) last = digits.find_last_not_of('0') + 1;
  return static_cast<int>(last - first);
}

std::string xml_escape(const std::string& text) {
  // Through the messages' filter first (whole, not cut): a name an input file gives (the robot's,
  // a file's, a column's) reaches the page with its control bytes escaped, its UTF-8 as written.
  const std::string shown = port::printable(text, text.size());
  std::string out;
  for (char c : shown) {
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
  for (const Series& s : series) {
    xs.push_back(&s.x);
    ys.push_back(&s.y);
  }
  const std::vector<double> fixed = {spec.y_lo, spec.y_hi};
  const std::vector<double> line = {spec.y_line};
  if (spec.fixed_y) ys = {&fixed};
  if (!spec.y_line_label.empty()) ys.push_back(&line);
  std::vector<std::string> names;
  for (const Series& s : series) names.push_back(s.name);
  if (!spec.y_line_label.empty()) names.push_back(spec.y_line_label);
  const double legend_px = legend_column_px(names);
  const Axis x = make_axis(xs, false, 70.0, spec.width_px - legend_px - 10.0);
  const Axis y = make_axis(ys, spec.log_y, spec.height_px - 45.0, 28.0);
  std::string out = open_svg(spec) + frame(spec, x, y);
  std::vector<LegendEntry> entries;  // only the series that drew something
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    const char* colour = kColours[k % 6];
    std::string points;
    bool drawn = false;
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (spec.log_y && s.y[i] <= 0.0)) continue;
      drawn = true;
      const double px = x.to_px(s.x[i]);
      const double py = y.to_px(s.y[i]);
      if (s.markers) {
        out += "<circle" + series_attr(s.name) + " cx='" + fmt("%.1f", px) + "' cy='" + fmt("%.1f", py) +
               "' r='2.5' fill='none' stroke='" + colour + "'/>\n";
      } else {
        points += fmt("%.1f", px) + "," + fmt("%.1f", py) + " ";
      }
    }
    if (!s.markers && !points.empty()) {
      out += "<polyline" + series_attr(s.name) + " fill='none' stroke='" + std::string(colour) +
             "' stroke-width='1.5' points='" + points + "'/>\n";
    }
    entries.push_back({drawn ? s.name : std::string(), colour});
  }
  out += reference_line(spec, x, y, &entries);
  out += legend(entries, spec.width_px - legend_px, 40.0);
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
  const double legend_px = legend_column_px(names);
  const Axis x = make_axis({&x_range}, false, 70.0, spec.width_px - legend_px - 10.0, true);
  const Axis y = make_axis({&y_range}, false, spec.height_px - 45.0, 28.0, true);
  std::string out = open_svg(spec) + frame(spec, x, y);
  const double bin_width = max_value / bins;
  const double group = static_cast<double>(value_sets.size());
  std::vector<LegendEntry> entries;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const std::string name = k < names.size() ? names[k] : std::string();
    bool drawn = false;
    for (int b = 0; b < bins; ++b) {
      if (counts[k][static_cast<std::size_t>(b)] <= 0.0) continue;
      drawn = true;
      const double x0 = x.to_px(bin_width * (b + static_cast<double>(k) / group));
      const double x1 = x.to_px(bin_width * (b + (static_cast<double>(k) + 1.0) / group));
      const double top = y.to_px(counts[k][static_cast<std::size_t>(b)]);
      const double base = y.to_px(0.0);
      out += "<rect" + series_attr(name) + " x='" + fmt("%.1f", x0) + "' y='" + fmt("%.1f", top) + "' width='" +
             fmt("%.1f", x1 - x0) + "' height='" + fmt("%.1f", base - top) + "' fill='" + kColours[k % 6] +
             "' fill-opacity='0.8'/>\n";
    }
    entries.push_back({drawn ? name : std::string(), kColours[k % 6]});
  }
  out += legend(entries, spec.width_px - legend_px, 40.0);
  return out + "</svg>\n";
}

std::string svg_arrows(const ChartSpec& spec, const std::vector<ArrowSet>& sets, double scale_length,
                       const std::string& scale_label) {
  std::vector<double> xs;
  std::vector<double> ys;
  for (const ArrowSet& a : sets) {
    for (std::size_t i = 0; i < a.x.size() && i < a.y.size() && i < a.dx.size() && i < a.dy.size(); ++i) {
      xs.insert(xs.end(), {a.x[i], a.x[i] + a.dx[i]});
      ys.insert(ys.end(), {a.y[i], a.y[i] + a.dy[i]});
    }
  }
  std::vector<std::string> names;
  for (const ArrowSet& a : sets) names.push_back(a.name);
  const double legend_px = legend_column_px(names);
  Axis x = make_axis({&xs}, false, 70.0, spec.width_px - legend_px - 10.0);
  Axis y = make_axis({&ys}, false, spec.height_px - 45.0, 28.0);
  equal_aspect(&x, &y);
  std::string out = open_svg(spec);
  out += "<defs>";
  for (std::size_t k = 0; k < sets.size(); ++k) {
    out += "<marker id='" + xml_escape(spec.id) + "-head" + std::to_string(k) +
           "' markerWidth='4' markerHeight='4' refX='3.5' refY='2' orient='auto'><path d='M0,0 L4,2 L0,4 z' fill='" +
           kColours[k % 6] + "'/></marker>";
  }
  out += "</defs>\n" + frame(spec, x, y);
  std::vector<LegendEntry> entries;
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const ArrowSet& a = sets[k];
    bool drawn = false;
    for (std::size_t i = 0; i < a.x.size() && i < a.y.size() && i < a.dx.size() && i < a.dy.size(); ++i) {
      if (!std::isfinite(a.x[i] + a.y[i] + a.dx[i] + a.dy[i])) continue;
      drawn = true;
      out += "<line" + series_attr(a.name) + " x1='" + fmt("%.1f", x.to_px(a.x[i])) + "' y1='" +
             fmt("%.1f", y.to_px(a.y[i])) + "' x2='" + fmt("%.1f", x.to_px(a.x[i] + a.dx[i])) + "' y2='" +
             fmt("%.1f", y.to_px(a.y[i] + a.dy[i])) + "' stroke='" + kColours[k % 6] +
             "' stroke-width='1.2' marker-end='url(#" + xml_escape(spec.id) + "-head" + std::to_string(k) + ")'/>\n";
    }
    entries.push_back({drawn ? a.name : std::string(), kColours[k % 6]});
  }
  // The reference arrow: its length in pixels is scale_length on the x axis.
  const double left = spec.width_px - legend_px;
  const double bottom = spec.height_px - 80.0;
  const double length_px = std::fabs(x.to_px(x.lo + scale_length) - x.px_lo);
  out += "<line class='scale' x1='" + fmt("%.1f", left) + "' y1='" + fmt("%.1f", bottom) + "' x2='" +
         fmt("%.1f", left + length_px) + "' y2='" + fmt("%.1f", bottom) + "' stroke='#000' stroke-width='1.5'/>\n";
  // The label's lines are separated by '|'.
  double line_y = bottom + 16.0;
  for (std::size_t at = 0; at <= scale_label.size();) {
    const std::size_t end = std::min(scale_label.find('|', at), scale_label.size());
    out += "<text class='scale-label' x='" + fmt("%.1f", left) + "' y='" + fmt("%.1f", line_y) + "'>" +
           xml_escape(scale_label.substr(at, end - at)) + "</text>\n";
    line_y += 14.0;
    at = end + 1;
  }
  out += legend(entries, spec.width_px - legend_px, 40.0);
  return out + "</svg>\n";
}

std::string svg_bars(const ChartSpec& spec, const std::vector<std::string>& categories,
                     const std::vector<double>& counts) {
  std::vector<double> range = {0.0};
  for (double c : counts) range.push_back(c);
  const double label_px = 200.0;
  const Axis x = make_axis({&range}, false, label_px, spec.width_px - 30.0, true);
  Axis y;  // categories: no numeric y axis
  y.px_lo = spec.height_px - 45.0;
  y.px_hi = 28.0;
  std::string out = open_svg(spec);
  out += "<rect x='" + fmt("%.1f", x.px_lo) + "' y='" + fmt("%.1f", y.px_hi) + "' width='" +
         fmt("%.1f", x.px_hi - x.px_lo) + "' height='" + fmt("%.1f", y.px_lo - y.px_hi) +
         "' fill='none' stroke='#444'/>\n";
  const Ticks xt = ticks_of(x);
  for (std::size_t i = 0; i < xt.at.size(); ++i) {
    out += "<text class='tick' x='" + fmt("%.1f", x.to_px(xt.at[i])) + "' y='" + fmt("%.1f", y.px_lo + 14) +
           "' text-anchor='middle'>" + xt.labels[i] + "</text>\n";
  }
  out += "<text x='" + fmt("%.1f", (x.px_lo + x.px_hi) / 2) + "' y='16' text-anchor='middle' font-weight='bold'>" +
         xml_escape(spec.title) + "</text>\n";
  out += "<text x='" + fmt("%.1f", (x.px_lo + x.px_hi) / 2) + "' y='" + fmt("%.1f", y.px_lo + 30) +
         "' text-anchor='middle'>" + xml_escape(spec.x_label + (xt.offset.empty() ? "" : " \u2212 " + xt.offset)) +
         "</text>\n";
  const double row = counts.empty() ? 0.0 : (y.px_lo - y.px_hi) / static_cast<double>(counts.size());
  for (std::size_t i = 0; i < counts.size() && i < categories.size(); ++i) {
    const double top = y.px_hi + row * static_cast<double>(i) + row * 0.15;
    out += "<text class='category' x='" + fmt("%.1f", x.px_lo - 6) + "' y='" + fmt("%.1f", top + row * 0.45) +
           "' text-anchor='end'>" + xml_escape(categories[i]) + "</text>\n";
    out += "<rect" + series_attr(categories[i]) + " x='" + fmt("%.1f", x.px_lo) + "' y='" + fmt("%.1f", top) +
           "' width='" + fmt("%.1f", x.to_px(counts[i]) - x.px_lo) + "' height='" + fmt("%.1f", row * 0.7) +
           "' fill='" + kColours[0] + "'/>\n";
    out += "<text class='value' x='" + fmt("%.1f", x.to_px(counts[i]) + 4) + "' y='" + fmt("%.1f", top + row * 0.45) +
           "'>" + fmt("%.0f", counts[i]) + "</text>\n";
  }
  return out + "</svg>\n";
}

std::string svg_strips(const ChartSpec& spec, const std::vector<std::string>& categories,
                       const std::vector<std::vector<std::uint32_t>>& counts, double duration) {
  const std::vector<double> range = {0.0, duration > 0.0 ? duration : 1.0};
  const Axis x = make_axis({&range}, false, 200.0, spec.width_px - 30.0, true);
  const double top = 28.0;
  const double bottom = spec.height_px - 45.0;
  std::string out = open_svg(spec);
  out += "<rect x='" + fmt("%.1f", x.px_lo) + "' y='" + fmt("%.1f", top) + "' width='" +
         fmt("%.1f", x.px_hi - x.px_lo) + "' height='" + fmt("%.1f", bottom - top) + "' fill='none' stroke='#444'/>\n";
  const Ticks xt = ticks_of(x);
  for (std::size_t i = 0; i < xt.at.size(); ++i) {
    out += "<text class='tick' x='" + fmt("%.1f", x.to_px(xt.at[i])) + "' y='" + fmt("%.1f", bottom + 14) +
           "' text-anchor='middle'>" + xt.labels[i] + "</text>\n";
  }
  out += "<text x='" + fmt("%.1f", (x.px_lo + x.px_hi) / 2) + "' y='16' text-anchor='middle' font-weight='bold'>" +
         xml_escape(spec.title) + "</text>\n";
  out += "<text x='" + fmt("%.1f", (x.px_lo + x.px_hi) / 2) + "' y='" + fmt("%.1f", bottom + 30) +
         "' text-anchor='middle'>" + xml_escape(spec.x_label + (xt.offset.empty() ? "" : " \u2212 " + xt.offset)) +
         "</text>\n";
  const std::size_t rows = std::min(categories.size(), counts.size());
  const double row = rows == 0 ? 0.0 : (bottom - top) / static_cast<double>(rows);
  for (std::size_t r = 0; r < rows; ++r) {
    const std::vector<std::uint32_t>& bins = counts[r];
    std::uint64_t total = 0;
    std::uint32_t largest = 0;
    for (std::uint32_t c : bins) {
      total += c;
      largest = std::max(largest, c);
    }
    const double y0 = top + row * static_cast<double>(r);
    out += "<text class='category' x='" + fmt("%.1f", x.px_lo - 6) + "' y='" + fmt("%.1f", y0 + row * 0.6) +
           "' text-anchor='end'>" + xml_escape(categories[r]) + " (" + std::to_string(total) + ")</text>\n";
    const double bin_s = range[1] / static_cast<double>(bins.empty() ? 1 : bins.size());
    for (std::size_t b = 0; b < bins.size(); ++b) {
      if (bins[b] == 0) continue;
      const double x0 = x.to_px(bin_s * static_cast<double>(b));
      const double x1 = x.to_px(bin_s * static_cast<double>(b + 1));
      out += "<rect" + series_attr(categories[r]) + " x='" + fmt("%.1f", x0) + "' y='" + fmt("%.1f", y0 + row * 0.15) +
             "' width='" + fmt("%.1f", x1 - x0) + "' height='" + fmt("%.1f", row * 0.7) + "' fill='" + kColours[r % 6] +
             "' fill-opacity='" +
             fmt("%.2f", 0.15 + 0.85 * static_cast<double>(bins[b]) / static_cast<double>(largest)) + "'/>\n";
    }
  }
  return out + "</svg>\n";
}

}  // namespace hivecal::report
