#include "hivecal/sync/capture_pipeline.hpp"

#include <cstring>

namespace hivecal {
namespace {

// A delivered frame is at least kMinFrameBytes long (TRACKER_POINT, the shortest packet), so a
// slice completes at most kSliceBytes / kMinFrameBytes + 1 records: the queue never overflows.
constexpr std::size_t kMinFrameBytes =
    cobs_max_encoded_bytes(kPacketHeaderBytes + kTrackerPointPayloadBytes + kPacketCrcBytes) + 1;
static_assert(FrameRecordReader::kSliceBytes / kMinFrameBytes + 1 <= FrameRecordReader::kQueueRecords,
              "a slice must not overflow the record queue");

void note_stats(const RecordReader& robot, const RecordReader& tracker, StreamPassStats* stats) {
  if (stats == nullptr) return;
  stats->robot_decoder = robot.counters();
  stats->tracker_decoder = tracker.counters();
}

/// The next record of `kind` from `reader` into *record (others skipped); false at the end
/// or on a read failure (*status).
bool next_of_kind(RecordReader& reader, StreamRecord::Kind kind, StreamRecord* record, Status* status) {
  for (;;) {
    const Status s = reader.next(record);
    if (s != Status::ok) {
      *status = s;
      return false;
    }
    if (record->kind == StreamRecord::Kind::end) return false;
    if (record->kind == kind) return true;
  }
}

}  // namespace

void FrameRecordReader::push(const StreamRecord& record) {
  // kQueueRecords bounds what one slice can complete (static_assert above).
  queue_[(queue_first_ + queue_size_) % kQueueRecords] = record;
  ++queue_size_;
}

void FrameRecordReader::on_joint_state(const JointStateRecord& record) {
  StreamRecord r;
  r.kind = StreamRecord::Kind::joint_state;
  r.joint = record;
  push(r);
}

void FrameRecordReader::on_tracker_point(const TrackerPointRecord& record) {
  StreamRecord r;
  r.kind = StreamRecord::Kind::tracker_point;
  r.point = record;
  push(r);
}

Status FrameRecordReader::next(StreamRecord* record) {
  while (queue_size_ == 0 && !ended_) {
    if (chunk_position_ == chunk_size_) {
      std::size_t count = 0;
      const Status s = bytes_->read(chunk_, kChunkBytes, &count);
      if (s != Status::ok || count > kChunkBytes) {
        ended_ = true;
        return Status::read_failed;
      }
      if (count == 0) {
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
  if (queue_size_ == 0) {
    record->kind = StreamRecord::Kind::end;
    return Status::ok;
  }
  *record = queue_[queue_first_];
  queue_first_ = (queue_first_ + 1) % kQueueRecords;
  --queue_size_;
  return Status::ok;
}

Status estimate_clock_from_streams(RecordReader& robot, RecordReader& tracker, ClockEstimatorBase* estimator,
                                   ClockFit* fit, StreamPassStats* stats) {
  // The estimator keeps the two streams apart: each is read to its end in turn.
  StreamRecord record;
  for (RecordReader* reader : {&robot, &tracker}) {
    for (;;) {
      if (reader->next(&record) != Status::ok) {
        note_stats(robot, tracker, stats);
        return Status::read_failed;
      }
      if (record.kind == StreamRecord::Kind::end) break;
      if (record.kind == StreamRecord::Kind::joint_state) estimator->push_robot(record.joint);
      if (record.kind == StreamRecord::Kind::tracker_point) estimator->push_tracker(record.point);
    }
  }
  note_stats(robot, tracker, stats);
  return estimator->estimate(fit);
}

Status estimate_clock_from_streams(ByteReader& robot, ByteReader& tracker, ClockEstimatorBase* estimator, ClockFit* fit,
                                   StreamPassStats* stats) {
  FrameRecordReader robot_records(&robot);
  FrameRecordReader tracker_records(&tracker);
  return estimate_clock_from_streams(robot_records, tracker_records, estimator, fit, stats);
}

Status extract_samples_from_streams(RecordReader& robot, RecordReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats) {
  Status result = Status::ok;
  auto note = [&result](Status s) {
    if (s != Status::ok) result = s;
  };
  Status read_status = Status::ok;
  StreamRecord joint;
  StreamRecord point;
  bool has_joint = next_of_kind(robot, StreamRecord::Kind::joint_state, &joint, &read_status);
  bool has_point = next_of_kind(tracker, StreamRecord::Kind::tracker_point, &point, &read_status);
  while (has_joint || has_point) {
    // Robot-clock order keeps the two streams within the extractor's rings.
    if (has_point && (!has_joint || extractor->clock().robot_us(static_cast<double>(point.point.timestamp_us)) <=
                                        static_cast<double>(joint.joint.timestamp_us))) {
      note(extractor->push_tracker(point.point));
      has_point = next_of_kind(tracker, StreamRecord::Kind::tracker_point, &point, &read_status);
    } else {
      note(extractor->push_robot(joint.joint));
      has_joint = next_of_kind(robot, StreamRecord::Kind::joint_state, &joint, &read_status);
    }
  }
  note_stats(robot, tracker, stats);
  if (read_status != Status::ok) return Status::read_failed;
  note(extractor->finish());
  return result;
}

Status extract_samples_from_streams(ByteReader& robot, ByteReader& tracker, SampleExtractorBase* extractor,
                                    StreamPassStats* stats) {
  FrameRecordReader robot_records(&robot);
  FrameRecordReader tracker_records(&tracker);
  return extract_samples_from_streams(robot_records, tracker_records, extractor, stats);
}

}  // namespace hivecal
