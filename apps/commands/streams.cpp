#include "commands/streams.hpp"

#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/host_storage.hpp"
#include "hivecal/port/capture_file.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/port/recorder.hpp"
#include "hivecal/port/rtde_client.hpp"
#include "hivecal/port/serial_port.hpp"
#include "streams/session.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"

namespace hivecal::streams {
namespace {

using port::Error;

volatile std::sig_atomic_t g_stop = 0;
void request_stop(int) {
  g_stop = 1;
}

/// SIGINT/SIGTERM/SIGHUP (a closed terminal) end the recording cleanly, stats printed (no
/// SA_RESTART: poll() wakes up at once).
void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGHUP, &action, nullptr);
}

void print_clock(std::FILE* out, const ClockFit& fit) {
  std::fprintf(out, "clock: t_robot = %.1f us + (1 %+.3f ppm) * t_tracker\n", fit.offset_us, fit.drift * 1e6);
  std::fprintf(out, "       offset %.1f +- %.1f us at tracker time %.6f s; drift +- %.3f ppm\n",
               fit.offset_at_reference_us, fit.sigma_offset_at_reference_us, fit.reference_tracker_us * 1e-6,
               fit.sigma_drift * 1e6);
  std::fprintf(out, "       correlation %.3f (runner-up %.3f), %u chords (%u on speed changes), rms %.1f um\n",
               fit.coarse_correlation, fit.runner_up_correlation, fit.chords_used, fit.edge_chords,
               fit.residual_rms_m * 1e6);
}

void print_counts(std::FILE* out, const ExtractionCounts& counts) {
  std::fprintf(out, "tracker points %llu: kept %llu\n", static_cast<unsigned long long>(counts.tracker_points),
               static_cast<unsigned long long>(counts.kept));
  for (int r = 0; r < kDropReasonCount; ++r)
    if (counts.dropped[r] != 0)
      std::fprintf(out, "  dropped %-22s %llu\n", drop_reason_name(static_cast<DropReason>(r)),
                   static_cast<unsigned long long>(counts.dropped[r]));
}

void print_input(std::FILE* out, const char* stream, const StreamInputCounts& in) {
  if (in.is_log()) {
    std::fprintf(out, "%s %s\n", stream, textio::describe_log(in.format, in.log).c_str());
    return;
  }
  const DecoderStats& s = in.frames;
  std::fprintf(out, "%s frames %llu ok, %llu rejected, %llu packets lost in %llu gaps\n", stream,
               static_cast<unsigned long long>(s.frames_ok), static_cast<unsigned long long>(s.frames_rejected()),
               static_cast<unsigned long long>(s.packets_lost), static_cast<unsigned long long>(s.sequence_gaps));
}

/// One recorded stream: its port and capture file options.
struct StreamOptions {
  const char* port;
  const char* out;
  const char* baud_option;
};
constexpr StreamOptions kStreams[] = {{"robot-port", "robot-out", "robot-baud"},
                                      {"tracker-port", "tracker-out", "tracker-baud"}};

/// Checks the command line of `record`: baud rates, duration, and the capture paths (each a
/// regular file or new, distinct from the other and from the ports, not existing unless --force).
Error check_record_options(const cli::Options& options, double* duration_s, int* bauds) {
  if (options.get("robot-port").empty() && options.get("tracker-port").empty()) {
    return Error::usage("give --robot-port and/or --tracker-port (see --help)");
  }
  Error error = cli::ranged_option(
      options, "duration-s", cli::NumberRange{0.0, 1e9, false, false, "s (0: until Ctrl-C / SIGTERM)"}, duration_s);
  if (!error.ok()) return error;
  port::OutputSet checks;  // used for its checks only: captures are written live, not staged
  for (std::size_t k = 0; k < 2; ++k) {
    const StreamOptions& s = kStreams[k];
    if (options.get(s.port).empty()) continue;
    std::size_t baud = 0;  // a whole number (115200.5 was taken as 115200), then one the port can set
    error = cli::count_option(options, s.baud_option, 1, 10000000, &baud);
    if (!error.ok()) return error;
    bauds[k] = static_cast<int>(baud);
    if (!port::baud_supported(bauds[k])) {
      return Error::usage(std::string("--") + s.baud_option + ": unsupported baud rate " + options.get(s.baud_option) +
                          " (the port takes " + port::supported_bauds() + " bit/s)");
    }
    error = checks.add_input(options.get(s.port), std::string("--") + s.port);
    if (!error.ok()) return error;
  }
  const std::string robot_port = options.get(kStreams[0].port);
  const std::string tracker_port = options.get(kStreams[1].port);
  if (!robot_port.empty() && !tracker_port.empty() &&
      port::same_file(port::identify(robot_port), port::identify(tracker_port))) {
    return Error::usage(std::string("--") + kStreams[0].port + " and --" + kStreams[1].port +
                        " name the same port: each stream needs its own");
  }
  for (const StreamOptions& s : kStreams) {
    if (options.get(s.port).empty()) continue;
    const std::string out = options.get(s.out);
    std::size_t id = 0;
    if (out == "-") return Error::usage(std::string("--") + s.out + ": a capture goes to a file, not stdout");
    error = checks.add_file(out, std::string("--") + s.out, &id);
    if (!error.ok()) return error;
    if (port::identify(out).exists && !options.given("force")) {
      return Error::output(std::string("--") + s.out + " " + port::quoted(out, 200) +
                           ": exists; refusing to overwrite a capture (--force replaces it)");
    }
  }
  return Error{};
}

