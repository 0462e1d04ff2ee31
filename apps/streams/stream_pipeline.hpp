// Wires port/ to lib/ for the stream path: byte sources (capture files, serial ports) ->
// the library's two passes (hivecal/capture_pipeline.hpp: StreamDecoder -> ClockEstimator,
// then SampleExtractor in robot-clock order) -> dataset. RecordQueue decodes bytes tapped
// elsewhere (a live recording). Memory stays bounded: records are decoded a chunk at a time.
#pragma once

#include <cstdint>
#include <deque>
#include <string>

#include "hivecal/capture_pipeline.hpp"
#include "hivecal/clock_sync.hpp"
#include "hivecal/codec.hpp"
#include "hivecal/port/byte_source.hpp"
#include "hivecal/sample_extraction.hpp"

namespace hivecal::streams {

/// Decodes bytes obtained elsewhere (e.g. a recorder's tap) into queues of records.
class RecordQueue final : public FrameHandler {
 public:
  std::deque<JointStateRecord>& joints() { return joints_; }      ///< decoded robot records
  std::deque<TrackerPointRecord>& points() { return points_; }    ///< decoded tracker records
  const DecoderStats& decoder_stats() const { return decoder_.stats(); }  ///< frame counters
  /// Decodes `count` bytes into the queues.
  void feed(const std::uint8_t* bytes, std::size_t count) { decoder_.feed(bytes, count, *this); }

  void on_joint_state(const JointStateRecord& record) override { joints_.push_back(record); }
  void on_tracker_point(const TrackerPointRecord& record) override { points_.push_back(record); }

 private:
  StreamDecoder decoder_;
  std::deque<JointStateRecord> joints_;
  std::deque<TrackerPointRecord> points_;
};

/// Counters of one pass over the two streams.
using PassStats = StreamPassStats;

/// Pass 1: every record of both sources into `estimator`, then estimate() into *fit.
/// Returns the estimate's status; I/O problems give invalid_argument with *error set.
Status estimate_clock(port::ByteSource* robot, port::ByteSource* tracker, ClockEstimatorBase* estimator,
                      ClockFit* fit, PassStats* stats, std::string* error);

/// Pass 2: both sources merged in robot-clock order (through extractor->clock()) into
/// `extractor`, then finish(). Returns ok, dataset_full, or invalid_argument with *error set.
Status extract_samples(port::ByteSource* robot, port::ByteSource* tracker, SampleExtractorBase* extractor,
                       PassStats* stats, std::string* error);

/// Everything a two-pass run over capture files reports.
struct CaptureRunReport {
  Status clock_status = Status::ok;       ///< outcome of the clock estimation
  ClockFit clock;                          ///< the clock relation (when clock_status is ok)
  ClockProfileStats clock_stats;           ///< what went into the clock profiles
  PassStats decoding;                      ///< frame counters (first pass)
  Status extraction_status = Status::ok;  ///< ok or dataset_full
  ExtractionCounts counts;                 ///< kept / dropped per reason
};

/// Both passes over two capture files into `dataset`. False with a message when a file
/// cannot be read; a failed clock fit is reported in *report (no extraction then).
bool extract_from_captures(const std::string& robot_capture, const std::string& tracker_capture,
                           const ClockSyncConfig& clock_config, const ExtractionConfig& extraction_config,
                           DatasetBase* dataset, CaptureRunReport* report, std::string* error,
                           ExtractionObserver* observer = nullptr);

}  // namespace hivecal::streams
