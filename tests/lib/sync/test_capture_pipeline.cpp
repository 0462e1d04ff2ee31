// The two stream passes (sync/capture_pipeline.hpp): FrameRecordReader gives exactly the joint
// and tracker records of random wire streams, however the bytes arrive; pass 1 and pass 2 over
// a simulated capture give the fit and samples of direct feeding and of the simulation's truth;
// read failures, empty streams, foreign records and a full dataset are reported as documented.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/sync/capture_pipeline.hpp"
#include "sim/sim_model.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_stream.hpp"
#include "testkit/codec_support.hpp"
#include "testkit/sync_checks.hpp"
#include "testkit/sim_capture.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::capture_pipeline_test {
namespace {

using test::append_frame;
using test::Bytes;
using Records = std::vector<StreamRecord>;

// ---------------------------------------------------------------------------------------
// Byte and record sources.

/// Hands out 1..max_step bytes per read (sizes from a seed), then fails once `fail_after`
/// bytes were given (SIZE_MAX: never).
class ChoppyReader final : public ByteReader {
 public:
  ChoppyReader(const Bytes& bytes, std::size_t max_step, std::uint64_t seed, std::size_t fail_after = SIZE_MAX)
      : bytes_(bytes), max_step_(max_step), random_(seed), fail_after_(fail_after) {}
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override {
    if (position_ >= fail_after_) return Status::read_failed;
    std::size_t n = std::min({capacity, static_cast<std::size_t>(1 + random_.below(max_step_)),
                              bytes_.size() - position_, fail_after_ - position_});
    std::copy(bytes_.begin() + static_cast<long>(position_), bytes_.begin() + static_cast<long>(position_ + n), out);
    position_ += n;
    *count = n;
    return Status::ok;
  }

 private:
  const Bytes& bytes_;
  std::size_t max_step_;
  Random random_;
  std::size_t fail_after_;
  std::size_t position_ = 0;
};

/// Records from a vector (a parsed log, say); read_failed at index `fail_at`; counts what it
/// gave as frames of their type.
class VectorRecordReader final : public RecordReader {
 public:
  explicit VectorRecordReader(const Records& records, std::size_t fail_at = SIZE_MAX)
      : records_(records), fail_at_(fail_at) {}
  Status next(StreamRecord* record) override {
    if (index_ == fail_at_) return Status::read_failed;
    if (index_ == records_.size()) {
      *record = StreamRecord();
      return Status::ok;
    }
    *record = records_[index_++];
    ++counters_.frames_ok;
    if (record->kind == StreamRecord::Kind::joint_state) ++counters_.joint_states;
    if (record->kind == StreamRecord::Kind::tracker_point) ++counters_.tracker_points;
    return Status::ok;
  }
  const DecoderStats& counters() const override { return counters_; }

 private:
  const Records& records_;
  std::size_t fail_at_;
  std::size_t index_ = 0;
  DecoderStats counters_;
};

StreamRecord joint_record(const JointStateRecord& joint) {
  StreamRecord r;
  r.kind = StreamRecord::Kind::joint_state;
  r.joint = joint;
  return r;
}

StreamRecord point_record(const TrackerPointRecord& point) {
  StreamRecord r;
  r.kind = StreamRecord::Kind::tracker_point;
  r.point = point;
  return r;
}

bool same_record(const StreamRecord& a, const StreamRecord& b) {
  if (a.kind != b.kind) return false;
  if (a.kind == StreamRecord::Kind::joint_state) return test::same_bits(a.joint, b.joint);
  if (a.kind == StreamRecord::Kind::tracker_point) return test::same_bits(a.point, b.point);
  return true;
}

/// Every record of `reader` up to the end (or an error: *status), under the allocation trap.
Records drain(RecordReader& reader, Status* status) {
  Records records;
  for (;;) {
    StreamRecord record;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = reader.next(&record));
    if (s != Status::ok) {
      *status = s;
      return records;
    }
    if (record.kind == StreamRecord::Kind::end) break;
    records.push_back(record);
  }
  *status = Status::ok;
  return records;
}

