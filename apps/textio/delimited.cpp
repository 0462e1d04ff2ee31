#include "textio/delimited.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "hivecal/core/math.hpp"
#include "hivecal/port/error.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

constexpr std::size_t kBufferBytes = 16 * kMaxLineBytes;  // few freads, room for one whole line

/// A field without the double quotes some exporters put around every value or name.
std::string_view unquote(std::string_view s) {
  s = trim(s);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = trim(s.substr(1, s.size() - 2));
  return s;
}

/// A unit as written between brackets, lower case; the degree sign (UTF-8) is "deg".
std::string unit_of(std::string_view text) {
  std::string unit = lower(trim(text));
  if (unit == "\xC2\xB0") return "deg";
  // The micro prefix as the micro sign (U+00B5) or the Greek mu (U+03BC): "um", "us".
  for (const char* micro : {"\xC2\xB5", "\xCE\xBC"}) {
    if (unit.size() > 2 && unit.compare(0, 2, micro) == 0) return "u" + unit.substr(2);
  }
  return unit;
}

/// A unit token "[mm]" or "(mm)" (pendants and some tracker exports write parentheses).
bool is_unit_token(std::string_view token) {
  return token.size() >= 2 &&
         ((token.front() == '[' && token.back() == ']') || (token.front() == '(' && token.back() == ')'));
}

/// A header token into a column: "X [mm]" or "X (mm)" -> {"x", "mm"}.
Column column_of(std::string_view token) {
  token = unquote(token);
  const char close = token.empty() ? '\0' : token.back();
  const std::size_t open = close == ']' ? token.rfind('[') : close == ')' ? token.rfind('(') : std::string_view::npos;
  if (open == std::string_view::npos) return Column{lower(token), ""};
  return Column{lower(trim(token.substr(0, open))), unit_of(token.substr(open + 1, token.size() - open - 2))};
}

/// The header's delimiter: the first of tab, semicolon, comma found in it, else spaces.
Delimiter delimiter_of(std::string_view header) {
  if (header.find('\t') != std::string_view::npos) return Delimiter::tab;
  if (header.find(';') != std::string_view::npos) return Delimiter::semicolon;
  if (header.find(',') != std::string_view::npos) return Delimiter::comma;
  return Delimiter::spaces;
}

/// The columns --columns may name besides the joints q1 .. q<kMaxJoints> (the fixed formats' and
/// the orientation's).
const char* const kAliasColumns[] = {"x", "y", "z", "t", "rx", "ry", "rz"};

/// True for a unit si_scale() knows for any quantity.
bool known_unit(std::string_view unit) {
  double scale = 0.0;
  return si_scale(unit, Quantity::length, &scale) || si_scale(unit, Quantity::angle, &scale) ||
         si_scale(unit, Quantity::time, &scale);
}

/// True for a number written with points in thousands positions only: "2.568", "-1.234.567"
/// (not "0.568": no thousands separator follows a lone zero).
bool thousands_pointed(std::string_view field) {
  if (!field.empty() && (field.front() == '-' || field.front() == '+')) field.remove_prefix(1);
  const std::size_t point = field.find('.');
  if (point == std::string_view::npos || point == 0 || point > 3 || field.front() == '0') return false;
  for (std::size_t i = 0; i < point; ++i) {
    if (field[i] < '0' || field[i] > '9') return false;
  }
  std::size_t at = point;
  while (at < field.size()) {  // groups ".ddd"
    if (field[at] != '.' || at + 4 > field.size()) return false;
    for (std::size_t i = at + 1; i < at + 4; ++i) {
      if (field[i] < '0' || field[i] > '9') return false;
    }
    at += 4;
  }
  return true;
}

}  // namespace

