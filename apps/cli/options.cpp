#include "cli/options.hpp"

#include <string_view>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdio>
#include <sys/stat.h>
#include <unistd.h>

#include "hivecal/core/math.hpp"
#include "textio/delimited.hpp"
#include "textio/text_util.hpp"
#include "textio/transform_text.hpp"

namespace hivecal::cli {

std::string Options::get(const std::string& name) const {
  const auto it = values_.find(name);
  if (it != values_.end()) return it->second;
  const auto def = defaults_.find(name);
  return def == defaults_.end() ? std::string() : def->second;
}

void error(const std::string& command, const std::string& message) {
  // Messages quote foreign text already cut; this is the last guard for the terminal.
  std::fprintf(stderr, "hivecal %s: %s\n", command.c_str(), port::printable(message, 4096).c_str());
}

int exit_with(const std::string& command, const Error& result) {
  if (!result.ok()) error(command, result.message);
  return result.exit_code();
}

namespace {

void print_help(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs) {
  std::printf("usage: hivecal %s [options]\n\n%s\n\noptions:\n", command.c_str(), summary.c_str());
  for (const OptionSpec& spec : specs) {
    const std::string value = spec.bare_value.empty() ? spec.value_name : "[" + spec.value_name + "]";
    std::string left = "  --" + spec.name + (spec.value_name.empty() ? "" : " " + value);
    if (left.size() < 30) left.resize(30, ' ');
    std::printf("%s %s%s\n", left.c_str(), spec.help.c_str(),
                spec.default_value.empty() ? "" : (" (default: " + spec.default_value + ")").c_str());
  }
  std::printf("  --help                       this text\n");
}

}  // namespace

int parse_options(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs,
                  int argc, char** argv, Options* options) {
  for (const OptionSpec& spec : specs) {
    if (!spec.default_value.empty()) options->defaults_[spec.name] = spec.default_value;
    options->accepted_.insert(spec.name);
  }
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      print_help(command, summary, specs);
      return kExitOk;
    }
    if (arg.rfind("--", 0) != 0) {
      error(command, "unexpected argument " + port::quoted(arg) + " (see --help)");
      return kExitUsage;
    }
    std::string name = arg.substr(2);
    std::string value;
    bool has_inline_value = false;
    const std::size_t equals = name.find('=');
    if (equals != std::string::npos) {
      value = name.substr(equals + 1);
      name = name.substr(0, equals);
      has_inline_value = true;
    }
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& candidate : specs) {
      if (candidate.name == name) spec = &candidate;
    }
    if (spec == nullptr) {
      error(command, "unknown option " + port::quoted("--" + name) + " (see --help)");
      return kExitUsage;
    }
    if (spec->value_name.empty()) {
      if (has_inline_value) {
        error(command, "option --" + name + " takes no value");
        return kExitUsage;
      }
      options->values_[name] = "1";
      continue;
    }
    const bool bare = !spec->bare_value.empty() && (i + 1 >= argc || std::string(argv[i + 1]).rfind("--", 0) == 0);
    if (!has_inline_value && bare) {
      value = spec->bare_value;
    } else if (!has_inline_value) {
      if (i + 1 >= argc) {
        error(command, "option --" + name + " needs a value " + spec->value_name);
        return kExitUsage;
      }
      value = argv[++i];
    }
    options->values_[name] = value;
  }
  return -1;
}

bool progress_enabled(const Options& options) {
  return !options.given("quiet") && isatty(STDERR_FILENO) != 0;
}

bool NumberRange::contains(double value) const {
  return (lo_open ? value > lo : value >= lo) && (hi_open ? value < hi : value <= hi);
}

std::string NumberRange::text() const {
  char range[96];
  std::snprintf(range, sizeof range, "%c%g, %g%c", lo_open ? '(' : '[', lo, hi, hi_open ? ')' : ']');
  return range + (unit.empty() ? "" : " " + unit);
}