/// What make_stream sent that a FrameRecordReader must give: its joint and tracker records
/// in frame order, for frames ending at or before `end_byte`.
Records expected_records(const test::SentStream& sent, std::size_t end_byte = SIZE_MAX) {
  Records records;
  for (const test::SentFrame& f : sent.frames) {
    if (f.end > end_byte) break;
    if (f.type == 1) records.push_back(joint_record(sent.joint_states[f.index]));
    if (f.type == 2) records.push_back(point_record(sent.tracker_points[f.index]));
  }
  return records;
}

void expect_same_records(const Records& got, const Records& expected, const char* label) {
  ASSERT_EQ(got.size(), expected.size()) << label;
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_TRUE(same_record(got[i], expected[i])) << label << ": record " << i;
  }
}

/// Ignores every decoded packet (to get a StreamDecoder's counters).
struct IgnoreFrames final : FrameHandler {};

DecoderStats decoder_stats_of(const Bytes& bytes) {
  StreamDecoder decoder;
  IgnoreFrames ignore;
  decoder.feed(bytes.data(), bytes.size(), ignore);
  return decoder.stats();
}

// ---------------------------------------------------------------------------------------
// A simulated capture: the session's records and their wire bytes (testkit/sim_capture.hpp),
// with the records as StreamRecords.

struct SimCapture : test::SimCapture {
  Records robot_records;    ///< joints as StreamRecords
  Records tracker_records;  ///< points as StreamRecords
};

const sim::Session& session() {
  return test::capture_session();
}

const SimCapture& capture() {
  static const SimCapture c = [] {
    SimCapture built;
    static_cast<test::SimCapture&>(built) = test::sim_capture();
    for (const JointStateRecord& joint : built.joints) built.robot_records.push_back(joint_record(joint));
    for (const TrackerPointRecord& point : built.points) built.tracker_records.push_back(point_record(point));
    return built;
  }();
  return c;
}

using Estimator = ClockEstimator<4096, 1024>;  // 82 s of robot data, 102 s of tracker points
using Extractor = SampleExtractor<256, 64>;    // 2 s of robot records: the window plus the merge lag

Estimator& estimator() {
  static Estimator e(make_clock_sync_config(session().truth().nominal));
  e.reset(make_clock_sync_config(session().truth().nominal));
  return e;
}

Extractor& extractor(const ClockFit& clock, DatasetBase* dataset) {
  static Extractor x(make_extraction_config(session().truth().nominal), clock, dataset);
  x.reset(make_extraction_config(session().truth().nominal), clock, dataset);
  return x;
}

static Dataset<1024> dataset_a;
static Dataset<1024> dataset_b;

/// The simulator's true clock relation as a ClockFit.
ClockFit true_clock() {
  ClockFit fit;
  fit.offset_us = session().truth().clock_offset_us;
  fit.offset_at_reference_us = fit.offset_us;
  fit.drift = session().truth().clock_drift;
  return fit;
}

bool same_counts(const ExtractionCounts& a, const ExtractionCounts& b) {
  return a.tracker_points == b.tracker_points && a.kept == b.kept && a.robot_records == b.robot_records &&
         a.robot_rejected == b.robot_rejected && std::memcmp(a.dropped, b.dropped, sizeof a.dropped) == 0;
}

/// Collects every extraction decision (room reserved: recording allocates nothing).
struct Recorder final : ExtractionObserver {
  Recorder() {
    samples.reserve(2048);
    drops.reserve(2048);
  }
  void on_sample(const ExtractedSample& sample) override { samples.push_back(sample); }
  void on_drop(std::uint64_t tracker_us, DropReason reason) override { drops.emplace_back(tracker_us, reason); }
  std::vector<ExtractedSample> samples;
  std::vector<std::pair<std::uint64_t, DropReason>> drops;
};

// ---------------------------------------------------------------------------------------
// FrameRecordReader.

