#include "textio/csv.hpp"

#include <cmath>
#include <functional>
#include <string_view>

#include "hivecal/core/math.hpp"
#include "hivecal/port/error.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

/// Expected header: `columns` in order, optionally one `optional_leading` column before them
/// (ignored); further columns after them are ignored.
struct CsvSchema {
  std::vector<std::string> columns;  ///< required column names, lower case
  std::vector<Quantity> quantities;  ///< what each measures (its units; joints and points are checked)
  std::string optional_leading;      ///< a column that may come first (ignored), or ""
  std::string optional_trailing;     ///< a unitless column that may follow them (its value appended), or ""
};

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ",") + n;
  return out;
}

/// Reads the whole file (through the one delimited-text reader, delimited.hpp) into
/// `on_row`, given the values of the schema's columns in order; on_row may reject a row by
/// returning an error text. Every error names the file and line.
port::Error read_csv(const std::string& path, const CsvSchema& schema, const InputUnits& units,
                     const std::function<std::string(const std::vector<double>&)>& on_row,
                     std::vector<std::size_t>* row_lines = nullptr) {
  const std::string expected =
      (schema.optional_leading.empty() ? "" : "[" + schema.optional_leading + ",]") + join(schema.columns);
  DelimitedReader r;
  r.set_units(units);
  if (!r.open(path, port::kMaxTextInputBytes)) return port::Error::input(r.error());
  if (!r.read_header()) return port::Error::input(r.error() + " (expected header " + expected + ")");
  const std::vector<Column>& header = r.columns();
  const std::size_t offset =
      (!schema.optional_leading.empty() && !header.empty() && header[0].name == schema.optional_leading) ? 1 : 0;
  bool match = header.size() >= offset + schema.columns.size();
  for (std::size_t i = 0; match && i < schema.columns.size(); ++i) {
    match = header[offset + i].name == schema.columns[i];
  }
  if (!match) return port::Error::input(r.where() + "unexpected header " + port::quoted(r.header_line()) + ", expected " + expected);
  std::vector<double> scales(schema.columns.size());
  std::vector<std::size_t> lengths;  // the x, y, z columns, when the schema has them
  for (std::size_t i = 0; i < scales.size(); ++i) {
    if (!r.column_scale(offset + i, schema.quantities[i], &scales[i])) return port::Error::input(r.error());
    if (schema.quantities[i] == Quantity::length) lengths.push_back(offset + i);
  }
  const std::size_t trailing = offset + schema.columns.size();
  const bool has_trailing = !schema.optional_trailing.empty() && header.size() > trailing &&
                            header[trailing].name == schema.optional_trailing;
  std::vector<double> values(schema.columns.size() + (has_trailing ? 1 : 0));
  std::size_t rows = 0;
  while (r.next_row()) {
    ++rows;
    int joint = 0;
    if (has_trailing && !r.number(trailing, 1.0, &values.back())) return port::Error::input(r.error());
    for (std::size_t i = 0; i < schema.columns.size(); ++i) {
      if (!r.number(offset + i, scales[i], &values[i])) return port::Error::input(r.error());
      if (schema.quantities[i] == Quantity::angle && !r.check_joint(++joint, offset + i, values[i])) {
        return port::Error::input(r.error());
      }
    }
    if (lengths.size() == 3 && !r.check_point(lengths.data(), &values[lengths[0] - offset])) {
      return port::Error::input(r.error());
    }
    const std::string rejection = on_row(values);
    if (!rejection.empty()) {
      r.fail(rejection);
      return port::Error::input(r.error());
    }
    if (row_lines != nullptr) row_lines->push_back(r.line_number());
  }
  if (!r.error().empty()) return port::Error::input(r.error());
  if (rows == 0) return port::Error::input(path + ": no data rows");
  return port::Error{};
}

std::string check_finite(const std::vector<double>& values, std::size_t first, std::size_t count) {
  for (std::size_t i = first; i < first + count; ++i) {
    if (!math::is_finite(values[i])) return "NaN or Inf in column " + std::to_string(i + 1);
  }
  return "";
}

const std::vector<std::string> kJointColumns = {"q1", "q2", "q3", "q4", "q5", "q6"};

template <typename T>
std::vector<T> with(std::vector<T> a, const std::vector<T>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

const std::vector<Quantity> kJointQuantities(kJointCount, Quantity::angle);

}  // namespace

