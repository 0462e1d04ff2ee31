#include "textio/robot_description.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"
#include "textio/urdf.hpp"

namespace hivecal::textio {
namespace {

constexpr const char* kFormat = "robot-calibration/1";

port::Error fail(const std::string& source, const std::string& what) {
  return port::Error::input(source + ": " + what);
}

bool read_number(const JsonValue* v, double* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::number) return false;
  *out = v->number;
  return true;
}

/// Reads number `key` of DH row j into *out, within its bound; the error names the row and key.
port::Error row_number(const JsonValue& row, std::size_t j, const char* key, const std::string& source, double* out) {
  const std::string at = "\"dh\"[" + std::to_string(j) + "]." + key;
  const JsonValue* v = row.find(key);
  if (v == nullptr) return fail(source, "\"dh\"[" + std::to_string(j) + "]: missing \"" + key + "\"");
  if (!read_number(v, out)) return fail(source, at + " must be a number");
  const bool angle = std::string(key) == "theta_offset" || std::string(key) == "alpha";
  const std::string beyond = beyond_bound(*out, angle ? ModelQuantity::angle : ModelQuantity::length);
  return beyond.empty() ? port::Error{} : fail(source, at + beyond);
}

/// The tool point(s) within kMaxToolLength_m; `what` names the key in the message.
port::Error check_tool(const double (&point)[3], const std::string& what, const std::string& source) {
  for (double value : point) {
    const std::string beyond = beyond_bound(value, ModelQuantity::tool);
    if (!beyond.empty()) return fail(source, what + beyond);
  }
  return port::Error{};
}

/// The rows as written (1 .. kMaxJoints of them, *count): theta_offset, d, a, alpha (standard)
/// or theta_offset, d, a_{i-1}, alpha_{i-1} (modified); rows[j] = {theta_offset, d, a, alpha}.
/// A row's optional "type" ("revolute", the default, or "prismatic") sets bit j of *prismatic.
port::Error parse_dh_rows(const JsonValue& root, const std::string& source, double (&rows)[kMaxJoints][4], int* count,
                          std::uint32_t* prismatic) {
  const std::string shape = "an array of 1 to " + std::to_string(kMaxJoints) + " joint objects, one per joint";
  const JsonValue* dh = root.find("dh");
  if (dh == nullptr) return fail(source, "missing \"dh\" (" + shape + ")");
  if (dh->kind != JsonValue::Kind::array || dh->array.empty() ||
      dh->array.size() > static_cast<std::size_t>(kMaxJoints)) {
    const std::string rows_given =
        dh->kind == JsonValue::Kind::array ? " (it has " + std::to_string(dh->array.size()) + " rows)" : std::string();
    return fail(source, "\"dh\" must be " + shape + rows_given);
  }
  static const char* const kKeys[4] = {"theta_offset", "d", "a", "alpha"};
  *prismatic = 0;
  for (std::size_t j = 0; j < dh->array.size(); ++j) {
    const JsonValue& row = dh->array[j];
    if (row.kind != JsonValue::Kind::object) return fail(source, "\"dh\"[" + std::to_string(j) + "] must be an object");
    for (std::size_t k = 0; k < 4; ++k) {
      port::Error r = row_number(row, j, kKeys[k], source, &rows[j][k]);
      if (!r.ok()) return r;
    }
    if (const JsonValue* type = row.find("type"); type != nullptr) {
      const bool revolute = type->kind == JsonValue::Kind::string && type->string == "revolute";
      const bool slides = type->kind == JsonValue::Kind::string && type->string == "prismatic";
      if (!revolute && !slides) {
        return fail(source, "\"dh\"[" + std::to_string(j) + "].type must be \"revolute\" (q turns theta) or " +
                                "\"prismatic\" (q moves d)");
      }
      if (slides) *prismatic |= 1U << j;
    }
  }
  *count = static_cast<int>(dh->array.size());
  return port::Error{};
}

/// "tools" (optional): every target's tool point, the first one equal to "tool". Both
/// conventions keep a tool point as written (model_from_modified_dh), so the others are too.
port::Error parse_other_tools(const JsonValue& root, const std::string& source, const double (&tool)[3],
                              RobotDescription* description) {
  const JsonValue* tools = root.find("tools");
  if (tools == nullptr) return port::Error{};
  const std::string shape = "\"tools\" must be 1 to " + std::to_string(kMaxTargets) + " points [x, y, z] in metres";
  if (tools->kind != JsonValue::Kind::array || tools->array.empty() || tools->array.size() > kMaxTargets) {
    return fail(source, shape);
  }
  for (std::size_t k = 0; k < tools->array.size(); ++k) {
    double point[3];
    if (!read_json_numbers(&tools->array[k], 3, point)) return fail(source, shape);
    const port::Error bounded = check_tool(point, "\"tools\"[" + std::to_string(k) + "]", source);
    if (!bounded.ok()) return bounded;
    if (k == 0 && (point[0] != tool[0] || point[1] != tool[1] || point[2] != tool[2])) {
      return fail(source, "\"tools\"[0] must equal \"tool\" (target 1)");
    }
    if (k > 0) target_tool(&description->model, static_cast<int>(k)) = Vec3(point[0], point[1], point[2]);
  }
  description->target_count = static_cast<int>(tools->array.size());
  return port::Error{};
}

/// Optional "joint_limits": one [lower, upper] pair per joint of the description's model, lower <
/// upper, a revolute joint's in rad within two turns, a prismatic joint's in m within
/// kMaxJointTravel_m.
port::Error parse_joint_limits(const JsonValue& root, const std::string& source, RobotDescription* description) {
  const JsonValue* limits = root.find("joint_limits");
  if (limits == nullptr) return port::Error{};
  const int joints = description->model.joint_count;
  if (limits->kind != JsonValue::Kind::array || limits->array.size() != static_cast<std::size_t>(joints)) {
    const std::string pairs = limits->kind == JsonValue::Kind::array
                                  ? std::to_string(limits->array.size()) + " pairs for "
                                  : std::string("not an array of pairs for ");
    return fail(source, "\"joint_limits\" must be one [lower, upper] pair per joint (" + pairs +
                            std::to_string(joints) + " joints in \"dh\")");
  }
  for (int j = 0; j < joints; ++j) {
    const bool slides = joint_type(description->model, j) == JointType::prismatic;
    const char* unit = slides ? " m" : " rad";
    const double bound = slides ? kMaxJointTravel_m : kMaxJointLimit_rad;
    double pair[2];
    const std::string at = "\"joint_limits\"[" + std::to_string(j) + "]";
    if (!read_json_numbers(&limits->array[static_cast<std::size_t>(j)], 2, pair)) {
      return fail(source, at + " must be [lower, upper] in" + unit);
    }
    if (!(pair[0] < pair[1]) || !(std::fabs(pair[0]) <= bound) || !(std::fabs(pair[1]) <= bound)) {
      return fail(source, at + " = [" + format_double(pair[0]) + ", " + format_double(pair[1]) + "]" + unit +
                              ": lower must be below upper, both within " +
                              (slides ? format_double(bound) + " m (a prismatic joint; millimetres?)"
                                      : std::string("two turns (4 pi rad; degrees?)")));
    }
    description->lower_rad(j) = pair[0];
    description->upper_rad(j) = pair[1];
  }
  description->has_joint_limits = true;
  return port::Error{};
}

port::Error parse_description(const JsonValue& root, const std::string& source, RobotDescription* description) {
  RobotDescription parsed;
  parsed.robot.clear();  // no built-in default: a file names its own arm (or read_robot_description names it)
  const JsonValue* robot = root.find("robot");
  if (robot != nullptr) {
    if (robot->kind != JsonValue::Kind::string) return fail(source, "\"robot\" must be a string");
    parsed.robot = robot->string;
  }
  const JsonValue* convention = root.find("convention");
  if (convention != nullptr) {
    const bool standard = convention->kind == JsonValue::Kind::string && convention->string == "standard-dh";
    const bool modified = convention->kind == JsonValue::Kind::string && convention->string == "modified-dh";
    if (!standard && !modified) {
      return fail(source, "unknown \"convention\"" +
                              (convention->kind == JsonValue::Kind::string ? " " + port::quoted(convention->string)
                                                                           : std::string()) +
                              ": \"standard-dh\" or \"modified-dh\"");
    }
    parsed.convention = modified ? DhConvention::modified : DhConvention::standard;
  }
  double rows[kMaxJoints][4];
  int joints = 0;
  std::uint32_t prismatic = 0;
  port::Error r = parse_dh_rows(root, source, rows, &joints, &prismatic);
  if (!r.ok()) return r;
  double tool[3];
  if (root.find("tool") == nullptr) return fail(source, "missing \"tool\" ([x, y, z] in metres)");
  if (!read_json_numbers(root.find("tool"), 3, tool)) return fail(source, "\"tool\" must be [x, y, z] in metres");
  r = check_tool(tool, "\"tool\"", source);
  if (!r.ok()) return r;
  const Vec3 tool_m(tool[0], tool[1], tool[2]);
  if (parsed.convention == DhConvention::standard) {
    parsed.model.joint_count = joints;
    parsed.model.prismatic_joints = prismatic;
    for (int j = 0; j < kMaxJoints; ++j) {
      parsed.model.joints[j] = j < joints ? DhJoint{rows[j][0], rows[j][1], rows[j][2], rows[j][3]} : DhJoint{};
    }
    parsed.model.tool_m = tool_m;
  } else {
    ModifiedDhRow modified[kMaxJoints];
    for (int j = 0; j < joints; ++j) modified[j] = ModifiedDhRow{rows[j][3], rows[j][2], rows[j][0], rows[j][1]};
    const Span<const ModifiedDhRow> written(modified, static_cast<std::size_t>(joints));
    if (model_from_modified_dh(written, tool_m, &parsed.model, &parsed.modified_base, prismatic) != Status::ok) {
      return fail(source, "\"dh\" or \"tool\" holds a number that is not finite");
    }
  }
  r = parse_other_tools(root, source, tool, &parsed);
  if (r.ok()) r = parse_joint_limits(root, source, &parsed);
  if (!r.ok()) return r;
  if (const JsonValue* compliance = root.find("compliance"); compliance != nullptr) {  // optional
    std::string what;
    const Mat3 to_file_base =
        parsed.convention == DhConvention::modified ? parsed.modified_base.transform().rotation : Mat3::Identity();
    if (!read_compliance(*compliance, to_file_base, parsed.model, &parsed.model.compliance, &what)) {
      return fail(source, "\"compliance\": " + what);
    }
  }
  *description = parsed;
  return port::Error{};
}

port::Error parse_root(const std::string& text, const std::string& source, JsonValue* root) {
  std::string_view body;
  const port::Error encoding = utf8_text(text, source, &body);  // UTF-16 is not malformed JSON
  if (!encoding.ok()) return encoding;
  const port::Error syntax = parse_json(text, root);
  if (!syntax.ok()) return fail(source, "malformed JSON: " + syntax.message);
  if (root->kind != JsonValue::Kind::object) return fail(source, "top level must be an object");
  return port::Error{};
}

port::Error check_format(const JsonValue& root, const std::string& source, bool required) {
  const JsonValue* format = root.find("format");
  if (format == nullptr && !required) return port::Error{};
  if (format == nullptr || format->kind != JsonValue::Kind::string || format->string != kFormat) {
    return fail(source, std::string("\"format\" must be \"") + kFormat + "\"");
  }
  return port::Error{};
}

/// The DH rows of `description` in its own convention: {theta_offset, d, a, alpha} each (its
/// model's joint_count rows), and the tool.
void rows_as_written(const RobotDescription& description, double (&rows)[kMaxJoints][4], Vec3* tool_m) {
  const int joints = description.model.joint_count;
  if (description.convention == DhConvention::standard) {
    for (int j = 0; j < joints; ++j) {
      const DhJoint& joint = description.model.joints[j];
      rows[j][0] = joint.theta_offset_rad;
      rows[j][1] = joint.d_m;
      rows[j][2] = joint.a_m;
      rows[j][3] = joint.alpha_rad;
    }
    *tool_m = description.model.tool_m;
    return;
  }
  ModifiedDhRow modified[kMaxJoints];
  modified_dh_from_model(description.model, description.modified_base, modified, tool_m);
  for (int j = 0; j < joints; ++j) {
    rows[j][0] = modified[j].theta_offset_rad;
    rows[j][1] = modified[j].d_m;
    rows[j][2] = modified[j].a_prev_m;
    rows[j][3] = modified[j].alpha_prev_rad;
  }
}

/// A term's load as written: "frame K" (point mass at DH frame K's origin), "tool", "arm masses".
std::string load_name(const ComplianceModel& compliance, const ComplianceTerm& term) {
  if (compliance.load == ComplianceLoad::arm_masses) return "arm masses";
  if (term.frame == kToolLoadFrame) return "tool";
  return "frame " + std::to_string(term.frame);
}

bool read_load(const std::string& text, ComplianceLoad load, int joints, ComplianceTerm* term) {
  if (load == ComplianceLoad::arm_masses) return text == "arm masses";
  if (text == "tool") {
    term->frame = kToolLoadFrame;
    return true;
  }
  for (int frame = 1; frame <= joints; ++frame) {
    if (text == "frame " + std::to_string(frame)) {
      term->frame = frame;
      return true;
    }
  }
  return false;
}

/// Link centres of mass in the library's (standard) DH frames, the payload's in the flange frame.
void write_masses(JsonWriter& json, const ArmMasses& masses, int joints) {
  json.key("masses").begin_object();
  json.key("link_mass_kg").inline_array(masses.link_mass_kg, static_cast<std::size_t>(joints));
  json.key("link_com_m").begin_array();
  for (int link = 0; link < joints; ++link) json.inline_array(masses.link_com_m[link].data(), 3);
  json.end_array();
  json.key("payload_kg").value(masses.payload_kg);
  json.key("payload_com_m").inline_array(masses.payload_com_m.data(), 3);
  json.end_object();
}

bool read_masses(const JsonValue* v, int joints, ArmMasses* masses, std::string* what) {
  const std::string n = std::to_string(joints);
  *what = "\"masses\" must hold link_mass_kg (" + n + " numbers, one per joint), link_com_m (" + n +
          " x [x, y, z]), payload_kg and payload_com_m";
  if (v == nullptr || v->kind != JsonValue::Kind::object) return false;
  const JsonValue* coms = v->find("link_com_m");
  if (!read_json_numbers(v->find("link_mass_kg"), static_cast<std::size_t>(joints), masses->link_mass_kg) ||
      coms == nullptr || coms->kind != JsonValue::Kind::array ||
      coms->array.size() != static_cast<std::size_t>(joints) ||
      !read_number(v->find("payload_kg"), &masses->payload_kg) ||
      !read_json_numbers(v->find("payload_com_m"), 3, masses->payload_com_m.data())) {
    return false;
  }
  for (std::size_t j = 0; j < coms->array.size(); ++j)
    if (!read_json_numbers(&coms->array[j], 3, masses->link_com_m[j].data())) return false;
  return true;
}

/// A harmonic term's function and order as written: "sin 1", "cos 2".
std::string harmonic_name(const ComplianceTerm& term) {
  return (term.kind == JointTermKind::harmonic_sin ? "sin " : "cos ") + std::to_string(term.order);
}

bool read_harmonic(const std::string& text, ComplianceTerm* term) {
  for (int order = 1; order <= kMaxHarmonicOrder; ++order) {
    for (const JointTermKind kind : {JointTermKind::harmonic_sin, JointTermKind::harmonic_cos}) {
      const ComplianceTerm candidate{term->joint, 0, kind, order};
      if (text == harmonic_name(candidate)) {
        *term = candidate;
        return true;
      }
    }
  }
  return false;
}

/// A term's basis: "harmonic" ("sin K" / "cos K") or "load" (gravity), into *term.
bool read_basis(const JsonValue& v, const std::string& at, const ComplianceModel& compliance, int joints,
                ComplianceTerm* term, std::string* what) {
  if (const JsonValue* harmonic = v.find("harmonic"); harmonic != nullptr) {
    if (harmonic->kind == JsonValue::Kind::string && read_harmonic(harmonic->string, term)) return true;
    *what = at + ".harmonic must be \"sin K\" or \"cos K\" (K = 1 .. " + std::to_string(kMaxHarmonicOrder) + ")";
    return false;
  }
  const JsonValue* load = v.find("load");
  if (load != nullptr && load->kind == JsonValue::Kind::string &&
      read_load(load->string, compliance.load, joints, term)) {
    return true;
  }
  *what = at + ".load must be " +
          (compliance.load == ComplianceLoad::arm_masses
               ? std::string("\"arm masses\"")
               : "\"frame K\" (K = 1 .. " + std::to_string(joints) + ") or \"tool\"") +
          ", or the term a \"harmonic\"";
  return false;
}

/// One term of a "terms" array into term `t` of *compliance.
bool read_term(const JsonValue& v, int t, int joints, ComplianceModel* compliance, std::string* what) {
  const std::string at = "\"terms\"[" + std::to_string(t) + "]";
  double joint = 0.0;
  const JsonValue* unit = v.find("unit");
  ComplianceTerm& term = compliance->terms[t];
  if (v.kind != JsonValue::Kind::object || !read_number(v.find("joint"), &joint) || joint < 1.0 ||
      joint > static_cast<double>(joints) || joint != static_cast<double>(static_cast<int>(joint))) {
    *what = at + ".joint must be a joint number 1 .. " + std::to_string(joints);
    return false;
  }
  term = ComplianceTerm{static_cast<int>(joint) - 1, 0, JointTermKind::gravity, 0};
  if (!read_basis(v, at, *compliance, joints, &term, what)) return false;
  if (!read_number(v.find("coefficient"), &compliance->coefficient[t]) ||
      !(std::fabs(compliance->coefficient[t]) <= kMaxJointTermCoefficient)) {
    *what = at + ".coefficient must be a number within +/-" + format_double(kMaxJointTermCoefficient) +
            " (rad/m or rad/(kg m); real arms: 1e-6..1e-4; rad for a harmonic)";
    return false;
  }
  const std::string expected_unit = is_harmonic(term) ? "rad" : compliance_unit(compliance->load);
  if (unit != nullptr && (unit->kind != JsonValue::Kind::string || unit->string != expected_unit)) {
    *what = at + ".unit must be \"" + expected_unit + "\"" +
            (is_harmonic(term) ? std::string(" for a harmonic")
                               : " for kind \"" + std::string(compliance_kind_name(compliance->load)) + "\"");
    return false;
  }
  return true;
}

}  // namespace

