#include "textio/csv.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>
#include <string_view>

#include "hivecal/core/math.hpp"
#include "hivecal/model/full_params.hpp"
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
  std::vector<std::string>
      optional_group;      ///< angle columns found by name after them, all or none (values appended last)
  std::size_t joints = 0;  ///< the first `joints` columns are the arm's joints q1.. (InputUnits::joints)
  bool nameable = true;    ///< --columns can name the columns (textio::parse_column_aliases)
};

/// Which optional columns a file had.
struct CsvFound {
  bool trailing = false;  ///< CsvSchema::optional_trailing
  bool group = false;     ///< every column of CsvSchema::optional_group
  /// The resolution the joint columns are written in: the finest place value of a last written
  /// digit among their fields (a trailing zero left off, "104.5" among "20.72", or a round
  /// value does not coarsen it), in the first joint column's unit converted to rad; 0 when not
  /// known [rad].
  double joint_resolution_rad = 0.0;
  /// The factor to SI of each schema column, in order [SI per unit].
  std::vector<double> scales{};
};

/// Joint names as a UR teach pendant's export writes them ("Base (°)", ..., "Wrist 3 (°)").
const char* const kPendantJointNames[kSixJoints] = {"base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3"};

/// Joint names as ROS (joint_states, the UR driver's URDF) writes them.
const char* const kRosJointNames[kSixJoints] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};

/// True when header column `name` is schema column `wanted`: equal, or (`ur_names`: the arm has
/// a UR's six revolute joints) the pendant's or ROS's name of joint qN.
bool column_matches(const std::string& name, const std::string& wanted, bool ur_names) {
  if (name == wanted) return true;
  for (int j = 0; ur_names && j < kSixJoints; ++j) {
    if (wanted == "q" + std::to_string(j + 1)) return name == kPendantJointNames[j] || name == kRosJointNames[j];
  }
  return false;
}

/// The header column the user mapped schema column `wanted` to (InputUnits::columns), or "".
std::string mapped_name(const InputUnits& units, const std::string& wanted) {
  for (const ColumnAlias& alias : units.columns) {
    if (alias.column == wanted) return alias.header;
  }
  return "";
}

/// "--columns 'x=x_t+x_dif': no column 'x_dif' in PATH (its columns: ...)" for an alias whose
/// column (or a term of whose sum) the header lacks.
std::string misnamed_column(const DelimitedReader& r, const ColumnAlias& alias) {
  std::string absent;
  for (const ColumnTerm& term : column_terms(alias.header)) {
    if (r.find(term.name) < 0) absent += (absent.empty() ? "" : ", ") + port::quoted(term.name, 40);
  }
  if (absent.empty()) absent = port::quoted(alias.header, 40);
  std::string listed;
  for (std::size_t k = 0; k < r.header_column_count(); ++k) {
    listed += (k == 0 ? "" : ", ") + r.columns()[k].name;
  }
  return "--columns " + port::quoted(column_alias_text(alias)) + ": no column " + absent + " in the header of " +
         r.name() + " (its columns: " + port::printable(listed, 200) + ")";
}

/// Where each schema column is in the header: in order from `offset` (the fixed format), or,
/// when that does not match, found by name anywhere (a mapped name first, then its own, the
/// pendant's and ROS's names). Empty with *missing set to the columns not found, and
/// *misnamed to the first --columns entry whose name the header lacks ("" when none).
std::vector<std::size_t> locate_columns(const DelimitedReader& r, const CsvSchema& schema, const InputUnits& units,
                                        std::size_t offset, std::string* missing, std::string* misnamed) {
  const std::vector<Column>& header = r.columns();
  const bool ur_names = units.joints.count == kSixJoints && units.joints.prismatic == 0;
  std::vector<std::size_t> at;
  bool in_order = units.columns.empty() && header.size() >= offset + schema.columns.size();
  for (std::size_t i = 0; in_order && i < schema.columns.size(); ++i) {
    in_order = column_matches(header[offset + i].name, schema.columns[i], ur_names);
    at.push_back(offset + i);
  }
  if (in_order) return at;
  at.clear();
  missing->clear();
  for (const std::string& wanted : schema.columns) {
    const std::string mapped = mapped_name(units, wanted);
    int found = -1;
    for (std::size_t k = 0; found < 0 && k < header.size(); ++k) {
      if (mapped.empty() ? column_matches(header[k].name, wanted, ur_names) : header[k].name == mapped)
        found = static_cast<int>(k);
    }
    if (found < 0) *missing += (missing->empty() ? "" : ", ") + (mapped.empty() ? wanted : wanted + "=" + mapped);
    if (found < 0 && !mapped.empty() && misnamed->empty()) {
      for (const ColumnAlias& alias : units.columns) {
        if (alias.column == wanted) *misnamed = misnamed_column(r, alias);
      }
    }
    at.push_back(static_cast<std::size_t>(found));
  }
  if (!missing->empty()) at.clear();
  return at;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ",") + n;
  return out;
}

