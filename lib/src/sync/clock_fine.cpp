// Fine stage of the clock estimation: the chord model
//   tracker_chord(a, b) = gain_block * (s_robot(map(b)) - s_robot(map(a)))
// scanned over lag x drift, then refined by Gauss-Newton with one free gain per block of
// chords (eliminated in closed form), weighted by a fitted residual-variance model.
#include <cmath>

#include "sync/clock_detail.hpp"
#include "hivecal/core/math.hpp"
#include "sync/stream_util.hpp"

namespace hivecal::detail {
namespace {

using Mat2 = Eigen::Matrix<double, 2, 2>;
using Vec2 = Eigen::Matrix<double, 2, 1>;

constexpr double kUsPerMs = 1000.0;
constexpr double kPpm = 1e-6;
constexpr double kHuberSigmas = 3.0;        // normalised residuals beyond this are down-weighted
constexpr std::size_t kMaxDriftSteps = 40;  // per side of the drift scan

/// One chord evaluated under a lag/drift: tracker chord y, robot path length c, and
/// dc/d(lag [ms], drift [ppm]).
struct Chord {
  double y_m = 0.0;
  double c_m = 0.0;
  Vec2 dc = Vec2::Zero();
  double speed_change_m_per_us = 0.0;
};

/// Evaluates the chord ending at tracker point k; false if the robot profile does not cover it.
bool evaluate_chord(const ClockProfiles& profiles, const LagDrift& map, std::size_t k, Chord* chord) {
  const ClockTrackerKnot& a = profiles.tracker[k - profiles.chord_span];
  const ClockTrackerKnot& b = profiles.tracker[k];
  const double ra = map.robot_rel_us(a.t_us);
  const double rb = map.robot_rel_us(b.t_us);
  chord->c_m = profiles.s_at(rb) - profiles.s_at(ra);
  const double va = profiles.speed_at(ra);
  const double vb = profiles.speed_at(rb);
  if (!math::is_finite(chord->c_m) || !math::is_finite(va) || !math::is_finite(vb)) return false;
  chord->y_m = b.s_m - a.s_m;
  chord->dc = Vec2((vb - va) * kUsPerMs, (vb * (b.t_us - map.reference_us) - va * (a.t_us - map.reference_us)) * kPpm);
  chord->speed_change_m_per_us = vb - va;
  return true;
}

/// Residual variance of a chord: floor + relative * c^2 (noise plus speed-model error).
struct NoiseModel {
  double floor_m2 = 1.0;  ///< [m^2]
  double relative = 0.0;  ///< [-]
  double variance(double c_m) const { return floor_m2 + relative * c_m * c_m; }
};

/// Normal equations in (lag [ms], drift [ppm]) after eliminating the block gains, and the
/// sums that fit the next noise model.
struct Normal {
  Mat2 normal = Mat2::Zero();
  Vec2 rhs = Vec2::Zero();
  double weighted_sse = 0.0;
  double sse_m2 = 0.0;
  double gain_num = 0.0, gain_den = 0.0;
  double n = 0.0, c2 = 0.0, c4 = 0.0, r2c2 = 0.0;
  std::uint32_t chords = 0, edges = 0, gain_blocks = 0;

  double gain() const { return gain_den > 0.0 ? gain_num / gain_den : 1.0; }
  /// Least squares of r^2 = floor + relative * c^2.
  NoiseModel noise_model() const {
    NoiseModel model;
    const double det = n * c4 - c2 * c2;
    model.relative = det > 0.0 ? (n * r2c2 - c2 * sse_m2) / det : 0.0;
    if (!(model.relative > 0.0)) model.relative = 0.0;
    model.floor_m2 = n > 0.0 ? (sse_m2 - model.relative * c2) / n : 0.0;
    const double least_m2 = n > 0.0 ? 1e-4 * sse_m2 / n : 0.0;  // keeps weights bounded
    if (!(model.floor_m2 > least_m2)) model.floor_m2 = least_m2 > 0.0 ? least_m2 : 1e-18;
    return model;
  }
};

/// Sums of the chords of one gain block (w: weight, y: tracker chord, c: robot length, D: dc).
struct GainBlock {
  Mat2 dd = Mat2::Zero();
  Vec2 dc = Vec2::Zero(), dy = Vec2::Zero();
  double cc = 0.0, cy = 0.0, yy = 0.0;
  double u_yy = 0.0, u_yc = 0.0, u_cc = 0.0, u_y2c2 = 0.0, u_yc3 = 0.0, u_c4 = 0.0, n = 0.0;
  double start_us = 0.0;

