#include "stream_commands.hpp"

#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli.hpp"
#include "csv.hpp"
#include "hivecal/port/capture_file.hpp"
#include "hivecal/port/recorder.hpp"
#include "hivecal/port/serial_port.hpp"
#include "stream_pipeline.hpp"
#include "text_util.hpp"

namespace hivecal::streams {
namespace {

using cli::kExitBadInput;
using cli::kExitFailure;
using cli::kExitOk;
using cli::kExitOutputError;
using cli::kExitUsage;

volatile std::sig_atomic_t g_stop = 0;
void request_stop(int) { g_stop = 1; }

/// SIGINT/SIGTERM end the recording cleanly (no SA_RESTART: poll() wakes up at once).
void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool parse_number(const std::string& command, const cli::Options& options, const char* name, double* value) {
  if (textio::parse_double(options.get(name), value)) return true;
  cli::error(command, std::string("--") + name + ": not a number: '" + options.get(name) + "'");
  return false;
}

/// "x,y,z" in metres.
bool parse_vec3(const std::string& text, Vec3* value) {
  std::size_t start = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t comma = text.find(',', start);
    if ((axis < 2) == (comma == std::string::npos)) return false;
    if (!textio::parse_double(std::string_view(text).substr(start, comma - start), &(*value)(axis))) return false;
    start = comma + 1;
  }
  return true;
}

void print_clock(const ClockFit& fit) {
  std::printf("clock: t_robot = %.1f us + (1 %+.3f ppm) * t_tracker\n", fit.offset_us, fit.drift * 1e6);
  std::printf("       offset %.1f +- %.1f us at tracker time %.6f s; drift +- %.3f ppm\n",
              fit.offset_at_reference_us, fit.sigma_offset_at_reference_us, fit.reference_tracker_us * 1e-6,
              fit.sigma_drift * 1e6);
  std::printf("       correlation %.3f (runner-up %.3f), %u chords (%u on speed changes), rms %.1f um\n",
              fit.coarse_correlation, fit.runner_up_correlation, fit.chords_used, fit.edge_chords,
              fit.residual_rms_m * 1e6);
}

void print_counts(const ExtractionCounts& counts) {
  std::printf("tracker points %llu: kept %llu\n", static_cast<unsigned long long>(counts.tracker_points),
              static_cast<unsigned long long>(counts.kept));
  for (int r = 0; r < kDropReasonCount; ++r)
    if (counts.dropped[r] != 0)
      std::printf("  dropped %-22s %llu\n", drop_reason_name(static_cast<DropReason>(r)),
                  static_cast<unsigned long long>(counts.dropped[r]));
}

void print_decoder(const char* stream, const DecoderStats& s, bool is_log, textio::LogFormat format,
                   const textio::LogCounters& log) {
  if (is_log) {
    std::printf("%s %s\n", stream, textio::describe_log(format, log).c_str());
    return;
  }
  std::printf("%s frames %llu ok, %llu rejected, %llu packets lost in %llu gaps\n", stream,
              static_cast<unsigned long long>(s.frames_ok), static_cast<unsigned long long>(s.frames_rejected()),
              static_cast<unsigned long long>(s.packets_lost), static_cast<unsigned long long>(s.sequence_gaps));
}

}  // namespace