std::string beyond_bound(double value, ModelQuantity quantity) {
  const double bound = quantity == ModelQuantity::angle  ? kMaxModelAngle_rad
                       : quantity == ModelQuantity::tool ? kMaxToolLength_m
                                                         : kMaxModelLength_m;
  if (std::fabs(value) <= bound) return "";
  const char* unit = quantity == ModelQuantity::angle ? " rad" : " m";
  const char* cause = quantity == ModelQuantity::angle  ? " (two turns): degrees?"
                      : quantity == ModelQuantity::tool ? ": millimetres?"
                                                        : ": not a robot";
  return " = " + format_double(value) + unit + " is beyond " + format_double(bound) + unit + cause;
}

port::Error check_model_bounds(const RobotDescription& description, const std::string& source) {
  static const char* const kKeys[4] = {"theta_offset", "d", "a", "alpha"};
  double rows[kMaxJoints][4];
  Vec3 tool_m;
  rows_as_written(description, rows, &tool_m);
  for (int j = 0; j < description.model.joint_count; ++j) {
    for (int k = 0; k < 4; ++k) {
      const std::string beyond =
          beyond_bound(rows[j][k], k == 0 || k == 3 ? ModelQuantity::angle : ModelQuantity::length);
      if (!beyond.empty()) return fail(source, "its DH table, row " + std::to_string(j + 1) + ": " + kKeys[k] + beyond);
    }
  }
  for (int t = 0; t < description.target_count; ++t) {
    RobotDescription target = description;
    target.model.tool_m = hivecal::target_tool(description.model, t);
    rows_as_written(target, rows, &tool_m);
    for (int axis = 0; axis < 3; ++axis) {
      const std::string beyond = beyond_bound(tool_m(axis), ModelQuantity::tool);
      if (!beyond.empty()) {
        return fail(source, "tool point " + std::to_string(t + 1) + " (flange frame), " + "xyz"[axis] + beyond);
      }
    }
  }
  return port::Error{};
}

