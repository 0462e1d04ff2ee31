// Readers and writers of the CSV formats of docs/formats.md (shared/spec/io-formats.md):
// robot joint log, tracker log, paired samples, poses to predict, predicted positions.
// Every error names the file and line; nothing is half-read silently.
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/ur_calibration_conf.hpp"  // port::Error

namespace hivecal::textio {

/// One row of a robot joint log (t on the robot clock).
struct RobotLogRow {
  double t_s = 0.0;                         ///< robot clock [s]
  JointVector q_rad = JointVector::Zero();  ///< joint positions [rad]
};

/// One row of a tracker log (t on the tracker clock).
struct TrackerLogRow {
  double t_s = 0.0;                 ///< tracker clock [s]
  Vec3 point_m = Vec3::Zero();      ///< position in the tracker frame [m] (NaN allowed when not valid)
  std::uint8_t status = 0;          ///< 0 valid, 1 beam lost, 2 unstable, other: not valid
};

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
/// Memory is one line (at most kMaxLineBytes), whatever the file length. Every error names
/// the file and line; a NUL byte or an over-long line is an error, never a silent cut.
/// The bytes come through port::InputFile (regular files or '-' only, size-checked).
class CsvReader {
 public:
  /// Longest line accepted [bytes].
  static constexpr std::size_t kMaxLineBytes = 64 * 1024;
  /// A reader of `schema`; `max_file_bytes` bounds the file [bytes].
  explicit CsvReader(CsvSchema schema, std::uint64_t max_file_bytes = port::kMaxStreamInputBytes);
  ~CsvReader();
  CsvReader(const CsvReader&) = delete;
  CsvReader& operator=(const CsvReader&) = delete;
  /// Opens `path` and reads its header (blank lines and a UTF-8 BOM are skipped).
  port::Error open(const std::string& path);
  /// Next data row into *row (*got_row true), or the end of the file (*got_row false; an
  /// error if the file had no data row), or an error.
  port::Error next(CsvRow* row, bool* got_row);
  /// An error at the current line: `problem` prefixed with file:line.
  port::Error reject(const std::string& problem) const;
  /// Bytes of the file read so far [bytes].
  std::uint64_t bytes_read() const { return bytes_read_; }

 private:
  /// Next line into *line (without its end); false at the end of the file or on an error
  /// (then *error is set).
  bool read_line(std::string* line, port::Error* error);
  bool match_header(const std::vector<std::string_view>& header);
  std::string expected_header() const;

  CsvSchema schema_;
  std::string path_;
  std::uint64_t max_file_bytes_;
  port::InputFile file_;
  std::string buffer_;        ///< bytes read and not yet returned as lines
  std::size_t buffer_at_ = 0;  ///< first unreturned byte of buffer_
  bool at_end_ = false;       ///< the file has no more bytes
  std::size_t line_number_ = 0;
  std::size_t offset_ = 0;    ///< 1 when the optional leading column is present
  std::size_t trailing_ = 0;  ///< optional trailing columns present
  std::size_t rows_ = 0;      ///< data rows returned so far
  std::uint64_t bytes_read_ = 0;
};

/// Rejects timestamps that do not strictly increase.
struct IncreasingTimestamps {
  bool started = false;  ///< a timestamp has been seen
  double last_s = 0.0;   ///< the last one [s]
  /// "" when t_s is later than the last one, else the problem.
  std::string check(double t_s);
};

/// Pull reader of a timed log: robot joint log (`t,q1..q6`, extra columns ignored) or tracker
/// log (`t,x,y,z[,status]`; no status: valid). Timestamps must increase.
template <typename Row>
class LogReader {
 public:
  LogReader();
  port::Error open(const std::string& path) { return csv_.open(path); }  ///< opens, checks the header
  std::uint64_t bytes_read() const { return csv_.bytes_read(); }          ///< [bytes]
  /// Next row (*got_row true), or the end (*got_row false), or an error naming file:line.
  port::Error next(Row* row, bool* got_row);

 private:
  CsvReader csv_;
  CsvRow raw_;
  IncreasingTimestamps timestamps_;
};
using RobotLogReader = LogReader<RobotLogRow>;      ///< robot joint log reader
using TrackerLogReader = LogReader<TrackerLogRow>;  ///< tracker log reader

/// Streams a robot joint log (`t,q1..q6`, extra columns ignored); timestamps must increase.
port::Error read_robot_log(const std::string& path, const std::function<void(const RobotLogRow&)>& on_row);
/// Streams a tracker log (`t,x,y,z[,status]`); timestamps must increase.
port::Error read_tracker_log(const std::string& path, const std::function<void(const TrackerLogRow&)>& on_row);
/// Reads paired static samples (`q1..q6,x,y,z`) into a dataset; reports a full dataset as an error.
port::Error read_samples_csv(const std::string& path, DatasetBase* dataset);
/// Reads poses to predict (`q1..q6`, optionally preceded by `t`).
port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses);

/// `x,y,z` rows with round-trip precision.
std::string format_points_csv(const std::vector<Vec3>& points_m);
/// `q1..q6,x,y,z` rows with round-trip precision.
std::string format_samples_csv(Span<const Sample> samples);

/// What a --robot/--tracker file is.
enum class StreamFileKind {
  capture,  ///< raw serial bytes (serial-protocol.md)
  csv_log,  ///< a CSV log of io-formats.md
};
/// Detects the kind by content: a first line of printable ASCII with a comma is a CSV log
/// (its header is checked when read); anything else, including an unreadable file, is a
/// capture (whose reader then reports the problem).
StreamFileKind detect_stream_file(const std::string& path);

}  // namespace hivecal::textio
