// A rigid transform as a lab writes it in a text file: a 4x4 homogeneous matrix, one row per
// line (e.g. a flange -> probe transform from a hand-eye calibration). docs/formats.md, "Tool
// transform".
#pragma once

#include <string>

#include "hivecal/core/types.hpp"
#include "hivecal/port/error.hpp"
#include "textio/delimited.hpp"

namespace hivecal::textio {

/// Reads a 4x4 homogeneous transform: four lines of four numbers (blanks, commas or
/// semicolons between them; blank lines and lines starting with '#' skipped), the last row
/// 0 0 0 1, the rotation orthonormal within 1e-5 with det > 0 (then made exactly orthonormal).
/// The translation is in units.length ("m" when not declared); a translation beyond
/// kMaxPointDistance_m read in metres is refused with the --length-unit mm hint. Errors name
/// the file and line (Fault::input).
port::Error read_transform_text(const std::string& path, const InputUnits& units, RigidTransform* transform);

}  // namespace hivecal::textio
