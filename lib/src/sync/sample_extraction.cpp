#include "hivecal/sync/sample_extraction.hpp"

#include "hivecal/core/math.hpp"
#include "sync/stream_util.hpp"

namespace hivecal {
namespace {

/// Largest speed [m/s] over pairs of samples first..last that are at least `baseline_us`
/// apart (each pair as short as possible); -1 when no pair spans the baseline.
/// `time_us(i)` and `point_m(i)` read sample i.
template <typename TimeAt, typename PointAt>
double max_baseline_speed(std::size_t first, std::size_t last, double baseline_us, TimeAt time_us, PointAt point_m) {
  double fastest = -1.0;
  std::size_t j = first;
  for (std::size_t i = first; i <= last; ++i) {
    if (j <= i) j = i + 1;
    while (j <= last && time_us(j) - time_us(i) < baseline_us) ++j;
    if (j > last) break;
    const double speed = (point_m(j) - point_m(i)).norm() / (time_us(j) - time_us(i)) * math::kUsPerS;
    if (speed > fastest) fastest = speed;
  }
  return fastest;
}

}  // namespace

/// The robot ring indices bracketing a window, and the speed found over them.
struct SampleExtractorBase::Window {
  std::size_t first = 0;  ///< last entry at or before the window start
  std::size_t last = 0;   ///< first entry at or after the window end
  double speed_m_s = 0.0;
};

const char* drop_reason_name(DropReason reason) {
  switch (reason) {
    case DropReason::beam_lost: return "beam_lost";
    case DropReason::unstable: return "unstable";
    case DropReason::bad_status: return "bad_status";
    case DropReason::non_finite_point: return "non_finite_point";
    case DropReason::out_of_order: return "out_of_order";
    case DropReason::outside_robot_range: return "outside_robot_range";
    case DropReason::robot_history_overrun: return "robot_history_overrun";
    case DropReason::robot_gap: return "robot_gap";
    case DropReason::window_incomplete: return "window_incomplete";
    case DropReason::moving_robot: return "moving_robot";
    case DropReason::moving_tracker: return "moving_tracker";
    case DropReason::backlog_overrun: return "backlog_overrun";
    case DropReason::dataset_full: return "dataset_full";
  }
  return "unknown";
}

ExtractionConfig make_extraction_config(const RobotModel& speed_model) {
  ExtractionConfig config;
  config.speed_model = speed_model;
  return config;
}

std::uint64_t ExtractionCounts::dropped_total() const {
  std::uint64_t total = 0;
  for (const std::uint64_t n : dropped) total += n;
  return total;
}

SampleExtractorBase::SampleExtractorBase(const ExtractionConfig& config, const ClockFit& clock, DatasetBase* dataset,
                                         ExtractorRobotEntry* robot_storage, std::size_t robot_capacity,
                                         ExtractorTrackerEntry* tracker_storage, std::size_t tracker_capacity)
    : config_(config),
      clock_(clock),
      dataset_(dataset),
      robot_(robot_storage, robot_capacity),
      tracker_(tracker_storage, tracker_capacity) {}

void SampleExtractorBase::reset(const ExtractionConfig& config, const ClockFit& clock, DatasetBase* dataset) {
  config_ = config;
  clock_ = clock;
  dataset_ = dataset;
  observer_ = nullptr;
  robot_.clear();
  tracker_.clear();
  tracker_decided_ = 0;
  counts_ = ExtractionCounts();
  robot_started_ = false;
  tracker_started_ = false;
}

double SampleExtractorBase::robot_half_span_us() const {
  const std::uint32_t span_us =
      config_.window_us > config_.speed_baseline_us ? config_.window_us : config_.speed_baseline_us;
  return 0.5 * static_cast<double>(span_us);
}

bool SampleExtractorBase::config_ok() const {
  return dataset_ != nullptr && robot_.capacity() >= 2 && tracker_.capacity() >= 2 && config_.max_speed_m_s > 0.0 &&
         config_.speed_baseline_us > 0 && (config_.window_us == 0 || config_.speed_baseline_us <= config_.window_us) &&
         config_.max_robot_gap_us > 0 && config_.max_tracker_gap_us > 0 &&
         math::is_finite(clock_.offset_at_reference_us) && math::is_finite(clock_.drift) &&
         math::is_finite(clock_.reference_tracker_us);
}

Status SampleExtractorBase::drop(double tracker_us, DropReason reason) {
  ++counts_.dropped[static_cast<int>(reason)];
  if (observer_ != nullptr) observer_->on_drop(static_cast<std::uint64_t>(tracker_us), reason);
  return reason == DropReason::dataset_full ? Status::dataset_full : Status::ok;
}

Status SampleExtractorBase::push_robot(const JointStateRecord& record) {
  if (!config_ok()) return Status::invalid_argument;
  ++counts_.robot_records;
  if (record.joint_count != config_.speed_model.joint_count) return Status::joint_count_mismatch;
  const JointVector q = detail::joints_of(record);
  const double t_us = detail::us_to_double(record.timestamp_us);
  if (!all_finite(q) || (robot_started_ && !(t_us > robot_latest_us_))) {
    ++counts_.robot_rejected;
    return Status::ok;
  }
  if (!robot_started_) {
    robot_started_ = true;
    robot_first_us_ = t_us;
  }
  robot_latest_us_ = t_us;
  robot_.push(
      ExtractorRobotEntry{t_us, q, fk_tool_point(config_.speed_model, q)});  // the oldest may go: see check_robot
  return drain(false);
}

Status SampleExtractorBase::push_tracker(const TrackerPointRecord& record) {
  if (!config_ok()) return Status::invalid_argument;
  ++counts_.tracker_points;
  const double t_us = detail::us_to_double(record.timestamp_us);
  if (tracker_started_ && !(t_us > tracker_latest_us_)) return drop(t_us, DropReason::out_of_order);
  tracker_started_ = true;
  tracker_latest_us_ = t_us;
  Status status = Status::ok;
  const Vec3 point = detail::point_of(record);
  if (record.status == static_cast<std::uint8_t>(TrackerStatus::beam_lost)) {
    status = drop(t_us, DropReason::beam_lost);
  } else if (record.status == static_cast<std::uint8_t>(TrackerStatus::unstable)) {
    status = drop(t_us, DropReason::unstable);
  } else if (!record.is_valid()) {
    status = drop(t_us, DropReason::bad_status);
  } else if (!all_finite(point)) {
    status = drop(t_us, DropReason::non_finite_point);
  } else {
    if (tracker_.full()) {
      // The oldest entry leaves the ring: mere window context, or a point never decided.
      if (tracker_decided_ > 0) {
        --tracker_decided_;
      } else {
        status = drop(tracker_[0].t_us, DropReason::backlog_overrun);
      }
    }
    tracker_.push(ExtractorTrackerEntry{t_us, point});
  }
  const Status drained = drain(false);
  return status != Status::ok ? status : drained;
}

Status SampleExtractorBase::finish() {
  if (!config_ok()) return Status::invalid_argument;
  return drain(true);
}

bool SampleExtractorBase::ready(const ExtractorTrackerEntry& entry) const {
  const double half_us = robot_half_span_us();
  const bool tracker_done = tracker_latest_us_ >= entry.t_us + half_us;
  const bool robot_done = robot_started_ && robot_latest_us_ >= clock_.robot_us(entry.t_us) + half_us;
  return tracker_done && robot_done;
}

Status SampleExtractorBase::drain(bool finishing) {
  Status result = Status::ok;
  while (tracker_decided_ < tracker_.size()) {
    const ExtractorTrackerEntry& entry = tracker_[tracker_decided_];
    if (!finishing && !ready(entry)) break;
    const Status status = decide(entry);
    if (status != Status::ok) result = status;
    ++tracker_decided_;
  }
  return result;
}

std::size_t SampleExtractorBase::robot_index_at_or_before(double t_us) const {
  // Binary search over the time-ordered ring; the caller ensures front().t_us <= t_us.
  std::size_t lo = 0;
  std::size_t hi = robot_.size() - 1;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo + 1) / 2;
    if (robot_[mid].t_us <= t_us) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  return lo;
}

