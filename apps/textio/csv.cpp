#include "csv.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string_view>

#include "hivecal/math.hpp"
#include "text_util.hpp"

namespace hivecal::textio {
namespace {

/// Expected header: `columns` in order, optionally one `leading` column before them and
/// `trailing` optional columns after them; further columns are ignored.
struct CsvSchema {
  std::vector<std::string> columns;
  std::string optional_leading;
  std::vector<std::string> optional_trailing;
};

/// Values of one data row in schema order (columns, then present optional trailing ones).
struct CsvRow {
  std::size_t line = 0;
  std::vector<double> values;
  std::size_t trailing_present = 0;
};

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

/// Matches the header; sets the column offset (0 or 1) and how many trailing optionals exist.
bool match_header(const std::vector<std::string_view>& header, const CsvSchema& schema, std::size_t* offset,
                  std::size_t* trailing) {
  *offset = (!schema.optional_leading.empty() && !header.empty() && lower(header[0]) == schema.optional_leading) ? 1 : 0;
  if (header.size() < *offset + schema.columns.size()) return false;
  for (std::size_t i = 0; i < schema.columns.size(); ++i) {
    if (lower(header[*offset + i]) != schema.columns[i]) return false;
  }
  *trailing = 0;
  const std::size_t after = *offset + schema.columns.size();
  while (*trailing < schema.optional_trailing.size() && after + *trailing < header.size() &&
         lower(header[after + *trailing]) == schema.optional_trailing[*trailing]) {
    ++*trailing;
  }
  return true;
}

std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line) + ": "; }

/// Reads the file line by line (bounded memory), checks the header and parses each row's
/// numeric fields; `on_row` may reject a row by returning an error text.
ParseResult read_csv(const std::string& path, const CsvSchema& schema,
                     const std::function<std::string(const CsvRow&)>& on_row) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return ParseResult{false, path + ": cannot open: " + std::strerror(errno)};
  struct Closer {
    std::FILE* f;
    ~Closer() { std::fclose(f); }
  } closer{file};

  std::string expected = (schema.optional_leading.empty() ? "" : "[" + schema.optional_leading + ",]") +
                         join(schema.columns);
  if (!schema.optional_trailing.empty()) expected += "[," + join(schema.optional_trailing) + "]";
  std::string line;
  std::size_t line_number = 0;
  std::size_t offset = 0;
  std::size_t trailing = 0;
  bool have_header = false;
  std::size_t rows = 0;
  char buffer[4096];
  auto handle_line = [&](std::string_view text) -> ParseResult {
    ++line_number;
    if (line_number == 1 && text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // BOM
    if (trim(text).empty()) return ParseResult{true, ""};
    const std::vector<std::string_view> fields = split_fields(text);
    if (!have_header) {
      if (!match_header(fields, schema, &offset, &trailing)) {
        return ParseResult{false, where(path, line_number) + "unexpected header '" + std::string(trim(text)) +
                                      "', expected " + expected};
      }
      have_header = true;
      return ParseResult{true, ""};
    }
    const std::size_t needed = offset + schema.columns.size() + trailing;
    if (fields.size() < needed) {
      return ParseResult{false, where(path, line_number) + "expected at least " + std::to_string(needed) +
                                    " columns, found " + std::to_string(fields.size())};
    }
    CsvRow row;
    row.line = line_number;
    row.trailing_present = trailing;
    for (std::size_t i = offset; i < needed; ++i) {
      double v = 0.0;
      if (!parse_double(fields[i], &v)) {
        return ParseResult{false, where(path, line_number) + "not a number: '" + std::string(fields[i]) + "'"};
      }
      row.values.push_back(v);
    }
    const std::string rejection = on_row(row);
    if (!rejection.empty()) return ParseResult{false, where(path, line_number) + rejection};
    ++rows;
    return ParseResult{true, ""};
  };
  while (std::fgets(buffer, sizeof buffer, file) != nullptr) {
    line += buffer;
    if (line.empty() || line.back() != '\n') {
      if (!std::feof(file)) continue;  // a line longer than the buffer: keep reading
    }
    const ParseResult r = handle_line(line);
    line.clear();
    if (!r.ok) return r;
  }
  if (std::ferror(file) != 0) return ParseResult{false, path + ": read error"};
  if (!line.empty()) {
    const ParseResult r = handle_line(line);
    if (!r.ok) return r;
  }
  if (!have_header) return ParseResult{false, path + ": empty file (expected header " + expected + ")"};
  if (rows == 0) return ParseResult{false, path + ": no data rows"};
  return ParseResult{true, ""};
}