const char* compliance_unit(ComplianceLoad load) {
  return load == ComplianceLoad::arm_masses ? "rad/(kg m)" : "rad/m";
}

const char* term_unit(const ComplianceModel& compliance, int t) {
  return is_harmonic(compliance.terms[t]) ? "rad" : compliance_unit(compliance.load);
}

const char* compliance_kind_name(ComplianceLoad load) {
  return load == ComplianceLoad::arm_masses ? "masses" : "basis";
}

void write_compliance(JsonWriter& json, const RobotModel& model, const Mat3& to_file_base, const double* sigma) {
  const ComplianceModel& compliance = model.compliance;
  json.begin_object();
  json.key("kind").value(compliance_kind_name(compliance.load));
  const Vec3 gravity = to_file_base * compliance.gravity_direction;
  json.key("gravity_direction").inline_array(gravity.data(), 3);
  json.key("terms").begin_array();
  for (int t = 0; t < compliance.term_count; ++t) {
    json.begin_object();
    json.key("name").value(compliance_term_name(compliance, t));
    json.key("joint").value(static_cast<long long>(compliance.terms[t].joint + 1));
    const ComplianceTerm& term = compliance.terms[t];
    if (is_harmonic(term)) {
      json.key("harmonic").value(harmonic_name(term));
    } else {
      json.key("load").value(load_name(compliance, term));
    }
    json.key("coefficient").value(compliance.coefficient[t]);
    json.key("unit").value(term_unit(compliance, t));
    if (sigma != nullptr && sigma[t] > 0.0) json.key("sigma").value(sigma[t]);
    json.end_object();
  }
  json.end_array();
  if (compliance.load == ComplianceLoad::arm_masses) write_masses(json, compliance.masses, model.joint_count);
  json.end_object();
}

