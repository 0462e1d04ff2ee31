#include "textio/text_util.hpp"

#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hivecal::textio {

bool read_text_file(const std::string& path, std::string* text, std::string* error) {
  const port::Error read = port::read_whole_file(path, port::kMaxTextInputBytes, text);
  if (!read.ok()) *error = read.message;
  return read.ok();
}

std::string_view trim(std::string_view s) {
  const char* blanks = " \t\r\n";
  const std::size_t first = s.find_first_not_of(blanks);
  if (first == std::string_view::npos) return {};
  const std::size_t last = s.find_last_not_of(blanks);
  return s.substr(first, last - first + 1);
}

bool parse_double(std::string_view field, double* value) {
  field = trim(field);
  if (field.empty()) return false;
  if (field.front() == '+') field.remove_prefix(1);
  const char* end = field.data() + field.size();
  const auto result = std::from_chars(field.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool write_file_atomically(const std::string& path, const std::string& content, std::string* error) {
  port::OutputSet outputs;
  std::size_t id = 0;
  port::Error result = outputs.add_file(path, "", &id);
  if (result.ok()) result = outputs.stage_text(id, "", content);
  if (result.ok()) result = outputs.commit();
  if (!result.ok()) *error = result.message;
  return result.ok();
}

std::string format_double(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

}  // namespace hivecal::textio