TEST(FrameRecordReader, GivesEveryJointAndTrackerRecordOfRandomStreamsInOrder) {
  EXPECT_EQ(StreamRecord().kind, StreamRecord::Kind::end);
  test::StreamShape shape;
  shape.frames = 300;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    test::SentStream sent;
    test::make_stream(seed, shape, &sent);
    ASSERT_EQ(sent.library_allocations, 0u);
    MemoryByteReader bytes(Span<const std::uint8_t>(sent.bytes.data(), sent.bytes.size()));
    FrameRecordReader reader(&bytes);
    Status status = Status::invalid_argument;
    const Records got = drain(reader, &status);
    EXPECT_EQ(status, Status::ok);
    expect_same_records(got, expected_records(sent), "random stream");
    // The end is sticky.
    StreamRecord again = joint_record(JointStateRecord());
    EXPECT_NO_HEAP(status = reader.next(&again));
    EXPECT_EQ(status, Status::ok);
    EXPECT_EQ(again.kind, StreamRecord::Kind::end);
    // Its counters are the decoder's over the whole stream: DEVICE_INFO and unknown types
    // counted (not given as records), garbage rejected, every byte seen.
    const DecoderStats& counters = reader.counters();
    EXPECT_TRUE(test::same_stats(counters, decoder_stats_of(sent.bytes))) << seed;
    EXPECT_EQ(counters.joint_states, sent.joint_states.size());
    EXPECT_EQ(counters.tracker_points, sent.tracker_points.size());
    EXPECT_EQ(counters.device_infos, sent.device_infos.size());
    EXPECT_GT(sent.device_infos.size(), 0u);
    EXPECT_EQ(counters.unknown_types, sent.unknown_frames);
    EXPECT_EQ(counters.bytes_total, sent.bytes.size());
  }
}

TEST(FrameRecordReader, ResultsDoNotDependOnHowTheBytesArrive) {
  test::StreamShape shape;
  shape.frames = 250;
  test::SentStream sent;
  test::make_stream(7, shape, &sent);
  const Records expected = expected_records(sent);
  const DecoderStats whole = decoder_stats_of(sent.bytes);
  for (const std::size_t max_step : {std::size_t{1}, std::size_t{3}, std::size_t{47}, std::size_t{5000}}) {
    ChoppyReader bytes(sent.bytes, max_step, 100 + max_step);
    FrameRecordReader reader(&bytes);
    Status status = Status::invalid_argument;
    const Records got = drain(reader, &status);
    EXPECT_EQ(status, Status::ok) << max_step;
    expect_same_records(got, expected, "choppy");
    EXPECT_TRUE(test::same_stats(reader.counters(), whole)) << max_step;
  }
}