/// The header column that --columns' naming of the arm's last joint predicts for one joint
/// more ("joint_7" when q6=joint_6), or "" when that name holds no joint number.
std::string next_joint_column(const InputUnits& units) {
  const int joints = units.joints.count;
  const std::string last = mapped_name(units, "q" + std::to_string(joints));
  const std::string number = std::to_string(joints);
  const std::size_t at = last.rfind(number);
  if (at == std::string::npos || column_terms(last).size() != 1) return "";
  const bool digit_before = at > 0 && std::isdigit(static_cast<unsigned char>(last[at - 1])) != 0;
  const bool digit_after =
      at + number.size() < last.size() && std::isdigit(static_cast<unsigned char>(last[at + number.size()])) != 0;
  if (digit_before || digit_after) return "";  // "joint_16" is no joint 6
  return last.substr(0, at) + std::to_string(joints + 1) + last.substr(at + number.size());
}

/// Fault::usage for a --columns entry naming a joint beyond the arm's (q7=... for six joints),
/// Fault::input for a header with a joint column beyond them (q7 for six joints, or joint_7 when
/// --columns names q6=joint_6: never cut) or (`missing`: what was not found) without all of
/// them, naming both counts; ok otherwise.
port::Error check_joint_count(const DelimitedReader& r, const InputUnits& units, const std::string& missing) {
  const int joints = units.joints.count;
  const std::string model = "the robot model has " + std::to_string(joints) + (joints == 1 ? " joint (" : " joints (") +
                            joint_names(joints) + ")";
  for (const ColumnAlias& alias : units.columns) {
    if (joint_number(alias.column) > joints)
      return port::Error::usage("--columns " + port::quoted(column_alias_text(alias)) + ": " + model);
  }
  const std::string next = next_joint_column(units);
  if (!next.empty() && r.find(next) >= 0) {
    return port::Error::input(r.name() + ": its header has a column " + port::quoted(next) + " after --columns' q" +
                              std::to_string(joints) + "=" + mapped_name(units, "q" + std::to_string(joints)) +
                              ", but " + model + ": the joints of another arm? (--robot-model names the arm)");
  }
  int highest = 0;   // the highest qK in the header or --columns
  int in_a_row = 0;  // q1 .. q<in_a_row> all there
  for (int k = 1; k <= 99; ++k) {
    const std::string name = "q" + std::to_string(k);
    if (r.find(name) < 0 && mapped_name(units, name).empty()) continue;
    highest = k;
    if (in_a_row == k - 1) in_a_row = k;
  }
  if (highest > joints) {
    return port::Error::input(r.name() + ": its header has joint columns up to q" + std::to_string(highest) + ", but " +
                              model + ": the joints of another arm? (--robot-model names the arm)");
  }
  if (!missing.empty() && in_a_row > 0 && in_a_row < joints && highest == in_a_row) {
    const bool named = std::any_of(units.columns.begin(), units.columns.end(),
                                   [](const ColumnAlias& alias) { return joint_number(alias.column) > 0; });
    if (named) {  // the header may well hold the rest under names of its own
      const std::string rest =
          "q" + std::to_string(in_a_row + 1) + (in_a_row + 1 < joints ? "..q" + std::to_string(joints) : std::string());
      return port::Error::usage("--columns names " + joint_names(in_a_row) + ", but " + model + ": name " + rest +
                                " too");
    }
    return port::Error::input(r.name() + ": its header has " + std::to_string(in_a_row) + " joint columns (" +
                              joint_names(in_a_row) + "), but " + model +
                              ": the joints of another arm? (--robot-model names the arm)");
  }
  return port::Error{};
}

