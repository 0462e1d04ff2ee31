#include "report/report.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

#include "hivecal/core/math.hpp"
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

ChartSpec chart(const std::string& id, const std::string& title, const std::string& x_label,
                const std::string& y_label) {
  ChartSpec spec;
  spec.id = id;
  spec.title = title;
  spec.x_label = x_label;
  spec.y_label = y_label;
  return spec;
}

/// The samples the error figures show: the test set, or the training set when there is none.
std::vector<std::size_t> shown_samples(const ReportData& data, bool* test) {
  std::vector<std::size_t> shown;
  *test = false;
  for (const SampleRow& s : data.samples) *test = *test || s.test;
  for (std::size_t i = 0; i < data.samples.size(); ++i)
    if (data.samples[i].test == *test) shown.push_back(i);
  return shown;
}

/// |error| of one prediction set on the given samples: an axis (0..2) or the 3D norm (3) [um].
std::vector<double> errors_um(const ReportData& data, const PredictionSet& set, const std::vector<std::size_t>& which,
                              int axis) {
  std::vector<double> v;
  for (std::size_t i : which) {
    if (i >= set.points_m.size()) continue;
    const Vec3 e = set.points_m[i] - data.samples[i].measured_m;
    v.push_back((axis < 3 ? std::fabs(e(axis)) : e.norm()) * 1e6);
  }
  return v;
}

std::vector<double> sorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v;
}

double max_of(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, x);
  return m;
}

/// One figure of the page.
struct Figure {
  std::string id;       ///< its <svg id>
  std::string svg;      ///< the <svg> element
  std::string drawn{};  ///< what of the data it draws when not all of it ("" when all), for its caption
};

// What a figure draws at most: beyond, an evenly spaced subset (its caption says how many).
// A scatter of thousands of points is a solid block and a page of 10^5 elements opens slowly
// (12,000 samples drew 10.4 MB that took 11 s to open).
constexpr std::size_t kScatterPointCap = 1000;  ///< markers of one panel [-]
constexpr std::size_t kArrowCap = 400;          ///< arrows of one set [-]
constexpr std::size_t kCurvePointCap = 1000;    ///< ranks of one sorted curve (its ends among them) [-]

/// `keep` of the positions 0 .. n-1, evenly spaced, floor((k + 1/2) n / keep) for k < keep;
/// every position when keep >= n [-].
std::vector<std::size_t> evenly_spaced(std::size_t n, std::size_t keep) {
  std::vector<std::size_t> at;
  for (std::size_t k = 0; k < std::min(n, keep); ++k) {
    at.push_back(keep >= n ? k
                           : static_cast<std::size_t>((2 * static_cast<std::uint64_t>(k) + 1) * n /
                                                      (2 * static_cast<std::uint64_t>(keep))));
  }
  return at;
}

/// `keep` (>= 2) of the ranks 0 .. n-1, evenly spaced from the first to the last,
/// round(k (n - 1) / (keep - 1)); every rank when keep >= n [-].
std::vector<std::size_t> spanning_ranks(std::size_t n, std::size_t keep) {
  if (keep >= n || keep < 2) return evenly_spaced(n, n);
  std::vector<std::size_t> at;
  const std::uint64_t steps = keep - 1;
  for (std::uint64_t k = 0; k < keep; ++k)
    at.push_back(static_cast<std::size_t>((2 * k * (n - 1) + steps) / (2 * steps)));
  return at;
}

/// 12000 -> "12,000".
std::string count_text(std::size_t n) {
  std::string digits = std::to_string(n);
  for (std::size_t at = digits.size(); at > 3; at -= 3) digits.insert(at - 3, ",");
  return digits;
}

/// The caption's note of a figure that draws `drawn` of `of` items ("" when all).
std::string drawn_note(std::size_t drawn, std::size_t of, const std::string& items) {
  return drawn < of ? count_text(drawn) + " of " + count_text(of) + " " + items + " drawn, evenly spaced." : "";
}

/// The sorted values `v` at no more than kCurvePointCap ranks as a line: x the rank (1-based)
/// times `rank_scale` (the run's samples per drawn one).
Series sorted_curve(const std::string& name, const std::vector<double>& v, double rank_scale) {
  Series s{name, {}, {}, false};
  for (const std::size_t k : spanning_ranks(v.size(), kCurvePointCap)) {
    s.x.push_back(static_cast<double>(k + 1) * rank_scale);
    s.y.push_back(v[k]);
  }
  return s;
}