bool read_compliance(const JsonValue& value, const Mat3& to_file_base, const RobotModel& model,
                     ComplianceModel* compliance, std::string* what) {
  ComplianceModel parsed;
  const JsonValue* kind = value.find("kind");
  const JsonValue* terms = value.find("terms");
  Vec3 gravity;
  if (value.kind != JsonValue::Kind::object || kind == nullptr || kind->kind != JsonValue::Kind::string ||
      (kind->string != "basis" && kind->string != "masses")) {
    *what = "must be an object with \"kind\": \"basis\" or \"masses\"";
    return false;
  }
  parsed.load = kind->string == "masses" ? ComplianceLoad::arm_masses : ComplianceLoad::point;
  if (!read_json_numbers(value.find("gravity_direction"), 3, gravity.data())) {
    *what = "\"gravity_direction\" must be [x, y, z] (a unit vector in the robot base frame)";
    return false;
  }
  parsed.gravity_direction = to_file_base.transpose() * gravity;
  if (terms == nullptr || terms->kind != JsonValue::Kind::array || terms->array.empty() ||
      terms->array.size() > static_cast<std::size_t>(kMaxComplianceTerms)) {
    *what = "\"terms\" must be an array of 1 to " + std::to_string(kMaxComplianceTerms) + " terms";
    return false;
  }
  parsed.term_count = static_cast<int>(terms->array.size());
  for (int t = 0; t < parsed.term_count; ++t)
    if (!read_term(terms->array[static_cast<std::size_t>(t)], t, model.joint_count, &parsed, what)) return false;
  if (parsed.load == ComplianceLoad::arm_masses &&
      !read_masses(value.find("masses"), model.joint_count, &parsed.masses, what))
    return false;
  if (check_compliance(parsed, model) != Status::ok) {
    *what =
        "not a usable compliance model (a term's load must lie beyond its joint, masses >= 0, every number finite, "
        "gravity_direction of unit length)";
    return false;
  }
  *compliance = parsed;
  return true;
}