std::vector<ColumnTerm> column_terms(std::string_view expression) {
  std::vector<ColumnTerm> terms;
  expression = trim(expression);
  double sign = 1.0;
  std::size_t start = 0;
  if (!expression.empty() && (expression.front() == '-' || expression.front() == '+')) {
    sign = expression.front() == '-' ? -1.0 : 1.0;
    start = 1;
  }
  for (;;) {
    const std::size_t stop = expression.find_first_of("+-", start);
    const std::string_view name =
        trim(expression.substr(start, stop == std::string_view::npos ? std::string_view::npos : stop - start));
    if (name.empty()) return {};
    terms.push_back(ColumnTerm{lower(name), sign});
    if (stop == std::string_view::npos) return terms;
    sign = expression[stop] == '-' ? -1.0 : 1.0;
    start = stop + 1;
  }
}

std::string joint_names(int count) {
  return count == 1 ? std::string("q1") : "q1..q" + std::to_string(count);
}

int joint_number(const std::string& column) {
  if (column.size() < 2 || column.size() > 3 || column[0] != 'q' || column[1] == '0') return 0;
  int k = 0;
  for (std::size_t i = 1; i < column.size(); ++i) {
    if (column[i] < '0' || column[i] > '9') return 0;
    k = 10 * k + (column[i] - '0');
  }
  return k;
}

std::string column_alias_text(const ColumnAlias& alias) {
  return alias.column + "=" + alias.header + (alias.unit.empty() ? "" : "[" + alias.unit + "]");
}

std::string parse_column_aliases(std::string_view text, std::vector<ColumnAlias>* aliases) {
  const std::size_t first_new = aliases->size();
  std::size_t begin = 0;
  while (!text.empty() && begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string_view entry = text.substr(begin, end - begin);
    begin = end + 1;
    const std::string shown = "--columns: " + port::quoted(entry);
    const std::size_t equals = entry.find('=');
    ColumnAlias alias;
    std::string_view spec;
    if (equals != std::string_view::npos) {
      alias.column = lower(trim(entry.substr(0, equals)));
      spec = trim(entry.substr(equals + 1));
    }
    const int joint = joint_number(alias.column);
    const bool known = (joint >= 1 && joint <= kMaxJoints) ||
                       std::find_if(std::begin(kAliasColumns), std::end(kAliasColumns),
                                    [&](const char* name) { return alias.column == name; }) != std::end(kAliasColumns);
    if (!known || spec.empty()) {
      return shown + " is not C=NAME or C=NAME[unit] with C one of " + joint_names(kMaxJoints) +
             " (the arm's joints), x, y, z, rx, ry, rz, t (e.g. x=measurement_x[mm], or a sum of columns "
             "x=x_t+x_dif[mm])";
    }
    const std::size_t open = spec.find('[');
    const std::size_t close = spec.find(']');
    if (open != std::string_view::npos || close != std::string_view::npos) {
      if (open == std::string_view::npos || close != spec.size() - 1 || spec.find('[', open + 1) != spec.npos) {
        return shown + ": a unit goes in one pair of brackets at the end, C=NAME[unit] (e.g. x=measurement_x[mm])";
      }
      alias.unit = unit_of(spec.substr(open + 1, close - open - 1));
      spec = trim(spec.substr(0, open));
      if (!known_unit(alias.unit)) {
        return shown + ": unknown unit " + port::quoted("[" + alias.unit + "]", 16) +
               "; one of [m], [mm], [um], [rad], [deg], [s], [ms], [us], [ns]";
      }
    }
    alias.header = lower(spec);
    if (column_terms(alias.header).empty()) {
      return shown + ": a name is missing in the sum (C=NAME, or C=NAME+NAME-NAME..., e.g. x=x_t+x_dif[mm])";
    }
    for (std::size_t k = first_new; k < aliases->size(); ++k) {
      if ((*aliases)[k].column == alias.column) return "--columns names " + alias.column + " twice";
    }
    aliases->push_back(alias);
  }
  return "";
}

