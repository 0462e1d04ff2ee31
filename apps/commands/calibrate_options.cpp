// hivecal calibrate: its options and their checks (calibrate_parts.hpp).
#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "cli/options.hpp"
#include "hivecal/calibration.hpp"
#include "commands/commands.hpp"
#include "textio/robot_description.hpp"
#include "textio/text_util.hpp"
#include "commands/calibrate_parts.hpp"

namespace hivecal::cli {
namespace {

// --- parse ------------------------------------------------------------------------------------

/// --payload KG@X,Y,Z into *masses.
Error payload_option(const Options& options, ArmMasses* masses) {
  const std::string text = options.get("payload");
  const std::size_t at = text.find('@');
  const Error bad = Error::usage(
      "--payload must be KG@X,Y,Z: a mass in kg >= 0 and its centre in the flange frame "
      "in metres (e.g. 1.2@0,0,0.05), not " +
      port::quoted(text));
  double kg = 0.0;
  if (at == std::string::npos || !textio::parse_double(text.substr(0, at), &kg) || !(kg >= 0.0 && kg < 1e4)) return bad;
  Vec3 com_m = Vec3::Zero();
  if (!parse_vec3(std::string_view(text).substr(at + 1), &com_m)) return bad;
  if (!com_m.allFinite() || com_m.norm() > 10.0) return bad;
  masses->payload_kg = kg;
  masses->payload_com_m = com_m;
  return Error{};
}

/// --compliance, --gravity, --payload into settings->compliance_model (the default terms of the
/// start model's nominal geometry); refused: a kind other than basis|masses, masses for an arm
/// without published masses, a zero or non-finite gravity.
Error gravity_terms_from_options(const Options& options, CalibrateSettings* settings) {
  const std::string kind = options.get("compliance");
  if (kind != "basis" && kind != "masses") {
    return Error::usage("--compliance must be 'basis' or 'masses', not " + port::quoted(kind));
  }
  const ComplianceLoad load = kind == "masses" ? ComplianceLoad::arm_masses : ComplianceLoad::point;
  if (options.given("payload") && load != ComplianceLoad::arm_masses) {
    return Error::usage("--payload needs --compliance masses (the basis kind weighs unit masses, not the payload)");
  }
  Vec3 gravity = Vec3::Zero();
  if (!parse_vec3(options.get("gravity"), &gravity) || !gravity.allFinite() || !(gravity.norm() > 1e-9)) {
    return Error::usage(
        "--gravity must be X,Y,Z: the direction of gravity in the robot base frame, not zero (e.g. "
        "0,0,-1 for a floor mount, 0,0,1 for a ceiling mount), not " +
        port::quoted(options.get("gravity")));
  }
  ComplianceModel& model = settings->compliance_model;
  if (load == ComplianceLoad::arm_masses) {
    RobotType type = RobotType::ur5;
    if (robot_type_from_name(settings->robot.robot.c_str(), &type) != Status::ok ||
        nominal_arm_masses(type, &model.masses) != Status::ok) {
      return Error::usage(
          "--compliance masses needs the arm's link masses, which are known here for the built-in types (" +
          std::string(robot_type_names()) + ") only (by --robot-model's name); " + port::quoted(settings->robot.robot) +
          " has none: use --compliance basis");
    }
    if (options.given("payload")) {
      const Error payload = payload_option(options, &model.masses);
      if (!payload.ok()) return payload;
    }
  }
  if (default_compliance_terms(settings->robot.model, gravity, load, &model) != Status::ok) {
    return Error::usage("--compliance: no joint of " + port::quoted(settings->robot.robot) +
                        " has a horizontal axis at q = 0 under --gravity " + options.get("gravity") +
                        " (the shoulder and elbow carry the deflection): check --gravity");
  }
  return Error{};
}

/// --harmonics K: the joint-angle harmonics of orders 1 .. K of every joint appended to
/// settings->compliance_model; refused beyond the build's capacity for joint terms.
Error harmonic_terms_from_options(const Options& options, CalibrateSettings* settings) {
  std::size_t orders = 0;
  const Error error = count_option(options, "harmonics", 1, static_cast<std::size_t>(kMaxHarmonicOrder), &orders);
  if (!error.ok()) return error;
  ComplianceModel& model = settings->compliance_model;
  const RobotModel& arm = settings->robot.model;  // a harmonic per revolute joint
  const int needed = model.term_count + harmonic_term_count(arm, static_cast<int>(orders));
  if (append_harmonic_terms(static_cast<int>(orders), arm, &model) != Status::ok) {
    return Error::usage("--harmonics " + options.get("harmonics") + " needs " + std::to_string(needed) +
                        " joint terms with the others; this build holds " + std::to_string(kMaxComplianceTerms) +
                        " (HIVECAL_MAX_JOINT_TERMS): use fewer orders");
  }
  return Error{};
}

/// --compliance and --harmonics: the joint terms of the LM+compliance stage; refused with a
/// method without LM, and --gravity / --payload without the compliance they set.
Error compliance_from_options(const Options& options, CalibrateSettings* settings) {
  const bool gravity_terms = options.given("compliance");
  const bool harmonics = options.given("harmonics");
  settings->compliance = gravity_terms || harmonics;
  settings->compliance_model = ComplianceModel{};
  if (!gravity_terms) {
    for (const char* name : {"gravity", "payload"})
      if (options.given(name)) return Error::usage(std::string("--") + name + " needs --compliance (see --help)");
  }
  if (!settings->compliance) return Error{};
  if (settings->method == CalibrationMethod::abc || settings->method == CalibrationMethod::gsa) {
    return Error::usage(std::string(gravity_terms ? "--compliance" : "--harmonics") +
                        " needs a method with LM (abc+lm, gsa+lm, lm, all), not --method " +
                        calibration_method_name(settings->method));
  }
  if (gravity_terms) {
    const Error error = gravity_terms_from_options(options, settings);
    if (!error.ok()) return error;
  }
  return harmonics ? harmonic_terms_from_options(options, settings) : Error{};
}

/// --position-sigma-m, --angle-sigma-rad, --orientation-lever-m (csv.hpp, OrientationInput).
Error orientation_options(const Options& options, textio::OrientationInput* orientation) {
  if (options.given("position-sigma-m") && options.given("tracker-sigma-um")) {
    return Error::usage("--tracker-sigma-um and --position-sigma-m say the same: give one");
  }
  Error error = number_option(options, "position-sigma-m", &orientation->position_sigma_m);
  if (error.ok() && options.given("tracker-sigma-um")) {
    double sigma_um = 0.0;
    error = number_option(options, "tracker-sigma-um", &sigma_um);
    orientation->position_sigma_m = sigma_um * 1e-6;
    if (error.ok() && !(sigma_um > 0.0 && sigma_um < 1e6))
      return Error::usage("--tracker-sigma-um must be in (0, 1e6)");
  }
  if (error.ok()) error = number_option(options, "angle-sigma-rad", &orientation->angle_sigma_rad);
  if (error.ok() && options.given("orientation-lever-m"))
    error = number_option(options, "orientation-lever-m", &orientation->lever_m);
  if (!error.ok()) return error;
  if (!(orientation->position_sigma_m > 0.0 && orientation->position_sigma_m < 1.0) ||
      !(orientation->angle_sigma_rad > 0.0 && orientation->angle_sigma_rad < 1.0)) {
    return Error::usage("--position-sigma-m and --angle-sigma-rad must be in (0, 1)");
  }
  if (options.given("orientation-lever-m") && !(orientation->lever_m >= 0.0 && orientation->lever_m <= 1.0)) {
    return Error::usage("--orientation-lever-m must be in [0, 1] m");
  }
  const std::string form = options.get("orientation-form");
  if (form == "euler-xyz") {
    orientation->form = textio::OrientationForm::euler_xyz;
  } else if (form != "rotation-vector") {
    return Error::usage("--orientation-form must be rotation-vector or euler-xyz, not " + port::quoted(form));
  }
  return Error{};
}

/// --joint-sigma-rad or --joint-sigma-deg (not both), in [0, 1) rad.
Error joint_sigma_option(const Options& options, double* sigma_rad) {
  const bool in_degrees = options.given("joint-sigma-deg");
  if (in_degrees && options.given("joint-sigma-rad"))
    return Error::usage("give --joint-sigma-rad or --joint-sigma-deg, not both");
  const Error error = number_option(options, in_degrees ? "joint-sigma-deg" : "joint-sigma-rad", sigma_rad);
  if (!error.ok()) return error;
  if (in_degrees) *sigma_rad *= math::kRadPerDeg;
  if (!(*sigma_rad >= 0.0 && *sigma_rad < 1.0)) return Error::usage("--joint-sigma-rad must be in [0, 1) rad");
  return Error{};
}

}  // namespace

const std::vector<OptionSpec>& calibrate_option_specs() {
  static const std::vector<OptionSpec> specs = [] {
    std::vector<OptionSpec> list = {
        {"robot", "FILE|BAG",
         "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
        {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
        {"joint-names", "N1,..,N6",
         "joint names in ROS logs (rostopic, bag), joints 1..6 in order (default: the UR drivers')", ""},
        {"samples", "FILE",
         "paired static samples q1..q6,x,y,z[,rx,ry,rz] (CSV; '-': stdin) instead of --robot/--tracker", ""},
        {"ur-calibration", "FILE", "UR calibration.conf: start from the controller's calibration", ""},
        {"robot-model", "NAME|FILE",
         std::string("nominal geometry: ") + robot_type_names() +
             ", or a robot description .json (standard or modified DH; a result file works)",
         "ur5"},
        {"tool", "X,Y,Z",
         "nominal retroreflector centre in the flange frame [m] (LM refines it; default: the description file's)",
         "0,0,0.1695"},
        {"params", "full|paper",
         "full identifiable model, or the link lengths (every non-zero d and a; for UR the paper's six)", "full"},
        {"method", "abc+lm|gsa+lm|lm|abc|gsa|all", "solver; 'all' runs GSA, ABC and LM (Table 1)", "abc+lm"},
        {"population-subset", "N",
         "hybrids (abc+lm, gsa+lm): ABC/GSA search on N training samples spread over the poses (farthest-point in "
         "joint space), LM refines on all; 0: every sample. --method abc, gsa and all always search on every sample",
         std::to_string(kDefaultPopulationSubset)},
        {"robust", "", "Huber loss in LM (a few bad tracker points do not drag the fit)", ""},
        {"seed", "N", "seed of the train/test split and of ABC/GSA", "1"},
        {"split", "FRACTION", "share of samples used for training (1: all, no test rows)", "0.7"},
        {"cv", "K|loo", "also cross-validate: K folds (or leave-one-out), held-out MAE per fold", ""},
        {"keep-outliers", "", "use every sample (no blunder search)", ""},
        {"controller-tcp", "",
         "the points are the controller's own TCP readings (a pendant export, RTDE actual_TCP_pose): in the base "
         "frame, at the TCP offset --tool; neither is fitted, joint 1's parameters are estimated instead (LM only; "
         "implies --method lm); the same as --frames controller",
         ""},
        {"frames", "auto|fitted|controller",
         "the base -> tracker transform and the tool points: 'fitted' as for a tracker; 'controller' as "
         "--controller-tcp; 'auto' fits them and, when the fitted base is within 10 mm and 10 mrad of the identity, "
         "fits again with the controller's (the identity, --tool; LM only) and keeps that fit when its residual is "
         "within what the measurement noise explains (chi-square at 0.1 %; --tracker-sigma-um with the joints' "
         "reading noise). Not given with a --method other than lm: fitted ('all' is always fitted)",
         "auto"},
        {"significance", "T|auto",
         "LM fixes parameters whose change is below T sigma (0: off; auto: chosen by leaving one pose out at a time, "
         "up to " +
             std::to_string(kAutoSignificanceMaxSamples) +
             " training samples). Not given: " + textio::format_double(kDefaultSignificance) +
             " sigma, the geometry tested on small sets only (fewer training poses than " +
             textio::format_double(kSignificancePosesPerParam) +
             " per estimated parameter); a given T tests it on any set",
         ""},
        {"out", "FILE", "calibration result (robot-calibration/1 JSON; '-': stdout)", "result.json"},
        {"ur-deltas", "FILE", "also write the model as UR calibration.conf [mounting] deltas", ""},
        {"report", "DIR", "write an HTML report with figures into DIR", ""},
        {"max-change-mm", "X", "warn (exit 5) when a length moves more than this from the start geometry [mm]", "20"},
        {"max-change-deg", "X", "warn (exit 5) when an angle moves more than this from the start geometry [deg]", "2"},
        {"compliance", "basis|masses",
         "also fit the joints' gravity deflection (LM+compliance stage, docs/compliance.md): the generic gravity "
         "basis, or the link masses (UR5, UR10, UR3e, UR5e)",
         "", "basis"},
        {"harmonics", "K",
         "also fit harmonics of orders 1 .. K of each joint's reading (encoder eccentricity, transmission error; "
         "LM+compliance stage, docs/compliance.md), each kept only when significant",
         ""},
        {"gravity", "X,Y,Z", "with --compliance: gravity direction in the robot base frame (wall or ceiling mounts)",
         "0,0,-1"},
        {"payload", "KG@X,Y,Z", "with --compliance masses: payload mass [kg] and its centre in the flange frame [m]",
         ""},
        {"quiet", "", "no progress on stderr", ""},
        {"profile", "",
         "print on stderr where the wall time went: reading the input, the job's screen, baseline, stages and "
         "w-tests, cross-validation, tables and outputs",
         ""},
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
  }();
  return specs;
}

Error calibrate_settings_from_options(const Options& options, CalibrateSettings* settings) {
  bool from_file = false;
  Error error = robot_model_option(options, "robot-model", &settings->robot, &from_file);
  if (error.ok() && from_file && !options.given("tool")) settings->tool_m = settings->robot.model.tool_m;
  if (error.ok() && (!from_file || options.given("tool"))) error = vec3_option(options, "tool", &settings->tool_m);
  if (!error.ok()) return error;
  const std::string params = options.get("params");
  if (params != "full" && params != "paper")
    return Error::usage("--params must be 'full' or 'paper', not " + port::quoted(params));
  settings->paper_params = params == "paper";
  if (calibration_method_from_name(options.get("method").c_str(), &settings->method) != Status::ok) {
    return Error::usage(std::string("--method must be one of ") + calibration_method_names() + "; not " +
                        port::quoted(options.get("method")));
  }
  Error seeded = seed_option(options, "seed", &settings->seed);
  if (seeded.ok()) {
    seeded = count_option(options, "population-subset", 0, kMaxPopulationSubset, &settings->population_subset);
  }
  if (!seeded.ok()) return seeded;
  if (!textio::parse_double(options.get("split"), &settings->train_fraction) ||
      !(settings->train_fraction > 0.0 && settings->train_fraction <= 1.0)) {
    return Error::usage("--split must be a fraction in (0, 1], not " + port::quoted(options.get("split")));
  }
  const std::string cv = options.get("cv");
  double folds = 0.0;
  if (cv == "loo") {
    settings->cv_folds = 1;
  } else if (!cv.empty()) {
    if (!textio::parse_double(cv, &folds) || folds < 2.0 || folds > static_cast<double>(kMaxCrossValidationFolds) ||
        folds != static_cast<double>(static_cast<std::size_t>(folds))) {
      return Error::usage("--cv must be 'loo' or a number of folds in [2, " + std::to_string(kMaxCrossValidationFolds) +
                          "], not " + port::quoted(cv));
    }
    settings->cv_folds = static_cast<std::size_t>(folds);
  }
  settings->keep_outliers = options.given("keep-outliers");
  const std::string frames = options.given("frames") ? options.get("frames") : "auto";
  if (frames != "auto" && frames != "fitted" && frames != "controller") {
    return Error::usage("--frames must be auto, fitted or controller, not " + port::quoted(frames));
  }
  settings->controller_tcp = options.given("controller-tcp") || frames == "controller";
  // Not given: auto unless a population method was asked for (it fits its own base).
  const bool population_asked = options.given("method") && settings->method != CalibrationMethod::lm;
  settings->detect_controller_frames = frames == "auto" && (options.given("frames") || !population_asked);
  if (settings->controller_tcp && options.given("controller-tcp") && options.given("frames") &&
      frames != "controller") {
    return Error::usage("--controller-tcp and --frames " + frames + " contradict each other");
  }
  if (settings->controller_tcp) {
    if (options.given("method") && settings->method != CalibrationMethod::lm) {
      return Error::usage("--controller-tcp works with --method lm only (ABC and GSA fit their own base), not " +
                          port::quoted(options.get("method")));
    }
    settings->method = CalibrationMethod::lm;
  }
  if (options.get("significance") == "auto") {
    settings->significance_t = -1.0;  // lib: chosen by leaving one pose out at a time on small sets
  } else if (options.given("significance")) {
    if (!textio::parse_double(options.get("significance"), &settings->significance_t) ||
        !(settings->significance_t >= 0.0 && settings->significance_t <= 10.0)) {
      return Error::usage("--significance must be 'auto' or a number in [0, 10]");
    }
    settings->significance_every_set = true;
  }
  const bool samples = !options.get("samples").empty();
  const bool streams = !options.get("robot").empty() || !options.get("tracker").empty();
  if (samples == streams) return Error::usage("give either --samples, or --robot and --tracker (see --help)");
  if (streams && (options.get("robot").empty() || options.get("tracker").empty())) {
    return Error::usage("--robot and --tracker go together");
  }
  error = input_units_option(options, &settings->units);
  if (!error.ok()) return error;
  double max_mm = 0.0;
  double max_deg = 0.0;
  error = number_option(options, "max-change-mm", &max_mm);
  if (error.ok()) error = number_option(options, "max-change-deg", &max_deg);
  if (!error.ok()) return error;
  if (!(max_mm > 0.0 && max_mm < 1e9) || !(max_deg > 0.0 && max_deg <= 360.0)) {
    return Error::usage("--max-change-mm must be positive and --max-change-deg in (0, 360]");
  }
  settings->bounds.max_length_change_m = max_mm * 1e-3;
  settings->bounds.max_angle_change_rad = max_deg * math::kRadPerDeg;
  settings->robust = options.given("robust");
  settings->progress = progress_enabled(options);
  settings->profile = options.given("profile");
  const Error compliance = compliance_from_options(options, settings);
  if (!compliance.ok()) return compliance;
  error = orientation_options(options, &settings->orientation);
  if (error.ok()) error = joint_sigma_option(options, &settings->joint_sigma_rad);
  return error;
}

}  // namespace hivecal::cli
