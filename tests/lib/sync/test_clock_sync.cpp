// Clock relation estimated from the data: offset and drift recovered on simulated sessions
// with various clocks, jitters and starts; honest failure without motion or when the
// motion is periodic; constant memory on long captures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "hivecal/core/random.hpp"
#include "sim/sim_model.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::clock_sync_test {
namespace {

constexpr double kTargetUs = 2000.0;  // the required offset accuracy [us]

ClockSyncConfig config_for(const sim::Session& session) {
  return make_clock_sync_config(session.truth().nominal);
}

/// One shared default-size estimator (1.2 MB: static, not on the stack).
ClockEstimatorBase& estimator_with(const ClockSyncConfig& config) {
  static ClockEstimator<> estimator(config);
  estimator.reset(config);
  return estimator;
}

/// Largest |fitted - true| robot time over the tracker times of the session [us] (the
/// error is linear in time, so the ends of the session bound it).
double max_clock_error_us(const ClockFit& fit, const sim::Session& session) {
  const sim::SimTruth& truth = session.truth();
  double worst = 0.0;
  for (const double t_s : {session.config().tracker_start_s, session.duration_s()}) {
    const auto tracker_us = static_cast<double>(session.tracker_clock_us(t_s));
    const double true_us = truth.clock_offset_us + (1.0 + truth.clock_drift) * tracker_us;
    const double error = fit.robot_us(tracker_us) - true_us;
    worst = std::max(worst, std::fabs(error));
  }
  return worst;
}

/// Estimates the clock of a session (chords of `chord_span_points` intervals); expects success
/// within the target.
ClockFit expect_recovered(const sim::SimConfig& config, const char* label,
                          std::uint32_t chord_span_points = ClockSyncConfig{}.chord_span_points) {
  const sim::Session session(config);
  ClockSyncConfig clock_config = config_for(session);
  clock_config.chord_span_points = chord_span_points;
  ClockEstimatorBase& estimator = estimator_with(clock_config);
  ClockFit fit;
  Status status = Status::ok;
  EXPECT_NO_HEAP(test::feed_clock(session, &estimator));
  EXPECT_NO_HEAP(status = estimator.estimate(&fit));
  EXPECT_EQ(status, Status::ok) << label;
  const double error_us = max_clock_error_us(fit, session);
  const double true_at_reference_us =
      session.truth().clock_offset_us + session.truth().clock_drift * fit.reference_tracker_us;
  std::printf("%-28s offset err %7.1f us (sigma %6.1f), drift err %6.2f ppm (sigma %5.2f), max err %7.1f us\n", label,
              fit.offset_at_reference_us - true_at_reference_us, fit.sigma_offset_at_reference_us,
              (fit.drift - session.truth().clock_drift) * 1e6, fit.sigma_drift * 1e6, error_us);
  EXPECT_LT(error_us, kTargetUs) << label;
  EXPECT_NEAR(fit.drift, session.truth().clock_drift, 10e-6) << label;
  EXPECT_GT(fit.sigma_offset_at_reference_us, 0.0) << label;
  EXPECT_LT(fit.sigma_offset_at_reference_us, kTargetUs / 3.0) << label;
  return fit;
}

TEST(ClockSync, RecoversOffsetAndDriftOfSimulatedSessions) {
  struct Case {
    const char* label;
    std::uint64_t seed;
    double drift;
    double robot_jitter_s;
    std::uint64_t robot_clock_start_us;
    std::uint64_t tracker_clock_start_us;
  };
  const Case cases[] = {
      {"default", 1, 40e-6, 0.0004, 1000000000ULL, 5000000ULL},
      {"-100 ppm, 1 ms jitter", 2, -100e-6, 0.001, 3600000000000ULL, 42ULL},
      {"+100 ppm, tracker ahead", 3, 100e-6, 0.0002, 1000ULL, 86400000000ULL},
      {"no drift, 2 ms jitter", 4, 0.0, 0.002, 77000000ULL, 76000000ULL},
      {"-30 ppm", 5, -30e-6, 0.0005, 123456789ULL, 987654321ULL},
  };
  for (const Case& c : cases) {
    sim::SimConfig config;
    sim::use_large_errors(&config);  // the 1 mm tool error these tests were written for
    config.seed = c.seed;
    config.clock_drift = c.drift;
    config.robot_jitter_s = c.robot_jitter_s;
    config.robot_clock_start_us = c.robot_clock_start_us;
    config.tracker_clock_start_us = c.tracker_clock_start_us;
    expect_recovered(config, c.label);
  }
}

// The scan keeps the path lengths of one chord's points in a ring of kMaxChordSpanPoints + 1:
// the longest chord it allows recovers the clock as the default does.
TEST(ClockSync, TheLongestChordsRecoverTheClock) {
  sim::SimConfig config;
  sim::use_large_errors(&config);
  config.seed = 1;
  config.clock_drift = 40e-6;
  expect_recovered(config, "chords of the most intervals", kMaxChordSpanPoints);
}

TEST(ClockSync, StreamsStartingMidMotionAndAtDifferentTimes) {
  sim::SimConfig config;
  sim::use_large_errors(&config);  // the 1 mm tool error these tests were written for
  config.seed = 11;
  config.clock_drift = 70e-6;
  const sim::Session probe(config);
  const sim::Segment& first_move = probe.schedule()[1];
  const sim::Segment& third_move = probe.schedule()[5];
  config.robot_start_s = first_move.start_s + 0.4 * first_move.duration_s;
  config.tracker_start_s = third_move.start_s + 0.5 * third_move.duration_s;
  expect_recovered(config, "mid-motion starts");
  // And the other way round: the tracker starts first, the robot publisher later.
  std::swap(config.robot_start_s, config.tracker_start_s);
  expect_recovered(config, "robot late, mid-motion");
}

TEST(ClockSync, LossyStreams) {
  sim::SimConfig config;
  sim::use_large_errors(&config);  // the 1 mm tool error these tests were written for
  config.seed = 12;
  config.robot_drop_probability = 0.02;
  config.beam_lost_probability = 0.02;
  config.unstable_probability = 0.05;
  expect_recovered(config, "2% robot, 2%+5% tracker loss");
}

TEST(ClockSync, ToleratesAToolModelError) {
  // The speed model's tool is 5 mm off the true one: per-block gains keep the timing unbiased.
  sim::SimConfig config;
  sim::use_large_errors(&config);  // the 1 mm tool error these tests were written for
  config.seed = 13;
  config.tool_sigma_m = 5e-3;
  expect_recovered(config, "5 mm tool error");
}

/// Feeds a session with some tracker points moved by `offset_m` (by index among all tracker
/// records), then estimates; the fit must be as good as without them, and each moved point
/// must be set aside (`all_set_aside`; a move within the jump limit may just be outweighed).
void expect_blunders_set_aside(const sim::SimConfig& config, std::initializer_list<std::size_t> bad_indices,
                               const Vec3& offset_m, const char* label, bool all_set_aside = true) {
  const sim::Session session(config);
  ClockEstimatorBase& estimator = estimator_with(config_for(session));
  sim::RobotStream robot(session);
  JointStateRecord joint;
  while (robot.next(&joint)) estimator.push_robot(joint);
  sim::TrackerStream tracker(session);
  TrackerPointRecord point;
  std::size_t index = 0;
  std::uint64_t bad_valid = 0;
  for (; tracker.next(&point); ++index) {
    for (std::size_t bad : bad_indices) {
      if (index != bad) continue;
      for (int a = 0; a < 3; ++a) point.point_m[a] += offset_m(a);
      bad_valid += point.is_valid() ? 1 : 0;
    }
    EXPECT_NO_HEAP(estimator.push_tracker(point));
  }
  ClockFit fit;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = estimator.estimate(&fit));
  ASSERT_EQ(status, Status::ok) << label;
  EXPECT_LT(max_clock_error_us(fit, session), kTargetUs) << label;
  if (all_set_aside) {
    EXPECT_EQ(estimator.stats().tracker_set_aside, bad_valid) << label;
    for (std::uint64_t k = 0; k < bad_valid && k < kClockSetAsideLog; ++k)
      EXPECT_GT(estimator.stats().set_aside_tracker_us[k], 0u) << label;
  }
  std::printf("%-32s set aside %llu, max err %.1f us\n", label,
              static_cast<unsigned long long>(estimator.stats().tracker_set_aside), max_clock_error_us(fit, session));
}

