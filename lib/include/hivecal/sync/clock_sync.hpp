// Relation between the tracker clock and the robot clock, estimated from the data alone:
//   t_robot = offset + (1 + drift) * t_tracker
// by aligning the tool's path-length profile seen by the robot (FK of the joint stream)
// with the one seen by the tracker (chords between successive points). Both are rotation
// and origin invariant, so neither the base->tracker transform nor the calibration is needed.
//
// Method (docs/streams.md): the records of each stream are folded into fixed-capacity
// profiles as they come (robot: cumulative tool path length on a uniform robot-time grid;
// tracker: cumulative chord length at each valid point). estimate() then
//   1. finds the coarse lag by normalised cross-correlation of the two speed profiles,
//   2. scans lag x drift around it with the chord model below,
//   3. refines lag and drift by weighted, robust Gauss-Newton on
//        chord_tracker(a, b) = gain_block * (s_robot(map(b)) - s_robot(map(a)))
//      over every pair of valid tracker points a, b three points apart, with one free gain per
//      1 s block of chords (a tool-model error scales speeds slowly along a move; a
//      global gain would let it bias the timing),
// and reports the covariance. Memory is the profiles' capacity, whatever the capture length:
// beyond it records are counted and ignored (the fit then rests on the first part).
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/model/kinematics.hpp"
#include "hivecal/wire/records.hpp"
#include "hivecal/core/status.hpp"

namespace hivecal {
/// Default robot profile length [knots]: 65536 x 20 ms = 21.8 min of robot data.
inline constexpr std::size_t kDefaultClockRobotKnots = 65536;
/// Default tracker profile length [points]: 16384 x 100 ms = 27 min of tracker data.
inline constexpr std::size_t kDefaultClockTrackerPoints = 16384;

/// Options of the clock estimation; the defaults suit 125 Hz / 10 Hz UR + tracker sessions.
struct ClockSyncConfig {
  RobotModel speed_model;                  ///< geometry for tool speeds (nominal + nominal tool is enough)
  std::uint32_t knot_interval_us = 20000;  ///< robot profile resolution [us]
  std::uint32_t coarse_step_us =
      100000;  ///< lag grid of the coarse correlation, a multiple >= 2 of knot_interval_us [us]
  std::uint32_t max_robot_gap_us = 50000;        ///< robot profile is unknown across longer gaps [us]
  std::uint32_t max_chord_interval_us = 350000;  ///< longest tracker interval used as a chord [us]
  std::uint64_t min_overlap_us =
      60000000;                      ///< least overlap of the profiles for a coarse lag [us] (halved for short data)
  double max_drift = 5e-4;           ///< largest |drift| searched and accepted [-]
  double min_correlation = 0.5;      ///< weakest acceptable coarse correlation peak [-]
  double max_runner_up_ratio = 0.9;  ///< ambiguous when another peak reaches this share of the best [-]
  std::uint32_t chord_span_points =
      3;  ///< tracker intervals spanned by one chord of the fine fit (one per point; 1 .. kMaxChordSpanPoints)
  std::uint32_t gain_block_us = 1000000;  ///< chords sharing one free speed gain in the fine fit [us]
  double edge_speed_change_m_s = 0.005;   ///< speed change within a chord that makes it informative [m/s]
  std::uint32_t min_edge_chords = 10;     ///< informative chords needed [chords]
  std::uint32_t max_iterations = 30;      ///< Gauss-Newton iteration limit
  double max_tool_speed_m_s = 5.0;        ///< a tracker point implying a faster tool is a blunder and set aside [m/s]
  std::uint32_t reanchor_points =
      5;  ///< this many consecutive consistent "blunders" mean the earlier point was the blunder [points]
};

/// A ClockSyncConfig with the given speed model and default options.
ClockSyncConfig make_clock_sync_config(const RobotModel& speed_model);

/// The estimated clock relation and its quality. Times are absolute device-clock values.
struct ClockFit {
  double offset_us = 0.0;               ///< t_robot = offset_us + (1 + drift) * t_tracker [us]
  double drift = 0.0;                   ///< relative rate of the robot clock w.r.t. the tracker's [-] (1e-6 = 1 ppm)
  double reference_tracker_us = 0.0;    ///< tracker time where offset and drift are uncorrelated [us]
  double offset_at_reference_us = 0.0;  ///< t_robot - t_tracker at reference_tracker_us [us]
  double sigma_offset_at_reference_us = 0.0;  ///< 1-sigma of offset_at_reference_us [us]
  double sigma_drift = 0.0;                   ///< 1-sigma of drift [-]
  double sigma_offset_us = 0.0;               ///< 1-sigma of offset_us (extrapolated to t_tracker = 0) [us]
  double speed_gain = 1.0;                    ///< overall tracker/robot path-length ratio (tool model error) [-]
  double residual_rms_m = 0.0;                ///< rms chord residual after the fit [m]
  double coarse_correlation = 0.0;            ///< peak normalised correlation of the speed profiles [-]
  double runner_up_correlation = 0.0;         ///< best other correlation peak outside the main lobe [-]
  std::uint32_t chords_used = 0;              ///< tracker chords in the final fit
  std::uint32_t edge_chords = 0;              ///< of which informative (speed changing) [chords]
  std::uint32_t iterations = 0;               ///< Gauss-Newton iterations run

