// The committed result of the capture calibration job (capture_job.hpp) on the committed
// capture pair tests/data/fw-session/{robot,tracker}.cap with the settings below. The host
// test (tests/unit/test_capture_job.cpp) and the firmware image (tests/firmware/capture_job_main.cpp,
// CTest firmware.capture_job) both compare their digest with it.
#pragma once

#include <cstdint>

#include "capture_job.hpp"

namespace hivecal::test {

/// The settings of the golden run: ABC budget reduced so that the Cortex-M4 run under QEMU
/// stays short (the footprint report measures the paper's 150 x 300 separately).
inline CaptureJobConfig golden_capture_job_config() {
  CaptureJobConfig config;
  config.seed = 1;
  config.food_sources = 20;
  config.cycles = 30;
  return config;
}

/// The committed digest: every target must reproduce it.
inline constexpr std::uint64_t kCaptureJobGoldenDigest = 0xcbd8767022598f97ULL;

}  // namespace hivecal::test