TEST(ClockSync, SetsAsideBlunderPointsOfTheTracker) {
  sim::SimConfig config;
  config.seed = 14;
  // Without the blunder gate (max_tool_speed_m_s = 1e9) the first case misses by 88 ms and
  // the burst by 1.4 s. One point 0.6 m off among 6,000 broke the whole fit before.
  expect_blunders_set_aside(config, {3000}, Vec3(0.6, 0.0, 0.0), "one point 0.6 m off");
  // A burst of three consecutive bad points at the same wrong place, and scattered ones.
  expect_blunders_set_aside(config, {1500, 1501, 1502}, Vec3(0.0, -0.8, 0.3), "burst of 3 points 0.85 m off");
  expect_blunders_set_aside(config, {100, 2222, 4000, 5900}, Vec3(2.0, 2.0, 0.0), "4 scattered points 2.8 m off");
}

/// Index of the first valid tracker record after the n-th beam loss of the session.
std::size_t after_beam_loss(const sim::SimConfig& config, int n) {
  const sim::Session session(config);
  sim::TrackerStream tracker(session);
  TrackerPointRecord point;
  bool lost = false;
  for (std::size_t index = 0; tracker.next(&point); ++index) {
    if (!point.is_valid()) {
      lost = true;
    } else if (lost && n-- == 0) {
      return index;
    } else {
      lost = false;
    }
  }
  return 0;
}

