// Minimal JSON for the calibration result format: a writer that produces readable,
// round-trip-exact output, and a strict parser into a small value tree (hosted code only).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hivecal/port/error.hpp"

namespace hivecal::textio {

/// A parsed JSON value.
struct JsonValue {
  enum class Kind { null, boolean, number, string, array, object };
  Kind kind = Kind::null;                   ///< which member is meaningful
  bool boolean = false;                     ///< for Kind::boolean
  double number = 0.0;                      ///< for Kind::number
  std::string string;                       ///< for Kind::string
  std::vector<JsonValue> array;             ///< for Kind::array
  std::map<std::string, JsonValue> object;  ///< for Kind::object

  /// Member `key` of an object, or nullptr.
  const JsonValue* find(const std::string& key) const;
};

/// Parses a whole JSON text; Fault::input with "line:column: problem" on failure.
port::Error parse_json(const std::string& text, JsonValue* value);

/// Reads an array of exactly `count` numbers into out[]; false for anything else (out[] then
/// partly written).
bool read_json_numbers(const JsonValue* value, std::size_t count, double* out);

/// One member of a JSON object as it is written: its key, and its text from the key's opening
/// quote to the end of its value (nested members and layout as they are).
struct JsonMemberText {
  std::string key;   ///< the member's key, unescaped
  std::string text;  ///< `"key": value` as written
};

/// The members of the object a JSON document is, in their written order, each as written: a
/// file carried forward with some members replaced keeps the others byte for byte. False when
/// the document is not an object (parse_json checks the rest).
bool object_member_texts(const std::string& document, std::vector<JsonMemberText>* members);

/// An object document of `members` laid out as JsonWriter writes one (two-space indentation,
/// a newline at the end).
std::string object_document(const std::vector<JsonMemberText>& members);

/// Streaming writer with two-space indentation; numbers as %.17g (NaN/Inf written as null).
class JsonWriter {
 public:
  JsonWriter& begin_object();                                         ///< `{`
  JsonWriter& end_object();                                           ///< `}`
  JsonWriter& begin_array();                                          ///< `[`
  JsonWriter& end_array();                                            ///< `]`
  JsonWriter& key(const std::string& name);                           ///< `"name": ` inside an object
  JsonWriter& value(double number);                                   ///< a number
  JsonWriter& value(long long integer);                               ///< an integer
  JsonWriter& value(unsigned long long integer);                      ///< an unsigned integer (a 64-bit seed, exactly)
  JsonWriter& value(const std::string& text);                         ///< an escaped string
  JsonWriter& value(const char* text);                                ///< an escaped string
  JsonWriter& value(bool flag);                                       ///< true / false
  JsonWriter& inline_array(const double* values, std::size_t count);  ///< `[a, b, c]` on one line
  const std::string& text() const { return out_; }                    ///< the document so far

 private:
  void before_value();
  void newline();
  std::string out_;
  std::vector<bool> first_in_scope_;
  bool after_key_ = false;
};

}  // namespace hivecal::textio
