#include "commands/simulate.hpp"

#include <signal.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/output_files.hpp"
#include "hivecal/port/pty.hpp"
#include "sim/sim_model.hpp"
#include "sim/sim_outputs.hpp"
#include "sim/sim_server.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::sim {
namespace {

using port::Error;

std::atomic<bool> g_stop{false};
void request_stop(int) {
  g_stop = true;
}

const std::vector<cli::OptionSpec>& option_specs() {
  static const std::vector<cli::OptionSpec> specs = {
      {"out-dir", "DIR", "where robot.cap, tracker.cap, the CSV logs and the truth go", "."},
      {"robot-model", "NAME|FILE", std::string(robot_type_names()) + ", or a robot description .json (docs/formats.md)",
       "ur5"},
      {"seed", "N", "seed of every random choice", "1"},
      {"waypoints", "N", "waypoints visited", "38"},
      {"duration-s", "S", "session length [s]", "600"},
      {"drift-ppm", "X", "tracker clock rate error: t_robot = offset + (1 + drift) t_tracker [ppm]", "40"},
      {"robot-clock-start-us", "T", "robot clock at the start of the session [us]", "1000000000"},
      {"tracker-clock-start-us", "T", "tracker clock at the start of the session [us]", "5000000"},
      {"noise-um", "X", "tracker noise per axis, 1 sigma [um]", "10"},
      {"jitter-us", "X", "robot period jitter, 1 sigma [us]", "400"},
      {"errors", "paper|large", "geometry errors: paper-like (tens of um/urad) or the large ones (0.3 mm/mrad)",
       "paper"},
      {"length-sigma-um", "X", "sigma of the true d and a errors [um] (default: from --errors)", ""},
      {"angle-sigma-urad", "X", "sigma of the true theta and alpha errors [urad] (default: from --errors)", ""},
      {"tool-sigma-um", "X", "sigma of the true tool's error per axis [um] (default: from --errors)", ""},
      {"compliance-urad", "J2,J3", "joint 2 and 3 gravity deflection [urad] (default: from --errors)", ""},
      {"harmonic-urad", "J,K,S,C",
       "joint J (1 .. the arm's joint count) turns by S sin(K q) + C cos(K q) [urad] more than it reads: an eccentric "
       "encoder (K = 1) or "
       "a gear's transmission error",
       ""},
      {"calibration-conf", "FILE", "true geometry = nominal + the [mounting] deltas of this UR calibration.conf", ""},
      {"force", "", "replace the files of an earlier session in --out-dir (never done without it)", ""},
      {"serve", "", "serve the streams live on two pseudo-terminals instead of writing captures", ""},
      {"speed", "X", "with --serve: session seconds per second (0: as fast as read)", "1"},
      {"serve-delay-s", "S", "with --serve: wait before streaming, to start a reader", "3"},
  };
  return specs;
}

/// Largest simulated joint deflection (compliance, harmonics) [urad].
constexpr double kMaxDeflection_urad = 1e4;
/// Largest sigma of the geometry's simulated errors [um or urad].
constexpr double kMaxErrorSigma = 1e5;

/// --harmonic-urad J,K,S,C into config's harmonic_*: the joint and the order whole numbers, the
/// amplitudes within +-kMaxDeflection_urad (cli::check_numbers), the joint one of the arm's
/// `joint_count` (config->nominal's, read before).
Error harmonic_option(const std::string& text, sim::SimConfig* config) {
  const int joint_count = config->nominal.joint_count;
  const cli::NumberRange amplitude{-kMaxDeflection_urad, kMaxDeflection_urad, false, false, "urad"};
  double v[4] = {};
  const Error error =
      cli::check_numbers("--harmonic-urad", text, "joint, order, sine and cosine amplitudes, e.g. 3,1,60,50",
                         {{"J", cli::NumberRange{1.0, static_cast<double>(joint_count)}},
                          {"K", cli::NumberRange{1.0, 3.0}},
                          {"S", amplitude},
                          {"C", amplitude}},
                         v);
  if (!error.ok()) return error;
  if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1])) {
    return Error::usage("--harmonic-urad J,K,S,C: the joint J and the order K are whole numbers, got " +
                        port::quoted(text));
  }
  config->harmonic_joint = static_cast<int>(v[0]) - 1;
  config->harmonic_order = static_cast<int>(v[1]);
  config->harmonic_sin_rad = v[2] * 1e-6;
  config->harmonic_cos_rad = v[3] * 1e-6;
  return Error{};
}

/// Largest session simulate writes: waypoints and seconds.
constexpr std::size_t kMaxWaypoints = 2000;
constexpr double kMaxDuration_s = 3600.0;