/// Sorted error per sample before and after, 3D and per axis (shared scale), with the noise level.
void error_figures(const ReportData& data, const std::vector<std::size_t>& shown, const std::string& set_name,
                   std::vector<Figure>* out) {
  // A report that keeps a subset of the samples draws the ranks of the run's: its test (or
  // training) samples per kept one.
  const std::size_t run_count = set_name == "test" ? data.calibrated.test.count : data.calibrated.train.count;
  const double rank_scale = data.sample_total > 0 && run_count > shown.size()
                                ? static_cast<double>(run_count) / static_cast<double>(shown.size())
                                : 1.0;
  const PredictionSet& before = data.predictions.front();
  const PredictionSet& after = data.predictions.back();
  // Mean |N(0, s)| per axis is s*sqrt(2/pi); the mean 3D norm of isotropic noise is s*sqrt(8/pi).
  const double per_axis_um = data.noise_sigma_m * 1e6 * std::sqrt(2.0 / math::kPi);
  const double norm_um = data.noise_sigma_m * 1e6 * std::sqrt(8.0 / math::kPi);
  double shared_max = per_axis_um;
  for (int axis = 0; axis < 3; ++axis) shared_max = std::max(shared_max, max_of(errors_um(data, before, shown, axis)));
  const char* names[] = {"x", "y", "z", "3D"};
  for (int axis : {3, 0, 1, 2}) {
    std::vector<double> b = sorted(errors_um(data, before, shown, axis));
    std::vector<double> a = sorted(errors_um(data, after, shown, axis));
    ChartSpec spec = chart(std::string("fig-error-") + (axis == 3 ? "3d" : names[axis]),
                           std::string(names[axis]) + " error per " + set_name + " sample, sorted",
                           set_name + " samples, by rank", std::string("|error ") + names[axis] + "| [um]");
    if (axis < 3) {
      spec.fixed_y = true;
      spec.y_lo = 0.0;
      spec.y_hi = shared_max;
    }
    if (data.noise_sigma_m > 0.0) {
      spec.y_line = axis == 3 ? norm_um : per_axis_um;
      spec.y_line_label = "measurement noise (" + data.noise_source + ")";
    }
    out->push_back(
        {spec.id,
         svg_chart(spec, {sorted_curve(before.method, b, rank_scale), sorted_curve(after.method, a, rank_scale)}),
         drawn_note(std::min(b.size(), kCurvePointCap), b.size(), "ranks")});
  }
}

/// Error vectors on the x-y and x-z planes, magnified by a stated round factor.
void vector_figures(const ReportData& data, const std::vector<std::size_t>& all_shown, std::vector<Figure>* out) {
  std::vector<std::size_t> shown;  // at most kArrowCap arrows a set
  for (const std::size_t k : evenly_spaced(all_shown.size(), kArrowCap)) shown.push_back(all_shown[k]);
  const PredictionSet* sets[] = {&data.predictions.front(), &data.predictions.back()};
  double largest_um = 0.0;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (std::size_t i : shown) {
    lo = lo.cwiseMin(data.samples[i].measured_m * 1e3);
    hi = hi.cwiseMax(data.samples[i].measured_m * 1e3);
    for (const PredictionSet* set : sets)
      if (i < set->points_m.size())
        largest_um = std::max(largest_um, (set->points_m[i] - data.samples[i].measured_m).norm() * 1e6);
  }
  if (shown.empty() || !(largest_um > 0.0)) return;
  // The longest arrow about a third of the workspace's extent: 1 mm of arrow stands for
  // um_per_mm (a round number), and a bar of bar_mm shows the scale.
  const double span_mm = std::max((hi - lo).maxCoeff(), 1.0);
  const double um_per_mm = nice_step(largest_um / (span_mm / 3.0));
  const double bar_mm = nice_step(span_mm / 12.0);
  char label[96];
  std::snprintf(label, sizeof label, "1 mm arrow = %g um|bar: %g um", um_per_mm, bar_mm * um_per_mm);
  const char* names[] = {"x", "y", "z"};
  for (int axis : {1, 2}) {
    std::vector<ArrowSet> arrows;
    for (const PredictionSet* set : sets) {
      ArrowSet a;
      a.name = set->method + " error";
      for (std::size_t i : shown) {
        if (i >= set->points_m.size()) continue;
        const Vec3 e_um = (set->points_m[i] - data.samples[i].measured_m) * 1e6;
        a.x.push_back(data.samples[i].measured_m(0) * 1e3);
        a.y.push_back(data.samples[i].measured_m(axis) * 1e3);
        a.dx.push_back(e_um(0) / um_per_mm);
        a.dy.push_back(e_um(axis) / um_per_mm);
      }
      arrows.push_back(a);
    }
    ChartSpec spec = chart(std::string("fig-vectors-x") + names[axis],
                           std::string("Error vectors, x-") + names[axis] + " plane (measured -> predicted)", "x [mm]",
                           std::string(names[axis]) + " [mm]");
    spec.height_px = 420;
    out->push_back({spec.id, svg_arrows(spec, arrows, bar_mm, label),
                    drawn_note(shown.size(), all_shown.size(), "samples' arrows")});
  }
}

/// Empirical CDF of the 3D error per method, and the histogram before / after side by side.
void distribution_figures(const ReportData& data, const std::vector<std::size_t>& shown, const std::string& set_name,
                          std::vector<Figure>* out) {
  std::vector<Series> cdf;
  for (const PredictionSet& set : data.predictions) {
    const std::vector<double> e = sorted(errors_um(data, set, shown, 3));
    Series s{set.method, {}, {}, false};
    for (const std::size_t k : spanning_ranks(e.size(), kCurvePointCap)) {  // a step function (at most its cap's steps)
      const double below = static_cast<double>(k) / static_cast<double>(e.size());
      const double at = static_cast<double>(k + 1) / static_cast<double>(e.size());
      s.x.insert(s.x.end(), {e[k], e[k]});
      s.y.insert(s.y.end(), {below, at});
    }
    cdf.push_back(s);
  }
  ChartSpec spec =
      chart("fig-cdf", "Empirical CDF of the 3D error (" + set_name + " samples)", "3D error [um]", "share of samples");
  spec.fixed_y = true;
  out->push_back(
      {spec.id, svg_chart(spec, cdf), drawn_note(std::min(shown.size(), kCurvePointCap), shown.size(), "steps")});
  out->push_back({"fig-histogram", svg_histogram(chart("fig-histogram", "3D error histogram (" + set_name + " samples)",
                                                       "3D error [um]", "samples"),
                                                 {data.predictions.front().method, data.predictions.back().method},
                                                 {errors_um(data, data.predictions.front(), shown, 3),
                                                  errors_um(data, data.predictions.back(), shown, 3)},
                                                 20)});
}

