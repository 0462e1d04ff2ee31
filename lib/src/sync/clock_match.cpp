// What a clock fit matched, for plotting: the fine fit's chords (tracker point k - span to
// k) under the fitted relation, averaged in time-uniform bins. Reads the stored profiles
// only, so estimate() and its bits are unaffected.
#include "hivecal/core/math.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "sync/clock_detail.hpp"

namespace hivecal {
namespace {

/// Running sums of the chords of one bin.
struct BinSums {
  double t_us = 0.0, robot = 0.0, tracker = 0.0, residual = 0.0;
  std::uint32_t chords = 0;

  /// Appends the means to `match` (if any chord) and empties the sums.
  void flush(ClockMatch* match) {
    if (chords > 0) {
      const double n = static_cast<double>(chords);
      match->bins[match->count++] =
          ClockMatchBin{t_us / n / math::kUsPerS, robot / n, tracker / n, residual / n, chords};
    }
    *this = BinSums();
  }
};

}  // namespace

Status ClockEstimatorBase::match_profiles(const ClockFit& fit, std::size_t bins, ClockMatch* match) const {
  if (match == nullptr || bins == 0 || bins > kClockMatchBins) return Status::invalid_argument;
  const detail::ClockProfiles view = profiles();
  if (!tracker_started_ || !robot_started_ || view.tracker_points <= view.chord_span || !(view.tracker_span_us() > 0.0))
    return Status::clock_fit_failed;
  match->count = 0;
  match->tracker_t0_us = static_cast<double>(tracker_t0_us_);
  const double robot_t0_us = static_cast<double>(robot_t0_us_);
  const double bin_us = view.tracker_span_us() / static_cast<double>(bins);
  BinSums sums;
  std::size_t current = 0;
  for (std::size_t k = view.chord_span; k < view.tracker_points; ++k) {
    const ClockTrackerKnot& a = view.tracker[k - view.chord_span];
    const ClockTrackerKnot& b = view.tracker[k];
    if (!view.chord_ok(k - view.chord_span, k)) continue;
    const double c_m = view.s_at(fit.robot_us(match->tracker_t0_us + b.t_us) - robot_t0_us) -
                       view.s_at(fit.robot_us(match->tracker_t0_us + a.t_us) - robot_t0_us);
    if (!math::is_finite(c_m)) continue;  // outside the robot profile or across a robot gap
    const double mid_us = 0.5 * (a.t_us + b.t_us);
    auto bin = static_cast<std::size_t>(mid_us / bin_us);
    if (bin >= bins) bin = bins - 1;
    if (bin != current) sums.flush(match);
    current = bin;
    const double per_s = math::kUsPerS / (b.t_us - a.t_us);
    const double robot = c_m * per_s;
    const double tracker = (b.s_m - a.s_m) * per_s;
    sums.t_us += mid_us;
    sums.robot += robot;
    sums.tracker += tracker;
    sums.residual += tracker - fit.speed_gain * robot;
    ++sums.chords;
  }
  sums.flush(match);
  return match->count > 0 ? Status::ok : Status::clock_fit_failed;
}

}  // namespace hivecal
