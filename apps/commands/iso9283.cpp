// hivecal iso9283: ISO 9283 pose accuracy AP and repeatability RP of measured reaches
// (docs/iso9283.md). The samples are grouped into poses by their joints (within
// kSamePoseTolerance_rad: every reach of one commanded pose); the commanded positions come from
// a calibration result (its base -> tracker and model), or from a nominal model with the
// base -> tracker fitted to the measurements.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unordered_map>
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
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

namespace {

constexpr std::size_t kNoReport = static_cast<std::size_t>(-1);

/// Joint cells of the grouping: kCellWidth_rad = 4 x kSamePoseTolerance_rad, so a sample's
/// tolerance reaches into the next cell only in the joints where it lies within the tolerance
/// of a cell's edge (on average 1.5 cells per joint, 11 of the 2^6 at most).
constexpr double kCellWidth_rad = 4.0 * kSamePoseTolerance_rad;
/// Beyond the tolerance itself, the slack that covers the rounding of a joint's cell [rad].
constexpr double kCellSlack_rad = 1e-9;

/// A cell of joint space and a target.
struct JointCell {
  std::array<std::int64_t, kMaxJoints> index{};  ///< floor(q_j / kCellWidth_rad) per joint (0 beyond the arm's) [-]
  int target = 0;                                ///< the reflector [-]
  bool operator==(const JointCell& other) const { return index == other.index && target == other.target; }
};

struct JointCellHash {
  std::size_t operator()(const JointCell& cell) const {
    std::uint64_t h = static_cast<std::uint64_t>(cell.target);
    for (const std::int64_t k : cell.index) h = (h ^ static_cast<std::uint64_t>(k)) * 0x9E3779B97F4A7C15ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

/// The cell index of a joint angle (joints are read within a turn or two: far from the int64 ends).
std::int64_t cell_index(double q_rad) {
  return static_cast<std::int64_t>(std::floor(std::clamp(q_rad, -1e12, 1e12) / kCellWidth_rad));
}

}  // namespace

std::vector<PoseReaches> group_reaches(Span<const Sample> samples, const std::vector<std::size_t>& lines, int joints,
                                       std::size_t* comparisons) {
  std::vector<PoseReaches> poses;
  std::unordered_map<JointCell, std::vector<std::size_t>, JointCellHash> cells;  // poses by their first reach's cell
  std::size_t compared = 0;
  for (const Sample& s : samples) {
    // The cells within the tolerance of s: its own, and per joint the neighbour whose edge is near.
    JointCell own{{}, s.target};
    std::array<int, kMaxJoints> low{};  // joints beyond the arm's: 0 .. 0, their cell 0
    std::array<int, kMaxJoints> high{};
    for (int j = 0; j < joints; ++j) {
      const std::int64_t k = cell_index(s.q_rad(j));
      own.index[static_cast<std::size_t>(j)] = k;
      const double from_lower_edge_rad = s.q_rad(j) - static_cast<double>(k) * kCellWidth_rad;
      low[static_cast<std::size_t>(j)] = from_lower_edge_rad <= kSamePoseTolerance_rad + kCellSlack_rad ? -1 : 0;
      high[static_cast<std::size_t>(j)] =
          kCellWidth_rad - from_lower_edge_rad <= kSamePoseTolerance_rad + kCellSlack_rad ? 1 : 0;
    }
    std::size_t latest = poses.size();  // none
    std::array<int, kMaxJoints> offset = low;
    for (bool more = true; more;) {
      JointCell cell = own;
      for (std::size_t j = 0; j < offset.size(); ++j) cell.index[j] += offset[j];
      if (const auto found = cells.find(cell); found != cells.end()) {
        for (const std::size_t p : found->second) {
          ++compared;
          if ((latest == poses.size() || p > latest) && same_point(poses[p].first, s)) latest = p;
        }
      }
      more = false;  // the next offset, joint 1 fastest
      for (std::size_t j = 0; j < offset.size() && !more; ++j) {
        more = offset[j] < high[j];
        offset[j] = more ? offset[j] + 1 : low[j];
      }
    }
    if (latest == poses.size()) {
      cells[own].push_back(poses.size());
      poses.push_back(PoseReaches{s, s.index < lines.size() ? lines[s.index] : 0, {}});
    }
    poses[latest].measured_m.push_back(s.point_m);
  }
  if (comparisons != nullptr) *comparisons = compared;
  return poses;
}

namespace {

std::string mm(double value_m) {
  char text[32];
  const double value_mm = std::fabs(value_m) < 0.5e-7 ? 0.0 : value_m * 1e3;  // no "-0.0000"
  std::snprintf(text, sizeof text, "%.4f", value_mm);
  return text;
}

/// ISO 9283's cycles per pose: fewer is warned of (RP_l from a few reaches is uncertain) [-].
constexpr std::size_t kIsoCycles = 30;
/// With --calibration, AP_P above this many times the calibration's own held-out MAE (3D)...
constexpr double kApBoundPerOwnMae = 10.0;
/// ...and above this, or above this alone when the result holds no metrics, is implausible [m].
constexpr double kApBoundFloor_m = 1e-3;

/// Where the commanded positions come from.
struct CommandFrame {
  record::CalibrationFile file;  ///< the model and base -> tracker
  std::string how;               ///< says which, for the output
  bool calibration = false;      ///< from --calibration (else the nominal model, base fitted to the reaches)
  double own_mae_m = 0.0;        ///< the calibration's own MAE (3D) from its metrics; 0: none [m]
  std::string own_mae_set;       ///< which samples that MAE is of: "held-out" or "training"
};

/// The calibration's own 3D MAE from result.json's "metrics": the held-out one, else the
/// training one (--split 1); 0 when the file has none (a description, a hand-made result).
void own_mae(const std::string& text, CommandFrame* frame) {
  textio::JsonValue root;
  if (!textio::parse_json(text, &root).ok() || root.find("metrics") == nullptr) return;
  for (const char* set : {"test", "train"}) {
    const textio::JsonValue* stats = root.find("metrics")->find(set);
    const textio::JsonValue* count = stats != nullptr ? stats->find(record::kErrorCountKey) : nullptr;
    const textio::JsonValue* mae = stats != nullptr ? stats->find("mae_m") : nullptr;
    const textio::JsonValue* mae_3d = mae != nullptr ? mae->find(record::kErrorAxisKeys[3]) : nullptr;
    if (count == nullptr || count->kind != textio::JsonValue::Kind::number || !(count->number > 0.0) ||
        mae_3d == nullptr || mae_3d->kind != textio::JsonValue::Kind::number || !(mae_3d->number > 0.0)) {
      continue;
    }
    frame->own_mae_m = mae_3d->number;
    frame->own_mae_set = std::string(set) == "test" ? "held-out" : "training";
    return;
  }
}

/// The command frame: a result's model and base -> tracker, or a nominal model (its tool:
/// --tool or --tool-transform, else a description file's, else kDefaultToolText) whose base ->
/// tracker fit_nominal_frame fits to the reaches.
Error command_frame(const Options& options, const textio::InputUnits& units, CommandFrame* frame) {
  if (!options.get("calibration").empty()) {
    if (tool_given(options)) {
      const std::string given = options.given("tool") ? "--tool" : "--tool-transform";
      return Error::usage(given +
                          " goes with --robot-model: a calibration result carries its own calibrated tool point (its "
                          "\"tool\"), which gives the commanded positions; leave " +
                          given + " out, or give --robot-model instead of --calibration");
    }
    frame->calibration = true;
    frame->how = "commanded positions from " + port::printable(options.get("calibration"), 4096) +
                 " (its model and base -> tracker)";
    std::string text;
    const Error read = record::read_calibration_json(options.get("calibration"), &frame->file, &text);
    if (read.ok()) own_mae(text, frame);
    return read;
  }
  bool from_file = false;
  std::string tool_note;
  Error error = robot_model_option(options, "robot-model", &frame->file, &from_file);
  if (error.ok()) {
    error = tool_point_option(options, units, from_file ? &frame->file.model.tool_m : nullptr,
                              &frame->file.model.tool_m, &tool_note);
  }
  if (!error.ok()) return error;
  const Vec3& tool_m = frame->file.model.tool_m;
  frame->how = "commanded positions from the nominal " + port::printable(frame->file.robot) + " (tool " +
               mm(tool_m.x()) + ", " + mm(tool_m.y()) + ", " + mm(tool_m.z()) +
               " mm; base -> tracker fitted to the reaches)" + (tool_note.empty() ? "" : "; " + tool_note);
  return Error{};
}

/// A nominal frame's base -> tracker, fitted to every reach (a calibration's is its own).
Error fit_nominal_frame(Span<const Sample> samples, CommandFrame* frame) {
  if (frame->calibration || fit_base_to_tracker(frame->file.model, samples, &frame->file.base_to_tracker) == Status::ok)
    return Error{};
  return Error::input("cannot fit the base -> tracker transform of the nominal model to the reaches (too few poses?)");
}

/// One pose's characteristics.
struct PoseResult {
  std::size_t pose = 0;   ///< index into the grouped poses [-]
  PoseAccuracy accuracy;  ///< AP and RP
};

/// Poses reached fewer than kIsoCycles times: a warning (the figures stand, their RP_l is uncertain); "" when none.
std::string cycles_warning(const std::vector<PoseResult>& results) {
  std::size_t short_poses = 0;
  std::size_t fewest = kIsoCycles;
  for (const PoseResult& r : results) {
    if (r.accuracy.cycles >= kIsoCycles) continue;
    ++short_poses;
    fewest = std::min(fewest, r.accuracy.cycles);
  }
  if (short_poses == 0) return "";
  return std::to_string(short_poses) + " of " + std::to_string(results.size()) + " poses have fewer than " +
         std::to_string(kIsoCycles) + " cycles (the fewest " + std::to_string(fewest) +
         "): ISO 9283 asks for 30 cycles per pose; RP_l from fewer reaches is uncertain (plan --iso9283 --cycles 30)";
}

/// The plausibility bound of AP_P with a calibration [m] and how it was set.
double ap_bound_m(const CommandFrame& frame, std::string* why) {
  const double bound_m = std::max(kApBoundFloor_m, kApBoundPerOwnMae * frame.own_mae_m);
  *why = frame.own_mae_m > 0.0 ? "10 x the calibration's own " + frame.own_mae_set + " MAE of " + mm(frame.own_mae_m) +
                                     " mm, at least 1 mm"
                               : "1 mm: the calibration holds no metrics";
  return bound_m;
}

/// With --calibration: when a pose's AP_P is beyond the plausibility bound (ap_bound_m), the
/// warning that makes the run exit 5, naming the cause (the base -> tracker registered again on
/// these reaches says whether the frame or the model is at fault) and the remedy; "" otherwise.
std::string frame_warning(const Options& options, const CommandFrame& frame, Span<const Sample> samples,
                          const std::vector<PoseReaches>& poses, const std::vector<PoseResult>& results) {
  if (!frame.calibration) return "";  // the nominal frame is fitted to these reaches
  std::string bound_why;
  const double bound_m = ap_bound_m(frame, &bound_why);
  std::size_t beyond = 0;
  const PoseResult* worst = &results.front();
  for (const PoseResult& r : results) {
    if (r.accuracy.accuracy_norm_m > bound_m) ++beyond;
    if (r.accuracy.accuracy_norm_m > worst->accuracy.accuracy_norm_m) worst = &r;
  }
  if (beyond == 0) return "";
  char head[400];
  std::snprintf(head, sizeof head,
                "%zu of %zu poses have AP_P beyond the plausibility bound %s mm (%s); the worst %s mm at pose %zu "
                "(line %zu): ",
                beyond, results.size(), mm(bound_m).c_str(), bound_why.c_str(),
                mm(worst->accuracy.accuracy_norm_m).c_str(), worst->pose + 1, poses[worst->pose].line);
  const std::string calibration = options.get("calibration");
  const std::string register_again = "hivecal calibrate --robot-model " + calibration + " --fit base --samples " +
                                     options.get("samples") + " --out registered.json";
  RigidTransform registered;
  if (fit_base_to_tracker(frame.file.model, samples, &registered) != Status::ok) {
    return head +
           std::string(
               "the calibration does not match these measurements (the base -> tracker could not be "
               "registered on them to tell why); if the tracker was set up anew, register the base "
               "again (") +
           register_again + ")";
  }
  double moved_m = 0.0;  // how far the registration moves a commanded point
  double worst_registered_m = 0.0;
  for (const PoseResult& r : results) {
    const Vec3 base_point = fk_sample_point(frame.file.model, poses[r.pose].first);
    moved_m = std::max(moved_m, (registered.apply(base_point) - frame.file.base_to_tracker.apply(base_point)).norm());
    worst_registered_m = std::max(worst_registered_m, (r.accuracy.barycentre_m - registered.apply(base_point)).norm());
  }
  const std::string registration =
      "registered again on these reaches, the base -> tracker moves the commanded "
      "points by up to " +
      mm(moved_m) + " mm and leaves a worst AP_P of " + mm(worst_registered_m) + " mm";
  if (worst_registered_m <= bound_m) {
    return head + std::string("the base -> tracker of ") + calibration + " does not match these measurements (" +
           registration +
           "): the tracker was set up anew or moved since the calibration. Register the base again on these "
           "measurements, keeping the arm (" +
           register_again + "), then run iso9283 with that result";
  }
  return std::string(head) + "the calibration does not predict these poses, not even with its base registered again (" +
         registration +
         "): another robot, tool or unit, or poses far outside the calibration's own? If the tracker was set up "
         "anew, register the base again (" +
         register_again + ")";
}

/// The outputs of one run: the table (CSV) and, with --report, the page.
std::string table_csv(const std::vector<std::vector<std::string>>& rows) {
  std::string table;
  for (const std::vector<std::string>& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) table += row[c] + (c + 1 < row.size() ? "," : "\n");
  }
  return table;
}

std::string report_page(const std::string& how, const std::string& summary, const std::vector<std::string>& warnings,
                        const std::vector<std::vector<std::string>>& rows) {
  std::string items = "<li>" + report::xml_escape(how) + "</li>\n<li>" + report::xml_escape(summary) + "</li>\n";
  for (const std::string& warning : warnings) items += "<li>warning: " + report::xml_escape(warning) + "</li>\n";
  return report::html_page_head("ISO 9283 pose accuracy and repeatability") + "<ul>\n" + items + "</ul>\n" +
         report::html_table(rows) +
         "<p>AP_P: distance of the reaches' barycentre from the commanded position; RP_l = "
         "mean distance of the reaches from their barycentre + 3 S_l (ISO 9283; docs/iso9283.md)."
         "</p>\n</body>\n</html>\n";
}

/// The analysis. `*warnings`: printed after the outputs are written; `*implausible`: the frame
/// check failed (exit 5, every output written).
Error iso9283(const Options& options, std::vector<std::string>* warnings, bool* implausible) {
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
  CommandFrame frame;  // its model first: the reaches carry its joints
  if (error.ok()) error = command_frame(options, units, &frame);
  units.joints = textio::input_joints(frame.file.model);
  std::vector<std::size_t> lines;
  if (error.ok()) error = textio::read_samples_csv(options.get("samples"), &dataset, units, &lines);
  if (error.ok()) error = fit_nominal_frame(dataset.samples(), &frame);
  if (!error.ok()) return error;
  const std::vector<PoseReaches> poses = group_reaches(dataset.samples(), lines, frame.file.model.joint_count);
  std::vector<PoseResult> results;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const PoseReaches& p = poses[k];
    PoseResult r{k, {}};
    const Vec3 commanded = frame.file.base_to_tracker.apply(fk_sample_point(frame.file.model, p.first));
    // One reach: no repeatability, left out (counted).
    if (pose_accuracy(Span<const Vec3>(p.measured_m.data(), p.measured_m.size()), commanded, &r.accuracy) ==
        Status::ok) {
      results.push_back(r);
    }
  }
  if (results.empty()) {
    return Error::input(options.get("samples") +
                        ": no pose was reached twice (ISO 9283 needs the cycles of each pose; " +
                        std::to_string(poses.size()) + " poses, one reach each)");
  }
  std::vector<std::vector<std::string>> rows = {
      {"pose", "line", "target", "cycles", "AP_P [mm]", "AP_x [mm]", "AP_y [mm]", "AP_z [mm]", "RP_l [mm]"}};
  double worst_ap_m = 0.0;
  double worst_rp_m = 0.0;
  for (const PoseResult& r : results) {
    const PoseAccuracy& a = r.accuracy;
    const PoseReaches& p = poses[r.pose];
    worst_ap_m = std::max(worst_ap_m, a.accuracy_norm_m);
    worst_rp_m = std::max(worst_rp_m, a.repeatability_m);
    rows.push_back({std::to_string(r.pose + 1), std::to_string(p.line), std::to_string(p.first.target + 1),
                    std::to_string(a.cycles), mm(a.accuracy_norm_m), mm(a.accuracy_m.x()), mm(a.accuracy_m.y()),
                    mm(a.accuracy_m.z()), mm(a.repeatability_m)});
  }
  const std::string summary = std::to_string(results.size()) + " poses with repeated reaches (" +
                              std::to_string(poses.size() - results.size()) +
                              " with one reach, left out); worst AP_P " + mm(worst_ap_m) + " mm, worst RP_l " +
                              mm(worst_rp_m) + " mm";
  const std::string frame_problem = frame_warning(options, frame, dataset.samples(), poses, results);
  *implausible = !frame_problem.empty();
  for (const std::string& warning : {cycles_warning(results), frame_problem})
    if (!warning.empty()) warnings->push_back(warning);
  std::fprintf(options.get("out") == "-" ? stderr : stdout, "%s\n%s\n", frame.how.c_str(), summary.c_str());
  error = outputs.stage_text(out_id, "", table_csv(rows));
  if (error.ok() && report_id != kNoReport)
    error = outputs.stage_text(report_id, "", report_page(frame.how, summary, *warnings, rows));
  return error.ok() ? outputs.commit() : error;
}

/// The smallest cube side of the test: P2..P5 then lie 14 mm from P1 (a smaller cube tests one
/// point several times over); the side auto starts from [m].
constexpr double kMinCubeSide_m = 0.02;

/// The cube of `--iso9283 X,Y,Z,SIDE` [m]: each coordinate of its centre within 10 m of the
/// base, its side within [kMinCubeSide_m, 10] (cli::check_numbers: a bad number is named).
Error cube_option(const Options& options, Vec3* centre_m, double* side_m) {
  const NumberRange coordinate{-10.0, 10.0, false, false, "m"};
  double values[4] = {};
  const Error error = check_numbers("--iso9283", options.get("iso9283"),
                                    "the cube's centre in the base frame and its side, in metres; or auto",
                                    {{"X", coordinate},
                                     {"Y", coordinate},
                                     {"Z", coordinate},
                                     {"SIDE", NumberRange{kMinCubeSide_m, 10.0, false, false, "m"}}},
                                    values);
  if (!error.ok()) return error;
  *centre_m = Vec3(values[0], values[1], values[2]);
  *side_m = values[3];
  return Error{};
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

/// What stands in the way of one position of the test.
enum class PositionVerdict { reachable, below_floor, inside_keep_out, unreachable };

/// Whether the reflector may be at `p` (above --floor-z, outside --keep-out-radius) and the arm
/// reaches it with the orientation `rotation` within the limits (*q: its joints).
PositionVerdict check_position(const RobotModel& model, const JointLimits& limits, const Vec3& p, const Vec3& rotation,
                               double floor_z_m, double keep_out_m, Random* random, JointVector* q) {
  if (p.z() < floor_z_m) return PositionVerdict::below_floor;
  if (p.head<2>().norm() < keep_out_m) return PositionVerdict::inside_keep_out;
  return reach(model, limits, p, rotation, random, q) ? PositionVerdict::reachable : PositionVerdict::unreachable;
}

/// Whether the arm reaches all five positions of the cube with the one orientation, above the
/// floor and outside the keep-out cylinder.
bool cube_reachable(const RobotModel& model, const JointLimits& limits, const Vec3& centre_m, double side_m,
                    const Vec3& rotation, double floor_z_m, double keep_out_m, Random* random) {
  Vec3 positions[5];
  iso_positions(centre_m, side_m, positions);
  for (const Vec3& p : positions) {
    JointVector q;
    if (check_position(model, limits, p, rotation, floor_z_m, keep_out_m, random, &q) != PositionVerdict::reachable)
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
    for (int j = 0; j < model.joint_count; ++j) q(j) = random.uniform(limits.lower_rad(j), limits.upper_rad(j));
    const Vec3 centre = fk_tool_point(model, q);
    const Vec3 rotation = tool_rotation_vector(centre, tracker_m, tool_down);
    if (!cube_reachable(model, limits, centre, std::max(*side_m, kMinCubeSide_m), rotation, floor_z_m, keep_out_m,
                        &random))
      continue;
    double low = std::max(*side_m, kMinCubeSide_m);
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

/// A value as an option gives it (0.05, not 0.050000000000000003).
std::string general_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

/// Why the given cube cannot be the test: each position below the floor, inside the keep-out
/// cylinder or out of reach, and what to do; "" when every position is reachable.
std::string cube_problems(const Options& options, const Vec3 (&positions)[5], const PositionVerdict (&verdicts)[5],
                          double floor_z_m, double keep_out_m, const std::string& cause) {
  const std::pair<PositionVerdict, std::string> reasons[] = {
      {PositionVerdict::below_floor, "below --floor-z " + general_number(floor_z_m) + " m"},
      {PositionVerdict::inside_keep_out, "inside --keep-out-radius " + general_number(keep_out_m) + " m"},
      {PositionVerdict::unreachable, "out of the arm's reach with the one orientation within the joint limits"}};
  std::string problems;
  for (const auto& [verdict, reason] : reasons) {
    std::string which;
    for (int k = 0; k < 5; ++k) {
      if (verdicts[k] != verdict) continue;
      char where[120];
      std::snprintf(where, sizeof where, "P%d (%.4f, %.4f, %.4f m)", k + 1, positions[k].x(), positions[k].y(),
                    positions[k].z());
      which += (which.empty() ? "" : ", ") + std::string(where);
    }
    if (!which.empty()) problems += which + ": " + reason + "; ";
  }
  if (problems.empty()) return "";
  return "--iso9283 " + options.get("iso9283") + ": " + problems + (cause.empty() ? std::string() : cause + "; ") +
         "the test needs all five positions: choose another cube (smaller, or nearer the middle of the arm's "
         "workspace), or --iso9283 auto (the largest cube the arm reaches)";
}

Error plan_iso9283(const Options& options, const RobotModel& model, const JointLimits& limits,
                   const JointLimits& widest) {
  Vec3 centre_m;
  double side_m = 0.0;
  const bool automatic = options.get("iso9283") == "auto";
  Error error = automatic ? Error{} : cube_option(options, &centre_m, &side_m);
  if (!error.ok()) return error;
  Vec3 tracker_m;
  std::size_t cycles = 0;
  double dwell_s = 0.0;
  double speed = 0.0;
  double acceleration = 0.0;
  error = vec3_option(options, "tracker-position", &tracker_m);
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
  const bool tool_down = options.given("tool-down");
  if (automatic && !largest_cube(model, limits, tracker_m, tool_down, floor_z_m, keep_out_m, &centre_m, &side_m)) {
    const std::string cause =
        blame_tool_or_limits(options, model, limits, widest, [&](const RobotModel& m, const JointLimits& l) {
          Vec3 centre;
          double side = 0.0;
          return largest_cube(m, l, tracker_m, tool_down, floor_z_m, keep_out_m, &centre, &side);
        });
    return Error::failure("--iso9283 auto: no cube whose five positions the arm reaches with one orientation (" +
                          (cause.empty() ? "move the tracker, lower --floor-z or --keep-out-radius" : cause) + ")");
  }
  Vec3 positions[5];
  iso_positions(centre_m, side_m, positions);
  const Vec3 rotation = tool_rotation_vector(centre_m, tracker_m, tool_down);
  // Each position with a joint solution of the model (the controller's own IK moves the arm;
  // these say that one exists within the limits, and let `predict` check the list). A given
  // cube is checked as auto's are: nothing is written for a position the arm cannot take.
  const auto check_cube = [&](const RobotModel& m, const JointLimits& l, PositionVerdict(&verdicts)[5],
                              JointVector(&q)[5]) {
    Random random(9283);
    bool all = true;
    for (int k = 0; k < 5; ++k) {
      verdicts[k] = check_position(m, l, positions[k], rotation, floor_z_m, keep_out_m, &random, &q[k]);
      all = all && verdicts[k] == PositionVerdict::reachable;
    }
    return all;
  };
  PositionVerdict verdicts[5];
  JointVector q[5];
  if (!check_cube(model, limits, verdicts, q)) {
    bool out_of_reach = false;
    for (const PositionVerdict v : verdicts) out_of_reach = out_of_reach || v == PositionVerdict::unreachable;
    const std::string cause = !out_of_reach ? std::string()
                                            : blame_tool_or_limits(options, model, limits, widest,
                                                                   [&](const RobotModel& m, const JointLimits& l) {
                                                                     PositionVerdict other[5];
                                                                     JointVector other_q[5];
                                                                     return check_cube(m, l, other, other_q);
                                                                   });
    return Error::failure(cube_problems(options, positions, verdicts, floor_z_m, keep_out_m, cause));
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  std::size_t script_id = 0;
  const bool script = !options.get("urscript").empty();
  error = declare_inputs(options, {"out", "urscript", "svg"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (error.ok() && script) error = outputs.add_file(options.get("urscript"), "--urscript", &script_id);
  if (!error.ok()) return error;
  std::string list = "pose,x,y,z,rx,ry,rz";
  for (int j = 0; j < model.joint_count; ++j) list += ",q" + std::to_string(j + 1);
  list += "\n";
  for (int k = 0; k < 5; ++k) {
    list += "P" + std::to_string(k + 1) + "," + textio::format_double(positions[k].x()) + "," +
            textio::format_double(positions[k].y()) + "," + textio::format_double(positions[k].z()) + "," +
            textio::format_double(rotation.x()) + "," + textio::format_double(rotation.y()) + "," +
            textio::format_double(rotation.z());
    for (int j = 0; j < model.joint_count; ++j) list += "," + textio::format_double(q[k](j));
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
      {"samples", "FILE",
       "measured reaches: paired samples q1..qN (the arm's N joints),x,y,z, every commanded pose reached several times",
       ""},
      {"calibration", "FILE", "command frame: a calibration result (its model and base -> tracker)", ""},
      {"robot-model", "NAME|FILE", "or the nominal model, its base -> tracker fitted to the reaches", "ur5"},
      {"out", "FILE", "per-pose table (CSV: AP_P, AP_x/y/z, RP_l in mm); '-' for stdout", "-"},
      {"report", "FILE", "the same as an HTML page in the calibration report's style", ""},
  };
  const std::vector<OptionSpec> tool = tool_option_specs(
      "with --robot-model: the reflector in the flange frame [m] (a description file's when not given; not with "
      "--calibration, whose tool is calibrated)");
  specs.insert(specs.begin() + 3, tool.begin(), tool.end());  // after --robot-model
  for (const OptionSpec& unit : input_unit_option_specs()) specs.push_back(unit);
  Options options;
  const int parsed = parse_options(kIso9283Command,
                                   "ISO 9283 pose accuracy (AP_P: barycentre of the reaches - commanded position) and\n"
                                   "repeatability (RP_l = mean distance from the barycentre + 3 S_l) of each pose of\n"
                                   "the measured reaches (samples at the same joints within 1e-3 rad are one pose).",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  std::vector<std::string> warnings;
  bool implausible = false;
  const int code = exit_with(kIso9283Command, iso9283(options, &warnings, &implausible));
  if (code != kExitOk) return code;
  for (const std::string& warning : warnings) error(kIso9283Command, "warning: " + warning);
  return implausible ? kExitWarnings : kExitOk;
}

}  // namespace hivecal::cli
