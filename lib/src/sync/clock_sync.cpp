#include "hivecal/sync/clock_sync.hpp"

#include <cmath>

#include "sync/clock_detail.hpp"
#include "sync/stream_util.hpp"

namespace hivecal {

ClockSyncConfig make_clock_sync_config(const RobotModel& speed_model) {
  ClockSyncConfig config;
  config.speed_model = speed_model;
  return config;
}

ClockEstimatorBase::ClockEstimatorBase(const ClockSyncConfig& config, double* robot_knots_m, std::size_t robot_capacity,
                                       ClockTrackerKnot* tracker_knots, std::size_t tracker_capacity, double* scratch,
                                       std::size_t scratch_capacity)
    : config_(config),
      robot_knots_m_(robot_knots_m),
      robot_capacity_(robot_capacity),
      tracker_knots_(tracker_knots),
      tracker_capacity_(tracker_capacity),
      scratch_(scratch),
      scratch_capacity_(scratch_capacity) {}

void ClockEstimatorBase::reset() {
  stats_ = ClockProfileStats();
  robot_started_ = false;
  tracker_started_ = false;
  held_count_ = 0;
}

void ClockEstimatorBase::reset(const ClockSyncConfig& config) {
  reset();
  config_ = config;
}

bool ClockEstimatorBase::config_ok() const {
  const ClockSyncConfig& c = config_;
  return c.knot_interval_us > 0 && c.coarse_step_us >= 2 * c.knot_interval_us && c.max_tool_speed_m_s > 0.0 &&
         c.reanchor_points >= 2 && c.reanchor_points <= kMaxHeldTrackerPoints &&
         c.coarse_step_us % c.knot_interval_us == 0 && c.max_chord_interval_us > 0 && c.max_drift >= 0.0 &&
         c.max_drift < 0.01 && c.min_correlation > 0.0 && c.min_correlation <= 1.0 && c.max_runner_up_ratio > 0.0 &&
         c.max_iterations > 0 && c.chord_span_points > 0 && c.chord_span_points <= kMaxChordSpanPoints &&
         c.gain_block_us > 0;
}

void ClockEstimatorBase::push_robot(const JointStateRecord& record) {
  ++stats_.robot_records;
  const JointVector q = detail::joints_of(record);
  if (record.joint_count != config_.speed_model.joint_count) {
    ++stats_.robot_rejected;
    ++stats_.robot_joint_count_mismatches;
    return;
  }
  if (!all_finite(q) || (robot_started_ && record.timestamp_us <= robot_last_us_)) {
    ++stats_.robot_rejected;
    return;
  }
  const Vec3 point = fk_tool_point(config_.speed_model, q);
  if (!robot_started_) {
    robot_started_ = true;
    robot_t0_us_ = record.timestamp_us;
    robot_last_s_m_ = 0.0;
    if (robot_capacity_ > 0) robot_knots_m_[stats_.robot_knots++] = 0.0;
  } else {
    const std::uint64_t dt_us = record.timestamp_us - robot_last_us_;
    const bool gap = dt_us > config_.max_robot_gap_us;
    if (gap) ++stats_.robot_gaps;
    const double s_m = robot_last_s_m_ + (point - robot_last_point_m_).norm();
    // Knots falling in (last, now]: linear in time; unknown across a gap.
    while (stats_.robot_knots < robot_capacity_) {
      const std::uint64_t knot_us =
          robot_t0_us_ + static_cast<std::uint64_t>(stats_.robot_knots) * config_.knot_interval_us;
      if (knot_us > record.timestamp_us) break;
      const double u = static_cast<double>(knot_us - robot_last_us_) / static_cast<double>(dt_us);
      robot_knots_m_[stats_.robot_knots++] = gap ? detail::kUnknown : robot_last_s_m_ + u * (s_m - robot_last_s_m_);
    }
    if (stats_.robot_knots == robot_capacity_) ++stats_.robot_beyond_capacity;
    robot_last_s_m_ = s_m;
  }
  robot_last_us_ = record.timestamp_us;
  robot_last_point_m_ = point;
  stats_.robot_first_us = robot_t0_us_;
  stats_.robot_last_us = robot_last_us_;
  stats_.robot_path_m = robot_last_s_m_;
}

void ClockEstimatorBase::push_tracker(const TrackerPointRecord& record) {
  ++stats_.tracker_records;
  const Vec3 point = detail::point_of(record);
  if (!record.is_valid() || !all_finite(point)) {
    ++stats_.tracker_not_valid;
    return;
  }
  if (tracker_started_ && record.timestamp_us <= tracker_newest_us_) {
    ++stats_.tracker_rejected;
    return;
  }
  tracker_newest_us_ = record.timestamp_us;
  const bool fits_stored =
      !tracker_started_ || plausible_move(tracker_last_us_, tracker_last_point_m_, record.timestamp_us, point);
  if (held_count_ == 0 && fits_stored) {
    store_tracker_point(record.timestamp_us, point);
    return;
  }
  // A jump no tool makes is held until the following points judge it: the track resuming
  // where it was sets the held points aside as blunders; a run of consistent points means
  // the stored point before them was the odd one (the track moved on). After a gap (a beam
  // loss) a point may be within reach of both: the one it is nearer to in speed goes on.
  const ClockHeldPoint* held = held_count_ > 0 ? &held_[held_count_ - 1] : nullptr;
  const bool fits_held =
      held != nullptr && plausible_move(held->timestamp_us, held->point_m, record.timestamp_us, point);
  const bool resumes =
      fits_stored && (!fits_held || speed_m_s(tracker_last_us_, tracker_last_point_m_, record.timestamp_us, point) <=
                                        speed_m_s(held->timestamp_us, held->point_m, record.timestamp_us, point));
  if (resumes) {
    set_aside_held();
    store_tracker_point(record.timestamp_us, point);
    return;
  }
  if (!fits_held) set_aside_held();
  held_[held_count_++] = ClockHeldPoint{record.timestamp_us, point};
  if (held_count_ >= config_.reanchor_points) {
    for (std::uint32_t k = 0; k < held_count_; ++k) store_tracker_point(held_[k].timestamp_us, held_[k].point_m);
    held_count_ = 0;
  }
}

double ClockEstimatorBase::speed_m_s(std::uint64_t from_us, const Vec3& from_m, std::uint64_t to_us, const Vec3& to_m) {
  return (to_m - from_m).norm() / (static_cast<double>(to_us - from_us) * 1e-6);
}

bool ClockEstimatorBase::plausible_move(std::uint64_t from_us, const Vec3& from_m, std::uint64_t to_us,
                                        const Vec3& to_m) const {
  const double dt_s = static_cast<double>(to_us - from_us) * 1e-6;
  return (to_m - from_m).norm() <= config_.max_tool_speed_m_s * dt_s;
}

void ClockEstimatorBase::set_aside_held() {
  for (std::uint32_t k = 0; k < held_count_; ++k) {
    if (stats_.tracker_set_aside < kClockSetAsideLog)
      stats_.set_aside_tracker_us[stats_.tracker_set_aside] = held_[k].timestamp_us;
    ++stats_.tracker_set_aside;
  }
  held_count_ = 0;
}

void ClockEstimatorBase::store_tracker_point(std::uint64_t timestamp_us, const Vec3& point_m) {
  if (!tracker_started_) {
    tracker_started_ = true;
    tracker_t0_us_ = timestamp_us;
    tracker_last_s_m_ = 0.0;
  } else {
    tracker_last_s_m_ += (point_m - tracker_last_point_m_).norm();
  }
  if (stats_.tracker_points < tracker_capacity_) {
    tracker_knots_[stats_.tracker_points++] =
        ClockTrackerKnot{static_cast<double>(timestamp_us - tracker_t0_us_), tracker_last_s_m_};
  } else {
    ++stats_.tracker_beyond_capacity;
  }
  tracker_last_us_ = timestamp_us;
  tracker_last_point_m_ = point_m;
  stats_.tracker_first_us = tracker_t0_us_;
  stats_.tracker_last_us = tracker_last_us_;
  stats_.tracker_path_m = tracker_last_s_m_;
}

namespace {

/// The public ClockFit of a fine fit, on the absolute clocks (robot_t0_us, tracker_t0_us: the
/// first record of each profile).
ClockFit to_clock_fit(const detail::FineFit& fine, const detail::CoarseLag& coarse, std::uint64_t robot_t0_us,
                      std::uint64_t tracker_t0_us_abs) {
  // Re-express the offset at the tracker time where it is uncorrelated with the drift.
  const double shift_us = fine.var_drift > 0.0 ? -fine.cov_lag_drift_us / fine.var_drift : 0.0;
  const double var_ref_us2 = fine.var_lag_us2 + fine.cov_lag_drift_us * shift_us;
  const double reference_rel_us = fine.estimate.reference_us + shift_us;
  const double tracker_t0_us = detail::us_to_double(tracker_t0_us_abs);
  ClockFit fit;
  fit.drift = fine.estimate.drift;
  fit.reference_tracker_us = tracker_t0_us + reference_rel_us;
  fit.offset_at_reference_us = detail::us_to_double(robot_t0_us) - tracker_t0_us +
                               fine.estimate.robot_rel_us(reference_rel_us) - reference_rel_us;
  fit.sigma_offset_at_reference_us = std::sqrt(var_ref_us2 > 0.0 ? var_ref_us2 : 0.0);
  fit.sigma_drift = std::sqrt(fine.var_drift);
  fit.offset_us = fit.offset_at_reference_us - fit.drift * fit.reference_tracker_us;
  fit.sigma_offset_us = std::sqrt(fit.sigma_offset_at_reference_us * fit.sigma_offset_at_reference_us +
                                  fit.reference_tracker_us * fit.reference_tracker_us * fine.var_drift);
  fit.speed_gain = fine.gain;
  fit.residual_rms_m = fine.residual_rms_m;
  fit.coarse_correlation = coarse.correlation;
  fit.runner_up_correlation = coarse.runner_up;
  fit.chords_used = fine.chords;
  fit.edge_chords = fine.edges;
  fit.iterations = fine.iterations;
  return fit;
}

}  // namespace

detail::ClockProfiles ClockEstimatorBase::profiles() const {
  detail::ClockProfiles view;
  view.robot_s_m = robot_knots_m_;
  view.robot_knots = stats_.robot_knots;
  view.knot_us = static_cast<double>(config_.knot_interval_us);
  view.tracker = tracker_knots_;
  view.tracker_points = stats_.tracker_points;
  view.max_chord_interval_us = static_cast<double>(config_.max_chord_interval_us);
  // The tracker sees the tool the robot moves: twice the robot's top speed (the speed model's
  // tool may be off the true reflector) plus 0.1 m/s (noise at rest) bounds every interval.
  double top_m_per_us = 0.0;
  for (std::size_t j = 0; j + 1 < stats_.robot_knots; ++j) {
    const double step_m = robot_knots_m_[j + 1] - robot_knots_m_[j];
    if (step_m > top_m_per_us * view.knot_us) top_m_per_us = step_m / view.knot_us;  // NaN (a gap) compares false
  }
  view.max_tracker_speed_m_per_us = 2.0 * top_m_per_us + 0.1e-6;
  view.chord_span = config_.chord_span_points;
  return view;
}

Status ClockEstimatorBase::estimate(ClockFit* fit) {
  if (!config_ok()) return Status::invalid_argument;
  set_aside_held();  // a jump that never came back nor went on: the last points were blunders
  if (stats_.robot_joint_count_mismatches > 0) return Status::joint_count_mismatch;
  if (stats_.robot_knots < 4 || stats_.tracker_points < 4) return Status::clock_fit_failed;
  const detail::ClockProfiles view = profiles();
  detail::CoarseLag coarse;
  const Status coarse_status = detail::coarse_lag(view, config_, scratch_, scratch_capacity_, &coarse);
  if (coarse_status != Status::ok) return coarse_status;
  const detail::LagDrift center{coarse.lag_us, 0.0, view.tracker_span_us() / 2.0};
  detail::FineFit fine;
  const Status fine_status = detail::fit_lag_drift(view, config_, detail::scan_lag_drift(view, config_, center), &fine);
  if (fine_status != Status::ok) return fine_status;
  if (fine.edges < config_.min_edge_chords || std::fabs(fine.estimate.drift) > config_.max_drift ||
      !(fine.gain > 0.5 && fine.gain < 2.0))
    return Status::clock_fit_failed;
  *fit = to_clock_fit(fine, coarse, robot_t0_us_, tracker_t0_us_);
  return Status::ok;
}

}  // namespace hivecal
