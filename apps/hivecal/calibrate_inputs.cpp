#include "calibrate_inputs.hpp"

#include <cstdio>

#include "csv.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "stream_pipeline.hpp"
#include "text_util.hpp"

namespace hivecal::cli {
namespace {

constexpr const char* kCommand = "calibrate";

std::string format(const char* fmt, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

/// The stream path: two captures -> clock fit -> quasi-static samples.
/// "[decode] pass 1/2 (clock): 45 %" on stderr, in place, when a percent changes.
class DecodeProgress {
 public:
  explicit DecodeProgress(bool enabled) : enabled_(enabled) {}
  ~DecodeProgress() {
    if (printed_) std::fprintf(stderr, "\n");
  }
  void operator()(int pass, std::uint64_t done_bytes, std::uint64_t total_bytes) {
    if (!enabled_ || total_bytes == 0) return;
    const int percent = static_cast<int>(100.0 * static_cast<double>(done_bytes) / static_cast<double>(total_bytes));
    if (pass == last_pass_ && percent == last_percent_) return;
    last_pass_ = pass;
    last_percent_ = percent;
    std::fprintf(stderr, "\r[decode] pass %d/2 (%s): %3d %%", pass, pass == 1 ? "clock" : "samples", percent);
    std::fflush(stderr);
    printed_ = true;
  }

 private:
  bool enabled_;
  bool printed_ = false;
  int last_pass_ = 0;
  int last_percent_ = -1;
};

int load_streams(const Options& options, const CalibrateSettings& settings, bool progress_on, DatasetBase* dataset,
                 InputFacts* facts) {
  const std::string robot = options.get("robot");
  const std::string tracker = options.get("tracker");
  RobotModel speed_model = nominal_model(settings.robot);
  speed_model.tool_m = settings.tool_m;  // for tool speeds only
  streams::CaptureRunReport report;
  std::string problem;
  DecodeProgress progress(progress_on);
  const bool read = streams::extract_from_files(
      robot, tracker, make_clock_sync_config(speed_model), make_extraction_config(speed_model), dataset, &report,
      &problem, nullptr, [&progress](int pass, std::uint64_t done, std::uint64_t total) { progress(pass, done, total); });
  if (!read) {
    error(kCommand, problem);
    return kExitBadInput;
  }
  const DecoderStats& r = report.decoding.robot_decoder;
  const DecoderStats& t = report.decoding.tracker_decoder;
  auto frames = [](const DecoderStats& s, bool is_log) {
    return is_log ? std::string(" (CSV log rows)")
                  : ", " + std::to_string(s.frames_rejected()) + " frames rejected, " + std::to_string(s.packets_lost) +
                        " packets lost";
  };
  facts->info_lines.push_back("robot stream: " + std::to_string(r.joint_states) + " joint states" +
                              frames(r, report.robot_is_log));
  facts->info_lines.push_back("tracker stream: " + std::to_string(t.tracker_points) + " points" +
                              frames(t, report.tracker_is_log));
  if (r.joint_states == 0 || t.tracker_points == 0) {
    const bool robot_empty = r.joint_states == 0;
    const bool is_log = robot_empty ? report.robot_is_log : report.tracker_is_log;
    error(kCommand, std::string(is_log ? "no data row in the " : "no valid frame in the ") +
                        (robot_empty ? "robot" : "tracker") + (is_log ? " log" : " capture"));
    return kExitBadInput;
  }
  if (report.clock_status != Status::ok) {
    error(kCommand, std::string("clock relation not found: ") + status_message(report.clock_status));
    return kExitBadInput;
  }
  facts->has_stream = true;
  facts->clock_offset_us = report.clock.offset_at_reference_us;
  facts->clock_offset_sigma_us = report.clock.sigma_offset_at_reference_us;
  facts->clock_drift = report.clock.drift;
  facts->clock_drift_sigma = report.clock.sigma_drift;
  facts->info_lines.push_back(format("clock: t_robot - t_tracker = %.6f s (sigma %.3f ms)", facts->clock_offset_us * 1e-6,
                                     facts->clock_offset_sigma_us * 1e-3) +
                              format(", drift %.2f ppm (sigma %.2f ppm)", facts->clock_drift * 1e6,
                                     facts->clock_drift_sigma * 1e6));
  facts->tracker_points = report.counts.tracker_points;
  facts->kept = report.counts.kept;
  std::string dropped;
  for (int k = 0; k < kDropReasonCount; ++k) {
    const std::uint64_t n = report.counts.dropped[k];
    if (n == 0) continue;
    const char* name = drop_reason_name(static_cast<DropReason>(k));
    facts->dropped.emplace_back(name, n);
    dropped += (dropped.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(n);
  }
  facts->info_lines.push_back("static samples: kept " + std::to_string(facts->kept) + " of " +
                              std::to_string(facts->tracker_points) + " tracker points; dropped: " +
                              (dropped.empty() ? "none" : dropped));
  if (report.extraction_status == Status::dataset_full) {
    error(kCommand, "dataset over capacity (" + std::to_string(dataset->capacity()) + " samples max)");
    return kExitBadInput;
  }
  return kExitOk;
}

}  // namespace

std::string settings_from_options(const Options& options, CalibrateSettings* settings) {
  if (robot_type_from_name(options.get("robot-model").c_str(), &settings->robot) != Status::ok) {
    return "unknown robot model '" + options.get("robot-model") + "' (ur3, ur5, ur10, ur5e)";
  }
  {
    const std::string text = options.get("tool");
    double xyz[3] = {};
    std::size_t start = 0;
    int count = 0;
    for (; count < 3; ++count) {
      const std::size_t comma = text.find(',', start);
      if (!textio::parse_double(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start),
                                &xyz[count])) break;
      if (comma == std::string::npos) {
        ++count;
        break;
      }
      start = comma + 1;
    }
    if (count != 3 || text.find(',', start) != std::string::npos) return "--tool must be X,Y,Z in metres";
    settings->tool_m << xyz[0], xyz[1], xyz[2];
  }
  const std::string params = options.get("params");
  if (params != "full" && params != "paper") return "--params must be 'full' or 'paper', not '" + params + "'";
  settings->paper_params = params == "paper";
  settings->method = options.get("method");
  const char* methods[] = {"abc+lm", "gsa+lm", "lm", "abc", "gsa", "all"};
  bool known = false;
  for (const char* m : methods) known = known || settings->method == m;
  if (!known) return "--method must be one of abc+lm, gsa+lm, lm, abc, gsa, all; not '" + settings->method + "'";
  double seed = 0.0;
  if (!textio::parse_double(options.get("seed"), &seed) || seed < 0.0 || seed > 9.007199254740992e15 ||
      seed != static_cast<double>(static_cast<std::uint64_t>(seed))) {
    return "--seed must be a non-negative integer";
  }
  settings->seed = static_cast<std::uint64_t>(seed);
  if (!textio::parse_double(options.get("split"), &settings->train_fraction) ||
      !(settings->train_fraction > 0.0 && settings->train_fraction < 1.0)) {
    return "--split must be a fraction in (0, 1)";
  }
  const bool samples = !options.get("samples").empty();
  const bool streams = !options.get("robot").empty() || !options.get("tracker").empty();
  if (samples == streams) return "give either --samples, or --robot and --tracker (see --help)";
  if (streams && (options.get("robot").empty() || options.get("tracker").empty())) {
    return "--robot and --tracker go together";
  }
  return "";
}

int load_dataset(const Options& options, const CalibrateSettings& settings, bool progress, DatasetBase* dataset,
                 InputFacts* facts) {
  if (!options.get("samples").empty()) {
    const textio::ParseResult r = textio::read_samples_csv(options.get("samples"), dataset);
    if (!r.ok) {
      error(kCommand, r.message);
      return kExitBadInput;
    }
    facts->info_lines.push_back("input: " + options.get("samples") + " (" + std::to_string(dataset->size()) +
                                " paired samples)");
    return kExitOk;
  }
  facts->info_lines.push_back("input: robot " + options.get("robot") + ", tracker " + options.get("tracker"));
  return load_streams(options, settings, progress, dataset, facts);
}

void write_input_facts(textio::JsonWriter& json, const InputFacts& facts) {
  if (!facts.has_stream) return;
  json.key("clock").begin_object();
  json.key("offset_at_reference_s").value(facts.clock_offset_us * 1e-6);
  json.key("offset_sigma_s").value(facts.clock_offset_sigma_us * 1e-6);
  json.key("drift").value(facts.clock_drift);
  json.key("drift_sigma").value(facts.clock_drift_sigma);
  json.end_object();
  json.key("extraction").begin_object();
  json.key("tracker_points").value(static_cast<long long>(facts.tracker_points));
  json.key("kept").value(static_cast<long long>(facts.kept));
  json.key("dropped").begin_object();
  for (const auto& [reason, count] : facts.dropped) json.key(reason).value(static_cast<long long>(count));
  json.end_object();
  json.end_object();
}

}  // namespace hivecal::cli