bool SampleExtractorBase::check_robot(double robot_us, Window* window, DropReason* reason) const {
  // Without a window this is the central difference over the baseline at the instant: the
  // only pairs of records at least a baseline apart bracket it.
  const double half_us = robot_half_span_us();
  if (!robot_started_ || robot_us < robot_first_us_ || robot_us > robot_latest_us_) {
    *reason = DropReason::outside_robot_range;
  } else if (robot_us - half_us < robot_first_us_ || robot_latest_us_ < robot_us + half_us) {
    *reason = DropReason::window_incomplete;
  } else if (robot_.front().t_us > robot_us - half_us) {
    *reason = DropReason::robot_history_overrun;  // it was there, but the ring forgot it
  } else {
    window->first = robot_index_at_or_before(robot_us - half_us);
    window->last = robot_index_at_or_before(robot_us + half_us);
    if (robot_[window->last].t_us < robot_us + half_us) ++window->last;
    const double max_gap_us = static_cast<double>(config_.max_robot_gap_us);
    for (std::size_t i = window->first; i < window->last; ++i) {
      if (robot_[i + 1].t_us - robot_[i].t_us > max_gap_us) {
        *reason = DropReason::robot_gap;
        return false;
      }
    }
    window->speed_m_s =
        config_.window_us > 0
            ? max_baseline_speed(
                  window->first, window->last, static_cast<double>(config_.speed_baseline_us),
                  [this](std::size_t i) { return robot_[i].t_us; }, [this](std::size_t i) { return robot_[i].tool_m; })
            : speed_at_instant(robot_us);
    if (!(window->speed_m_s <= config_.max_speed_m_s)) {
      *reason = window->speed_m_s < 0.0 ? DropReason::window_incomplete : DropReason::moving_robot;
      return false;
    }
    return true;
  }
  return false;
}

