// Coarse stage of the clock estimation: normalised cross-correlation of the two tool-speed
// profiles on a common 100 ms grid, searched over every lag with enough overlap.
#include <cmath>

#include "sync/clock_detail.hpp"
#include "hivecal/core/math.hpp"
#include "sync/stream_util.hpp"

namespace hivecal::detail {
namespace {

constexpr std::size_t kPeakCandidates = 16;  // local correlation maxima remembered
constexpr std::size_t kDecimation = 10;      // coarse steps per step of the global search

/// Pearson correlation accumulator.
struct Correlation {
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  void add(double x, double y) {
    n += 1.0;
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  double value() const {
    const double vx = n * sxx - sx * sx;
    const double vy = n * syy - sy * sy;
    if (!(vx > 0.0) || !(vy > 0.0)) return 0.0;
    return (n * sxy - sx * sy) / std::sqrt(vx * vy);
  }
};

/// A lag and its correlation.
struct Peak {
  std::ptrdiff_t lag = 0;
  double r = -2.0;
};

/// Two speed profiles on the same grid: tracker[i] pairs with robot[i + lag].
struct SpeedProfiles {
  const double* robot = nullptr;
  std::ptrdiff_t robot_count = 0;
  const double* tracker = nullptr;
  std::ptrdiff_t tracker_count = 0;