TEST(FrameRecordReader, BackToBackShortestFramesAreNeverLost) {
  // TRACKER_POINT frames (the shortest) with no idle bytes: a slice completes several at once.
  Random random(72);
  Bytes bytes;
  Records expected;
  for (std::uint16_t i = 0; i < 400; ++i) {
    const TrackerPointRecord point = test::random_tracker_point(&random, i, 1000u * i);
    expected.push_back(point_record(point));
    append_frame(point, encode_tracker_point, &bytes);
    if (i % 50 == 49) {  // and a few joint states between them
      const JointStateRecord joint = test::random_joint_state(&random, i, 1000u * i + 1);
      expected.push_back(joint_record(joint));
      append_frame(joint, encode_joint_state, &bytes);
    }
  }
  MemoryByteReader memory(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  FrameRecordReader reader(&memory);
  Status status = Status::invalid_argument;
  const Records got = drain(reader, &status);
  EXPECT_EQ(status, Status::ok);
  expect_same_records(got, expected, "back to back");
  EXPECT_EQ(reader.counters().frames_ok, expected.size());
}

TEST(FrameRecordReader, StartsAtTheByteReadersCurrentPosition) {
  test::StreamShape shape;
  shape.frames = 120;
  test::SentStream sent;
  test::make_stream(9, shape, &sent);
  const test::SentFrame& start = sent.frames[40];
  MemoryByteReader bytes(Span<const std::uint8_t>(sent.bytes.data(), sent.bytes.size()));
  Bytes skipped(start.begin);
  std::size_t count = 0;
  ASSERT_EQ(bytes.read(skipped.data(), skipped.size(), &count), Status::ok);
  ASSERT_EQ(count, start.begin);
  FrameRecordReader reader(&bytes);
  Status status = Status::invalid_argument;
  const Records got = drain(reader, &status);
  EXPECT_EQ(status, Status::ok);
  Records expected = expected_records(sent);
  const Records before = expected_records(sent, start.begin);
  expected.erase(expected.begin(), expected.begin() + static_cast<long>(before.size()));
  expect_same_records(got, expected, "from frame 40");
  EXPECT_EQ(reader.counters().bytes_total, sent.bytes.size() - start.begin);
}

TEST(FrameRecordReader, AReadFailureComesAfterTheRecordsBeforeIt) {
  test::StreamShape shape;
  shape.frames = 200;
  test::SentStream sent;
  test::make_stream(11, shape, &sent);
  for (const std::size_t fail_after : {std::size_t{0}, sent.bytes.size() / 3, sent.bytes.size() - 1}) {
    ChoppyReader bytes(sent.bytes, 200, 5, fail_after);
    FrameRecordReader reader(&bytes);
    Status status = Status::ok;
    const Records got = drain(reader, &status);
    EXPECT_EQ(status, Status::read_failed) << fail_after;
    expect_same_records(got, expected_records(sent, fail_after), "before the failure");
    EXPECT_EQ(reader.counters().bytes_total, fail_after);
  }
}

TEST(FrameRecordReader, EmptyIdleOrGarbageStreamsEndWithoutRecords) {
  const Bytes empty;
  const Bytes idle(500, 0);
  Random random(73);
  Bytes noise(3000);
  for (std::uint8_t& b : noise) b = static_cast<std::uint8_t>(random.next());
  const Bytes& garbage = noise;
  for (const Bytes* bytes : {&empty, &idle, &garbage}) {
    MemoryByteReader memory(Span<const std::uint8_t>(bytes->data(), bytes->size()));
    FrameRecordReader reader(&memory);
    Status status = Status::invalid_argument;
    EXPECT_TRUE(drain(reader, &status).empty()) << bytes->size();
    EXPECT_EQ(status, Status::ok);
    EXPECT_EQ(reader.counters().frames_ok, 0u);
    EXPECT_EQ(reader.counters().bytes_total, bytes->size());
  }
  MemoryByteReader memory(Span<const std::uint8_t>(idle.data(), idle.size()));
  FrameRecordReader reader(&memory);
  Status status = Status::invalid_argument;
  (void)drain(reader, &status);
  EXPECT_EQ(reader.counters().bytes_idle, 500u);
}

// ---------------------------------------------------------------------------------------
// Pass 1: the clock.

TEST(CaptureClockPass, BothOverloadsGiveTheFitOfDirectFeedingAndTheTrueClock) {
  const SimCapture& c = capture();
  ASSERT_GT(c.joints.size(), 4000u);
  ASSERT_GT(c.points.size(), 300u);
  // Reference: the records pushed straight into an estimator, robot stream first.
  Estimator& direct = estimator();
  ClockFit reference;
  Status status = Status::invalid_argument;
  for (const JointStateRecord& joint : c.joints) direct.push_robot(joint);
  for (const TrackerPointRecord& point : c.points) direct.push_tracker(point);
  ASSERT_EQ(direct.estimate(&reference), Status::ok);

  // The bytes, decoded.
  MemoryByteReader robot(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  MemoryByteReader tracker(Span<const std::uint8_t>(c.tracker_bytes.data(), c.tracker_bytes.size()));
  ClockFit from_bytes;
  StreamPassStats stats;
  EXPECT_NO_HEAP(status = estimate_clock_from_streams(robot, tracker, &estimator(), &from_bytes, &stats));
  ASSERT_EQ(status, Status::ok);
  EXPECT_TRUE(test::same_fit(from_bytes, reference));
  EXPECT_EQ(stats.robot_decoder.joint_states, c.joints.size());
  EXPECT_EQ(stats.robot_decoder.device_infos, 1u);
  EXPECT_EQ(stats.robot_decoder.frames_rejected(), 0u);
  EXPECT_EQ(stats.robot_decoder.bytes_total, c.robot_bytes.size());
  EXPECT_EQ(stats.tracker_decoder.tracker_points, c.points.size());
  EXPECT_EQ(stats.tracker_decoder.joint_states, 0u);
  EXPECT_EQ(stats.tracker_decoder.bytes_total, c.tracker_bytes.size());

  // The records, from a RecordReader (stats may be null).
  VectorRecordReader robot_records(c.robot_records);
  VectorRecordReader tracker_records(c.tracker_records);
  ClockFit from_records;
  EXPECT_NO_HEAP(status =
                     estimate_clock_from_streams(robot_records, tracker_records, &estimator(), &from_records, nullptr));
  ASSERT_EQ(status, Status::ok);
  EXPECT_TRUE(test::same_fit(from_records, reference));

  // And the simulator's true clock (t_robot = offset + (1 + drift) t_tracker) at both ends.
  const sim::SimTruth& truth = session().truth();
  for (const TrackerPointRecord* p : {&c.points.front(), &c.points.back()}) {
    const auto t_us = static_cast<double>(p->timestamp_us);
    EXPECT_NEAR(from_bytes.robot_us(t_us), truth.clock_offset_us + (1.0 + truth.clock_drift) * t_us, 2000.0);
  }
}

TEST(CaptureClockPass, AReadFailureEstimatesNothing) {
  const SimCapture& c = capture();
  ClockFit fit;
  fit.offset_us = 12345.0;  // must stay as it is
  Status status = Status::ok;
  // The tracker stream fails half way: the robot stream was read whole, the tracker up to it.
  VectorRecordReader robot(c.robot_records);
  VectorRecordReader tracker(c.tracker_records, c.tracker_records.size() / 2);
  StreamPassStats stats;
  EXPECT_NO_HEAP(status = estimate_clock_from_streams(robot, tracker, &estimator(), &fit, &stats));
  EXPECT_EQ(status, Status::read_failed);
  EXPECT_EQ(fit.offset_us, 12345.0);
  EXPECT_EQ(stats.robot_decoder.joint_states, c.joints.size());
  EXPECT_EQ(stats.tracker_decoder.tracker_points, c.tracker_records.size() / 2);
  // A robot byte stream failing at once, stats null.
  ChoppyReader failing(c.robot_bytes, 100, 1, 0);
  MemoryByteReader tracker_bytes(Span<const std::uint8_t>(c.tracker_bytes.data(), c.tracker_bytes.size()));
  EXPECT_NO_HEAP(status = estimate_clock_from_streams(failing, tracker_bytes, &estimator(), &fit, nullptr));
  EXPECT_EQ(status, Status::read_failed);
  EXPECT_EQ(fit.offset_us, 12345.0);
}

TEST(CaptureClockPass, EmptyOrOneSidedStreamsFailTheFit) {
  const SimCapture& c = capture();
  ClockFit fit;
  fit.drift = 0.5;
  StreamPassStats stats;
  Status status = Status::ok;
  MemoryByteReader none_a{Span<const std::uint8_t>()};
  MemoryByteReader none_b{Span<const std::uint8_t>()};
  EXPECT_NO_HEAP(status = estimate_clock_from_streams(none_a, none_b, &estimator(), &fit, &stats));
  EXPECT_EQ(status, Status::clock_fit_failed);
  EXPECT_EQ(fit.drift, 0.5);
  EXPECT_EQ(stats.robot_decoder.bytes_total + stats.tracker_decoder.bytes_total, 0u);
  // The robot capture given twice: no tracker point at all.
  MemoryByteReader robot(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  MemoryByteReader robot_again(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  EXPECT_NO_HEAP(status = estimate_clock_from_streams(robot, robot_again, &estimator(), &fit, &stats));
  EXPECT_EQ(status, Status::clock_fit_failed);
  EXPECT_EQ(fit.drift, 0.5);
  EXPECT_EQ(stats.tracker_decoder.tracker_points, 0u);
  EXPECT_EQ(stats.tracker_decoder.joint_states, c.joints.size());
}

// ---------------------------------------------------------------------------------------
// Pass 2: the samples.

TEST(CaptureExtractionPass, SamplesMatchTheSimulatedJointsAndPoints) {
  const SimCapture& c = capture();
  const ClockFit clock = true_clock();
  dataset_a.clear();
  Extractor& x = extractor(clock, &dataset_a);
  Recorder recorder;
  x.set_observer(&recorder);
  MemoryByteReader robot(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  MemoryByteReader tracker(Span<const std::uint8_t>(c.tracker_bytes.data(), c.tracker_bytes.size()));
  StreamPassStats stats;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot, tracker, &x, &stats));
  ASSERT_EQ(status, Status::ok);
  const ExtractionCounts& counts = x.counts();
  // Every tracker point decided (finish() ran), none lost to the small rings: the merge in
  // robot-clock order keeps the two streams within 2 s of each other.
  EXPECT_EQ(counts.tracker_points, c.points.size());
  EXPECT_EQ(counts.robot_records, c.joints.size());
  EXPECT_EQ(counts.pending(), 0u);
  EXPECT_EQ(counts.dropped_by(DropReason::robot_history_overrun), 0u);
  EXPECT_EQ(counts.dropped_by(DropReason::backlog_overrun), 0u);
  EXPECT_EQ(stats.robot_decoder.joint_states, c.joints.size());
  EXPECT_EQ(stats.tracker_decoder.tracker_points, c.points.size());
  // The observer saw each decision once; the dataset holds the kept samples in order.
  EXPECT_GT(counts.kept, 100u);
  EXPECT_EQ(dataset_a.size(), counts.kept);
  ASSERT_EQ(recorder.samples.size(), counts.kept);
  EXPECT_EQ(recorder.drops.size(), counts.dropped_total());
  const sim::Session& s = session();
  double worst_q_rad = 0.0;
  double worst_point_m = 0.0;
  for (std::size_t i = 0; i < recorder.samples.size(); ++i) {
    const ExtractedSample& e = recorder.samples[i];
    EXPECT_TRUE(e.q_rad == dataset_a.samples()[i].q_rad) << i;
    EXPECT_TRUE(e.point_m == dataset_a.samples()[i].point_m) << i;
    EXPECT_DOUBLE_EQ(e.robot_us, clock.robot_us(e.tracker_us)) << i;
    const double t_s = s.true_time_of_tracker_us(static_cast<std::uint64_t>(e.tracker_us));
    const JointVector q_true = s.joints_at(t_s);
    worst_q_rad = std::max(worst_q_rad, (e.q_rad - q_true).cwiseAbs().maxCoeff());
    worst_point_m = std::max(worst_point_m, (e.point_m - s.true_point(q_true)).norm());
  }
  EXPECT_LT(worst_q_rad, 1e-5);
  EXPECT_LT(worst_point_m, 6.0 * s.config().tracker_noise_m);
  // Only valid tracker points become samples.
  std::size_t valid = 0;
  for (const TrackerPointRecord& p : c.points) valid += p.is_valid() ? 1 : 0;
  EXPECT_LE(counts.kept, valid);
  EXPECT_EQ(counts.dropped_by(DropReason::beam_lost) + counts.dropped_by(DropReason::unstable),
            c.points.size() - valid);
}

TEST(CaptureExtractionPass, ForeignRecordsAreIgnoredAndEveryRunGivesTheSameBits) {
  const SimCapture& c = capture();
  const ClockFit clock = true_clock();
  // The bytes, twice: the same bits.
  dataset_a.clear();
  MemoryByteReader robot(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  MemoryByteReader tracker(Span<const std::uint8_t>(c.tracker_bytes.data(), c.tracker_bytes.size()));
  Status status = Status::invalid_argument;
  Extractor& first = extractor(clock, &dataset_a);
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot, tracker, &first, nullptr));
  ASSERT_EQ(status, Status::ok);
  const ExtractionCounts from_bytes = first.counts();  // copied: extractor() resets the object
  ASSERT_GT(from_bytes.kept, 100u);
  dataset_b.clear();
  robot.rewind();
  tracker.rewind();
  Extractor& again = extractor(clock, &dataset_b);
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot, tracker, &again, nullptr));
  ASSERT_EQ(status, Status::ok);
  EXPECT_TRUE(same_counts(again.counts(), from_bytes));
  EXPECT_TRUE(test::same_samples(dataset_b, dataset_a));

  // The same records from RecordReaders, with a tracker point after every 9th joint state in
  // the robot stream and a joint state before every 7th tracker point in the tracker stream:
  // those are read and ignored.
  Records robot_mixed;
  Records tracker_mixed;
  for (std::size_t i = 0; i < c.robot_records.size(); ++i) {
    robot_mixed.push_back(c.robot_records[i]);
    if (i % 9 == 0 && i / 9 < c.tracker_records.size()) robot_mixed.push_back(c.tracker_records[i / 9]);
  }
  for (std::size_t i = 0; i < c.tracker_records.size(); ++i) {
    if (i % 7 == 0) tracker_mixed.push_back(c.robot_records[(i * 37) % c.robot_records.size()]);
    tracker_mixed.push_back(c.tracker_records[i]);
  }
  dataset_b.clear();
  VectorRecordReader robot_records(robot_mixed);
  VectorRecordReader tracker_records(tracker_mixed);
  Extractor& second = extractor(clock, &dataset_b);
  StreamPassStats stats;
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot_records, tracker_records, &second, &stats));
  ASSERT_EQ(status, Status::ok);
  EXPECT_TRUE(same_counts(second.counts(), from_bytes));
  EXPECT_TRUE(test::same_samples(dataset_b, dataset_a));
  EXPECT_EQ(stats.robot_decoder.frames_ok, robot_mixed.size());  // read, then ignored
  EXPECT_EQ(stats.tracker_decoder.frames_ok, tracker_mixed.size());
}

