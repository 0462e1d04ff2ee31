// Small SVG chart writer for the report: line charts, scatter plots and histograms.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hivecal::report {

/// One named series of (x, y) points drawn in one colour.
struct Series {
  std::string name;       ///< legend label
  std::vector<double> x;  ///< abscissae
  std::vector<double> y;  ///< ordinates (same count as x)
  bool markers = false;   ///< draw points instead of a line
};

/// Chart frame and labels.
struct ChartSpec {
  std::string title;           ///< above the plot
  std::string x_label;         ///< under the x axis
  std::string y_label;         ///< beside the y axis
  bool log_y = false;          ///< logarithmic y axis (values <= 0 are skipped)
  int width_px = 560;          ///< SVG width
  int height_px = 320;         ///< SVG height
  std::string id{};            ///< id attribute of the <svg> ("" for none)
  bool fixed_y = false;        ///< use [y_lo, y_hi] (a scale shared with other panels) instead of the data's range
  double y_lo = 0.0;           ///< lower y limit when fixed_y (in data units)
  double y_hi = 1.0;           ///< upper y limit when fixed_y (in data units)
  double y_line = 0.0;         ///< a dashed horizontal reference line at this y (e.g. the noise level)
  std::string y_line_label{};  ///< its legend label; "" draws no line
};

/// Arrows from (x, y) to (x + dx, y + dy), in axis units, drawn in one colour.
struct ArrowSet {
  std::string name;        ///< legend label
  std::vector<double> x;   ///< arrow tails
  std::vector<double> y;   ///< arrow tails
  std::vector<double> dx;  ///< arrow vectors (already scaled for display)
  std::vector<double> dy;  ///< arrow vectors (already scaled for display)
};

/// An inline <svg> element plotting the series.
std::string svg_chart(const ChartSpec& spec, const std::vector<Series>& series);

/// Histogram bars of `values` in `bins` equal bins over [0, max]; one bar group per set.
std::string svg_histogram(const ChartSpec& spec, const std::vector<std::string>& names,
                          const std::vector<std::vector<double>>& value_sets, int bins);

/// Arrows over a plot whose axes span the tails and heads; `scale_label` (e.g.
/// "1 mm arrow = 50 um|bar: 500 um", lines split at '|') is printed under a reference bar
/// `scale_length` axis units long.
std::string svg_arrows(const ChartSpec& spec, const std::vector<ArrowSet>& sets, double scale_length,
                       const std::string& scale_label);

/// Horizontal bars: one per category, length `counts[i]`, axis from 0.
std::string svg_bars(const ChartSpec& spec, const std::vector<std::string>& categories,
                     const std::vector<double>& counts);

/// Rows of time bins over a linear x axis [0, duration]: one row per category, each bin
/// shaded by its count relative to the row's largest (a count of 0 draws nothing); the row
/// label carries the row's total.
std::string svg_strips(const ChartSpec& spec, const std::vector<std::string>& categories,
                       const std::vector<std::vector<std::uint32_t>>& counts, double duration);

/// A round value near `raw` (> 0): 1, 2, 2.5 or 5 times a power of ten, >= raw.
double nice_step(double raw);

/// Significant digits of a plain decimal tick label: "231.25" -> 5, "1250" -> 3, "0.025" -> 2.
int significant_digits(const std::string& label);

/// Text for XML/HTML content and attributes: through port::printable (control bytes and what is
/// no UTF-8 as \xNN), then the markup characters escaped. Every text of the report goes through it.
std::string xml_escape(const std::string& text);

}  // namespace hivecal::report
