// One reader for the delimited text logs other tools write (io-formats.md, "Logs written by
// other tools"): the delimiter is taken from the header line (comma, semicolon, tab or runs
// of spaces), columns are found by name, a unit in brackets after a name converts to SI.
// Bounded: a line is at most kMaxLineBytes, read through a fixed buffer, whatever the file
// length. Refused with file:line: binary bytes (NUL, control bytes), over-long lines, comma
// decimal separators in comma-separated files (a ';', tab or space separated file may use a
// single decimal comma), rows whose field count differs from the header's. Messages quote the
// file's text through port::quoted() (control bytes escaped, long text cut). The units the
// user declares for columns without a bracket unit (--length-unit, --angle-unit) and the
// plausibility of joints and points read (degrees or millimetres taken for SI) are checked
// here too, for every text input.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/core/joints.hpp"
#include "hivecal/port/input_file.hpp"

namespace hivecal::textio {

constexpr std::size_t kMaxLineBytes = 65536;  ///< longest line read [bytes]; longer is refused
constexpr std::size_t kMaxColumns = 1024;     ///< most fields in a line; more is refused

/// What a column measures: decides which bracket units it accepts.
enum class Quantity { length, angle, time };

/// Factor from `unit` (text between the brackets, "" for none) to SI for a `quantity`
/// column: m, mm, um / rad, deg / s, ms, us, ns; "" is the SI unit itself. False when the
/// unit is not one of those of its quantity.
bool si_scale(std::string_view unit, Quantity quantity, double* scale);

/// One --columns entry: the format's column and the header name it has in the file (both as
/// Column::name: lower case, unit stripped), or a sum of header columns ("x_t+x_dif").
struct ColumnAlias {
  std::string column;  ///< e.g. "x"
  std::string header;  ///< e.g. "measurement_x", or "x_t+x_dif" (column_terms)
  std::string unit;    ///< e.g. "mm" from "measurement_x[mm]": the column's unit when its header gives none
};

/// One term of a --columns sum: a header column and its sign.
struct ColumnTerm {
  std::string name;   ///< the header column (Column::name)
  double sign = 1.0;  ///< +1 or -1
};

/// The --columns grammar (docs/formats.md, "Exports as a lab writes them"), in one place for
/// every reader: `C=SPEC,...` with C one of q1..qN, x, y, z, rx, ry, rz, t and SPEC a header column NAME or
/// a sum of them, `[-]NAME{(+|-)NAME}`, optionally followed by `[unit]` (m, mm, um or µm, rad,
/// deg, s, ms, us, ns), each C once. Names and units are lower-cased, blanks around them
/// ignored. Appends to *aliases; returns "" or the problem, quoting the option's entry.
std::string parse_column_aliases(std::string_view text, std::vector<ColumnAlias>* aliases);

/// The terms of a --columns SPEC without its unit: "x_t+x_dif" -> {x_t, +1}, {x_dif, +1};
/// "-x_dif" -> {x_dif, -1}; a name with neither sign is one term. A header column whose whole
/// name is `expression` is read as that column instead (a name may hold '+' or '-'). Empty
/// when a term is empty ("a++b", "a+").
std::vector<ColumnTerm> column_terms(std::string_view expression);

/// "C=SPEC[unit]" of an alias, as the messages quote it.
std::string column_alias_text(const ColumnAlias& alias);

/// Units the user declared for text columns whose header gives none (--length-unit,
/// --angle-unit); "" for not declared: the format's SI unit. A bracket unit in a header
/// wins; a declared unit that differs from it is an error.
/// The joints a text input's rows carry, as the robot model has them: q1 .. q<count>, a
/// prismatic joint's position a length (its unit --length-unit's), a revolute one's an angle.
struct InputJoints {
  int count = kSixJoints;       ///< joints of the arm, 1 .. kMaxJoints [-]
  std::uint32_t prismatic = 0;  ///< bit j set: joint j + 1 is prismatic [-]
  /// True when joint j (0-based) is prismatic.
  bool slides(int j) const { return (prismatic >> static_cast<unsigned>(j) & 1U) != 0; }
};

/// "q1..q6" for six joints ("q1" for one).
std::string joint_names(int count);
/// The number K when `column` is "qK" (K = 1 .. 99), else 0.
int joint_number(const std::string& column);

struct InputUnits {
  std::string length;  ///< "m", "mm" or "" (lengths: x, y, z)
  std::string angle;   ///< "rad", "deg" or "" (joints)
  /// Columns the user named (--columns x=measurement_x,...): a fixed format's column (x, q1,
  /// ...) found under another header name; the file is then read by name.
  std::vector<ColumnAlias> columns{};
  /// The command takes --columns: a header without the expected columns may suggest it.
  bool columns_option = true;
  /// The arm's joints (the robot model's: textio::input_joints): the joint columns a file must
  /// have, no more and no fewer; six revolute by default.
  InputJoints joints{};
};

/// Largest |joint| read as plausible: one turn either way [rad].
constexpr double kMaxJointMagnitude_rad = 6.283185307179586;
/// Largest joint limit a file may give: two turns (a J6 of +-720 deg) [rad].
constexpr double kMaxJointLimit_rad = 2.0 * kMaxJointMagnitude_rad;
/// Largest |position| or limit of a prismatic joint read as plausible (a rail of 100 m; more is
/// millimetres) [m].
constexpr double kMaxJointTravel_m = 100.0;
/// Farthest point from the tracker (or base) origin read as plausible [m].
constexpr double kMaxPointDistance_m = 100.0;

/// The place value of the last digit a number is written to, as a power of ten: "20.72" and
/// "20,72" give -2, "-115" gives 0, "1.5e-3" gives -4, "2,02011E+13" gives 8. False for a field
/// that is not a plain decimal number (nan, inf, hexadecimal, empty).
bool written_resolution_exponent(std::string_view field, int* exponent);

/// Lines of a text file or of text in memory, without their end (\n, \r\n). Its first bytes
/// go through utf8_text (text_util.hpp): a UTF-8 BOM is skipped, UTF-16 and UTF-32 stop it
/// ("save it as UTF-8"). Stops with error() set at a binary byte, a line over kMaxLineBytes or
/// a read error.
class LineReader {
 public:
  LineReader() = default;
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;
  /// Reads the file at `path` (port::InputFile: a regular file of at most `max_bytes`, or
  /// "-"); false with error() set when it cannot be opened.
  bool open(const std::string& path, std::uint64_t max_bytes = port::kMaxStreamInputBytes);
  /// Reads `text` (not copied: it must outlive the reader); `name` stands for it in messages.
  void open_memory(std::string_view text, std::string name);
  /// The next line into *line (valid until the next call); false at the end or on an error.
  bool next(std::string_view* line);
  const std::string& error() const { return error_; }       ///< why reading stopped, "" at a clean end
  std::size_t line_number() const { return line_number_; }  ///< 1-based number of the last line read
  std::uint64_t bytes_read() const { return bytes_read_; }  ///< [bytes]
  const std::string& name() const { return name_; }         ///< the file name used in messages
  /// "name:line: " for messages about the last line read.
  std::string where() const;

