// Small SVG chart writer for the report: line charts, scatter plots and histograms.
#pragma once

#include <string>
#include <vector>

namespace hivecal::report {

/// One named series of (x, y) points drawn in one colour.
struct Series {
  std::string name;        ///< legend label
  std::vector<double> x;   ///< abscissae
  std::vector<double> y;   ///< ordinates (same count as x)
  bool markers = false;    ///< draw points instead of a line
};

/// Chart frame and labels.
struct ChartSpec {
  std::string title;     ///< above the plot
  std::string x_label;   ///< under the x axis
  std::string y_label;   ///< beside the y axis
  bool log_y = false;    ///< logarithmic y axis (values <= 0 are skipped)
  int width_px = 560;    ///< SVG width
  int height_px = 320;   ///< SVG height
};

/// An inline <svg> element plotting the series.
std::string svg_chart(const ChartSpec& spec, const std::vector<Series>& series);

/// Histogram bars of `values` in `bins` equal bins over [0, max]; one bar group per set.
std::string svg_histogram(const ChartSpec& spec, const std::vector<std::string>& names,
                          const std::vector<std::vector<double>>& value_sets, int bins);

/// Significant digits of a plain decimal tick label: "231.25" -> 5, "1250" -> 3, "0.025" -> 2.
int significant_digits(const std::string& label);

/// Text escaped for XML/HTML content and attributes.
std::string xml_escape(const std::string& text);

}  // namespace hivecal::report
