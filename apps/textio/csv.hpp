// Readers and writers of the fixed-column CSV formats of docs/formats.md
// (shared/spec/io-formats.md): paired samples, poses to predict, predicted positions. The
// robot and tracker logs (hivecal's and other tools') are read by logs.hpp.
// Every error names the file and line; nothing is half-read silently.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/model/dataset.hpp"
#include "hivecal/core/types.hpp"
#include "ur_calibration_conf.hpp"  // ParseResult

namespace hivecal::textio {

/// Expected header: `columns` in order, optionally one `optional_leading` column before them
/// and `optional_trailing` columns after them (in that order); further columns are ignored.
struct CsvSchema {
  std::vector<std::string> columns;            ///< required column names, lower case
  std::string optional_leading;                ///< a column that may come first (ignored), or ""
  std::vector<std::string> optional_trailing;  ///< columns that may follow, in order
};

/// Values of one data row in schema order (columns, then the optional trailing ones present).
struct CsvRow {
  std::size_t line = 0;              ///< 1-based line number in the file
  std::vector<double> values;        ///< numeric fields
  std::size_t trailing_present = 0;  ///< how many optional trailing columns the file has
};

/// Pull reader of a CSV file: checks the header, then parses one numeric row per next().
/// Memory is one line, whatever the file length. Every error names the file and line.
class CsvReader {
 public:
  explicit CsvReader(CsvSchema schema);
  ~CsvReader();
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;
  /// Opens `path` and reads its header (blank lines and a UTF-8 BOM are skipped).
  ParseResult open(const std::string& path);
  /// Next data row into *row (*got_row true), or the end of the file (*got_row false; an
  /// error if the file had no data row), or an error.
  ParseResult next(CsvRow* row, bool* got_row);
  /// An error at the current line: `problem` prefixed with file:line.
  ParseResult reject(const std::string& problem) const;
  /// Bytes of the file read so far [bytes].
  std::uint64_t bytes_read() const { return bytes_read_; }

 private:
  bool read_line(std::string* line);
  bool match_header(const std::vector<std::string_view>& header);
  std::string expected_header() const;

  CsvSchema schema_;
  std::string path_;
  std::FILE* file_ = nullptr;
  std::size_t line_number_ = 0;
  std::size_t offset_ = 0;    ///< 1 when the optional leading column is present
  std::size_t trailing_ = 0;  ///< optional trailing columns present
  std::size_t rows_ = 0;      ///< data rows returned so far
  std::uint64_t bytes_read_ = 0;
};

/// Reads paired static samples (`q1..q6,x,y,z`) into a dataset; reports a full dataset as an error.
ParseResult read_samples_csv(const std::string& path, DatasetBase* dataset);
/// Reads poses to predict (`q1..q6`, optionally preceded by `t`).
ParseResult read_joints_csv(const std::string& path, std::vector<JointVector>* poses);

/// `x,y,z` rows with round-trip precision.
std::string format_points_csv(const std::vector<Vec3>& points_m);
/// `q1..q6,x,y,z` rows with round-trip precision.
std::string format_samples_csv(Span<const Sample> samples);

}  // namespace hivecal::textio