const char* delimiter_name(Delimiter d) {
  switch (d) {
    case Delimiter::comma: return "comma";
    case Delimiter::semicolon: return "semicolon";
    case Delimiter::tab: return "tab";
    case Delimiter::spaces: return "space";
  }
  return "?";
}

bool si_scale(std::string_view unit, Quantity quantity, double* scale) {
  struct Known {
    const char* name;
    Quantity quantity;
    double scale;
  };
  static const Known kUnits[] = {
      {"m", Quantity::length, 1.0},
      {"mm", Quantity::length, 1e-3},
      {"um", Quantity::length, 1e-6},
      {"rad", Quantity::angle, 1.0},
      {"deg", Quantity::angle, math::kRadPerDeg},
      {"s", Quantity::time, 1.0},
      {"ms", Quantity::time, 1e-3},
      {"us", Quantity::time, 1e-6},
      {"ns", Quantity::time, 1e-9},
  };
  if (unit.empty()) {
    *scale = 1.0;
    return true;
  }
  for (const Known& k : kUnits) {
    if (k.quantity == quantity && unit == k.name) {
      *scale = k.scale;
      return true;
    }
  }
  return false;
}

bool written_resolution_exponent(std::string_view field, int* exponent) {
  int power = 0;
  const std::size_t e = field.find_first_of("eE");
  if (e != std::string_view::npos) {
    std::string_view digits = field.substr(e + 1);
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    const auto parsed = std::from_chars(digits.data(), digits.data() + digits.size(), power);
    if (parsed.ec != std::errc() || parsed.ptr != digits.data() + digits.size()) return false;
    field = field.substr(0, e);
  }
  if (!field.empty() && (field.front() == '+' || field.front() == '-')) field.remove_prefix(1);
  int decimals = 0;
  bool separator = false;
  bool digit = false;
  for (const char c : field) {
    if (c == '.' || c == ',') {
      if (separator) return false;
      separator = true;
    } else if (c >= '0' && c <= '9') {
      digit = true;
      decimals += separator ? 1 : 0;
    } else {
      return false;
    }
  }
  if (!digit) return false;
  *exponent = power - decimals;
  return true;
}

LineReader::~LineReader() = default;

bool LineReader::open(const std::string& path, std::uint64_t max_bytes) {
  name_ = path;
  const port::Error opened = file_.open(path, max_bytes);
  if (!opened.ok()) return fail(opened.message);
  from_file_ = true;
  buffer_.reset(new char[kBufferBytes]);
  data_ = buffer_.get();
  return true;
}

void LineReader::open_memory(std::string_view text, std::string name) {
  name_ = std::move(name);
  data_ = text.data();
  end_ = text.size();
  eof_ = true;
}

bool LineReader::fail(const std::string& problem) {
  error_ = problem;
  return false;
}

std::string LineReader::where() const {
  return name_ + ":" + std::to_string(line_number_) + ": ";
}

bool LineReader::refill() {
  if (!from_file_) return false;
  std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
  end_ -= begin_;
  begin_ = 0;
  std::size_t got = 0;
  if (file_.read(reinterpret_cast<std::uint8_t*>(buffer_.get() + end_), kBufferBytes - end_, &got) != Status::ok) {
    return fail(file_.error().message);
  }
  end_ += got;
  eof_ = got == 0;
  return true;
}

bool LineReader::read_encoding() {
  while (from_file_ && !eof_ && end_ - begin_ < 4) {  // the four bytes that tell UTF-32 from UTF-16
    if (!refill()) return false;
  }
  std::string_view body;
  const port::Error encoding = utf8_text(std::string_view(data_ + begin_, end_ - begin_), name_, &body);
  if (!encoding.ok()) return fail(encoding.message);
  const std::size_t mark = (end_ - begin_) - body.size();  // a UTF-8 byte order mark's bytes
  begin_ += mark;
  bytes_read_ += mark;
  return true;
}

