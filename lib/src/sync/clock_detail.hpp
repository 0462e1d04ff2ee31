// Internals of the clock estimation (library-private): a read-only view of the stored
// profiles and the three stages of estimate(): coarse lag, lag x drift scan, fine fit.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/sync/clock_sync.hpp"

namespace hivecal::detail {

/// The robot and tracker profiles as estimate() reads them.
struct ClockProfiles {
  const double* robot_s_m = nullptr;          ///< path length at robot_rel = j * knot_us [m]
  std::size_t robot_knots = 0;                ///< knots stored
  double knot_us = 1.0;                       ///< knot spacing [us]
  const ClockTrackerKnot* tracker = nullptr;  ///< valid tracker points, time since the first [us]
  std::size_t tracker_points = 0;             ///< points stored
  double max_chord_interval_us = 0.0;         ///< longer tracker intervals are not chords [us]
  double max_tracker_speed_m_per_us = 0.0;    ///< faster tracker intervals are a blunder's, not chords [m/us]

  /// Robot path length at a robot-relative time [m]; NaN outside the profile or in a gap.
  double s_at(double robot_rel_us) const;
  /// Robot tool speed at a robot-relative time (central difference over two knots) [m/us].
  double speed_at(double robot_rel_us) const;
  std::size_t chord_span = 1;  ///< tracker intervals per fine-fit chord (chords overlap: one ends at each point)

  /// True when no interval between tracker points first..last is longer than
  /// max_chord_interval_us or faster than max_tracker_speed_m_per_us (a wild point within the
  /// jump limits would otherwise weigh more than the whole track in both stages' sums).
  bool chord_ok(std::size_t first, std::size_t last) const {
    for (std::size_t k = first; k < last; ++k) {
      if (!interval_ok(k)) return false;
    }
    return true;
  }
  /// Whether tracker interval k (points k, k + 1) may be part of a chord (chord_ok).
  bool interval_ok(std::size_t k) const {
    const double dt_us = tracker[k + 1].t_us - tracker[k].t_us;
    return dt_us <= max_chord_interval_us && tracker[k + 1].s_m - tracker[k].s_m <= max_tracker_speed_m_per_us * dt_us;
  }
  /// Tracker time span of the profile [us].
  double tracker_span_us() const { return tracker_points > 0 ? tracker[tracker_points - 1].t_us : 0.0; }
};

/// Robot-relative time as a function of tracker-relative time.
struct LagDrift {
  double lag_us = 0.0;        ///< robot_rel - tracker_rel at reference_us [us]
  double drift = 0.0;         ///< rate difference [-]
  double reference_us = 0.0;  ///< tracker_rel time of lag_us [us]

  /// Robot-relative time of a tracker-relative time [us].
  double robot_rel_us(double tracker_rel_us) const {
    return tracker_rel_us + lag_us + drift * (tracker_rel_us - reference_us);
  }
};

/// Outcome of the coarse correlation.
struct CoarseLag {
  double lag_us = 0.0;       ///< best lag on the coarse grid [us]
  double correlation = 0.0;  ///< its normalised correlation [-]
  double runner_up = 0.0;    ///< best other peak outside the main lobe [-]
};

/// Coarse lag by correlating the speed profiles (global search on a 10x coarser grid,
/// then the coarse grid near it). Uses `scratch` for the speed profiles.
/// Errors: clock_fit_failed (too little overlap, weak or ambiguous peak).
Status coarse_lag(const ClockProfiles& profiles, const ClockSyncConfig& config, double* scratch,
                  std::size_t scratch_capacity, CoarseLag* result);

/// Best lag and drift on a grid around `center` (lag +-1.5 coarse steps, drift +-max_drift).
LagDrift scan_lag_drift(const ClockProfiles& profiles, const ClockSyncConfig& config, const LagDrift& center);

/// Outcome of the fine fit.
struct FineFit {
  LagDrift estimate;              ///< fitted relation
  double var_lag_us2 = 0.0;       ///< variance of lag_us [us^2]
  double var_drift = 0.0;         ///< variance of drift [-]
  double cov_lag_drift_us = 0.0;  ///< their covariance [us]
  double gain = 1.0;              ///< overall tracker/robot path-length ratio [-]
  double residual_rms_m = 0.0;    ///< rms chord residual [m]
  std::uint32_t chords = 0;       ///< chords used
  std::uint32_t edges = 0;        ///< informative chords
  std::uint32_t iterations = 0;   ///< Gauss-Newton iterations
};

/// Gauss-Newton on lag and drift with a free speed gain per block of chords (so that a
/// tool-model error, which scales the speed slowly along a move, does not bias the timing).
/// Errors: clock_fit_failed (singular, too few chords, no convergence to a finite value).
Status fit_lag_drift(const ClockProfiles& profiles, const ClockSyncConfig& config, const LagDrift& start,
                     FineFit* result);

}  // namespace hivecal::detail