  /// The robot-clock time of a tracker-clock time [us].
  double robot_us(double tracker_us) const {
    return tracker_us + offset_at_reference_us + drift * (tracker_us - reference_tracker_us);
  }
};

/// What went into the profiles.
/// Timestamps of set-aside tracker points kept for messages (the count has them all).
inline constexpr std::size_t kClockSetAsideLog = 8;

struct ClockProfileStats {
  std::uint64_t robot_records = 0;                 ///< JointStateRecords pushed
  std::uint64_t robot_rejected = 0;                ///< of which out of time order, non-finite or of another joint count
  std::uint64_t robot_beyond_capacity = 0;         ///< of which after the profile was full
  std::uint64_t robot_gaps = 0;                    ///< robot gaps longer than max_robot_gap_us
  std::uint64_t robot_joint_count_mismatches = 0;  ///< of the rejected, of another joint count than the speed model
  std::uint64_t tracker_records = 0;               ///< TrackerPointRecords pushed
  std::uint64_t tracker_not_valid = 0;             ///< of which status not valid or non-finite point
  std::uint64_t tracker_rejected = 0;              ///< of which out of time order
  std::uint64_t tracker_beyond_capacity = 0;       ///< of which after the profile was full
  std::uint64_t tracker_set_aside =
      0;  ///< of which valid but set aside as blunders (an implausible jump away and back)
  std::uint64_t set_aside_tracker_us[kClockSetAsideLog] =
      {};                          ///< tracker timestamps of the first set-aside points [us]
  std::size_t robot_knots = 0;     ///< robot profile knots stored
  std::size_t tracker_points = 0;  ///< tracker profile points stored
  // What a failed estimate is explained with (times on each device's own clock):
  std::uint64_t robot_first_us = 0;    ///< first accepted joint state [us]
  std::uint64_t robot_last_us = 0;     ///< last accepted joint state [us]
  std::uint64_t tracker_first_us = 0;  ///< first stored tracker point [us]
  std::uint64_t tracker_last_us = 0;   ///< last stored tracker point [us]
  double robot_path_m = 0.0;           ///< path length of the speed model's tool point [m]
  double tracker_path_m = 0.0;         ///< path length of the stored tracker points [m]
};

/// Most tracker points held back while a jump is judged (ClockSyncConfig::reanchor_points <= this).
inline constexpr std::uint32_t kMaxHeldTrackerPoints = 8;

/// Most tracker intervals one chord of the fine fit spans (ClockSyncConfig::chord_span_points <= this):
/// the lag x drift scan keeps the path lengths of the points of one chord on the stack.
inline constexpr std::uint32_t kMaxChordSpanPoints = 16;

/// A tracker point held back while the estimator judges a jump.
struct ClockHeldPoint {
  std::uint64_t timestamp_us = 0;  ///< tracker clock [us]
  Vec3 point_m = Vec3::Zero();     ///< position [m]
};

/// One stored tracker point: time since the first stored point and cumulative chord length.
struct ClockTrackerKnot {
  double t_us = 0.0;  ///< tracker time since the first valid point [us]
  double s_m = 0.0;   ///< chord length accumulated up to this point [m]
};

/// Most bins of a ClockMatch (time-uniform over the tracker profile).
inline constexpr std::size_t kClockMatchBins = 512;

/// One time bin of the matched speed profiles: means over the fine-fit chords ending in it.
struct ClockMatchBin {
  double tracker_s = 0.0;          ///< mean chord mid-time, since the first stored tracker point [s]
  double robot_speed_m_s = 0.0;    ///< robot tool speed at the fitted robot times of the chords [m/s]
  double tracker_speed_m_s = 0.0;  ///< tracker point speed over the chords [m/s]
  double residual_m_s = 0.0;       ///< tracker speed - speed_gain * robot speed [m/s]
  std::uint32_t chords = 0;        ///< chords averaged
};

/// The two speed profiles aligned by a ClockFit, decimated for plotting (observation only:
/// estimate() does not use it).
struct ClockMatch {
  double tracker_t0_us = 0.0;           ///< tracker clock of the first stored tracker point [us]
  std::size_t count = 0;                ///< bins filled (empty bins are skipped)
  ClockMatchBin bins[kClockMatchBins];  ///< in time order
};

namespace detail {
struct ClockProfiles;
}

/// Capacity-erased clock estimator: push each stream in its own time order (the two
/// streams may be interleaved in any way, or pushed one after the other), then estimate().
class ClockEstimatorBase {
 public:
  ClockEstimatorBase(const ClockEstimatorBase&) = delete;
  ClockEstimatorBase& operator=(const ClockEstimatorBase&) = delete;

