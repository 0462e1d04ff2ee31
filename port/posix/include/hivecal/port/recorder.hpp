// Records byte sources (serial ports) to capture files as the bytes come: one poll() over
// every open port, each chunk written at once, fsync every sync_interval_ms and at the end.
// Memory is one fixed buffer whatever the capture length.
#pragma once

#include <csignal>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/capture_file.hpp"

namespace hivecal::port {

/// How long and how safely to record.
struct RecordOptions {
  int poll_timeout_ms = 100;    ///< longest wait before checking the stop flag [ms]
  int sync_interval_ms = 1000;  ///< fsync period [ms]
  double duration_s = 0.0;      ///< stop after this long [s]; 0: until stopped
  /// Optional tap: called with (source index, bytes, count) after each chunk is written,
  /// e.g. to decode the live streams while they are recorded.
  std::function<void(std::size_t, const std::uint8_t*, std::size_t)> on_bytes;
};

/// What was recorded per source.
struct RecordStats {
  std::vector<std::uint64_t> bytes;        ///< bytes written to each capture (what is in it)
  std::vector<std::uint64_t> bytes_read;   ///< bytes read from each source (more after a failed write)
  std::vector<std::uint64_t> disconnects;  ///< device losses per source
  bool ended_by_stop_flag = false;         ///< the flag (a signal) ended the recording
};

/// Copies sources[i] into writers[i] until *stop becomes nonzero, `duration_s` passes, or
/// every source reports end_of_stream. Closes (fsync) every writer before returning.
/// Fault::output on a write error, Fault::input on a permanent read error.
Error record_streams(const std::vector<ByteSource*>& sources, const std::vector<CaptureWriter*>& writers,
                     const volatile std::sig_atomic_t* stop, const RecordOptions& options, RecordStats* stats);

}  // namespace hivecal::port
