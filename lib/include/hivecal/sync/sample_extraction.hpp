// Quasi-static sample extraction: pairs each valid tracker point with the robot joints
// resampled at the same instant (through a ClockFit) and keeps the pair when the tool was
// quasi-static at that instant: robot-side tool speed below 2 mm/s (the paper's rule), from
// short one-sided differences of the resampled tool path, so a pause of 0.2 s yields its two
// points.
// A stricter stability window (both sides still over a longer span) is an option, off by
// default: it costs the points of short pauses. Streaming and bounded: the two streams are pushed as they come, each in
// its own time order, into fixed rings (capacities are template parameters); every tracker point ends up either kept or
// dropped for exactly one DropReason.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/wire/records.hpp"
#include "hivecal/core/ring.hpp"
#include "hivecal/core/status.hpp"

namespace hivecal {

/// Why a tracker point did not become a sample (docs/streams.md gives the order of the checks).
enum class DropReason : std::uint8_t {
  beam_lost = 0,          ///< status 1
  unstable,               ///< status 2
  bad_status,             ///< any status other than 0, 1, 2
  non_finite_point,       ///< status 0 but a NaN/Inf coordinate
  out_of_order,           ///< timestamp not after the previous tracker point's
  outside_robot_range,    ///< its robot-clock instant is before the first or after the last robot record
  robot_history_overrun,  ///< the robot records around it were already evicted (ring too small for the streams' lag)
  robot_gap,  ///< a robot gap longer than max_robot_gap_us inside the speed baseline (or window) around the instant
  window_incomplete,  ///< the speed baseline (or window) around it is not covered by data (stream start/end, tracker
                      ///< dropouts)
  moving_robot,       ///< robot-side tool speed above the threshold at the instant (or anywhere in the window)
  moving_tracker,     ///< tracker-side point speed above the threshold in the window (only with a window)
  backlog_overrun,    ///< still undecided when the tracker ring overflowed (robot stream lagging)
  dataset_full,       ///< quasi-static but the dataset had no room
};
/// Number of DropReason values.
inline constexpr int kDropReasonCount = 13;
/// Lower-case name of a drop reason ("moving_robot").
const char* drop_reason_name(DropReason reason);

/// Options of the extraction; defaults follow the paper (tool speed below 2 mm/s at the instant).
struct ExtractionConfig {
  RobotModel speed_model;        ///< geometry for robot-side tool speeds (nominal is enough)
  double max_speed_m_s = 0.002;  ///< quasi-static threshold [m/s]
  std::uint32_t speed_baseline_us =
      24000;  ///< speed at the instant: the slower of the backward and forward differences over half of this each (3
              ///< periods at 125 Hz: encoder noise) [us]
  std::uint32_t window_us =
      0;  ///< optional stability window centred on the instant, both sides still over it; 0: off [us]
  std::uint32_t max_robot_gap_us = 40000;     ///< never interpolate across a longer robot gap [us]
  std::uint32_t max_tracker_gap_us = 250000;  ///< longest spacing of valid tracker points inside a window [us]
};

/// An ExtractionConfig with the given speed model and default options.
ExtractionConfig make_extraction_config(const RobotModel& speed_model);

/// What happened to the pushed records.
struct ExtractionCounts {
  std::uint64_t tracker_points = 0;              ///< tracker records pushed
  std::uint64_t kept = 0;                        ///< samples added to the dataset
  std::uint64_t dropped[kDropReasonCount] = {};  ///< per DropReason
  std::uint64_t robot_records = 0;               ///< robot records pushed
  std::uint64_t robot_rejected = 0;              ///< of which out of time order or non-finite (not used)

  /// Tracker points dropped for `reason`.
  std::uint64_t dropped_by(DropReason reason) const { return dropped[static_cast<int>(reason)]; }
  /// Tracker points dropped for any reason.
  std::uint64_t dropped_total() const;
  /// Tracker points not decided yet (0 after finish()).
  std::uint64_t pending() const { return tracker_points - kept - dropped_total(); }
};

/// A kept sample with its timing and the speeds that qualified it.
struct ExtractedSample {
  double tracker_us = 0.0;                  ///< tracker timestamp [us]
  double robot_us = 0.0;                    ///< the same instant on the robot clock [us]
  JointVector q_rad = JointVector::Zero();  ///< joints interpolated at robot_us [rad]
  Vec3 point_m = Vec3::Zero();              ///< tracker point [m]
  double robot_speed_m_s = 0.0;    ///< robot-side tool speed at the instant (largest in the window, with one) [m/s]
  double tracker_speed_m_s = 0.0;  ///< largest tracker-side speed in the window; 0 without a window [m/s]
};

/// Optional listener of every decision (logging, tests); defaults ignore them.
class ExtractionObserver {
 public:
  /// A sample was added to the dataset.
  virtual void on_sample(const ExtractedSample& /*sample*/) {}
  /// A tracker point (timestamp [us]) was dropped.
  virtual void on_drop(std::uint64_t /*tracker_us*/, DropReason /*reason*/) {}

