// The simulated world behind `hivecal simulate`: a UR arm moving through waypoints (linear
// joint-space moves with minimum-jerk profiles, stops at each waypoint), a "true" geometry,
// joint compliance no DH model captures, and the two devices observing it on their own
// clocks: the robot's joint-state publisher (125 Hz with jitter and dropped packets) and the
// laser tracker (10 Hz, drifting clock, noise, beam-lost and unstable points).
// Deterministic for a seed (own PRNG, own trigonometry): the same records on every target.
// docs/streams.md describes the model and its ground truth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "hivecal/wire/records.hpp"

namespace hivecal::sim {

/// Everything that defines a simulated session; defaults give the paper-like UR5 session.
struct SimConfig {
  std::string robot_name = "ur5";                      ///< arm name (device info, truth file)
  RobotModel nominal = nominal_model(RobotType::ur5);  ///< nominal geometry (standard DH; the tool is nominal_tool_m)
  DhConvention convention = DhConvention::standard;    ///< how the truth file writes the DH rows
  ModifiedDhBase modified_base;                        ///< modified DH: Rx(alpha_0) Tx(a_0) of the description
  std::uint64_t seed = 1;                              ///< seed of every random choice
  int waypoint_count = 38;                             ///< waypoints visited (>= 2)
  double duration_s = 600.0;                           ///< target session length [s] (moves are slowed down to fill it)
  double max_joint_speed_rad_s = 0.5;                  ///< fastest peak joint speed of a move [rad/s]
  double min_move_s = 2.0;                             ///< shortest move [s]
  double mean_stop_s = 2.0;                            ///< mean stop at a waypoint (uniform 0.5..1.5 times) [s]
  double min_stop_s = 1.5;                             ///< shortest stop at a waypoint [s]
  // Geometry.
  bool use_deltas = false;     ///< true: true geometry = nominal + `deltas` (calibration.conf)
  UrCalibrationDeltas deltas;  ///< used when use_deltas
  // Paper-like magnitudes (docs/streams.md, "Geometry errors"): seed 1 gives an uncalibrated
  // test MAE of ~73 um and paper-6 + ABC ~19 % better, as in the paper (75.4 -> 60.1 um).
  double length_sigma_m = 30e-6;                 ///< otherwise: sigma of the d and a errors [m]
  double angle_sigma_rad = 40e-6;                ///< otherwise: sigma of the theta and alpha errors [rad]
  Vec3 nominal_tool_m = Vec3(0.0, 0.0, 0.1695);  ///< nominal retroreflector position in the flange frame [m]
  double tool_sigma_m = 25e-6;                   ///< sigma of the true tool's deviation from nominal [m]
  double compliance_j2_rad = 60e-6;              ///< gravity deflection of joint 2 at full horizontal reach [rad]
  double compliance_j3_rad = 30e-6;              ///< gravity deflection of joint 3 with the forearm horizontal [rad]
  /// An eccentric encoder or a gear's transmission error: joint harmonic_joint (0-based; -1:
  /// none) turns by sin_rad sin(order q) + cos_rad cos(order q) more than it reads.
  int harmonic_joint = -1;
  int harmonic_order = 1;           ///< periods per joint turn [-]
  double harmonic_sin_rad = 0.0;    ///< amplitude of sin(order q) [rad]
  double harmonic_cos_rad = 0.0;    ///< amplitude of cos(order q) [rad]
  double tracker_distance_m = 3.0;  ///< tracker distance from the robot base [m]
  // Robot stream (the robot clock is the reference: true time + its start value).
  std::uint64_t robot_clock_start_us = 1000000000;  ///< robot clock at true time 0 [us]
  double robot_period_s = 0.008;                    ///< nominal joint-state period [s]
  double robot_jitter_s = 0.0004;                   ///< sigma of each period's deviation [s]
  double robot_drop_probability = 0.001;            ///< chance that a packet is never sent (sequence gap)
  double robot_start_s = 0.0;                       ///< true time of the first robot packet [s]
  // Tracker stream.
  std::uint64_t tracker_clock_start_us = 5000000;  ///< tracker clock at true time 0 [us]
  double clock_drift = 40e-6;                      ///< t_robot = offset + (1 + drift) * t_tracker [-]
  double tracker_period_s = 0.1;                   ///< nominal period on the tracker clock [s]
  double tracker_jitter_s = 0.00005;               ///< sigma of each timestamp's deviation [s]
  double tracker_noise_m = 10e-6;                  ///< sigma of the measurement noise per axis [m]
  double beam_lost_probability = 0.003;            ///< chance per point that a beam-lost burst starts
  int beam_lost_max_points = 20;                   ///< longest burst [points]
  double unstable_probability = 0.01;              ///< chance per point of an unstable (status 2) point
  double tracker_start_s = 0.0;                    ///< true time of the first tracker point [s]
};

/// The simulator's first geometry errors (sigma 0.3 mm / 0.3 mrad on every DH parameter, 1 mm
/// on the tool, twice the default compliance): far from the paper (uncalibrated test MAE
/// ~2 mm). Kept for tests that want large, easily identified errors (`simulate --errors large`).
void use_large_errors(SimConfig* config);

/// The simulator's joint compliance (its own form, not the library's gravity basis): joint 2
/// deflects by j2_rad x the horizontal reach of upper arm + forearm relative to full reach, joint
/// 3 by j3_rad x the forearm's; a2, a3 from `truth`. Session::compliance and `hivecal validate`
/// (true points of a truth.json) both use it [rad].
JointVector simulated_compliance(const RobotModel& truth, double j2_rad, double j3_rad, const JointVector& q_rad);

/// One leg of the schedule: a stop at a waypoint or a move between two.
struct Segment {
  double start_s = 0.0;                        ///< true start time [s]
  double duration_s = 0.0;                     ///< [s]
  JointVector from_rad = JointVector::Zero();  ///< joints at the start [rad]
  JointVector to_rad = JointVector::Zero();    ///< joints at the end (= from for a stop) [rad]
  int waypoint = -1;                           ///< waypoint index for a stop, -1 for a move
};

/// The hidden truth of a session.
struct SimTruth {
  RobotModel nominal;              ///< datasheet geometry with the nominal tool
  RobotModel model;                ///< true geometry and tool
  RigidTransform base_to_tracker;  ///< true robot base -> tracker frame
  double clock_offset_us = 0.0;    ///< t_robot = offset + (1 + drift) * t_tracker [us]
  double clock_drift = 0.0;        ///< [-]
};

/// The world: truth, schedule and the true motion as a function of true time.
class Session {
 public:
  /// Builds the truth and the schedule of `config` (deterministic for config.seed).
  explicit Session(const SimConfig& config);