bool LineReader::next(std::string_view* line) {
  if (!error_.empty() || data_ == nullptr) return false;
  if (line_number_ == 0 && bytes_read_ == 0 && !read_encoding()) return false;
  std::size_t length = 0;
  bool ended = false;  // by a '\n'
  for (;;) {
    const void* nl = std::memchr(data_ + begin_, '\n', end_ - begin_);
    if (nl != nullptr) {
      length = static_cast<std::size_t>(static_cast<const char*>(nl) - (data_ + begin_));
      ended = true;
      break;
    }
    if (end_ - begin_ > kMaxLineBytes || eof_) {
      length = end_ - begin_;
      break;
    }
    if (!refill()) return false;
  }
  if (length == 0 && !ended) return false;  // the end
  ++line_number_;
  if (length > kMaxLineBytes) {
    return fail(where() + "line longer than " + std::to_string(kMaxLineBytes) + " bytes: not a log of text rows");
  }
  std::string_view text(data_ + begin_, length);
  begin_ += length + (ended ? 1 : 0);
  bytes_read_ += length + (ended ? 1 : 0);
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      return fail(where() + "binary byte " + hex + " at byte " + std::to_string(i + 1) +
                  " of the line: not a text log (a serial capture?)");
    }
  }
  *line = text;
  return true;
}

bool DelimitedReader::fail(const std::string& problem) {
  if (error_.empty()) error_ = lines_.where() + problem;
  return false;
}

bool DelimitedReader::read_header() {
  std::string_view line;
  while (lines_.next(&line)) {
    if (trim(line).empty()) continue;
    header_ = std::string(trim(line));
    delimiter_ = delimiter_of(header_);
    if (!split(header_)) return false;
    columns_.clear();
    for (const std::string_view token : fields_) {
      // "Time [ms] X [mm]" with spaces between fields: a lone "[unit]" belongs to the name before it.
      if (delimiter_ == Delimiter::spaces && is_unit_token(token) && !columns_.empty() &&
          columns_.back().unit.empty()) {
        columns_.back().unit = unit_of(token.substr(1, token.size() - 2));
        continue;
      }
      columns_.push_back(column_of(token));
    }
    header_columns_ = columns_.size();
    return add_sum_columns();
  }
  if (!lines_.error().empty()) return false;
  error_ = lines_.name() + ": empty file (no header line)";
  return false;
}

bool DelimitedReader::add_sum_columns() {
  sums_.clear();
  for (const ColumnAlias& alias : units_.columns) {
    const bool whole = find(alias.header) >= 0;  // a name that holds '+' or '-' itself
    const std::vector<ColumnTerm> terms =
        whole ? std::vector<ColumnTerm>{{alias.header, 1.0}} : column_terms(alias.header);
    bool complete = !terms.empty();
    for (const ColumnTerm& term : terms) {
      complete = complete && find(term.name) >= 0;
      // A unit given with a --columns name ("rx=measurement_rx[deg]") is that column's header unit.
      for (Column& column : columns_) {
        if (alias.unit.empty() || column.name != term.name) continue;
        if (!column.unit.empty() && column.unit != alias.unit) {
          return fail("column " + port::quoted(column.name, 32) + " is in [" + column.unit +
                      "] by its header, but --columns gives [" + alias.unit + "]");
        }
        column.unit = alias.unit;
        column.unit_from_option = true;
      }
    }
    // A sum whose terms are not all here is the reader's to report (a log ignores --columns).
    if (whole || !complete) continue;
    SumColumn sum;
    Column column{alias.header, "", false};
    for (const ColumnTerm& term : terms) {
      const Column& read = columns_[static_cast<std::size_t>(find(term.name))];
      if (!sum.index.empty() && read.unit != column.unit) {
        return fail("--columns " + port::quoted(column_alias_text(alias)) + ": its terms are in [" + column.unit +
                    "] and [" + read.unit + "] by the header: a sum needs one unit");
      }
      column.unit = read.unit;
      column.unit_from_option = column.unit_from_option || read.unit_from_option;
      sum.index.push_back(static_cast<std::size_t>(find(term.name)));
      sum.sign.push_back(term.sign);
    }
    sums_.push_back(sum);
    columns_.push_back(column);
  }
  sum_fields_.assign(sums_.size(), std::string());
  return true;
}