std::string check_finite(const std::vector<double>& values, std::size_t first, std::size_t count) {
  for (std::size_t i = first; i < first + count; ++i) {
    if (!math::is_finite(values[i])) return "NaN or Inf in column " + std::to_string(i + 1);
  }
  return "";
}

/// Rejects timestamps that do not strictly increase.
struct MonotonicClock {
  bool started = false;
  double last_s = 0.0;
  std::string check(double t_s) {
    if (started && !(t_s > last_s)) {
      return "timestamp " + format_double(t_s) + " s does not increase (previous " + format_double(last_s) + " s)";
    }
    started = true;
    last_s = t_s;
    return "";
  }
};

const std::vector<std::string> kJointColumns = {"q1", "q2", "q3", "q4", "q5", "q6"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

}  // namespace

ParseResult read_robot_log(const std::string& path, const std::function<void(const RobotLogRow&)>& on_row) {
  MonotonicClock clock;
  return read_csv(path, CsvSchema{with({"t"}, kJointColumns), "", {}}, [&](const CsvRow& row) {
    std::string error = check_finite(row.values, 0, 7);
    if (error.empty()) error = clock.check(row.values[0]);
    if (!error.empty()) return error;
    RobotLogRow out;
    out.t_s = row.values[0];
    for (int j = 0; j < kJointCount; ++j) out.q_rad(j) = row.values[static_cast<std::size_t>(j) + 1];
    on_row(out);
    return std::string();
  });
}

ParseResult read_tracker_log(const std::string& path, const std::function<void(const TrackerLogRow&)>& on_row) {
  MonotonicClock clock;
  return read_csv(path, CsvSchema{{"t", "x", "y", "z"}, "", {"status"}}, [&](const CsvRow& row) {
    TrackerLogRow out;
    if (row.trailing_present == 1) {
      const double status = row.values[4];
      if (!(status >= 0.0 && status <= 255.0) || status != static_cast<double>(static_cast<int>(status))) {
        return std::string("status must be an integer 0..255");
      }
      out.status = static_cast<std::uint8_t>(status);
    }
    std::string error = check_finite(row.values, 0, 1);
    if (error.empty() && out.status == 0) error = check_finite(row.values, 1, 3);
    if (error.empty()) error = clock.check(row.values[0]);
    if (!error.empty()) return error;
    out.t_s = row.values[0];
    out.point_m << row.values[1], row.values[2], row.values[3];
    on_row(out);
    return std::string();
  });
}

ParseResult read_samples_csv(const std::string& path, DatasetBase* dataset) {
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

ParseResult read_joints_csv(const std::string& path, std::vector<JointVector>* poses) {
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

bool looks_like_csv(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return false;
  unsigned char head[256];
  const std::size_t got = std::fread(head, 1, sizeof head, file);
  std::fclose(file);
  if (got == 0) return false;
  for (std::size_t i = 0; i < got; ++i) {
    const unsigned char c = head[i];
    if (c == '\n') return true;
    const bool printable = (c >= 0x20 && c < 0x7f) || c == '\t' || c == '\r' || c >= 0x80;
    if (!printable) return false;
  }
  return true;
}

}  // namespace hivecal::textio
