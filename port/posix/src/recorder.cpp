#include "hivecal/port/recorder.hpp"

#include <poll.h>

#include <cerrno>
#include <cstring>

namespace hivecal::port {
namespace {

constexpr std::size_t kChunkBytes = 65536;  // one read's worth; the only buffer

/// Waits until a source is readable, a disconnected source may be retried, or the timeout.
void wait_for_input(const std::vector<ByteSource*>& sources, const std::vector<bool>& done, int timeout_ms) {
  std::vector<pollfd> fds;
  bool any_closed = false;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    if (done[i]) continue;
    const int fd = sources[i]->poll_fd();
    if (fd < 0) {
      any_closed = true;
    } else {
      fds.push_back(pollfd{fd, POLLIN, 0});
    }
  }
  // A closed (reconnecting) port has no descriptor: come back soon to let it retry.
  const int wait_ms = any_closed && timeout_ms > 20 ? 20 : timeout_ms;
  if (fds.empty()) {
    sleep_ms(wait_ms);
    return;
  }
  (void)::poll(fds.data(), fds.size(), wait_ms);  // EINTR: the caller checks the stop flag
}

}  // namespace

Error record_streams(const std::vector<ByteSource*>& sources, const std::vector<CaptureWriter*>& writers,
                     const volatile std::sig_atomic_t* stop, const RecordOptions& options, RecordStats* stats) {
  stats->bytes.assign(sources.size(), 0);
  stats->bytes_read.assign(sources.size(), 0);
  stats->disconnects.assign(sources.size(), 0);
  std::vector<bool> done(sources.size(), false);
  std::vector<bool> lost(sources.size(), false);
  std::vector<std::uint8_t> chunk(kChunkBytes);
  const std::int64_t start_ms = monotonic_ms();
  std::int64_t last_sync_ms = start_ms;
  Error error;
  std::size_t remaining = sources.size();
  while (error.ok() && remaining > 0) {
    if (stop != nullptr && *stop != 0) {
      stats->ended_by_stop_flag = true;
      break;
    }
    if (options.duration_s > 0.0 && static_cast<double>(monotonic_ms() - start_ms) >= options.duration_s * 1000.0)
      break;
    wait_for_input(sources, done, options.poll_timeout_ms);
    for (std::size_t i = 0; error.ok() && i < sources.size(); ++i) {
      if (done[i]) continue;
      const ReadResult got = sources[i]->read(chunk.data(), chunk.size(), 0);
      const bool was_lost = lost[i];
      lost[i] = got.status == ReadStatus::disconnected;
      if (got.status == ReadStatus::data) {
        stats->bytes_read[i] += got.bytes;
        error = writers[i]->write(chunk.data(), got.bytes);
        stats->bytes[i] = writers[i]->bytes_written();  // a full disk takes fewer than were read
        if (error.ok() && options.on_bytes) options.on_bytes(i, chunk.data(), got.bytes);
      } else if (got.status == ReadStatus::disconnected) {
        if (!was_lost) ++stats->disconnects[i];  // count each loss once, not each retry
      } else if (got.status == ReadStatus::end_of_stream) {
        done[i] = true;
        --remaining;
      } else if (got.status == ReadStatus::error) {
        error = Error::input(sources[i]->name() + ": read failed: " + std::strerror(got.error_number));
      }
    }
    if (monotonic_ms() - last_sync_ms >= options.sync_interval_ms) {
      for (CaptureWriter* writer : writers) {
        const Error synced = writer->sync();
        if (error.ok()) error = synced;
      }
      last_sync_ms = monotonic_ms();
    }
  }
  for (CaptureWriter* writer : writers) {
    const Error closed = writer->close();
    if (error.ok()) error = closed;
  }
  return error;
}

}  // namespace hivecal::port
