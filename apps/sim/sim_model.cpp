#include "sim/sim_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/model/ur_deltas.hpp"

namespace hivecal::sim {
namespace {

constexpr double kMinJerkPeak = 1.875;  // peak of d/du (10u^3 - 15u^4 + 6u^5)

/// Minimum-jerk progress s(u) in [0, 1] for u in [0, 1].
double min_jerk(double u) {
  return u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
}
/// ds/du of min_jerk.
double min_jerk_rate(double u) {
  return 30.0 * u * u * (1.0 - u) * (1.0 - u);
}

/// Three standard normal deviates drawn x, y, z in this order (the order of a
/// constructor's arguments is unspecified and differs between targets).
Vec3 normal_vector(Random* random) {
  Vec3 v;
  for (int axis = 0; axis < 3; ++axis) v(axis) = random->normal();
  return v;
}

/// Nearest integer of a non-negative value.
std::uint64_t round_us(double x_us) {
  return static_cast<std::uint64_t>(std::llround(x_us));
}

DeviceInfoRecord make_device_info(DeviceKind kind, float rate_hz, const char* name, std::uint16_t sequence,
                                  std::uint64_t t_us) {
  DeviceInfoRecord info;
  info.sequence = sequence;
  info.timestamp_us = t_us;
  info.device_kind = static_cast<std::uint8_t>(kind);
  info.nominal_rate_hz = rate_hz;
  std::strncpy(info.name, name, sizeof info.name - 1);
  for (char& c : info.name) {
    if (c != '\0' && (c < 0x20 || c > 0x7e)) c = '?';  // the wire takes printable ASCII only
  }
  return info;
}

}  // namespace

void use_large_errors(SimConfig* config) {
  config->length_sigma_m = 3e-4;
  config->angle_sigma_rad = 3e-4;
  config->tool_sigma_m = 1e-3;
  config->compliance_j2_rad = 2e-4;
  config->compliance_j3_rad = 1e-4;
}

Session::Session(const SimConfig& config) : config_(config) {
  Random random(config.seed);
  build_truth(&random);
  build_schedule(&random);
}

void Session::build_truth(Random* random) {
  truth_.nominal = config_.nominal;
  truth_.nominal.tool_m = config_.nominal_tool_m;
  if (config_.use_deltas) {
    (void)apply_ur_deltas(truth_.nominal, config_.deltas, &truth_.model);
  } else {
    truth_.model = truth_.nominal;
    for (DhJoint& joint : model_joints(&truth_.model)) {
      joint.theta_offset_rad += config_.angle_sigma_rad * random->normal();
      joint.d_m += config_.length_sigma_m * random->normal();
      joint.a_m += config_.length_sigma_m * random->normal();
      joint.alpha_rad += config_.angle_sigma_rad * random->normal();
    }
  }
  for (int axis = 0; axis < 3; ++axis) truth_.model.tool_m(axis) += config_.tool_sigma_m * random->normal();

  // Tracker somewhere around the robot at tracker_distance_m, yawed and slightly tilted.
  const double azimuth_rad = random->uniform(-math::kPi, math::kPi);
  double s = 0.0;
  double c = 0.0;
  math::sincos(azimuth_rad, &s, &c);
  const Vec3 tracker_in_base(config_.tracker_distance_m * c, config_.tracker_distance_m * s,
                             random->uniform(-0.3, 0.3));
  const double yaw_rad = random->uniform(-math::kPi, math::kPi);  // draws in statement order:
  const double tilt_rad = random->uniform(-0.02, 0.02);           // argument order is unspecified
  const Mat3 tracker_axes_in_base = rotation_z(yaw_rad) * rotation_x(tilt_rad);
  truth_.base_to_tracker.rotation = tracker_axes_in_base.transpose();
  truth_.base_to_tracker.translation_m = -(tracker_axes_in_base.transpose() * tracker_in_base);

  truth_.clock_drift = config_.clock_drift;
  truth_.clock_offset_us = static_cast<double>(config_.robot_clock_start_us) -
                           (1.0 + config_.clock_drift) * static_cast<double>(config_.tracker_clock_start_us);
}

JointVector Session::random_waypoint(Random* random) const {
  // Tool roughly pointing down: q4 = -pi/2 - q2 - q3 and q5 = -pi/2 put the flange z axis
  // straight down on UR arms; +-0.35 rad around that. Reject poses too low or out of reach.
  // Other arms (a description file whose upper arm and forearm are not UR's negative a2, a3)
  // take poses spread over their joints, above the base plane.
  const RobotModel& model = truth_.nominal;
  const double reach_m = -(model.joints[1].a_m + model.joints[2].a_m);
  if (!(reach_m > 0.2) || model.joint_count != kSixJoints || model.prismatic_joints != 0)
    return general_waypoint(random);
  for (;;) {
    JointVector q;
    q(0) = random->uniform(-1.6, 1.6);
    q(1) = random->uniform(-2.0, -0.9);
    q(2) = random->uniform(0.7, 2.3);
    q(3) = -math::kHalfPi - q(1) - q(2) + random->uniform(-0.35, 0.35);
    q(4) = -math::kHalfPi + random->uniform(-0.35, 0.35);
    q(5) = random->uniform(-1.5, 1.5);
    const Vec3 p = fk_tool_point(model, q);
    const double radial_m = std::sqrt(p.x() * p.x() + p.y() * p.y());
    if (p.z() > 0.05 && p.z() < 0.8 && radial_m > 0.3 && radial_m < 0.9 * reach_m) return q;
  }
}

JointVector Session::general_waypoint(Random* random) const {
  JointVector q = JointVector::Zero();
  for (int attempt = 0; attempt < 1000; ++attempt) {
    q(0) = random->uniform(-1.6, 1.6);
    q(1) = random->uniform(-1.0, 1.0);
    q(2) = random->uniform(-1.0, 1.0);
    q(3) = random->uniform(-1.5, 1.5);
    q(4) = random->uniform(0.3, 1.6);
    q(5) = random->uniform(-1.5, 1.5);
    for (int j = kSixJoints; j < truth_.nominal.joint_count; ++j) q(j) = random->uniform(-1.5, 1.5);  // a 7th ..
    for (int j = 0; j < truth_.nominal.joint_count; ++j) {  // a slide anywhere on its first half metre
      if (joint_type(truth_.nominal, j) == JointType::prismatic) q(j) = 0.5 * std::fabs(q(j)) / 1.6;
    }
    if (random->uniform(0.0, 1.0) < 0.5) q(4) = -q(4);  // both wrist branches
    if (fk_tool_point(truth_.nominal, q).z() > 0.05) break;
  }
  return q;
}

void Session::build_schedule(Random* random) {
  // Stops of about mean_stop_s each; moves as long as their largest joint travel needs at
  // max_joint_speed_rad_s, then stretched together so that the session lasts duration_s.
  const int count = std::max(2, config_.waypoint_count);
  for (int i = 0; i < count; ++i) waypoints_.push_back(random_waypoint(random));
  std::vector<double> stops_s;
  double stops_total_s = 0.0;
  for (int i = 0; i < count; ++i) {
    stops_s.push_back(std::max(config_.min_stop_s, config_.mean_stop_s * random->uniform(0.5, 1.5)));
    stops_total_s += stops_s.back();
  }
  std::vector<double> moves_s;
  double moves_total_s = 0.0;
  for (std::size_t i = 1; i < waypoints_.size(); ++i) {
    const double largest_rad = (waypoints_[i] - waypoints_[i - 1]).cwiseAbs().maxCoeff();
    moves_s.push_back(std::max(config_.min_move_s, kMinJerkPeak * largest_rad / config_.max_joint_speed_rad_s));
    moves_total_s += moves_s.back();
  }
  const double stretch = std::max(1.0, (config_.duration_s - stops_total_s) / moves_total_s);
  double t_s = 0.0;
  for (std::size_t i = 0; i < waypoints_.size(); ++i) {
    schedule_.push_back(Segment{t_s, stops_s[i], waypoints_[i], waypoints_[i], static_cast<int>(i)});
    t_s += stops_s[i];
    if (i + 1 < waypoints_.size()) {
      schedule_.push_back(Segment{t_s, stretch * moves_s[i], waypoints_[i], waypoints_[i + 1], -1});
      t_s += stretch * moves_s[i];
    }
  }
}

double Session::duration_s() const {
  return schedule_.back().start_s + schedule_.back().duration_s;
}

const Segment& Session::segment_at(double t_s) const {
  const auto after = std::upper_bound(schedule_.begin(), schedule_.end(), t_s,
                                      [](double t, const Segment& s) { return t < s.start_s; });
  return after == schedule_.begin() ? schedule_.front() : *(after - 1);
}

JointVector Session::joints_at(double t_s) const {
  const Segment& segment = segment_at(t_s);
  const double u = std::clamp((t_s - segment.start_s) / segment.duration_s, 0.0, 1.0);
  return segment.from_rad + min_jerk(u) * (segment.to_rad - segment.from_rad);
}

JointVector Session::joint_speeds_at(double t_s) const {
  const Segment& segment = segment_at(t_s);
  const double u = std::clamp((t_s - segment.start_s) / segment.duration_s, 0.0, 1.0);
  return (min_jerk_rate(u) / segment.duration_s) * (segment.to_rad - segment.from_rad);
}

JointVector simulated_compliance(const RobotModel& truth, double j2_rad, double j3_rad, const JointVector& q_rad) {
  // Gravity torque on joint 2 ~ horizontal reach of upper arm + forearm; on joint 3 ~ the forearm's.
  const double a2_m = std::fabs(truth.joints[1].a_m);
  const double a3_m = std::fabs(truth.joints[2].a_m);
  const double forearm = math::cos(q_rad(1) + q_rad(2));
  JointVector deflection = JointVector::Zero();
  deflection(1) = j2_rad * (a2_m * math::cos(q_rad(1)) + a3_m * forearm) / (a2_m + a3_m);
  deflection(2) = j3_rad * forearm;
  return deflection;
}

JointVector Session::compliance(const JointVector& q_rad) const {
  JointVector dq = simulated_compliance(truth_.model, config_.compliance_j2_rad, config_.compliance_j3_rad, q_rad);
  const int j = config_.harmonic_joint;
  if (j >= 0 && j < truth_.model.joint_count) {
    const double angle = static_cast<double>(config_.harmonic_order) * q_rad(j);
    dq(j) += config_.harmonic_sin_rad * math::sin(angle) + config_.harmonic_cos_rad * math::cos(angle);
  }
  return dq;
}

Vec3 Session::true_point(const JointVector& q_rad) const {
  return truth_.base_to_tracker.apply(fk_tool_point(truth_.model, q_rad + compliance(q_rad)));
}

std::uint64_t Session::robot_clock_us(double t_s) const {
  return config_.robot_clock_start_us + round_us(t_s * math::kUsPerS);
}

double Session::true_time_of_robot_us(std::uint64_t t_us) const {
  return static_cast<double>(t_us - config_.robot_clock_start_us) / math::kUsPerS;
}

std::uint64_t Session::tracker_clock_us(double t_s) const {
  return config_.tracker_clock_start_us + round_us(t_s * math::kUsPerS / (1.0 + config_.clock_drift));
}

double Session::true_time_of_tracker_us(std::uint64_t t_us) const {
  return static_cast<double>(t_us - config_.tracker_clock_start_us) * (1.0 + config_.clock_drift) / math::kUsPerS;
}

RobotStream::RobotStream(const Session& session)
    : session_(session),
      random_(session.config().seed ^ 0x526f626f74ULL),
      next_us_(session.robot_clock_us(std::max(0.0, session.config().robot_start_s))) {}

DeviceInfoRecord RobotStream::device_info() {
  return make_device_info(DeviceKind::robot, static_cast<float>(1.0 / session_.config().robot_period_s),
                          session_.config().robot_name.c_str(), sequence_++, next_us_);
}

bool RobotStream::next(JointStateRecord* record) {
  const SimConfig& config = session_.config();
  const double period_us = config.robot_period_s * math::kUsPerS;
  for (;;) {
    const std::uint64_t t_us = next_us_;
    const double step_us =
        std::max(0.25 * period_us, period_us + config.robot_jitter_s * math::kUsPerS * random_.normal());
    next_us_ += round_us(step_us);
    const double t_s = session_.true_time_of_robot_us(t_us);
    if (t_s > session_.duration_s()) return false;
    const std::uint16_t sequence = sequence_++;
    if (random_.uniform01() < config.robot_drop_probability) continue;  // lost: a sequence gap
    const JointVector q = session_.joints_at(t_s);
    const JointVector qd = session_.joint_speeds_at(t_s);
    record->sequence = sequence;
    record->timestamp_us = t_us;
    record->joint_count = session_.truth().model.joint_count;
    for (int j = 0; j < record->joint_count; ++j) {
      record->q_rad[j] = q(j);
      record->qd_rad_s[j] = qd(j);
      record->current_a[j] = static_cast<float>(0.8 * qd(j) + (j == 1 || j == 2 ? 1.5 * math::cos(q(1)) : 0.1));
    }
    last_s_ = t_s;
    return true;
  }
}

TrackerStream::TrackerStream(const Session& session)
    : session_(session),
      random_(session.config().seed ^ 0x547261636bULL),
      first_us_(session.tracker_clock_us(std::max(0.0, session.config().tracker_start_s))) {}

DeviceInfoRecord TrackerStream::device_info() {
  return make_device_info(DeviceKind::tracker, static_cast<float>(1.0 / session_.config().tracker_period_s),
                          "tracker-sim", sequence_++, first_us_);
}

bool TrackerStream::next(TrackerPointRecord* record) {
  const SimConfig& config = session_.config();
  const double nominal_us = static_cast<double>(index_) * config.tracker_period_s * math::kUsPerS;
  const double jitter_us = config.tracker_jitter_s * math::kUsPerS * random_.normal();
  const std::uint64_t t_us = first_us_ + round_us(std::max(0.0, nominal_us + jitter_us));
  const double t_s = session_.true_time_of_tracker_us(t_us);
  if (t_s > session_.duration_s()) return false;
  ++index_;
  const Vec3 noise = normal_vector(&random_);
  Vec3 point = session_.true_point(session_.joints_at(t_s)) + config.tracker_noise_m * noise;
  std::uint8_t status = static_cast<std::uint8_t>(TrackerStatus::valid);
  if (burst_left_ == 0 && random_.uniform01() < config.beam_lost_probability)
    burst_left_ =
        1 + static_cast<int>(random_.below(static_cast<std::uint64_t>(std::max(1, config.beam_lost_max_points))));
  if (burst_left_ > 0) {
    --burst_left_;
    status = static_cast<std::uint8_t>(TrackerStatus::beam_lost);
    point = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  } else if (random_.uniform01() < config.unstable_probability) {
    status = static_cast<std::uint8_t>(TrackerStatus::unstable);
    point += 20.0 * config.tracker_noise_m * normal_vector(&random_);
  }
  record->sequence = sequence_++;
  record->timestamp_us = t_us;
  for (int axis = 0; axis < 3; ++axis) record->point_m[axis] = point(axis);
  record->status = status;
  last_s_ = t_s;
  return true;
}

std::vector<TruthSample> truth_samples(const Session& session, double margin_s) {
  std::vector<TruthSample> samples;
  TrackerStream tracker(session);
  TrackerPointRecord record;
  const double drift = session.truth().clock_drift;
  while (tracker.next(&record)) {
    const double t_s = tracker.last_true_time_s();
    const Segment& segment = session.segment_at(t_s);
    if (segment.waypoint < 0 || t_s < segment.start_s + margin_s ||
        t_s > segment.start_s + segment.duration_s - margin_s)
      continue;
    TruthSample sample;
    sample.waypoint = segment.waypoint;
    sample.tracker_us = record.timestamp_us;
    sample.robot_us = session.truth().clock_offset_us + (1.0 + drift) * static_cast<double>(record.timestamp_us);
    sample.q_rad = segment.from_rad;
    sample.point_m = session.true_point(sample.q_rad);
    samples.push_back(sample);
  }
  return samples;
}

std::vector<TruthSample> quasi_static_truth_samples(const Session& session, double max_speed_m_s, double window_s) {
  constexpr double kStepS = 0.01;
  constexpr double kHalfDifferenceS = 0.001;
  const RobotModel& model = session.truth().model;
  auto speed_m_s = [&](double t_s) {
    const Vec3 a = fk_tool_point(model, session.joints_at(t_s - kHalfDifferenceS));
    const Vec3 b = fk_tool_point(model, session.joints_at(t_s + kHalfDifferenceS));
    return (b - a).norm() / (2.0 * kHalfDifferenceS);
  };
  std::vector<TruthSample> samples;
  TrackerStream tracker(session);
  TrackerPointRecord record;
  const double drift = session.truth().clock_drift;
  const int steps = static_cast<int>(std::ceil(0.5 * window_s / kStepS));
  while (tracker.next(&record)) {
    const double t_s = tracker.last_true_time_s();
    if (t_s - 0.5 * window_s < 0.0 || t_s + 0.5 * window_s > session.duration_s()) continue;
    bool still = true;
    for (int k = -steps; k <= steps && still; ++k)
      still = speed_m_s(t_s + std::clamp(k * kStepS, -0.5 * window_s, 0.5 * window_s)) <= max_speed_m_s;
    if (!still) continue;
    TruthSample sample;
    sample.waypoint = session.segment_at(t_s).waypoint;
    sample.tracker_us = record.timestamp_us;
    sample.robot_us = session.truth().clock_offset_us + (1.0 + drift) * static_cast<double>(record.timestamp_us);
    sample.q_rad = session.joints_at(t_s);
    sample.point_m = session.true_point(sample.q_rad);
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace hivecal::sim
