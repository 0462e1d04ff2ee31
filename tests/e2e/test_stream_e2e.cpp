// End to end through real pseudo-terminals: the simulated robot and tracker serve their
// streams on two ptys; the recorder reads them with SerialPorts into capture files while a
// decoder tap feeds the clock estimator live (pass 1); the captures are then replayed
// through the decoder into the sample extractor (pass 2). The pairs must match the
// simulator's truth and the clock its true offset within 2 ms.
#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

#include "hivecal/port/capture_file.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/port/pty.hpp"
#include "hivecal/port/recorder.hpp"
#include "hivecal/port/serial_port.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "sim/sim_model.hpp"
#include "sim/sim_server.hpp"
#include "streams/stream_pipeline.hpp"

namespace hivecal::stream_e2e_test {
namespace {

/// Collects the kept samples.
struct Kept final : ExtractionObserver {
  std::vector<ExtractedSample> samples;
  void on_sample(const ExtractedSample& sample) override { samples.push_back(sample); }
};

std::string temp_path(const std::string& name) {
  return "hivecal_e2e_" + std::to_string(::getpid()) + "_" + name;
}

TEST(StreamEndToEnd, SimulatedDevicesOnPtysToSamplesMatchingTheTruth) {
  sim::SimConfig config;
  config.seed = 31;  // the default 600 s, 38-waypoint session
  config.clock_drift = -60e-6;
  const sim::Session session(config);

  port::PtyPair robot_pty;
  port::PtyPair tracker_pty;
  std::string error;
  ASSERT_TRUE(port::open_pty(&robot_pty).ok() && port::open_pty(&tracker_pty).ok()) << error;
  port::SerialPort robot_port(port::SerialOptions{robot_pty.slave_path, port::kRobotBaud});
  port::SerialPort tracker_port(port::SerialOptions{tracker_pty.slave_path, port::kTrackerBaud});
  ASSERT_TRUE(robot_port.open().ok() && tracker_port.open().ok()) << error;
  const std::string robot_path = temp_path("robot.cap");
  const std::string tracker_path = temp_path("tracker.cap");
  port::CaptureWriter robot_file;
  port::CaptureWriter tracker_file;
  ASSERT_TRUE(robot_file.open(robot_path, true).ok() && tracker_file.open(tracker_path, true).ok()) << error;

  // Pass 1 live: decode what the recorder writes and fold it into the clock profiles.
  const auto estimator = std::make_unique<ClockEstimator<>>(make_clock_sync_config(session.truth().nominal));
  streams::RecordQueue robot_decoder;
  streams::RecordQueue tracker_decoder;
  std::atomic<std::uint64_t> received[2] = {{0}, {0}};
  port::RecordOptions record_options;
  record_options.on_bytes = [&](std::size_t source, const std::uint8_t* bytes, std::size_t count) {
    streams::RecordQueue& queue = source == 0 ? robot_decoder : tracker_decoder;
    queue.feed(bytes, count);
    for (const JointStateRecord& r : queue.joints()) estimator->push_robot(r);
    for (const TrackerPointRecord& r : queue.points()) estimator->push_tracker(r);
    queue.joints().clear();
    queue.points().clear();
    received[source] += count;
  };

  // The devices, unpaced (as fast as the ptys take the bytes).
  sim::ServeStats served;
  std::atomic<bool> serving_done{false};
  std::string serve_error;
  bool serve_ok = false;
  std::thread devices([&] {
    const port::Error served_error =
        sim::serve_session(session, robot_pty, tracker_pty, sim::ServeOptions{0.0}, nullptr, &served);
    serve_ok = served_error.ok();
    serve_error = served_error.message;
    serving_done = true;
  });
  volatile std::sig_atomic_t stop = 0;
  std::thread watcher([&] {  // stop once everything served has been recorded
    while (!serving_done || received[0] < served.robot_bytes || received[1] < served.tracker_bytes) usleep(2000);
    stop = 1;
  });
  port::RecordStats recorded;
  EXPECT_TRUE(
      port::record_streams({&robot_port, &tracker_port}, {&robot_file, &tracker_file}, &stop, record_options, &recorded)
          .ok());
  devices.join();
  watcher.join();
  ASSERT_TRUE(serve_ok) << serve_error;
  EXPECT_EQ(recorded.bytes[0], served.robot_bytes);
  EXPECT_EQ(recorded.bytes[1], served.tracker_bytes);
  EXPECT_EQ(robot_decoder.decoder_stats().frames_ok, served.robot_frames);
  EXPECT_EQ(tracker_decoder.decoder_stats().frames_ok, served.tracker_frames);
  EXPECT_EQ(robot_decoder.decoder_stats().frames_rejected(), 0u);
  // One sequence counter per stream, DEVICE_INFO included: the tracker drops nothing, so no
  // gap at all; neither stream restarts (a DEVICE_INFO numbered apart would show as one).
  EXPECT_EQ(tracker_decoder.decoder_stats().sequence_gaps + tracker_decoder.decoder_stats().packets_lost, 0u);
  EXPECT_EQ(tracker_decoder.decoder_stats().sequence_resets + robot_decoder.decoder_stats().sequence_resets, 0u);

  ClockFit fit;
  ASSERT_EQ(estimator->estimate(&fit), Status::ok);
  const sim::SimTruth& truth = session.truth();
  double clock_error_us = 0.0;
  for (const double t_s : {0.0, session.duration_s()}) {
    const auto tracker_us = static_cast<double>(session.tracker_clock_us(t_s));
    const double e = fit.robot_us(tracker_us) - (truth.clock_offset_us + (1.0 + truth.clock_drift) * tracker_us);
    clock_error_us = std::max(clock_error_us, std::fabs(e));
  }
  std::printf("live clock: offset %.1f +- %.1f us, drift %.2f +- %.2f ppm (true %.2f); max error %.1f us\n",
              fit.offset_at_reference_us, fit.sigma_offset_at_reference_us, fit.drift * 1e6, fit.sigma_drift * 1e6,
              truth.clock_drift * 1e6, clock_error_us);
  EXPECT_LT(clock_error_us, 2000.0);

  // Pass 2 from the captures.
  static Dataset<4096> dataset;
  dataset.clear();
  const auto extractor =
      std::make_unique<SampleExtractor<>>(make_extraction_config(session.truth().nominal), fit, &dataset);
  Kept kept;
  extractor->set_observer(&kept);
  port::InputFile robot_bytes;
  port::InputFile tracker_bytes;
  ASSERT_TRUE(robot_bytes.open(robot_path, port::kMaxStreamInputBytes).ok());
  ASSERT_TRUE(tracker_bytes.open(tracker_path, port::kMaxStreamInputBytes).ok());
  streams::PassStats pass;
  EXPECT_EQ(extract_samples_from_streams(robot_bytes, tracker_bytes, extractor.get(), &pass), Status::ok) << error;
  const ExtractionCounts& counts = extractor->counts();
  EXPECT_EQ(counts.pending(), 0u);
  ASSERT_GT(counts.kept, 200u);
  double worst_q_rad = 0.0;
  double worst_point_m = 0.0;
  for (const ExtractedSample& s : kept.samples) {
    const double t_s = session.true_time_of_tracker_us(static_cast<std::uint64_t>(s.tracker_us));
    const JointVector q_true = session.joints_at(t_s);
    worst_q_rad = std::max(worst_q_rad, (s.q_rad - q_true).cwiseAbs().maxCoeff());
    worst_point_m = std::max(worst_point_m, (s.point_m - session.true_point(q_true)).norm());
  }
  std::printf("kept %llu samples: worst joint error %.2e rad, worst point error %.1f um\n",
              static_cast<unsigned long long>(counts.kept), worst_q_rad, worst_point_m * 1e6);
  EXPECT_LT(worst_q_rad, 1e-5);
  EXPECT_LT(worst_point_m, 6.0 * config.tracker_noise_m);
  port::close_pty(&robot_pty);
  port::close_pty(&tracker_pty);
  ::unlink(robot_path.c_str());
  ::unlink(tracker_path.c_str());
}

}  // namespace
}  // namespace hivecal::stream_e2e_test