port::Error read_samples_csv(const std::string& path, DatasetBase* dataset, const InputUnits& units,
                             std::vector<std::size_t>* lines) {
  const CsvSchema schema{with(kJointColumns, {"x", "y", "z"}),
                         with(kJointQuantities, {Quantity::length, Quantity::length, Quantity::length}), "",
                         "target"};
  return read_csv(path, schema, units, [&](const std::vector<double>& values) {
    const std::string error = check_finite(values, 0, 9);
    if (!error.empty()) return error;
    int target = 0;  // 0-based; no target column: every row is target 1
    if (values.size() > 9) {
      const double named = values[9];
      if (!(named >= 1.0 && named <= kMaxTargets && named == std::floor(named))) {
        return "target " + format_double(named) + " is not an integer from 1 to " + std::to_string(kMaxTargets);
      }
      target = static_cast<int>(named) - 1;
    }
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q(j) = values[static_cast<std::size_t>(j)];
    const Status status = dataset->add(q, Vec3(values[6], values[7], values[8]), target);
    if (status == Status::dataset_full) {
      return "dataset over capacity (" + std::to_string(dataset->capacity()) + " samples max)";
    }
    return status == Status::ok ? std::string() : std::string(status_message(status));
  }, lines);
}

port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses, const InputUnits& units) {
  return read_csv(path, CsvSchema{kJointColumns, kJointQuantities, "t", ""}, units, [&](const std::vector<double>& values) {
    const std::string error = check_finite(values, 0, 6);
    if (!error.empty()) return error;
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q(j) = values[static_cast<std::size_t>(j)];
    poses->push_back(q);
    return std::string();
  });
}

port::Error read_joint_limits_csv(const std::string& path, JointVector* lower_rad, JointVector* upper_rad) {
  JointVector lower;
  JointVector upper;
  int rows = 0;
  port::Error error = read_csv(path, CsvSchema{{"lower", "upper"}, {Quantity::angle, Quantity::angle}, "", ""}, InputUnits{}, [&](const std::vector<double>& values) {
    const std::string bad = check_finite(values, 0, 2);
    if (!bad.empty()) return bad;
    if (rows == kJointCount) return std::string("more than six rows (one per joint)");
    if (!(values[0] < values[1])) return std::string("lower limit not below the upper one");
    lower(rows) = values[0];
    upper(rows) = values[1];
    ++rows;
    return std::string();
  });
  if (!error.ok()) return error;
  if (rows != kJointCount) return port::Error::input(path + ": " + std::to_string(rows) + " rows, expected six (one per joint)");
  *lower_rad = lower;
  *upper_rad = upper;
  return error;
}

std::string format_joints_csv(Span<const JointVector> poses_rad) {
  std::string out = "q1,q2,q3,q4,q5,q6\n";
  for (const JointVector& q : poses_rad) {
    for (int j = 0; j < kJointCount; ++j) out += format_double(q(j)) + (j + 1 < kJointCount ? "," : "\n");
  }
  return out;
}

std::string format_points_csv(const std::vector<Vec3>& points_m, const std::string& length_unit) {
  const bool mm = length_unit == "mm";
  const double scale = mm ? 1e3 : 1.0;
  std::string out = mm ? "x [mm],y [mm],z [mm]\n" : "x,y,z\n";
  for (const Vec3& p : points_m) {
    out += format_double(p.x() * scale) + "," + format_double(p.y() * scale) + "," + format_double(p.z() * scale) + "\n";
  }
  return out;
}

std::string format_samples_csv(Span<const Sample> samples) {
  const bool targets = target_count(samples) > 1;
  std::string out = targets ? "q1,q2,q3,q4,q5,q6,x,y,z,target\n" : "q1,q2,q3,q4,q5,q6,x,y,z\n";
  for (const Sample& s : samples) {
    for (int j = 0; j < kJointCount; ++j) out += format_double(s.q_rad(j)) + ",";
    out += format_double(s.point_m.x()) + "," + format_double(s.point_m.y()) + "," + format_double(s.point_m.z());
    out += targets ? "," + std::to_string(s.target + 1) + "\n" : "\n";
  }
  return out;
}

}  // namespace hivecal::textio