TEST(CaptureExtractionPass, EveryTrackerPointIsDecidedWhenTheRobotStreamEndsFirst) {
  // The robot capture stops half way: the later tracker points wait for robot data that never
  // comes; those still in the tracker ring at the end are decided by finish(), as outside the
  // robot's range (the older ones were pushed out of the ring: backlog_overrun).
  const SimCapture& c = capture();
  const Records first_half(c.robot_records.begin(),
                           c.robot_records.begin() + static_cast<long>(c.robot_records.size() / 2));
  VectorRecordReader robot(first_half);
  VectorRecordReader tracker(c.tracker_records);
  dataset_a.clear();
  Extractor& x = extractor(true_clock(), &dataset_a);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot, tracker, &x, nullptr));
  EXPECT_EQ(status, Status::ok);
  const ExtractionCounts& counts = x.counts();
  EXPECT_EQ(counts.tracker_points, c.points.size());
  EXPECT_EQ(counts.robot_records, first_half.size());
  EXPECT_EQ(counts.pending(), 0u);
  EXPECT_GT(counts.dropped_by(DropReason::outside_robot_range), 0u);
  EXPECT_GT(counts.dropped_by(DropReason::outside_robot_range) + counts.dropped_by(DropReason::backlog_overrun),
            c.points.size() / 3);
  EXPECT_GT(counts.kept, 20u);
  EXPECT_EQ(dataset_a.size(), counts.kept);
}

