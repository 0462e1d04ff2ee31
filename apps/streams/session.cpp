#include "streams/session.hpp"

#include <cstdio>

#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "textio/csv.hpp"
#include "textio/logs.hpp"

namespace hivecal::streams {
namespace {

/// The stream path: two captures -> clock fit -> quasi-static samples.
/// "[decode] pass 1/2 (clock): 45 %" on stderr, in place, when a percent changes.
class DecodeProgress {
 public:
  explicit DecodeProgress(bool enabled) : enabled_(enabled) {}
  ~DecodeProgress() {
    if (printed_) std::fprintf(stderr, "\n");
  }
  void operator()(int pass, std::uint64_t done_bytes, std::uint64_t total_bytes) {
    if (!enabled_ || total_bytes == 0) return;
    const int percent = static_cast<int>(100.0 * static_cast<double>(done_bytes) / static_cast<double>(total_bytes));
    if (pass == last_pass_ && percent == last_percent_) return;
    last_pass_ = pass;
    last_percent_ = percent;
    std::fprintf(stderr, "\r[decode] pass %d/2 (%s): %3d %%", pass, pass == 1 ? "clock" : "samples", percent);
    std::fflush(stderr);
    printed_ = true;
  }

 private:
  bool enabled_;
  bool printed_ = false;
  int last_pass_ = 0;
  int last_percent_ = -1;
};

std::string format(const char* fmt, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

std::string input_line(const char* stream, const StreamInputCounts& in, const char* records) {
  std::string line = std::string(stream) + " stream: " + std::to_string(in.records) + " " + records;
  if (in.is_log()) return line + " (" + textio::describe_log(in.format, in.log) + ")";
  return line + ", " + std::to_string(in.frames.frames_rejected()) + " frames rejected, " +
         std::to_string(in.frames.packets_lost) + " packets lost";
}

}  // namespace

port::Error joint_names_option(const std::string& value, textio::RobotLogOptions* log_options) {
  if (value.empty() || textio::parse_joint_names(value, log_options)) return port::Error{};
  return port::Error::usage("--joint-names needs six different comma-separated names, joints 1..6 in order");
}

namespace {

/// Names each kept sample by its tracker point (file and timestamp), in the order the
/// extraction adds them to the dataset (Sample::index): a blunder is reported where it is.
/// Every event is passed on to `next` (the caller's observer, SessionConfig::observer) too.
class SampleSources final : public ExtractionObserver {
 public:
  SampleSources(std::string tracker, std::vector<std::string>* out, ExtractionObserver* next)
      : tracker_(std::move(tracker)), out_(out), next_(next) {}
  void on_sample(const ExtractedSample& sample) override {
    char buf[64];
    std::snprintf(buf, sizeof buf, " tracker point at t = %.6f s", sample.tracker_us * 1e-6);
    out_->push_back(tracker_ + buf);
    if (next_ != nullptr) next_->on_sample(sample);
  }
  void on_drop(std::uint64_t tracker_us, DropReason reason) override {
    if (next_ != nullptr) next_->on_drop(tracker_us, reason);
  }