// A wild point beside a beam loss is within reach of the track on both sides (the gap doubles
// the time); one within the jump limit (0.15 m in 0.1 s) is not held at all. Neither may move
// the clock: before, either gave "clock relation not found" at some rows of a 6,000-point session.
TEST(ClockSync, AWildPointWithinTheJumpLimitsDoesNotMoveTheClock) {
  sim::SimConfig config;
  config.seed = 3;
  expect_blunders_set_aside(config, {}, Vec3::Zero(), "no wild point");
  for (int n = 0; n < 4; ++n) {
    const std::size_t index = after_beam_loss(config, n);
    ASSERT_GT(index, 0u) << "the session has no beam loss";
    expect_blunders_set_aside(config, {index}, Vec3(0.0, 0.6, 0.0), "0.6 m after a beam loss", false);
    expect_blunders_set_aside(config, {index - 2}, Vec3(0.0, 0.6, 0.0), "0.6 m before a beam loss", false);
    expect_blunders_set_aside(config, {index}, Vec3(0.0, 0.0, -0.15), "0.15 m after a beam loss", false);
  }
  for (std::size_t index : {100u, 2222u, 4000u})
    expect_blunders_set_aside(config, {index}, Vec3(0.0, 0.15, 0.0), "0.15 m mid-track", false);
}

TEST(ClockSync, FailsWithoutMotion) {
  const RobotModel model = nominal_model(RobotType::ur5);
  ClockEstimatorBase& estimator = estimator_with(make_clock_sync_config(model));
  JointStateRecord joint;
  for (int j = 0; j < kSixJoints; ++j) joint.q_rad[j] = 0.3 * j - 1.0;
  for (int i = 0; i < 40000; ++i) {
    joint.timestamp_us = 1000000ULL + 8000ULL * static_cast<std::uint64_t>(i);
    estimator.push_robot(joint);
  }
  TrackerPointRecord point;
  for (int i = 0; i < 3000; ++i) {
    point.timestamp_us = 100000ULL * static_cast<std::uint64_t>(i);
    point.point_m[0] = 1.0 + 1e-5 * ((i * 7) % 3);
    estimator.push_tracker(point);
  }
  ClockFit fit;
  EXPECT_EQ(estimator.estimate(&fit), Status::clock_fit_failed);
}