/// The controller's text messages printed on stderr; more are only counted (the summary).
constexpr std::uint64_t kTextMessagesShown = 20;

/// The summary line of `record --rtde`: what the log holds, or that this run wrote nothing (a
/// controller that never sent a row, a file another recorder holds), without counts that read
/// as if a recording were there.
void print_rtde_summary(const std::string& host, int port_number, const std::string& out, bool written,
                        const port::RtdeStats& stats) {
  const std::string address = host.find(':') == std::string::npos ? host : "[" + host + "]";
  const std::uint32_t* v = stats.controller_version;
  char controller[64] = "";
  if (v[0] + v[1] + v[2] + v[3] > 0)
    std::snprintf(controller, sizeof controller, " (URControl %u.%u.%u.%u)", v[0], v[1], v[2], v[3]);
  if (!written) {
    std::printf("rtde %s:%d%s: nothing recorded, nothing written to %s (%llu text messages from the controller)\n",
                address.c_str(), port_number, controller, port::printable(out, 4096).c_str(),
                static_cast<unsigned long long>(stats.text_messages));
    return;
  }
  std::printf("rtde %s:%d%s -> %s: %llu data packages, %llu rows, %llu text messages%s\n", address.c_str(), port_number,
              controller, port::printable(out, 4096).c_str(), static_cast<unsigned long long>(stats.data_packages),
              static_cast<unsigned long long>(stats.rows_written), static_cast<unsigned long long>(stats.text_messages),
              stats.ended_by_controller ? "; the controller closed the connection" : "");
}

/// `record --rtde HOST[:PORT]`: the controller's joint states through RTDE into a robot log
/// (the RTDE recorder's text format, which every reader takes), written as it comes.
Error record_rtde(const cli::Options& options) {
  if (!options.get("robot-port").empty() || !options.get("tracker-port").empty()) {
    return Error::usage("--rtde records the robot alone: record the tracker's port in a second `hivecal record`");
  }
  std::string host;
  int port_number = port::kRtdePort;
  Error error = port::parse_rtde_address(options.get("rtde"), &host, &port_number);
  if (!error.ok()) return error;
  port::RtdeRecordOptions rtde;
  error = cli::bounded_option(options, "duration-s", 0.0, 1e9, &rtde.duration_s);
  if (error.ok()) error = cli::bounded_option(options, "rtde-frequency", 1.0, 500.0, &rtde.frequency_hz);
  if (!error.ok()) return error;
  const std::string out = options.get("robot-out") == "robot.cap" && !options.given("robot-out")
                              ? "robot_rtde.txt"
                              : options.get("robot-out");
  port::OutputSet checks;
  std::size_t id = 0;
  error = checks.add_file(out, "--robot-out", &id);
  if (error.ok() && port::identify(out).exists && !options.given("force")) {
    error = Error::output("--robot-out " + port::quoted(out, 200) +
                          ": exists; refusing to overwrite a recording (--force replaces it)");
  }
  if (!error.ok()) return error;
  port::CaptureWriter file;  // rows are appended as they come: Ctrl-C loses nothing
  bool opened = false;
  std::uint64_t texts_shown = 0;  // a chattering controller does not flood the terminal
  rtde.on_text = [&texts_shown](const std::string& text) {
    if (texts_shown < kTextMessagesShown) {
      std::fprintf(stderr, "hivecal record: controller says: %s\n", text.c_str());
    } else if (texts_shown == kTextMessagesShown) {
      std::fprintf(stderr, "hivecal record: further controller messages are counted, not shown\n");
    }
    ++texts_shown;
  };
  install_stop_handlers();
  port::RtdeStats stats;
  error = port::record_rtde(
      host, port_number, rtde, &g_stop,
      [&](const std::string& row) {
        if (!opened) {  // the file exists only once the controller has accepted the recipe
          const Error created = file.open(out, options.given("force"));
          if (!created.ok()) return created;
          opened = true;
        }
        return file.write_whole(reinterpret_cast<const std::uint8_t*>(row.data()), row.size());
      },
      &stats);
  const Error closed = file.close();
  if (error.ok()) error = closed;
  print_rtde_summary(host, port_number, out, opened, stats);
  return error;
}

