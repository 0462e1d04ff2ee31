// Feeds simulated device streams (apps/sim) into the sync and extraction classes, the way
// the serial readers would: each stream in its own time order.
#pragma once

#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "sim/sim_model.hpp"

namespace hivecal::test {

/// The simulator settings the extraction tests and their digest were set on: large errors.
inline sim::SimConfig large_error_config(std::uint64_t seed) {
  sim::SimConfig config;
  sim::use_large_errors(&config);
  config.seed = seed;
  return config;
}

/// The same over `waypoint_count` waypoints in `duration_s`.
inline sim::SimConfig large_error_config(std::uint64_t seed, int waypoint_count, double duration_s) {
  sim::SimConfig config = large_error_config(seed);
  config.waypoint_count = waypoint_count;
  config.duration_s = duration_s;
  return config;
}

/// Pushes the whole robot stream, then the whole tracker stream (allowed: the estimator
/// keeps the two profiles apart).
inline void feed_clock(const sim::Session& session, ClockEstimatorBase* estimator) {
  sim::RobotStream robot(session);
  JointStateRecord joint;
  while (robot.next(&joint)) estimator->push_robot(joint);
  sim::TrackerStream tracker(session);
  TrackerPointRecord point;
  while (tracker.next(&point)) estimator->push_tracker(point);
}

/// What feed_extractor saw come back from the pushes.
struct FeedResult {
  std::size_t dataset_full_returns = 0;  ///< pushes that returned Status::dataset_full
  std::size_t other_errors = 0;          ///< pushes that returned anything else but ok
};

/// Runs a push as it is: the default `around_push` of feed_extractor.
struct PlainPush {
  template <typename Push>
  Status operator()(Push push) const {
    return push();
  }
};

/// Pushes both streams interleaved in true-time order (as live ports deliver them), then
/// finish(). `lead_s` delays the tracker stream (positive) or the robot stream (negative).
/// Each push runs as around_push(push) (say, under the allocation trap); finish() does not.
template <typename AroundPush = PlainPush>
FeedResult feed_extractor(const sim::Session& session, SampleExtractorBase* extractor, double lead_s = 0.0,
                          AroundPush around_push = AroundPush()) {
  FeedResult result;
  auto note = [&result](Status s) {
    if (s == Status::dataset_full)
      ++result.dataset_full_returns;
    else if (s != Status::ok)
      ++result.other_errors;
  };
  sim::RobotStream robot(session);
  sim::TrackerStream tracker(session);
  JointStateRecord joint;
  TrackerPointRecord point;
  bool has_joint = robot.next(&joint);
  bool has_point = tracker.next(&point);
  while (has_joint || has_point) {
    const bool tracker_first =
        has_point && (!has_joint || tracker.last_true_time_s() + lead_s < robot.last_true_time_s());
    if (tracker_first) {
      note(around_push([&] { return extractor->push_tracker(point); }));
      has_point = tracker.next(&point);
    } else {
      note(around_push([&] { return extractor->push_robot(joint); }));
      has_joint = robot.next(&joint);
    }
  }
  note(extractor->finish());
  return result;
}

}  // namespace hivecal::test