void write_description_members(JsonWriter& json, const RobotDescription& file, const double* compliance_sigma) {
  json.key("format").value(kFormat);
  json.key("robot").value(file.robot);
  json.key("convention").value(dh_convention_name(file.convention));
  double rows[kMaxJoints][4];
  Vec3 tool_m;
  rows_as_written(file, rows, &tool_m);
  json.key("dh").begin_array();
  const bool typed = !all_revolute(file.model);  // an all-revolute arm's rows need no "type"
  for (int j = 0; j < file.model.joint_count; ++j) {
    json.begin_object();
    json.key("theta_offset").value(rows[j][0]);
    json.key("d").value(rows[j][1]);
    json.key("a").value(rows[j][2]);
    json.key("alpha").value(rows[j][3]);
    if (typed) json.key("type").value(joint_type(file.model, j) == JointType::prismatic ? "prismatic" : "revolute");
    json.end_object();
  }
  json.end_array();
  json.key("tool").inline_array(tool_m.data(), 3);
  if (file.target_count > 1) {  // every target, as written in the file's convention
    json.key("tools").begin_array();
    for (int k = 0; k < file.target_count; ++k) {
      RobotDescription target = file;
      target.model.tool_m = hivecal::target_tool(file.model, k);
      Vec3 target_m;
      rows_as_written(target, rows, &target_m);
      json.inline_array(target_m.data(), 3);
    }
    json.end_array();
  }
  if (file.model.compliance.term_count > 0) {
    json.key("compliance");
    write_compliance(
        json, file.model,
        file.convention == DhConvention::modified ? file.modified_base.transform().rotation : Mat3::Identity(),
        compliance_sigma);
  }
  if (file.has_joint_limits) {
    json.key("joint_limits").begin_array();
    for (int j = 0; j < file.model.joint_count; ++j) {
      const double pair[2] = {file.lower_rad(j), file.upper_rad(j)};
      json.inline_array(pair, 2);
    }
    json.end_array();
  }
}

