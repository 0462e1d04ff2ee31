// Captures to a dataset (sync/capture_dataset.hpp): a simulated capture pair gives the true
// clock and samples at the simulated joints; the passes open the captures once each and use the
// workspace's arena one object at a time; re-runs give the same bits; null arguments, open and
// read failures, empty or garbage captures and a full dataset name their status and pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/sync/capture_dataset.hpp"
#include "sim/sim_model.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"
#include "testkit/sync_checks.hpp"
#include "testkit/sim_capture.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::capture_dataset_test {
namespace {

using test::Bytes;

/// The simulated session and its capture pair (testkit/sim_capture.hpp).
const sim::Session& session() {
  return test::capture_session();
}
const test::SimCapture& capture() {
  return test::sim_capture();
}

/// A ByteReader that always fails.
class BrokenReader final : public ByteReader {
 public:
  Status read(std::uint8_t*, std::size_t, std::size_t*) override { return Status::read_failed; }
};

/// Both captures in memory; counts open() calls; open number `fail_open` fails, and on open
/// number `broken_tracker_open` the tracker reader fails.
class MemoryCaptures final : public CaptureSource {
 public:
  MemoryCaptures(const Bytes& robot, const Bytes& tracker)
      : robot_(Span<const std::uint8_t>(robot.data(), robot.size())),
        tracker_(Span<const std::uint8_t>(tracker.data(), tracker.size())) {}
  Status open(ByteReader** robot, ByteReader** tracker) override {
    ++opens;
    if (opens == fail_open) return Status::read_failed;
    robot_.rewind();
    tracker_.rewind();
    *robot = &robot_;
    *tracker = opens == broken_tracker_open ? static_cast<ByteReader*>(&broken_) : &tracker_;
    return Status::ok;
  }
  int opens = 0;
  int fail_open = 0;
  int broken_tracker_open = 0;

 private:
  MemoryByteReader robot_;
  MemoryByteReader tracker_;
  BrokenReader broken_;
};

/// Collects the kept samples (room reserved: recording allocates nothing).
struct Recorder final : ExtractionObserver {
  Recorder() { samples.reserve(2048); }
  void on_sample(const ExtractedSample& sample) override { samples.push_back(sample); }
  std::vector<ExtractedSample> samples;
};

/// Clock profiles of 82 s and 102 s, extractor rings of 2 s and 6.4 s.
using Workspace = CaptureWorkspace<4096, 1024, 256, 64>;

/// A real workspace that logs the pass calls ('E' open_estimator, 'X' open_extractor, 'C'
/// close), keeps what it was given, and can attach an observer to the extractor.
class SpyWorkspace final : public CaptureWorkspaceBase {
 public:
  ClockEstimatorBase* open_estimator(const ClockSyncConfig& config) override {
    log('E');
    clock_config = config;
    return inner_.open_estimator(config);
  }
  SampleExtractorBase* open_extractor(const ExtractionConfig& config, const ClockFit& clock,
                                      DatasetBase* dataset) override {
    log('X');
    extraction_config = config;
    clock_given = clock;
    dataset_given = dataset;
    SampleExtractorBase* extractor = inner_.open_extractor(config, clock, dataset);
    extractor->set_observer(observer);
    return extractor;
  }
  void close() override {
    log('C');
    inner_.close();
  }
  void forget() {
    events[0] = '\0';
    event_count = 0;
    dataset_given = nullptr;
    observer = nullptr;
  }

  char events[16] = {};
  std::size_t event_count = 0;
  ClockSyncConfig clock_config;
  ExtractionConfig extraction_config;
  ClockFit clock_given;
  DatasetBase* dataset_given = nullptr;
  ExtractionObserver* observer = nullptr;

