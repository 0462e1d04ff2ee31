// A second session generator with other habits than apps/sim (issue 12: validate the stream
// path on sessions it was not tuned on): trapezoidal joint moves instead of minimum-jerk,
// short or random dwells, freely varied tool orientations, UR5 or UR10, a tool off the flange
// axis, a compliance of another form, large clock drift, 2 ms robot jitter, lossy tracker and
// byte errors on both links. It writes the serial captures as other devices would (lib's
// encoder) and the oracle's samples: every tracker instant whose true tool speed is below
// 2 mm/s, paired through the true clock with the true joints and the noise-free point plus
// the same noise.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/wire/codec.hpp"

namespace hivecal::test {

/// The habits of one generated session.
struct OtherSessionConfig {
  RobotType robot = RobotType::ur5;      ///< nominal geometry
  std::uint64_t seed = 1;                ///< every draw
  int waypoints = 40;                    ///< poses visited
  double min_dwell_s = 0.2;              ///< shortest stop at a pose [s]
  double max_dwell_s = 0.2;              ///< longest stop [s]
  double joint_speed_rad_s = 0.8;        ///< trapezoid cruise speed of the leading joint [rad/s]
  double joint_accel_rad_s2 = 2.0;       ///< trapezoid acceleration [rad/s^2]
  double drift = 250e-6;                 ///< tracker clock rate error [-]
  double robot_jitter_s = 0.002;         ///< robot period jitter, uniform +- [s]
  double tracker_noise_m = 15e-6;        ///< per axis [m]
  double beam_lost_probability = 0.05;   ///< per tracker point [-]
  double unstable_probability = 0.03;    ///< per tracker point [-]
  double byte_error_probability = 2e-5;  ///< per byte on both links [-]
};

/// A generated session: captures, truth and the oracle's samples.
struct OtherSession {
  RobotModel nominal;                         ///< datasheet geometry with the nominal tool
  RobotModel truth;                           ///< true geometry and tool
  RigidTransform base_to_tracker;             ///< true robot base -> tracker
  std::vector<std::uint8_t> robot_capture;    ///< robot serial bytes
  std::vector<std::uint8_t> tracker_capture;  ///< tracker serial bytes
  std::vector<Sample> oracle;                 ///< true-clock quasi-static samples (noisy points)
  double duration_s = 0.0;                    ///< session length [s]
};

namespace other_session_detail {

/// Gravity-shaped deflection of another form than the simulator's [rad].
inline JointVector deflected(const JointVector& q) {
  JointVector d = q;
  d(1) += 45e-6 * std::cos(q(1)) + 20e-6 * std::cos(q(1) + q(2));
  d(2) += 25e-6 * std::cos(q(1) + q(2));
  return d;
}

/// One move or stop of the schedule.
struct Leg {
  double start_s;
  double duration_s;
  JointVector from;
  JointVector to;
  double accel_s;  ///< trapezoid ramp time (0 for a stop) [s]
};

/// Normalised trapezoid position in [0, 1] at time t of a leg.
inline double trapezoid(const Leg& leg, double t_s) {
  if (leg.accel_s <= 0.0) return 1.0;
  const double T = leg.duration_s;
  const double ta = leg.accel_s;
  const double v = 1.0 / (T - ta);  // cruise speed so that the area is 1
  const double a = v / ta;
  if (t_s <= 0.0) return 0.0;
  if (t_s >= T) return 1.0;
  if (t_s < ta) return 0.5 * a * t_s * t_s;
  if (t_s > T - ta) return 1.0 - 0.5 * a * (T - t_s) * (T - t_s);
  return 0.5 * a * ta * ta + v * (t_s - ta);
}

template <typename Encode, typename Record>
void append_frame(Encode encode, const Record& record, std::vector<std::uint8_t>* out) {
  std::uint8_t frame[kMaxFrameBytes];
  std::size_t written = 0;
  if (encode(record, Span<std::uint8_t>(frame, kMaxFrameBytes), &written) == Status::ok)
    out->insert(out->end(), frame, frame + written);
}

inline void corrupt(std::vector<std::uint8_t>* bytes, double probability, Random* random) {
  for (std::uint8_t& b : *bytes)
    if (random->uniform01() < probability) b = static_cast<std::uint8_t>(b ^ (1U + random->below(255)));
}

}  // namespace other_session_detail

/// Generates a session (deterministic for the config).
inline OtherSession make_other_session(const OtherSessionConfig& config) {
  using namespace other_session_detail;
  Random random(config.seed * 0x9e3779b97f4a7c15ULL + 17);
  OtherSession s;
  s.nominal = nominal_model(config.robot);
  s.nominal.tool_m = Vec3(0.012, -0.018, 0.115);  // a reflector nest off the flange axis
  s.truth = s.nominal;
  for (DhJoint& j : model_joints(&s.truth)) {
    j.theta_offset_rad += 60e-6 * random.normal();
    j.d_m += 60e-6 * random.normal();
    j.a_m += 60e-6 * random.normal();
    j.alpha_rad += 60e-6 * random.normal();
  }
  for (int a = 0; a < 3; ++a) s.truth.tool_m(a) += 0.4e-3 * random.normal();
  const double yaw = random.uniform(-3.0, 3.0);
  const double c = std::cos(yaw), sn = std::sin(yaw);
  s.base_to_tracker.rotation << c, -sn, 0.0, sn, c, 0.0, 0.0, 0.0, 1.0;
  s.base_to_tracker.translation_m = Vec3(3.5 * std::cos(yaw + 1.0), 3.5 * std::sin(yaw + 1.0), -0.4);

  // Waypoints: varied orientations, reflector above the floor and away from the base axis.
  std::vector<JointVector> poses;
  while (static_cast<int>(poses.size()) < config.waypoints) {
    JointVector q;
    q << random.uniform(-2.6, 2.6), random.uniform(-2.3, -0.8), random.uniform(-2.3, 2.3), random.uniform(-3.1, 3.1),
        random.uniform(-2.8, 2.8), random.uniform(-3.1, 3.1);
    const Vec3 p = fk_tool_point(s.truth, q);
    if (p.z() < 0.05 || p.head<2>().norm() < 0.25) continue;
    poses.push_back(q);
  }
  // Schedule: stop, move, stop, ...
  std::vector<Leg> legs;
  double t_s = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const double dwell_s = random.uniform(config.min_dwell_s, config.max_dwell_s + 1e-9);
    legs.push_back(Leg{t_s, dwell_s, poses[k], poses[k], 0.0});
    t_s += dwell_s;
    if (k + 1 == poses.size()) break;
    const double delta = (poses[k + 1] - poses[k]).cwiseAbs().maxCoeff();
    const double v = config.joint_speed_rad_s, a = config.joint_accel_rad_s2;
    double ramp_s = v / a;
    double duration_s = delta / v + ramp_s;
    if (delta < v * v / a) {
      ramp_s = std::sqrt(delta / a);
      duration_s = 2.0 * ramp_s;
    }
    legs.push_back(Leg{t_s, duration_s, poses[k], poses[k + 1], ramp_s});
    t_s += duration_s;
  }
  s.duration_s = t_s;
  std::size_t leg_index = 0;
  auto joints_at = [&](double time_s) {
    while (leg_index + 1 < legs.size() && time_s >= legs[leg_index + 1].start_s) ++leg_index;
    while (leg_index > 0 && time_s < legs[leg_index].start_s) --leg_index;
    const Leg& leg = legs[leg_index];
    const double u = trapezoid(leg, time_s - leg.start_s);
    return JointVector(leg.from + u * (leg.to - leg.from));
  };
  auto true_point = [&](const JointVector& q) { return s.base_to_tracker.apply(fk_tool_point(s.truth, deflected(q))); };

