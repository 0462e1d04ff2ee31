// hivecal plan: which poses to measure, in which order, and the robot program that visits
// them (docs/planning.md). The selection is the library's (hivecal/plan/pose_plan.hpp); this
// file parses, prints the before/after report and writes the joints CSV and URScript.
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/iso9283.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/plan/pose_plan.hpp"
#include "hivecal/port/output_files.hpp"
#include "report/svg.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"
#include "textio/ur_calibration_conf.hpp"

namespace hivecal::cli {

namespace {

// Shortest dwell: the extraction keeps a tracker point when the robot was still around it;
// a 10 Hz tracker needs three points (the speed baseline on both sides) of stillness.
constexpr double kMinDwell_s = 0.3;

PlanWorkspace workspace;  // ~280 kB: static, as the library asks
PlanResult result;

/// What the command line asked for beyond PlanOptions.
struct PlanRequest {
  RobotModel model;           ///< nominal geometry with the reflector
  PlanOptions options;        ///< the library's settings
  JointLimits widest_limits;  ///< tried when options' limits leave no pose (robot_option)
};

std::string text(double value, const char* format) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

/// True when an output of the plan goes to stdout: the summary then goes to stderr.
bool stdout_carries_output(const Options& options) {
  return options.get("out") == "-" || options.get("urscript") == "-" || options.get("svg") == "-";
}

/// Within this of the arm's own range, --joint-limits are taken as that range without a word
/// (360 deg read from a file is 2 pi to the last bit or two) [rad].
constexpr double kLimitSlack_rad = 1e-9;

/// --joint-limits clamped to the arm's own range `own` (a built-in type's controller limits, or
/// the description's): a limit beyond it is said on stderr and clamped (the controller would
/// refuse a pose there); a joint whose given range lies outside the arm's is refused.
Error clamp_to_own_range(const Options& options, const std::string& arm, int joints, const JointLimits& own,
                         JointLimits* limits) {
  for (int j = 0; j < joints; ++j) {
    double& lower = limits->lower_rad(j);
    double& upper = limits->upper_rad(j);
    const double own_lower = own.lower_rad(j);
    const double own_upper = own.upper_rad(j);
    if (!(std::max(lower, own_lower) < std::min(upper, own_upper))) {
      return Error::input(options.get("joint-limits") + ": joint " + std::to_string(j + 1) + " [" +
                          text(lower, "%.4f") + ", " + text(upper, "%.4f") + "] rad lies outside the " + arm +
                          "'s own range [" + text(own_lower, "%.4f") + ", " + text(own_upper, "%.4f") + "] rad");
    }
    if (lower < own_lower - kLimitSlack_rad || upper > own_upper + kLimitSlack_rad) {
      std::fprintf(stderr,
                   "hivecal plan: warning: --joint-limits joint %d [%.4f, %.4f] rad goes beyond the %s's own range "
                   "[%.4f, %.4f] rad: clamped to it\n",
                   j + 1, lower, upper, arm.c_str(), own_lower, own_upper);
    }
    lower = std::max(lower, own_lower);
    upper = std::min(upper, own_upper);
  }
  return Error{};
}

/// The arm, its tool point and its joint limits. The tool: --tool or --tool-transform, else the
/// description's, else the default (cli::tool_point_option, as calibrate takes it). The limits:
/// --joint-limits (clamped to the arm's own range when that is known), else the description's
/// own ("joint_limits", URDF <limit>), else a built-in type's controller limits, else +-2 pi
/// (said on stderr). *widest: the limits to try when these leave no pose (a built-in type's
/// own, else +-2 pi).
Error robot_option(const Options& options, RobotModel* model, JointLimits* limits, JointLimits* widest) {
  textio::RobotDescription description;
  bool from_file = false;
  textio::InputUnits units;
  std::string tool_note;
  Error error = robot_model_option(options, "robot-model", &description, &from_file);
  if (error.ok()) error = input_units_option(options, &units);
  units.joints = textio::input_joints(description.model);
  if (error.ok()) {
    error = tool_point_option(options, units, from_file ? &description.model.tool_m : nullptr,
                              &description.model.tool_m, &tool_note);
  }
  if (!error.ok()) return error;
  if (!tool_note.empty()) std::fprintf(stderr, "hivecal plan: %s\n", tool_note.c_str());
  if (!options.get("urscript").empty()) {  // movej and movel are a UR controller's
    error = textio::require_ur_joints(description.model, description.robot, "--urscript (URScript)");
    if (!error.ok()) return error;
  }
  for (int j = 0; j < description.model.joint_count; ++j) {  // a slide's travel has no default
    if (joint_type(description.model, j) != JointType::prismatic || description.has_joint_limits ||
        !options.get("joint-limits").empty())
      continue;
    return Error::usage(port::printable(description.robot) + "'s joint " + std::to_string(j + 1) +
                        " is prismatic: its travel has no default; give \"joint_limits\" in the description or "
                        "--joint-limits FILE (a prismatic joint's row in m)");
  }
  *model = description.model;
  RobotType type = RobotType::ur5;
  const bool built_in = !from_file && robot_type_from_name(description.robot.c_str(), &type) == Status::ok;
  JointLimits own;  // the arm's own range: the description's, a built-in type's, else none known
  if (description.has_joint_limits) {
    own.lower_rad = description.lower_rad;
    own.upper_rad = description.upper_rad;
  } else if (built_in) {
    own = default_joint_limits(type);
  }
  *widest = built_in ? own : JointLimits{};
  if (!options.get("joint-limits").empty()) {
    error = textio::read_joint_limits_csv(options.get("joint-limits"), &limits->lower_rad, &limits->upper_rad, units);
    if (!error.ok() || !(description.has_joint_limits || built_in)) return error;
    return clamp_to_own_range(options, port::printable(description.robot), model->joint_count, own,
                              limits);  // the file's name, made safe
  }
  *limits = own;
  if (!description.has_joint_limits && !built_in) {
    std::fprintf(stderr,
                 "hivecal plan: %s gives no joint limits: assuming +-360 deg for every joint (--joint-limits FILE, or "
                 "\"joint_limits\" in the description, sets them)\n",
                 options.get("robot-model").c_str());
  }
  return Error{};
}

/// --params: full, or the link lengths of `model` (and the base).
Error params_option(const Options& options, const RobotModel& model, ParamMask* mask) {
  const std::string params = options.get("params");
  if (params != "full" && params != "paper") {
    return Error::usage("--params must be 'full' or 'paper', not " + port::quoted(params));
  }
  *mask = lm_param_mask(params == "full" ? LmParamSet::full : LmParamSet::link_lengths, 0, model);
  return Error{};
}

Error criterion_option(const Options& options, PlanCriterion* criterion) {
  const std::string name = options.get("objective");
  for (PlanCriterion c : {PlanCriterion::d_optimal, PlanCriterion::i_optimal, PlanCriterion::i_optimal_workspace}) {
    if (name == plan_criterion_name(c)) {
      *criterion = c;
      return Error{};
    }
  }
  return Error::usage("--objective must be d-optimal, i-optimal or i-optimal-workspace, not " + port::quoted(name));
}

/// The cell and the timing; --count, --tracker-position and --out are required.
Error parse_request(const Options& options, PlanRequest* request) {
  if (options.get("count").empty() || options.get("tracker-position").empty() || options.get("out").empty()) {
    return Error::usage("--count, --tracker-position and --out are required (see --help)");
  }
  PlanOptions& o = request->options;
  PlanConstraints& c = o.constraints;
  Error error = robot_option(options, &request->model, &c.limits, &request->widest_limits);
  if (error.ok()) error = vec3_option(options, "tracker-position", &c.tracker_m);
  if (error.ok()) error = count_option(options, "count", 1, kPlanPoseCapacity, &o.pose_count);
  if (error.ok()) error = count_option(options, "candidates", 1, kPlanCandidateCapacity, &o.candidate_count);
  double acceptance_deg = 0.0;
  if (error.ok()) error = bounded_option(options, "acceptance-deg", 1.0, 180.0, &acceptance_deg);
  c.acceptance_rad = acceptance_deg * math::kRadPerDeg;
  if (error.ok()) error = bounded_option(options, "floor-z", -10.0, 10.0, &c.floor_z_m);
  if (error.ok()) error = bounded_option(options, "keep-out-radius", 0.0, 10.0, &c.keep_out_radius_m);
  if (error.ok()) error = seed_option(options, "seed", &o.seed);
  if (error.ok()) error = params_option(options, request->model, &o.free_mask);
  if (error.ok()) error = criterion_option(options, &o.criterion);
  double noise_um = 0.0;
  if (error.ok()) error = bounded_option(options, "noise-um", 1e-3, 1e4, &noise_um);
  o.noise_m = noise_um * 1e-6;
  double prior_mm = 0.0;
  double prior_mrad = 0.0;
  std::size_t restarts = 0;
  std::size_t refine = 0;
  if (error.ok()) error = bounded_option(options, "prior-mm", 0.0, 1e3, &prior_mm);
  if (error.ok()) error = bounded_option(options, "prior-mrad", 0.0, 1e3, &prior_mrad);
  if (error.ok()) error = count_option(options, "restarts", 1, 64, &restarts);
  if (error.ok()) error = count_option(options, "refine", 0, 16, &refine);
  o.prior_length_m = prior_mm * 1e-3;
  o.prior_angle_rad = prior_mrad * 1e-3;
  o.restarts = static_cast<int>(restarts);
  o.refine_passes = static_cast<int>(refine);
  if (error.ok()) error = bounded_option(options, "joint-speed", 1e-3, 10.0, &o.joint_speed_rad_s);
  if (error.ok()) error = bounded_option(options, "joint-acceleration", 1e-3, 100.0, &o.joint_acceleration_rad_s2);
  if (error.ok()) error = bounded_option(options, "dwell", kMinDwell_s, 3600.0, &o.dwell_s);
  if (!error.ok()) return error;
  if (!all_finite(c.tracker_m) || !all_finite(request->model.tool_m)) {
    return Error::usage("--tracker-position and --tool must be finite");
  }
  if (o.candidate_count < o.pose_count) return Error::usage("--candidates must be at least --count");
  if (options.given("tool-down")) c.orientation = PlanOrientation::tool_down;
  return Error{};
}

std::string names_of(ParamMask mask, const RobotModel& model) {
  std::string out;
  for (int k = 0; k < kFullParamCount; ++k) {
    if (mask_has(mask, k)) out += (out.empty() ? "" : " ") + std::string(full_param_name(k, model));
  }
  return out.empty() ? "-" : out;
}

bool is_angle(int index, const RobotModel& model) {
  return model_param_is_angle(index, model.joint_count) ||
         (index >= base_rotation_param_index(model, 0) && index <= base_rotation_param_index(model, 2));
}

/// The dropped parameters of an analysis with the combination each one is redundant in.
std::string dropped_lines(const IdentifiabilityReport& report, const RobotModel& model) {
  std::string out;
  for (int i = 0; i < report.dropped_count; ++i) {
    const DroppedParam& d = report.dropped[i];
    out += "  " + std::string(full_param_name(d.index, model)) + ": " + unidentifiable_reason_name(d.reason);
    if (d.reason == UnidentifiableReason::null_combination) {
      out += " (with";
      for (int k = 1; k < kNullComponentCount && d.component_index[k] >= 0; ++k) {
        out += " " + std::string(full_param_name(d.component_index[k], model));
      }
      out += ")";
    }
    out += "\n";
  }
  return out;
}

std::string report_text(const PlanRequest& request, const IdentifiabilityReport* facing) {
  const PlanOptions& o = request.options;
  std::string out = "hivecal plan: " + std::to_string(result.pose_count) + " poses chosen (" +
                    plan_criterion_name(o.criterion) + ", " + std::to_string(result.exchanges) + " exchanges in " +
                    std::to_string(result.exchange_passes) + " passes) from " + std::to_string(result.candidate_count) +
                    " candidates (" + std::to_string(result.attempts) + " random draws, seed " +
                    std::to_string(o.seed) + ")\n";
  out += "identifiable by the candidate pool: " + std::to_string(result.pool.kept_count()) + " of " +
         std::to_string(mask_count(o.free_mask)) + " parameters; no pose set under these constraints identifies:\n";
  const RobotModel& model = request.model;
  out += dropped_lines(result.pool, model);
  out += "objective: " + std::to_string(result.objective.kept_count()) + " parameters, the tool " +
         text(o.prior_length_m * 1e3, "%g") + " mm off the flange axis in x and y (its prior)" +
         ((result.objective.kept_mask & ~result.pool.kept_mask) != 0
              ? ": also " + names_of(result.objective.kept_mask & ~result.pool.kept_mask, model)
              : std::string()) +
         "\n";
  if (facing != nullptr) {
    out += "freeing the orientation (flange z within " + text(o.constraints.acceptance_rad * math::kDegPerRad, "%g") +
           " deg of the tracker) makes identifiable: " + names_of(facing->kept_mask & ~result.pool.kept_mask, model) +
           "\n";
  }
  const PoseSetQuality& r = result.random;
  const PoseSetQuality& p = result.planned;
  out += "                                random    planned   (same count, same constraints)\n";
  out += "  log det (D-criterion)      " + text(r.log_det, "%9.2f") + "  " + text(p.log_det, "%9.2f") + "\n";
  out += "  mean prediction variance   " + text(r.prediction_variance, "%9.3f") + "  " +
         text(p.prediction_variance, "%9.3f") + "   (per unit noise variance)\n";
  out += "  condition number           " + text(r.condition, "%9.2f") + "  " + text(p.condition, "%9.2f") + "\n";
  out += "  smallest singular value    " + text(r.smallest_singular, "%9.4f") + "  " +
         text(p.smallest_singular, "%9.4f") + "   (column-scaled J)\n";
  out += "  identifiable parameters    " + text(r.identifiability.kept_count(), "%9.0f") + "  " +
         text(p.identifiability.kept_count(), "%9.0f") + "\n";
  const ParamMask only_planned = p.identifiability.kept_mask & ~r.identifiability.kept_mask;
  out += "  identifiable only when planned: " + names_of(only_planned, model) + "\n";
  out += "predicted sigma at " + text(o.noise_m * 1e6, "%g") + " um tracker noise (um or urad):\n";
  for (int k = 0; k < kFullParamCount; ++k) {
    if (!mask_has(r.identifiability.kept_mask | p.identifiability.kept_mask, k)) continue;
    const double unit = 1e6;  // m -> um, rad -> urad
    const std::string name = full_param_name(k, model);
    out += "  " + name + std::string(name.size() < 10 ? 10 - name.size() : 1, ' ') + text(r.sigma(k) * unit, "%9.2f") +
           "  " + text(p.sigma(k) * unit, "%9.2f") + (is_angle(k, model) ? " urad" : " um") + "\n";
  }
  out += "session: " + text(result.travel_s, "%.1f") + " s of movej (" + text(result.unordered_travel_s, "%.1f") +
         " s unordered) + " + std::to_string(result.pose_count) + " x " + text(o.dwell_s, "%g") +
         " s dwell = " + text(result.session_s, "%.1f") + " s (" + text(result.session_s / 60.0, "%.1f") + " min) at " +
         text(o.joint_speed_rad_s, "%g") + " rad/s, " + text(o.joint_acceleration_rad_s2, "%g") + " rad/s^2\n";
  return out;
}

/// URScript: movej to each pose, then a still dwell for the tracker.
std::string urscript(const PlanOptions& o) {
  std::string out = "# hivecal plan: " + std::to_string(result.pose_count) + " poses, seed " + std::to_string(o.seed) +
                    ", about " + text(result.session_s, "%.0f") + " s\ndef hivecal_session():\n";
  for (std::size_t i = 0; i < result.pose_count; ++i) {
    out += "  movej([";  // a UR arm's six joints (robot_option refuses others)
    for (int j = 0; j < kSixJoints; ++j)
      out += textio::format_double(result.poses[i](j)) + (j + 1 < kSixJoints ? ", " : "");
    out += "], a=" + text(o.joint_acceleration_rad_s2, "%.10g") + ", v=" + text(o.joint_speed_rad_s, "%.10g") +
           ")\n  sleep(" + text(o.dwell_s, "%.10g") + ")\n";
  }
  return out + "end\n";
}

/// Reflector positions of planned and random poses and the tracker, seen from above and from
/// the side (distance from the base axis vs height): the report figure "planned vs random".
std::string svg_figure(const PlanRequest& request) {
  const auto series = [&](const std::string& name, const JointVector* poses, std::size_t stride, bool top) {
    report::Series s{name, {}, {}, true};
    for (std::size_t i = 0; i < result.pose_count; ++i) {
      const Vec3 p = fk_tool_point(request.model, poses[i * stride]);
      s.x.push_back(top ? p.x() : p.head<2>().norm());
      s.y.push_back(top ? p.y() : p.z());
    }
    return s;
  };
  std::vector<JointVector> random;
  for (std::size_t i = 0; i < result.pose_count; ++i) random.push_back(workspace.candidates[i].q_rad);
  const Vec3 t = request.options.constraints.tracker_m;
  std::string out = "<svg xmlns='http://www.w3.org/2000/svg' width='560' height='640'>\n";
  for (const bool top : {true, false}) {
    report::ChartSpec spec;
    spec.title = top ? "Reflector positions, top view: planned vs random (same count, same constraints)"
                     : "Side view: distance from the base axis vs height";
    spec.x_label = top ? "x [m]" : "radius [m]";
    spec.y_label = top ? "y [m]" : "z [m]";
    report::Series tracker{"tracker", {top ? t.x() : t.head<2>().norm()}, {top ? t.y() : t.z()}, true};
    const std::string chart = report::svg_chart(
        spec, {series("random", random.data(), 1, top), series("planned", result.poses, 1, top), tracker});
    out += top ? chart : "<g transform='translate(0,320)'>" + chart + "</g>\n";
  }
  return out + "</svg>\n";
}

}  // namespace

std::string blame_tool_or_limits(const Options& options, const RobotModel& model, const JointLimits& limits,
                                 const JointLimits& widest,
                                 const std::function<bool(const RobotModel&, const JointLimits&)>& finds) {
  RobotModel at_flange = model;
  at_flange.tool_m = Vec3::Zero();
  if (!model.tool_m.isZero() && finds(at_flange, limits)) {
    const std::string tool = options.given("tool-transform")
                                 ? "--tool-transform " + port::quoted(options.get("tool-transform"))
                             : options.given("tool") ? "--tool " + options.get("tool")
                                                     : "the tool point " + options.get("tool");
    return "the tool is why: " + tool + " puts the reflector " + text(model.tool_m.norm(), "%.4g") +
           " m from the flange (with the reflector at the flange the search finds some); --tool is the reflector in "
           "the flange frame, in metres (millimetres given?)";
  }
  const bool limited =
      (limits.lower_rad - widest.lower_rad).maxCoeff() > 0.0 || (limits.upper_rad - widest.upper_rad).minCoeff() < 0.0;
  if (limited && finds(model, widest)) {
    return "the joint limits are why: " +
           (options.get("joint-limits").empty() ? std::string("the description's joint_limits")
                                                : "--joint-limits " + options.get("joint-limits")) +
           " leave none (with the arm's full range the search finds some): widen them";
  }
  return "";
}

namespace {

/// An option of the other mode (pose planning, or the ISO 9283 test) is refused: it was read by
/// neither and dropped without a word (--count with --iso9283, --cycles without it).
Error refuse_the_other_modes_options(const Options& options) {
  static const char* const kPlanningOnly[] = {
      "count",      "acceptance-deg", "params", "objective",   "candidates",         "seed", "noise-um", "prior-mm",
      "prior-mrad", "restarts",       "refine", "joint-speed", "joint-acceleration", "svg"};
  static const char* const kIsoOnly[] = {"cycles", "tool-speed", "tool-acceleration"};
  const bool iso = options.given("iso9283");
  if (iso) {
    for (const char* name : kPlanningOnly) {
      if (options.given(name)) {
        return Error::usage(std::string("--") + name +
                            " is an option of pose planning, not of the ISO 9283 test (--iso9283): leave it out");
      }
    }
    return Error{};
  }
  for (const char* name : kIsoOnly) {
    if (options.given(name)) return Error::usage(std::string("--") + name + " goes with --iso9283 (the ISO 9283 test)");
  }
  return Error{};
}

Error plan(const Options& options) {
  const Error other = refuse_the_other_modes_options(options);
  if (!other.ok()) return other;
  if (options.given("iso9283")) {
    RobotModel model;
    JointLimits limits;
    JointLimits widest;
    const Error error = robot_option(options, &model, &limits, &widest);
    return error.ok() ? plan_iso9283(options, model, limits, widest) : error;
  }
  PlanRequest request;
  Error error = parse_request(options, &request);
  if (!error.ok()) return error;
  port::OutputSet outputs;
  std::size_t out_id = 0;
  std::size_t script_id = 0;
  std::size_t svg_id = 0;
  const bool script = !options.get("urscript").empty();
  const bool svg = !options.get("svg").empty();
  error = declare_inputs(options, {"out", "urscript", "svg"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (error.ok() && script) error = outputs.add_file(options.get("urscript"), "--urscript", &script_id);
  if (error.ok() && svg) error = outputs.add_file(options.get("svg"), "--svg", &svg_id);
  if (!error.ok()) return error;

  IdentifiabilityReport facing;
  const bool down = request.options.constraints.orientation == PlanOrientation::tool_down;
  if (down) {  // what the same cell identifies with the reflector free to face the tracker
    PlanOptions free_orientation = request.options;
    free_orientation.constraints.orientation = PlanOrientation::facing_tracker;
    std::size_t draws = 0;
    const Status status = pool_identifiability(request.model, free_orientation, &workspace, &facing, &draws);
    if (status != Status::ok) {
      return Error::failure(std::string("no pool facing the tracker to compare with: ") + status_message(status));
    }
  }
  const Status status = plan_session(request.model, request.options, &workspace, &result);
  if (status == Status::too_few_samples) {
    const std::string cause =
        blame_tool_or_limits(options, request.model, request.options.constraints.limits, request.widest_limits,
                             [&](const RobotModel& model, const JointLimits& limits) {
                               PlanOptions probe = request.options;
                               probe.constraints.limits = limits;
                               std::size_t attempts = 0;
                               return generate_candidates(model, probe, &workspace, &attempts) == Status::ok;
                             });
    return Error::failure("too few poses meet the constraints (" + std::to_string(request.options.candidate_count) +
                          " candidates wanted): " +
                          (cause.empty() ? "move the tracker, widen --acceptance-deg or lower --floor-z" : cause));
  }
  if (status != Status::ok) return Error::failure(std::string("planning failed: ") + status_message(status));

  std::fputs(report_text(request, down ? &facing : nullptr).c_str(), stdout_carries_output(options) ? stderr : stdout);
  error = outputs.stage_text(
      out_id, "",
      textio::format_joints_csv(Span<const JointVector>(result.poses, result.pose_count), request.model.joint_count));
  if (error.ok() && script) error = outputs.stage_text(script_id, "", urscript(request.options));
  if (error.ok() && svg) error = outputs.stage_text(svg_id, "", svg_figure(request));
  return error.ok() ? outputs.commit() : error;
}

}  // namespace

int plan_main(int argc, char** argv) {
  std::vector<OptionSpec> specs = {
      {"robot-model", "NAME|FILE",
       std::string("nominal geometry and joint limits: ") + robot_type_names() +
           ", or a robot description .json or .urdf",
       "ur5e"},
      {"count", "N", "poses to measure (1 .. 128)", ""},
      {"tracker-position", "X,Y,Z", "tracker position in the robot base frame [m]", ""},
      {"acceptance-deg", "DEG", "largest angle flange z - line to the tracker (red-ring reflector: 30)", "30"},
      {"floor-z", "M", "reflector and flange above this base z [m]", "0.05"},
      {"keep-out-radius", "M", "reflector and flange at least this far from the base z axis [m]", "0.15"},
      {"tool-down", "", "the flange z axis points down in every pose (the paper's session)", ""},
      {"joint-limits", "FILE",
       "CSV lower,upper (rad, the header's unit as in 'lower [deg]', or --angle-unit), one row per joint (default: the "
       "robot's)",
       ""},
      {"params", "full|paper", "parameters the calibration will estimate", "full"},
      {"objective", "NAME", "i-optimal-workspace | i-optimal | d-optimal (docs/planning.md)", "i-optimal-workspace"},
      {"candidates", "N", "random candidate configurations to choose from (<= 2048)", "2048"},
      {"seed", "S", "seed of the candidate draws", "1"},
      {"noise-um", "UM", "tracker noise per axis for the predicted sigmas [um]", "10"},
      {"prior-mm", "MM", "prior sigma of the geometry's lengths and the tool in the objective (0: none)", "1"},
      {"prior-mrad", "MRAD", "prior sigma of the geometry's angles in the objective (0: none)", "1"},
      {"restarts", "N", "exchange runs: the greedy start, then seeded random starts (1 .. 64)", "4"},
      {"refine", "N", "passes moving each chosen pose in joint space within the constraints (0 .. 16)", "2"},
      {"joint-speed", "RAD/S", "movej joint speed", "1.05"},
      {"joint-acceleration", "RAD/S2", "movej joint acceleration", "1.4"},
      {"dwell", "S", "wait at each pose (>= 0.3 s: the extraction needs the arm still at 10 Hz)", "1"},
      {"out", "FILE", "planned poses, CSV q1..qN [rad] in visiting order ('-': stdout)", ""},
      {"urscript", "FILE", "URScript program: movej + sleep(dwell) per pose", ""},
      {"svg", "FILE", "figure: reflector positions planned vs random (top and side views)", ""},
      {"iso9283", "X,Y,Z,SIDE",
       "instead: the ISO 9283 test in this cube (centre and side, base frame) [m], or 'auto' (the largest cube the arm "
       "reaches): the 5 positions (--out: pose,x,y,z,rx,ry,rz) and a movel program (--urscript)",
       ""},
      {"cycles", "N", "with --iso9283: cycles P1 P5 P4 P3 P2 (the standard: 30)", "30"},
      {"tool-speed", "M/S", "with --iso9283: movel speed", "0.25"},
      {"tool-acceleration", "M/S2", "with --iso9283: movel acceleration", "1.2"},
  };
  const std::vector<OptionSpec> tool =
      tool_option_specs("reflector in the flange frame [m] (one target; default: the description file's)");
  specs.insert(specs.begin() + 3, tool.begin(), tool.end());  // after --tracker-position
  specs.push_back(input_unit_option_specs()[0]);              // --length-unit: of --tool-transform
  specs.push_back(input_unit_option_specs()[1]);              // --angle-unit: of --joint-limits
  Options options;
  const int parsed =
      parse_options(kPlanCommand,
                    "Chooses the poses of a tracker session (I-optimal over the cell by default, over\n"
                    "the parameters the calibration estimates), orders them for a short path and writes them as a\n"
                    "joints CSV and optionally a URScript program; prints random-vs-planned figures.",
                    specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kPlanCommand, plan(options));
}

}  // namespace hivecal::cli