 private:
  void log(char event) {
    if (event_count + 1 < sizeof events) {
      events[event_count++] = event;
      events[event_count] = '\0';
    }
  }
  Workspace inner_;
};

static SpyWorkspace spy;
static Workspace workspace;
static Dataset<1024> dataset_a;
static Dataset<1024> dataset_b;

RobotModel nominal() {
  return session().truth().nominal;
}

bool same_extraction(const CaptureExtraction& a, const CaptureExtraction& b) {
  return a.status == b.status && a.pass == b.pass && test::same_fit(a.clock, b.clock) &&
         test::same_stats(a.decoding.robot_decoder, b.decoding.robot_decoder) &&
         test::same_stats(a.decoding.tracker_decoder, b.decoding.tracker_decoder) &&
         a.counts.tracker_points == b.counts.tracker_points && a.counts.kept == b.counts.kept &&
         a.counts.robot_records == b.counts.robot_records &&
         std::memcmp(a.counts.dropped, b.counts.dropped, sizeof a.counts.dropped) == 0;
}

/// A result full of leftovers from some earlier run.
CaptureExtraction stale_result() {
  CaptureExtraction r;
  r.status = Status::bad_crc;
  r.pass = CapturePass::done;
  r.decoding.robot_decoder.bytes_total = 777;
  r.clock.offset_us = 4.0e9;
  r.counts.kept = 999;
  return r;
}

/// Stale samples that must not survive pass 2.
void fill_with_junk(DatasetBase* dataset, std::size_t count) {
  dataset->clear();
  for (std::size_t i = 0; i < count; ++i) (void)dataset->add(JointVector::Constant(9.0), Vec3(7.0, 7.0, 7.0));
}

// ---------------------------------------------------------------------------------------

TEST(CaptureWorkspace, BuildsOnePassObjectAtATimeInItsArena) {
  using Small = CaptureWorkspace<1024, 256, 64, 16>;
  static_assert(Small::kArenaBytes == std::max(sizeof(Small::Estimator), sizeof(Small::Extractor)),
                "the arena is the larger of the two");
  // A workspace pays for the larger pass object, not for both.
  EXPECT_LT(sizeof(Small), sizeof(Small::Estimator) + sizeof(Small::Extractor));
  EXPECT_LT(sizeof(Workspace), sizeof(Workspace::Estimator) + sizeof(Workspace::Extractor));
  static Small small;
  const auto* begin = reinterpret_cast<const unsigned char*>(&small);
  const auto inside = [&](const void* p) {
    const auto* at = static_cast<const unsigned char*>(p);
    return at >= begin && at < begin + sizeof small;
  };
  ClockSyncConfig config = make_clock_sync_config(nominal());
  config.max_drift = 3e-4;
  ClockEstimatorBase* estimator = nullptr;
  EXPECT_NO_HEAP(estimator = small.open_estimator(config));
  ASSERT_NE(estimator, nullptr);
  EXPECT_TRUE(inside(estimator));
  EXPECT_EQ(estimator->config().max_drift, 3e-4);
  JointStateRecord joint;
  joint.timestamp_us = 1000;
  estimator->push_robot(joint);
  EXPECT_EQ(estimator->stats().robot_records, 1u);
  // Opening again ends the pass: a fresh estimator.
  EXPECT_NO_HEAP(estimator = small.open_estimator(config));
  ASSERT_NE(estimator, nullptr);
  EXPECT_EQ(estimator->stats().robot_records, 0u);

  ClockFit clock;
  clock.offset_at_reference_us = 123.0;
  dataset_a.clear();
  SampleExtractorBase* extractor = nullptr;
  EXPECT_NO_HEAP(extractor = small.open_extractor(make_extraction_config(nominal()), clock, &dataset_a));
  ASSERT_NE(extractor, nullptr);
  EXPECT_TRUE(inside(extractor));
  EXPECT_EQ(extractor->clock().offset_at_reference_us, 123.0);
  TrackerPointRecord point;
  point.timestamp_us = 5000;
  EXPECT_EQ(extractor->push_tracker(point), Status::ok);
  EXPECT_EQ(extractor->counts().tracker_points, 1u);
  EXPECT_NO_HEAP(extractor = small.open_extractor(make_extraction_config(nominal()), clock, &dataset_a));
  ASSERT_NE(extractor, nullptr);
  EXPECT_EQ(extractor->counts().tracker_points, 0u);
  EXPECT_NO_HEAP(small.close());
  EXPECT_NO_HEAP(small.close());  // closing twice is harmless
}

TEST(CaptureDataset, ASimulatedCaptureGivesTheTrueClockAndTheSimulatedJoints) {
  const test::SimCapture& c = capture();
  MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
  Recorder recorder;
  spy.forget();
  spy.observer = &recorder;
  fill_with_junk(&dataset_a, 5);
  CaptureExtraction result = stale_result();
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &spy, &dataset_a, &result));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(result.status, Status::ok);
  EXPECT_EQ(result.pass, CapturePass::done);
  // Each pass opens the captures once and uses the arena for one object, closed before the next.
  EXPECT_EQ(source.opens, 2);
  EXPECT_STREQ(spy.events, "ECXC");
  EXPECT_EQ(spy.dataset_given, &dataset_a);
  EXPECT_TRUE(test::same_fit(spy.clock_given, result.clock));  // pass 2 runs through pass 1's clock
  EXPECT_TRUE(spy.clock_config.speed_model.tool_m == nominal().tool_m);
  EXPECT_EQ(spy.extraction_config.max_speed_m_s, make_extraction_config(nominal()).max_speed_m_s);
  // Pass 1's decoder counters: every frame of both captures, nothing rejected.
  EXPECT_EQ(result.decoding.robot_decoder.joint_states, c.joints.size());
  EXPECT_EQ(result.decoding.robot_decoder.device_infos, 1u);
  EXPECT_EQ(result.decoding.robot_decoder.frames_rejected(), 0u);
  EXPECT_EQ(result.decoding.tracker_decoder.tracker_points, c.points.size());
  EXPECT_EQ(result.decoding.tracker_decoder.frames_rejected(), 0u);
  EXPECT_EQ(result.decoding.tracker_decoder.bytes_total, c.tracker_bytes.size());
  // The simulator's clocks: t_robot = offset + (1 + drift) t_tracker, over the whole session.
  const sim::Session& s = session();
  for (const double t_s : {0.0, s.duration_s()}) {
    const auto tracker_us = static_cast<double>(s.tracker_clock_us(t_s));
    EXPECT_NEAR(result.clock.robot_us(tracker_us),
                s.truth().clock_offset_us + (1.0 + s.truth().clock_drift) * tracker_us, 2000.0)
        << t_s;
  }
  // Pass 2: the dataset was emptied first and holds the kept samples, at the simulated joints
  // of their instants and near the true points.
  EXPECT_EQ(result.counts.tracker_points, c.points.size());
  EXPECT_EQ(result.counts.pending(), 0u);
  EXPECT_GT(result.counts.kept, 100u);
  ASSERT_EQ(dataset_a.size(), result.counts.kept);
  ASSERT_EQ(recorder.samples.size(), result.counts.kept);
  double worst_q_rad = 0.0;
  double worst_point_m = 0.0;
  for (std::size_t i = 0; i < dataset_a.size(); ++i) {
    const Sample& sample = dataset_a.samples()[i];
    EXPECT_NE(sample.q_rad(0), 9.0) << i;
    const ExtractedSample& e = recorder.samples[i];
    EXPECT_TRUE(e.q_rad == sample.q_rad) << i;
    const JointVector q_true = s.joints_at(s.true_time_of_tracker_us(static_cast<std::uint64_t>(e.tracker_us)));
    worst_q_rad = std::max(worst_q_rad, (sample.q_rad - q_true).cwiseAbs().maxCoeff());
    worst_point_m = std::max(worst_point_m, (sample.point_m - s.true_point(q_true)).norm());
  }
  EXPECT_LT(worst_q_rad, 1e-5);
  EXPECT_LT(worst_point_m, 6.0 * s.config().tracker_noise_m);
}

