// Plumbing shared by every hivecal command: option parsing, --help, the shared option
// helpers, exit codes and the one way an error reaches the user (docs/cli.md).
#pragma once

#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/port/error.hpp"
#include "hivecal/port/output_files.hpp"
#include "textio/delimited.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::cli {

using port::Error;
using port::Fault;

/// Process exit codes of every command (docs/cli.md): the values of port::Fault.
enum ExitCode : int {
  kExitOk = static_cast<int>(Fault::none),             ///< success
  kExitFailure = static_cast<int>(Fault::failure),     ///< the computation failed (e.g. no convergence)
  kExitUsage = static_cast<int>(Fault::usage),         ///< bad command line, or refused paths
  kExitBadInput = static_cast<int>(Fault::input),      ///< an input is missing, not a regular file, or malformed
  kExitOutputError = static_cast<int>(Fault::output),  ///< an output cannot be created or written
  kExitWarnings = 5,  ///< calibrate: the result is written, but the fit looks implausible (warnings printed)
};

/// One command-line option.
struct OptionSpec {
  std::string name;           ///< long name without dashes, e.g. "out"
  std::string value_name;     ///< e.g. "FILE"; empty for a flag
  std::string help;           ///< one line
  std::string default_value;  ///< shown in --help and used when absent (empty: none)
  /// Non-empty: the value may be left out (`--compliance` alone, followed by another option
  /// or nothing) and is then this one.
  std::string bare_value{};
};

/// Parsed options of one subcommand.
class Options {
 public:
  /// Value of an option (or its default); empty when absent without default.
  std::string get(const std::string& name) const;
  /// True when a flag or valued option was given on the command line.
  bool given(const std::string& name) const { return values_.count(name) != 0; }
  /// Every option given on the command line, by name, with its value.
  const std::map<std::string, std::string>& given_values() const { return values_; }
  /// True when the command has option `name` (its messages may suggest it).
  bool accepts(const std::string& name) const { return accepted_.count(name) != 0; }

 private:
  friend int parse_options(const std::string&, const std::string&, const std::vector<OptionSpec>&, int, char**,
                           Options*);
  std::map<std::string, std::string> values_;
  std::map<std::string, std::string> defaults_;
  std::set<std::string> accepted_;  ///< the command's option names
};

/// Parses argv (after the subcommand name). Returns -1 when the command should run;
/// otherwise the exit code to return at once: kExitOk after printing --help, kExitUsage
/// after printing what was wrong.
int parse_options(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs,
                  int argc, char** argv, Options* options);

/// Prints "hivecal <command>: <message>" to stderr (control bytes escaped, cut when huge).
void error(const std::string& command, const std::string& message);
/// Prints a failed Error as error() does and returns its exit code (kExitOk when ok).
int exit_with(const std::string& command, const Error& result);

/// Declares as an input of `outputs` every given option, other than the run's outputs
/// `output_names`, whose value names an existing regular file (a robot description, a
/// calibration, joint limits, a log...): an input given as an output of the run (for example
/// --robot-model FILE as --out, or inside an output folder under a name the run writes) is
/// refused before anything is written, whichever option names it.
Error declare_inputs(const Options& options, const std::vector<std::string>& output_names, port::OutputSet* outputs);

/// True when progress lines should go to stderr (a terminal and not --quiet).
bool progress_enabled(const Options& options);