void convergence_figures(const ReportData& data, std::vector<Figure>* out) {
  for (bool lm : {false, true}) {
    std::vector<Series> series;
    for (const ConvergenceSeries& c : data.convergence) {
      if (c.per_iteration != lm || c.best_cost_m.empty()) continue;
      std::vector<double> y;
      for (double v : c.best_cost_m) y.push_back(v * 1e6);
      series.push_back(Series{c.method, index_axis(y.size()), y, lm});
    }
    if (series.empty()) continue;
    ChartSpec spec =
        lm ? chart("fig-convergence-lm", "Levenberg-Marquardt: RMS residual per iteration", "iteration",
                   "RMS residual [um]")
           : chart("fig-convergence-global", "Global search: best MAE per cycle", "cycle", "best MAE [um]");
    spec.log_y = true;
    out->push_back({spec.id, svg_chart(spec, series)});
  }
}

/// With a compliant final model: the last rigid calibrated model before it (the rigid LM
/// stage, the reference of the compliance figures); else null.
const PredictionSet* rigid_reference(const ReportData& data) {
  if (data.predictions.size() < 3 || data.predictions.back().model.compliance.term_count == 0) return nullptr;
  for (std::size_t k = data.predictions.size() - 1; k-- > 1;)  // [0] is the uncalibrated model
    if (data.predictions[k].model.compliance.term_count == 0) return &data.predictions[k];
  return nullptr;
}

/// Whether a joint term of `model` deflects joint j (0-based): a gravity term of the joint, or
/// a harmonic of it that was fitted (the ones the significance test fixed at 0 are not drawn).
bool deflected_joint(const RobotModel& model, int j) {
  const ComplianceModel& c = model.compliance;
  for (int t = 0; t < c.term_count; ++t)
    if (c.terms[t].joint == j && (!is_harmonic(c.terms[t]) || c.coefficient[t] != 0.0)) return true;
  return false;
}

std::vector<double> residuals_um(const ReportData& data, const PredictionSet& set) {
  std::vector<double> residual_um;
  for (std::size_t i = 0; i < data.samples.size() && i < set.points_m.size(); ++i)
    residual_um.push_back((set.points_m[i] - data.samples[i].measured_m).norm() * 1e6);
  return residual_um;
}

/// Residual after calibration against each joint angle (unmodelled effects show as trends).
/// The joints a joint term deflects show the rigid fit (before) and the final one (after) on
/// every sample instead of training / test: a fitted harmonic shows as the wave it took out.
void joint_figures(const ReportData& data, std::vector<Figure>* out) {
  const PredictionSet& after = data.predictions.back();
  const PredictionSet* rigid = rigid_reference(data);
  const std::vector<double> residual_um = residuals_um(data, after);
  const std::vector<double> rigid_um = rigid != nullptr ? residuals_um(data, *rigid) : std::vector<double>{};
  const double y_hi = std::max(max_of(residual_um), max_of(rigid_um));
  const std::vector<std::size_t> drawn = evenly_spaced(residual_um.size(), kScatterPointCap);
  for (int j = 0; j < after.model.joint_count; ++j) {
    const bool before_after = rigid != nullptr && deflected_joint(after.model, j);
    // A prismatic joint's reading is a length [m], drawn in mm; a revolute one's in degrees.
    const bool prismatic = joint_type(after.model, j) == JointType::prismatic;
    const double to_axis = prismatic ? 1e3 : math::kDegPerRad;  // [mm/m] or [deg/rad]
    std::vector<Series> series;
    if (before_after) {
      series = {Series{rigid->method + " (rigid)", {}, {}, true}, Series{after.method, {}, {}, true}};
      for (const std::size_t i : drawn) {
        if (i >= rigid_um.size()) continue;
        for (Series* s : {&series[0], &series[1]}) s->x.push_back(data.samples[i].q_rad[j] * to_axis);
        series[0].y.push_back(rigid_um[i]);
        series[1].y.push_back(residual_um[i]);
      }
    } else {
      series = {Series{"training", {}, {}, true}, Series{"test", {}, {}, true}};
      for (const std::size_t i : drawn) {
        Series& s = series[data.samples[i].test ? 1 : 0];
        s.x.push_back(data.samples[i].q_rad[j] * to_axis);
        s.y.push_back(residual_um[i]);
      }
    }
    const std::string joint = std::to_string(j + 1);
    ChartSpec spec = chart("fig-residual-q" + joint,
                           before_after ? "Residual vs joint " + joint + ": rigid vs " + after.method
                                        : "Residual after calibration vs joint " + joint,
                           "q" + joint + (prismatic ? " [mm]" : " [deg]"), "3D residual [um]");
    spec.width_px = 400;
    spec.height_px = 260;
    spec.fixed_y = true;
    spec.y_hi = y_hi;
    const std::string both = before_after ? " Both fits on the same samples, training and test." : "";
    out->push_back({spec.id, svg_chart(spec, series), drawn_note(drawn.size(), residual_um.size(), "samples") + both});
  }
}