namespace {

/// Why a text that parse_number read as `read` is no value for `range` ("" for a number): the one
/// wording of check_number and check_vec3. 0 is advised for an underflow only where 0 is taken.
std::string number_reason(textio::NumberText read, const NumberRange& range) {
  switch (read) {
    case textio::NumberText::ok: return "";
    case textio::NumberText::malformed: return "not a number";
    case textio::NumberText::overflow: return "beyond a double's range (1.8e308)";
    case textio::NumberText::underflow:
      return std::string("too small for a double (it underflows below 4.9e-324): give ") +
             (range.contains(0.0) ? "0 or " : "") + "a larger value";
  }
  return "";
}

/// parse_number, with NaN as no number (a NaN is no value of any option).
textio::NumberText read_number(std::string_view text, double* value) {
  const textio::NumberText read = textio::parse_number(text, value);
  return read == textio::NumberText::ok && std::isnan(*value) ? textio::NumberText::malformed : read;
}

}  // namespace

Error check_number(const std::string& option, std::string_view text, const NumberRange& range, double* value) {
  double parsed = 0.0;
  const textio::NumberText read = read_number(text, &parsed);
  const bool unbounded = std::isinf(range.lo) && std::isinf(range.hi);  // number_option
  const std::string within = unbounded ? "" : " within " + range.text();
  const std::string got = ", got " + port::quoted(text);
  if (read == textio::NumberText::malformed) {
    return Error::usage(option + " must be a number" + within + got + ": " + number_reason(read, range));
  }
  if (read != textio::NumberText::ok) {
    return Error::usage(option + " must be" + (unbounded ? " a number" : within) + got + ": " +
                        number_reason(read, range));
  }
  if (!range.contains(parsed)) return Error::usage(option + " must be within " + range.text() + got);
  *value = parsed;
  return Error{};
}

Error number_option(const Options& options, const std::string& name, double* value) {
  return check_number("--" + name, options.get(name),
                      NumberRange{-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()},
                      value);
}

Error ranged_option(const Options& options, const std::string& name, const NumberRange& range, double* value) {
  return check_number("--" + name, options.get(name), range, value);
}

Error bounded_option(const Options& options, const std::string& name, double lo, double hi, double* value) {
  return ranged_option(options, name, NumberRange{lo, hi}, value);
}

Error check_count(const std::string& option, std::string_view text, const NumberRange& range, std::size_t* value) {
  double number = 0.0;
  Error error = check_number(option, text, range, &number);
  if (!error.ok()) return error;
  if (number < 0.0 || number != static_cast<double>(static_cast<std::size_t>(number))) {
    return Error::usage(option + " must be a whole number, not " + port::quoted(text));
  }
  *value = static_cast<std::size_t>(number);
  return Error{};
}

Error count_option(const Options& options, const std::string& name, std::size_t lo, std::size_t hi,
                   std::size_t* value) {
  return check_count("--" + name, options.get(name), NumberRange{static_cast<double>(lo), static_cast<double>(hi)},
                     value);
}

Error seed_option(const Options& options, const std::string& name, std::uint64_t* value) {
  const std::string text = std::string(textio::trim(options.get(name)));
  const char* end = text.data() + text.size();
  const auto parsed = std::from_chars(text.data(), end, *value);
  const bool digits =
      !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || parsed.ec != std::errc() || parsed.ptr != end) {
    return Error::usage("--" + name + " must be a whole number from 0 to 18446744073709551615, not " +
                        port::quoted(options.get(name)));
  }
  return Error{};
}

