// Names with numbers in them, built at compile time into static storage: the parameter and
// joint-term names of every joint a build holds ("theta7", "c_j7_tool", "h_j8_cos3"), without
// formatting at run time.
#pragma once

namespace hivecal::detail {

/// One name, NUL-terminated.
struct Name {
  char text[16] = {};  // the longest, "compliance100", has 13 characters
};

/// Appends `text` to *name at *at.
constexpr void append_text(Name* name, int* at, const char* text) {
  for (int k = 0; text[k] != '\0'; ++k) name->text[(*at)++] = text[k];
}

/// Appends the decimal digits of `number` (0 .. 999) to *name at *at.
constexpr void append_number(Name* name, int* at, int number) {
  if (number >= 100) name->text[(*at)++] = static_cast<char>('0' + number / 100);
  if (number >= 10) name->text[(*at)++] = static_cast<char>('0' + number / 10 % 10);
  name->text[(*at)++] = static_cast<char>('0' + number % 10);
}

/// prefix, number, middle, then `second` when it is not negative, then suffix: "c_j2_o4".
constexpr Name numbered_name(const char* prefix, int number, const char* middle = "", int second = -1,
                             const char* suffix = "") {
  Name name;
  int at = 0;
  append_text(&name, &at, prefix);
  append_number(&name, &at, number);
  append_text(&name, &at, middle);
  if (second >= 0) append_number(&name, &at, second);
  append_text(&name, &at, suffix);
  return name;
}

}  // namespace hivecal::detail
