// Reader of the [mounting] section of a UR controller's calibration.conf.
#pragma once

#include <string>

#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "hivecal/port/error.hpp"  // every parse returns a port::Error (Fault::input naming file and line)

namespace hivecal::textio {

/// Parses calibration.conf text; needs delta_theta, delta_a, delta_d and delta_alpha in
/// [mounting], six finite numbers each. `source_name` prefixes error messages.
port::Error parse_ur_calibration_conf(const std::string& text, const std::string& source_name,
                                      UrCalibrationDeltas* deltas);

/// Reads and parses a calibration.conf file.
port::Error read_ur_calibration_conf(const std::string& path, UrCalibrationDeltas* deltas);

/// Writes deltas in calibration.conf's [mounting] syntax (%.17g).
std::string format_ur_calibration_conf(const UrCalibrationDeltas& deltas);

}  // namespace hivecal::textio
