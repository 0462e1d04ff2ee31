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

/// Text from outside (file content, a path, an argument, a name a file gives) made safe to
/// print: control bytes (C0, DEL, C1), the bidirectional overrides and isolates, and bytes that
/// are no valid UTF-8 become \xNN (per byte); other UTF-8 is kept ("µm", "°"). Cut after at
/// most `max_bytes` input bytes (never inside a character) with a note of the full length.
/// The one filter of every message that echoes foreign text, and of the report's text.
std::string printable(std::string_view text, std::size_t max_bytes = 80);

/// Bytes of the well-formed UTF-8 character at `text[at]` (1 for ASCII, 2..4 for a multi-byte
/// one: no overlong form, no surrogate, at most U+10FFFF); 0 when there is none there.
std::size_t utf8_sequence_bytes(std::string_view text, std::size_t at);

/// `text` quoted for a message: '<printable(text, max_bytes)>'.
std::string quoted(std::string_view text, std::size_t max_bytes = 80);

/// strerror(errno_value) as a string.
std::string system_message(int errno_value);

}  // namespace hivecal::port