TEST(CaptureDataset, ReRunsAndSeparatePassesGiveTheSameBits) {
  const test::SimCapture& c = capture();
  MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
  CaptureExtraction first;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &workspace, &dataset_a, &first));
  ASSERT_EQ(status, Status::ok);
  // Again, over the same source and workspace.
  CaptureExtraction second = stale_result();
  fill_with_junk(&dataset_b, 3);
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &workspace, &dataset_b, &second));
  ASSERT_EQ(status, Status::ok);
  EXPECT_TRUE(same_extraction(second, first));
  EXPECT_TRUE(test::same_samples(dataset_b, dataset_a));
  // The two passes called one by one: each leaves its own pass in the result.
  CaptureExtraction separate;
  fill_with_junk(&dataset_b, 3);
  EXPECT_NO_HEAP(status = estimate_capture_clock(nominal(), source, &workspace, &separate));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(separate.pass, CapturePass::clock);
  EXPECT_TRUE(test::same_fit(separate.clock, first.clock));
  EXPECT_NO_HEAP(status = extract_capture_samples(nominal(), source, &workspace, &dataset_b, &separate));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(separate.pass, CapturePass::extraction);
  separate.pass = CapturePass::done;
  EXPECT_TRUE(same_extraction(separate, first));
  EXPECT_TRUE(test::same_samples(dataset_b, dataset_a));
  EXPECT_EQ(source.opens, 6);
}