  /// Correlation over the known pairs at `lag`; -2 with fewer than `min_pairs` pairs.
  double correlation_at(std::ptrdiff_t lag, std::ptrdiff_t min_pairs) const {
    Correlation c;
    const std::ptrdiff_t lo = lag < 0 ? -lag : 0;
    const std::ptrdiff_t hi = tracker_count < robot_count - lag ? tracker_count : robot_count - lag;
    for (std::ptrdiff_t i = lo; i < hi; ++i) {
      const double x = tracker[i];
      const double y = robot[i + lag];
      if (math::is_finite(x) && math::is_finite(y)) c.add(x, y);
    }
    return c.n >= static_cast<double>(min_pairs) ? c.value() : -2.0;
  }
};

/// Keeps the best kPeakCandidates local maxima (ties: the earlier lag stays).
void remember_peak(Peak* peaks, const Peak& candidate) {
  std::size_t worst = 0;
  for (std::size_t i = 1; i < kPeakCandidates; ++i)
    if (peaks[i].r < peaks[worst].r) worst = i;
  if (candidate.r > peaks[worst].r) peaks[worst] = candidate;
}

/// The best lag in [first, last] and the best other local maximum outside its
/// half-height lobe (a second, similar peak means the alignment is ambiguous).
CoarseLag search_lags(const SpeedProfiles& speeds, std::ptrdiff_t first, std::ptrdiff_t last, std::ptrdiff_t min_pairs,
                      Peak* best) {
  Peak peaks[kPeakCandidates];
  double r_before = -2.0;
  double r_here = -2.0;
  for (std::ptrdiff_t lag = first; lag <= last + 1; ++lag) {
    const double r_next = lag <= last ? speeds.correlation_at(lag, min_pairs) : -2.0;
    if (lag > first && r_here >= r_before && r_here > r_next) remember_peak(peaks, Peak{lag - 1, r_here});
    if (lag <= last && r_next > best->r) *best = Peak{lag, r_next};
    r_before = r_here;
    r_here = r_next;
  }
  std::ptrdiff_t lobe_lo = best->lag;
  std::ptrdiff_t lobe_hi = best->lag;
  const double half = best->r / 2.0;
  while (lobe_lo > first && speeds.correlation_at(lobe_lo - 1, min_pairs) > half) --lobe_lo;
  while (lobe_hi < last && speeds.correlation_at(lobe_hi + 1, min_pairs) > half) ++lobe_hi;
  CoarseLag result;
  result.correlation = best->r;
  for (const Peak& p : peaks)
    if ((p.lag < lobe_lo || p.lag > lobe_hi) && p.r > result.runner_up) result.runner_up = p.r;
  return result;
}

/// Averages groups of `factor` values into out[] (may alias values; unknown unless half
/// of a group is known); returns the group count.
std::size_t decimate(const double* values, std::size_t count, std::size_t factor, double* out) {
  const std::size_t groups = count / factor;
  for (std::size_t g = 0; g < groups; ++g) {
    double sum = 0.0;
    std::size_t known = 0;
    for (std::size_t i = g * factor; i < (g + 1) * factor; ++i) {
      if (math::is_finite(values[i])) {
        sum += values[i];
        ++known;
      }
    }
    out[g] = 2 * known >= factor ? sum / static_cast<double>(known) : kUnknown;
  }
  return groups;
}

/// Robot speeds on the coarse grid [m/s] into out[]; returns the count.
std::size_t robot_speeds(const ClockProfiles& profiles, std::size_t knots_per_step, double step_s, double* out,
                         std::size_t capacity) {
  std::size_t count = profiles.robot_knots > 0 ? (profiles.robot_knots - 1) / knots_per_step : 0;
  if (count > capacity) count = capacity;
  for (std::size_t i = 0; i < count; ++i)
    out[i] = (profiles.robot_s_m[(i + 1) * knots_per_step] - profiles.robot_s_m[i * knots_per_step]) / step_s;
  return count;
}

/// Tracker path length at tracker-relative time t_us, walking `*m` forward; NaN across
/// intervals that are no chords.
double tracker_s_at(const ClockProfiles& profiles, double t_us, std::size_t* m) {
  const std::size_t n = profiles.tracker_points;
  while (*m + 2 < n && profiles.tracker[*m + 1].t_us <= t_us) ++*m;
  if (*m + 1 >= n) return kUnknown;
  const ClockTrackerKnot& a = profiles.tracker[*m];
  const ClockTrackerKnot& b = profiles.tracker[*m + 1];
  if (!profiles.chord_ok(*m, *m + 1) || t_us < a.t_us || t_us > b.t_us) return kUnknown;
  return a.s_m + (t_us - a.t_us) / (b.t_us - a.t_us) * (b.s_m - a.s_m);
}

/// Tracker speeds on the coarse grid [m/s] into out[]; returns the count.
std::size_t tracker_speeds(const ClockProfiles& profiles, double step_us, double* out, std::size_t capacity) {
  auto count = static_cast<std::size_t>(profiles.tracker_span_us() / step_us);
  if (count > capacity) count = capacity;
  std::size_t m = 0;
  double previous = tracker_s_at(profiles, 0.0, &m);
  for (std::size_t i = 0; i < count; ++i) {
    const double next = tracker_s_at(profiles, static_cast<double>(i + 1) * step_us, &m);
    out[i] = (next - previous) / (step_us * 1e-6);
    previous = next;
  }
  return count;
}

}  // namespace

Status coarse_lag(const ClockProfiles& profiles, const ClockSyncConfig& config, double* scratch,
                  std::size_t scratch_capacity, CoarseLag* result) {
  const double step_us = static_cast<double>(config.coarse_step_us);
  const std::size_t knots_per_step = config.coarse_step_us / config.knot_interval_us;
  const std::size_t n_robot = robot_speeds(profiles, knots_per_step, step_us * 1e-6, scratch, scratch_capacity);
  const std::size_t n_tracker = tracker_speeds(profiles, step_us, scratch + n_robot, scratch_capacity - n_robot);

  // Global search on the decimated profiles (in place at the front of scratch).
  const std::size_t d_robot = decimate(scratch, n_robot, kDecimation, scratch);
  const std::size_t d_tracker = decimate(scratch + n_robot, n_tracker, kDecimation, scratch + d_robot);
  const SpeedProfiles coarse{scratch, static_cast<std::ptrdiff_t>(d_robot), scratch + d_robot,
                             static_cast<std::ptrdiff_t>(d_tracker)};
  std::ptrdiff_t min_overlap =
      static_cast<std::ptrdiff_t>(config.min_overlap_us / (config.coarse_step_us * std::uint64_t{kDecimation}));
  const std::ptrdiff_t shorter = coarse.robot_count < coarse.tracker_count ? coarse.robot_count : coarse.tracker_count;
  if (min_overlap > shorter / 2) min_overlap = shorter / 2;
  if (min_overlap < 10) return Status::clock_fit_failed;
  Peak global;
  *result = search_lags(coarse, min_overlap - coarse.tracker_count, coarse.robot_count - min_overlap, min_overlap / 2,
                        &global);
  if (result->correlation < config.min_correlation ||
      result->runner_up > config.max_runner_up_ratio * result->correlation)
    return Status::clock_fit_failed;

  // Refine on the full-resolution coarse grid within two decimated steps.
  (void)robot_speeds(profiles, knots_per_step, step_us * 1e-6, scratch, scratch_capacity);
  (void)tracker_speeds(profiles, step_us, scratch + n_robot, scratch_capacity - n_robot);
  const SpeedProfiles fine{scratch, static_cast<std::ptrdiff_t>(n_robot), scratch + n_robot,
                           static_cast<std::ptrdiff_t>(n_tracker)};
  const auto factor = static_cast<std::ptrdiff_t>(kDecimation);
  Peak local;
  (void)search_lags(fine, (global.lag - 2) * factor, (global.lag + 2) * factor, min_overlap * factor / 2, &local);
  result->lag_us = static_cast<double>(local.lag) * step_us;
  return Status::ok;
}

}  // namespace hivecal::detail