bool DelimitedReader::compute_sums() {
  for (std::size_t k = 0; k < sums_.size(); ++k) {
    double total = 0.0;
    for (std::size_t t = 0; t < sums_[k].index.size(); ++t) {
      double term = 0.0;
      if (!number(sums_[k].index[t], 1.0, &term)) return false;
      total += sums_[k].sign[t] * term;
    }
    sum_fields_[k] = format_double(total);  // reads back to the same bits
  }
  for (const std::string& field : sum_fields_) fields_.push_back(field);
  return true;
}

bool DelimitedReader::check_separators(std::size_t index, std::string_view field) {
  if (delimiter_ == Delimiter::comma || index >= header_columns_) return true;  // a sum's field is ours
  const bool comma = field.find(',') != std::string_view::npos;
  SeparatorSeen& seen = comma ? decimal_comma_ : thousands_point_;
  if ((!comma && !thousands_pointed(field)) || seen.line != 0) return true;
  seen = SeparatorSeen{lines_.line_number(), columns_[index].name, std::string(field)};
  if (decimal_comma_.line == 0 || thousands_point_.line == 0) return true;
  const std::string comma_at = "line " + std::to_string(decimal_comma_.line) + ", column " +
                               port::quoted(decimal_comma_.column, 32) + ": " + port::quoted(decimal_comma_.text, 32);
  const std::string point_at = "line " + std::to_string(thousands_point_.line) + ", column " +
                               port::quoted(thousands_point_.column, 32) + ": " +
                               port::quoted(thousands_point_.text, 32);
  return fail("the file writes decimal commas (" + comma_at + ") and points in thousands positions (" + point_at +
              "): a thousands separator, which would be read as a decimal point; export the numbers without "
              "thousands separators");
}

int DelimitedReader::find(std::string_view name) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

bool DelimitedReader::split(std::string_view line) {
  fields_.clear();
  if (delimiter_ == Delimiter::spaces) {
    std::size_t at = 0;
    for (;;) {
      at = line.find_first_not_of(" \t\r", at);
      if (at == std::string_view::npos) break;
      const std::size_t stop = std::min(line.find_first_of(" \t\r", at), line.size());
      fields_.push_back(unquote(line.substr(at, stop - at)));
      at = stop;
      if (fields_.size() > kMaxColumns) break;
    }
  } else {
    const char d = static_cast<char>(delimiter_);
    std::size_t start = 0;
    for (;;) {
      const std::size_t stop = line.find(d, start);
      fields_.push_back(
          unquote(line.substr(start, stop == std::string_view::npos ? std::string_view::npos : stop - start)));
      if (stop == std::string_view::npos || fields_.size() > kMaxColumns) break;
      start = stop + 1;
    }
  }
  if (fields_.size() > kMaxColumns) return fail("more than " + std::to_string(kMaxColumns) + " fields in a line");
  return true;
}

bool DelimitedReader::next_row() {
  std::string_view line;
  while (lines_.next(&line)) {
    if (trim(line).empty()) continue;
    if (!split(line)) return false;
    if (fields_.size() != header_columns_) {
      const bool decimal_comma = delimiter_ == Delimiter::comma && fields_.size() > header_columns_;
      return fail(std::to_string(fields_.size()) + " fields where the header has " + std::to_string(header_columns_) +
                  " (" + delimiter_name(delimiter_) + "-separated)" +
                  (decimal_comma ? ": a comma used as decimal separator? Export with a '.' decimal point" : ""));
    }
    return compute_sums();
  }
  return false;
}

