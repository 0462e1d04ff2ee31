// The robot description of a serial arm of 1 .. kMaxJoints revolute or prismatic joints, format "robot-calibration/1"
// (docs/formats.md): the DH table, tool points, compliance and joint limits. A result file (record/result_json.hpp) is
// a description with the fit's members added, so a result is also a valid start model.
#pragma once

#include <string>

#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/kinematics.hpp"
#include "textio/json.hpp"
#include "textio/ur_calibration_conf.hpp"  // port::Error

namespace hivecal::textio {

/// A robot description: the DH table (a row per joint, each revolute or prismatic) and tool of
/// an arm, in either convention. The
/// library works on the standard-DH `model`; a modified-DH file is converted exactly
/// (model/dh_convention.hpp) and written back in its own convention.
struct RobotDescription {
  std::string robot = "ur5";                         ///< name ("ur5", "abb-irb120", ...; free text)
  DhConvention convention = DhConvention::standard;  ///< how the file writes its rows
  ModifiedDhBase modified_base;                      ///< modified DH: Rx(alpha_0) Tx(a_0) before joint 1
  RobotModel model;                                  ///< the standard-DH table, tool point and compliance [m, rad]
  int target_count = 1;           ///< targets whose tool points `model` holds, 1 .. kMaxTargets ("tools" when > 1) [-]
  bool has_joint_limits = false;  ///< the file gave "joint_limits" (URDF: <limit>), one pair per joint
  /// A UR arm read from a URDF whose root is UR's base turned by pi about z (ROS's base_link):
  /// the model is UR's table in UR's own base (textio::is_ur_table_turned), not in the root's.
  bool base_turned_by_pi = false;
  /// Lowest joint positions [rad], a prismatic joint's [m] (without "joint_limits": -2 pi).
  JointVector lower_rad = JointVector::Constant(-2.0 * math::kPi);
  /// Highest joint positions [rad], a prismatic joint's [m] (without "joint_limits": 2 pi).
  JointVector upper_rad = JointVector::Constant(2.0 * math::kPi);
};

/// What a robot description may hold, from JSON or URDF alike: beyond it is no robot and would
/// predict NaN or nonsense in silence. Lengths: real factory calibrations carry cancelling
/// offsets of hundreds of metres on UR's parallel joints (+/-204 m), so 1 km [m].
inline constexpr double kMaxModelLength_m = 1000.0;
/// Angles (DH offsets and twists, URDF's rpy): two turns; more is degrees [rad].
inline constexpr double kMaxModelAngle_rad = 4.0 * math::kPi;
/// Each coordinate of a tool point in the flange frame; more is millimetres [m].
inline constexpr double kMaxToolLength_m = 10.0;
/// What a bounded number of a robot description is.
enum class ModelQuantity { length, angle, tool };
/// "" when |value| is within the bound of its quantity; else what a refusal says after the key:
/// " = V m is beyond 1000 m: not a robot" (angles: "... rad (two turns): degrees?", tool
/// points: "...: millimetres?"). NaN is beyond every bound.
std::string beyond_bound(double value, ModelQuantity quantity);
/// Fault::input naming `source`, the row and the key, unless every DH number as the description's
/// convention writes it and every tool point is within its bound.
port::Error check_model_bounds(const RobotDescription& description, const std::string& source);

/// The JSON name of a convention: "standard-dh" or "modified-dh".
const char* dh_convention_name(DhConvention convention);
/// Parses a robot description (format optional; "robot" optional, any name, "" when absent;
/// "convention" optional, standard-dh by default); errors name the file and the key at fault.
port::Error parse_robot_description(const std::string& text, const std::string& source_name,
                                    RobotDescription* description);
/// Reads and parses a robot description file; without "robot" the arm is named after the
/// file ("irb120" for .../irb120.json).
port::Error read_robot_description(const std::string& path, RobotDescription* description);
/// `--robot-model VALUE`: a built-in table name (ur5, iiwa14, ...; tool at the flange; in the
/// maker's convention, with the maker's joint limits where published; it wins over a file or
/// folder of that name, which `./ur5` names) or a file (an existing path, or a name ending in
/// .json or .urdf). Usage-style errors name the value. *from_file (optional) says which it was.
port::Error robot_description_from_value(const std::string& value, RobotDescription* description,
                                         bool* from_file = nullptr);

/// A robot description document (what --robot-model reads): the result's shape without
/// base_to_tracker and metrics.
std::string format_robot_description(const RobotDescription& robot);
/// Writes the members every robot-calibration/1 document holds (format, robot, convention, dh
/// (a "type" in every row when a joint is prismatic), tool, tools with several targets,
/// compliance with terms, joint_limits when given) into the
/// open top-level object. `compliance_sigma` (optional): each coefficient's sigma, written when > 0.
void write_description_members(JsonWriter& json, const RobotDescription& description,
                               const double* compliance_sigma = nullptr);
/// Parses a robot-calibration/1 document's description members; `format_required`: "format"
/// must be present (a result) rather than optional (a description). *root receives the parsed
/// document for the caller's own members. Errors name the file and the key at fault.
port::Error parse_description_document(const std::string& text, const std::string& source_name, bool format_required,
                                       RobotDescription* description, JsonValue* root);

/// The "compliance" object of a model with compliance terms (docs/formats.md): "kind"
/// (basis | masses), "gravity_direction", "terms" (name, joint 1-based, load, coefficient,
/// unit, sigma when `sigma` holds one > 0) and, for masses, "masses" (one link per joint of
/// `model`). `to_file_base` turns the library's base frame into the file's (modified DH:
/// modified_base's rotation).
void write_compliance(JsonWriter& json, const RobotModel& model, const Mat3& to_file_base,
                      const double* sigma = nullptr);
/// Reads a "compliance" object written by write_compliance into *compliance (checked with
/// check_compliance for the joints of `model`); false with *what naming the fault otherwise.
bool read_compliance(const JsonValue& value, const Mat3& to_file_base, const RobotModel& model,
                     ComplianceModel* compliance, std::string* what);
/// The unit of a compliance coefficient: "rad/m" (point loads) or "rad/(kg m)" (arm masses).
const char* compliance_unit(ComplianceLoad load);
/// The unit of term t's coefficient: its load's (compliance_unit), or "rad" for a harmonic.
const char* term_unit(const ComplianceModel& compliance, int t);
/// The name of a load kind on the command line and in "kind": "basis" or "masses".
const char* compliance_kind_name(ComplianceLoad load);

}  // namespace hivecal::textio
