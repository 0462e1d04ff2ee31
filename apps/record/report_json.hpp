// ReportData in result.json (key "report", docs/formats.md): calibrate writes it, `hivecal
// report` reads it back and draws the same page. Numbers round-trip exactly (%.17g); stage
// times are not written (result files hold no wall-clock values).
#pragma once

#include <string>
#include <vector>

#include "hivecal/port/error.hpp"
#include "report/report.hpp"
#include "textio/json.hpp"

namespace hivecal::record {

/// Writes `data` as the value of the current key (an object), without MethodRow::seconds.
void write_report_data(textio::JsonWriter& json, const report::ReportData& data);

/// Reads the object written by write_report_data; Fault::input naming the key at fault.
port::Error parse_report_data(const textio::JsonValue& value, const std::string& source, report::ReportData* data);

/// The training samples a result (its text) keeps in its "report" (none when it has no report
/// or it cannot be read); `source` names the file in the reader's messages.
std::vector<report::SampleRow> report_training_samples(const std::string& result_text, const std::string& source);

}  // namespace hivecal::record
