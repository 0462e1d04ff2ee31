// Small locale-independent text helpers shared by the text formats.
#pragma once

#include <string>
#include <string_view>

#include "hivecal/port/error.hpp"

namespace hivecal::textio {

/// s without leading and trailing blanks (space, tab, CR, LF).
std::string_view trim(std::string_view s);
/// s with ASCII letters in lower case (locale-independent).
std::string lower(std::string_view s);
/// What parse_number found in a field.
enum class NumberText {
  ok,         ///< a number a double holds (NaN and Inf included)
  malformed,  ///< not a number, or trailing text
  overflow,   ///< a number beyond the largest double (~1.8e308)
  underflow,  ///< a non-zero number below the smallest double (~4.9e-324)
};
/// Parses a whole field as a double (C locale, blanks around it ignored, no trailing junk).
NumberText parse_number(std::string_view field, double* value);
/// Parses a whole field as a double (parse_number); false when it is not NumberText::ok.
bool parse_double(std::string_view field, double* value);
/// Writes `content` to `path` as the only output of a port::OutputSet (temporary beside it,
/// rename; special files refused, symlink and mode kept). On failure an older file stays.
port::Error write_text_file(const std::string& path, const std::string& content);
/// `text` as hivecal reads a text file: without a UTF-8 byte order mark. UTF-16 and UTF-32 (by
/// their byte order marks, or by the NUL bytes of ASCII so written) are refused: Fault::input
/// "SOURCE: UTF-16 text (little-endian): save it as UTF-8".
port::Error utf8_text(std::string_view text, const std::string& source, std::string_view* body);
/// Formats a double so that it reads back to the same bits: printf's "%.17g", C locale.
std::string format_double(double value);

}  // namespace hivecal::textio
