// hivecal calibrate: its options and their checks (calibrate_parts.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hivecal/core/math.hpp"
#include "cli/options.hpp"
#include "hivecal/calibration.hpp"
#include "commands/commands.hpp"
#include "textio/robot_description.hpp"
#include "textio/text_util.hpp"
#include "textio/transform_text.hpp"
#include "commands/calibrate_parts.hpp"

namespace hivecal::cli {
namespace {

// --- parse ------------------------------------------------------------------------------------

/// --payload KG@X,Y,Z into *masses.
Error payload_option(const Options& options, ArmMasses* masses) {
  const std::string text = options.get("payload");
  const std::size_t at = text.find('@');
  if (at == std::string::npos) {
    return Error::usage(
        "--payload must be KG@X,Y,Z: a mass in kg and its centre in the flange frame in metres (e.g. "
        "1.2@0,0,0.05), got " +
        port::quoted(text));
  }
  double kg = 0.0;
  Vec3 com_m = Vec3::Zero();
  Error error = check_number("--payload must be KG@X,Y,Z: its mass KG", std::string_view(text).substr(0, at),
                             NumberRange{0.0, 1e4, false, true, "kg"}, &kg);
  if (error.ok()) {
    error =
        check_vec3("--payload must be KG@X,Y,Z: its centre", std::string_view(text).substr(at + 1),
                   "in the flange frame", NumberRange{-kMaxToolOption_m, kMaxToolOption_m, false, false, "m"}, &com_m);
  }
  if (!error.ok()) return error;
  masses->payload_kg = kg;
  masses->payload_com_m = com_m;
  return Error{};
}

/// Largest component of --gravity (a direction of any length) [-].
constexpr double kMaxGravityComponent = 1e6;

/// The built-in types whose published link masses --compliance masses weighs (nominal_arm_masses),
/// for --help and the refusal alike: "ur3, ur5, ...".
std::string types_with_masses() {
  const std::string all = robot_type_names();
  std::string names;
  for (std::size_t begin = 0; begin < all.size();) {
    const std::size_t end = std::min(all.find(',', begin), all.size());
    const std::string name(textio::trim(std::string_view(all).substr(begin, end - begin)));
    begin = end + 1;
    RobotType type = RobotType::ur5;
    ArmMasses masses;
    if (robot_type_from_name(name.c_str(), &type) == Status::ok && nominal_arm_masses(type, &masses) == Status::ok) {
      names += (names.empty() ? "" : ", ") + name;
    }
  }
  return names;
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
  const Error direction =
      check_vec3("--gravity", options.get("gravity"), "(the direction of gravity in the robot base frame, any length)",
                 NumberRange{-kMaxGravityComponent, kMaxGravityComponent}, &gravity);
  if (!direction.ok()) return direction;
  if (!(gravity.norm() > 1e-9)) {
    return Error::usage(
        "--gravity must be X,Y,Z: the direction of gravity in the robot base frame, not zero (e.g. "
        "0,0,-1 for a floor mount, 0,0,1 for a ceiling mount), got " +
        port::quoted(options.get("gravity")));
  }
  ComplianceModel& model = settings->compliance_model;
  if (load == ComplianceLoad::arm_masses) {
    RobotType type = RobotType::ur5;
    if (robot_type_from_name(settings->robot.robot.c_str(), &type) != Status::ok ||
        nominal_arm_masses(type, &model.masses) != Status::ok) {
      return Error::usage(
          "--compliance masses needs the arm's link masses, which are known here for the built-in types (" +
          types_with_masses() + ") only (by --robot-model's name); " + port::quoted(settings->robot.robot) +
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

/// --prior nominal|off and the tolerances of the start model it holds (--dh-tolerance-mm,
/// --dh-tolerance-mrad, --tool-tolerance-mm), each positive and below 1 m / 1 rad.
Error prior_options(const Options& options, LmPriorTolerances* prior) {
  const std::string kind = options.get("prior");
  if (kind != "nominal" && kind != "off") {
    return Error::usage("--prior must be 'nominal' or 'off', not " + port::quoted(kind));
  }
  const char* const names[] = {"dh-tolerance-mm", "dh-tolerance-mrad", "tool-tolerance-mm"};
  double* const values[] = {&prior->dh_length_m, &prior->dh_angle_rad, &prior->tool_m};
  for (int k = 0; k < 3; ++k) {
    if (kind == "off" && options.given(names[k])) {
      return Error::usage(std::string("--") + names[k] + " goes with the prior: not with --prior off");
    }
    double value = 0.0;
    const Error error =
        ranged_option(options, names[k], NumberRange{0.0, 1000.0, true, true, k == 1 ? "mrad" : "mm"}, &value);
    if (!error.ok()) return error;
    *values[k] = kind == "off" ? 0.0 : value * 1e-3;
  }
  return Error{};
}

}  // namespace

const std::vector<OptionSpec>& calibrate_option_specs() {
  static const std::vector<OptionSpec> specs = [] {
    std::vector<OptionSpec> list = {
        {"robot", "FILE|BAG",
         "robot joints: serial capture, hivecal CSV, UR RTDE or rostopic log, ROS 2 bag (by content)", ""},
        {"tracker", "FILE", "tracker points: serial capture, hivecal CSV or tracker export (by content)", ""},
        {"joint-names", "N1,..,NN",
         "joint names in ROS logs (rostopic, bag), the arm's joints 1..N in order (default: a UR's the UR "
         "drivers', another arm's the message's own order)",
         ""},
        {"samples", "FILE",
         "paired static samples q1..qN,x,y,z[,rx,ry,rz] (CSV; '-': stdin) instead of --robot/--tracker", ""},
        {"ur-calibration", "FILE", "UR calibration.conf: start from the controller's calibration", ""},
        {"robot-model", "NAME|FILE",
         std::string("nominal geometry: ") + robot_type_names() +
             ", or a robot description .json (standard or modified DH; a result file works)",
         "ur5"},
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
        {"fit", "base|frames",
         "register, not calibrate: fit only the base -> tracker transform (and with 'frames' every target's tool "
         "point) of --robot-model RESULT.json to the inputs, keeping its arm and model terms; every pose registers "
         "unless --split is given (docs/cli.md)",
         ""},
        {"out", "FILE", "calibration result (robot-calibration/1 JSON; '-': stdout)", "result.json"},
        {"ur-deltas", "FILE", "also write the model as UR calibration.conf [mounting] deltas", ""},
        {"report", "DIR", "write an HTML report with figures into DIR", ""},
        {"max-change-mm", "X", "warn (exit 5) when a length moves more than this from the start geometry [mm]", "20"},
        {"max-change-deg", "X", "warn (exit 5) when an angle moves more than this from the start geometry [deg]", "2"},
        {"compliance", "basis|masses",
         "also fit the joints' gravity deflection (LM+compliance stage, docs/compliance.md): the generic gravity "
         "basis, or the link masses (" +
             types_with_masses() + ")",
         "", "basis"},
        {"harmonics", "K",
         "also fit harmonics of orders 1 .. K of each joint's reading (encoder eccentricity, transmission error; "
         "LM+compliance stage, docs/compliance.md), each kept only when significant",
         ""},
        {"gravity", "X,Y,Z", "with --compliance: gravity direction in the robot base frame (wall or ceiling mounts)",
         "0,0,-1"},
        {"payload", "KG@X,Y,Z", "with --compliance masses: payload mass [kg] and its centre in the flange frame [m]",
         ""},
        {"prior", "nominal|off",
         "LM holds the start model (its DH and the --tool point) as a prior with the tolerances below, so that what "
         "the data do not determine stays at nominal (docs/solver-lm.md); off: plain least squares",
         "nominal"},
        {"dh-tolerance-mm", "X", "the prior's tolerance of each DH length (d, a) [mm]",
         textio::format_double(kDefaultPriorTolerances.dh_length_m * 1e3)},
        {"dh-tolerance-mrad", "X", "the prior's tolerance of each DH angle (theta offset, alpha) [mrad]",
         textio::format_double(kDefaultPriorTolerances.dh_angle_rad * 1e3)},
        {"tool-tolerance-mm", "X", "the prior's tolerance of each coordinate of the --tool point [mm]",
         textio::format_double(kDefaultPriorTolerances.tool_m * 1e3)},
        {"quiet", "", "no progress on stderr", ""},
        {"profile", "",
         "print on stderr where the wall time went: reading the input, the job's screen, baseline, stages and "
         "w-tests, cross-validation, tables and outputs",
         ""},
    };
    const std::vector<OptionSpec> tool = tool_option_specs(
        "nominal retroreflector centre in the flange frame [m] (LM refines it; default: the description file's)");
    list.insert(std::find_if(list.begin(), list.end(), [](const OptionSpec& spec) { return spec.name == "params"; }),
                tool.begin(), tool.end());
    for (const OptionSpec& spec : sample_reader_option_specs()) list.push_back(spec);
    return list;
  }();
  return specs;
}

Error calibrate_settings_from_options(const Options& options, CalibrateSettings* settings) {
  bool from_file = false;
  Error error = robot_model_option(options, "robot-model", &settings->robot, &from_file);
  if (error.ok()) error = sample_reader_settings_from_options(options, settings);
  if (!error.ok()) return error;
  error = tool_point_option(options, settings->units, from_file ? &settings->robot.model.tool_m : nullptr,
                            &settings->tool_m, &settings->tool_note);
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
  error = ranged_option(options, "split", NumberRange{0.0, 1.0, true, false, "(the training share)"},
                        &settings->train_fraction);
  if (!error.ok()) return error;
  const std::string cv = options.get("cv");
  if (cv == "loo") {
    settings->cv_folds = 1;
  } else if (!cv.empty()) {
    error = check_count(
        "--cv", cv, NumberRange{2.0, static_cast<double>(kMaxCrossValidationFolds), false, false, "folds, or 'loo'"},
        &settings->cv_folds);
    if (!error.ok()) return error;
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
    error = ranged_option(options, "significance", NumberRange{0.0, 10.0, false, false, "sigma (or 'auto')"},
                          &settings->significance_t);
    if (!error.ok()) return error;
    settings->significance_every_set = true;
  }
  const bool samples = !options.get("samples").empty();
  const bool streams = !options.get("robot").empty() || !options.get("tracker").empty();
  if (samples == streams) return Error::usage("give either --samples, or --robot and --tracker (see --help)");
  if (streams && (options.get("robot").empty() || options.get("tracker").empty())) {
    return Error::usage("--robot and --tracker go together");
  }
  double max_mm = 0.0;
  double max_deg = 0.0;
  error = ranged_option(options, "max-change-mm", NumberRange{0.0, 1e6, true, false, "mm"}, &max_mm);
  if (error.ok())
    error = ranged_option(options, "max-change-deg", NumberRange{0.0, 360.0, true, false, "deg"}, &max_deg);
  if (!error.ok()) return error;
  settings->bounds.max_length_change_m = max_mm * 1e-3;
  settings->bounds.max_angle_change_rad = max_deg * math::kRadPerDeg;
  settings->robust = options.given("robust");
  settings->progress = progress_enabled(options);
  settings->profile = options.given("profile");
  const Error compliance = compliance_from_options(options, settings);
  if (!compliance.ok()) return compliance;
  return prior_options(options, &settings->prior);
}

}  // namespace hivecal::cli
