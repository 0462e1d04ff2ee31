// The firmware's calibration jobs from captures (tests/testkit/golden_capture_job.hpp: the
// capture passes of capture_dataset.hpp, then calibrate()) on the host: the same code, the
// same committed capture bytes and seed as CTest firmware.capture_job[_lm] runs on
// Cortex-M7/M4 under QEMU, compared with the same committed digests.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "testkit/alloc_trap.hpp"
#include "testkit/golden_capture_job.hpp"

namespace hivecal::capture_job_golden_test {
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
class MemoryCaptures final : public CaptureSource {
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
  const CalibrationResult& c = report.calibration;
  ASSERT_EQ(status, Status::ok) << status_message(c.status) << " at " << calibration_step_name(c.step);
  EXPECT_EQ(c.step, CalibrationStep::done);
  ASSERT_EQ(c.stage_count, 2u);
  EXPECT_STREQ(c.stage_name(1), "ABC+LM");
  // What the digest stands for must be a real calibration, not just the same bits.
  EXPECT_GE(report.samples, 200u);
  EXPECT_EQ(report.capture.counts.kept, report.samples);
  // The simulator's clocks (tests/data/fw-session/truth.json): t_robot = 994999800 us +
  // (1 + 40 ppm) t_tracker; tracker time runs from 5 s over ~160 s.
  for (const double tracker_us : {5e6, 165e6}) {
    const double truth_us = 994999800.0 + (1.0 + 40e-6) * tracker_us;
    EXPECT_NEAR(report.capture.clock.robot_us(tracker_us), truth_us, 2000.0) << tracker_us;
  }
  // 24 identifiable; a few of them may be fixed at their start values as not significant.
  EXPECT_GE(c.lm.identifiability.kept_count() + mask_count(c.lm_pruned_mask), 24);
  const double before = c.baseline.test.mae(ErrorAxis::norm_3d);
  const double after = c.stages[c.stage_count - 1].test.mae(ErrorAxis::norm_3d);
  EXPECT_LT(after, 0.2 * before) << "nominal " << before << " m, calibrated " << after << " m";
  EXPECT_LT(after, 100e-6);
  std::printf("capture job: %zu samples, ABC best %.3g m, LM RMS %.3g m, test MAE %.3g -> %.3g m, digest 0x%016llx\n",
              report.samples, c.stages[0].best_cost_m, c.lm.rms_m, before, after,
              static_cast<unsigned long long>(report.digest));
  EXPECT_EQ(report.digest, test::kCaptureJobGoldenDigest)
      << std::hex << "0x" << report.digest << " (update golden_capture_job.hpp only for an intended change)";
}

TEST_F(CaptureJob, TheLmOnlyJobCalibratesBetterThanTheNominalModel) {
  MemoryCaptures captures(robot_, tracker_);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = test::run_capture_job(captures, test::golden_lm_job_config(), &workspace, &report));
  const CalibrationResult& c = report.calibration;
  ASSERT_EQ(status, Status::ok) << status_message(c.status) << " at " << calibration_step_name(c.step);
  ASSERT_EQ(c.stage_count, 1u);
  EXPECT_STREQ(c.stage_name(0), "LM");
  const double before = c.baseline.test.mae(ErrorAxis::norm_3d);
  const double after = c.stages[c.stage_count - 1].test.mae(ErrorAxis::norm_3d);
  EXPECT_LT(after, 100e-6) << "nominal " << before << " m";
  std::printf("LM job: test MAE %.3g -> %.3g m, digest 0x%016llx\n", before, after,
              static_cast<unsigned long long>(report.digest));
  EXPECT_EQ(report.digest, test::kLmJobGoldenDigest)
      << std::hex << "0x" << report.digest << " (update golden_capture_job.hpp only for an intended change)";
}

