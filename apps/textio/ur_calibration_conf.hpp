// Reader of the [mounting] section of a UR controller's calibration.conf.
#pragma once

#include <string>

#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "hivecal/port/error.hpp"  // every parse returns a port::Error (Fault::input naming file and line)

namespace hivecal::textio {

/// The joints of `model` in words: "7 revolute joints", "7 joints, joint 1 prismatic".
std::string joint_shape(const RobotModel& model);
/// Fault::usage unless `model` has a UR's joints (has_ur_joints: six revolute): "`feature` is a
/// Universal Robots controller's (six revolute joints); `model_name` has 7 revolute joints".
port::Error require_ur_joints(const RobotModel& model, const std::string& model_name, const std::string& feature);

/// Parses calibration.conf text; needs delta_theta, delta_a, delta_d and delta_alpha in
/// [mounting], six finite numbers each. `source_name` prefixes error messages.
port::Error parse_ur_calibration_conf(const std::string& text, const std::string& source_name,
                                      UrCalibrationDeltas* deltas);

/// Reads and parses a calibration.conf file.
port::Error read_ur_calibration_conf(const std::string& path, UrCalibrationDeltas* deltas);

/// Largest tool displacement a calibration.conf may cause against the nominal model [m]: a
/// controller calibration corrects millimetres; more is another arm's file (or a broken one).
constexpr double kMaxUrDeltaToolShift_m = 0.05;
/// Test poses over which the displacement is measured (seeded, joints uniform in +-pi).
constexpr int kUrDeltaTestPoses = 64;

/// Largest distance between the tool point of `nominal` and of `nominal` + `deltas` over the
/// test poses [m] (both with nominal's tool; FK in double: UR deltas cancel by metres).
double ur_deltas_tool_shift_m(const RobotModel& nominal, const UrCalibrationDeltas& deltas);

/// Fault::input naming `source_name` when the deltas move the tool by more than
/// kMaxUrDeltaToolShift_m ("not a calibration of this robot model?"); `model_name` is named
/// in the message.
port::Error check_ur_deltas_plausible(const RobotModel& nominal, const UrCalibrationDeltas& deltas,
                                      const std::string& source_name, const std::string& model_name);

/// `nominal` with the deltas of the calibration.conf at `path` applied, after reading it and
/// check_ur_deltas_plausible (messages name `path` and `model_name`). The deltas are UR's, in
/// UR's table: a `nominal` turned by pi (is_ur_table_turned) gets them in UR's table and is
/// turned back, so *calibrated stays in nominal's base.
port::Error read_ur_calibrated_model(const std::string& path, const RobotModel& nominal, const std::string& model_name,
                                     RobotModel* calibrated);

/// The calibration.conf deltas that turn `nominal` into `calibrated` (two models of one arm in
/// one base), in UR's table: a pair turned by pi (is_ur_table_turned of `nominal`) is turned
/// back first, so that the controller, which applies them to its own table, gets their signs.
UrCalibrationDeltas ur_deltas_in_ur_table(const RobotModel& nominal, const RobotModel& calibrated);

/// Writes deltas in calibration.conf's [mounting] syntax (%.17g).
std::string format_ur_calibration_conf(const UrCalibrationDeltas& deltas);

}  // namespace hivecal::textio
