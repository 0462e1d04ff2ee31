#include "textio/transform_text.hpp"

#include <cmath>
#include <cstdio>
#include <string_view>
#include <vector>

#include "hivecal/model/rigid_fit.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

/// The fields of a line split at blanks, commas and semicolons.
std::vector<std::string_view> fields_of(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t at = 0;
  for (;;) {
    at = line.find_first_not_of(" \t\r,;", at);
    if (at == std::string_view::npos) return fields;
    const std::size_t stop = std::min(line.find_first_of(" \t\r,;", at), line.size());
    fields.push_back(line.substr(at, stop - at));
    at = stop;
  }
}

}  // namespace

port::Error read_transform_text(const std::string& path, const InputUnits& units, RigidTransform* transform) {
  LineReader lines;
  if (!lines.open(path, port::kMaxTextInputBytes)) return port::Error::input(lines.error());
  double m[4][4] = {};
  int rows = 0;
  std::string_view line;
  while (lines.next(&line)) {
    line = trim(line);
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = fields_of(line);
    if (rows == 4) return port::Error::input(lines.where() + "more than four rows: not a 4x4 transform");
    if (fields.size() != 4) {
      return port::Error::input(lines.where() + std::to_string(fields.size()) +
                                " numbers where a row of a 4x4 transform has 4");
    }
    for (int c = 0; c < 4; ++c) {
      if (!parse_double(fields[static_cast<std::size_t>(c)], &m[rows][c]) || !std::isfinite(m[rows][c])) {
        return port::Error::input(lines.where() + "not a number: " + port::quoted(fields[static_cast<std::size_t>(c)]));
      }
    }
    ++rows;
  }
  if (!lines.error().empty()) return port::Error::input(lines.error());
  if (rows != 4) {
    return port::Error::input(path + ": " + std::to_string(rows) + " rows, expected 4 (a 4x4 homogeneous transform)");
  }
  Mat3 rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = m[r][c];
  }
  const bool last_row = m[3][0] == 0.0 && m[3][1] == 0.0 && m[3][2] == 0.0 && m[3][3] == 1.0;
  const double orthonormality = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!last_row || !(orthonormality <= 1e-5) || !(rotation.determinant() > 0.0)) {
    char what[120];
    std::snprintf(what, sizeof what, "last row %s, rotation orthonormal within %.1e, det %.6f",
                  last_row ? "0 0 0 1" : "not 0 0 0 1", orthonormality, rotation.determinant());
    return port::Error::input(path + ": not a rigid transform (" + what +
                              "; expected the last row 0 0 0 1 and a rotation within 1e-5 of orthonormal, det 1)");
  }
  const std::string& unit = units.length.empty() ? std::string("m") : units.length;
  double scale = 1.0;
  if (!si_scale(unit, Quantity::length, &scale)) {
    return port::Error::usage("--length-unit " + port::quoted(unit) + " is not m or mm");
  }
  const Vec3 translation_m = Vec3(m[0][3], m[1][3], m[2][3]) * scale;
  if (translation_m.norm() > kMaxPointDistance_m) {
    char far[160];
    std::snprintf(far, sizeof far, ": its translation is %.4g m long in [%s] (more than %.0f m)", translation_m.norm(),
                  unit.c_str(), kMaxPointDistance_m);
    return port::Error::input(path + far +
                              (units.length.empty() ? ": looks like millimetres: use --length-unit mm" : ""));
  }
  transform->rotation = rotation_from_cross_covariance(rotation.transpose());  // the nearest rotation
  transform->translation_m = translation_m;
  return port::Error{};
}

}  // namespace hivecal::textio