TEST(CaptureDataset, NullArgumentsAreRefusedBeforeOpening) {
  const test::SimCapture& c = capture();
  MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
  CaptureExtraction result = stale_result();
  fill_with_junk(&dataset_a, 4);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, nullptr, &dataset_a, &result));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &workspace, nullptr, &result));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &workspace, &dataset_a, nullptr));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = estimate_capture_clock(nominal(), source, nullptr, &result));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = estimate_capture_clock(nominal(), source, &workspace, nullptr));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = extract_capture_samples(nominal(), source, nullptr, &dataset_a, &result));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = extract_capture_samples(nominal(), source, &workspace, nullptr, &result));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_NO_HEAP(status = extract_capture_samples(nominal(), source, &workspace, &dataset_a, nullptr));
  EXPECT_EQ(status, Status::invalid_argument);
  EXPECT_EQ(source.opens, 0);
  EXPECT_EQ(dataset_a.size(), 4u);      // untouched
  EXPECT_EQ(result.counts.kept, 999u);  // untouched
}

TEST(CaptureDataset, OpenAndReadFailuresNameThePass) {
  const test::SimCapture& c = capture();
  Status status = Status::ok;
  {  // The first open fails: nothing done, and *result was reset first.
    MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
    source.fail_open = 1;
    spy.forget();
    CaptureExtraction result = stale_result();
    EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &spy, &dataset_a, &result));
    EXPECT_EQ(status, Status::read_failed);
    EXPECT_EQ(result.status, Status::read_failed);
    EXPECT_EQ(result.pass, CapturePass::clock);
    EXPECT_TRUE(test::same_stats(result.decoding.robot_decoder, DecoderStats()));
    EXPECT_EQ(result.counts.kept, 0u);
    EXPECT_EQ(result.clock.offset_us, 0.0);
    EXPECT_STREQ(spy.events, "");
    EXPECT_EQ(source.opens, 1);
  }
  {  // The second open fails: the clock is there, the extraction never started.
    MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
    source.fail_open = 2;
    spy.forget();
    CaptureExtraction result;
    EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &spy, &dataset_a, &result));
    EXPECT_EQ(status, Status::read_failed);
    EXPECT_EQ(result.pass, CapturePass::extraction);
    EXPECT_EQ(result.decoding.robot_decoder.joint_states, c.joints.size());
    EXPECT_GT(result.clock.chords_used, 0u);
    EXPECT_STREQ(spy.events, "EC");
    EXPECT_EQ(source.opens, 2);
  }
  {  // The tracker capture cannot be read in pass 1: the estimator is still closed.
    MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
    source.broken_tracker_open = 1;
    spy.forget();
    CaptureExtraction result;
    EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &spy, &dataset_a, &result));
    EXPECT_EQ(status, Status::read_failed);
    EXPECT_EQ(result.pass, CapturePass::clock);
    EXPECT_STREQ(spy.events, "EC");
  }
  {  // ... or in pass 2.
    MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
    source.broken_tracker_open = 2;
    spy.forget();
    CaptureExtraction result;
    EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &spy, &dataset_a, &result));
    EXPECT_EQ(status, Status::read_failed);
    EXPECT_EQ(result.status, Status::read_failed);
    EXPECT_EQ(result.pass, CapturePass::extraction);
    EXPECT_STREQ(spy.events, "ECXC");
  }
  {  // The single passes report their own pass.
    MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
    source.fail_open = 1;
    CaptureExtraction result;
    EXPECT_NO_HEAP(status = extract_capture_samples(nominal(), source, &workspace, &dataset_a, &result));
    EXPECT_EQ(status, Status::read_failed);
    EXPECT_EQ(result.pass, CapturePass::extraction);
  }
}

TEST(CaptureDataset, EmptyOrGarbageCapturesFailTheClockPass) {
  const Bytes empty;
  Random random(81);
  Bytes garbage(20000);
  for (std::uint8_t& b : garbage) b = static_cast<std::uint8_t>(random.next());
  const RobotModel model = nominal();  // before the trap: the first call builds the shared session
  for (const Bytes* bytes : {&empty, static_cast<const Bytes*>(&garbage)}) {
    MemoryCaptures source(*bytes, *bytes);
    spy.forget();
    fill_with_junk(&dataset_a, 2);
    CaptureExtraction result;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = extract_dataset_from_captures(model, source, &spy, &dataset_a, &result));
    EXPECT_EQ(status, Status::clock_fit_failed) << bytes->size();
    EXPECT_EQ(result.status, Status::clock_fit_failed);
    EXPECT_EQ(result.pass, CapturePass::clock);
    EXPECT_STREQ(spy.events, "EC");  // no extraction without a clock
    EXPECT_EQ(source.opens, 1);
    EXPECT_EQ(result.decoding.robot_decoder.frames_ok + result.decoding.tracker_decoder.frames_ok, 0u);
    EXPECT_EQ(result.decoding.robot_decoder.bytes_total, bytes->size());
  }
}

