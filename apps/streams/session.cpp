#include "streams/session.hpp"

#include <cstdio>

#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "textio/csv.hpp"
#include "textio/logs.hpp"
#include "hivecal/port/error.hpp"

namespace hivecal::streams {
namespace {

/// Longest path printed whole in the input lines (PATH_MAX) [bytes].
constexpr std::size_t kShownPathBytes = 4096;

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

/// Records per second of a stream that held `records` over [first_us, last_us]; 0 if unknown.
double rate_hz(std::uint64_t records, std::uint64_t first_us, std::uint64_t last_us) {
  if (records < 2 || last_us <= first_us) return 0.0;
  return static_cast<double>(records - 1) / (static_cast<double>(last_us - first_us) * 1e-6);
}

/// Why a stream's times cannot be right, or "" when they look like a device's.
std::string times_cause(const char* stream, const StreamInputCounts& input, std::uint64_t records,
                        std::uint64_t rejected, std::uint64_t first_us, std::uint64_t last_us, double low_hz,
                        double high_hz) {
  const char* unit_hint =
      input.is_log() ? "; is the time column in the unit its header names (seconds when it names none)?" : "";
  const std::uint64_t repeated = input.is_log() ? input.log.repeated_time : 0;
  if (input.is_log() && 2 * repeated > input.log.rows) {
    return std::to_string(repeated) + " of the " + std::to_string(input.log.rows) + " " + stream +
           " rows repeat the time of the row before (times finer than 1 us read as equal)" + unit_hint;
  }
  if (records > 0 && 2 * rejected > records) {
    return std::to_string(rejected) + " of " + std::to_string(records) + " " + stream +
           " records do not advance in time (repeated or going back)" + unit_hint;
  }
  const double hz = rate_hz(records - rejected, first_us, last_us);
  if (hz > 0.0 && (hz < low_hz || hz > high_hz)) {
    return std::string("the ") + stream + " records come " + format("%.3g s apart on average (%.3g Hz)", 1.0 / hz, hz) +
           format(", where a device sends %g to %g Hz", low_hz, high_hz) + unit_hint;
  }
  return "";
}

/// What most likely made the clock relation fail, from what went into the profiles.
std::string clock_failure_cause(const CaptureRunReport& report) {
  const ClockProfileStats& s = report.clock_stats;
  if (s.tracker_records > 0 && s.tracker_not_valid == s.tracker_records) {
    return "every one of the " + std::to_string(s.tracker_records) +
           " tracker points is marked invalid (beam lost or status != 0): there is no track to relate";
  }
  std::string cause = times_cause("robot", report.robot, s.robot_records, s.robot_rejected, s.robot_first_us,
                                  s.robot_last_us, 5.0, 10000.0);
  if (cause.empty()) {
    const std::uint64_t valid = s.tracker_records - s.tracker_not_valid;
    cause = times_cause("tracker", report.tracker, valid, s.tracker_rejected, s.tracker_first_us, s.tracker_last_us,
                        0.5, 10000.0);
  }
  if (!cause.empty()) return cause;
  if (s.robot_knots < 4 || s.tracker_points < 4) {
    return "too few usable records (" + std::to_string(s.robot_knots) + " robot knots, " +
           std::to_string(s.tracker_points) + " tracker points)";
  }
  if (s.robot_path_m < 0.01 || s.tracker_path_m < 0.01) {
    return format(
        "the tool hardly moves (robot path %.4f m, tracker path %.4f m): the clocks are related by the motion",
        s.robot_path_m, s.tracker_path_m);
  }
  return format(
      "the robot's and the tracker's speed profiles do not match (robot path %.2f m, tracker path %.2f m):"
      " do both streams cover the same motion?",
      s.robot_path_m, s.tracker_path_m);
}

}  // namespace

port::Error joint_names_option(const std::string& value, textio::RobotLogOptions* log_options) {
  const int joints = log_options->units.joints.count;  // the arm's: set before
  const std::string form = "--joint-names needs " + std::to_string(joints) +
                           " different comma-separated names, the robot model's joints " + textio::joint_names(joints) +
                           " in order";
  if (value.empty()) return port::Error{};
  if (!textio::parse_joint_names(value, log_options)) return port::Error::usage(form);
  if (log_options->joint_names.size() == static_cast<std::size_t>(joints)) return port::Error{};
  const std::size_t given = log_options->joint_names.size();
  log_options->joint_names.clear();
  return port::Error::usage(form + ", got " + std::to_string(given) + " (" + port::quoted(value, 200) + ")");
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
  if (report.clock_status == Status::joint_count_mismatch) {  // the records of another arm: never cut nor padded
    const int joints = config.speed_model.joint_count;
    return port::Error::input(std::to_string(report.clock_stats.robot_joint_count_mismatches) + " of the " +
                              std::to_string(report.clock_stats.robot_records) +
                              " robot records carry another joint count than the robot model's " +
                              std::to_string(joints) + " joints (q1..q" + std::to_string(joints) +
                              "): the joint states of another arm? (--robot-model names the arm)");
  }
  if (report.clock_status != Status::ok) {
    return port::Error::input(std::string("clock relation not found: ") + clock_failure_cause(report));
  }
  const ClockFit& clock = report.clock;
  facts->info_lines.push_back(format("clock: t_robot - t_tracker = %.6f s (sigma %.3f ms)",
                                     clock.offset_at_reference_us * 1e-6, clock.sigma_offset_at_reference_us * 1e-3) +
                              format(", drift %.2f ppm (sigma %.2f ppm)", clock.drift * 1e6, clock.sigma_drift * 1e6));
  const ClockProfileStats& profile = report.clock_stats;
  if (profile.tracker_set_aside > 0) {
    // Blunders (a jump no tool makes, then back): named by tracker timestamp so they can be found.
    std::string when;
    for (std::uint64_t k = 0; k < profile.tracker_set_aside && k < kClockSetAsideLog; ++k) {
      char stamp[32];
      std::snprintf(stamp, sizeof stamp, k == 0 ? "%.3f" : ", %.3f",
                    static_cast<double>(profile.set_aside_tracker_us[k]) * 1e-6);
      when += stamp;
    }
    if (profile.tracker_set_aside > kClockSetAsideLog) when += ", ...";
    facts->info_lines.push_back("clock: set aside " + std::to_string(profile.tracker_set_aside) +
                                " tracker point(s) that jump faster than any tool moves, at t_tracker = " + when +
                                " s");
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
                              std::to_string(report.counts.tracker_points) +
                              " tracker points; dropped: " + (dropped.empty() ? "none" : dropped));
  if (report.extraction_status == Status::dataset_full) {
    return port::Error::input("more static samples than the dataset holds (" + std::to_string(dataset->capacity()) +
                              " samples max): split the session");
  }
  return port::Error{};
}

}  // namespace