bool DelimitedReader::number(std::size_t index, double scale, double* value) {
  std::string_view field = fields_[index];
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  const char* end = field.data() + field.size();
  const auto parsed = std::from_chars(field.data(), end, *value);
  if (!field.empty() && parsed.ec == std::errc() && parsed.ptr == end) {
    *value *= scale;
    return check_separators(index, field);
  }
  // A field separated by ';', a tab or spaces may use a decimal comma (as a lab's locale
  // exports it): one comma and no point is read as the decimal separator.
  const std::size_t comma = field.find(',');
  if (delimiter_ != Delimiter::comma && comma != std::string_view::npos &&
      field.find(',', comma + 1) == std::string_view::npos && field.find('.') == std::string_view::npos) {
    std::string dotted(field);
    dotted[comma] = '.';
    const auto dotted_parsed = std::from_chars(dotted.data(), dotted.data() + dotted.size(), *value);
    if (dotted_parsed.ec == std::errc() && dotted_parsed.ptr == dotted.data() + dotted.size()) {
      *value *= scale;
      return check_separators(index, field);
    }
  }
  const std::string column = port::quoted(columns_[index].name, 32);
  if (field.find(',') != std::string_view::npos) {
    std::string dotted(field);
    for (char& c : dotted) c = c == ',' ? '.' : c;
    double ignored = 0.0;
    if (parse_double(dotted, &ignored)) {
      return fail("column " + column + ": " + port::quoted(fields_[index]) +
                  " has a comma decimal separator; export with a '.' decimal point (C locale)");
    }
  }
  return fail("column " + column + ": not a number: " + port::quoted(fields_[index]));
}

bool DelimitedReader::unit_assumed(std::size_t index, Quantity quantity) const {
  const std::string& declared = quantity == Quantity::length ? units_.length : units_.angle;
  return columns_[index].unit.empty() && (quantity == Quantity::time || declared.empty());
}

bool DelimitedReader::column_scale(std::size_t index, Quantity quantity, double* scale) {
  static const char* const kAccepted[] = {"[m], [mm], [um]", "[rad], [deg]", "[s], [ms], [us], [ns]"};
  static const char* const kOption[] = {"--length-unit", "--angle-unit", ""};
  const Column& c = columns_[index];
  const int q = static_cast<int>(quantity);
  const std::string none;
  const std::string& declared = quantity == Quantity::length  ? units_.length
                                : quantity == Quantity::angle ? units_.angle
                                                              : none;
  if (!si_scale(c.unit, quantity, scale)) {
    return fail("column " + port::quoted(c.name, 32) + ": unit " + port::quoted("[" + c.unit + "]", 16) +
                (c.unit_from_option ? " (given by --columns)" : "") + " is not one of " + kAccepted[q]);
  }
  if (c.unit.empty()) {
    if (si_scale(declared, quantity, scale)) return true;
    return fail(std::string(kOption[q]) + " " + port::quoted(declared, 16) + " is not one of " + kAccepted[q]);
  }
  if (!declared.empty() && declared != c.unit) {
    return fail("column " + port::quoted(c.name, 32) + " is in [" + c.unit + "] by " +
                (c.unit_from_option ? "--columns" : "its header") + ", but " + kOption[q] + " " + declared +
                " was given: the " +
                (c.unit_from_option ? "two options disagree" : "header unit and the option disagree"));
  }
  return true;
}

bool DelimitedReader::check_joint(int joint, std::size_t index, double q_rad) {
  if (!std::isfinite(q_rad) || std::fabs(q_rad) <= kMaxJointMagnitude_rad) return true;  // NaN: the caller's message
  const std::string name = "q" + std::to_string(joint);
  const std::string& column = columns_[index].name;
  std::string what = "joint " + name + (column == name ? "" : " (column " + port::quoted(column, 32) + ")") + " = " +
                     port::printable(fields_[index], 40);
  if (unit_assumed(index, Quantity::angle))
    return fail(what + " looks like degrees: use --angle-unit deg (joints are read in rad without it)");
  return fail(what + " is more than one turn (|q| > 2 pi rad) in the unit " +
              (columns_[index].unit.empty() ? "of --angle-unit" : "of its header") + ": not a joint position");
}