std::string format_robot_description(const RobotDescription& robot) {
  JsonWriter json;
  json.begin_object();
  write_description_members(json, robot, nullptr);
  json.end_object();
  return json.text();
}

const char* dh_convention_name(DhConvention convention) {
  return convention == DhConvention::modified ? "modified-dh" : "standard-dh";
}

port::Error parse_robot_description(const std::string& text, const std::string& source_name,
                                    RobotDescription* description) {
  JsonValue root;
  return parse_description_document(text, source_name, false, description, &root);
}

port::Error parse_description_document(const std::string& text, const std::string& source_name, bool format_required,
                                       RobotDescription* description, JsonValue* root) {
  port::Error r = parse_root(text, source_name, root);
  if (r.ok()) r = check_format(*root, source_name, format_required);
  if (r.ok()) r = parse_description(*root, source_name, description);
  return r;
}

}  // namespace hivecal::textio

namespace hivecal::textio {

port::Error read_robot_description(const std::string& path, RobotDescription* description) {
  std::string text;
  const port::Error read = port::read_whole_file(path, port::kMaxTextInputBytes, &text);
  if (!read.ok()) return read;
  std::string_view body;
  port::Error parsed = utf8_text(text, path, &body);
  if (!parsed.ok()) return parsed;
  const std::string_view start = trim(body);
  if (start.empty()) return port::Error::input(path + ": empty file");
  // A URDF (XML) or the JSON description, by content; anything else is neither (not "malformed JSON").
  if (start[0] == '<') {
    parsed = parse_urdf_description(body, path, description);
  } else if (start[0] == '{') {
    parsed = parse_robot_description(text, path, description);
  } else {
    return port::Error::input(path +
                              ": not a robot description: a JSON description starts with '{', a URDF with '<'; " +
                              "this file starts with " + port::quoted(start, 20));
  }
  if (parsed.ok() && description->robot.empty()) {  // unnamed: the file's name without folder and .json
    const std::size_t slash = path.find_last_of('/');
    std::string stem = slash == std::string::npos ? path : path.substr(slash + 1);
    for (const char* extension : {".json", ".urdf"}) {
      const std::size_t n = std::string(extension).size();
      if (stem.size() > n && stem.compare(stem.size() - n, n, extension) == 0) stem.resize(stem.size() - n);
    }
    description->robot = stem;
  }
  return parsed;
}

port::Error robot_description_from_value(const std::string& value, RobotDescription* description, bool* from_file) {
  RobotType type = RobotType::ur5;
  // A built-in name wins over a file or folder of that name in the working directory: `./ur5e` names the file.
  const bool builtin_name = robot_type_from_name(value.c_str(), &type) == Status::ok;
  const bool is_file = !builtin_name && !value.empty() && port::identify(value).exists;
  const bool json_name = (value.size() >= 5 && value.compare(value.size() - 5, 5, ".json") == 0) ||
                         (value.size() >= 5 && value.compare(value.size() - 5, 5, ".urdf") == 0);
  if (from_file != nullptr) *from_file = is_file || json_name;
  if (is_file || json_name) return read_robot_description(value, description);
  if (!builtin_name) {
    return port::Error::usage("unknown robot model " + port::quoted(value) + " (" + robot_type_names() +
                              ", or a robot description .json or .urdf file)");
  }
  RobotDescription builtin;
  builtin.robot = robot_type_name(type);
  builtin.model = nominal_model(type);
  builtin.convention = nominal_convention(type, &builtin.modified_base);  // the maker's (Franka: modified)
  // The seven-axis arms' published limits travel with the description (plan, result.json, URDF);
  // UR's +-360 deg joints carry none, as before.
  builtin.has_joint_limits = maker_joint_limits(type, &builtin.lower_rad, &builtin.upper_rad) == Status::ok;
  *description = builtin;
  return port::Error{};
}

}  // namespace hivecal::textio