  void add(const Chord& chord, double w) {
    const double c = chord.c_m;
    const double y = chord.y_m;
    dd += w * (chord.dc * chord.dc.transpose());
    dc += (w * c) * chord.dc;
    dy += (w * y) * chord.dc;
    cc += w * c * c;
    cy += w * c * y;
    yy += w * y * y;
    u_yy += y * y;
    u_yc += y * c;
    u_cc += c * c;
    u_y2c2 += y * y * c * c;
    u_yc3 += y * c * c * c;
    u_c4 += c * c * c * c;
    n += 1.0;
  }

  /// Adds the block to `out` with its best gain eliminated (variable projection), then empties it.
  void close_into(Normal* out) {
    if (n > 0.0) {
      const double g = cc > 0.0 ? cy / cc : 0.0;
      if (cc > 0.0) {
        out->normal += (g * g) * (dd - dc * dc.transpose() / cc);
        out->rhs += g * (dy - g * dc);
        ++out->gain_blocks;
      }
      out->weighted_sse += yy - g * cy;
      out->sse_m2 += u_yy - 2.0 * g * u_yc + g * g * u_cc;
      out->r2c2 += u_y2c2 - 2.0 * g * u_yc3 + g * g * u_c4;
      out->c2 += u_cc;
      out->c4 += u_c4;
      out->n += n;
      out->gain_num += cy;
      out->gain_den += cc;
    }
    *this = GainBlock();
  }
};

/// Normal equations of all chords under `map`, weights from `noise` and a Huber clip on the
/// residual with the previous overall gain.
Normal accumulate(const ClockProfiles& profiles, const ClockSyncConfig& config, const LagDrift& map,
                  const NoiseModel& noise, double previous_gain, double huber_sigmas) {
  Normal out;
  GainBlock block;
  const double edge_m_per_us = config.edge_speed_change_m_s * 1e-6;
  bool block_open = false;
  for (std::size_t k = profiles.chord_span; k < profiles.tracker_points; ++k) {
    Chord chord;
    if (!profiles.chord_ok(k - profiles.chord_span, k) || !evaluate_chord(profiles, map, k, &chord)) {
      block.close_into(&out);  // a gain block never spans a hole
      block_open = false;
      continue;
    }
    const double t_us = profiles.tracker[k].t_us;
    if (!block_open || t_us - block.start_us > static_cast<double>(config.gain_block_us)) {
      block.close_into(&out);
      block.start_us = t_us;
      block_open = true;
    }
    const double variance = noise.variance(previous_gain * chord.c_m);
    const double z = std::fabs(chord.y_m - previous_gain * chord.c_m) / std::sqrt(variance);
    block.add(chord, (z <= huber_sigmas ? 1.0 : huber_sigmas / z) / variance);
    ++out.chords;
    if (std::fabs(chord.speed_change_m_per_us) > edge_m_per_us) ++out.edges;
  }
  block.close_into(&out);
  return out;
}

/// Inverse of a symmetric 2x2 matrix in closed form (Eigen's decompositions pull in heap
/// code paths on some targets); false unless positive definite.
bool invert_spd(const Mat2& m, Mat2* inverse) {
  const double det = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
  if (!(m(0, 0) > 0.0) || !(det > 0.0)) return false;
  *inverse << m(1, 1) / det, -m(0, 1) / det, -m(1, 0) / det, m(0, 0) / det;
  return true;
}

/// Mean squared residual with one best gain: the score of the lag x drift scan. One pass over
/// the points: each point's robot path length is computed once (it ends one chord and starts
/// another, chord_span points later: a ring of the last chord_span + 1) and each interval is
/// checked once (chord_ok, through the last bad interval), the sums in chord order.
double chord_cost(const ClockProfiles& profiles, const LagDrift& map) {
  const std::size_t span = profiles.chord_span;  // <= kMaxChordSpanPoints (config_ok)
  double path_m[kMaxChordSpanPoints + 1];        // path length of point i at i % (span + 1)
  std::size_t bad_end = 0;                       // one past the last bad interval; 0: none yet
  double sdc = 0.0, scc = 0.0, sdd = 0.0, n = 0.0;
  std::size_t slot = span;  // k % (span + 1), kept without a division
  for (std::size_t k = 0; k < profiles.tracker_points; ++k) {
    slot = slot == span ? 0 : slot + 1;
    path_m[slot] = profiles.s_at(map.robot_rel_us(profiles.tracker[k].t_us));
    if (k > 0 && !profiles.interval_ok(k - 1)) bad_end = k;
    if (k < span || bad_end + span > k) continue;  // no chord ends here, or one of its intervals is bad
    const std::size_t first = k - span;            // at slot + 1 (mod span + 1)
    const double c = path_m[slot] - path_m[slot == span ? 0 : slot + 1];
    if (!math::is_finite(c)) continue;
    const double d = profiles.tracker[k].s_m - profiles.tracker[first].s_m;
    sdc += d * c;
    scc += c * c;
    sdd += d * d;
    n += 1.0;
  }
  if (!(scc > 0.0)) return kUnknown;
  return (sdd - sdc * sdc / scc) / n;
}

}  // namespace

double ClockProfiles::s_at(double robot_rel_us) const {
  const double x = robot_rel_us / knot_us;
  if (!(x >= 0.0) || x >= static_cast<double>(robot_knots) - 1.0) return kUnknown;
  const auto j = static_cast<std::size_t>(x);
  const double u = x - static_cast<double>(j);
  return robot_s_m[j] + u * (robot_s_m[j + 1] - robot_s_m[j]);
}

double ClockProfiles::speed_at(double robot_rel_us) const {
  return (s_at(robot_rel_us + knot_us) - s_at(robot_rel_us - knot_us)) / (2.0 * knot_us);
}

LagDrift scan_lag_drift(const ClockProfiles& profiles, const ClockSyncConfig& config, const LagDrift& center) {
  // Drift steps that move the ends of the data by about one knot; lag steps of half a knot.
  const double half_span_us = profiles.tracker_span_us() / 2.0;
  double drift_step = half_span_us > 0.0 ? profiles.knot_us / half_span_us : config.max_drift;
  auto drift_steps = static_cast<std::ptrdiff_t>(drift_step > 0.0 ? config.max_drift / drift_step : 0.0);
  if (drift_steps > static_cast<std::ptrdiff_t>(kMaxDriftSteps)) {
    drift_steps = static_cast<std::ptrdiff_t>(kMaxDriftSteps);
    drift_step = config.max_drift / static_cast<double>(kMaxDriftSteps);
  }
  const double lag_step_us = profiles.knot_us / 2.0;
  const auto lag_steps = static_cast<std::ptrdiff_t>(1.5 * static_cast<double>(config.coarse_step_us) / lag_step_us);
  LagDrift best = center;
  double best_cost = kUnknown;
  for (std::ptrdiff_t i = -drift_steps; i <= drift_steps; ++i) {
    for (std::ptrdiff_t j = -lag_steps; j <= lag_steps; ++j) {
      const LagDrift candidate{center.lag_us + static_cast<double>(j) * lag_step_us,
                               center.drift + static_cast<double>(i) * drift_step, center.reference_us};
      const double cost = chord_cost(profiles, candidate);
      if (math::is_finite(cost) && (!math::is_finite(best_cost) || cost < best_cost)) {
        best_cost = cost;
        best = candidate;
      }
    }
  }
  return best;
}

Status fit_lag_drift(const ClockProfiles& profiles, const ClockSyncConfig& config, const LagDrift& start,
                     FineFit* result) {
  LagDrift map = start;
  constexpr double kNoHuber = 1e300;
  Normal normal = accumulate(profiles, config, map, NoiseModel(), 1.0, kNoHuber);
  std::uint32_t iterations = 0;
  while (iterations < config.max_iterations) {
    const NoiseModel noise = normal.noise_model();
    const double gain = normal.gain();
    Mat2 inverse;
    if (normal.chords < 3 || !invert_spd(normal.normal, &inverse)) return Status::clock_fit_failed;
    const Vec2 step = inverse * normal.rhs;
    if (!all_finite(step)) return Status::clock_fit_failed;
    map.lag_us += step(0) * kUsPerMs;
    map.drift += step(1) * kPpm;
    normal = accumulate(profiles, config, map, noise, gain, kHuberSigmas);
    ++iterations;
    if (std::fabs(step(0)) < 1e-5 && std::fabs(step(1)) < 1e-4) break;  // 0.01 us, 1e-4 ppm
  }
  Mat2 inverse;
  const double dof = normal.n - 2.0 - static_cast<double>(normal.gain_blocks);
  if (normal.chords < 3 || !invert_spd(normal.normal, &inverse) || !(dof > 0.0)) return Status::clock_fit_failed;
  const Mat2 covariance = (normal.weighted_sse / dof) * inverse;
  result->estimate = map;
  result->var_lag_us2 = covariance(0, 0) * kUsPerMs * kUsPerMs;
  result->var_drift = covariance(1, 1) * kPpm * kPpm;
  result->cov_lag_drift_us = covariance(0, 1) * kUsPerMs * kPpm;
  result->gain = normal.gain();
  result->residual_rms_m = std::sqrt(normal.sse_m2 / normal.n);
  result->chords = normal.chords;
  result->edges = normal.edges;
  result->iterations = iterations;
  return Status::ok;
}

}  // namespace hivecal::detail