TEST(CaptureExtractionPass, ReadFailureAndAFullDatasetAreReported) {
  const SimCapture& c = capture();
  const ClockFit clock = true_clock();
  Status status = Status::ok;
  // The robot records fail part way.
  dataset_a.clear();
  VectorRecordReader robot(c.robot_records, c.robot_records.size() / 2);
  VectorRecordReader tracker(c.tracker_records);
  StreamPassStats stats;
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot, tracker, &extractor(clock, &dataset_a), &stats));
  EXPECT_EQ(status, Status::read_failed);
  EXPECT_EQ(stats.robot_decoder.joint_states, c.robot_records.size() / 2);
  // The tracker bytes fail at once.
  MemoryByteReader robot_bytes(Span<const std::uint8_t>(c.robot_bytes.data(), c.robot_bytes.size()));
  ChoppyReader tracker_bytes(c.tracker_bytes, 64, 3, 0);
  EXPECT_NO_HEAP(status =
                     extract_samples_from_streams(robot_bytes, tracker_bytes, &extractor(clock, &dataset_a), nullptr));
  EXPECT_EQ(status, Status::read_failed);
  // Room for 10 samples only: dataset_full, the first ten kept, the rest counted.
  static Dataset<10> small;
  small.clear();
  robot_bytes.rewind();
  MemoryByteReader tracker_whole(Span<const std::uint8_t>(c.tracker_bytes.data(), c.tracker_bytes.size()));
  Extractor& x = extractor(clock, &small);
  EXPECT_NO_HEAP(status = extract_samples_from_streams(robot_bytes, tracker_whole, &x, nullptr));
  EXPECT_EQ(status, Status::dataset_full);
  EXPECT_EQ(small.size(), 10u);
  EXPECT_EQ(x.counts().kept, 10u);
  EXPECT_GT(x.counts().dropped_by(DropReason::dataset_full), 50u);
  EXPECT_EQ(x.counts().pending(), 0u);
}

}  // namespace
}  // namespace hivecal::capture_pipeline_test
