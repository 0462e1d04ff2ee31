#include "cli/options.hpp"

#include <string_view>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdio>
#include <sys/stat.h>
#include <unistd.h>

#include "textio/delimited.hpp"
#include "textio/text_util.hpp"

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

Error check_number(const std::string& option, std::string_view text, const NumberRange& range, double* value) {
  double parsed = 0.0;
  textio::NumberText read = textio::parse_number(text, &parsed);
  if (read == textio::NumberText::ok && std::isnan(parsed)) read = textio::NumberText::malformed;  // NaN: no value
  const bool unbounded = std::isinf(range.lo) && std::isinf(range.hi);                             // number_option
  const std::string within = unbounded ? "" : " within " + range.text();
  const std::string got = ", got " + port::quoted(text);
  switch (read) {
    case textio::NumberText::ok: break;
    case textio::NumberText::malformed:
      return Error::usage(option + " must be a number" + within + got + ": not a number");
    case textio::NumberText::overflow:
      return Error::usage(option + " must be" + (unbounded ? " a number" : within) + got +
                          ": beyond a double's range (1.8e308)");
    case textio::NumberText::underflow:
      return Error::usage(option + " must be" + (unbounded ? " a number" : within) + got +
                          ": too small for a double (it underflows below 4.9e-324): give 0 or a larger value");
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

Error count_option(const Options& options, const std::string& name, std::size_t lo, std::size_t hi,
                   std::size_t* value) {
  double number = 0.0;
  Error error = bounded_option(options, name, static_cast<double>(lo), static_cast<double>(hi), &number);
  if (!error.ok()) return error;
  if (number != static_cast<double>(static_cast<std::size_t>(number))) {
    return Error::usage("--" + name + " must be a whole number, not " + port::quoted(options.get(name)));
  }
  *value = static_cast<std::size_t>(number);
  return Error{};
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

bool parse_vec3(std::string_view text, Vec3* value) {
  std::size_t start = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t comma = text.find(',', start);
    const bool last = axis == 2;
    if (last != (comma == std::string_view::npos) ||
        !textio::parse_double(text.substr(start, last ? std::string_view::npos : comma - start), &(*value)(axis))) {
      return false;
    }
    start = comma + 1;
  }
  return true;
}

Error check_vec3(const std::string& option, std::string_view text, const std::string& what, const NumberRange& range,
                 Vec3* value) {
  const std::string shape = option + " must be X,Y,Z" + (what.empty() ? "" : " " + what) + ", each within " +
                            range.text() + ", got " + port::quoted(text);
  std::size_t start = 0;
  Vec3 parsed = Vec3::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t comma = text.find(',', start);
    if ((axis == 2) != (comma == std::string_view::npos)) return Error::usage(shape);
    const std::string_view field = text.substr(start, axis == 2 ? std::string_view::npos : comma - start);
    start = comma + 1;
    const textio::NumberText read = textio::parse_number(field, &parsed(axis));
    if (read == textio::NumberText::overflow) return Error::usage(shape + ": beyond a double's range (1.8e308)");
    if (read == textio::NumberText::underflow) {
      return Error::usage(shape + ": " + port::quoted(field) +
                          " is too small for a double (it underflows below 4.9e-324): give 0 or a larger value");
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

std::vector<OptionSpec> input_unit_option_specs() {
  return {
      {"length-unit", "m|mm", "unit of lengths (x, y, z) in text inputs whose header names none (default: m)", ""},
      {"angle-unit", "rad|deg", "unit of joint angles in text inputs whose header names none (default: rad)", ""},
      {"columns", "C=NAME,...",
       "read text inputs by column name: C (q1..q6, x, y, z, rx, ry, rz) is the header's column NAME, or a sum of "
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
