// The reader options of the commands that read measured samples (sample_reader.hpp).
#include "commands/sample_reader.hpp"

#include "hivecal/core/math.hpp"
#include "textio/text_util.hpp"

namespace hivecal::cli {
namespace {

/// --position-sigma-m, --angle-sigma-rad, --orientation-lever-m (csv.hpp, OrientationInput).
Error orientation_options(const Options& options, textio::OrientationInput* orientation) {
  if (options.given("position-sigma-m") && options.given("tracker-sigma-um")) {
    return Error::usage("--tracker-sigma-um and --position-sigma-m say the same: give one");
  }
  Error error = ranged_option(options, "position-sigma-m", NumberRange{0.0, 1.0, true, true, "m"},
                              &orientation->position_sigma_m);
  if (error.ok() && options.given("tracker-sigma-um")) {
    double sigma_um = 0.0;
    error = ranged_option(options, "tracker-sigma-um", NumberRange{0.0, 1e6, true, true, "um"}, &sigma_um);
    orientation->position_sigma_m = sigma_um * 1e-6;
  }
  if (error.ok()) {
    error = ranged_option(options, "angle-sigma-rad", NumberRange{0.0, 1.0, true, true, "rad"},
                          &orientation->angle_sigma_rad);
  }
  if (error.ok() && options.given("orientation-lever-m")) {
    error =
        ranged_option(options, "orientation-lever-m", NumberRange{0.0, 1.0, false, false, "m"}, &orientation->lever_m);
  }
  if (!error.ok()) return error;
  const std::string form = options.get("orientation-form");
  if (form == "euler-xyz") {
    orientation->form = textio::OrientationForm::euler_xyz;
  } else if (form != "rotation-vector") {
    return Error::usage("--orientation-form must be rotation-vector or euler-xyz, not " + port::quoted(form));
  }
  return Error{};
}

/// --joint-sigma-rad or --joint-sigma-deg (not both), below 1 rad.
Error joint_sigma_option(const Options& options, double* sigma_rad) {
  const bool in_degrees = options.given("joint-sigma-deg");
  if (in_degrees && options.given("joint-sigma-rad"))
    return Error::usage("give --joint-sigma-rad or --joint-sigma-deg, not both");
  constexpr double kMaxJointSigma_rad = 1.0;
  if (!in_degrees)
    return ranged_option(options, "joint-sigma-rad", NumberRange{0.0, kMaxJointSigma_rad, false, true, "rad"},
                         sigma_rad);
  const Error error =
      ranged_option(options, "joint-sigma-deg",
                    NumberRange{0.0, kMaxJointSigma_rad * math::kDegPerRad, false, true, "deg"}, sigma_rad);
  *sigma_rad *= math::kRadPerDeg;
  return error;
}

}  // namespace

std::vector<OptionSpec> sample_reader_option_specs() {
  std::vector<OptionSpec> list = {
      {"tracker-sigma-um", "S",
       "stated noise of the tracker per axis: the blunder test's sigma when the fit leaves too little redundancy, "
       "and the report's measurement noise (the same as --position-sigma-m) [um]",
       "10"},
      {"position-sigma-m", "S",
       "stated noise of the measured positions; with --angle-sigma-rad it weighs a measured orientation (rx, ry, rz "
       "columns of --samples) [m]",
       "1e-05"},
      {"angle-sigma-rad", "S", "stated noise of the measured orientations rx, ry, rz [rad]", "0.001"},
      {"joint-sigma-rad", "S",
       "noise of the joint readings, in the units of --position-sigma-m (e.g. the readings' rounding step): LM "
       "weighs each sample by its point covariance (errors in variables, docs/robust.md; 0: off), and a measured "
       "orientation's lever takes it in [rad]",
       "0"},
      {"joint-sigma-deg", "S", "--joint-sigma-rad in degrees (a UR pendant export's rounding: 0.01) [deg]", ""},
      {"orientation-form", "rotation-vector|euler-xyz",
       "what rx, ry, rz are: the tool frame's rotation vector, or intrinsic X-Y-Z Euler angles (R = Rx(rx) Ry(ry) "
       "Rz(rz), e.g. a Leica T-Mac export)",
       "rotation-vector"},
      {"orientation-lever-m", "L",
       "a measured orientation adds two points at this lever along the tool frame's x and y axes (targets 2, 3; 0: "
       "rx, ry, rz not used) [m] (default: from the noise: position and angle sigma, and the joints' (--joint-sigma-"
       "rad, else their written resolution) through the arm)",
       ""},
  };
  for (const OptionSpec& spec : input_unit_option_specs()) list.push_back(spec);
  return list;
}

Error sample_reader_settings_from_options(const Options& options, SampleReaderSettings* settings) {
  Error error = input_units_option(options, &settings->units);
  if (error.ok()) error = orientation_options(options, &settings->orientation);
  if (error.ok()) error = joint_sigma_option(options, &settings->joint_sigma_rad);
  return error;
}

streams::SessionConfig sample_session_config(const SampleReaderSettings& settings, const RobotModel& arm) {
  streams::SessionConfig config;
  config.speed_model = arm;
  config.log_options.units = settings.units;
  config.log_options.units.joints = textio::input_joints(arm);  // q1..qN of the arm's N joints
  config.orientation = settings.orientation;
  config.orientation.joint_sigma_rad = settings.joint_sigma_rad;  // 0: the joint columns' written resolution
  return config;
}

}  // namespace hivecal::cli
