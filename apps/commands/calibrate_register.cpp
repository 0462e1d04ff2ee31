// hivecal calibrate --fit base|frames --robot-model RESULT.json: a calibration carried to a new
// tracker setup (or a reflector set anew) by registering it on the inputs, without calibrating
// again (lib's register_frames, commands/registration_io.hpp). The result is RESULT with the
// registered members replaced and the rest carried forward byte for byte, so that predict,
// export and report read it as they read RESULT.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands/calibrate_parts.hpp"
#include "commands/commands.hpp"
#include "commands/registration_io.hpp"
#include "commands/uncertainty.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/port/output_files.hpp"
#include "record/result_json.hpp"
#include "report/report.hpp"
#include "textio/json.hpp"

namespace hivecal::cli {
namespace {

/// Options that calibrate and a registration do not share: what they set is RESULT's.
constexpr const char* kNotWithFit[] = {
    "method",       "params", "population-subset", "robust",        "cv",        "controller-tcp", "frames",
    "significance", "tool",   "ur-calibration",    "compliance",    "harmonics", "gravity",        "payload",
    "ur-deltas",    "report", "max-change-mm",     "max-change-deg"};

Error refuse_calibration_options(const Options& options) {
  for (const char* name : kNotWithFit) {
    if (!options.given(name)) continue;
    return Error::usage(std::string("--fit registers the calibration of --robot-model as it is: --") + name +
                        " belongs to a calibration (the registered result keeps RESULT's model, terms and report; "
                        "`hivecal report --calibration OUT` redraws its page)");
  }
  return Error{};
}

/// RESULT's text with the registered members replaced (base_to_tracker, metrics, tool points,
/// covariance, domain) and "fitted", "registration" added; RESULT's metrics kept as
/// "calibration_metrics". Every other member is carried as written.
std::string registered_result_json(const std::string& result_text, const record::CalibrationFile& registered,
                                   const RegistrationRun& run, const streams::SessionFacts& facts,
                                   const std::vector<std::string>& warnings) {
  std::vector<textio::JsonMemberText> members;
  std::vector<textio::JsonMemberText> fresh;
  (void)textio::object_member_texts(result_text, &members);  // parsed already: an object
  const std::string generated = record::format_calibration_json(registered, [&](textio::JsonWriter& w) {
    w.key("fitted").value(registration_fit_name(run.result->fit));
    write_registration(w, run, facts, warnings);
    record::write_uncertainty(w, registered.uncertainty, registered.model);
  });
  (void)textio::object_member_texts(generated, &fresh);
  const auto find = [](std::vector<textio::JsonMemberText>& list, const std::string& key) -> textio::JsonMemberText* {
    for (textio::JsonMemberText& m : list)
      if (m.key == key) return &m;
    return nullptr;
  };
  textio::JsonMemberText* metrics = find(members, "metrics");
  if (metrics != nullptr && find(members, "calibration_metrics") == nullptr) {
    textio::JsonMemberText calibration = *metrics;
    calibration.key = "calibration_metrics";
    calibration.text = "\"calibration_metrics\"" + metrics->text.substr(metrics->text.find(':'));
    members.push_back(calibration);
  }
  for (const char* key :
       {"base_to_tracker", "metrics", "tool", "tools", "fitted", "registration", "covariance", "domain"}) {
    const textio::JsonMemberText* replacement = find(fresh, key);
    textio::JsonMemberText* original = find(members, key);
    if (replacement != nullptr && original != nullptr) {
      *original = *replacement;
    } else if (replacement != nullptr) {
      members.push_back(*replacement);
    } else if (original != nullptr) {  // RESULT's, no longer true of the registered file
      members.erase(members.begin() + (original - members.data()));
    }
  }
  return textio::object_document(members);
}

void print_metrics(std::FILE* out, const AccuracyReport& metrics) {
  std::fprintf(out, "\n            samples   MAE x     MAE y     MAE z     MAE 3D    max 3D [mm]\n");
  const auto row = [&](const char* name, const ErrorStats& s) {
    if (s.count == 0) return;
    std::fprintf(out, "  %-9s %7zu  %8.4f  %8.4f  %8.4f  %8.4f  %8.4f\n", name, s.count, s.mae_m[0] * 1e3,
                 s.mae_m[1] * 1e3, s.mae_m[2] * 1e3, s.mae(ErrorAxis::norm_3d) * 1e3, s.max(ErrorAxis::norm_3d) * 1e3);
  };
  row("fitted", metrics.train);
  row("held out", metrics.test);
}

}  // namespace

Error calibrate_registration(const Options& options, std::vector<std::string>* warnings) {
  RegistrationFit fit = RegistrationFit::base;
  Error error = refuse_calibration_options(options);
  if (error.ok()) error = registration_fit_option(options, &fit);
  if (!error.ok()) return error;
  // RESULT: a calibration result, its text carried forward.
  record::CalibrationFile calibration;
  std::string result_text;
  const std::string path = options.get("robot-model");
  if (!options.given("robot-model")) {
    return Error::usage("--fit registers a calibration: give it as --robot-model RESULT.json");
  }
  port::Error read = record::read_calibration_json(path, &calibration, &result_text);
  if (!read.ok()) {
    return Error::input(read.message +
                        " (--fit registers a calibration: --robot-model must be a result.json of calibrate, with its "
                        "base_to_tracker)");
  }
  CalibrateSettings settings;
  error = calibrate_settings_from_options(options, &settings);
  if (!error.ok()) return error;
  if (!options.given("split")) settings.train_fraction = 1.0;  // every pose registers
  if (!options.given("orientation-lever-m")) settings.orientation.lever_m = result_orientation_lever_m(result_text);
  settings.tool_m = calibration.model.tool_m;
  port::OutputSet outputs;
  std::size_t out_id = 0;
  error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok()) error = outputs.add_file(options.get("out"), "--out", &out_id);
  const auto dataset = std::make_unique<CliDataset>();
  streams::SessionFacts facts;
  PointFates fates;
  if (error.ok()) error = load_dataset(options, settings, dataset.get(), &facts, &fates);
  if (!error.ok()) return error;
  const int targets = target_count(dataset->samples());
  if (targets > calibration.target_count) {
    return Error::input(path + " holds " + std::to_string(calibration.target_count) + " target(s); the samples have " +
                        std::to_string(targets) +
                        " (a measured orientation makes 3: --orientation-lever-m 0 reads positions only)");
  }
  if (settings.train_fraction < 1.0 && dataset->split(settings.train_fraction, settings.seed) != Status::ok) {
    return Error::usage("--split " + options.get("split") + " leaves no pose to register on");
  }
  // run
  RegistrationRun run;
  error = register_calibration(calibration, dataset->train(), fit, settings.keep_outliers,
                               settings.orientation.position_sigma_m, &run);
  if (!error.ok()) return error;
  record::CalibrationFile registered = calibration;
  std::string note;
  apply_registration(run, result_text, &registered, &note);
  registered.has_metrics = true;
  registered.metrics.train = position_error_stats(registered.model, registered.base_to_tracker, run.fitted());
  registered.metrics.test = position_error_stats(registered.model, registered.base_to_tracker, dataset->test());
  registered.metrics.overall = position_error_stats(registered.model, registered.base_to_tracker, dataset->samples());
  // present
  const bool result_on_stdout = options.get("out") == "-";
  std::FILE* terminal = result_on_stdout ? stderr : stdout;
  for (const std::string& line : facts.info_lines) std::fprintf(terminal, "%s\n", line.c_str());
  std::fprintf(terminal, "registering %s (%s%s) on %zu of %zu samples%s\n", port::printable(path, 4096).c_str(),
               port::printable(calibration.robot).c_str(),
               calibration.fitted.empty() ? "" : ", itself a registered result", dataset->train().size(),
               dataset->size(),
               dataset->test().empty() ? " (every pose: --split F holds some out)" : "; the rest held out");
  for (const std::string& line : registration_lines(run, facts, warnings)) std::fprintf(terminal, "%s\n", line.c_str());
  if (!note.empty()) std::fprintf(terminal, "registration: %s\n", note.c_str());
  for (const std::string& line : domain_lines(registered.uncertainty, registered.model.joint_count))
    std::fprintf(terminal, "%s\n", line.c_str());
  print_metrics(terminal, registered.metrics);
  // write
  error = outputs.stage_text(out_id, "", registered_result_json(result_text, registered, run, facts, *warnings));
  if (error.ok()) error = outputs.commit();
  if (!error.ok()) return error;
  if (!result_on_stdout) std::fprintf(terminal, "\nresult: %s\n", options.get("out").c_str());
  for (const std::string& warning : *warnings) cli::error(kCalibrateCommand, "warning: " + warning);
  return Error{};
}

}  // namespace hivecal::cli