/// Every pose's normalised residual w under the final calibration, sorted, the set-aside ones
/// marked, with the test's threshold: the same numbers as the console and the table.
void outlier_figure(const ReportData& data, std::vector<Figure>* out) {
  const OutlierTable& o = data.outliers;
  if (!o.searched || o.kept_w.empty()) return;
  // Each kept w with its rank among the kept poses: kept_w holds every one, or (kept_total)
  // the sorted values at spanning ranks of them.
  std::vector<double> kept = o.kept_w;
  std::sort(kept.begin(), kept.end());
  const std::size_t kept_count = o.kept_total > 0 ? o.kept_total : kept.size();
  const std::vector<std::size_t> kept_rank =
      o.kept_total > 0 ? spanning_ranks(kept_count, kept.size()) : evenly_spaced(kept.size(), kept.size());
  // At most kScatterPointCap markers: the kept ones at spanning ranks, every set-aside one.
  struct Point {
    double w;        // [-]
    bool aside;      // set aside as a blunder
    std::size_t at;  // rank among the kept poses (kept), or the kept poses below it (set aside)
  };
  std::vector<Point> points;
  const std::vector<std::size_t> drawn = spanning_ranks(kept.size(), kScatterPointCap);
  for (const std::size_t k : drawn) points.push_back({kept[k], false, kept_rank[k]});
  for (const OutlierRow& r : o.rows) {
    const auto below = static_cast<std::size_t>(std::upper_bound(kept.begin(), kept.end(), r.w) - kept.begin());
    points.push_back({r.w, true, below == 0 ? 0 : kept_rank[below - 1] + 1});
  }
  std::sort(points.begin(), points.end(),
            [](const Point& a, const Point& b) { return a.w < b.w || (a.w == b.w && !a.aside && b.aside); });
  Series kept_series{"kept", {}, {}, true};
  Series aside{"set aside", {}, {}, true};
  std::size_t aside_below = 0;  // set-aside poses ranked before this point
  for (const Point& p : points) {
    Series& s = p.aside ? aside : kept_series;
    s.x.push_back(static_cast<double>(p.at + aside_below + 1));
    s.y.push_back(p.w);
    aside_below += p.aside ? 1 : 0;
  }
  ChartSpec spec =
      chart("fig-outliers", "Normalised residual w of each pose after calibration, sorted", "poses, by rank", "w [-]");
  spec.log_y = true;
  if (o.critical_w > 0.0) {
    spec.y_line = o.critical_w;
    spec.y_line_label = "blunder threshold";
  }
  std::string note = drawn_note(drawn.size(), kept_count, "kept poses");
  if (!note.empty() && !o.rows.empty()) note += " Every set-aside pose drawn.";
  out->push_back({spec.id, svg_chart(spec, {kept_series, aside}), note});
}

/// --cv: the held-out (and training) 3-D MAE of each fold, the overall held-out MAE as a line.
void cross_validation_figure(const ReportData& data, std::vector<Figure>* out) {
  const CrossValidationTable& cv = data.cross_validation;
  if (!cv.present || cv.folds.empty()) return;
  Series test{"held-out MAE", index_axis(cv.folds.size()), {}, true};
  Series train{"training MAE", index_axis(cv.folds.size()), {}, true};
  for (const FoldRow& f : cv.folds) {
    test.y.push_back(f.test_mae_m * 1e6);
    train.y.push_back(f.train_mae_m * 1e6);
  }
  ChartSpec spec = chart("fig-cv-folds", "Cross-validation: 3D MAE per fold", "fold", "3D MAE [um]");
  spec.fixed_y = true;
  spec.y_hi = std::max(max_of(test.y), max_of(train.y));
  spec.y_line = cv.mae_3d_m * 1e6;
  spec.y_line_label = "overall held-out";
  out->push_back({spec.id, svg_chart(spec, {test, train})});
}

