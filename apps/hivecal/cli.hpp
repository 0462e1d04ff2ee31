// Shared plumbing of the hivecal subcommands: option parsing, --help, exit codes, messages.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace hivecal::cli {

/// Process exit codes (docs/cli.md).
enum ExitCode : int {
  kExitOk = 0,           ///< success
  kExitFailure = 1,      ///< the computation failed (e.g. calibration did not converge)
  kExitUsage = 2,        ///< bad command line
  kExitBadInput = 3,     ///< an input file is missing, unreadable or malformed
  kExitOutputError = 4,  ///< an output file could not be written
};

/// One command-line option.
struct OptionSpec {
  std::string name;         ///< long name without dashes, e.g. "out"
  std::string value_name;   ///< e.g. "FILE"; empty for a flag
  std::string help;         ///< one line
  std::string default_value;  ///< shown in --help and used when absent (empty: none)
};

/// Parsed options of one subcommand.
class Options {
 public:
  /// Value of an option (or its default); empty when absent without default.
  std::string get(const std::string& name) const;
  /// True when a flag or valued option was given on the command line.
  bool given(const std::string& name) const { return values_.count(name) != 0; }

 private:
  friend int parse_options(const std::string&, const std::string&, const std::vector<OptionSpec>&, int, char**, Options*);
  std::map<std::string, std::string> values_;
  std::map<std::string, std::string> defaults_;
};

/// Parses argv (after the subcommand name). Returns -1 when the command should run;
/// otherwise the exit code to return at once: kExitOk after printing --help, kExitUsage
/// after printing what was wrong.
int parse_options(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs,
                  int argc, char** argv, Options* options);

/// Prints "hivecal <command>: <message>" to stderr.
void error(const std::string& command, const std::string& message);

/// True when progress lines should go to stderr (a terminal and not --quiet).
bool progress_enabled(const Options& options);

}  // namespace hivecal::cli