std::string sample_source(const SessionFacts& facts, std::uint32_t index) {
  if (index < facts.sample_sources.size()) return facts.sample_sources[index];
  return "sample " + std::to_string(index);
}

std::string orientation_line(const SessionFacts& facts) {
  if (facts.orientation.poses == 0) return "";
  const textio::OrientationInput& given = facts.orientation_input;
  char why[160];
  if (given.lever_m < 0.0 && facts.orientation.joint_sigma_rad > 0.0) {
    std::snprintf(why, sizeof why,
                  "from the noise: position sigma %.3g m, angle sigma %.3g rad, joints read to %.3g rad through the "
                  "arm",
                  given.position_sigma_m, given.angle_sigma_rad, facts.orientation.joint_sigma_rad);
  } else if (given.lever_m < 0.0) {
    std::snprintf(why, sizeof why, "position sigma %.3g m / angle sigma %.3g rad", given.position_sigma_m,
                  given.angle_sigma_rad);
  } else {
    std::snprintf(why, sizeof why, "as given");
  }
  char line[384];
  std::snprintf(line, sizeof line,
                "orientation used: %zu poses with rx, ry, rz, each also as targets 2 and 3 at a "
                "lever of %.6g m (%s)",
                facts.orientation.poses, facts.orientation.lever_m, why);
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
    // The paths as printed (terminal, report): escaped as every name from outside is.
    facts->info_lines.push_back("input: robot " + port::printable(sources.robot, kShownPathBytes) + ", tracker " +
                                port::printable(sources.tracker, kShownPathBytes));
    return load_streams(sources, config, dataset, facts);
  }
  std::vector<std::size_t> lines;
  facts->orientation_input = config.orientation;
  textio::OrientationInput orientation = config.orientation;
  orientation.arm = &config.speed_model;  // whose joints' reading noise the lever takes in
  const port::Error r = textio::read_samples_csv(sources.samples, dataset, config.log_options.units, &lines,
                                                 orientation, &facts->orientation);
  const std::string shown = port::printable(sources.samples, kShownPathBytes);  // in tables, warnings, the report
  for (std::size_t line : lines) facts->sample_sources.push_back(shown + ":" + std::to_string(line));
  if (!r.ok()) return r;
  facts->info_lines.push_back("input: " + shown + " (" + std::to_string(dataset->size()) + " paired samples)");
  return port::Error{};
}

}  // namespace hivecal::streams