namespace {

/// `text` split at its commas into exactly `count` fields; false for another count.
bool split_fields(std::string_view text, std::size_t count, std::vector<std::string_view>* fields) {
  fields->clear();
  for (std::size_t start = 0;;) {
    const std::size_t comma = text.find(',', start);
    fields->push_back(text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields->size() == count;
}

}  // namespace

Error check_numbers(const std::string& option, std::string_view text, const std::string& what,
                    const std::vector<NumberField>& fields, double* values) {
  std::string form;
  for (const NumberField& field : fields) form += (form.empty() ? "" : ",") + field.name;
  std::vector<std::string_view> texts;
  if (!split_fields(text, fields.size(), &texts)) {
    return Error::usage(option + " must be " + form + (what.empty() ? "" : " (" + what + ")") + ", got " +
                        port::quoted(text));
  }
  std::vector<double> parsed(fields.size(), 0.0);
  for (std::size_t k = 0; k < fields.size(); ++k) {
    const Error error =
        check_number(option + " " + form + ": " + fields[k].name, texts[k], fields[k].range, &parsed[k]);
    if (!error.ok()) return error;
  }
  std::copy(parsed.begin(), parsed.end(), values);
  return Error{};
}

Error check_vec3(const std::string& option, std::string_view text, const std::string& what, const NumberRange& range,
                 Vec3* value) {
  const std::string shape = option + " must be X,Y,Z" + (what.empty() ? "" : " " + what) + ", each within " +
                            range.text() + ", got " + port::quoted(text);
  std::vector<std::string_view> fields;
  if (!split_fields(text, 3, &fields)) return Error::usage(shape);
  Vec3 parsed = Vec3::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    const std::string_view field = fields[static_cast<std::size_t>(axis)];
    const textio::NumberText read = read_number(field, &parsed(axis));
    if (read == textio::NumberText::overflow || read == textio::NumberText::underflow) {
      return Error::usage(shape + ": " + port::quoted(field) + " is " + number_reason(read, range));
    }
    if (read != textio::NumberText::ok || !range.contains(parsed(axis))) return Error::usage(shape);
  }
  *value = parsed;
  return Error{};
}

Error vec3_option(const Options& options, const std::string& name, Vec3* value_m) {
  return check_vec3("--" + name, options.get(name), "in metres",
                    NumberRange{-kMaxPointOption_m, kMaxPointOption_m, false, false, "m"}, value_m);
}

std::vector<OptionSpec> tool_option_specs(const std::string& tool_help) {
  return {
      {"tool", "X,Y,Z", tool_help, kDefaultToolText},
      {"tool-transform", "FILE",
       "instead of --tool: a 4x4 transform (text, one row per line; lengths in --length-unit), the tool frame's "
       "pose in the flange frame, whose translation is the tool point (its rotation is not used)",
       ""},
      {"tool-transform-inverse", "",
       "--tool-transform's file is the flange's pose in the tool frame (e.g. a lab's T_TOOL_F): its inverse's "
       "translation is the tool point",
       ""},
  };
}

bool tool_given(const Options& options) {
  return options.given("tool") || options.given("tool-transform");
}

namespace {

/// "x, y, z mm" of a point [m], to the micrometre (no "-0.000" for a rounding's sign).
std::string millimetres(const Vec3& point_m) {
  const Vec3 shown_mm = (point_m * 1e6).array().round() / 1e3 + 0.0;  // + 0.0: -0.0 becomes 0.0
  char text[96];
  std::snprintf(text, sizeof text, "%.3f, %.3f, %.3f mm", shown_mm.x(), shown_mm.y(), shown_mm.z());
  return text;
}

/// --tool-transform FILE [--tool-transform-inverse]: the tool point is the origin of the tool
/// frame in the flange frame, the translation of the file's transform (or of its inverse, when
/// the file is the flange's pose in the tool frame); *note says so, and what the rotation is.
Error tool_transform_option(const Options& options, const textio::InputUnits& units, Vec3* tool_m, std::string* note) {
  const std::string path = options.get("tool-transform");
  RigidTransform read;
  const Error error = textio::read_transform_text(path, units, &read);
  if (!error.ok()) return error;
  const bool inverse = options.given("tool-transform-inverse");
  const RigidTransform tool_in_flange = inverse ? read.inverse() : read;
  const Vec3 other_m = inverse ? read.translation_m : read.inverse().translation_m;  // the other reading's point
  *tool_m = tool_in_flange.translation_m;
  if (tool_m->cwiseAbs().maxCoeff() > kMaxToolOption_m) {
    return Error::usage("--tool-transform " + port::quoted(path) + " puts the tool point at " + millimetres(*tool_m) +
                        ", beyond " + textio::format_double(kMaxToolOption_m) + " m of the flange");
  }
  const double cosine = std::clamp((tool_in_flange.rotation.trace() - 1.0) / 2.0, -1.0, 1.0);
  char rotation[80];
  std::snprintf(rotation, sizeof rotation, "%.3f deg", std::acos(cosine) * math::kDegPerRad);
  *note = "tool point from --tool-transform " + port::printable(path, 4096) + ": " + millimetres(*tool_m) +
          " (the translation of " + (inverse ? "the inverse of the file's transform" : "the file's transform") +
          ", the tool frame's pose in the flange frame); its rotation, " + rotation +
          ", is not used: a reflector is a point";
  if (tool_m->z() < 0.0 && other_m.z() > 0.0) {
    *note += "; the point lies behind the flange (z < 0): if the file is the " +
             std::string(inverse ? "tool's pose in the flange frame, leave out --tool-transform-inverse"
                                 : "flange's pose in the tool frame (a lab's T_TOOL_F), add --tool-transform-inverse") +
             " (the point at " + millimetres(other_m) + ")";
  }
  return Error{};
}

}  // namespace

Error tool_point_option(const Options& options, const textio::InputUnits& units, const Vec3* description_tool_m,
                        Vec3* tool_m, std::string* note) {
  note->clear();
  const bool transform = options.given("tool-transform");
  if (transform && options.given("tool")) return Error::usage("give --tool or --tool-transform, not both");
  if (!transform && options.given("tool-transform-inverse")) {
    return Error::usage("--tool-transform-inverse needs --tool-transform FILE");
  }
  if (transform) return tool_transform_option(options, units, tool_m, note);
  if (description_tool_m != nullptr && !options.given("tool")) {
    *tool_m = *description_tool_m;
    return Error{};
  }
  return check_vec3("--tool", options.get("tool"), "in metres",
                    NumberRange{-kMaxToolOption_m, kMaxToolOption_m, false, false, "m"}, tool_m);
}

std::vector<OptionSpec> input_unit_option_specs() {
  return {
      {"length-unit", "m|mm", "unit of lengths (x, y, z) in text inputs whose header names none (default: m)", ""},
      {"angle-unit", "rad|deg", "unit of joint angles in text inputs whose header names none (default: rad)", ""},
      {"columns", "C=NAME,...",
       "read text inputs by column name: C (q1..qN: the arm's N joints, x, y, z, rx, ry, rz) is the header's column "
       "NAME, or a sum of "
       "columns, with an optional unit: x=measurement_x, x=x_t+x_dif[mm], q1=joint_1[deg] (ROS and pendant joint "
       "names are recognised without it)",
       ""},
  };
}

/// --columns C=SPEC,... into units->columns (textio::parse_column_aliases: the grammar's one place).
Error columns_option(const Options& options, textio::InputUnits* units) {
  const std::string problem = textio::parse_column_aliases(options.get("columns"), &units->columns);
  return problem.empty() ? Error{} : Error::usage(problem);
}

Error declare_inputs(const Options& options, const std::vector<std::string>& output_names, port::OutputSet* outputs) {
  std::string reads_stdin;  // the input option that reads stdin: one at most
  for (const auto& [name, value] : options.given_values()) {
    if (std::find(output_names.begin(), output_names.end(), name) != output_names.end()) continue;
    if (value == "-" && !reads_stdin.empty()) {
      return Error::usage("--" + reads_stdin + " and --" + name + " both read stdin ('-'): give one of them a file");
    }
    if (value == "-") reads_stdin = name;
    struct stat info {};
    if (value.empty() || value == "-" || ::stat(value.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) continue;
    const Error error = outputs->add_input(value, "--" + name);
    if (!error.ok()) return error;
  }
  return Error{};
}

Error input_units_option(const Options& options, textio::InputUnits* units) {
  const std::string length = options.get("length-unit");
  const std::string angle = options.get("angle-unit");
  if (!length.empty() && length != "m" && length != "mm") {
    return Error::usage("--length-unit must be 'm' or 'mm', not " + port::quoted(length));
  }
  if (!angle.empty() && angle != "rad" && angle != "deg") {
    return Error::usage("--angle-unit must be 'rad' or 'deg', not " + port::quoted(angle));
  }
  units->length = length;
  units->angle = angle;
  units->columns_option = options.accepts("columns");
  return columns_option(options, units);
}

Error robot_model_option(const Options& options, const std::string& name, textio::RobotDescription* description,
                         bool* from_file) {
  const Error error = textio::robot_description_from_value(options.get(name), description, from_file);
  if (error.ok() || error.fault != port::Fault::usage) return error;
  return Error::usage("--" + name + ": " + error.message);
}

}  // namespace hivecal::cli
