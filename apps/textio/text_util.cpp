#include "textio/text_util.hpp"

#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hivecal::textio {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return out;
}

std::string_view trim(std::string_view s) {
  const char* blanks = " \t\r\n";
  const std::size_t first = s.find_first_not_of(blanks);
  if (first == std::string_view::npos) return {};
  const std::size_t last = s.find_last_not_of(blanks);
  return s.substr(first, last - first + 1);
}

NumberText parse_number(std::string_view field, double* value) {
  field = trim(field);
  if (field.empty()) return NumberText::malformed;
  if (field.front() == '+') field.remove_prefix(1);
  const char* end = field.data() + field.size();
  double parsed = 0.0;
  const auto result = std::from_chars(field.data(), end, parsed);
  if (result.ptr != end) return NumberText::malformed;
  if (result.ec == std::errc::result_out_of_range) {
    // Too large or too small: a negative exponent, or no exponent and no non-zero integer digit, is small.
    const std::size_t e = field.find_first_of("eE");
    const std::string_view mantissa = field.substr(0, e);
    const std::string_view integer = mantissa.substr(0, mantissa.find('.'));
    const bool small = e != std::string_view::npos ? field.substr(e + 1, 1) == "-"
                                                   : integer.find_first_not_of("-0") == std::string_view::npos;
    return small ? NumberText::underflow : NumberText::overflow;
  }
  if (result.ec != std::errc()) return NumberText::malformed;
  *value = parsed;
  return NumberText::ok;
}

bool parse_double(std::string_view field, double* value) {
  return parse_number(field, value) == NumberText::ok;
}

port::Error write_text_file(const std::string& path, const std::string& content) {
  port::OutputSet outputs;
  std::size_t id = 0;
  port::Error result = outputs.add_file(path, "", &id);
  if (result.ok()) result = outputs.stage_text(id, "", content);
  return result.ok() ? outputs.commit() : result;
}

port::Error utf8_text(std::string_view text, const std::string& source, std::string_view* body) {
  // Which encoding the first bytes say: a byte order mark, or ASCII with its NUL bytes around
  // ('<', '{' or a blank written in UTF-16 or UTF-32).
  const auto starts = [&](std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; };
  const auto ascii_at = [&](std::size_t i) {
    return i < text.size() && text[i] != '\0' && static_cast<unsigned char>(text[i]) < 0x80;
  };
  const auto nul_at = [&](std::size_t i) { return i < text.size() && text[i] == '\0'; };
  const char* encoding = nullptr;
  if (starts(std::string_view("\xFF\xFE\0\0", 4)) || (ascii_at(0) && nul_at(1) && nul_at(2) && nul_at(3))) {
    encoding = "UTF-32 text (little-endian)";
  } else if (starts(std::string_view("\0\0\xFE\xFF", 4)) || (nul_at(0) && nul_at(1) && nul_at(2) && ascii_at(3))) {
    encoding = "UTF-32 text (big-endian)";
  } else if (starts("\xFF\xFE") || (ascii_at(0) && nul_at(1))) {
    encoding = "UTF-16 text (little-endian)";
  } else if (starts("\xFE\xFF") || (nul_at(0) && ascii_at(1))) {
    encoding = "UTF-16 text (big-endian)";
  }
  if (encoding != nullptr) return port::Error::input(source + ": " + encoding + ": save it as UTF-8");
  *body = starts("\xEF\xBB\xBF") ? text.substr(3) : text;  // a UTF-8 byte order mark, as some editors write it
  return port::Error{};
}

std::string format_double(double value) {
  // The characters of printf's "%.17g" in the C locale (the standard defines to_chars with a
  // precision so), about five times faster than snprintf: result.json writes every sample's
  // residuals with it.
  char buffer[32];
  const std::to_chars_result written =
      std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 17);
  return std::string(buffer, written.ptr);
}

}  // namespace hivecal::textio
