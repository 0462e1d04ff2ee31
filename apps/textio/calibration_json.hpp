// The calibration result file, format "robot-calibration/1" (docs/formats.md).
#pragma once

#include <functional>
#include <string>

#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/metrics.hpp"
#include "textio/json.hpp"
#include "textio/ur_calibration_conf.hpp"  // port::Error

namespace hivecal::textio {

/// What a result file must hold to predict positions, plus its accuracy figures.
struct CalibrationFile {
  RobotType robot = RobotType::ur5;  ///< robot type of the nominal model
  RobotModel model;                  ///< calibrated DH table and tool point
  RigidTransform base_to_tracker;    ///< robot base -> tracker frame
  bool has_metrics = false;          ///< metrics below were present / are to be written
  AccuracyReport metrics;            ///< train / test / overall error statistics [m]
};

/// The JSON document; `extra_members` may add more keys to the top-level object.
std::string format_calibration_json(const CalibrationFile& file,
                                    const std::function<void(JsonWriter&)>& extra_members = {});
/// Parses and validates a result document (six DH rows, finite numbers, a proper rigid
/// 4x4 transform within 1e-5, re-orthonormalised); errors name the key at fault.
port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file);
/// Reads and parses a result file.
port::Error read_calibration_json(const std::string& path, CalibrationFile* file);

/// Writes one ErrorStats as {"count", "mae_m": {x, y, z, 3d}, "sigma_m": {...}, "max_m": {...}}.
void write_error_stats(JsonWriter& json, const ErrorStats& stats);

}  // namespace hivecal::textio