  const SimConfig& config() const { return config_; }                       ///< the configuration
  const SimTruth& truth() const { return truth_; }                          ///< the hidden truth
  const std::vector<Segment>& schedule() const { return schedule_; }        ///< stops and moves in order
  const std::vector<JointVector>& waypoints() const { return waypoints_; }  ///< visited poses [rad]
  double duration_s() const;                                                ///< end of the last stop [s]

  /// Joint positions at true time t_s (clamped to the schedule) [rad].
  JointVector joints_at(double t_s) const;
  /// Joint velocities at true time t_s [rad/s].
  JointVector joint_speeds_at(double t_s) const;
  /// Where the tracker truly sees the tool for commanded joints q (compliance included) [m].
  Vec3 true_point(const JointVector& q_rad) const;
  /// The segment under way at true time t_s.
  const Segment& segment_at(double t_s) const;
  /// Gravity deflection added to the commanded joints (what no DH model captures) [rad].
  JointVector compliance(const JointVector& q_rad) const;

  /// Robot clock reading at true time t_s [us] (rounded).
  std::uint64_t robot_clock_us(double t_s) const;
  /// True time of a robot clock reading [s].
  double true_time_of_robot_us(std::uint64_t t_us) const;
  /// True time of a tracker clock reading [s].
  double true_time_of_tracker_us(std::uint64_t t_us) const;
  /// Tracker clock reading at true time t_s [us] (rounded).
  std::uint64_t tracker_clock_us(double t_s) const;

 private:
  void build_truth(Random* random);
  void build_schedule(Random* random);
  JointVector random_waypoint(Random* random) const;
  JointVector general_waypoint(Random* random) const;  // any arm: joints spread, tool above the base plane

  SimConfig config_;
  SimTruth truth_;
  std::vector<JointVector> waypoints_;
  std::vector<Segment> schedule_;
};

/// The robot's joint-state publisher: JointStateRecords in time order (DEVICE_INFO first).
class RobotStream {
 public:
  /// A publisher over `session` (which must outlive it).
  explicit RobotStream(const Session& session);
  /// A DEVICE_INFO (sent at stream start); it takes the stream's next sequence number.
  DeviceInfoRecord device_info();
  /// Next packet; false once the session is over.
  bool next(JointStateRecord* record);
  /// True time of the packet last returned [s].
  double last_true_time_s() const { return last_s_; }

 private:
  const Session& session_;
  Random random_;
  std::uint64_t next_us_;
  std::uint16_t sequence_ = 0;  ///< the stream's next sequence number, shared by every packet type
  double last_s_ = 0.0;
};

/// The laser tracker: TrackerPointRecords in time order (DEVICE_INFO first).
class TrackerStream {
 public:
  /// A tracker over `session` (which must outlive it).
  explicit TrackerStream(const Session& session);
  /// A DEVICE_INFO (sent at stream start); it takes the stream's next sequence number.
  DeviceInfoRecord device_info();
  /// Next packet; false once the session is over.
  bool next(TrackerPointRecord* record);
  /// True time of the packet last returned [s].
  double last_true_time_s() const { return last_s_; }

 private:
  const Session& session_;
  Random random_;
  std::uint64_t first_us_;
  std::uint64_t index_ = 0;
  std::uint16_t sequence_ = 0;  ///< the stream's next sequence number, shared by every packet type
  int burst_left_ = 0;
  double last_s_ = 0.0;
};

/// One ideal paired sample: a tracker instant inside a stop, with the commanded joints and
/// the noise-free point, paired through the true clocks (no point dropped).
struct TruthSample {
  int waypoint = 0;                         ///< waypoint index
  std::uint64_t tracker_us = 0;             ///< tracker timestamp of the instant [us]
  double robot_us = 0.0;                    ///< the same instant on the robot clock [us]
  JointVector q_rad = JointVector::Zero();  ///< commanded joints [rad]
  Vec3 point_m = Vec3::Zero();              ///< true point in the tracker frame [m]
};

/// Margin of `hivecal simulate`'s truth_samples.csv: at least this far inside a stop [s].
inline constexpr double kTruthSampleMarginS = 0.6;

/// Every tracker instant at least `margin_s` inside a stop (before any status is drawn).
std::vector<TruthSample> truth_samples(const Session& session, double margin_s);

/// Every tracker instant (whatever its status: nothing dropped) at which the true tool speed
/// stays at or below `max_speed_m_s` throughout a window of `window_s` centred on it (checked
/// every 10 ms): the quasi-static instants a perfect extraction would keep. Each comes with
/// the true joints at that instant and the noise-free point (compliance included).
std::vector<TruthSample> quasi_static_truth_samples(const Session& session, double max_speed_m_s, double window_s);

}  // namespace hivecal::sim
