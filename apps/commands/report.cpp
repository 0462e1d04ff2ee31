// hivecal report: the HTML report of a calibration, drawn again from its result.json alone
// (the "report" key that calibrate writes; docs/report.md).
#include <cstdio>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/port/output_files.hpp"
#include "report/report.hpp"
#include "record/report_json.hpp"
#include "textio/robot_description.hpp"
#include "textio/json.hpp"
#include "record/result_json.hpp"

namespace hivecal::cli {

namespace {

/// The report data kept in a result file (which must be a valid robot-calibration/1 document).
Error load_report_data(const std::string& path, report::ReportData* data) {
  std::string text;
  port::Error r = port::read_whole_file(path, port::kMaxTextInputBytes, &text);
  if (!r.ok()) return r;
  record::CalibrationFile calibration;
  r = record::parse_calibration_json(text, path, &calibration);
  if (!r.ok()) return r;
  textio::JsonValue root;
  r = textio::parse_json(text, &root);  // parse_calibration_json accepted it: cannot fail
  if (!r.ok()) return r;
  const textio::JsonValue* value = root.find("report");
  if (value == nullptr) {
    return Error::input(path +
                        ": no \"report\" key (written by hivecal calibrate since session 6; run calibrate again)");
  }
  return record::parse_report_data(*value, path, data);
}

Error make_report(const Options& options) {
  if (options.get("calibration").empty() || options.get("out").empty()) {
    return Error::usage("--calibration and --out are required (see --help)");
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  Error error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok()) error = outputs.add_folder(options.get("out"), "--out", {report::kReportPageName}, &out_id);
  if (!error.ok()) return error;
  report::ReportData data;
  error = load_report_data(options.get("calibration"), &data);
  if (!error.ok()) return error;
  error = outputs.stage_text(out_id, report::kReportPageName, report::render_html(data));
  if (error.ok()) error = outputs.commit();
  if (error.ok()) std::printf("report: %s/%s\n", options.get("out").c_str(), report::kReportPageName);
  return error;
}

}  // namespace

int report_main(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"calibration", "FILE", "calibration result written by hivecal calibrate (robot-calibration/1 JSON)", ""},
      {"out", "DIR", "folder for index.html", ""},
  };
  Options options;
  const int parsed = parse_options(kReportCommand,
                                   "Draws the HTML report of a calibration again from its result file: the same\n"
                                   "tables and figures as calibrate --report, without stage times (result files\n"
                                   "hold no wall-clock values), the same bytes for the same result.",
                                   specs, argc, argv, &options);
  if (parsed >= 0) return parsed;
  return exit_with(kReportCommand, make_report(options));
}

}  // namespace hivecal::cli