/// Stream input: the speed profiles as the clock fit matched them, and what is left between
/// them (two panels on the same time axis as the drop timeline).
void clock_figures(const ReportData& data, std::vector<Figure>* out) {
  const ClockMatchSeries& m = data.clock_match;
  if (!data.has_stream || m.t_s.empty()) return;
  std::vector<double> robot_mm_s, tracker_mm_s, residual_mm_s;
  for (std::size_t k = 0; k < m.t_s.size(); ++k) {
    robot_mm_s.push_back(m.speed_gain * m.robot_speed_m_s[k] * 1e3);
    tracker_mm_s.push_back(m.tracker_speed_m_s[k] * 1e3);
    residual_mm_s.push_back(m.residual_m_s[k] * 1e3);
  }
  char gain[48];
  std::snprintf(gain, sizeof gain, "robot tool x %.4f", m.speed_gain);
  ChartSpec speeds =
      chart("fig-clock-speeds", "Clock sync: tool speed seen by the robot (fitted clock) and by the tracker",
            "tracker time [s]", "speed [mm/s]");
  speeds.width_px = 1100;
  out->push_back({speeds.id, svg_chart(speeds, {Series{gain, m.t_s, robot_mm_s, false},
                                                Series{"tracker", m.t_s, tracker_mm_s, false}})});
  ChartSpec residual = chart("fig-clock-residual", "Clock sync: speed residual (tracker - robot x gain)",
                             "tracker time [s]", "residual [mm/s]");
  residual.width_px = 1100;
  residual.height_px = 240;
  out->push_back({residual.id, svg_chart(residual, {Series{"residual", m.t_s, residual_mm_s, false}})});
}

std::vector<Figure> all_figures(const ReportData& data) {
  std::vector<Figure> figures;
  bool test = false;
  const std::vector<std::size_t> shown = shown_samples(data, &test);
  const std::string set_name = test ? "test" : "training";
  if (!data.predictions.empty() && !shown.empty()) {
    error_figures(data, shown, set_name, &figures);
    vector_figures(data, shown, &figures);
    distribution_figures(data, shown, set_name, &figures);
  }
  convergence_figures(data, &figures);
  if (!data.predictions.empty() && !data.samples.empty()) joint_figures(data, &figures);
  outlier_figure(data, &figures);
  cross_validation_figure(data, &figures);
  clock_figures(data, &figures);
  if (data.has_stream && !data.timeline.reasons.empty()) {
    ChartSpec spec =
        chart("fig-drop-timeline", "Tracker points over the session: kept, or why dropped", "tracker time [s]", "");
    spec.height_px = 60 + 24 * static_cast<int>(data.timeline.reasons.size());
    spec.width_px = 1100;
    figures.push_back(
        {spec.id, svg_strips(spec, data.timeline.reasons, data.timeline.counts, data.timeline.duration_s)});
  }
  if (data.has_stream && !data.drops.empty()) {
    std::vector<std::string> reasons;
    std::vector<double> counts;
    for (const auto& [reason, count] : data.drops) {
      reasons.push_back(reason);
      counts.push_back(static_cast<double>(count));
    }
    ChartSpec spec = chart("fig-drops", "Tracker points: kept and dropped, by reason", "tracker points", "");
    spec.height_px = 60 + 22 * static_cast<int>(reasons.size());
    figures.push_back({spec.id, svg_bars(spec, reasons, counts)});
  }
  return figures;
}

bool has_test(const ReportData& data) {
  for (const MethodRow& m : data.methods)
    if (m.test.count > 0) return true;
  return data.calibrated.test.count > 0;
}

bool has_timings(const ReportData& data) {
  for (const MethodRow& m : data.methods)
    if (m.seconds > 0.0) return true;
  return false;
}

std::vector<std::vector<std::string>> table1_rows(const ReportData& data) {
  const bool test = has_test(data);
  const bool timed = has_timings(data);
  std::vector<std::string> header = {"method", "parameters", "train MAE [um]", "train sigma [um]"};
  if (test) header.insert(header.end(), {"test MAE [um]", "test sigma [um]", "test vs uncalibrated"});
  header.push_back("evaluations");
  if (timed) header.push_back("time [s]");
  std::vector<std::vector<std::string>> rows = {header};
  const double before = data.methods.empty() ? 0.0 : data.methods.front().test.mae(ErrorAxis::norm_3d);
  for (const MethodRow& m : data.methods) {
    const bool tested = m.test.count > 0;  // --split 1: no test samples, no test cells
    std::vector<std::string> row = {m.method, m.parameters, um(m.train.mae(ErrorAxis::norm_3d)),
                                    um(m.train.sigma(ErrorAxis::norm_3d))};
    if (test) {
      row.insert(
          row.end(),
          {tested ? um(m.test.mae(ErrorAxis::norm_3d)) : "-", tested ? um(m.test.sigma(ErrorAxis::norm_3d)) : "-",
           &m == &data.methods.front() || !tested ? "" : improvement(before, m.test.mae(ErrorAxis::norm_3d))});
    }
    row.push_back(m.evaluations > 0 ? std::to_string(m.evaluations) : "");
    if (timed) {
      char seconds[32];
      std::snprintf(seconds, sizeof seconds, "%.3f", m.seconds);
      row.push_back(m.seconds > 0.0 ? seconds : "");
    }
    rows.push_back(row);
  }
  return rows;
}

