#include "textio/csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>

#include "hivecal/core/math.hpp"
#include "hivecal/port/error.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  if (out.size() >= 2 && out.front() == '"' && out.back() == '"') out = out.substr(1, out.size() - 2);
  return out;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ",") + n;
  return out;
}

std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line) + ": "; }

}  // namespace

CsvReader::CsvReader(CsvSchema schema, std::uint64_t max_file_bytes)
    : schema_(std::move(schema)), max_file_bytes_(max_file_bytes) {}

CsvReader::~CsvReader() = default;

std::string CsvReader::expected_header() const {
  std::string expected = (schema_.optional_leading.empty() ? "" : "[" + schema_.optional_leading + ",]") +
                         join(schema_.columns);
  if (!schema_.optional_trailing.empty()) expected += "[," + join(schema_.optional_trailing) + "]";
  return expected;
}

bool CsvReader::match_header(const std::vector<std::string_view>& header) {
  offset_ = (!schema_.optional_leading.empty() && !header.empty() && lower(header[0]) == schema_.optional_leading) ? 1 : 0;
  if (header.size() < offset_ + schema_.columns.size()) return false;
  for (std::size_t i = 0; i < schema_.columns.size(); ++i) {
    if (lower(header[offset_ + i]) != schema_.columns[i]) return false;
  }
  trailing_ = 0;
  const std::size_t after = offset_ + schema_.columns.size();
  while (trailing_ < schema_.optional_trailing.size() && after + trailing_ < header.size() &&
         lower(header[after + trailing_]) == schema_.optional_trailing[trailing_]) {
    ++trailing_;
  }
  return true;
}

bool CsvReader::read_line(std::string* line, port::Error* error) {
  line->clear();
  for (;;) {
    const std::size_t newline = buffer_.find('\n', buffer_at_);
    if (newline != std::string::npos || (at_end_ && buffer_at_ < buffer_.size())) {
      const std::size_t end = newline == std::string::npos ? buffer_.size() : newline;
      line->assign(buffer_, buffer_at_, end - buffer_at_);
      bytes_read_ += end - buffer_at_ + (newline == std::string::npos ? 0 : 1);
      buffer_at_ = newline == std::string::npos ? buffer_.size() : newline + 1;
      break;
    }
    if (at_end_) return false;
    if (buffer_.size() - buffer_at_ > kMaxLineBytes) {
      *error = port::Error::input(where(path_, line_number_ + 1) + "line longer than " +
                                      std::to_string(kMaxLineBytes) + " bytes (not a CSV text file?)");
      return false;
    }
    buffer_.erase(0, buffer_at_);
    buffer_at_ = 0;
    std::uint8_t chunk[16384];
    std::size_t got = 0;
    if (file_.read(chunk, sizeof chunk, &got) != Status::ok) {
      *error = port::Error::input(file_.error().message);
      return false;
    }
    at_end_ = got == 0;
    buffer_.append(reinterpret_cast<const char*>(chunk), got);
  }
  ++line_number_;
  if (line->size() > kMaxLineBytes) {
    *error = port::Error::input(where(path_, line_number_) + "line longer than " + std::to_string(kMaxLineBytes) +
                                    " bytes (not a CSV text file?)");
    return false;
  }
  if (line->find('\0') != std::string::npos) {
    *error = port::Error::input(where(path_, line_number_) + "NUL byte in the line (binary data in a CSV file?)");
    return false;
  }
  if (line_number_ == 1 && line->compare(0, 3, "\xEF\xBB\xBF") == 0) line->erase(0, 3);  // BOM
  return true;
}

port::Error CsvReader::open(const std::string& path) {
  path_ = path;
  const port::Error opened = file_.open(path, max_file_bytes_);
  if (!opened.ok()) return opened;
  std::string line;
  port::Error error;
  while (read_line(&line, &error)) {
    if (trim(line).empty()) continue;
    if (!match_header(split_fields(line))) {
      return port::Error::input(where(path, line_number_) + "unexpected header " + port::quoted(trim(line)) +
                                    ", expected " + expected_header());
    }
    return port::Error{};
  }
  if (!error.ok()) return error;
  return port::Error::input(path + ": empty file (expected header " + expected_header() + ")");
}