bool DelimitedReader::check_slide(int joint, std::size_t index, double q_m) {
  if (!std::isfinite(q_m) || std::fabs(q_m) <= kMaxJointTravel_m) return true;  // NaN: the caller's message
  const std::string name = "q" + std::to_string(joint);
  const std::string& column = columns_[index].name;
  std::string what = "prismatic joint " + name + (column == name ? "" : " (column " + port::quoted(column, 32) + ")") +
                     " = " + port::printable(fields_[index], 40);
  if (unit_assumed(index, Quantity::length))
    return fail(what + " looks like millimetres: use --length-unit mm (lengths are read in m without it)");
  char beyond[64];
  std::snprintf(beyond, sizeof beyond, " is more than %.0f m in the unit ", kMaxJointTravel_m);
  return fail(what + beyond + (columns_[index].unit.empty() ? "of --length-unit" : "of its header") +
              ": not a joint position");
}

bool DelimitedReader::check_point(const std::size_t index[3], const double point_m[3]) {
  const double distance_m = std::sqrt(point_m[0] * point_m[0] + point_m[1] * point_m[1] + point_m[2] * point_m[2]);
  if (!std::isfinite(distance_m) || distance_m <= kMaxPointDistance_m) return true;  // NaN: the caller's message
  char far[64];
  std::snprintf(far, sizeof far, " is %.4g m from the origin (more than %.0f m)", distance_m, kMaxPointDistance_m);
  std::string what = "point " + columns_[index[0]].name + "," + columns_[index[1]].name + "," +
                     columns_[index[2]].name + " = " + port::printable(fields_[index[0]], 24) + ", " +
                     port::printable(fields_[index[1]], 24) + ", " + port::printable(fields_[index[2]], 24) + far;
  bool assumed = true;
  for (int k = 0; k < 3; ++k) assumed = assumed && unit_assumed(index[k], Quantity::length);
  if (assumed) return fail(what + ": looks like millimetres: use --length-unit mm (lengths are read in m without it)");
  return fail(what + " in the unit of its " + (columns_[index[0]].unit.empty() ? "--length-unit" : "header") +
              ": not a measured point");
}

bool DelimitedReader::check_rotation(const std::size_t index[3], const double vector_rad[3]) {
  const double angle_rad =
      std::sqrt(vector_rad[0] * vector_rad[0] + vector_rad[1] * vector_rad[1] + vector_rad[2] * vector_rad[2]);
  if (!std::isfinite(angle_rad) || angle_rad <= kMaxJointMagnitude_rad) return true;  // NaN: the caller's message
  std::string what = "rotation vector " + columns_[index[0]].name + "," + columns_[index[1]].name + "," +
                     columns_[index[2]].name + " = " + port::printable(fields_[index[0]], 24) + ", " +
                     port::printable(fields_[index[1]], 24) + ", " + port::printable(fields_[index[2]], 24);
  bool assumed = true;
  for (int k = 0; k < 3; ++k) assumed = assumed && unit_assumed(index[k], Quantity::angle);
  if (assumed) return fail(what + " looks like degrees: use --angle-unit deg (angles are read in rad without it)");
  return fail(what + " turns more than once (|r| > 2 pi rad) in the unit of its " +
              (columns_[index[0]].unit.empty() ? "--angle-unit" : "header") + ": not a rotation vector");
}

bool DelimitedReader::whole_number(std::size_t index, std::uint64_t* value) const {
  const std::string_view field = fields_[index];
  const char* end = field.data() + field.size();
  const auto parsed = std::from_chars(field.data(), end, *value);
  return !field.empty() && parsed.ec == std::errc() && parsed.ptr == end;
}

}  // namespace hivecal::textio