std::vector<std::vector<std::string>> table2_rows(const ReportData& data) {
  std::vector<std::vector<std::string>> rows = {
      {"set", "axis", "MAE before [um]", "sigma before [um]", "MAE after [um]", "sigma after [um]", "change"}};
  const std::pair<const char*, const ErrorStats AccuracyReport::*> sets[] = {
      {"train", &AccuracyReport::train}, {"test", &AccuracyReport::test}, {"overall", &AccuracyReport::overall}};
  const bool test = has_test(data);
  for (const auto& [name, member] : sets) {
    if (!test && member != &AccuracyReport::train) continue;  // overall = train then
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

std::string general(double v) {
  if (!std::isfinite(v)) return "inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

std::vector<std::vector<std::string>> identifiability_rows(const IdentifiabilityTable& id) {
  std::vector<std::vector<std::string>> rows = {
      {"set aside", "why", "sigma ratio", "combination that is not separable"}};
  for (const DroppedRow& d : id.dropped) rows.push_back({d.param, d.reason, general(d.singular_ratio), d.combination});
  for (const std::string& name : id.fixed)
    rows.push_back({name, "not significant (< " + general(id.significance_t) + " sigma)", "", ""});
  return rows;
}

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::string fixed(double v, int decimals) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%+.*f", decimals, v);
  return buf;
}

/// The note of a parameter without a sigma. Only an LM fit (Table 3 present) gives sigmas: after
/// ABC or GSA every row is an estimate without one. After LM, the parameter
/// was not estimated; when it moved all the same, a step before LM moved it (the tool point, fitted
/// with the start geometry for the uncalibrated row) and LM kept that value.
std::string note_without_sigma(const ReportData& data, const ParameterRow& p) {
  if (!data.identifiability.present) return "no sigma (not an LM fit)";
  if (p.value != p.start) return "not estimated by LM: kept at the value fitted before it";
  return "not estimated";
}

std::vector<std::vector<std::string>> parameter_rows(const ReportData& data) {
  std::vector<std::vector<std::string>> rows = {
      {"parameter", "unit", "start", "calibrated", "change", "sigma", "note"}};
  for (const ParameterRow& p : data.parameters) {
    const bool compliance = !p.compliance_unit.empty();
    const double scale = compliance ? 1e6 : 1e3;  // m -> mm, rad -> mrad; rad/m -> urad/m
    const std::string unit = compliance ? "u" + p.compliance_unit : p.angle ? "mrad" : "mm";
    const double change = (p.value - p.start) * scale;
    std::string note;
    if (p.sigma <= 0.0)
      note = note_without_sigma(data, p);
    else if (std::fabs(change) < 2.0 * p.sigma * scale)
      note = "change within 2 sigma";
    if (std::fabs(p.correlation) > kCorrelationWarning) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%scorrelation %+.3f with %s", note.empty() ? "" : "; ", p.correlation,
                    p.correlated_with.c_str());
      note += buf;
    }
    rows.push_back({p.name, unit, fixed(p.start * scale, 4), fixed(p.value * scale, 4), fixed(change, 4),
                    p.sigma > 0.0 ? general(p.sigma * scale) : "", note});
  }
  return rows;
}

std::string mm(double metres) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", metres * 1e3);
  return buf;
}

/// The blunder search: its test, the samples set aside and the uncontrolled poses.
std::string outlier_html(const OutlierTable& o) {
  if (!o.searched) return "<h2>Blunders</h2>\n<p>No blunder search ran (--keep-outliers): every sample was used.</p>\n";
  char test[200];
  std::snprintf(test, sizeof test,
                "w-test of each pose at %.2g %% for the whole set, threshold w = %.2f, sigma %s mm (%s). ",
                o.alpha * 100.0, o.critical_w, mm(o.sigma_m).c_str(),
                o.sigma_source == "tracker" ? "the tracker's stated noise" : "from the fit's residuals");
  std::string s = "<h2>Blunders</h2>\n<p>" + std::string(test);
  if (o.pooled_correlation) {
    s += "The readings of a pose share their error (their correlation pooled over the poses): a pose is tested as one "
         "error seen several times, not as independent readings. ";
  }
  if (o.verdict == "at_threshold") {
    s += "A pose at the threshold fails the test while fitted and passes when left out (the split moves with it): "
         "kept, named in the information above. ";
  }
  if (o.verdict == "model_error") {
    s += "More poses fail than a blunder explains: the model, not the data, is wrong (unmodelled effects); none "
         "removed. ";
  }
  if (o.verdict == "prediction_error") {
    s += "More test poses fail as predictions than a blunder explains: the fit does not carry to poses it did not "
         "see (too few poses for its parameters, or unmodelled effects); none of them set aside. ";
  }
  if (!o.uncontrolled.empty()) {
    s += std::to_string(o.uncontrolled.size()) +
         " pose(s) uncontrolled (redundancy below 0.1: a blunder there cannot be told from the geometry): ";
    for (std::size_t k = 0; k < o.uncontrolled.size(); ++k) s += (k > 0 ? ", " : "") + o.uncontrolled[k];
    s += ". ";
  }
  if (o.rows.empty()) return s + "None set aside.</p>\n";
  s += std::to_string(o.rows.size()) + " sample(s) set aside.</p>\n";
  std::vector<std::vector<std::string>> rows = {{"sample", "residual [mm]", "w", "threshold w"}};
  char w[32];
  char critical[32];
  std::snprintf(critical, sizeof critical, "%.2f", o.critical_w);
  for (const OutlierRow& r : o.rows) {
    std::snprintf(w, sizeof w, "%.2f", r.w);
    rows.push_back({r.source, mm(r.residual_m), w, critical});
  }
  return s + html_table(rows);
}

