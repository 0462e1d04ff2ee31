// hivecal iso9283: ISO 9283 pose accuracy AP and repeatability RP of measured reaches
// (docs/iso9283.md). The samples are grouped into poses by their joints (within
// kSamePoseTolerance_rad: every reach of one commanded pose); the commanded positions come from
// a calibration result (its base -> tracker and model), or from a nominal model with the
// base -> tracker fitted to the measurements.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/host_storage.hpp"
#include "commands/iso9283.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/iso9283.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/plan/inverse_kinematics.hpp"
#include "hivecal/port/output_files.hpp"
#include "report/report.hpp"
#include "report/svg.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

namespace {

constexpr std::size_t kNoReport = static_cast<std::size_t>(-1);

/// The reaches of one commanded pose.
struct PoseReaches {
  Sample first;                  ///< the first reach (its joints: the command; its target)
  std::size_t line = 0;          ///< file line of the first reach
  std::vector<Vec3> measured_m;  ///< every reach's measured point [m]
};

/// Samples grouped by pose and target, in the order of their first reach.
std::vector<PoseReaches> group_reaches(Span<const Sample> samples, const std::vector<std::size_t>& lines) {
  std::vector<PoseReaches> poses;
  for (const Sample& s : samples) {
    PoseReaches* pose = nullptr;
    for (PoseReaches& p : poses) {
      if (same_point(p.first, s)) pose = &p;
    }
    if (pose == nullptr) {
      poses.push_back(PoseReaches{s, s.index < lines.size() ? lines[s.index] : 0, {}});
      pose = &poses.back();
    }
    pose->measured_m.push_back(s.point_m);
  }
  return poses;
}

/// The command frame: a result's model and base -> tracker, or a nominal model with the
/// base -> tracker fitted to every reach. *how says which.
Error command_frame(const Options& options, Span<const Sample> samples, record::CalibrationFile* frame,
                    std::string* how) {
  if (!options.get("calibration").empty()) {
    *how = "commanded positions from " + options.get("calibration") + " (its model and base -> tracker)";
    return record::read_calibration_json(options.get("calibration"), frame);
  }
  Error error = robot_model_option(options, "robot-model", frame);
  if (error.ok()) error = vec3_option(options, "tool", &frame->model.tool_m);
  if (!error.ok()) return error;
  if (fit_base_to_tracker(frame->model, samples, &frame->base_to_tracker) != Status::ok) {
    return Error::input(
        "cannot fit the base -> tracker transform of the nominal model to the reaches (too few poses?)");
  }
  *how = "commanded positions from the nominal " + frame->robot + " (base -> tracker fitted to the reaches)";
  return Error{};
}

std::string mm(double value_m) {
  char text[32];
  const double value_mm = std::fabs(value_m) < 0.5e-7 ? 0.0 : value_m * 1e3;  // no "-0.0000"
  std::snprintf(text, sizeof text, "%.4f", value_mm);
  return text;
}

Error iso9283(const Options& options) {
  if (options.get("samples").empty()) return Error::usage("--samples is required (see --help)");
  if (!options.get("calibration").empty() && options.given("robot-model")) {
    return Error::usage("give --calibration or --robot-model, not both: the command frame is one of them");
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  std::size_t report_id = kNoReport;
  Error error = declare_inputs(options, {"out", "report"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (error.ok() && !options.get("report").empty())
    error = outputs.add_file(options.get("report"), "--report", &report_id);
  if (!error.ok()) return error;
  cli::HostDataset dataset;
  textio::InputUnits units;
  error = input_units_option(options, &units);
  std::vector<std::size_t> lines;
  if (error.ok()) error = textio::read_samples_csv(options.get("samples"), &dataset, units, &lines);
  if (!error.ok()) return error;
  record::CalibrationFile frame;
  std::string how;
  error = command_frame(options, dataset.samples(), &frame, &how);
  if (!error.ok()) return error;
  const std::vector<PoseReaches> poses = group_reaches(dataset.samples(), lines);
  std::vector<std::vector<std::string>> rows = {
      {"pose", "line", "target", "cycles", "AP_P [mm]", "AP_x [mm]", "AP_y [mm]", "AP_z [mm]", "RP_l [mm]"}};
  std::size_t measured = 0;
  std::size_t single = 0;
  double worst_ap_m = 0.0;
  double worst_rp_m = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const PoseReaches& p = poses[k];
    PoseAccuracy accuracy;
    const Vec3 commanded = frame.base_to_tracker.apply(fk_sample_point(frame.model, p.first));
    if (pose_accuracy(Span<const Vec3>(p.measured_m.data(), p.measured_m.size()), commanded, &accuracy) != Status::ok) {
      ++single;  // one reach: no repeatability
      continue;
    }
    ++measured;
    worst_ap_m = std::max(worst_ap_m, accuracy.accuracy_norm_m);
    worst_rp_m = std::max(worst_rp_m, accuracy.repeatability_m);
    rows.push_back({std::to_string(k + 1), std::to_string(p.line), std::to_string(p.first.target + 1),
                    std::to_string(accuracy.cycles), mm(accuracy.accuracy_norm_m), mm(accuracy.accuracy_m.x()),
                    mm(accuracy.accuracy_m.y()), mm(accuracy.accuracy_m.z()), mm(accuracy.repeatability_m)});
  }
  if (measured == 0) {
    return Error::input(options.get("samples") +
                        ": no pose was reached twice (ISO 9283 needs the cycles of each pose; " +
                        std::to_string(poses.size()) + " poses, one reach each)");
  }
  const std::string summary = std::to_string(measured) + " poses with repeated reaches (" + std::to_string(single) +
                              " with one reach, left out); worst AP_P " + mm(worst_ap_m) + " mm, worst RP_l " +
                              mm(worst_rp_m) + " mm";
  std::fprintf(options.get("out") == "-" ? stderr : stdout, "%s\n%s\n", how.c_str(), summary.c_str());
  std::string table;
  for (const std::vector<std::string>& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) table += row[c] + (c + 1 < row.size() ? "," : "\n");
  }
  error = outputs.stage_text(out_id, "", table);
  if (error.ok() && report_id != kNoReport) {
    error = outputs.stage_text(
        report_id, "",
        report::html_page_head("ISO 9283 pose accuracy and repeatability") + "<ul>\n<li>" + report::xml_escape(how) +
            "</li>\n<li>" + report::xml_escape(summary) + "</li>\n</ul>\n" + report::html_table(rows) +
            "<p>AP_P: distance of the reaches' barycentre from the commanded position; RP_l = "
            "mean distance of the reaches from their barycentre + 3 S_l (ISO 9283; docs/iso9283.md)."
            "</p>\n</body>\n</html>\n");
  }
  return error.ok() ? outputs.commit() : error;
}

/// The cube of `--iso9283 X,Y,Z,SIDE` [m]: false when malformed or not a positive side.
bool parse_cube(const std::string& text, Vec3* centre_m, double* side_m) {
  double values[4];
  std::size_t begin = 0;
  for (int k = 0; k < 4; ++k) {
    const std::size_t end = k < 3 ? text.find(',', begin) : text.size();
    if (end == std::string::npos || !textio::parse_double(text.substr(begin, end - begin), &values[k]) ||
        !std::isfinite(values[k])) {
      return false;
    }
    begin = end + 1;
  }
  *centre_m = Vec3(values[0], values[1], values[2]);
  *side_m = values[3];
  return *side_m > 0.0 && *side_m <= 10.0 && centre_m->norm() <= 10.0;
}

/// The rotation vector of the one tool orientation: flange z towards the tracker (or down).
Vec3 tool_rotation_vector(const Vec3& from_m, const Vec3& tracker_m, bool tool_down) {
  if (tool_down) return Vec3(0.0, math::kPi, 0.0);  // z down, as a UR pendant writes it
  const Vec3 z = (tracker_m - from_m).normalized();
  const Vec3 axis = Vec3::UnitZ().cross(z);
  const double angle = std::atan2(axis.norm(), z.z());
  return axis.norm() > 1e-12 ? Vec3(axis.normalized() * angle)
                             : Vec3(z.z() > 0.0 ? Vec3::Zero() : Vec3(math::kPi, 0, 0));
}

/// The five ISO positions of the cube at `centre_m` with side `side_m` (P1 first).
void iso_positions(const Vec3& centre_m, double side_m, Vec3 (&positions)[5]) {
  // The diagonal plane through the cube's x edges: corners (+-s/2, -s/2, -s/2), (+-s/2, +s/2,
  // +s/2); P2 .. P5 on its diagonals, 10 % of a diagonal from each corner.
  const double h = side_m / 2.0;
  const Vec3 corners[4] = {Vec3(-h, -h, -h), Vec3(h, -h, -h), Vec3(h, h, h), Vec3(-h, h, h)};
  positions[0] = centre_m;
  for (int k = 0; k < 4; ++k) positions[k + 1] = centre_m + 0.8 * corners[k];
}

/// Joints putting the reflector at `position` with the tool orientation `rotation` (a rotation
/// vector of the flange); false when not reachable within the limits.
bool reach(const RobotModel& model, const JointLimits& limits, const Vec3& position, const Vec3& rotation,
           Random* random, JointVector* q) {
  const Mat3 flange_rotation = rotation_from_vector(rotation);
  const RigidTransform flange{flange_rotation, position - flange_rotation * model.tool_m};
  return solve_flange_pose(model, limits, flange, InverseKinematicsOptions{}, random, q) == Status::ok;
}

/// Whether the arm reaches all five positions of the cube with the one orientation, above the
/// floor and outside the keep-out cylinder.
bool cube_reachable(const RobotModel& model, const JointLimits& limits, const Vec3& centre_m, double side_m,
                    const Vec3& rotation, double floor_z_m, double keep_out_m, Random* random) {
  Vec3 positions[5];
  iso_positions(centre_m, side_m, positions);
  for (const Vec3& p : positions) {
    JointVector q;
    if (p.z() < floor_z_m || p.head<2>().norm() < keep_out_m || !reach(model, limits, p, rotation, random, &q))
      return false;
  }
  return true;
}

/// The largest cube found: centres at reflector positions of random configurations, each
/// grown by bisection while its five positions stay reachable.
bool largest_cube(const RobotModel& model, const JointLimits& limits, const Vec3& tracker_m, bool tool_down,
                  double floor_z_m, double keep_out_m, Vec3* centre_m, double* side_m) {
  Random random(9283);
  *side_m = 0.0;
  for (int candidate = 0; candidate < 40; ++candidate) {
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = random.uniform(limits.lower_rad(j), limits.upper_rad(j));
    const Vec3 centre = fk_tool_point(model, q);
    const Vec3 rotation = tool_rotation_vector(centre, tracker_m, tool_down);
    if (!cube_reachable(model, limits, centre, std::max(*side_m, 0.02), rotation, floor_z_m, keep_out_m, &random))
      continue;
    double low = std::max(*side_m, 0.02);
    double high = 2.0;
    for (int step = 0; step < 8; ++step) {
      const double mid = 0.5 * (low + high);
      (cube_reachable(model, limits, centre, mid, rotation, floor_z_m, keep_out_m, &random) ? low : high) = mid;
    }
    if (low > *side_m) {
      *side_m = low;
      *centre_m = centre;
    }
  }
  return *side_m > 0.0;
}

std::string pose_text(const Vec3& p, const Vec3& r) {
  return textio::format_double(p.x()) + ", " + textio::format_double(p.y()) + ", " + textio::format_double(p.z()) +
         ", " + textio::format_double(r.x()) + ", " + textio::format_double(r.y()) + ", " +
         textio::format_double(r.z());
}

}  // namespace

Error plan_iso9283(const Options& options, const RobotModel& model, const JointLimits& limits) {
  Vec3 centre_m;
  double side_m = 0.0;
  const bool automatic = options.get("iso9283") == "auto";
  if (!automatic && !parse_cube(options.get("iso9283"), &centre_m, &side_m)) {
    return Error::usage(
        "--iso9283 must be X,Y,Z,SIDE (the cube's centre in the base frame and its side, metres; "
        "side in (0, 10]) or auto, not " +
        port::quoted(options.get("iso9283")));
  }
  Vec3 tracker_m;
  std::size_t cycles = 0;
  double dwell_s = 0.0;
  double speed = 0.0;
  double acceleration = 0.0;
  Error error = vec3_option(options, "tracker-position", &tracker_m);
  if (error.ok()) error = count_option(options, "cycles", 1, 1000, &cycles);
  if (error.ok()) error = bounded_option(options, "dwell", 0.3, 3600.0, &dwell_s);
  if (error.ok()) error = bounded_option(options, "tool-speed", 1e-3, 1.0, &speed);
  if (error.ok()) error = bounded_option(options, "tool-acceleration", 1e-3, 10.0, &acceleration);
  if (!error.ok()) return error;
  double floor_z_m = 0.0;
  double keep_out_m = 0.0;
  if (error.ok()) error = bounded_option(options, "floor-z", -10.0, 10.0, &floor_z_m);
  if (error.ok()) error = bounded_option(options, "keep-out-radius", 0.0, 10.0, &keep_out_m);
  if (!error.ok()) return error;
  if (options.get("out").empty()) return Error::usage("--out is required (see --help)");
  if (automatic &&
      !largest_cube(model, limits, tracker_m, options.given("tool-down"), floor_z_m, keep_out_m, &centre_m, &side_m)) {
    return Error::failure(
        "--iso9283 auto: no cube whose five positions the arm reaches with one orientation (move the "
        "tracker, lower --floor-z or --keep-out-radius)");
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  std::size_t script_id = 0;
  const bool script = !options.get("urscript").empty();
  error = declare_inputs(options, {"out", "urscript", "svg"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (error.ok() && script) error = outputs.add_file(options.get("urscript"), "--urscript", &script_id);
  if (!error.ok()) return error;
  Vec3 positions[5];
  iso_positions(centre_m, side_m, positions);
  const Vec3 rotation = tool_rotation_vector(centre_m, tracker_m, options.given("tool-down"));
  // Each position with a joint solution of the model (the controller's own IK moves the arm;
  // these say that one exists within the limits, and let `predict` check the list).
  std::string list = "pose,x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6\n";
  Random random(9283);
  for (int k = 0; k < 5; ++k) {
    JointVector q;
    const bool reachable = reach(model, limits, positions[k], rotation, &random, &q);
    if (!reachable) {
      std::fprintf(
          stderr, "hivecal plan: warning: P%d is not reachable with this orientation within the joint limits\n", k + 1);
    }
    list += "P" + std::to_string(k + 1) + "," + textio::format_double(positions[k].x()) + "," +
            textio::format_double(positions[k].y()) + "," + textio::format_double(positions[k].z()) + "," +
            textio::format_double(rotation.x()) + "," + textio::format_double(rotation.y()) + "," +
            textio::format_double(rotation.z());
    for (int j = 0; j < kSixJoints; ++j) list += "," + (reachable ? textio::format_double(q(j)) : std::string("nan"));
    list += "\n";
  }
  char head[400];
  std::snprintf(head, sizeof head,
                "# hivecal plan --iso9283: cube centre %.4f, %.4f, %.4f m, side %.4f m; P1 centre, P2..P5 at 10 %% of\n"
                "# the diagonals from the corners of the plane through the cube's x edges; %zu cycles P1 P5 P4 P3 P2.\n"
                "# Set the TCP to the reflector first: the positions are the reflector's, in the base frame.\n",
                centre_m.x(), centre_m.y(), centre_m.z(), side_m, cycles);
  std::string program = std::string(head) + "def hivecal_iso9283():\n";
  for (int k = 0; k < 5; ++k)
    program += "  p" + std::to_string(k + 1) + " = p[" + pose_text(positions[k], rotation) + "]\n";
  const std::string motion =
      ", a=" + textio::format_double(acceleration) + ", v=" + textio::format_double(speed) + ")\n";
  const std::string wait = "    sleep(" + textio::format_double(dwell_s) + ")\n";
  program += "  cycle = 0\n  while (cycle < " + std::to_string(cycles) + "):\n";
  for (const int k : {1, 5, 4, 3, 2}) program += "    movel(p" + std::to_string(k) + motion + wait;
  program += "    cycle = cycle + 1\n  end\nend\n";
  error = outputs.stage_text(out_id, "", list);
  if (error.ok() && script) error = outputs.stage_text(script_id, "", program);
  if (!error.ok()) return error;
  std::fprintf(
      options.get("out") == "-" || options.get("urscript") == "-" ? stderr : stdout,
      "ISO 9283 test: 5 positions in a %.3f m cube around %.3f, %.3f, %.3f m, %zu cycles of %.0f s dwell each\n",
      side_m, centre_m.x(), centre_m.y(), centre_m.z(), cycles, dwell_s);
  return outputs.commit();
}

int iso9283_main(int argc, char** argv) {
  std::vector<OptionSpec> specs = {
      {"samples", "FILE", "measured reaches: paired samples q1..q6,x,y,z, every commanded pose reached several times",
       ""},
      {"calibration", "FILE", "command frame: a calibration result (its model and base -> tracker)", ""},
      {"robot-model", "NAME|FILE", "or the nominal model, its base -> tracker fitted to the reaches", "ur5"},
      {"tool", "X,Y,Z", "with --robot-model: the reflector in the flange frame [m]", "0,0,0"},
      {"out", "FILE", "per-pose table (CSV: AP_P, AP_x/y/z, RP_l in mm); '-' for stdout", "-"},
      {"report", "FILE", "the same as an HTML page in the calibration report's style", ""},
  };
  for (const OptionSpec& unit : input_unit_option_specs()) specs.push_back(unit);
  Options options;
  const int parsed = parse_options(kIso9283Command,
                                   "ISO 9283 pose accuracy (AP_P: barycentre of the reaches - commanded position) and\n"
                                   "repeatability (RP_l = mean distance from the barycentre + 3 S_l) of each pose of\n"
                                   "the measured reaches (samples at the same joints within 1e-3 rad are one pose).",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kIso9283Command, iso9283(options));
}

}  // namespace hivecal::cli
