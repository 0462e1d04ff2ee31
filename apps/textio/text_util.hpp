// Small locale-independent text helpers shared by the text formats.
#pragma once

#include <string>
#include <string_view>

namespace hivecal::textio {

/// Whole file into *text; false with a message (including strerror) on failure.
bool read_text_file(const std::string& path, std::string* text, std::string* error);
/// s without leading and trailing blanks (space, tab, CR, LF).
std::string_view trim(std::string_view s);
/// Parses a whole field as a double (C locale, no trailing junk); false otherwise.
bool parse_double(std::string_view field, double* value);
/// Writes `content` to `path` atomically: a temporary in the same folder, fsync, rename.
/// On failure nothing is left at `path` (an older file stays untouched).
bool write_file_atomically(const std::string& path, const std::string& content, std::string* error);
/// Creates the folder `path` and its missing parents (like mkdir -p); true if it exists as
/// a folder afterwards, else false with a message.
bool make_directories(const std::string& path, std::string* error);
/// Formats a double so that it reads back to the same bits (%.17g).
std::string format_double(double value);

}  // namespace hivecal::textio
