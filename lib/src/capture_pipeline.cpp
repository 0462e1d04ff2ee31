#include "hivecal/capture_pipeline.hpp"

#include <cstring>

#include "hivecal/ring.hpp"

namespace hivecal {
namespace {

// Bytes read from a ByteReader at a time, and fed to the decoder at a time. A delivered
// frame is at least kMinFrameBytes long (TRACKER_POINT, the shortest packet), so a slice
// completes at most kSliceBytes / kMinFrameBytes + 1 records: the queues never overflow.
constexpr std::size_t kChunkBytes = 256;
constexpr std::size_t kSliceBytes = 128;
constexpr std::size_t kMinFrameBytes = cobs_max_encoded_bytes(kPacketHeaderBytes + kTrackerPointPayloadBytes +
                                                              kPacketCrcBytes) + 1;
constexpr std::size_t kQueueRecords = 4;
static_assert(kSliceBytes / kMinFrameBytes + 1 <= kQueueRecords, "a slice must not overflow the record queues");

/// One stream: its reader, a decoder and short queues of the records decoded but not yet used.
class RecordPump final : public FrameHandler {
 public:
  explicit RecordPump(ByteReader* reader)
      : reader_(reader), joints_(joint_storage_, kQueueRecords), points_(point_storage_, kQueueRecords) {}

  /// Decodes until a record is queued or the stream ends; false at the end with nothing
  /// queued (or after a read error: failed()).
  bool fill() {
    while (joints_.empty() && points_.empty() && !ended_) {
      if (chunk_position_ == chunk_size_) {
        std::size_t count = 0;
        if (reader_->read(chunk_, kChunkBytes, &count) != Status::ok) {
          failed_ = true;
          ended_ = true;
          break;
        }
        if (count == 0 || count > kChunkBytes) {
          failed_ = count > kChunkBytes;
          ended_ = true;
          break;
        }
        chunk_size_ = count;
        chunk_position_ = 0;
      }
      std::size_t slice = chunk_size_ - chunk_position_;
      if (slice > kSliceBytes) slice = kSliceBytes;
      decoder_.feed(chunk_ + chunk_position_, slice, *this);
      chunk_position_ += slice;
    }
    return !joints_.empty() || !points_.empty();
  }

  void on_joint_state(const JointStateRecord& record) override { joints_.push(record); }
  void on_tracker_point(const TrackerPointRecord& record) override { points_.push(record); }

  RingView<JointStateRecord>& joints() { return joints_; }
  RingView<TrackerPointRecord>& points() { return points_; }
  const DecoderStats& decoder_stats() const { return decoder_.stats(); }
  bool failed() const { return failed_; }

 private:
  ByteReader* reader_;
  StreamDecoder decoder_;
  std::uint8_t chunk_[kChunkBytes] = {};
  std::size_t chunk_size_ = 0;
  std::size_t chunk_position_ = 0;
  bool ended_ = false;
  bool failed_ = false;
  JointStateRecord joint_storage_[kQueueRecords];
  TrackerPointRecord point_storage_[kQueueRecords];
  RingView<JointStateRecord> joints_;
  RingView<TrackerPointRecord> points_;
};

void note_stats(const RecordPump& robot, const RecordPump& tracker, StreamPassStats* stats) {
  if (stats == nullptr) return;
  stats->robot_decoder = robot.decoder_stats();
  stats->tracker_decoder = tracker.decoder_stats();
}

}  // namespace

Status MemoryByteReader::read(std::uint8_t* out, std::size_t capacity, std::size_t* count) {
  std::size_t n = bytes_.size() - position_;
  if (n > capacity) n = capacity;
  if (n > 0) std::memcpy(out, bytes_.data() + position_, n);
  position_ += n;
  *count = n;
  return Status::ok;
}

Status estimate_clock_from_streams(ByteReader& robot, ByteReader& tracker, ClockEstimatorBase* estimator,
                                   ClockFit* fit, StreamPassStats* stats) {
  RecordPump robot_pump(&robot);
  RecordPump tracker_pump(&tracker);
  // The estimator keeps the two streams apart: each is read to its end in turn.
  for (RecordPump* pump : {&robot_pump, &tracker_pump}) {
    while (pump->fill()) {
      for (; !pump->joints().empty(); pump->joints().pop_front()) estimator->push_robot(pump->joints().front());
      for (; !pump->points().empty(); pump->points().pop_front()) estimator->push_tracker(pump->points().front());
    }
    if (pump->failed()) {
      note_stats(robot_pump, tracker_pump, stats);
      return Status::read_failed;
    }
  }
  note_stats(robot_pump, tracker_pump, stats);
  return estimator->estimate(fit);
}

Status extract_samples_from_streams(ByteReader& robot, ByteReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats) {
  RecordPump robot_pump(&robot);
  RecordPump tracker_pump(&tracker);
  Status result = Status::ok;
  auto note = [&result](Status s) {
    if (s != Status::ok) result = s;
  };
  for (;;) {
    if (robot_pump.joints().empty()) robot_pump.fill();
    if (tracker_pump.points().empty()) tracker_pump.fill();
    robot_pump.points().clear();  // a robot stream carries no tracker points (ignored if any)
    tracker_pump.joints().clear();
    const bool has_joint = !robot_pump.joints().empty();
    const bool has_point = !tracker_pump.points().empty();
    if (!has_joint && !has_point) break;
    // Robot-clock order keeps the two streams within the extractor's rings.
    if (has_point && (!has_joint || extractor->clock().robot_us(static_cast<double>(
                                        tracker_pump.points().front().timestamp_us)) <=
                                        static_cast<double>(robot_pump.joints().front().timestamp_us))) {
      note(extractor->push_tracker(tracker_pump.points().front()));
      tracker_pump.points().pop_front();
    } else {
      note(extractor->push_robot(robot_pump.joints().front()));
      robot_pump.joints().pop_front();
    }
  }
  note_stats(robot_pump, tracker_pump, stats);
  if (robot_pump.failed() || tracker_pump.failed()) return Status::read_failed;
  note(extractor->finish());
  return result;
}

}  // namespace hivecal