port::Error CsvReader::next(CsvRow* row, bool* got_row) {
  *got_row = false;
  std::string line;
  port::Error error;
  while (read_line(&line, &error)) {
    if (trim(line).empty()) continue;
    const std::vector<std::string_view> fields = split_fields(line);
    const std::size_t needed = offset_ + schema_.columns.size() + trailing_;
    if (fields.size() < needed) {
      return port::Error::input(where(path_, line_number_) + "expected at least " + std::to_string(needed) +
                                    " columns, found " + std::to_string(fields.size()));
    }
    row->line = line_number_;
    row->trailing_present = trailing_;
    row->values.clear();
    for (std::size_t i = offset_; i < needed; ++i) {
      double v = 0.0;
      if (!parse_double(fields[i], &v)) {
        return port::Error::input(where(path_, line_number_) + "not a number: " + port::quoted(fields[i]));
      }
      row->values.push_back(v);
    }
    ++rows_;
    *got_row = true;
    return port::Error{};
  }
  if (!error.ok()) return error;
  if (rows_ == 0) return port::Error::input(path_ + ": no data rows");
  return port::Error{};
}

port::Error CsvReader::reject(const std::string& problem) const {
  return port::Error::input(where(path_, line_number_) + problem);
}

namespace {

/// Reads the whole file through `on_row`, which may reject a row by returning an error text.
port::Error read_csv(const std::string& path, const CsvSchema& schema,
                     const std::function<std::string(const CsvRow&)>& on_row) {
  CsvReader reader(schema);
  port::Error result = reader.open(path);
  CsvRow row;
  bool got_row = false;
  while (result.ok() && (result = reader.next(&row, &got_row)).ok() && got_row) {
    const std::string rejection = on_row(row);
    if (!rejection.empty()) return reader.reject(rejection);
  }
  return result;
}

std::string check_finite(const std::vector<double>& values, std::size_t first, std::size_t count) {
  for (std::size_t i = first; i < first + count; ++i) {
    if (!math::is_finite(values[i])) return "NaN or Inf in column " + std::to_string(i + 1);
  }
  return "";
}

const std::vector<std::string> kJointColumns = {"q1", "q2", "q3", "q4", "q5", "q6"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

std::string IncreasingTimestamps::check(double t_s) {
  if (started && !(t_s > last_s)) {
    return "timestamp " + format_double(t_s) + " s does not increase (previous " + format_double(last_s) + " s)";
  }
  started = true;
  last_s = t_s;
  return "";
}

namespace {

CsvSchema schema_of(const RobotLogRow*) { return CsvSchema{with({"t"}, kJointColumns), "", {}}; }
CsvSchema schema_of(const TrackerLogRow*) { return CsvSchema{{"t", "x", "y", "z"}, "", {"status"}}; }

/// Fills *row from a robot log row's values (t, q1..q6); "" or the problem.
std::string to_row(const CsvRow& raw, RobotLogRow* row) {
  const std::string error = check_finite(raw.values, 0, 7);
  if (!error.empty()) return error;
  row->t_s = raw.values[0];
  for (int j = 0; j < kJointCount; ++j) row->q_rad(j) = raw.values[static_cast<std::size_t>(j) + 1];
  return "";
}

/// Status 1 (beam lost) of the wire format: its position fields carry NaN.
constexpr std::uint8_t kBeamLostStatus = 1;

bool all_nan(const std::vector<double>& values, std::size_t first, std::size_t count) {
  for (std::size_t i = first; i < first + count; ++i) {
    if (!std::isnan(values[i])) return false;
  }
  return true;
}

/// Fills *row from a tracker log row's values (t, x, y, z[, status]); "" or the problem.
std::string to_row(const CsvRow& raw, TrackerLogRow* row) {
  row->status = 0;
  if (raw.trailing_present == 0) {
    // No status column: every row is valid, except one whose x, y and z are all NaN, which
    // is how the wire format marks a lost beam (a log written without the column keeps it).
    if (all_nan(raw.values, 1, 3)) row->status = kBeamLostStatus;
  } else {
    const double status = raw.values[4];
    if (!(status >= 0.0 && status <= 255.0) || status != static_cast<double>(static_cast<int>(status))) {
      return "status must be an integer 0..255";
    }
    row->status = static_cast<std::uint8_t>(status);
  }
  std::string error = check_finite(raw.values, 0, 1);
  if (error.empty() && row->status == 0) error = check_finite(raw.values, 1, 3);  // beam lost: NaN allowed
  if (!error.empty()) return error;
  row->t_s = raw.values[0];
  row->point_m << raw.values[1], raw.values[2], raw.values[3];
  return "";
}

}  // namespace

template <typename Row>
LogReader<Row>::LogReader() : csv_(schema_of(static_cast<const Row*>(nullptr))) {}

template <typename Row>
port::Error LogReader<Row>::next(Row* row, bool* got_row) {
  const port::Error result = csv_.next(&raw_, got_row);
  if (!result.ok() || !*got_row) return result;
  std::string error = to_row(raw_, row);
  if (error.empty()) error = timestamps_.check(row->t_s);
  return error.empty() ? result : csv_.reject(error);
}

template class LogReader<RobotLogRow>;
template class LogReader<TrackerLogRow>;

namespace {

/// Streams every row of a log reader into `on_row`.
template <typename Reader, typename Row>
port::Error read_log(const std::string& path, const std::function<void(const Row&)>& on_row) {
  Reader reader;
  port::Error result = reader.open(path);
  Row row;
  bool got_row = false;
  while (result.ok() && (result = reader.next(&row, &got_row)).ok() && got_row) on_row(row);
  return result;
}

}  // namespace

port::Error read_robot_log(const std::string& path, const std::function<void(const RobotLogRow&)>& on_row) {
  return read_log<RobotLogReader>(path, on_row);
}

port::Error read_tracker_log(const std::string& path, const std::function<void(const TrackerLogRow&)>& on_row) {
  return read_log<TrackerLogReader>(path, on_row);
}

port::Error read_samples_csv(const std::string& path, DatasetBase* dataset) {
  return read_csv(path, CsvSchema{with(kJointColumns, {"x", "y", "z"}), "", {}}, [&](const CsvRow& row) {
    const std::string error = check_finite(row.values, 0, 9);
    if (!error.empty()) return error;
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q(j) = row.values[static_cast<std::size_t>(j)];
    const Status status = dataset->add(q, Vec3(row.values[6], row.values[7], row.values[8]));
    if (status == Status::dataset_full) {
      return "dataset over capacity (" + std::to_string(dataset->capacity()) + " samples max)";
    }
    return status == Status::ok ? std::string() : std::string(status_message(status));
  });
}

port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses) {
  return read_csv(path, CsvSchema{kJointColumns, "t", {}}, [&](const CsvRow& row) {
    const std::string error = check_finite(row.values, 0, 6);
    if (!error.empty()) return error;
    JointVector q;
    for (int j = 0; j < kJointCount; ++j) q(j) = row.values[static_cast<std::size_t>(j)];
    poses->push_back(q);
    return std::string();
  });
}

std::string format_points_csv(const std::vector<Vec3>& points_m) {
  std::string out = "x,y,z\n";
  for (const Vec3& p : points_m) {
    out += format_double(p.x()) + "," + format_double(p.y()) + "," + format_double(p.z()) + "\n";
  }
  return out;
}

std::string format_samples_csv(Span<const Sample> samples) {
  std::string out = "q1,q2,q3,q4,q5,q6,x,y,z\n";
  for (const Sample& s : samples) {
    for (int j = 0; j < kJointCount; ++j) out += format_double(s.q_rad(j)) + ",";
    out += format_double(s.point_m.x()) + "," + format_double(s.point_m.y()) + "," + format_double(s.point_m.z()) + "\n";
  }
  return out;
}

StreamFileKind detect_stream_file(const std::string& path) {
  port::InputFile file;
  // Not a readable regular file: the capture reader reports the problem.
  if (!file.open(path, port::kMaxStreamInputBytes).ok() || file.is_stdin()) return StreamFileKind::capture;
  std::uint8_t head[512];
  std::size_t got = 0;
  if (file.read(head, sizeof head, &got) != Status::ok) return StreamFileKind::capture;
  std::size_t at = (got >= 3 && head[0] == 0xEF && head[1] == 0xBB && head[2] == 0xBF) ? 3 : 0;  // BOM
  bool comma = false;
  for (; at < got && head[at] != '\n'; ++at) {
    const unsigned char c = head[at];
    // A capture's frames end in 0x00 and are mostly bytes outside printable ASCII.
    if (!((c >= 0x20 && c < 0x7f) || c == '\t' || c == '\r')) return StreamFileKind::capture;
    comma = comma || c == ',';
  }
  return comma ? StreamFileKind::csv_log : StreamFileKind::capture;
}

}  // namespace hivecal::textio