/// Back-and-forth moves of joint 1 (smoothstep over 5 s, then a pause); cycle i lasts
/// cycle_s(i). Robot at 125 Hz, tracker at 10 Hz with its clock 3.3 s behind.
template <typename CycleLength>
Status estimate_back_and_forth(CycleLength cycle_s) {
  const RobotModel model = nominal_model(RobotType::ur5);
  ClockEstimatorBase& estimator = estimator_with(make_clock_sync_config(model));
  auto joints_at = [&](double t_s) {
    int cycle = 0;
    while (t_s >= cycle_s(cycle)) t_s -= cycle_s(cycle++);
    const double u = t_s < 5.0 ? t_s / 5.0 : 1.0;
    const double s = u * u * (3.0 - 2.0 * u);
    JointVector q;
    q << 0.2 + (cycle % 2 == 0 ? s : 1.0 - s), -1.5, 1.6, -1.6, -1.57, 0.0;
    return q;
  };
  for (int i = 0; i < 300 * 125; ++i) {
    JointStateRecord joint;
    joint.timestamp_us = 8000ULL * static_cast<std::uint64_t>(i);
    const JointVector q = joints_at(static_cast<double>(i) * 0.008);
    for (int j = 0; j < kSixJoints; ++j) joint.q_rad[j] = q(j);
    estimator.push_robot(joint);
  }
  for (int i = 0; i < 2900; ++i) {
    TrackerPointRecord point;
    point.timestamp_us = 100000ULL * static_cast<std::uint64_t>(i);
    const Vec3 p = fk_tool_point(model, joints_at(static_cast<double>(i) * 0.1 + 3.3));
    for (int a = 0; a < 3; ++a) point.point_m[a] = p(a);
    estimator.push_tracker(point);
  }
  ClockFit fit;
  const Status status = estimator.estimate(&fit);
  if (status == Status::ok) {
    EXPECT_NEAR(fit.offset_us, 3.3e6, kTargetUs);
  }
  return status;
}

TEST(ClockSync, FailsWhenTheMotionIsPeriodic) {
  // Equal cycles: any whole number of cycles fits as well, so the offset is ambiguous.
  EXPECT_EQ(estimate_back_and_forth([](int) { return 10.0; }), Status::clock_fit_failed);
  // The same moves with pauses of random length are unambiguous.
  double cycles_s[64];
  Random random(5);
  for (double& c : cycles_s) c = random.uniform(7.0, 12.0);
  EXPECT_EQ(estimate_back_and_forth([&](int i) { return cycles_s[i % 64]; }), Status::ok);
}

TEST(ClockSync, RejectsBadConfiguration) {
  ClockSyncConfig config = make_clock_sync_config(nominal_model(RobotType::ur5));
  config.coarse_step_us = config.knot_interval_us;  // must be at least two knots
  ClockEstimatorBase& estimator = estimator_with(config);
  ClockFit fit;
  EXPECT_EQ(estimator.estimate(&fit), Status::invalid_argument);
  config = make_clock_sync_config(nominal_model(RobotType::ur5));
  config.chord_span_points = kMaxChordSpanPoints + 1;  // longer than the scan's ring
  EXPECT_EQ(estimator_with(config).estimate(&fit), Status::invalid_argument);
}

/// Rms of the bins' residuals and of their tracker speeds [m/s].
void match_rms(const ClockMatch& match, double* residual_m_s, double* tracker_m_s) {
  double r2 = 0.0, v2 = 0.0;
  for (std::size_t k = 0; k < match.count; ++k) {
    r2 += match.bins[k].residual_m_s * match.bins[k].residual_m_s;
    v2 += match.bins[k].tracker_speed_m_s * match.bins[k].tracker_speed_m_s;
  }
  const double n = static_cast<double>(match.count);
  *residual_m_s = std::sqrt(r2 / n);
  *tracker_m_s = std::sqrt(v2 / n);
}