// --- option helpers shared by the commands (one parser per kind of value)
/// The values a number on the command line may take: lo .. hi, either end open or closed, in
/// `unit`. Every numeric option is checked against one (check_number): docs/cli.md, "Numbers
/// on the command line".
struct NumberRange {
  double lo = 0.0;       ///< smallest value (or the open end below it)
  double hi = 0.0;       ///< largest value (or the open end above it)
  bool lo_open = false;  ///< lo itself is refused: "(lo, ..."
  bool hi_open = false;  ///< hi itself is refused: "..., hi)"
  std::string unit{};    ///< what the message names after the range ("mm", "deg"); "" for none
  /// True for a finite value within the range.
  bool contains(double value) const;
  /// "[0, 1) rad", "(0, 1e+06] mm": the range as the messages write it.
  std::string text() const;
};
/// The one check of a number given on the command line: `text` (the value of `option`, named
/// with its dashes, e.g. "--tool") as a finite number within `range`. Otherwise Fault::usage
/// "OPTION must be within RANGE, got 'TEXT'", with what is wrong when it is not a number at all
/// ("not a number", "beyond a double's range", "underflows a double: give 0 or ...").
Error check_number(const std::string& option, std::string_view text, const NumberRange& range, double* value);
/// --<name> as any number but NaN, Inf included (the caller checks its range; check_number's
/// reasons for a text that is none). Prefer ranged_option.
Error number_option(const Options& options, const std::string& name, double* value);
/// --<name> as a number within `range` (check_number).
Error ranged_option(const Options& options, const std::string& name, const NumberRange& range, double* value);
/// --<name> as a finite number within [lo, hi]; the message names the option and the range.
Error bounded_option(const Options& options, const std::string& name, double lo, double hi, double* value);
/// `text` (the value of `option`) as a whole number within `range` (check_number); otherwise
/// also Fault::usage "OPTION must be a whole number, not 'TEXT'".
Error check_count(const std::string& option, std::string_view text, const NumberRange& range, std::size_t* value);
/// --<name> as a whole number within [lo, hi] (check_count).
Error count_option(const Options& options, const std::string& name, std::size_t lo, std::size_t hi, std::size_t* value);
/// --<name> as a seed: decimal digits, 0 .. 2^64 - 1, exactly (no rounding through a double).
Error seed_option(const Options& options, const std::string& name, std::uint64_t* value);
/// One number of an option that takes several ("X,Y,Z,SIDE"): its name and its range.
struct NumberField {
  std::string name;   ///< as the option's form writes it, e.g. "SIDE"
  NumberRange range;  ///< the values it may take
};
/// `text` (the value of `option`, e.g. "--iso9283") as one comma-separated number per field,
/// each through check_number, into values[0 .. fields.size()). Otherwise Fault::usage: another
/// count of numbers "OPTION must be N1,N2,... (WHAT), got 'TEXT'"; a number out of its range
/// "OPTION N1,N2,...: NAME must be within RANGE, got 'X'" (check_number's reasons for one that is
/// no number).
Error check_numbers(const std::string& option, std::string_view text, const std::string& what,
                    const std::vector<NumberField>& fields, double* values);
/// `text` as X,Y,Z (the value of `option`, e.g. "--tool"), each within `range`; otherwise
/// Fault::usage "OPTION must be X,Y,Z WHAT, each within RANGE, got 'TEXT'" (check_number's
/// reasons for a coordinate that is no number).
Error check_vec3(const std::string& option, std::string_view text, const std::string& what, const NumberRange& range,
                 Vec3* value);
/// Largest coordinate of a point option in metres (--tracker-position, --tool): the text
/// readers' bound on a point (textio::kMaxPointDistance_m) [m].
constexpr double kMaxPointOption_m = textio::kMaxPointDistance_m;
/// Largest coordinate of a tool point option (--tool of calibrate): the robot description's [m].
constexpr double kMaxToolOption_m = 10.0;
/// --<name> as X,Y,Z in metres (e.g. --tracker-position), each within +-kMaxPointOption_m.
Error vec3_option(const Options& options, const std::string& name, Vec3* value_m);
/// The default --tool of every command that takes one (calibrate, extract, iso9283, plan): the
/// reflector 169.5 mm along the flange z axis, as in the paper's session ("X,Y,Z" [m]).
inline constexpr const char* kDefaultToolText = "0,0,0.1695";
/// The options that give the tool point, for every command that takes one: --tool X,Y,Z (its
/// help `tool_help`, default kDefaultToolText), or --tool-transform FILE [--tool-transform-inverse]
/// (a lab's 4x4 flange/probe transform, lengths in --length-unit).
std::vector<OptionSpec> tool_option_specs(const std::string& tool_help);
/// The tool point [m] of tool_option_specs(): --tool-transform's (its translation, or its
/// inverse's with --tool-transform-inverse; *note says what was read and where the point went),
/// else --tool's, else `description_tool_m` (a robot description file's; nullptr: none), else
/// kDefaultToolText; each within +-kMaxToolOption_m. --tool with --tool-transform is refused.
/// *note is "" without --tool-transform.
Error tool_point_option(const Options& options, const textio::InputUnits& units, const Vec3* description_tool_m,
                        Vec3* tool_m, std::string* note);
/// True when the run was given a tool point (--tool or --tool-transform).
bool tool_given(const Options& options);
/// The options of every command that reads text inputs: --length-unit, --angle-unit.
std::vector<OptionSpec> input_unit_option_specs();
/// --length-unit (m|mm) and --angle-unit (rad|deg) into *units ("" when not given: SI unless
/// a header says otherwise); Fault::usage otherwise.
Error input_units_option(const Options& options, textio::InputUnits* units);
/// --<name> as a robot model: a built-in name (robot_type_names()) or a robot description
/// JSON file (an existing path, or a name ending in .json; textio::robot_description_from_value).
/// *from_file (optional): whether it was a file.
Error robot_model_option(const Options& options, const std::string& name, textio::RobotDescription* description,
                         bool* from_file = nullptr);

}  // namespace hivecal::cli