int record_main(int argc, char** argv) {
  const std::string command = "record";
  const std::vector<cli::OptionSpec> specs = {
      {"robot-port", "DEV", "serial port of the robot joint-state stream", ""},
      {"tracker-port", "DEV", "serial port of the tracker stream", ""},
      {"robot-out", "FILE", "capture file of the robot stream", "robot.cap"},
      {"tracker-out", "FILE", "capture file of the tracker stream", "tracker.cap"},
      {"robot-baud", "N", "robot line rate [bit/s]", std::to_string(port::kRobotBaud)},
      {"tracker-baud", "N", "tracker line rate [bit/s]", std::to_string(port::kTrackerBaud)},
      {"duration-s", "S", "stop after this long [s]; 0: until Ctrl-C / SIGTERM", "0"},
  };
  cli::Options options;
  const int parsed = cli::parse_options(
      command,
      "Records the raw bytes of the robot and/or tracker serial ports into capture files as they\n"
      "come (fsync every second and on Ctrl-C/SIGTERM; a capture cut mid-frame stays usable).\n"
      "A port that disappears is reopened with backoff.",
      specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  double robot_baud = 0, tracker_baud = 0, duration_s = 0;
  if (!parse_number(command, options, "robot-baud", &robot_baud) ||
      !parse_number(command, options, "tracker-baud", &tracker_baud) ||
      !parse_number(command, options, "duration-s", &duration_s))
    return kExitUsage;
  if (options.get("robot-port").empty() && options.get("tracker-port").empty()) {
    cli::error(command, "give --robot-port and/or --tracker-port (see --help)");
    return kExitUsage;
  }
  std::vector<std::unique_ptr<port::SerialPort>> ports;
  std::vector<std::unique_ptr<port::CaptureWriter>> files;
  const struct {
    const char* port;
    const char* out;
    const char* baud_option;
    double baud;
  } streams[] = {{"robot-port", "robot-out", "robot-baud", robot_baud},
                 {"tracker-port", "tracker-out", "tracker-baud", tracker_baud}};
  std::string error;
  for (const auto& s : streams) {
    if (options.get(s.port).empty()) continue;
    const int baud = static_cast<int>(s.baud);
    if (!port::baud_supported(baud)) {
      cli::error(command, std::string("--") + s.baud_option + ": unsupported baud rate " + options.get(s.baud_option));
      return kExitUsage;
    }
    ports.push_back(std::make_unique<port::SerialPort>(port::SerialOptions{options.get(s.port), baud}));
    if (!ports.back()->open(&error)) {
      cli::error(command, error);
      return kExitBadInput;
    }
    files.push_back(std::make_unique<port::CaptureWriter>());
    if (!files.back()->open(options.get(s.out), &error)) {
      cli::error(command, error);
      return kExitOutputError;
    }
  }
  std::vector<port::ByteSource*> sources;
  std::vector<port::CaptureWriter*> writers;
  for (std::size_t i = 0; i < ports.size(); ++i) {
    sources.push_back(ports[i].get());
    writers.push_back(files[i].get());
  }
  install_stop_handlers();
  port::RecordOptions record_options;
  record_options.duration_s = duration_s;
  port::RecordStats stats;
  const bool ok = port::record_streams(sources, writers, &g_stop, record_options, &stats, &error);
  for (std::size_t i = 0; i < sources.size(); ++i)
    std::printf("%s -> %s: %llu bytes, %llu disconnections\n", sources[i]->name().c_str(),
                writers[i]->path().c_str(), static_cast<unsigned long long>(stats.bytes[i]),
                static_cast<unsigned long long>(stats.disconnects[i]));
  if (!ok) {
    cli::error(command, error);
    return kExitOutputError;
  }
  return kExitOk;
}

int extract_main(int argc, char** argv) {
  const std::string command = "extract";
  const std::vector<cli::OptionSpec> specs = {
      {"robot", "FILE|BAG", "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
      {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
      {"joint-names", "N1,..,N6", "joint names of ROS logs (rostopic, bag), joints 1..6 in order (default: UR driver names)", ""},
      {"robot-model", "NAME", "ur3, ur5, ur10 or ur5e (nominal geometry for tool speeds)", "ur5"},
      {"tool", "X,Y,Z", "nominal tool point in the flange frame [m] (for tool speeds)", "0,0,0.1695"},
      {"max-speed-mm-s", "X", "quasi-static threshold on both sides [mm/s]", "2"},
      {"window-s", "S", "width of the quasi-static window around each tracker instant [s]", "1"},
      {"samples", "FILE", "paired samples q1..q6,x,y,z (CSV); '-' for stdout; empty: none", ""},
  };
  cli::Options options;
  const int parsed = cli::parse_options(
      command,
      "Relates the tracker clock to the robot clock from the motion itself (t_robot = offset +\n"
      "(1 + drift) t_tracker), then pairs each valid tracker point with the joints at the same\n"
      "instant and keeps the quasi-static ones. Prints the clock fit and the drop statistics.",
      specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  if (options.get("robot").empty() || options.get("tracker").empty()) {
    cli::error(command, "--robot and --tracker are required (see --help)");
    return kExitUsage;
  }
  RobotType type = RobotType::ur5;
  Vec3 tool = Vec3::Zero();
  double max_speed_mm_s = 0, window_s = 0;
  if (robot_type_from_name(options.get("robot-model").c_str(), &type) != Status::ok ||
      !parse_vec3(options.get("tool"), &tool) || !parse_number(command, options, "max-speed-mm-s", &max_speed_mm_s) ||
      !parse_number(command, options, "window-s", &window_s) || max_speed_mm_s <= 0 || window_s <= 0) {
    cli::error(command, "bad --robot-model, --tool, --max-speed-mm-s or --window-s (see --help)");
    return kExitUsage;
  }
  RobotModel speed_model = nominal_model(type);
  speed_model.tool_m = tool;
  ExtractionConfig extraction = make_extraction_config(speed_model);
  extraction.max_speed_m_s = max_speed_mm_s * 1e-3;
  extraction.window_us = static_cast<std::uint32_t>(window_s * 1e6);
  textio::RobotLogOptions log_options;
  if (!options.get("joint-names").empty() && !textio::parse_joint_names(options.get("joint-names"), &log_options)) {
    cli::error(command, "--joint-names needs six comma-separated names");
    return kExitUsage;
  }
  const auto dataset = std::make_unique<Dataset<65536>>();
  CaptureRunReport report;
  std::string error;
  if (!extract_from_files(options.get("robot"), options.get("tracker"), make_clock_sync_config(speed_model),
                             extraction, dataset.get(), &report, &error, nullptr, {}, log_options)) {
    cli::error(command, error);
    return kExitBadInput;
  }
  print_decoder("robot  ", report.decoding.robot_decoder, report.robot_is_log, report.robot_format, report.robot_log);
  print_decoder("tracker", report.decoding.tracker_decoder, report.tracker_is_log, report.tracker_format,
                report.tracker_log);
  if (report.clock_status != Status::ok) {
    cli::error(command, std::string("clock relation not found: ") + status_message(report.clock_status));
    return kExitFailure;
  }
  print_clock(report.clock);
  print_counts(report.counts);
  if (report.extraction_status == Status::dataset_full) cli::error(command, "more samples than the dataset holds");
  const std::string out = options.get("samples");
  if (out.empty()) return kExitOk;
  const std::string csv = textio::format_samples_csv(dataset->samples());
  if (out == "-") {
    std::fwrite(csv.data(), 1, csv.size(), stdout);
    return kExitOk;
  }
  if (!textio::write_file_atomically(out, csv, &error)) {
    cli::error(command, error);
    return kExitOutputError;
  }
  return kExitOk;
}

}  // namespace hivecal::streams