 private:
  bool refill();
  bool fail(const std::string& problem);
  /// Before the first line: the encoding its first bytes say (utf8_text); false with error() set.
  bool read_encoding();

  std::string name_;
  port::InputFile file_;
  bool from_file_ = false;
  /// File mode: kBufferBytes, the bytes read and not yet returned. Not zero-filled, so a small
  /// file touches only the pages its bytes reach (a zeroed 1 MiB was a quarter of the page
  /// faults of a short calibration).
  std::unique_ptr<char[]> buffer_;
  const char* data_ = nullptr;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  bool eof_ = false;
  std::size_t line_number_ = 0;
  std::uint64_t bytes_read_ = 0;
  std::string error_;
};

/// The field separator of a delimited file, chosen from its header line.
enum class Delimiter : char { comma = ',', semicolon = ';', tab = '\t', spaces = ' ' };

/// "comma", "semicolon", "tab" or "space", for messages.
const char* delimiter_name(Delimiter delimiter);

/// One header column: name in lower case without blanks, quotes and unit; unit text (in
/// brackets or parentheses after the name).
struct Column {
  std::string name;               ///< e.g. "x" for "X [mm]"
  std::string unit;               ///< e.g. "mm" from "[mm]" or "(mm)", "deg" from "(°)"; "" when the header gives none
  bool unit_from_option = false;  ///< the unit was given by --columns (NAME[unit]), not by the header
};

/// Delimited text, header first, then one row of fields per non-blank line.
class DelimitedReader {
 public:
  /// Opens the file (as LineReader::open); false with error() set.
  bool open(const std::string& path, std::uint64_t max_bytes = port::kMaxStreamInputBytes) {
    return lines_.open(path, max_bytes);
  }
  /// Reads `text` in memory (it must outlive the reader); `name` stands for it in messages.
  void open_memory(std::string_view text, std::string name) { lines_.open_memory(text, std::move(name)); }
  /// Units for columns without a bracket unit (default: SI); set before column_scale().
  void set_units(const InputUnits& units) { units_ = units; }
  /// Factor to SI of column `index` measuring `quantity`: its bracket unit, else the declared
  /// one (set_units), else 1. False with error() set for a unit of another quantity, an
  /// unknown one, or a bracket unit that differs from the declared one.
  bool column_scale(std::size_t index, Quantity quantity, double* scale);
  /// Checks joint `joint` (1-based), read from field `index` as `q_rad`: false with error()
  /// set ("joint q3 = 95.2 looks like degrees: use --angle-unit deg") beyond
  /// kMaxJointMagnitude_rad; true for NaN/Inf (refused by the caller with its own message).
  bool check_joint(int joint, std::size_t index, double q_rad);
  /// The same for a prismatic joint read as `q_m`: beyond kMaxJointTravel_m "... looks like
  /// millimetres: use --length-unit mm".
  bool check_slide(int joint, std::size_t index, double q_m);
  /// Checks a point read from fields `index[0..2]` as `point_m`: false with error() set
  /// ("... looks like millimetres: use --length-unit mm") beyond kMaxPointDistance_m; true
  /// for NaN/Inf (the caller's to refuse: a lost beam may carry NaN).
  bool check_point(const std::size_t index[3], const double point_m[3]);
  /// Checks a rotation vector read from fields `index[0..2]` as `vector_rad`: false with
  /// error() set beyond one turn (|r| > 2 pi; "looks like degrees: use --angle-unit deg" when
  /// no unit was named); true for NaN/Inf (the caller's to refuse).
  bool check_rotation(const std::size_t index[3], const double vector_rad[3]);
  /// Reads the header (first non-blank line): delimiter and columns. A --columns sum
  /// (InputUnits::columns, column_terms) whose terms are all in the header becomes one more
  /// column after the header's, named by its SPEC, whose field in each row is the sum of its
  /// terms (in their one unit, which is the column's). False with error() set for an empty
  /// file, a binary one, or a unit --columns gives that the header contradicts.
  bool read_header();
  const std::vector<Column>& columns() const { return columns_; }      ///< the header's columns, then the sums
  std::size_t header_column_count() const { return header_columns_; }  ///< columns of the header line itself
  Delimiter delimiter() const { return delimiter_; }                   ///< the header's delimiter
  const std::string& header_line() const { return header_; }           ///< the header as read
  /// Index of the first column named `name` (lower case), or -1.
  int find(std::string_view name) const;
  /// The next data row (blank lines skipped), with the sums of read_header() computed; false
  /// at the end or on an error (error() set).
  bool next_row();
  const std::vector<std::string_view>& fields() const { return fields_; }  ///< the row's fields, trimmed
  /// Field `index` of the row as a number times `scale`; false with error() set naming the
  /// line, the column and the text (a comma decimal separator is named as such). In a file
  /// that is not comma-separated a single decimal comma is read; a file whose numbers hold
  /// decimal commas and, elsewhere, points in thousands positions ("2.568": 2,568 written with
  /// a thousands separator) is refused at the second of the two, naming both lines.
  bool number(std::size_t index, double scale, double* value);
  /// Field `index` as an unsigned integer; false (no error set) when it is not all digits.
  bool whole_number(std::size_t index, std::uint64_t* value) const;
  /// Sets error() to "file:line: problem" and returns false.
  bool fail(const std::string& problem);
  const std::string& error() const { return error_.empty() ? lines_.error() : error_; }  ///< "" when none
  std::size_t line_number() const { return lines_.line_number(); }  ///< 1-based line of the last row
  std::uint64_t bytes_read() const { return lines_.bytes_read(); }  ///< [bytes]
  const std::string& name() const { return lines_.name(); }         ///< file name in messages
  /// "name:line: " for the last line read.
  std::string where() const { return lines_.where(); }