/// Reads the whole file (through the one delimited-text reader, delimited.hpp) into
/// `on_row`, given the values of the schema's columns in order; on_row may reject a row by
/// returning an error text. Every error names the file and line.
port::Error read_csv(const std::string& path, const CsvSchema& schema, const InputUnits& units,
                     const std::function<std::string(const std::vector<double>&)>& on_row,
                     std::vector<std::size_t>* row_lines = nullptr, CsvFound* found = nullptr) {
  const std::string expected =
      (schema.optional_leading.empty() ? "" : "[" + schema.optional_leading + ",]") + join(schema.columns);
  DelimitedReader r;
  r.set_units(units);
  if (!r.open(path, port::kMaxTextInputBytes)) return port::Error::input(r.error());
  if (!r.read_header()) {  // the expected header helps when there is none; not with a --columns problem
    return port::Error::input(r.error() + (r.header_line().empty() ? " (expected header " + expected + ")" : ""));
  }
  const std::vector<Column>& header = r.columns();
  const std::size_t offset =
      (!schema.optional_leading.empty() && !header.empty() && header[0].name == schema.optional_leading) ? 1 : 0;
  std::string missing;
  std::string misnamed;
  const std::vector<std::size_t> at = locate_columns(r, schema, units, offset, &missing, &misnamed);
  if (!misnamed.empty()) return port::Error::usage(misnamed);  // the option's fault, not the file's
  if (schema.joints > 0) {
    const port::Error counted = check_joint_count(r, units, missing);
    if (!counted.ok()) return counted;
  }
  if (at.empty()) {
    const bool hint = schema.nameable && units.columns_option;  // only where the command has --columns
    return port::Error::input(r.where() + "unexpected header " + port::quoted(r.header_line()) + ", expected " +
                              expected + " (or these columns by name anywhere; not found: " + missing +
                              (hint ? "; name them with --columns, e.g. x=measurement_x" : "") + ")");
  }
  const bool in_order = at[0] == offset;  // the fixed format (a named header may happen to agree)
  std::vector<double> scales(schema.columns.size());
  std::vector<std::size_t> lengths;  // the x, y, z columns, when the schema has them
  std::size_t first_length = 0;      // their first value's place in the row's values
  for (std::size_t i = 0; i < scales.size(); ++i) {
    if (!r.column_scale(at[i], schema.quantities[i], &scales[i])) return port::Error::input(r.error());
    const bool point = schema.quantities[i] == Quantity::length && i >= schema.joints;  // x, y, z
    if (point && lengths.empty()) first_length = i;
    if (point) lengths.push_back(at[i]);
  }
  // The optional columns: right after the fixed columns, or by name in a named header.
  const std::size_t trailing_from = in_order ? offset + schema.columns.size() : 0;
  const int named_trailing = schema.optional_trailing.empty() ? -1 : r.find(schema.optional_trailing);
  const bool has_trailing = in_order ? (!schema.optional_trailing.empty() && header.size() > trailing_from &&
                                        header[trailing_from].name == schema.optional_trailing)
                                     : named_trailing >= 0;
  const std::size_t trailing =
      in_order || named_trailing < 0 ? trailing_from : static_cast<std::size_t>(named_trailing);
  std::vector<std::size_t> group;  // the optional group's columns, when all are present
  for (const std::string& name : schema.optional_group) {
    const std::string mapped = mapped_name(units, name);
    const int found_at = r.find(mapped.empty() ? name : mapped);
    if (found_at >= 0 && static_cast<std::size_t>(found_at) >= trailing_from)
      group.push_back(static_cast<std::size_t>(found_at));
  }
  if (!group.empty() && group.size() != schema.optional_group.size()) {
    return port::Error::input(r.where() + "header has " + std::to_string(group.size()) + " of the columns " +
                              join(schema.optional_group) + ": give all of them or none");
  }
  std::vector<double> group_scales(group.size());
  for (std::size_t k = 0; k < group.size(); ++k) {
    if (!r.column_scale(group[k], Quantity::angle, &group_scales[k])) return port::Error::input(r.error());
  }
  if (found != nullptr) *found = CsvFound{has_trailing, !group.empty(), 0.0, scales};
  const std::size_t group_at = schema.columns.size() + (has_trailing ? 1 : 0);
  std::vector<double> values(group_at + group.size());
  int finest_joint_exponent = std::numeric_limits<int>::max();  // of the joints' written resolution
  double joint_scale = 0.0;                                     // the first joint column's unit [rad per unit]
  std::size_t rows = 0;
  while (r.next_row()) {
    ++rows;
    int joint = 0;
    if (has_trailing && !r.number(trailing, 1.0, &values[schema.columns.size()])) return port::Error::input(r.error());
    for (std::size_t k = 0; k < group.size(); ++k) {
      if (!r.number(group[k], group_scales[k], &values[group_at + k])) return port::Error::input(r.error());
    }
    if (group.size() == 3 && !r.check_rotation(group.data(), &values[group_at])) return port::Error::input(r.error());
    for (std::size_t i = 0; i < schema.columns.size(); ++i) {
      if (!r.number(at[i], scales[i], &values[i])) return port::Error::input(r.error());
      if (i < schema.joints && schema.quantities[i] == Quantity::length) {  // a prismatic joint
        if (!r.check_slide(++joint, at[i], values[i])) return port::Error::input(r.error());
      } else if (i < schema.joints) {
        if (!r.check_joint(++joint, at[i], values[i])) return port::Error::input(r.error());
        int exponent = 0;
        if (written_resolution_exponent(r.fields()[at[i]], &exponent))
          finest_joint_exponent = std::min(finest_joint_exponent, exponent);
        if (joint_scale == 0.0) joint_scale = scales[i];
      }
    }
    if (lengths.size() == 3 && !r.check_point(lengths.data(), &values[first_length])) {
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
  if (found != nullptr && finest_joint_exponent != std::numeric_limits<int>::max()) {
    found->joint_resolution_rad = std::pow(10.0, finest_joint_exponent) * joint_scale;
  }
  return port::Error{};
}

std::string check_finite(const std::vector<double>& values, std::size_t first, std::size_t count) {
  for (std::size_t i = first; i < first + count; ++i) {
    if (!math::is_finite(values[i])) return "NaN or Inf in column " + std::to_string(i + 1);
  }
  return "";
}

/// The joint columns of the arm: q1 .. q<count>.
std::vector<std::string> joint_columns(const InputJoints& joints) {
  std::vector<std::string> names;
  for (int j = 0; j < joints.count; ++j) names.push_back("q" + std::to_string(j + 1));
  return names;
}

/// What each joint column measures: a prismatic joint a length, a revolute one an angle.
std::vector<Quantity> joint_quantities(const InputJoints& joints) {
  std::vector<Quantity> quantities;
  for (int j = 0; j < joints.count; ++j) quantities.push_back(joints.slides(j) ? Quantity::length : Quantity::angle);
  return quantities;
}

template <typename T>
std::vector<T> with(std::vector<T> a, const std::vector<T>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// A row whose orientation makes targets 2 and 3: added once the file is read, when the lever
/// (which may depend on the joints' written resolution) is known.
struct OrientedRow {
  JointVector q_rad;
  Vec3 point_m;
  Vec3 angles_rad;  ///< rx, ry, rz as read (converted to rad)
  Vec3 x_axis;      ///< the measured tool frame's x axis in the tracker frame [-]
  Vec3 y_axis;      ///< its y axis [-]
};

std::string over_capacity(const DatasetBase& dataset, bool oriented) {
  return "dataset over capacity (" + std::to_string(dataset.capacity()) + " samples max" +
         (oriented ? "; a row with an orientation takes three)" : ")");
}

/// The lever of `orientation` for the rows read: as given, or from the noise (with the joints'
/// noise when the input names the arm: given, else the joint columns' written resolution).
double lever_for(const OrientationInput& orientation, double joint_resolution_rad, const std::vector<OrientedRow>& rows,
                 double* joint_sigma_rad) {
  *joint_sigma_rad = 0.0;
  if (orientation.lever_m >= 0.0 || orientation.arm == nullptr) return orientation.lever();
  *joint_sigma_rad = orientation.joint_sigma_rad > 0.0 ? orientation.joint_sigma_rad : joint_resolution_rad;
  std::vector<JointVector> poses;
  poses.reserve(rows.size());
  for (const OrientedRow& row : rows) poses.push_back(row.q_rad);
  return noise_lever_m(orientation.position_sigma_m, orientation.angle_sigma_rad, *joint_sigma_rad, *orientation.arm,
                       Span<const JointVector>(poses.data(), poses.size()));
}

}  // namespace

InputJoints input_joints(const RobotModel& model) {
  return InputJoints{model.joint_count, model.prismatic_joints};
}

double joint_position_variance_m2(double joint_sigma_rad, const RobotModel& arm, Span<const JointVector> poses) {
  if (poses.empty()) return 0.0;
  constexpr double kStep_rad = 1e-6;  // central differences: the error is ~1e-12 of |J|
  double jacobian_norm2_m2 = 0.0;     // sum over the poses of |d point / d q|_F^2
  for (const JointVector& q_rad : poses) {
    for (int j = 0; j < arm.joint_count; ++j) {
      JointVector ahead = q_rad;
      JointVector behind = q_rad;
      ahead(j) += kStep_rad;
      behind(j) -= kStep_rad;
      jacobian_norm2_m2 += ((fk_tool_point(arm, ahead) - fk_tool_point(arm, behind)) / (2.0 * kStep_rad)).squaredNorm();
    }
  }
  const double mean_norm2_m2 = jacobian_norm2_m2 / static_cast<double>(poses.size());
  return joint_sigma_rad * joint_sigma_rad * mean_norm2_m2 / 3.0;
}

double noise_lever_m(double position_sigma_m, double angle_sigma_rad, double joint_sigma_rad, const RobotModel& arm,
                     Span<const JointVector> poses) {
  if (!(joint_sigma_rad > 0.0) || poses.empty()) return position_sigma_m / angle_sigma_rad;
  const double position2 =
      position_sigma_m * position_sigma_m + joint_position_variance_m2(joint_sigma_rad, arm, poses);
  const double angle2 = angle_sigma_rad * angle_sigma_rad + 2.0 * joint_sigma_rad * joint_sigma_rad;
  return std::sqrt(position2 / angle2);
}

port::Error read_samples_csv(const std::string& path, DatasetBase* dataset, const InputUnits& units,
                             std::vector<std::size_t>* lines, const OrientationInput& orientation,
                             OrientationRead* found) {
  const int joints = units.joints.count;
  const std::size_t n = static_cast<std::size_t>(joints);
  const CsvSchema schema{with(joint_columns(units.joints), {"x", "y", "z"}),
                         with(joint_quantities(units.joints), {Quantity::length, Quantity::length, Quantity::length}),
                         "",
                         "target",
                         {"rx", "ry", "rz"},
                         n};
  const double given_lever_m = orientation.lever();
  if (!(given_lever_m >= 0.0 && math::is_finite(given_lever_m))) {
    return port::Error::usage("orientation lever " + format_double(given_lever_m) +
                              " m: the stated sigmas must be positive and finite");
  }
  CsvFound columns;
  std::vector<std::size_t> row_lines;
  std::vector<std::size_t> samples_per_row;
  std::vector<OrientedRow> oriented;
  OrientationRead read;
  port::Error result = read_csv(
      path, schema, units,
      [&](const std::vector<double>& values) {
        const std::string error = check_finite(values, 0, n + 3);
        if (!error.empty()) return error;
        if (columns.group && !check_finite(values, values.size() - 3, 3).empty()) {
          return std::string("NaN or Inf in the rotation vector rx, ry, rz");
        }
        if (columns.trailing && columns.group) {
          return std::string(
              "a measured orientation (rx, ry, rz) and a target column together: the orientation "
              "makes targets 2 and 3 itself; give one or the other");
        }
        int target = 0;  // 0-based; no target column: every row is target 1
        if (columns.trailing) {
          const double named = values[n + 3];
          if (!(named >= 1.0 && named <= kMaxTargets && named == std::floor(named))) {
            return "target " + format_double(named) + " is not an integer from 1 to " + std::to_string(kMaxTargets);
          }
          target = static_cast<int>(named) - 1;
        }
        JointVector q;
        for (int j = 0; j < joints; ++j) q(j) = values[static_cast<std::size_t>(j)];
        const Vec3 point_m(values[n], values[n + 1], values[n + 2]);
        if (columns.group && given_lever_m > 0.0) {  // targets 2 and 3 once the lever is known
          const std::size_t at = values.size() - 3;
          const Vec3 angles_rad(values[at], values[at + 1], values[at + 2]);
          const Mat3 rotation =
              orientation.form == OrientationForm::euler_xyz
                  ? Mat3(rotation_x(angles_rad.x()) * rotation_y(angles_rad.y()) * rotation_z(angles_rad.z()))
                  : rotation_from_vector(angles_rad);
          oriented.push_back(OrientedRow{q, point_m, angles_rad, rotation.col(0), rotation.col(1)});
          samples_per_row.push_back(3);
          return std::string();
        }
        const Status status = dataset->add(q, point_m, target);
        if (status == Status::dataset_full) return over_capacity(*dataset, false);
        if (status != Status::ok) return std::string(status_message(status));
        samples_per_row.push_back(1);
        return std::string();
      },
      &row_lines, &columns);
  read.joint_resolution_rad = columns.joint_resolution_rad;
  if (result.ok() && !oriented.empty()) {  // the virtual reflectors along the measured x and y axes
    read.lever_m = lever_for(orientation, columns.joint_resolution_rad, oriented, &read.joint_sigma_rad);
    read.poses = oriented.size();
    read.orientation_constant = oriented.size() >= 2;
    for (const OrientedRow& row : oriented) {
      read.orientation_constant = read.orientation_constant && row.angles_rad == oriented.front().angles_rad;
    }
    for (std::size_t row = 0; row < oriented.size() && result.ok(); ++row) {
      const OrientedRow& o = oriented[row];
      const Vec3 points_m[3] = {o.point_m, o.point_m + read.lever_m * o.x_axis, o.point_m + read.lever_m * o.y_axis};
      for (int k = 0; k < 3 && result.ok(); ++k) {
        const Status status = dataset->add(o.q_rad, points_m[k], k);
        if (status == Status::ok) continue;
        const std::string problem =
            status == Status::dataset_full ? over_capacity(*dataset, true) : std::string(status_message(status));
        result = port::Error::input(path + ":" + std::to_string(row_lines[row]) + ": " + problem);
      }
    }
  }
  for (std::size_t row = 0; lines != nullptr && row < row_lines.size(); ++row) {
    lines->insert(lines->end(), samples_per_row[row], row_lines[row]);
  }
  if (found != nullptr) *found = read;
  return result;
}

void start_orientation_targets(const OrientationRead& read, RobotModel* start) {
  if (read.poses == 0) return;
  start->other_tools_m[0] = start->tool_m + Vec3(read.lever_m, 0.0, 0.0);
  start->other_tools_m[1] = start->tool_m + Vec3(0.0, read.lever_m, 0.0);
}

port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses, const InputUnits& units) {
  const int joints = units.joints.count;
  const CsvSchema schema{joint_columns(units.joints),     joint_quantities(units.joints), "t", "", {},
                         static_cast<std::size_t>(joints)};
  return read_csv(path, schema, units, [&](const std::vector<double>& values) {
    const std::string error = check_finite(values, 0, static_cast<std::size_t>(joints));
    if (!error.empty()) return error;
    JointVector q;
    for (int j = 0; j < joints; ++j) q(j) = values[static_cast<std::size_t>(j)];
    poses->push_back(q);
    return std::string();
  });
}

port::Error read_joint_limits_csv(const std::string& path, JointVector* lower_rad, JointVector* upper_rad,
                                  const InputUnits& units) {
  JointVector lower;
  JointVector upper;
  const InputJoints& joints = units.joints;
  const std::string one_per_joint = "one per joint: the robot model has " + std::to_string(joints.count) + " joints";
  int rows = 0;
  CsvFound found;
  CsvSchema schema{{"lower", "upper"}, {Quantity::angle, Quantity::angle}, "", "", {}};
  schema.nameable = false;  // --columns names q1..qN, x, y, z, ...: not lower, upper
  // A limit may span two turns (J6 +-720 deg): the columns are no joint positions (schema.joints 0).
  port::Error error = read_csv(
      path, schema, units,
      [&](const std::vector<double>& values) {
        const std::string bad = check_finite(values, 0, 2);
        if (!bad.empty()) return bad;
        if (rows == joints.count) return "more than " + std::to_string(joints.count) + " rows (" + one_per_joint + ")";
        if (joints.slides(rows)) {  // a prismatic joint's limits: lengths in m, the angle unit not applied
          if (found.scales[0] != 1.0 || found.scales[1] != 1.0) {
            return "joint " + std::to_string(rows + 1) +
                   " is prismatic: its limits are in m, and this file's are angles in another unit than rad: give "
                   "them in rad and m";
          }
          if (!(std::fabs(values[0]) <= kMaxJointTravel_m) || !(std::fabs(values[1]) <= kMaxJointTravel_m)) {
            return "joint " + std::to_string(rows + 1) + " is prismatic: a limit beyond " +
                   format_double(kMaxJointTravel_m) + " m: millimetres?";
          }
        } else if (!(std::fabs(values[0]) <= kMaxJointLimit_rad) || !(std::fabs(values[1]) <= kMaxJointLimit_rad)) {
          return std::string(
              "a limit beyond two turns (4 pi rad): degrees? name the unit in the header (lower [deg]) "
              "or give --angle-unit deg");
        }
        if (!(values[0] < values[1])) return std::string("lower limit not below the upper one");
        lower(rows) = values[0];
        upper(rows) = values[1];
        ++rows;
        return std::string();
      },
      nullptr, &found);
  if (!error.ok()) return error;
  if (rows != joints.count)
    return port::Error::input(path + ": " + std::to_string(rows) + " rows, expected " + std::to_string(joints.count) +
                              " (" + one_per_joint + ")");
  *lower_rad = lower;
  *upper_rad = upper;
  return error;
}

std::string joint_header(int joints) {
  std::string out;
  for (int j = 0; j < joints; ++j) out += (j == 0 ? "q" : ",q") + std::to_string(j + 1);
  return out;
}

std::string format_joints_csv(Span<const JointVector> poses_rad, int joints) {
  std::string out = joint_header(joints) + "\n";
  for (const JointVector& q : poses_rad) {
    for (int j = 0; j < joints; ++j) out += format_double(q(j)) + (j + 1 < joints ? "," : "\n");
  }
  return out;
}

std::string format_points_csv(const std::vector<Vec3>& points_m, const std::string& length_unit) {
  const bool mm = length_unit == "mm";
  const double scale = mm ? 1e3 : 1.0;
  std::string out = mm ? "x [mm],y [mm],z [mm]\n" : "x,y,z\n";
  for (const Vec3& p : points_m) {
    out +=
        format_double(p.x() * scale) + "," + format_double(p.y() * scale) + "," + format_double(p.z() * scale) + "\n";
  }
  return out;
}

std::string format_predictions_csv(const std::vector<Vec3>& points_m, const std::vector<double>& sigma_m,
                                   const std::vector<bool>& extrapolated, const std::string& length_unit) {
  const bool mm = length_unit == "mm";
  const double scale = mm ? 1e3 : 1.0;
  std::string out = mm ? "x [mm],y [mm],z [mm],sigma [mm],extrapolated\n" : "x,y,z,sigma_m,extrapolated\n";
  for (std::size_t k = 0; k < points_m.size(); ++k) {
    const Vec3& p = points_m[k];
    out += format_double(p.x() * scale) + "," + format_double(p.y() * scale) + "," + format_double(p.z() * scale) +
           "," + format_double(sigma_m[k] * scale) + (extrapolated[k] ? ",1\n" : ",0\n");
  }
  return out;
}

std::string format_samples_csv(Span<const Sample> samples, int joints) {
  const bool targets = target_count(samples) > 1;
  std::string out = joint_header(joints) + (targets ? ",x,y,z,target\n" : ",x,y,z\n");
  for (const Sample& s : samples) {
    for (int j = 0; j < joints; ++j) out += format_double(s.q_rad(j)) + ",";
    out += format_double(s.point_m.x()) + "," + format_double(s.point_m.y()) + "," + format_double(s.point_m.z());
    out += targets ? "," + std::to_string(s.target + 1) + "\n" : "\n";
  }
  return out;
}

}  // namespace hivecal::textio