 protected:
  ~ExtractionObserver() = default;
};

/// One robot record in the extractor's ring.
struct ExtractorRobotEntry {
  double t_us = 0.0;                        ///< robot timestamp [us]
  JointVector q_rad = JointVector::Zero();  ///< joint positions [rad]
  Vec3 tool_m = Vec3::Zero();               ///< speed-model tool point in the base frame [m]
};

/// One valid tracker point in the extractor's ring.
struct ExtractorTrackerEntry {
  double t_us = 0.0;            ///< tracker timestamp [us]
  Vec3 point_m = Vec3::Zero();  ///< position [m]
};

/// Capacity-erased extractor. Push records as they come; call finish() at the end of the
/// streams so that the last points are decided.
class SampleExtractorBase {
 public:
  SampleExtractorBase(const SampleExtractorBase&) = delete;
  SampleExtractorBase& operator=(const SampleExtractorBase&) = delete;

  /// Adds a robot record and decides the tracker points it completes. Errors:
  /// invalid_argument (config), dataset_full (a quasi-static point was not stored),
  /// joint_count_mismatch (the record's joint count is not the speed model's: not used).
  Status push_robot(const JointStateRecord& record);
  /// Adds a tracker record and decides what is complete. Errors as push_robot.
  Status push_tracker(const TrackerPointRecord& record);
  /// Decides every pending tracker point with the data at hand. Errors as push_robot.
  Status finish();
  /// Starts over (empty rings, zero counts, no observer) with new settings.
  void reset(const ExtractionConfig& config, const ClockFit& clock, DatasetBase* dataset);
  /// Counters so far.
  const ExtractionCounts& counts() const { return counts_; }
  /// Listener of decisions (nullptr for none); not owned.
  void set_observer(ExtractionObserver* observer) { observer_ = observer; }
  /// The clock relation in use.
  const ClockFit& clock() const { return clock_; }

 protected:
  SampleExtractorBase(const ExtractionConfig& config, const ClockFit& clock, DatasetBase* dataset,
                      ExtractorRobotEntry* robot_storage, std::size_t robot_capacity,
                      ExtractorTrackerEntry* tracker_storage, std::size_t tracker_capacity);
  ~SampleExtractorBase() = default;

 private:
  struct Window;
  /// The ring entries around a robot instant and its fraction between them.
  struct RobotBracket {
    std::size_t before = 0;  ///< last entry at or before the instant
    std::size_t after = 0;   ///< the next one (= before at the newest entry)
    double fraction = 0.0;   ///< (t - t_before) / (t_after - t_before) [-]
  };
  bool config_ok() const;
  double robot_half_span_us() const;
  Status drain(bool finishing);
  bool ready(const ExtractorTrackerEntry& entry) const;
  Status decide(const ExtractorTrackerEntry& entry);
  bool check_robot(double robot_us, Window* window, DropReason* reason) const;
  bool check_tracker(const ExtractorTrackerEntry& entry, double* speed_m_s, DropReason* reason) const;
  std::size_t robot_index_at_or_before(double t_us) const;
  RobotBracket bracket_at(double robot_us) const;
  Vec3 tool_at(double robot_us) const;
  double speed_at_instant(double robot_us) const;
  Status drop(double tracker_us, DropReason reason);

  ExtractionConfig config_;
  ClockFit clock_;
  DatasetBase* dataset_;
  ExtractionObserver* observer_ = nullptr;
  RingView<ExtractorRobotEntry> robot_;
  RingView<ExtractorTrackerEntry> tracker_;
  std::size_t tracker_decided_ = 0;  // oldest entries of tracker_ already decided (window context)
  ExtractionCounts counts_;
  double robot_first_us_ = 0.0;
  double robot_latest_us_ = 0.0;
  bool robot_started_ = false;
  double tracker_latest_us_ = 0.0;  // newest tracker timestamp of any status
  bool tracker_started_ = false;
};

/// An extractor with rings of `RobotHistory` robot records (88 bytes each; 1024 = 8 s at
/// 125 Hz) and `TrackerHistory` tracker points (32 bytes each; 64 = 6.4 s at 10 Hz). The
/// robot ring must span the window plus the lag between the two streams as pushed.
template <std::size_t RobotHistory = 1024, std::size_t TrackerHistory = 64>
class SampleExtractor final : public SampleExtractorBase {
 public:
  /// An extractor writing into `dataset` (not owned) through the clock relation `clock`.
  SampleExtractor(const ExtractionConfig& config, const ClockFit& clock, DatasetBase* dataset)
      : SampleExtractorBase(config, clock, dataset, robot_storage_, RobotHistory, tracker_storage_, TrackerHistory) {}

 private:
  ExtractorRobotEntry robot_storage_[RobotHistory];
  ExtractorTrackerEntry tracker_storage_[TrackerHistory];
};

}  // namespace hivecal