 private:
  bool split(std::string_view line);
  /// Appends the --columns sums of the header's columns (read_header).
  bool add_sum_columns();
  /// Fills the row's sum fields (next_row).
  bool compute_sums();
  /// Notes a number field's separators: false with error() set when the file holds decimal
  /// commas and thousands points both.
  bool check_separators(std::size_t index, std::string_view field);

  /// A column that is a sum of header columns.
  struct SumColumn {
    std::vector<std::size_t> index;  ///< the terms' header columns
    std::vector<double> sign;        ///< their signs, +1 or -1
  };
  /// Where a number was first written in one style: its line (0: not yet seen) and text.
  struct SeparatorSeen {
    std::size_t line = 0;  ///< 1-based line [-]
    std::string column;    ///< its column's name
    std::string text;      ///< the field as written
  };

  /// True when column `index` was read in SI because neither its header nor the user named a unit.
  bool unit_assumed(std::size_t index, Quantity quantity) const;

  LineReader lines_;
  InputUnits units_;
  Delimiter delimiter_ = Delimiter::comma;
  std::vector<Column> columns_;
  std::string header_;
  std::vector<std::string_view> fields_;
  std::size_t header_columns_ = 0;       ///< columns of the header line itself (the sums follow)
  std::vector<SumColumn> sums_;          ///< the --columns sums, columns header_columns_ ...
  std::vector<std::string> sum_fields_;  ///< the row's sums as text (%.17g), which fields_ views
  SeparatorSeen decimal_comma_;          ///< the first number with a decimal comma
  SeparatorSeen thousands_point_;        ///< the first number with a point in a thousands position
  std::string error_;
};

}  // namespace hivecal::textio
