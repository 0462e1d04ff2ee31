// The one error type of the hosted code (port/, apps/): a category that is also the process
// exit code (docs/cli.md), and a message for a person. lib/ keeps its Status codes.
#pragma once

#include <string>
#include <string_view>
#include <utility>

namespace hivecal::port {

/// What failed; the values are the exit codes of every hivecal command (docs/cli.md).
enum class Fault : int {
  none = 0,     ///< success
  failure = 1,  ///< the computation failed (e.g. no convergence)
  usage = 2,    ///< bad command line (unknown option, bad value, refused combination of paths)
  input = 3,    ///< an input is missing, unreadable, not a regular file, too large or malformed
  output = 4,   ///< an output cannot be created or written (stdout included)
};

/// Outcome of a hosted operation: ok, or a fault with its message.
struct Error {
  Fault fault = Fault::none;  ///< none when ok
  std::string message;        ///< what went wrong, naming the file (and line) at fault

  bool ok() const { return fault == Fault::none; }           ///< nothing went wrong
  int exit_code() const { return static_cast<int>(fault); }  ///< process exit code

  static Error failure(std::string m) { return Error{Fault::failure, std::move(m)}; }  ///< computation failed
  static Error usage(std::string m) { return Error{Fault::usage, std::move(m)}; }      ///< bad command line
  static Error input(std::string m) { return Error{Fault::input, std::move(m)}; }      ///< bad input
  static Error output(std::string m) { return Error{Fault::output, std::move(m)}; }    ///< output failed
};

/// Text from outside (file content, a path, an argument) made safe to print: control bytes,
/// DEL and bytes >= 0x80 become \xNN, and it is cut after `max_bytes` input bytes with a note
/// of the full length. Every message that echoes foreign text goes through this.
std::string printable(std::string_view text, std::size_t max_bytes = 80);

/// `text` quoted for a message: '<printable(text, max_bytes)>'.
std::string quoted(std::string_view text, std::size_t max_bytes = 80);

/// strerror(errno_value) as a string.
std::string system_message(int errno_value);

}  // namespace hivecal::port