Error record(const cli::Options& options) {
  if (!options.get("rtde").empty()) return record_rtde(options);
  double duration_s = 0.0;
  int bauds[2] = {0, 0};
  Error error = check_record_options(options, &duration_s, bauds);
  if (!error.ok()) return error;
  // Every port is opened before any file is created: a missing port leaves no empty capture.
  std::vector<std::unique_ptr<port::SerialPort>> ports;
  std::vector<const StreamOptions*> recorded;
  for (std::size_t k = 0; k < 2; ++k) {
    if (options.get(kStreams[k].port).empty()) continue;
    ports.push_back(std::make_unique<port::SerialPort>(port::SerialOptions{options.get(kStreams[k].port), bauds[k]}));
    recorded.push_back(&kStreams[k]);
    error = ports.back()->open();
    if (!error.ok()) return error;
  }
  std::vector<std::unique_ptr<port::CaptureWriter>> files;
  for (const StreamOptions* s : recorded) {
    files.push_back(std::make_unique<port::CaptureWriter>());
    error = files.back()->open(options.get(s->out), options.given("force"));
    if (!error.ok()) return error;
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
  error = port::record_streams(sources, writers, &g_stop, record_options, &stats);
  for (std::size_t i = 0; i < sources.size(); ++i) {
    // What the capture holds; after a failed write (a full disk) also what was read and lost.
    const std::string lost = stats.bytes_read[i] == stats.bytes[i]
                                 ? std::string()
                                 : " (" + std::to_string(stats.bytes_read[i]) + " read, " +
                                       std::to_string(stats.bytes_read[i] - stats.bytes[i]) + " not written)";
    std::printf("%s -> %s: %llu bytes%s, %llu disconnections\n", sources[i]->name().c_str(), writers[i]->path().c_str(),
                static_cast<unsigned long long>(stats.bytes[i]), lost.c_str(),
                static_cast<unsigned long long>(stats.disconnects[i]));
  }
  return error;
}

Error extract(const cli::Options& options) {
  if (options.get("robot").empty() || options.get("tracker").empty()) {
    return Error::usage("--robot and --tracker are required (see --help)");
  }
  textio::RobotDescription robot;
  bool from_file = false;
  textio::InputUnits units;
  Vec3 tool = Vec3::Zero();
  std::string tool_note;
  double max_speed_mm_s = 0, window_s = 0;
  Error error = cli::robot_model_option(options, "robot-model", &robot, &from_file);
  if (error.ok()) error = cli::input_units_option(options, &units);
  if (error.ok()) {  // the tool point as calibrate takes it: the same samples from the same session
    error = cli::tool_point_option(options, units, from_file ? &robot.model.tool_m : nullptr, &tool, &tool_note);
  }
  if (error.ok())
    error = cli::ranged_option(options, "max-speed-mm-s", cli::NumberRange{0.0, 1e6, true, true}, &max_speed_mm_s);
  if (error.ok()) error = cli::bounded_option(options, "window-s", 0.0, 60.0, &window_s);
  if (!error.ok()) return error;
  port::OutputSet outputs;
  std::size_t samples_id = 0;
  const std::string out = options.get("samples");
  error = declare_inputs(options, {"samples"}, &outputs);
  if (error.ok() && !out.empty()) error = outputs.add_file(out, "--samples", &samples_id);
  if (!error.ok()) return error;
  streams::SessionConfig config;
  config.speed_model = robot.model;
  config.speed_model.tool_m = tool;
  config.max_speed_m_s = max_speed_mm_s * 1e-3;
  config.window_s = window_s;
  config.log_options.units = units;
  config.log_options.units.joints = textio::input_joints(robot.model);
  config.log_options.arm_name = robot.robot;
  error = streams::joint_names_option(options.get("joint-names"), &config.log_options);
  if (!error.ok()) return error;
  const auto dataset = std::make_unique<cli::HostDataset>();  // as large as the captures' static samples
  SessionFacts facts;
  error = load_session({"", options.get("robot"), options.get("tracker")}, config, dataset.get(), &facts);
  std::FILE* terminal = out == "-" ? stderr : stdout;  // stdout may carry the samples
  if (!tool_note.empty()) std::fprintf(terminal, "%s\n", tool_note.c_str());
  const bool counted = facts.run.robot.records > 0 && facts.run.tracker.records > 0;
  if (counted) {  // also when the clock fit failed: the counts tell why
    print_input(terminal, "robot  ", facts.run.robot);
    print_input(terminal, "tracker", facts.run.tracker);
  }
  if (!error.ok()) return error;
  print_clock(terminal, facts.run.clock);
  print_counts(terminal, facts.run.counts);
  if (out.empty()) return Error{};
  error = outputs.stage_text(samples_id, "", textio::format_samples_csv(dataset->samples(), robot.model.joint_count));
  return error.ok() ? outputs.commit() : error;
}

}  // namespace