TEST_F(CaptureJob, TheComplianceJobFitsTheSimulatedCompliance) {
  MemoryCaptures captures(robot_, tracker_);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = test::run_capture_job(captures, test::golden_compliance_job_config(), &workspace, &report));
  const CalibrationResult& c = report.calibration;
  ASSERT_EQ(status, Status::ok) << status_message(c.status) << " at " << calibration_step_name(c.step);
  ASSERT_EQ(c.stage_count, 2u);
  EXPECT_STREQ(c.stage_name(0), "LM");
  EXPECT_STREQ(c.stage_name(1), "LM+compliance");
  EXPECT_TRUE(c.stages[1].compliance);
  EXPECT_GT(c.lm.model.compliance.term_count, 0);
  const double before = c.baseline.test.mae(ErrorAxis::norm_3d);
  const double rigid = c.stages[0].test.mae(ErrorAxis::norm_3d);
  const double compliant = c.stages[1].test.mae(ErrorAxis::norm_3d);
  EXPECT_LT(compliant, 100e-6) << "nominal " << before << " m";
  // The session was simulated with joint 2 and 3 compliance (truth.json): the stage finds it
  // significant. Its test part is about five stops, too few to show the few-um gain; it must not
  // get worse than the rigid fit by more than 1 %.
  EXPECT_FALSE(c.stages[1].rigid_kept);
  EXPECT_LT(compliant, 1.01 * rigid);
  std::printf("compliance job: test MAE nominal %.3g, LM %.3g, LM+compliance %.3g m, digest 0x%016llx\n", before, rigid,
              compliant, static_cast<unsigned long long>(report.digest));
  EXPECT_EQ(report.digest, test::kComplianceJobGoldenDigest)
      << std::hex << "0x" << report.digest << " (update golden_capture_job.hpp only for an intended change)";
}

TEST_F(CaptureJob, ATruncatedTrackerCaptureChangesTheDigest) {
  tracker_.resize(tracker_.size() / 2);
  MemoryCaptures captures(robot_, tracker_);
  (void)test::run_capture_job(captures, test::golden_capture_job_config(), &workspace, &report);
  EXPECT_NE(report.digest, test::kCaptureJobGoldenDigest);
}

/// Hands out at most `step` bytes per read, then fails after `fail_after` bytes (0: never).
class ChoppyReader final : public ByteReader {
 public:
  ChoppyReader(const std::vector<std::uint8_t>& bytes, std::size_t step, std::size_t fail_after)
      : bytes_(bytes), step_(step), fail_after_(fail_after) {}
  Status read(std::uint8_t* out, std::size_t capacity, std::size_t* count) override {
    if (fail_after_ != 0 && position_ >= fail_after_) return Status::read_failed;
    std::size_t n = std::min({capacity, step_, bytes_.size() - position_});
    std::copy(bytes_.begin() + static_cast<std::ptrdiff_t>(position_),
              bytes_.begin() + static_cast<std::ptrdiff_t>(position_ + n), out);
    position_ += n;
    *count = n;
    return Status::ok;
  }

 private:
  const std::vector<std::uint8_t>& bytes_;
  std::size_t step_;
  std::size_t fail_after_;
  std::size_t position_ = 0;
};

TEST_F(CaptureJob, ClockPassDoesNotDependOnHowTheBytesArriveAndReportsReadErrors) {
  static test::JobCaptureWorkspace::Estimator whole(make_clock_sync_config(nominal_model(RobotType::ur5)));
  static test::JobCaptureWorkspace::Estimator choppy(make_clock_sync_config(nominal_model(RobotType::ur5)));
  MemoryByteReader robot(Span<const std::uint8_t>(robot_.data(), robot_.size()));
  MemoryByteReader tracker(Span<const std::uint8_t>(tracker_.data(), tracker_.size()));
  ClockFit a;
  ClockFit b;
  StreamPassStats stats_a;
  StreamPassStats stats_b;
  ASSERT_EQ(estimate_clock_from_streams(robot, tracker, &whole, &a, &stats_a), Status::ok);
  ChoppyReader robot_bits(robot_, 7, 0);
  ChoppyReader tracker_bits(tracker_, 13, 0);
  ASSERT_EQ(estimate_clock_from_streams(robot_bits, tracker_bits, &choppy, &b, &stats_b), Status::ok);
  EXPECT_EQ(a.offset_us, b.offset_us);
  EXPECT_EQ(a.drift, b.drift);
  EXPECT_EQ(stats_a.robot_decoder.joint_states, stats_b.robot_decoder.joint_states);
  EXPECT_EQ(stats_a.tracker_decoder.tracker_points, stats_b.tracker_decoder.tracker_points);
  EXPECT_GT(stats_a.robot_decoder.joint_states, 10000u);

  choppy.reset();
  ChoppyReader robot_fails(robot_, 4096, 100000);
  tracker.rewind();
  EXPECT_EQ(estimate_clock_from_streams(robot_fails, tracker, &choppy, &b, nullptr), Status::read_failed);
}

}  // namespace
}  // namespace hivecal::capture_job_golden_test