SampleExtractorBase::RobotBracket SampleExtractorBase::bracket_at(double robot_us) const {
  RobotBracket bracket;
  bracket.before = robot_index_at_or_before(robot_us);
  bracket.after = bracket.before + 1 < robot_.size() ? bracket.before + 1 : bracket.before;
  const double t0_us = robot_[bracket.before].t_us;
  const double t1_us = robot_[bracket.after].t_us;
  bracket.fraction = t1_us > t0_us ? (robot_us - t0_us) / (t1_us - t0_us) : 0.0;
  return bracket;
}

Vec3 SampleExtractorBase::tool_at(double robot_us) const {
  const RobotBracket at = bracket_at(robot_us);
  const Vec3& a = robot_[at.before].tool_m;
  return a + at.fraction * (robot_[at.after].tool_m - a);
}

double SampleExtractorBase::speed_at_instant(double robot_us) const {
  // The slower of the backward and the forward difference over half the baseline each: at
  // the edge of a pause one side is still, as the tool is at that instant; in a move both
  // sides see its speed.
  const double half_us = 0.5 * static_cast<double>(config_.speed_baseline_us);
  const Vec3 here_m = tool_at(robot_us);
  const double backward_m = (here_m - tool_at(robot_us - half_us)).norm();
  const double forward_m = (tool_at(robot_us + half_us) - here_m).norm();
  return (backward_m < forward_m ? backward_m : forward_m) / half_us * math::kUsPerS;
}

bool SampleExtractorBase::check_tracker(const ExtractorTrackerEntry& entry, double* speed_m_s,
                                        DropReason* reason) const {
  const double half_us = 0.5 * static_cast<double>(config_.window_us);
  const double max_gap_us = static_cast<double>(config_.max_tracker_gap_us);
  std::size_t first = 0;
  while (first < tracker_.size() && tracker_[first].t_us < entry.t_us - half_us) ++first;
  std::size_t last = first;
  while (last + 1 < tracker_.size() && tracker_[last + 1].t_us <= entry.t_us + half_us) ++last;
  // Covered: valid points near both ends and no dropout longer than max_gap_us between them.
  bool covered = tracker_[first].t_us - (entry.t_us - half_us) <= max_gap_us &&
                 (entry.t_us + half_us) - tracker_[last].t_us <= max_gap_us;
  for (std::size_t i = first; covered && i < last; ++i) covered = tracker_[i + 1].t_us - tracker_[i].t_us <= max_gap_us;
  if (covered) {
    *speed_m_s = max_baseline_speed(
        first, last, static_cast<double>(config_.speed_baseline_us), [this](std::size_t i) { return tracker_[i].t_us; },
        [this](std::size_t i) { return tracker_[i].point_m; });
  }
  if (!covered || !(*speed_m_s >= 0.0)) {
    *reason = DropReason::window_incomplete;
    return false;
  }
  if (*speed_m_s > config_.max_speed_m_s) {
    *reason = DropReason::moving_tracker;
    return false;
  }
  return true;
}

Status SampleExtractorBase::decide(const ExtractorTrackerEntry& entry) {
  const double robot_us = clock_.robot_us(entry.t_us);
  Window window;
  double tracker_speed_m_s = 0.0;
  DropReason reason = DropReason::window_incomplete;
  if (!check_robot(robot_us, &window, &reason)) return drop(entry.t_us, reason);
  // The tracker side is tested only over a stability window: at the instant alone a 10 Hz
  // tracker has no second point, and its neighbours lie outside short pauses.
  if (config_.window_us > 0 && !check_tracker(entry, &tracker_speed_m_s, &reason)) return drop(entry.t_us, reason);

  // Linear interpolation between the robot records bracketing the instant (gaps checked above).
  const RobotBracket at = bracket_at(robot_us);
  const ExtractorRobotEntry& a = robot_[at.before];
  const ExtractorRobotEntry& b = robot_[at.after];
  const double u = at.fraction;
  ExtractedSample sample;
  sample.tracker_us = entry.t_us;
  sample.robot_us = robot_us;
  sample.q_rad = a.q_rad + u * (b.q_rad - a.q_rad);
  sample.point_m = entry.point_m;
  sample.robot_speed_m_s = window.speed_m_s;
  sample.tracker_speed_m_s = tracker_speed_m_s;
  if (dataset_->add(sample.q_rad, sample.point_m) != Status::ok) return drop(entry.t_us, DropReason::dataset_full);
  ++counts_.kept;
  if (observer_ != nullptr) observer_->on_sample(sample);
  return Status::ok;
}

}  // namespace hivecal