TEST(CaptureDataset, AFullDatasetIsReportedAtTheExtractionPass) {
  const test::SimCapture& c = capture();
  MemoryCaptures source(c.robot_bytes, c.tracker_bytes);
  static Dataset<10> small;
  CaptureExtraction result;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = extract_dataset_from_captures(nominal(), source, &workspace, &small, &result));
  EXPECT_EQ(status, Status::dataset_full);
  EXPECT_EQ(result.status, Status::dataset_full);
  EXPECT_EQ(result.pass, CapturePass::extraction);
  EXPECT_EQ(small.size(), 10u);
  EXPECT_EQ(result.counts.kept, 10u);
  EXPECT_GT(result.counts.dropped_by(DropReason::dataset_full), 50u);
  EXPECT_EQ(result.counts.pending(), 0u);
}

/// The captures as records, decoded here by the test's own FrameRecordReaders (a host's source
/// of records: logs, or captures with progress).
class MemoryRecords final : public RecordSource {
 public:
  MemoryRecords(const Bytes& robot, const Bytes& tracker)
      : robot_bytes_(Span<const std::uint8_t>(robot.data(), robot.size())),
        tracker_bytes_(Span<const std::uint8_t>(tracker.data(), tracker.size())) {}
  Status open(RecordReader** robot, RecordReader** tracker) override {
    ++opens;
    robot_bytes_.rewind();
    tracker_bytes_.rewind();
    robot_ = std::make_unique<FrameRecordReader>(&robot_bytes_);
    tracker_ = std::make_unique<FrameRecordReader>(&tracker_bytes_);
    *robot = robot_.get();
    *tracker = tracker_.get();
    return Status::ok;
  }
  int opens = 0;

 private:
  MemoryByteReader robot_bytes_;
  MemoryByteReader tracker_bytes_;
  std::unique_ptr<FrameRecordReader> robot_;
  std::unique_ptr<FrameRecordReader> tracker_;
};

TEST(CaptureDataset, RecordsFrontHasTheBitsOfTheByteFrontAndDescribesTheClockMatch) {
  const test::SimCapture& c = capture();
  const RobotModel model = nominal();
  MemoryCaptures bytes(c.robot_bytes, c.tracker_bytes);
  CaptureExtraction from_bytes;
  ASSERT_EQ(extract_dataset_from_captures(model, bytes, &workspace, &dataset_a, &from_bytes), Status::ok);
  MemoryRecords records(c.robot_bytes, c.tracker_bytes);
  static ClockMatch match;
  struct MatchAtTheEndOfPassOne final : ClockPassObserver {
    void on_clock_pass(const ClockEstimatorBase& estimator, Status status, const ClockFit& fit) override {
      ++calls;
      EXPECT_EQ(status, Status::ok);
      EXPECT_EQ(estimator.match_profiles(fit, 64, &match), Status::ok);  // the profiles are still there
    }
    int calls = 0;
  } clock_observer;
  Recorder recorder;
  CaptureOptions options = make_capture_options(model);
  options.observer = &recorder;
  options.clock_observer = &clock_observer;
  CaptureExtraction from_records;
  ASSERT_EQ(extract_dataset_from_captures(records, options, &workspace, &dataset_b, &from_records), Status::ok);
  EXPECT_EQ(records.opens, 2);
  EXPECT_TRUE(same_extraction(from_bytes, from_records));
  EXPECT_TRUE(test::same_samples(dataset_a, dataset_b));
  EXPECT_EQ(recorder.samples.size(), from_records.counts.kept);
  EXPECT_EQ(clock_observer.calls, 1);
  EXPECT_GT(match.count, 0u);
  EXPECT_LE(match.count, 64u);
  EXPECT_EQ(from_records.clock_stats.robot_records, c.joints.size());  // every joint state went into pass 1's profile
  EXPECT_EQ(from_bytes.clock_stats.robot_records, c.joints.size());
}

}  // namespace
}  // namespace hivecal::capture_dataset_test