std::vector<std::vector<std::string>> cross_validation_rows(const CrossValidationTable& cv) {
  // Which samples each fold held out (file lines), when the run said: a fold far off names them.
  const bool held_out = !cv.held_out_of.empty();
  std::vector<std::vector<std::string>> rows = {
      {"fold", "train samples", "test samples", "train MAE [um]", "held-out MAE [um]"}};
  if (held_out) rows[0].push_back("held out (" + cv.held_out_of + ")");
  for (std::size_t k = 0; k < cv.folds.size(); ++k) {
    const FoldRow& f = cv.folds[k];
    rows.push_back({std::to_string(k + 1), std::to_string(f.train_count), std::to_string(f.test_count),
                    um(f.train_mae_m), um(f.test_mae_m)});
    if (held_out) rows.back().push_back(f.held_out);
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
    for (std::size_t c = 0; c < row.size(); ++c)
      s += (c == 0 ? pad_right(row[c], widths[c]) : "  " + pad(row[c], widths[c]));
    s += "\n";
  }
  return s;
}

/// The question each figure answers (its caption), by id prefix.
const char* caption(const std::string& id) {
  struct Caption {
    const char* prefix;
    const char* text;
  };
  static const Caption captions[] = {
      {"fig-error-3d", "Is each sample better after calibration, and how far above the tracker noise is it?"},
      {"fig-error-", "Which axis gains? (the three axes share one scale)"},
      {"fig-vectors-",
       "Where in the workspace are the errors, and do they point the same way (a frame or scale error)?"},
      {"fig-cdf", "What share of the samples is within a given error, per method?"},
      {"fig-histogram", "How are the errors distributed before and after?"},
      {"fig-convergence-global", "Did ABC / GSA converge before their cycle budget ran out?"},
      {"fig-convergence-lm", "Did Levenberg-Marquardt converge?"},
      {"fig-residual-q", "Does the residual depend on a joint angle (compliance, an unmodelled effect)?"},
      {"fig-clock-speeds",
       "Did the clock fit line the two speed profiles up? Means per time bin over the fit's chords (each a few tracker "
       "points long); the robot speed is scaled by the fitted tracker/robot path-length gain."},
      {"fig-clock-residual",
       "Is anything left between the matched profiles? Near zero while moving: aligned. A timing error shows as "
       "opposite spikes at each start and stop; a slow trend, a tool-model scale error (the fit's per-second gains "
       "absorb it). At rest it sits a little above zero: tracker noise alone makes a chord longer."},
      {"fig-outliers",
       "Which samples did the blunder search set aside, and how far above the rest and the threshold are they? "
       "(residuals under the final calibration; set-aside samples were not fitted)"},
      {"fig-cv-folds",
       "Does the calibration predict samples it was not fitted to, fold after fold? (a fold far above the line: "
       "samples the others do not explain)"},
      {"fig-drops", "How many tracker points became samples, and why were the others dropped?"},
      {"fig-drop-timeline",
       "When in the session were points kept or dropped (beam losses, moves, a stream gap)? Shade: count in the bin "
       "relative to the row's busiest bin."},
  };
  for (const Caption& c : captions)
    if (id.compare(0, std::strlen(c.prefix), c.prefix) == 0) return c.text;
  return "";
}

}  // namespace

ClockMatchSeries clock_match_series(const std::vector<ClockMatchBin>& bins, double speed_gain) {
  ClockMatchSeries series;
  series.speed_gain = speed_gain;
  for (const ClockMatchBin& bin : bins) {
    series.t_s.push_back(bin.tracker_s);
    series.robot_speed_m_s.push_back(bin.robot_speed_m_s);
    series.tracker_speed_m_s.push_back(bin.tracker_speed_m_s);
    series.residual_m_s.push_back(bin.residual_m_s);
  }
  return series;
}

void keep_at_most(std::size_t cap, ReportData* data) {
  const std::size_t n = data->samples.size();
  if (n > cap) {
    std::vector<std::size_t> sets[2];  // training, test
    for (std::size_t i = 0; i < n; ++i) sets[data->samples[i].test ? 1 : 0].push_back(i);
    // The test samples' share of the cap, at least one when there are any.
    std::size_t keep_test = static_cast<std::size_t>((static_cast<std::uint64_t>(sets[1].size()) * cap + n / 2) / n);
    keep_test = std::min(sets[1].size(), std::max<std::size_t>(keep_test, sets[1].empty() ? 0 : 1));
    const std::size_t keeps[2] = {cap - keep_test, keep_test};
    std::vector<std::size_t> kept;
    for (int set = 0; set < 2; ++set)
      for (const std::size_t k : evenly_spaced(sets[set].size(), keeps[set])) kept.push_back(sets[set][k]);
    std::sort(kept.begin(), kept.end());
    std::vector<SampleRow> samples;
    for (const std::size_t i : kept) samples.push_back(data->samples[i]);
    data->samples = samples;
    for (PredictionSet& set : data->predictions) {
      std::vector<Vec3> points_m;
      for (const std::size_t i : kept)
        if (i < set.points_m.size()) points_m.push_back(set.points_m[i]);
      set.points_m = points_m;
    }
    data->sample_total = n;
  }
  OutlierTable& o = data->outliers;
  if (o.kept_w.size() > cap) {
    std::vector<double> sorted_w = sorted(o.kept_w);
    o.kept_w.clear();
    for (const std::size_t k : spanning_ranks(sorted_w.size(), cap)) o.kept_w.push_back(sorted_w[k]);
    o.kept_total = sorted_w.size();
  }
}

