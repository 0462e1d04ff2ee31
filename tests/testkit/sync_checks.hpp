// Bit equality of what the capture passes produce (clock fits, datasets), for the tests that
// compare two ways to the same result. Header-only, lib/ only.
#pragma once

#include <cstring>

#include "hivecal/model/dataset.hpp"
#include "hivecal/sync/clock_sync.hpp"

namespace hivecal::test {

/// Every estimated value of two clock fits has the same bits, and the same counts.
inline bool same_fit(const ClockFit& a, const ClockFit& b) {
  const double av[] = {a.offset_us,
                       a.drift,
                       a.reference_tracker_us,
                       a.offset_at_reference_us,
                       a.sigma_offset_at_reference_us,
                       a.sigma_drift,
                       a.sigma_offset_us,
                       a.speed_gain,
                       a.residual_rms_m,
                       a.coarse_correlation,
                       a.runner_up_correlation};
  const double bv[] = {b.offset_us,
                       b.drift,
                       b.reference_tracker_us,
                       b.offset_at_reference_us,
                       b.sigma_offset_at_reference_us,
                       b.sigma_drift,
                       b.sigma_offset_us,
                       b.speed_gain,
                       b.residual_rms_m,
                       b.coarse_correlation,
                       b.runner_up_correlation};
  return std::memcmp(av, bv, sizeof av) == 0 && a.chords_used == b.chords_used && a.edge_chords == b.edge_chords &&
         a.iterations == b.iterations;
}

/// The same samples in the same order, joints and points bit for bit.
inline bool same_samples(const DatasetBase& a, const DatasetBase& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Sample& x = a.samples()[i];
    const Sample& y = b.samples()[i];
    if (std::memcmp(x.q_rad.data(), y.q_rad.data(), sizeof(double) * kSixJoints) != 0) return false;
    if (std::memcmp(x.point_m.data(), y.point_m.data(), sizeof(double) * 3) != 0) return false;
  }
  return true;
}

}  // namespace hivecal::test