 private:
  std::string tracker_;
  std::vector<std::string>* out_;
  ExtractionObserver* next_;
};

port::Error load_streams(const SessionSources& sources, const SessionConfig& config, DatasetBase* dataset,
                         SessionFacts* facts) {
  ExtractionConfig extraction = make_extraction_config(config.speed_model);
  if (config.max_speed_m_s > 0.0) extraction.max_speed_m_s = config.max_speed_m_s;
  if (config.window_s > 0.0) extraction.window_us = static_cast<std::uint32_t>(config.window_s * 1e6);
  CaptureRunReport& report = facts->run;
  DecodeProgress progress(config.progress);
  SampleSources sample_sources(sources.tracker, &facts->sample_sources, config.observer);
  const port::Error read = extract_from_files(
      sources.robot, sources.tracker, make_clock_sync_config(config.speed_model), extraction, dataset, &report,
      &sample_sources, [&progress](int pass, std::uint64_t done, std::uint64_t total) { progress(pass, done, total); },
      config.log_options);
  if (!read.ok()) return read;
  facts->has_stream = true;
  facts->info_lines.push_back(input_line("robot", report.robot, "joint states"));
  facts->info_lines.push_back(input_line("tracker", report.tracker, "points"));
  if (report.robot.records == 0 || report.tracker.records == 0) {
    const StreamInputCounts& empty = report.robot.records == 0 ? report.robot : report.tracker;
    return port::Error::input(std::string(empty.is_log() ? "no data row in the " : "no valid frame in the ") +
                              (report.robot.records == 0 ? "robot" : "tracker") +
                              (empty.is_log() ? " log" : " capture"));
  }
  if (report.clock_status != Status::ok) {
    return port::Error::input(std::string("clock relation not found: ") + status_message(report.clock_status) +
                              " (do both streams cover the same motion?)");
  }
  const ClockFit& clock = report.clock;
  facts->info_lines.push_back(
      format("clock: t_robot - t_tracker = %.6f s (sigma %.3f ms)", clock.offset_at_reference_us * 1e-6,
             clock.sigma_offset_at_reference_us * 1e-3) +
      format(", drift %.2f ppm (sigma %.2f ppm)", clock.drift * 1e6, clock.sigma_drift * 1e6));
  const ClockProfileStats& profile = report.clock_stats;
  if (profile.tracker_set_aside > 0) {
    // Blunders (a jump no tool makes, then back): named by tracker timestamp so they can be found.
    std::string when;
    for (std::uint64_t k = 0; k < profile.tracker_set_aside && k < kClockSetAsideLog; ++k)
    {
      char stamp[32];
      std::snprintf(stamp, sizeof stamp, k == 0 ? "%.3f" : ", %.3f", static_cast<double>(profile.set_aside_tracker_us[k]) * 1e-6);
      when += stamp;
    }
    if (profile.tracker_set_aside > kClockSetAsideLog) when += ", ...";
    facts->info_lines.push_back("clock: set aside " + std::to_string(profile.tracker_set_aside) +
                                " tracker point(s) that jump faster than any tool moves, at t_tracker = " + when + " s");
  }
  std::string dropped;
  for (int k = 0; k < kDropReasonCount; ++k) {
    const std::uint64_t n = report.counts.dropped[k];
    if (n == 0) continue;
    const char* name = drop_reason_name(static_cast<DropReason>(k));
    facts->dropped.emplace_back(name, n);
    dropped += (dropped.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(n);
  }
  facts->info_lines.push_back("static samples: kept " + std::to_string(report.counts.kept) + " of " +
                              std::to_string(report.counts.tracker_points) + " tracker points; dropped: " +
                              (dropped.empty() ? "none" : dropped));
  if (report.extraction_status == Status::dataset_full) {
    return port::Error::input("more static samples than the dataset holds (" + std::to_string(dataset->capacity()) +
                              " samples max): split the session");
  }
  return port::Error{};
}

}  // namespace

std::string orientation_line(const SessionFacts& facts) {
  if (facts.orientation.poses == 0) return "";
  const textio::OrientationInput& given = facts.orientation_input;
  char why[96];
  if (given.lever_m < 0.0) {
    std::snprintf(why, sizeof why, "position sigma %.3g m / angle sigma %.3g rad", given.position_sigma_m,
                  given.angle_sigma_rad);
  } else {
    std::snprintf(why, sizeof why, "as given");
  }
  char line[256];
  std::snprintf(line, sizeof line, "orientation used: %zu poses with rx, ry, rz, each also as targets 2 and 3 at a "
                "lever of %.6g m (%s)", facts.orientation.poses, facts.orientation.lever_m, why);
  return line;
}

port::Error load_session(const SessionSources& sources, const SessionConfig& config, DatasetBase* dataset,
                         SessionFacts* facts) {
  const bool samples = !sources.samples.empty();
  const bool streams = !sources.robot.empty() || !sources.tracker.empty();
  if (samples == streams) return port::Error::usage("give either --samples, or --robot and --tracker (see --help)");
  if (streams && (sources.robot.empty() || sources.tracker.empty())) {
    return port::Error::usage("--robot and --tracker go together");
  }
  if (streams) {
    facts->info_lines.push_back("input: robot " + sources.robot + ", tracker " + sources.tracker);
    return load_streams(sources, config, dataset, facts);
  }
  std::vector<std::size_t> lines;
  facts->orientation_input = config.orientation;
  const port::Error r = textio::read_samples_csv(sources.samples, dataset, config.log_options.units, &lines,
                                                 config.orientation, &facts->orientation);
  for (std::size_t line : lines) facts->sample_sources.push_back(sources.samples + ":" + std::to_string(line));
  if (!r.ok()) return r;
  facts->info_lines.push_back("input: " + sources.samples + " (" + std::to_string(dataset->size()) +
                              " paired samples)");
  return port::Error{};
}

}  // namespace hivecal::streams