  /// Folds one robot record into the robot profile (out-of-order or non-finite ones, and those of
  /// another joint count than the speed model's, are counted, not used).
  void push_robot(const JointStateRecord& record);
  /// Folds one tracker record into the tracker profile (only status valid with a finite point is used).
  void push_tracker(const TrackerPointRecord& record);
  /// Estimates the clock relation from what was pushed so far. Errors: invalid_argument
  /// (config), joint_count_mismatch (a robot record of another joint count than the speed
  /// model's), clock_fit_failed (too little overlapping motion, weak or ambiguous
  /// correlation, fit outside max_drift). *fit is written only on success.
  Status estimate(ClockFit* fit);
  /// What `fit` (from estimate() on the same records) matched: the chords of the fine fit
  /// in at most `bins` (<= kClockMatchBins) time-uniform bins. Reads only; allocates nothing.
  /// Errors: invalid_argument (null, bins out of range), clock_fit_failed (no chord covered).
  Status match_profiles(const ClockFit& fit, std::size_t bins, ClockMatch* match) const;
  /// Forgets every record (keeps the configuration).
  void reset();
  /// Forgets every record and takes a new configuration.
  void reset(const ClockSyncConfig& config);
  /// Counters of what was pushed.
  const ClockProfileStats& stats() const { return stats_; }
  /// The configuration in use.
  const ClockSyncConfig& config() const { return config_; }

 protected:
  ClockEstimatorBase(const ClockSyncConfig& config, double* robot_knots_m, std::size_t robot_capacity,
                     ClockTrackerKnot* tracker_knots, std::size_t tracker_capacity, double* scratch,
                     std::size_t scratch_capacity);
  ~ClockEstimatorBase() = default;

 private:
  bool config_ok() const;
  detail::ClockProfiles profiles() const;  // the stored profiles as estimate() and match_profiles() read them
  void store_tracker_point(std::uint64_t timestamp_us, const Vec3& point_m);
  void set_aside_held();
  bool plausible_move(std::uint64_t from_us, const Vec3& from_m, std::uint64_t to_us, const Vec3& to_m) const;
  /// Speed implied by a move [m/s] (to_us > from_us).
  static double speed_m_s(std::uint64_t from_us, const Vec3& from_m, std::uint64_t to_us, const Vec3& to_m);

  ClockSyncConfig config_;
  double* robot_knots_m_;
  std::size_t robot_capacity_;
  ClockTrackerKnot* tracker_knots_;
  std::size_t tracker_capacity_;
  double* scratch_;
  std::size_t scratch_capacity_;
  ClockProfileStats stats_;
  // Robot profile state: knot j is at robot time robot_t0_us_ + j * knot_interval_us.
  std::uint64_t robot_t0_us_ = 0;
  std::uint64_t robot_last_us_ = 0;
  Vec3 robot_last_point_m_ = Vec3::Zero();
  double robot_last_s_m_ = 0.0;
  bool robot_started_ = false;
  // Tracker profile state. Points that jump implausibly far from the last stored one are
  // held until the next points tell a blunder (set aside) from a new track (stored).
  ClockHeldPoint held_[kMaxHeldTrackerPoints];
  std::uint32_t held_count_ = 0;
  std::uint64_t tracker_newest_us_ = 0;
  std::uint64_t tracker_t0_us_ = 0;
  std::uint64_t tracker_last_us_ = 0;
  Vec3 tracker_last_point_m_ = Vec3::Zero();
  double tracker_last_s_m_ = 0.0;
  bool tracker_started_ = false;
};

/// A clock estimator with storage for `RobotKnots` robot knots and `TrackerPoints` tracker
/// points (8 + 16 bytes each, plus 8 * (TrackerPoints + RobotKnots / 2) bytes of scratch).
template <std::size_t RobotKnots = kDefaultClockRobotKnots, std::size_t TrackerPoints = kDefaultClockTrackerPoints>
class ClockEstimator final : public ClockEstimatorBase {
 public:
  /// An empty estimator using `config`.
  explicit ClockEstimator(const ClockSyncConfig& config)
      : ClockEstimatorBase(config, robot_knots_m_, RobotKnots, tracker_knots_, TrackerPoints, scratch_, kScratch) {}

 private:
  static constexpr std::size_t kScratch = TrackerPoints + RobotKnots / 2;
  double robot_knots_m_[RobotKnots];
  ClockTrackerKnot tracker_knots_[TrackerPoints];
  double scratch_[kScratch];
};

}  // namespace hivecal
