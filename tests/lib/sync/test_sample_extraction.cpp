// Quasi-static sample extraction: pairing against the simulator's truth, resampling on
// uneven timestamps, status filtering, the speed rule on both sides, gaps, ranges, ring
// overruns, dataset_full and constant memory over hours (the golden digest of the output:
// test_extraction_golden.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "hivecal/core/digest.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "sim/sim_model.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::sample_extraction_test {
namespace {

using test::large_error_config;

const RobotModel kUr5 = nominal_model(RobotType::ur5);

/// Collects every decision.
struct Recorder final : ExtractionObserver {
  Recorder() {  // room enough that recording allocates nothing inside the library calls
    samples.reserve(8192);
    drops.reserve(16384);
  }
  std::vector<ExtractedSample> samples;
  std::vector<std::pair<std::uint64_t, DropReason>> drops;
  void on_sample(const ExtractedSample& sample) override { samples.push_back(sample); }
  void on_drop(std::uint64_t tracker_us, DropReason reason) override { drops.emplace_back(tracker_us, reason); }
};

/// Every pushed tracker point is decided exactly once.
void expect_accounted(const ExtractionCounts& counts) {
  EXPECT_EQ(counts.pending(), 0u);
  EXPECT_EQ(counts.kept + counts.dropped_total(), counts.tracker_points);
}

/// The counts, one reason a line (for failure messages and logs).
std::string describe(const ExtractionCounts& counts) {
  std::string text = "kept " + std::to_string(counts.kept) + " of " + std::to_string(counts.tracker_points);
  for (int r = 0; r < kDropReasonCount; ++r)
    if (counts.dropped[r] != 0)
      text +=
          std::string(", ") + drop_reason_name(static_cast<DropReason>(r)) + " " + std::to_string(counts.dropped[r]);
  return text;
}

/// A clock relation with known offset and drift (reference at tracker time 0).
ClockFit known_clock(double offset_us, double drift) {
  ClockFit fit;
  fit.offset_us = offset_us;
  fit.offset_at_reference_us = offset_us;
  fit.drift = drift;
  return fit;
}

/// Synthetic streams over `duration_s`: robot records of joints_at(t) at ~125 Hz with
/// 0.5 ms jitter, tracker records every 100 ms of point_at(t) and status_at(i), both in
/// true time t [s]; the tracker clock is the robot's mapped through `clock`.
template <typename JointsAt, typename PointAt, typename StatusAt>
void feed_synthetic(SampleExtractorBase* extractor, const ClockFit& clock, double duration_s, JointsAt joints_at,
                    PointAt point_at, StatusAt status_at) {
  Random random(3);
  const double robot_start_us = 1e9;
  // Tracker instant i is at robot time robot_start + 50 ms + i * 100 ms, stamped on the tracker clock.
  auto tracker_stamp_us = [&](int i) {
    const double robot_us = robot_start_us + 5e4 + 1e5 * i;
    return std::round((robot_us - clock.offset_at_reference_us + clock.drift * clock.reference_tracker_us) /
                      (1.0 + clock.drift));
  };
  double robot_t_us = robot_start_us;
  int tracker_index = 0;
  while (robot_t_us < robot_start_us + duration_s * 1e6) {
    const double stamp_us = tracker_stamp_us(tracker_index);
    const double tracker_robot_us = clock.robot_us(stamp_us);
    if (tracker_robot_us - robot_start_us < duration_s * 1e6 && tracker_robot_us < robot_t_us) {
      TrackerPointRecord point;
      point.timestamp_us = static_cast<std::uint64_t>(stamp_us);
      const Vec3 p = point_at((tracker_robot_us - robot_start_us) * 1e-6);
      for (int a = 0; a < 3; ++a) point.point_m[a] = p(a);
      point.status = status_at(tracker_index);
      if (point.status == 1) point.point_m[0] = std::numeric_limits<double>::quiet_NaN();
      EXPECT_NO_HEAP(extractor->push_tracker(point));
      ++tracker_index;
      continue;
    }
    JointStateRecord joint;
    joint.timestamp_us = static_cast<std::uint64_t>(robot_t_us);
    const JointVector q = joints_at((static_cast<double>(joint.timestamp_us) - robot_start_us) * 1e-6);
    for (int j = 0; j < kSixJoints; ++j) joint.q_rad[j] = q(j);
    EXPECT_NO_HEAP(extractor->push_robot(joint));
    robot_t_us += std::round(8000.0 + 500.0 * random.normal());
  }
  EXPECT_NO_HEAP(extractor->finish());
}

JointVector home_pose() {
  JointVector q;
  q << 0.3, -1.5, 1.6, -1.67, -1.57, 0.2;
  return q;
}

TEST(Extraction, PairsQuasiStaticSamplesWithTheSimulatorTruth) {
  const sim::SimConfig config = large_error_config(21);
  const sim::Session session(config);
  static ClockEstimator<> estimator(make_clock_sync_config(session.truth().nominal));
  estimator.reset();
  test::feed_clock(session, &estimator);
  ClockFit fit;
  ASSERT_EQ(estimator.estimate(&fit), Status::ok);

  static Dataset<4096> dataset;
  dataset.clear();
  static SampleExtractor<> extractor(make_extraction_config(session.truth().nominal), fit, &dataset);
  extractor.reset(make_extraction_config(session.truth().nominal), fit, &dataset);
  Recorder recorder;
  extractor.set_observer(&recorder);
  const test::FeedResult fed = test::feed_extractor(session, &extractor);
  EXPECT_EQ(fed.other_errors, 0u);
  EXPECT_EQ(fed.dataset_full_returns, 0u);
  const ExtractionCounts& counts = extractor.counts();
  expect_accounted(counts);
  EXPECT_EQ(dataset.size(), counts.kept);

  // Every kept pair: joints = the pose at the true instant (quasi-static: within what
  // 2 mm/s over the clock error allows), point = truth within the tracker noise.
  double worst_q_rad = 0.0;
  double worst_point_m = 0.0;
  std::set<std::uint64_t> kept_instants;
  for (const ExtractedSample& s : recorder.samples) {
    const double t_s = session.true_time_of_tracker_us(static_cast<std::uint64_t>(s.tracker_us));
    const JointVector q_true = session.joints_at(t_s);
    worst_q_rad = std::max(worst_q_rad, (s.q_rad - q_true).cwiseAbs().maxCoeff());
    worst_point_m = std::max(worst_point_m, (s.point_m - session.true_point(q_true)).norm());
    EXPECT_LE(s.robot_speed_m_s, 0.002);
    EXPECT_LE(s.tracker_speed_m_s, 0.002);
    kept_instants.insert(static_cast<std::uint64_t>(s.tracker_us));
  }
  EXPECT_LT(worst_q_rad, 1e-5);
  EXPECT_LT(worst_point_m, 6.0 * config.tracker_noise_m);

  // Recall: every ideal sample well inside a stop is kept, unless its own point or too many
  // of its window's points were not valid.
  std::map<std::uint64_t, DropReason> dropped;
  for (const auto& [t_us, reason] : recorder.drops) dropped[t_us] = reason;
  std::size_t expected = 0;
  std::size_t found = 0;
  for (const sim::TruthSample& truth : sim::truth_samples(session, 0.6)) {
    const auto drop = dropped.find(truth.tracker_us);
    if (drop != dropped.end() && (drop->second == DropReason::beam_lost || drop->second == DropReason::unstable ||
                                  drop->second == DropReason::window_incomplete))
      continue;
    ++expected;
    found += kept_instants.count(truth.tracker_us);
    EXPECT_EQ(kept_instants.count(truth.tracker_us), 1u)
        << "ideal sample at " << truth.tracker_us << " dropped: " << drop_reason_name(drop->second);
  }
  std::printf("kept %llu of %llu tracker points; ideal samples found %zu / %zu; worst q %.2e rad, point %.1f um\n",
              static_cast<unsigned long long>(counts.kept), static_cast<unsigned long long>(counts.tracker_points),
              found, expected, worst_q_rad, worst_point_m * 1e6);
  for (int r = 0; r < kDropReasonCount; ++r)
    if (counts.dropped[r] != 0)
      std::printf("  dropped %-22s %llu\n", drop_reason_name(static_cast<DropReason>(r)),
                  static_cast<unsigned long long>(counts.dropped[r]));
  EXPECT_GT(expected, 300u);
  EXPECT_GT(counts.dropped_by(DropReason::beam_lost), 0u);
  EXPECT_GT(counts.dropped_by(DropReason::unstable), 0u);
  EXPECT_GT(counts.dropped_by(DropReason::moving_robot), counts.kept);
}

TEST(Extraction, DropsEveryStatusButValid) {
  static Dataset<256> dataset;
  dataset.clear();
  static SampleExtractor<> extractor(make_extraction_config(kUr5), known_clock(-1e6, 0.0), &dataset);
  extractor.reset(make_extraction_config(kUr5), known_clock(-1e6, 0.0), &dataset);
  const Vec3 p = fk_tool_point(kUr5, home_pose());
  const std::uint8_t statuses[] = {0, 1, 0, 2, 0, 7, 0, 255};
  feed_synthetic(
      &extractor, known_clock(-1e6, 0.0), 20.0, [](double) { return home_pose(); }, [&](double) { return p; },
      [&](int i) { return statuses[i % 8]; });
  const ExtractionCounts& counts = extractor.counts();
  expect_accounted(counts);
  EXPECT_EQ(counts.tracker_points, 200u);
  EXPECT_EQ(counts.dropped_by(DropReason::beam_lost), 25u);
  EXPECT_EQ(counts.dropped_by(DropReason::unstable), 25u);
  EXPECT_EQ(counts.dropped_by(DropReason::bad_status), 50u);
  // Valid ones are kept except within half a window of the ends of the streams.
  EXPECT_EQ(counts.kept + counts.dropped_by(DropReason::window_incomplete) +
                counts.dropped_by(DropReason::outside_robot_range),
            100u);
  EXPECT_GE(counts.kept, 90u);

  // A valid status with a NaN coordinate is not a measurement either.
  TrackerPointRecord nan_point;
  nan_point.timestamp_us = 5000000000ULL;
  nan_point.point_m[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(extractor.push_tracker(nan_point), Status::ok);
  EXPECT_EQ(extractor.counts().dropped_by(DropReason::non_finite_point), 1u);
  nan_point.point_m[2] = 0.0;
  EXPECT_EQ(extractor.push_tracker(nan_point), Status::ok);  // same timestamp again
  EXPECT_EQ(extractor.counts().dropped_by(DropReason::out_of_order), 1u);
}

TEST(Extraction, ResamplesJointsAtTheTrackerInstantOnUnevenTimestamps) {
  // A slow joint sine (tool well below 2 mm/s): linear interpolation between the uneven
  // robot samples must match the analytic joints at each mapped instant within
  // dt^2 / 8 * max|q''| (dt <= 11 ms here).
  const double amplitude_rad = 2e-3;
  const double omega_rad_s = 0.5;
  auto joints_at = [&](double t_s) {
    JointVector q = home_pose();
    q(0) += amplitude_rad * std::sin(omega_rad_s * t_s);
    q(5) += amplitude_rad * std::cos(omega_rad_s * t_s);
    return q;
  };
  static Dataset<1024> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(987654321.0, 80e-6);
  ExtractionConfig config = make_extraction_config(kUr5);
  static SampleExtractor<> extractor(config, clock, &dataset);
  extractor.reset(config, clock, &dataset);
  Recorder recorder;
  extractor.set_observer(&recorder);
  feed_synthetic(
      &extractor, clock, 60.0, joints_at, [&](double t_s) { return fk_tool_point(kUr5, joints_at(t_s)); },
      [](int) { return std::uint8_t{0}; });
  expect_accounted(extractor.counts());
  ASSERT_GT(recorder.samples.size(), 500u);
  const double bound_rad = 0.011 * 0.011 / 8.0 * amplitude_rad * omega_rad_s * omega_rad_s + 1e-15;
  double worst_rad = 0.0;
  for (const ExtractedSample& s : recorder.samples) {
    EXPECT_DOUBLE_EQ(s.robot_us, clock.robot_us(s.tracker_us));
    const JointVector q = joints_at((s.robot_us - 1e9) * 1e-6);
    worst_rad = std::max(worst_rad, (s.q_rad - q).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst_rad, bound_rad);
  std::printf("resampling error %.2e rad (bound %.2e)\n", worst_rad, bound_rad);
}

/// Robot at exactly 8 ms except a 100 ms hole after t = 5 s, tracker every 100 ms at x.x5 s,
/// the tool still: the counts of an extractor with `config`.
ExtractionCounts counts_around_a_robot_gap(const ExtractionConfig& config) {
  static Dataset<1024> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(0.0, 0.0);
  // The whole robot stream goes in first: a ring of 2048 (16 s) keeps all of it.
  static SampleExtractor<2048> extractor(config, clock, &dataset);
  extractor.reset(config, clock, &dataset);
  for (int i = 0; i <= 1250; ++i) {
    const std::uint64_t t_us = 8000ULL * static_cast<std::uint64_t>(i);
    if (t_us > 5000000 && t_us < 5100000) continue;
    JointStateRecord joint;
    joint.timestamp_us = t_us;
    for (int j = 0; j < kSixJoints; ++j) joint.q_rad[j] = home_pose()(j);
    (void)extractor.push_robot(joint);
  }
  for (int i = 10; i < 90; ++i) {
    TrackerPointRecord point;
    point.timestamp_us = 100000ULL * static_cast<std::uint64_t>(i) + 50000;
    (void)extractor.push_tracker(point);
  }
  EXPECT_EQ(extractor.finish(), Status::ok);
  expect_accounted(extractor.counts());
  return extractor.counts();
}

TEST(Extraction, NeverInterpolatesAcrossARobotGap) {
  // The paper's rule: only the speed baseline (+-12 ms) around 5.05 s meets the hole
  // (5.000 -> 5.104 s); every other point is kept.
  const ExtractionCounts at_instant = counts_around_a_robot_gap(make_extraction_config(kUr5));
  EXPECT_EQ(at_instant.dropped_by(DropReason::robot_gap), 1u) << describe(at_instant);
  EXPECT_EQ(at_instant.kept, 80u - 1u) << describe(at_instant);

  // A 1 s stability window: windows of +-0.5 s touch the hole for instants in (4.5, 5.6) s,
  // 11 points, and 3 at each end lack tracker data over their window.
  ExtractionConfig windowed = make_extraction_config(kUr5);
  windowed.window_us = 1000000;
  const ExtractionCounts counts = counts_around_a_robot_gap(windowed);
  EXPECT_EQ(counts.dropped_by(DropReason::robot_gap), 11u);
  EXPECT_EQ(counts.dropped_by(DropReason::window_incomplete), 6u) << describe(counts);
  EXPECT_EQ(counts.kept, 80u - 11u - 6u) << describe(counts);
}

TEST(Extraction, QuasiStaticRuleOnBothSides) {
  struct Case {
    const char* label;
    double robot_speed_m_s;
    double tracker_speed_m_s;
    DropReason expected;  // dataset_full stands for "kept"
  };
  const Case cases[] = {
      {"both still", 0.0, 0.0, DropReason::dataset_full},
      {"both at 1.5 mm/s", 0.0015, 0.0015, DropReason::dataset_full},
      {"robot at 3 mm/s", 0.003, 0.0, DropReason::moving_robot},
      {"tracker at 3 mm/s", 0.0, 0.003, DropReason::moving_tracker},
  };
  for (const Case& c : cases) {
    static Dataset<1024> dataset;
    dataset.clear();
    const ClockFit clock = known_clock(0.0, 0.0);
    // Both sides are tested over a stability window only (the paper's rule is robot-side).
    ExtractionConfig windowed = make_extraction_config(kUr5);
    windowed.window_us = 1000000;
    static SampleExtractor<> extractor(windowed, clock, &dataset);
    extractor.reset(windowed, clock, &dataset);
    // Joint 1 turns the tool (0.7 m from the axis) at the requested tool speed.
    const double radius_m = fk_tool_point(kUr5, home_pose()).head<2>().norm();
    auto joints_at = [&](double t_s) {
      JointVector q = home_pose();
      q(0) += c.robot_speed_m_s / radius_m * t_s;
      return q;
    };
    feed_synthetic(
        &extractor, clock, 20.0, joints_at, [&](double t_s) { return Vec3(1.0 + c.tracker_speed_m_s * t_s, 2.0, 0.5); },
        [](int) { return std::uint8_t{0}; });
    const ExtractionCounts& counts = extractor.counts();
    expect_accounted(counts);
    const std::uint64_t edge_drops =
        counts.dropped_by(DropReason::window_incomplete) + counts.dropped_by(DropReason::outside_robot_range);
    if (c.expected == DropReason::dataset_full) {
      EXPECT_EQ(counts.kept + edge_drops, counts.tracker_points) << c.label;
    } else {
      EXPECT_EQ(counts.kept, 0u) << c.label;
      EXPECT_EQ(counts.dropped_by(c.expected) + edge_drops, counts.tracker_points) << c.label;
    }
  }
}

TEST(Extraction, ShortPausesYieldTheirPoints) {
  // Moves of 0.83 s with a smooth (cosine) speed profile, 0.26 rad on joint 1 (~180 mm/s
  // peak), and pauses of 0.2 s: two tracker points a pause, at a phase that drifts from pause
  // to pause. The paper's rule keeps a point when the true tool speed at its instant is below
  // 2 mm/s; the extraction must keep (almost) all of those and nothing fast.
  constexpr double kMoveS = 0.83;
  constexpr double kPauseS = 0.2;
  constexpr double kCycleS = kMoveS + kPauseS;
  constexpr double kStrokeRad = 0.26;
  auto angle_at = [&](double t_s) {
    const double cycle = std::floor(t_s / kCycleS);
    const double in_cycle = t_s - cycle * kCycleS;
    const double move = in_cycle < kMoveS ? 0.5 * (1.0 - std::cos(3.141592653589793 * in_cycle / kMoveS)) : 1.0;
    return (cycle + move) * kStrokeRad;
  };
  auto joints_at = [&](double t_s) {
    JointVector q = home_pose();
    q(0) += angle_at(t_s);
    return q;
  };
  auto true_speed_m_s = [&](double t_s) {
    return (fk_tool_point(kUr5, joints_at(t_s + 1e-4)) - fk_tool_point(kUr5, joints_at(t_s - 1e-4))).norm() / 2e-4;
  };
  struct Kept final : ExtractionObserver {
    std::vector<double> robot_us;
    void on_sample(const ExtractedSample& sample) override { robot_us.push_back(sample.robot_us); }
  } kept;
  kept.robot_us.reserve(1024);  // the observer runs inside the no-heap checks
  static Dataset<1024> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(0.0, 0.0);
  static SampleExtractor<> extractor(make_extraction_config(kUr5), clock, &dataset);
  extractor.reset(make_extraction_config(kUr5), clock, &dataset);
  extractor.set_observer(&kept);
  constexpr double kDurationS = 40.0;
  feed_synthetic(
      &extractor, clock, kDurationS, joints_at, [&](double t_s) { return fk_tool_point(kUr5, joints_at(t_s)); },
      [](int) { return std::uint8_t{0}; });
  expect_accounted(extractor.counts());
  // The oracle: tracker instants (50 ms + i * 100 ms) where the true speed is below 2 mm/s.
  int oracle = 0;
  for (double t_s = 0.05; t_s < kDurationS - 0.05; t_s += 0.1) oracle += true_speed_m_s(t_s) < 0.002 ? 1 : 0;
  const int pauses = static_cast<int>(kDurationS / kCycleS);
  EXPECT_GE(oracle, 2 * pauses - 2);
  EXPECT_GE(static_cast<double>(kept.robot_us.size()), 0.97 * oracle) << describe(extractor.counts());
  EXPECT_LE(static_cast<int>(kept.robot_us.size()), oracle + 2) << describe(extractor.counts());
  for (double robot_us : kept.robot_us) EXPECT_LT(true_speed_m_s((robot_us - 1e9) * 1e-6), 0.004);
  std::printf("short pauses: kept %zu, oracle %d, pauses %d\n", kept.robot_us.size(), oracle, pauses);
}

TEST(Extraction, TrackerInstantsOutsideTheRobotRecord) {
  static Dataset<1024> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(0.0, 0.0);
  static SampleExtractor<> extractor(make_extraction_config(kUr5), clock, &dataset);
  extractor.reset(make_extraction_config(kUr5), clock, &dataset);
  auto push_tracker_at = [&](std::uint64_t t_us) {
    TrackerPointRecord point;
    point.timestamp_us = t_us;
    (void)extractor.push_tracker(point);
  };
  for (std::uint64_t t = 0; t < 2000000; t += 100000) push_tracker_at(t);  // before the robot
  for (int i = 0; i < 1000; ++i) {
    JointStateRecord joint;
    joint.timestamp_us = 3000000ULL + 8000ULL * static_cast<std::uint64_t>(i);
    (void)extractor.push_robot(joint);
  }
  for (std::uint64_t t = 20000000; t < 21000000; t += 100000) push_tracker_at(t);  // after it
  EXPECT_EQ(extractor.finish(), Status::ok);
  expect_accounted(extractor.counts());
  EXPECT_EQ(extractor.counts().dropped_by(DropReason::outside_robot_range), 30u);
}

TEST(Extraction, ReportsDatasetFull) {
  const sim::Session session(large_error_config(22, 10, 150.0));
  static Dataset<50> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(session.truth().clock_offset_us, session.truth().clock_drift);
  static SampleExtractor<> extractor(make_extraction_config(session.truth().nominal), clock, &dataset);
  extractor.reset(make_extraction_config(session.truth().nominal), clock, &dataset);
  const test::FeedResult fed = test::feed_extractor(session, &extractor);
  const ExtractionCounts& counts = extractor.counts();
  expect_accounted(counts);
  EXPECT_EQ(counts.kept, 50u);
  EXPECT_TRUE(dataset.full());
  EXPECT_GT(counts.dropped_by(DropReason::dataset_full), 50u);
  EXPECT_EQ(fed.dataset_full_returns, counts.dropped_by(DropReason::dataset_full));
  EXPECT_EQ(fed.other_errors, 0u);
}

TEST(Extraction, RingOverrunsAreCountedNotHidden) {
  const sim::Session session(large_error_config(23, 8, 100.0));
  const ClockFit clock = known_clock(session.truth().clock_offset_us, session.truth().clock_drift);
  static Dataset<1024> dataset;
  // Robot stream 3 s ahead of the tracker with a 1 s robot ring: history lost.
  dataset.clear();
  static SampleExtractor<125, 64> short_robot(make_extraction_config(session.truth().nominal), clock, &dataset);
  short_robot.reset(make_extraction_config(session.truth().nominal), clock, &dataset);
  (void)test::feed_extractor(session, &short_robot, 3.0);
  expect_accounted(short_robot.counts());
  // Only points in the robot stream's last second, which the ring still holds at the end.
  EXPECT_LE(short_robot.counts().kept, 12u);
  EXPECT_GT(short_robot.counts().dropped_by(DropReason::robot_history_overrun), 100u);
  // Tracker stream 5 s ahead with a 2 s tracker ring: undecided points pushed out.
  dataset.clear();
  static SampleExtractor<1024, 20> short_tracker(make_extraction_config(session.truth().nominal), clock, &dataset);
  short_tracker.reset(make_extraction_config(session.truth().nominal), clock, &dataset);
  (void)test::feed_extractor(session, &short_tracker, -5.0);
  expect_accounted(short_tracker.counts());
  EXPECT_GT(short_tracker.counts().dropped_by(DropReason::backlog_overrun), 100u);
}

TEST(Extraction, ConstantMemoryOverHours) {
  // Two hours of 125 Hz joints (900 000 records) through fixed rings into a small
  // dataset: no allocation, every point accounted for, dataset_full reported.
  const sim::Session session(large_error_config(24, 460, 7200.0));
  static Dataset<512> dataset;
  dataset.clear();
  const ClockFit clock = known_clock(session.truth().clock_offset_us, session.truth().clock_drift);
  static SampleExtractor<> extractor(make_extraction_config(session.truth().nominal), clock, &dataset);
  extractor.reset(make_extraction_config(session.truth().nominal), clock, &dataset);
  EXPECT_EQ(sizeof(extractor),
            sizeof(SampleExtractorBase) + 1024 * sizeof(ExtractorRobotEntry) + 64 * sizeof(ExtractorTrackerEntry));
  std::size_t allocations = 0;
  (void)test::feed_extractor(session, &extractor, 0.0, [&](auto push) {
    Status status = Status::ok;
    allocations += test::count_allocations([&] { status = push(); });
    return status;
  });
  EXPECT_EQ(allocations, 0u);
  const ExtractionCounts& counts = extractor.counts();
  expect_accounted(counts);
  EXPECT_GT(counts.robot_records, 890000u);
  EXPECT_EQ(counts.kept, 512u);
  EXPECT_GT(counts.dropped_by(DropReason::dataset_full), 5000u);
}

// Joint records of another joint count than the robot model are another arm's: refused by the
// extractor (the status says why) and the clock estimator (counted, and its fit says why),
// never cut or padded.
TEST(Extraction, RecordsOfAnotherJointCountAreRefused) {
  static Dataset<64> dataset;
  dataset.clear();
  static SampleExtractor<> extractor(make_extraction_config(kUr5), known_clock(0.0, 0.0), &dataset);
  extractor.reset(make_extraction_config(kUr5), known_clock(0.0, 0.0), &dataset);
  JointStateRecord six;
  six.timestamp_us = 1000;
  EXPECT_EQ(extractor.push_robot(six), Status::ok);
  JointStateRecord seven = six;
  seven.timestamp_us = 9000;
  seven.joint_count = 7;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = extractor.push_robot(seven));
  EXPECT_EQ(status, Status::joint_count_mismatch);

  static ClockEstimator<> estimator(make_clock_sync_config(kUr5));
  estimator.reset();
  for (int k = 0; k < 100; ++k) {
    JointStateRecord r;
    r.timestamp_us = 8000 * static_cast<std::uint64_t>(k + 1);
    r.joint_count = k == 50 ? 5 : kSixJoints;
    estimator.push_robot(r);
  }
  EXPECT_EQ(estimator.stats().robot_joint_count_mismatches, 1u);
  EXPECT_EQ(estimator.stats().robot_rejected, 1u);
  ClockFit fit;
  EXPECT_EQ(estimator.estimate(&fit), Status::joint_count_mismatch);
}

}  // namespace
}  // namespace hivecal::sample_extraction_test
