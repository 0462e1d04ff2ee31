// hivecal: robot geometry calibration from laser-tracker data (docs/cli.md).
#include <csignal>
#include <cstdio>
#include <cstring>

#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/streams.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/port/temporaries.hpp"

namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

const Command kCommands[] = {
    {hivecal::cli::kCalibrateCommand,
     "estimate the geometry from tracker data; paper-style tables, result JSON, report", hivecal::cli::calibrate_main},
    {hivecal::cli::kReportCommand, "the HTML report of a calibration again, from its result.json",
     hivecal::cli::report_main},
    {hivecal::cli::kValidateCommand, "compare a calibration with a reference geometry (e.g. truth.json) on fresh poses",
     hivecal::cli::validate_main},
    {hivecal::cli::kPlanCommand, "choose and order the poses of a tracker session; joints CSV and URScript",
     hivecal::cli::plan_main},
    {hivecal::cli::kPredictCommand, "tool positions of joint poses from a calibration result",
     hivecal::cli::predict_main},
    {hivecal::cli::kExportCommand, "a calibration (or nominal arm) as URDF, ROS UR kinematics YAML or robot JSON",
     hivecal::cli::export_main},
    {hivecal::cli::kIso9283Command, "ISO 9283 pose accuracy AP and repeatability RP of measured reaches",
     hivecal::cli::iso9283_main},
    {hivecal::cli::kCheckRobotCommand, "what hivecal reads from a robot file: table, tools, limits, FK",
     hivecal::cli::check_robot_main},
    {hivecal::sim::kSimulateCommand, "simulated UR + tracker session: captures, CSV logs, ground truth, live ptys",
     hivecal::sim::simulate_main},
    {hivecal::streams::kRecordCommand, "record serial ports (or ptys) to capture files, nothing lost on SIGINT/SIGTERM",
     hivecal::streams::record_main},
    {hivecal::streams::kExtractCommand,
     "captures -> clock sync -> quasi-static paired samples (CSV) with drop statistics",
     hivecal::streams::extract_main},
    {hivecal::cli::kDemoCommand, "small simulated check of the core library", hivecal::cli::demo_main},
};

void print_usage(std::FILE* out) {
  std::fprintf(out, "usage: hivecal <command> [options]   (hivecal <command> --help for its options)\n\ncommands:\n");
  for (const Command& c : kCommands) std::fprintf(out, "  %-10s %s\n", c.name, c.summary);
  std::fprintf(out,
               "\nexit codes (every command, docs/cli.md): 0 ok, 1 computation failed,\n"
               "  2 bad command line or refused paths, 3 bad input, 4 output could not be written,\n"
               "  5 calibrated with warnings (result written; see the warnings on stderr)\n");
}

}  // namespace

int main(int argc, char** argv) {
  // A reader that went away (`hivecal predict --out - | head -1`) is an output error, exit 4
  // with a message: writes then fail with EPIPE, which every output checks, instead of the
  // process dying silently of SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  // Ctrl-C, SIGTERM or a hangup in the middle of a run leaves no temporary behind.
  hivecal::port::remove_temporaries_on_signals();
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    print_usage(argc < 2 ? stderr : stdout);
    if (argc < 2) return hivecal::cli::kExitUsage;
    return hivecal::cli::exit_with("help", hivecal::port::finish_stdout());
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    const int code = c.run(argc - 2, argv + 2);
    // What was printed on stdout must have arrived (e.g. not on a full device).
    const hivecal::port::Error flushed = hivecal::port::finish_stdout();
    if (code == hivecal::cli::kExitOk && !flushed.ok()) return hivecal::cli::exit_with(c.name, flushed);
    return code;
  }
  std::fprintf(stderr, "hivecal: unknown command '%s'\n\n", argv[1]);
  print_usage(stderr);
  return hivecal::cli::kExitUsage;
}
