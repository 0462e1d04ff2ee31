#include "hivecal/port/error.hpp"

#include <cstdio>
#include <cstring>

namespace hivecal::port {

std::size_t utf8_sequence_bytes(std::string_view text, std::size_t at) {
  if (at >= text.size()) return 0;
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[at + k]); };
  const unsigned char lead = byte(0);
  if (lead < 0x80) return 1;
  // The lead byte's length and the range its first continuation byte may take: no overlong
  // form, no UTF-16 surrogate (U+D800..U+DFFF), nothing beyond U+10FFFF (RFC 3629's table).
  std::size_t length = 0;
  unsigned char low = 0x80;
  unsigned char high = 0xBF;
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    low = lead == 0xE0 ? 0xA0 : 0x80;
    high = lead == 0xED ? 0x9F : 0xBF;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    low = lead == 0xF0 ? 0x90 : 0x80;
    high = lead == 0xF4 ? 0x8F : 0xBF;
  } else {
    return 0;
  }
  if (at + length > text.size() || byte(1) < low || byte(1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k) {
    if ((byte(k) & 0xC0) != 0x80) return 0;
  }
  return length;
}

namespace {

/// True for a code point that steers a terminal or the text's direction rather than being
/// shown: C1 controls (U+0080..U+009F: U+009B is a CSI to some terminals) and the bidirectional
/// embeddings, overrides and isolates (U+202A..U+202E, U+2066..U+2069), which reorder what
/// follows them.
bool steering(std::string_view sequence) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(sequence[k]); };
  if (sequence.size() == 2) return b(0) == 0xC2 && b(1) <= 0x9F;
  if (sequence.size() != 3 || b(0) != 0xE2) return false;
  return (b(1) == 0x80 && b(2) >= 0xAA && b(2) <= 0xAE) || (b(1) == 0x81 && b(2) >= 0xA6 && b(2) <= 0xA9);
}

}  // namespace

std::string printable(std::string_view text, std::size_t max_bytes) {
  std::string out;
  const std::size_t shown = text.size() < max_bytes ? text.size() : max_bytes;
  out.reserve(shown + 16);
  std::size_t i = 0;
  while (i < shown) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t length = utf8_sequence_bytes(text, i);
    if (length > 1 && i + length > shown) break;  // a character is shown whole or not at all
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else if (c == '\t') {
      out += "\\t";
    } else if (length > 1 && !steering(text.substr(i, length))) {
      out.append(text.data() + i, length);  // UTF-8 as written: "µm", "°"
    } else {                                // a control byte, DEL, a steering character, or a byte that is no UTF-8
      for (std::size_t k = 0; k < (length > 1 ? length : 1); ++k) {
        char hex[5];
        std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned char>(text[i + k]));
        out += hex;
      }
    }
    i += length > 1 ? length : 1;
  }
  if (i < text.size()) out += "...[" + std::to_string(text.size()) + " bytes]";
  return out;
}

std::string quoted(std::string_view text, std::size_t max_bytes) {
  return "'" + printable(text, max_bytes) + "'";
}

std::string system_message(int errno_value) {
  return std::strerror(errno_value);
}

}  // namespace hivecal::port
