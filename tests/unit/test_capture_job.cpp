// The firmware's capture calibration job (tests/support/capture_job.hpp) on the host: the
// same code, the same committed capture bytes and seed as CTest firmware.capture_job runs on
// Cortex-M7/M4 under QEMU, compared with the same committed digest.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "alloc_trap.hpp"
#include "capture_job.hpp"
#include "golden_capture_job.hpp"

namespace hivecal {
namespace {

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::vector<std::uint8_t> bytes;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return bytes;
  std::uint8_t buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) bytes.insert(bytes.end(), buffer, buffer + n);
  std::fclose(f);
  return bytes;
}

/// Both captures in memory, re-read from the start on every open().
class MemoryCaptures final : public test::CaptureSource {
 public:
  MemoryCaptures(const std::vector<std::uint8_t>& robot, const std::vector<std::uint8_t>& tracker)
      : robot_(Span<const std::uint8_t>(robot.data(), robot.size())),
        tracker_(Span<const std::uint8_t>(tracker.data(), tracker.size())) {}
  Status open(ByteReader** robot, ByteReader** tracker) override {
    robot_.rewind();
    tracker_.rewind();
    *robot = &robot_;
    *tracker = &tracker_;
    return Status::ok;
  }

 private:
  MemoryByteReader robot_;
  MemoryByteReader tracker_;
};

class CaptureJob : public ::testing::Test {
 protected:
  void SetUp() override {
    robot_ = read_file(std::string(HIVECAL_FW_SESSION_DIR) + "/robot.cap");
    tracker_ = read_file(std::string(HIVECAL_FW_SESSION_DIR) + "/tracker.cap");
    ASSERT_FALSE(robot_.empty()) << HIVECAL_FW_SESSION_DIR;
    ASSERT_FALSE(tracker_.empty()) << HIVECAL_FW_SESSION_DIR;
  }
  std::vector<std::uint8_t> robot_;
  std::vector<std::uint8_t> tracker_;
};

static test::CaptureJobWorkspace workspace;
static test::CaptureJobReport report;

TEST_F(CaptureJob, CalibratesTheCommittedSessionLikeTheFirmware) {
  MemoryCaptures captures(robot_, tracker_);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = test::run_capture_job(captures, test::golden_capture_job_config(), &workspace, &report));
  ASSERT_EQ(status, Status::ok) << status_message(report.status) << " at stage " << static_cast<int>(report.stage);
  EXPECT_EQ(report.stage, test::JobStage::done);
  // What the digest stands for must be a real calibration, not just the same bits.
  EXPECT_GE(report.samples, 200u);
  EXPECT_EQ(report.counts.kept, report.samples);
  // The simulator's clocks (tests/data/fw-session/truth.json): t_robot = 994999800 us +
  // (1 + 40 ppm) t_tracker; tracker time runs from 5 s over ~160 s.
  for (const double tracker_us : {5e6, 165e6}) {
    const double truth_us = 994999800.0 + (1.0 + 40e-6) * tracker_us;
    EXPECT_NEAR(report.clock.robot_us(tracker_us), truth_us, 2000.0) << tracker_us;
  }
  EXPECT_GE(report.lm.identifiability.kept_count(), 24);
  const double before = report.uncalibrated_test.mae_m[static_cast<int>(ErrorAxis::norm_3d)];
  const double after = report.calibrated_test.mae_m[static_cast<int>(ErrorAxis::norm_3d)];
  EXPECT_LT(after, 0.2 * before) << "nominal " << before << " m, calibrated " << after << " m";
  EXPECT_LT(after, 100e-6);
  std::printf("capture job: %zu samples, ABC best %.3g m, LM RMS %.3g m, test MAE %.3g -> %.3g m, digest 0x%016llx\n",
              report.samples, report.abc.best_cost_m, report.lm.rms_m, before, after,
              static_cast<unsigned long long>(report.digest));
  EXPECT_EQ(report.digest, test::kCaptureJobGoldenDigest)
      << std::hex << "0x" << report.digest << " (update golden_capture_job.hpp only for an intended change)";
}

TEST_F(CaptureJob, ATruncatedTrackerCaptureChangesTheDigest) {
  tracker_.resize(tracker_.size() / 2);
  MemoryCaptures captures(robot_, tracker_);
  (void)test::run_capture_job(captures, test::golden_capture_job_config(), &workspace, &report);
  EXPECT_NE(report.digest, test::kCaptureJobGoldenDigest);
}

}  // namespace
}  // namespace hivecal
