#include "textio/calibration_json.hpp"

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

constexpr const char* kFormat = "robot-calibration/1";
constexpr const char* kAxisNames[kErrorAxisCount] = {"x", "y", "z", "3d"};

void write_axis_values(JsonWriter& json, const char* name, const double* values) {
  json.key(name).begin_object();
  for (int axis = 0; axis < kErrorAxisCount; ++axis) json.key(kAxisNames[axis]).value(values[axis]);
  json.end_object();
}

port::Error fail(const std::string& source, const std::string& what) { return port::Error::input(source + ": " + what); }

bool read_number(const JsonValue* v, double* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::number) return false;
  *out = v->number;
  return true;
}

/// Reads an array of exactly n numbers.
bool read_numbers(const JsonValue* v, std::size_t n, double* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::array || v->array.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i) {
    if (!read_number(&v->array[i], &out[i])) return false;
  }
  return true;
}

port::Error parse_dh(const JsonValue& root, const std::string& source, RobotModel* model) {
  const JsonValue* dh = root.find("dh");
  if (dh == nullptr || dh->kind != JsonValue::Kind::array || dh->array.size() != kJointCount) {
    return fail(source, "\"dh\" must be an array of 6 joint objects");
  }
  for (std::size_t j = 0; j < static_cast<std::size_t>(kJointCount); ++j) {
    const JsonValue& row = dh->array[j];
    DhJoint& joint = model->joints[j];
    if (!read_number(row.find("theta_offset"), &joint.theta_offset_rad) || !read_number(row.find("d"), &joint.d_m) ||
        !read_number(row.find("a"), &joint.a_m) || !read_number(row.find("alpha"), &joint.alpha_rad)) {
      return fail(source, "\"dh\"[" + std::to_string(j) + "] needs numbers theta_offset, d, a, alpha");
    }
  }
  double tool[3];
  if (!read_numbers(root.find("tool"), 3, tool)) return fail(source, "\"tool\" must be [x, y, z] in metres");
  model->tool_m << tool[0], tool[1], tool[2];
  return port::Error{};
}

port::Error parse_transform(const JsonValue& root, const std::string& source, RigidTransform* transform) {
  const JsonValue* rows = root.find("base_to_tracker");
  if (rows == nullptr || rows->kind != JsonValue::Kind::array || rows->array.size() != 4) {
    return fail(source, "\"base_to_tracker\" must be a 4x4 array of rows");
  }
  Eigen::Matrix4d m;
  for (std::size_t r = 0; r < 4; ++r) {
    double row[4];
    if (!read_numbers(&rows->array[r], 4, row)) return fail(source, "\"base_to_tracker\" row " + std::to_string(r) + " must hold 4 numbers");
    for (std::size_t c = 0; c < 4; ++c) m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c];
  }
  const Mat3 rotation = m.block<3, 3>(0, 0);
  const bool last_row_ok = m(3, 0) == 0.0 && m(3, 1) == 0.0 && m(3, 2) == 0.0 && m(3, 3) == 1.0;
  const double orthonormality = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!last_row_ok || orthonormality > 1e-5 || rotation.determinant() <= 0.0) {
    return fail(source, "\"base_to_tracker\" is not a proper rigid transform");
  }
  transform->rotation = rotation_from_cross_covariance(rotation.transpose());  // nearest rotation
  transform->translation_m = m.block<3, 1>(0, 3);
  return port::Error{};
}

}  // namespace

void write_error_stats(JsonWriter& json, const ErrorStats& stats) {
  json.begin_object();
  json.key("count").value(static_cast<long long>(stats.count));
  write_axis_values(json, "mae_m", stats.mae_m);
  write_axis_values(json, "sigma_m", stats.sigma_m);
  write_axis_values(json, "max_m", stats.max_m);
  json.end_object();
}

std::string format_calibration_json(const CalibrationFile& file, const std::function<void(JsonWriter&)>& extra_members) {
  JsonWriter json;
  json.begin_object();
  json.key("format").value(kFormat);
  json.key("robot").value(robot_type_name(file.robot));
  json.key("convention").value("standard-dh");
  json.key("dh").begin_array();
  for (const DhJoint& joint : file.model.joints) {
    json.begin_object();
    json.key("theta_offset").value(joint.theta_offset_rad);
    json.key("d").value(joint.d_m);
    json.key("a").value(joint.a_m);
    json.key("alpha").value(joint.alpha_rad);
    json.end_object();
  }
  json.end_array();
  json.key("tool").inline_array(file.model.tool_m.data(), 3);
  json.key("base_to_tracker").begin_array();
  for (int r = 0; r < 4; ++r) {
    double row[4] = {0.0, 0.0, 0.0, 1.0};
    if (r < 3) {
      for (int c = 0; c < 3; ++c) row[c] = file.base_to_tracker.rotation(r, c);
      row[3] = file.base_to_tracker.translation_m(r);
    }
    json.inline_array(row, 4);
  }
  json.end_array();
  if (file.has_metrics) {
    json.key("metrics").begin_object();
    json.key("train");
    write_error_stats(json, file.metrics.train);
    json.key("test");
    write_error_stats(json, file.metrics.test);
    json.key("overall");
    write_error_stats(json, file.metrics.overall);
    json.end_object();
  }
  if (extra_members) extra_members(json);
  json.end_object();
  return json.text();
}

port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file) {
  JsonValue root;
  const port::Error syntax = parse_json(text, &root);
  if (!syntax.ok()) return fail(source_name, "malformed JSON: " + syntax.message);
  if (root.kind != JsonValue::Kind::object) return fail(source_name, "top level must be an object");
  const JsonValue* format = root.find("format");
  if (format == nullptr || format->kind != JsonValue::Kind::string || format->string != kFormat) {
    return fail(source_name, std::string("\"format\" must be \"") + kFormat + "\"");
  }
  CalibrationFile parsed;
  const JsonValue* robot = root.find("robot");
  if (robot == nullptr || robot->kind != JsonValue::Kind::string ||
      robot_type_from_name(robot->string.c_str(), &parsed.robot) != Status::ok) {
    return fail(source_name, "unknown robot model" + (robot != nullptr && robot->kind == JsonValue::Kind::string
                                                          ? " '" + robot->string + "' (" + robot_type_names() + ")"
                                                          : std::string(" (missing \"robot\")")));
  }
  const JsonValue* convention = root.find("convention");
  if (convention != nullptr && (convention->kind != JsonValue::Kind::string || convention->string != "standard-dh")) {
    return fail(source_name, "\"convention\" must be \"standard-dh\"");
  }
  port::Error r = parse_dh(root, source_name, &parsed.model);
  if (!r.ok()) return r;
  r = parse_transform(root, source_name, &parsed.base_to_tracker);
  if (!r.ok()) return r;
  *file = parsed;
  return port::Error{};
}

port::Error read_calibration_json(const std::string& path, CalibrationFile* file) {
  std::string text;
  const port::Error read = port::read_whole_file(path, port::kMaxTextInputBytes, &text);
  if (!read.ok()) return read;
  if (trim(text).empty()) return port::Error::input(path + ": empty file");
  return parse_calibration_json(text, path, file);
}

}  // namespace hivecal::textio