  // Robot link: 125 Hz with jitter and drops; the robot clock is the reference.
  constexpr std::uint64_t kRobotStartUs = 2000000000ULL;
  DeviceInfoRecord robot_info;
  robot_info.device_kind = static_cast<std::uint8_t>(DeviceKind::robot);
  robot_info.nominal_rate_hz = 125.0f;
  robot_info.timestamp_us = kRobotStartUs;
  std::snprintf(robot_info.name, sizeof robot_info.name, "%s", "OTHER-LAB ARM");
  append_frame(encode_device_info, robot_info, &s.robot_capture);
  std::uint16_t sequence = 1;
  for (double time_s = 0.0; time_s < s.duration_s;
       time_s += 0.008 + random.uniform(-1.0, 1.0) * config.robot_jitter_s) {
    if (random.uniform01() < 0.003) continue;  // never sent
    JointStateRecord record;
    record.sequence = sequence++;
    record.timestamp_us = kRobotStartUs + static_cast<std::uint64_t>(std::llround(time_s * 1e6));
    const JointVector q = joints_at(time_s);
    const JointVector q_next = joints_at(time_s + 1e-3);
    for (int j = 0; j < kSixJoints; ++j) {
      record.q_rad[j] = q(j);
      record.qd_rad_s[j] = (q_next(j) - q(j)) * 1e3;
    }
    append_frame(encode_joint_state, record, &s.robot_capture);
  }
  // Tracker link: 10 Hz on its own drifting clock; t_robot = offset + (1 + drift) t_tracker.
  constexpr double kTrackerStartUs = 7000000.0;
  const double offset_us = static_cast<double>(kRobotStartUs) - (1.0 + config.drift) * kTrackerStartUs + 1.234e6;
  DeviceInfoRecord tracker_info;
  tracker_info.device_kind = static_cast<std::uint8_t>(DeviceKind::tracker);
  tracker_info.nominal_rate_hz = 10.0f;
  tracker_info.timestamp_us = static_cast<std::uint64_t>(kTrackerStartUs);
  std::snprintf(tracker_info.name, sizeof tracker_info.name, "%s", "OTHER-LAB TRACKER");
  append_frame(encode_device_info, tracker_info, &s.tracker_capture);
  sequence = 1;
  int lost_run = 0;
  for (int k = 1;; ++k) {
    const double tracker_us = kTrackerStartUs + 1e5 * k + 30.0 * random.normal();
    const double time_s = (offset_us + (1.0 + config.drift) * tracker_us - static_cast<double>(kRobotStartUs)) * 1e-6;
    if (time_s < 0.0) continue;
    if (time_s >= s.duration_s) break;
    const JointVector q = joints_at(time_s);
    const Vec3 exact = true_point(q);
    Vec3 measured = exact;
    for (int a = 0; a < 3; ++a) measured(a) += config.tracker_noise_m * random.normal();
    const double speed_m_s =
        (fk_tool_point(s.truth, joints_at(time_s + 1e-4)) - fk_tool_point(s.truth, joints_at(time_s - 1e-4))).norm() /
        2e-4;
    if (speed_m_s < 0.002) {
      Sample oracle;
      oracle.q_rad = q;
      oracle.point_m = exact;
      for (int a = 0; a < 3; ++a) oracle.point_m(a) += config.tracker_noise_m * random.normal();
      s.oracle.push_back(oracle);
    }
    TrackerPointRecord record;
    record.sequence = sequence++;
    record.timestamp_us = static_cast<std::uint64_t>(std::llround(tracker_us));
    if (lost_run == 0 && random.uniform01() < config.beam_lost_probability / 3.0)
      lost_run = 1 + static_cast<int>(random.below(5));
    if (lost_run > 0) {
      --lost_run;
      record.status = static_cast<std::uint8_t>(TrackerStatus::beam_lost);
      for (double& v : record.point_m) v = std::nan("");
    } else {
      const bool unstable = random.uniform01() < config.unstable_probability;
      record.status = static_cast<std::uint8_t>(unstable ? TrackerStatus::unstable : TrackerStatus::valid);
      for (int a = 0; a < 3; ++a) record.point_m[a] = measured(a) + (unstable ? 2e-4 * random.normal() : 0.0);
    }
    append_frame(encode_tracker_point, record, &s.tracker_capture);
  }
  corrupt(&s.robot_capture, config.byte_error_probability, &random);
  corrupt(&s.tracker_capture, config.byte_error_probability, &random);
  return s;
}

}  // namespace hivecal::test