int record_main(int argc, char** argv) {
  const std::string command = kRecordCommand;
  const std::vector<cli::OptionSpec> specs = {
      {"robot-port", "DEV", "serial port of the robot joint-state stream", ""},
      {"tracker-port", "DEV", "serial port of the tracker stream", ""},
      {"robot-out", "FILE", "capture file of the robot stream", "robot.cap"},
      {"tracker-out", "FILE", "capture file of the tracker stream", "tracker.cap"},
      {"robot-baud", "N", "robot line rate [bit/s]", std::to_string(port::kRobotBaud)},
      {"tracker-baud", "N", "tracker line rate [bit/s]", std::to_string(port::kTrackerBaud)},
      {"duration-s", "S", "stop after this long [s]; 0: until Ctrl-C / SIGTERM", "0"},
      {"force", "", "replace existing capture files (never done without it)", ""},
      {"rtde", "HOST[:PORT]|[IPv6]:PORT",
       "record a UR controller's joint states over RTDE (port 30004) into --robot-out as a robot log", ""},
      {"rtde-frequency", "HZ", "with --rtde: output rate (CB-series 125, e-Series up to 500) [Hz]", "125"},
  };
  cli::Options options;
  const int parsed =
      cli::parse_options(command,
                         "Records the raw bytes of the robot and/or tracker serial ports into capture files as they\n"
                         "come (fsync every second and on Ctrl-C/SIGTERM; a capture cut mid-frame stays usable).\n"
                         "A port that disappears is reopened with backoff. With --rtde, a UR controller's\n"
                         "timestamp, actual_q and actual_TCP_pose over RTDE into a robot log (default robot_rtde.txt).",
                         specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return cli::exit_with(command, record(options));
}

int extract_main(int argc, char** argv) {
  const std::string command = kExtractCommand;
  std::vector<cli::OptionSpec> specs = {
      {"robot", "FILE|BAG",
       "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
      {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
      {"joint-names", "N1,..,NN",
       "joint names in ROS logs (rostopic, bag), the arm's joints 1..N in order (default: a UR's the UR "
       "drivers', another arm's the message's own order)",
       ""},
      {"robot-model", "NAME|FILE",
       std::string(robot_type_names()) + " or a robot description .json (nominal geometry for tool speeds)", "ur5"},
      {"max-speed-mm-s", "X", "quasi-static threshold: tool speed at the tracker instant [mm/s]", "2"},
      {"window-s", "S", "optional stability window around each instant, both streams still over it; 0: off [s]", "0"},
      {"samples", "FILE", "write the paired samples q1..qN,x,y,z (CSV) here; '-' for stdout; empty: none", ""},
  };
  const std::vector<cli::OptionSpec> tool = cli::tool_option_specs(
      "nominal tool point in the flange frame [m] (for tool speeds; default: the description file's)");
  specs.insert(specs.begin() + 4, tool.begin(), tool.end());
  for (const cli::OptionSpec& spec : cli::input_unit_option_specs()) specs.push_back(spec);
  cli::Options options;
  const int parsed =
      cli::parse_options(command,
                         "Relates the tracker clock to the robot clock from the motion itself (t_robot = offset +\n"
                         "(1 + drift) t_tracker), then pairs each valid tracker point with the joints at the same\n"
                         "instant and keeps the quasi-static ones. Prints the clock fit and the drop statistics.",
                         specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return cli::exit_with(command, extract(options));
}

}  // namespace hivecal::streams