/// Builds the session configuration.
Error configure(const cli::Options& options, SimConfig* config) {
  textio::RobotDescription robot;
  bool from_file = false;
  Error error = cli::robot_model_option(options, "robot-model", &robot, &from_file);
  if (!error.ok()) return error;
  if (from_file) config->nominal_tool_m = robot.model.tool_m;
  config->robot_name = robot.robot;
  config->nominal = robot.model;
  config->convention = robot.convention;
  config->modified_base = robot.modified_base;
  // Each bounded, with its name in the message: the generator's size is bounded too (an hour
  // of session at most: ~0.5 GB of captures, logs and truth), and a NaN is never a value.
  double drift_ppm = 0, robot_start = 0, tracker_start = 0, noise_um = 0, jitter_us = 0;
  std::size_t waypoints = 0;
  error = cli::seed_option(options, "seed", &config->seed);
  if (error.ok()) error = cli::count_option(options, "waypoints", 2, kMaxWaypoints, &waypoints);
  if (error.ok()) error = cli::bounded_option(options, "duration-s", 1e-3, kMaxDuration_s, &config->duration_s);
  if (error.ok()) error = cli::bounded_option(options, "drift-ppm", -1000.0, 1000.0, &drift_ppm);
  if (error.ok()) error = cli::bounded_option(options, "robot-clock-start-us", 0.0, 9.0e15, &robot_start);
  if (error.ok()) error = cli::bounded_option(options, "tracker-clock-start-us", 0.0, 9.0e15, &tracker_start);
  if (error.ok()) error = cli::bounded_option(options, "noise-um", 0.0, 1e6, &noise_um);
  if (error.ok()) error = cli::bounded_option(options, "jitter-us", 0.0, 1e6, &jitter_us);
  if (!error.ok()) return error;
  config->waypoint_count = static_cast<int>(waypoints);
  config->clock_drift = drift_ppm * 1e-6;
  config->robot_clock_start_us = static_cast<std::uint64_t>(robot_start);
  config->tracker_clock_start_us = static_cast<std::uint64_t>(tracker_start);
  config->tracker_noise_m = noise_um * 1e-6;
  config->robot_jitter_s = jitter_us * 1e-6;
  if (options.get("errors") == "large") {
    use_large_errors(config);
  } else if (options.get("errors") != "paper") {
    return Error::usage("--errors must be paper or large, not '" + options.get("errors") + "'");
  }
  // The geometry's error sigmas up to 0.1 m / 0.1 rad, the deflections up to 10 mrad: far
  // beyond any arm, still a session the pipeline can take.
  for (auto [name, target, scale] : {std::tuple{"length-sigma-um", &config->length_sigma_m, 1e-6},
                                     std::tuple{"angle-sigma-urad", &config->angle_sigma_rad, 1e-6},
                                     std::tuple{"tool-sigma-um", &config->tool_sigma_m, 1e-6}}) {
    if (!options.given(name)) continue;
    double value = 0.0;
    error = cli::bounded_option(options, name, 0.0, kMaxErrorSigma, &value);
    if (!error.ok()) return error;
    *target = value * scale;
  }
  if (options.given("compliance-urad")) {
    const cli::NumberRange deflection{-kMaxDeflection_urad, kMaxDeflection_urad, false, false, "urad"};
    double j_urad[2] = {};
    error = cli::check_numbers("--compliance-urad", options.get("compliance-urad"),
                               "joints 2 and 3's gravity deflection, e.g. 40,20",
                               {{"J2", deflection}, {"J3", deflection}}, j_urad);
    if (!error.ok()) return error;
    config->compliance_j2_rad = j_urad[0] * 1e-6;
    config->compliance_j3_rad = j_urad[1] * 1e-6;
  }
  if (options.given("harmonic-urad")) {
    const Error harmonic = harmonic_option(options.get("harmonic-urad"), config);
    if (!harmonic.ok()) return harmonic;
  }
  if (!options.get("calibration-conf").empty()) {
    const port::Error read = textio::read_ur_calibration_conf(options.get("calibration-conf"), &config->deltas);
    if (!read.ok()) {
      return Error::input(read.message);
    }
    config->use_deltas = true;
  }
  return Error{};
}

/// Refuses to overwrite the captures, logs or truth of an earlier session (they may be a real
/// recording's) unless --force: the same rule as `record`.
Error check_not_overwriting(const cli::Options& options) {
  if (options.given("force")) return Error{};
  const std::string folder = options.get("out-dir");
  std::string found;
  for (const std::string& name : output_names(!options.given("serve"))) {
    if (!port::identify(folder + "/" + name).exists) continue;
    found += (found.empty() ? "" : ", ") + name;
  }
  if (found.empty()) return Error{};
  return Error::output("--out-dir " + port::quoted(folder, 200) + " already holds " + found +
                       "; refusing to overwrite a session (--force replaces it)");
}