PredictionSet predict_samples(const std::string& method, const RobotModel& model, const RigidTransform& base_to_tracker,
                              const std::vector<SampleRow>& samples) {
  PredictionSet set{method, model, base_to_tracker, {}};
  for (const SampleRow& s : samples) {
    JointVector q;
    for (int j = 0; j < s.joint_count; ++j) q(j) = s.q_rad[j];
    set.points_m.push_back(base_to_tracker.apply(fk_target_point(model, q, s.target)));
  }
  return set;
}

std::string format_tables_text(const ReportData& data) {
  return "Table 1: accuracy per method (3D)\n" + text_table(table1_rows(data)) +
         "\nTable 2: accuracy per axis, uncalibrated vs calibrated\n" + text_table(table2_rows(data));
}

std::vector<std::string> format_parameters_text(const ReportData& data) {
  const std::string table = text_table(parameter_rows(data));
  std::vector<std::string> lines;
  for (std::size_t at = 0; at < table.size();) {
    const std::size_t end = table.find('\n', at);
    lines.push_back(table.substr(at, end - at));
    at = end + 1;
  }
  return lines;
}

std::vector<std::string> figure_ids(const ReportData& data) {
  std::vector<std::string> ids;
  for (const Figure& figure : all_figures(data)) ids.push_back(figure.id);
  return ids;
}

std::string html_table(const std::vector<std::vector<std::string>>& rows) {
  std::string s = "<table>\n";
  for (std::size_t r = 0; r < rows.size(); ++r) {
    s += "<tr>";
    for (const std::string& cell : rows[r])
      s += (r == 0 ? "<th>" : "<td>") + xml_escape(cell) + (r == 0 ? "</th>" : "</td>");
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

std::string html_page_head(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang='en'>\n<head>\n<meta charset='utf-8'>\n<title>" + xml_escape(title) +
         "</title>\n<style>body{font-family:sans-serif;max-width:1300px;margin:2em auto;padding:0 1em}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}"
         "th{background:#eee}svg{margin:4px;border:1px solid "
         "#eee}figure{display:inline-block;margin:4px;vertical-align:top}"
         "figcaption{font-size:12px;color:#444;width:0;min-width:100%}</style>\n"
         "</head>\n<body>\n<h1>" +
         xml_escape(title) + "</h1>\n";
}

std::string render_html(const ReportData& data) {
  std::string s = html_page_head(data.title) + "<ul>\n";
  for (const std::string& line : data.input_lines) s += "<li>" + xml_escape(line) + "</li>\n";
  for (const std::string& line : data.info_lines) s += "<li>" + xml_escape(line) + "</li>\n";
  s += "</ul>\n<h2>Table 1: accuracy per method</h2>\n" + html_table(table1_rows(data));
  if (!has_timings(data)) s += "<p>Stage times are not kept in result.json (it holds no wall-clock values).</p>\n";
  s += "<h2>Table 2: accuracy per axis</h2>\n" + html_table(table2_rows(data));
  if (data.identifiability.present) {
    const IdentifiabilityTable& id = data.identifiability;
    s += "<h2>Table 3: identifiability</h2>\n<p>" + std::to_string(id.estimated.size()) + " of " +
         std::to_string(id.free_count) + " free parameters estimated; condition number of the scaled Jacobian " +
         general(id.condition_before) + " over the free parameters, " + general(id.condition_after) +
         " over the estimated ones.</p>\n<p>Estimated: " + xml_escape(join(id.estimated)) + "</p>\n" +
         (id.dropped.empty() && id.fixed.empty() ? std::string() : html_table(identifiability_rows(id)));
  }
  s += outlier_html(data.outliers);
  if (data.cross_validation.present) {
    const CrossValidationTable& cv = data.cross_validation;
    s += "<h2>Cross-validation</h2>\n<p>" + std::to_string(cv.folds.size()) + " folds over " +
         std::to_string(cv.sample_count) + " samples (blunders left out); 3D MAE over every held-out sample " +
         um(cv.mae_3d_m) + " um (uncalibrated: " + um(cv.baseline_mae_3d_m) + " um).</p>\n" +
         html_table(cross_validation_rows(cv));
  }
  if (!data.parameters.empty()) {
    s += "<h2>Table 4: parameters (start, calibrated, change, sigma)</h2>\n" + html_table(parameter_rows(data));
  }
  s += "<h2>Figures</h2>\n";
  if (data.sample_total > 0) {
    s += "<p>The report keeps " + count_text(data.samples.size()) + " of the run's " + count_text(data.sample_total) +
         " samples, evenly spaced in the training and in the test samples: the figures are drawn from them, the "
         "tables are over every sample.</p>\n";
  }
  for (const Figure& figure : all_figures(data)) {
    const std::string note = figure.drawn.empty() ? "" : " " + figure.drawn;
    s += "<figure>\n" + figure.svg + "<figcaption>" + xml_escape(caption(figure.id) + note) +
         "</figcaption>\n</figure>\n";
  }
  return s + "</body>\n</html>\n";
}

}  // namespace hivecal::report
