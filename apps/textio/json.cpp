#include "textio/json.hpp"

#include <cstdio>

#include "hivecal/core/math.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {

const JsonValue* JsonValue::find(const std::string& key) const {
  if (kind != Kind::object) return nullptr;
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &it->second;
}

namespace {

class JsonParser {
 public:
  explicit JsonParser(std::string_view text) : text_(text) {}

  bool parse_document(JsonValue* value, std::string* error) {
    skip_blanks();
    if (!parse_value(value, 0)) return fail_with(error);
    skip_blanks();
    if (pos_ != text_.size()) {
      problem_ = "unexpected text after the document";
      return fail_with(error);
    }
    return true;
  }

 private:
  static constexpr int kMaxDepth = 64;

  bool fail_with(std::string* error) {
    std::size_t line = 1;
    std::size_t column = 1;
    for (std::size_t i = 0; i < pos_ && i < text_.size(); ++i) {
      if (text_[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    *error = std::to_string(line) + ":" + std::to_string(column) + ": " + problem_;
    return false;
  }
  bool fail(const char* what) {
    problem_ = what;
    return false;
  }
  void skip_blanks() {
    while (pos_ < text_.size() &&
           (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\n' || text_[pos_] == '\r'))
      ++pos_;
  }
  bool consume(const char* word) {
    std::size_t n = 0;
    while (word[n] != '\0') ++n;
    if (text_.compare(pos_, n, word) != 0) return false;
    pos_ += n;
    return true;
  }

  bool parse_value(JsonValue* v, int depth) {
    if (depth > kMaxDepth) return fail("nesting too deep");
    if (pos_ >= text_.size()) return fail("unexpected end of input");
    const char c = text_[pos_];
    if (c == '{') return parse_object(v, depth);
    if (c == '[') return parse_array(v, depth);
    if (c == '"') {
      v->kind = JsonValue::Kind::string;
      return parse_string(&v->string);
    }
    if (consume("true")) {
      v->kind = JsonValue::Kind::boolean;
      v->boolean = true;
      return true;
    }
    if (consume("false")) {
      v->kind = JsonValue::Kind::boolean;
      return true;
    }
    if (consume("null")) {
      v->kind = JsonValue::Kind::null;
      return true;
    }
    return parse_number(v);
  }

  bool parse_number(JsonValue* v) {
    const std::size_t start = pos_;
    while (pos_ < text_.size() && std::string("+-0123456789.eE").find(text_[pos_]) != std::string::npos) ++pos_;
    if (start == pos_) return fail("expected a value");
    if (!parse_double(std::string_view(text_).substr(start, pos_ - start), &v->number) || !math::is_finite(v->number)) {
      pos_ = start;
      return fail("malformed number");
    }
    v->kind = JsonValue::Kind::number;
    return true;
  }

  bool parse_string(std::string* out) {
    ++pos_;  // opening quote
    while (pos_ < text_.size()) {
      const char c = text_[pos_++];
      if (c == '"') return true;
      if (static_cast<unsigned char>(c) < 0x20) return fail("control character in string");
      if (c != '\\') {
        out->push_back(c);
        continue;
      }
      if (pos_ >= text_.size()) break;
      const char e = text_[pos_++];
      switch (e) {
        case '"': out->push_back('"'); break;
        case '\\': out->push_back('\\'); break;
        case '/': out->push_back('/'); break;
        case 'b': out->push_back('\b'); break;
        case 'f': out->push_back('\f'); break;
        case 'n': out->push_back('\n'); break;
        case 'r': out->push_back('\r'); break;
        case 't': out->push_back('\t'); break;
        case 'u':
          if (!unicode_escape(out)) return false;
          break;
        default: return fail("bad escape");
      }
    }
    return fail("unterminated string");
  }

  /// Four hex digits at pos_ into *code.
  bool hex4(unsigned* code) {
    if (pos_ + 4 > text_.size()) return fail("short \\u escape");
    *code = 0;
    for (int i = 0; i < 4; ++i) {
      const char h = text_[pos_++];
      *code <<= 4U;
      if (h >= '0' && h <= '9')
        *code |= static_cast<unsigned>(h - '0');
      else if (h >= 'a' && h <= 'f')
        *code |= static_cast<unsigned>(h - 'a' + 10);
      else if (h >= 'A' && h <= 'F')
        *code |= static_cast<unsigned>(h - 'A' + 10);
      else
        return fail("bad \\u escape");
    }
    return true;
  }

  /// The code point of a backslash-u escape (a surrogate pair: two of them), appended as UTF-8.
  bool unicode_escape(std::string* out) {
    unsigned code = 0;
    if (!hex4(&code)) return false;
    if (code >= 0xDC00 && code <= 0xDFFF) return fail("\\u escape of a low surrogate without its high half");
    if (code >= 0xD800 && code <= 0xDBFF) {  // the high half: the low half must follow
      unsigned low = 0;
      if (text_.compare(pos_, 2, "\\u") != 0) return fail("\\u escape of a high surrogate without its low half");
      pos_ += 2;
      if (!hex4(&low)) return false;
      if (low < 0xDC00 || low > 0xDFFF) return fail("\\u escape of a high surrogate without its low half");
      code = 0x10000U + ((code - 0xD800U) << 10U) + (low - 0xDC00U);
    }
    const auto byte = [](unsigned value) { return static_cast<char>(static_cast<unsigned char>(value)); };
    if (code < 0x80U) {
      out->push_back(byte(code));
    } else if (code < 0x800U) {
      out->push_back(byte(0xC0U | (code >> 6U)));
      out->push_back(byte(0x80U | (code & 0x3FU)));
    } else if (code < 0x10000U) {
      out->push_back(byte(0xE0U | (code >> 12U)));
      out->push_back(byte(0x80U | ((code >> 6U) & 0x3FU)));
      out->push_back(byte(0x80U | (code & 0x3FU)));
    } else {
      out->push_back(byte(0xF0U | (code >> 18U)));
      out->push_back(byte(0x80U | ((code >> 12U) & 0x3FU)));
      out->push_back(byte(0x80U | ((code >> 6U) & 0x3FU)));
      out->push_back(byte(0x80U | (code & 0x3FU)));
    }
    return true;
  }

  bool parse_array(JsonValue* v, int depth) {
    v->kind = JsonValue::Kind::array;
    ++pos_;
    skip_blanks();
    if (pos_ < text_.size() && text_[pos_] == ']') {
      ++pos_;
      return true;
    }
    for (;;) {
      skip_blanks();
      v->array.emplace_back();
      if (!parse_value(&v->array.back(), depth + 1)) return false;
      skip_blanks();
      if (pos_ < text_.size() && text_[pos_] == ',') {
        ++pos_;
        continue;
      }
      if (pos_ < text_.size() && text_[pos_] == ']') {
        ++pos_;
        return true;
      }
      return fail("expected ',' or ']'");
    }
  }

  bool parse_object(JsonValue* v, int depth) {
    v->kind = JsonValue::Kind::object;
    ++pos_;
    skip_blanks();
    if (pos_ < text_.size() && text_[pos_] == '}') {
      ++pos_;
      return true;
    }
    for (;;) {
      skip_blanks();
      if (pos_ >= text_.size() || text_[pos_] != '"') return fail("expected a key string");
      std::string key;
      if (!parse_string(&key)) return false;
      skip_blanks();
      if (pos_ >= text_.size() || text_[pos_] != ':') return fail("expected ':'");
      ++pos_;
      skip_blanks();
      JsonValue member;
      if (!parse_value(&member, depth + 1)) return false;
      v->object[key] = std::move(member);
      skip_blanks();
      if (pos_ < text_.size() && text_[pos_] == ',') {
        ++pos_;
        continue;
      }
      if (pos_ < text_.size() && text_[pos_] == '}') {
        ++pos_;
        return true;
      }
      return fail("expected ',' or '}'");
    }
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  std::string problem_;
};

std::string escape(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string number_text(double x) {
  return math::is_finite(x) ? format_double(x) : "null";
}

}  // namespace

bool read_json_numbers(const JsonValue* value, std::size_t count, double* out) {
  if (value == nullptr || value->kind != JsonValue::Kind::array || value->array.size() != count) return false;
  for (std::size_t i = 0; i < count; ++i) {
    if (value->array[i].kind != JsonValue::Kind::number) return false;
    out[i] = value->array[i].number;
  }
  return true;
}

port::Error parse_json(const std::string& text, JsonValue* value) {
  *value = JsonValue();
  std::string error;
  std::string_view body;  // a UTF-8 byte order mark is not part of the document; UTF-16 is no JSON here
  const port::Error encoding = utf8_text(text, "the document", &body);
  if (!encoding.ok()) return encoding;
  if (JsonParser(body).parse_document(value, &error)) return port::Error{};
  return port::Error::input(error);
}

void JsonWriter::newline() {
  out_ += '\n';
  out_.append(2 * first_in_scope_.size(), ' ');
}

void JsonWriter::before_value() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_in_scope_.empty()) {
    if (!first_in_scope_.back()) out_ += ',';
    first_in_scope_.back() = false;
    newline();
  }
}

JsonWriter& JsonWriter::begin_object() {
  before_value();
  out_ += '{';
  first_in_scope_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::end_object() {
  const bool empty = first_in_scope_.back();
  first_in_scope_.pop_back();
  if (!empty) newline();
  out_ += '}';
  if (first_in_scope_.empty()) out_ += '\n';
  return *this;
}

JsonWriter& JsonWriter::begin_array() {
  before_value();
  out_ += '[';
  first_in_scope_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::end_array() {
  const bool empty = first_in_scope_.back();
  first_in_scope_.pop_back();
  if (!empty) newline();
  out_ += ']';
  return *this;
}

JsonWriter& JsonWriter::key(const std::string& name) {
  before_value();
  out_ += escape(name) + ": ";
  after_key_ = true;
  return *this;
}

JsonWriter& JsonWriter::value(double number) {
  before_value();
  out_ += number_text(number);
  return *this;
}

JsonWriter& JsonWriter::value(long long integer) {
  before_value();
  out_ += std::to_string(integer);
  return *this;
}

JsonWriter& JsonWriter::value(unsigned long long integer) {
  before_value();
  out_ += std::to_string(integer);
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& text) {
  before_value();
  out_ += escape(text);
  return *this;
}

JsonWriter& JsonWriter::value(const char* text) {
  return value(std::string(text));
}

JsonWriter& JsonWriter::value(bool flag) {
  before_value();
  out_ += flag ? "true" : "false";
  return *this;
}

JsonWriter& JsonWriter::inline_array(const double* values, std::size_t count) {
  before_value();
  out_ += '[';
  for (std::size_t i = 0; i < count; ++i) out_ += (i == 0 ? "" : ", ") + number_text(values[i]);
  out_ += ']';
  return *this;
}

namespace {

/// The end of the JSON value that starts at `pos` (after blanks): past its closing quote or
/// bracket, or the end of a scalar; text.size() when it does not end.
std::size_t value_end(const std::string& text, std::size_t pos) {
  int depth = 0;
  for (std::size_t i = pos; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      for (++i; i < text.size() && text[i] != '"'; ++i)
        if (text[i] == '\\') ++i;
      if (depth == 0) return i + 1;
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if (c == '}' || c == ']') {
      if (depth == 0) return i;  // a scalar's end at its object's close
      if (--depth == 0) return i + 1;
    } else if (depth == 0 && (c == ',' || c == ' ' || c == '\n' || c == '\r' || c == '\t')) {
      return i;
    }
  }
  return text.size();
}

}  // namespace

bool object_member_texts(const std::string& document, std::vector<JsonMemberText>* members) {
  members->clear();
  std::size_t i = document.find_first_not_of(" \t\r\n");
  if (document.compare(i == std::string::npos ? document.size() : i, 3, "\xEF\xBB\xBF") == 0) i += 3;
  i = document.find_first_not_of(" \t\r\n", i);
  if (i == std::string::npos || document[i] != '{') return false;
  for (++i;;) {
    i = document.find_first_not_of(" \t\r\n,", i);
    if (i == std::string::npos) return false;
    if (document[i] == '}') return true;
    if (document[i] != '"') return false;
    const std::size_t key_end = value_end(document, i);
    JsonValue key;
    if (!parse_json(document.substr(i, key_end - i), &key).ok() || key.kind != JsonValue::Kind::string) return false;
    const std::size_t colon = document.find_first_not_of(" \t\r\n", key_end);
    if (colon == std::string::npos || document[colon] != ':') return false;
    const std::size_t value = document.find_first_not_of(" \t\r\n", colon + 1);
    if (value == std::string::npos) return false;
    const std::size_t end = value_end(document, value);
    members->push_back({key.string, document.substr(i, end - i)});
    i = end;
  }
}

std::string object_document(const std::vector<JsonMemberText>& members) {
  std::string out = "{";
  for (std::size_t k = 0; k < members.size(); ++k) out += (k == 0 ? "\n  " : ",\n  ") + members[k].text;
  return out + (members.empty() ? "}\n" : "\n}\n");
}

}  // namespace hivecal::textio