/// How a live session is paced: --speed (0, or within [kMinServeSpeed, kMaxServeSpeed]) and
/// --serve-delay-s; read before anything is written, so a bad value leaves nothing behind.
struct Pacing {
  double speed = 1.0;    ///< session seconds per second; 0: as fast as read
  double delay_s = 0.0;  ///< wait before streaming [s]
};

Error pacing_options(const cli::Options& options, Pacing* pacing) {
  Error error = cli::number_option(options, "speed", &pacing->speed);
  if (error.ok() && !(pacing->speed == 0.0 || (pacing->speed >= kMinServeSpeed && pacing->speed <= kMaxServeSpeed))) {
    char range[120];
    std::snprintf(range, sizeof range,
                  "--speed must be 0 (as fast as read) or within [%g, %g] session seconds per second", kMinServeSpeed,
                  kMaxServeSpeed);
    error = Error::usage(std::string(range) + ", got " + port::quoted(options.get("speed")));
  }
  if (error.ok()) error = cli::bounded_option(options, "serve-delay-s", 0.0, kMaxServeDelay_s, &pacing->delay_s);
  return error;
}

/// Serves the session on two ptys, printing their paths first.
Error serve(const Session& session, const Pacing& pacing) {
  port::PtyPair robot;
  port::PtyPair tracker;
  Error error = port::open_pty(&robot);
  if (error.ok()) error = port::open_pty(&tracker);
  if (!error.ok()) return error;
  std::printf("robot   %s\ntracker %s\n", robot.slave_path.c_str(), tracker.slave_path.c_str());
  std::fflush(stdout);
  // SIGINT, SIGTERM and SIGHUP end the session cleanly (stats printed), even when a reader
  // left and the writes wait for room that never comes (write_all polls the stop request).
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
  (void)port::sleep_ms(static_cast<std::int64_t>(pacing.delay_s * 1000.0), g_stop);
  ServeStats stats;
  error = serve_session(session, robot, tracker, ServeOptions{pacing.speed}, &g_stop, &stats);
  (void)port::sleep_ms(500, g_stop);  // let readers drain the ptys before the hangup
  port::close_pty(&robot);
  port::close_pty(&tracker);
  std::printf("served %llu robot frames (%llu bytes), %llu tracker frames (%llu bytes)\n",
              static_cast<unsigned long long>(stats.robot_frames), static_cast<unsigned long long>(stats.robot_bytes),
              static_cast<unsigned long long>(stats.tracker_frames),
              static_cast<unsigned long long>(stats.tracker_bytes));
  return error;
}

}  // namespace

int simulate_main(int argc, char** argv) {
  cli::Options options;
  const int parsed =
      cli::parse_options(kSimulateCommand,
                         "Simulates a UR arm visiting waypoints, seen by its joint-state publisher (125 Hz) and a\n"
                         "laser tracker (10 Hz) on their own clocks. Writes robot.cap and tracker.cap (wire format),\n"
                         "robot_joints.csv and tracker.csv (io-formats), truth.json (true model, base->tracker,\n"
                         "clocks: robot-calibration/1 + \"simulation\") and truth_samples.csv (ideal static pairs);\n"
                         "or, with --serve, streams live on two pseudo-terminals (truth files still written).",
                         option_specs(), argc, argv, &options);
  if (parsed >= 0) return parsed;
  SimConfig config;
  Pacing pacing;
  Error error = configure(options, &config);
  if (error.ok()) error = pacing_options(options, &pacing);
  if (!error.ok()) return cli::exit_with(kSimulateCommand, error);
  port::OutputSet outputs;
  std::size_t folder = 0;
  error = declare_inputs(options, {"out-dir"}, &outputs);
  if (error.ok())
    error = outputs.add_folder(options.get("out-dir"), "--out-dir", output_names(!options.given("serve")), &folder);
  if (error.ok()) error = check_not_overwriting(options);
  if (!error.ok()) return cli::exit_with(kSimulateCommand, error);
  const Session session(config);
  // With --serve, `hivecal record` makes the captures from the ptys.
  error = stage_outputs(session, !options.given("serve"), kTruthSampleMarginS, &outputs, folder);
  if (error.ok()) error = outputs.commit();
  if (!error.ok()) return cli::exit_with(kSimulateCommand, error);
  return cli::exit_with(kSimulateCommand, options.given("serve") ? serve(session, pacing) : Error{});
}

}  // namespace hivecal::sim
