// The calibration result file, format "robot-calibration/1" (docs/formats.md), and the robot
// description of any 6-axis arm in the same shape (a result is also a valid start model).
#pragma once

#include <functional>
#include <string>

#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "textio/json.hpp"
#include "textio/ur_calibration_conf.hpp"  // port::Error

namespace hivecal::textio {

/// A robot description: the DH table and tool of a 6-axis arm, in either convention. The
/// library works on the standard-DH `model`; a modified-DH file is converted exactly
/// (model/dh_convention.hpp) and written back in its own convention.
struct RobotDescription {
  std::string robot = "ur5";                         ///< name ("ur5", "abb-irb120", ...; free text)
  DhConvention convention = DhConvention::standard;  ///< how the file writes its rows
  ModifiedDhBase modified_base;                      ///< modified DH: Rx(alpha_0) Tx(a_0) before joint 1
  RobotModel model;                                  ///< the standard-DH table, tool point and compliance [m, rad]
  int target_count = 1;           ///< targets whose tool points `model` holds, 1 .. kMaxTargets ("tools" when > 1) [-]
  bool has_joint_limits = false;  ///< the file gave "joint_limits" (URDF: <limit>)
  JointVector lower_rad = JointVector::Constant(-2.0 * math::kPi);  ///< lowest joint positions [rad]
  JointVector upper_rad = JointVector::Constant(2.0 * math::kPi);   ///< highest joint positions [rad]
};

/// What a result file must hold to predict positions, plus its accuracy figures.
struct CalibrationFile : RobotDescription {
  /// Base of the standard-DH chain -> tracker frame: predicted = base_to_tracker * FK(model)
  /// (for a modified-DH file, the file's own base -> tracker times modified_base).
  RigidTransform base_to_tracker;
  bool has_metrics = false;  ///< metrics below were present / are to be written
  AccuracyReport metrics;    ///< train / test / overall error statistics [m]
  /// Standard deviation of each compliance coefficient (model.compliance's unit); 0: unknown,
  /// not written.
  double compliance_sigma[kMaxComplianceTerms] = {};
};

/// The JSON name of a convention: "standard-dh" or "modified-dh".
const char* dh_convention_name(DhConvention convention);
/// Parses a robot description (format optional; "robot" optional, any name, "" when absent;
/// "convention" optional, standard-dh by default); errors name the file and the key at fault.
port::Error parse_robot_description(const std::string& text, const std::string& source_name,
                                    RobotDescription* description);
/// Reads and parses a robot description file; without "robot" the arm is named after the
/// file ("irb120" for .../irb120.json).
port::Error read_robot_description(const std::string& path, RobotDescription* description);
/// `--robot-model VALUE`: a file (an existing path, or a name ending in .json) or a built-in
/// table name (ur5, ...; tool at the flange). Usage-style errors name the value. *from_file
/// (optional) says which it was.
port::Error robot_description_from_value(const std::string& value, RobotDescription* description,
                                         bool* from_file = nullptr);

/// A robot description document (what --robot-model reads): the result's shape without
/// base_to_tracker and metrics.
std::string format_robot_description(const RobotDescription& robot);
/// The JSON document; `extra_members` may add more keys to the top-level object.
std::string format_calibration_json(const CalibrationFile& file,
                                    const std::function<void(JsonWriter&)>& extra_members = {});
/// Parses and validates a result document (six DH rows, finite numbers, a proper rigid
/// 4x4 transform within 1e-5, re-orthonormalised); errors name the key at fault.
port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file);
/// Reads and parses a result file; `text` (optional) receives the file's text, for the keys
/// the caller reads itself (e.g. "report").
port::Error read_calibration_json(const std::string& path, CalibrationFile* file, std::string* text = nullptr);

/// The "compliance" object of a model with compliance terms (docs/formats.md): "kind"
/// (basis | masses), "gravity_direction", "terms" (name, joint 1-based, load, coefficient,
/// unit, sigma when `sigma` holds one > 0) and, for masses, "masses". `to_file_base` turns the
/// library's base frame into the file's (modified DH: modified_base's rotation).
void write_compliance(JsonWriter& json, const ComplianceModel& compliance, const Mat3& to_file_base,
                      const double* sigma = nullptr);
/// Reads a "compliance" object written by write_compliance into *compliance (checked with
/// check_compliance); false with *what naming the fault otherwise.
bool read_compliance(const JsonValue& value, const Mat3& to_file_base, ComplianceModel* compliance, std::string* what);
/// The unit of a compliance coefficient: "rad/m" (point loads) or "rad/(kg m)" (arm masses).
const char* compliance_unit(ComplianceLoad load);
/// The name of a load kind on the command line and in "kind": "basis" or "masses".
const char* compliance_kind_name(ComplianceLoad load);

/// Writes one ErrorStats as {"count", "mae_m": {x, y, z, 3d}, "sigma_m": {...}, "max_m": {...}}.
void write_error_stats(JsonWriter& json, const ErrorStats& stats);

}  // namespace hivecal::textio