TEST(ClockSync, MatchedProfilesShowTheFitAndChangeNoResult) {
  sim::SimConfig config;
  sim::use_large_errors(&config);
  config.seed = 1;
  config.clock_drift = 40e-6;
  const sim::Session session(config);
  ClockEstimatorBase& estimator = estimator_with(config_for(session));
  test::feed_clock(session, &estimator);
  ClockFit fit;
  ASSERT_EQ(estimator.estimate(&fit), Status::ok);
  static ClockMatch match;
  static ClockMatch shifted;
  constexpr std::size_t kBins = 256;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = estimator.match_profiles(fit, kBins, &match));
  ASSERT_EQ(status, Status::ok);
  ASSERT_GT(match.count, kBins / 2);
  ASSERT_LE(match.count, kBins);
  std::uint64_t chords = 0;
  for (std::size_t k = 0; k < match.count; ++k) {
    chords += match.bins[k].chords;
    if (k > 0) {
      EXPECT_GT(match.bins[k].tracker_s, match.bins[k - 1].tracker_s) << k;
    }
  }
  EXPECT_GE(match.bins[0].tracker_s, 0.0);
  EXPECT_NEAR(static_cast<double>(chords), fit.chords_used, 0.05 * fit.chords_used);
  // Observation only: estimating again gives the same bits.
  ClockFit again;
  ASSERT_EQ(estimator.estimate(&again), Status::ok);
  EXPECT_EQ(std::memcmp(&again, &fit, sizeof fit), 0);
  // A clock 0.3 s off leaves the profiles apart: the residual grows many times.
  ClockFit off = fit;
  off.offset_at_reference_us += 300000.0;
  ASSERT_EQ(estimator.match_profiles(off, kBins, &shifted), Status::ok);
  double residual = 0.0, speed = 0.0, residual_off = 0.0, speed_off = 0.0;
  match_rms(match, &residual, &speed);
  match_rms(shifted, &residual_off, &speed_off);
  std::printf(
      "matched profiles: %zu bins, %llu chords (fit %u), rms tracker speed %.1f mm/s, residual %.2f mm/s; "
      "0.3 s off: %.2f mm/s\n",
      match.count, static_cast<unsigned long long>(chords), fit.chords_used, speed * 1e3, residual * 1e3,
      residual_off * 1e3);
  EXPECT_GT(speed, 0.01);
  EXPECT_LT(residual, 0.05 * speed);
  EXPECT_GT(residual_off, 5.0 * residual);
  EXPECT_EQ(estimator.match_profiles(fit, 0, &match), Status::invalid_argument);
  EXPECT_EQ(estimator.match_profiles(fit, kClockMatchBins + 1, &match), Status::invalid_argument);
  EXPECT_EQ(estimator.match_profiles(fit, kBins, nullptr), Status::invalid_argument);
}

TEST(ClockSync, ConstantMemoryOnAnHourLongCapture) {
  // Small profiles (16384 knots = 5.5 min, 2048 points = 3.4 min) over a one-hour session:
  // the rest is counted, not stored, and the fit from the first minutes holds for the hour.
  sim::SimConfig config;
  sim::use_large_errors(&config);  // the 1 mm tool error these tests were written for
  config.seed = 14;
  config.waypoint_count = 230;
  config.duration_s = 3600.0;
  config.clock_drift = -50e-6;
  const sim::Session session(config);
  static ClockEstimator<16384, 2048> small(config_for(session));
  EXPECT_EQ(sizeof(small), sizeof(ClockEstimatorBase) + 16384 * 8 + 2048 * 16 + (2048 + 8192) * 8);
  ClockFit fit;
  Status status = Status::ok;
  EXPECT_NO_HEAP(test::feed_clock(session, &small));
  EXPECT_NO_HEAP(status = small.estimate(&fit));
  ASSERT_EQ(status, Status::ok);
  EXPECT_GT(small.stats().robot_beyond_capacity, 400000u);
  EXPECT_GT(small.stats().tracker_beyond_capacity, 30000u);
  EXPECT_EQ(small.stats().robot_knots, 16384u);
  const sim::SimTruth& truth = session.truth();
  const auto early_us = static_cast<double>(session.tracker_clock_us(100.0));
  EXPECT_NEAR(fit.robot_us(early_us), truth.clock_offset_us + (1.0 + truth.clock_drift) * early_us, kTargetUs);
  std::printf("1 h capture, 3.4 min fitted: max error over the hour %.1f us (drift sigma %.2f ppm)\n",
              max_clock_error_us(fit, session), fit.sigma_drift * 1e6);
}

}  // namespace
}  // namespace hivecal::clock_sync_test
