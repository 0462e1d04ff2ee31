#include <cerrno>
#include <ctime>

#include "hivecal/port/byte_source.hpp"

namespace hivecal::port {

std::int64_t monotonic_ms() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1000 + now.tv_nsec / 1000000;
}

void sleep_ms(std::int64_t ms) {
  if (ms <= 0) return;
  timespec left{static_cast<time_t>(ms / 1000), static_cast<long>((ms % 1000) * 1000000)};
  while (nanosleep(&left, &left) != 0 && errno == EINTR) {
  }
}

bool sleep_ms(std::int64_t ms, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSlice_ms = 100;
  const std::int64_t end_ms = monotonic_ms() + (ms > 0 ? ms : 0);
  for (std::int64_t left_ms = ms; !stop.load(); left_ms = end_ms - monotonic_ms()) {
    if (left_ms <= 0) return true;
    sleep_ms(left_ms < kSlice_ms ? left_ms : kSlice_ms);
  }
  return false;
}

}  // namespace hivecal::port
