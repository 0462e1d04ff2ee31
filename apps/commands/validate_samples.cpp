// hivecal validate --calibration RESULT.json --samples FILE: a calibration scored on a separate
// file of measured samples, read as calibrate reads them, optionally after registering it on
// that file (--fit base|frames, on its first --fit-poses poses): MAE, sigma and max per axis and
// 3D, each pose's error by file line with its predicted sigma and extrapolation flag
// (Predictor: the same predictions as `predict`), and --out's JSON.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/host_storage.hpp"
#include "commands/registration_io.hpp"
#include "commands/sample_reader.hpp"
#include "commands/uncertainty.hpp"
#include "commands/validation.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/port/output_files.hpp"
#include "record/result_json.hpp"
#include "streams/session.hpp"
#include "textio/json.hpp"

namespace hivecal::cli {
namespace {

/// A pose's error beyond this misses: the share of them flagged as extrapolated is what the
/// flag is for (docs/robust.md) [m].
constexpr double kMissBound_m = 1e-3;

/// One scored sample.
struct ScoredSample {
  std::string source;     ///< "file:line"
  int target = 0;         ///< 0-based
  Vec3 error_m;           ///< predicted - measured [m]
  Prediction prediction;  ///< the point, its sigma and extrapolation
};

/// What validate found.
struct Validation {
  std::size_t registered_poses = 0;  ///< poses the registration used (0: none)
  bool same_poses = false;           ///< the registration and the scoring use the same poses
  ErrorStats stats;                  ///< over the scored samples
  std::vector<ScoredSample> samples;
  bool has_uncertainty = false;  ///< sigma and extrapolated meaningful
};

/// The first `poses` poses (runs of samples at equal joints) of `samples`: their sample count.
std::size_t samples_of_first_poses(Span<const Sample> samples, std::size_t poses) {
  std::size_t end = 0;
  for (std::size_t k = 0; k < poses && end < samples.size(); ++k) end = pose_run_end(samples, end);
  return end;
}

std::size_t poses_in(Span<const Sample> samples) {
  std::size_t poses = 0;
  for (std::size_t begin = 0; begin < samples.size(); begin = pose_run_end(samples, begin)) ++poses;
  return poses;
}

/// "extrapolated: N of M ...; of those that miss by more than 1 mm a of b, of the others c of d".
std::string extrapolation_line(const Validation& v) {
  ExtrapolationCount all;
  ExtrapolationCount misses;
  ExtrapolationCount others;
  for (const ScoredSample& s : v.samples) {
    all.add(s.prediction.extrapolation);
    (s.error_m.norm() > kMissBound_m ? misses : others).add(s.prediction.extrapolation);
  }
  char line[200];
  std::snprintf(line, sizeof line, "; of those that miss by more than %.0f mm %zu of %zu, of the others %zu of %zu",
                kMissBound_m * 1e3, misses.flagged, misses.poses, others.flagged, others.poses);
  return "extrapolated: " + all.text() + line;
}

void print_validation(std::FILE* out, const std::string& samples_path, const Validation& v) {
  std::fprintf(out, "\nvalidation on %s: %zu samples scored%s\n", port::printable(samples_path, 4096).c_str(),
               v.stats.count,
               v.registered_poses == 0 ? ""
               : v.same_poses          ? " (the registration's own poses: optimistic; --fit-poses N scores the rest)"
                                       : " (not the registration's poses)");
  std::fprintf(out, "           MAE [mm]   sigma [mm]   max [mm]\n");
  for (int axis = 0; axis < kErrorAxisCount; ++axis) {
    std::fprintf(out, "  %-4s  %10.4f   %10.4f   %8.4f\n", record::kErrorAxisKeys[axis], v.stats.mae_m[axis] * 1e3,
                 v.stats.sigma_m[axis] * 1e3, v.stats.max_m[axis] * 1e3);
  }
  std::fprintf(out, "\nper pose (predicted - measured):\n  %-28s %6s %9s %9s %9s %9s%s\n", "source", "target", "x [mm]",
               "y [mm]", "z [mm]", "3D [mm]", v.has_uncertainty ? "  sigma [mm]  extrapolated" : "");
  for (const ScoredSample& s : v.samples) {
    std::fprintf(out, "  %-28s %6d %9.4f %9.4f %9.4f %9.4f", s.source.c_str(), s.target + 1, s.error_m.x() * 1e3,
                 s.error_m.y() * 1e3, s.error_m.z() * 1e3, s.error_m.norm() * 1e3);
    if (v.has_uncertainty) {
      std::fprintf(out, "  %10.4f  %d", s.prediction.sigma_m * 1e3, s.prediction.extrapolation.extrapolated() ? 1 : 0);
    }
    std::fprintf(out, "\n");
  }
  if (v.has_uncertainty) std::fprintf(out, "%s\n", extrapolation_line(v).c_str());
}

std::string validation_json(const Options& options, const record::CalibrationFile& calibration, const Validation& v,
                            const RegistrationRun* run, const streams::SessionFacts& facts,
                            const std::vector<std::string>& warnings) {
  textio::JsonWriter w;
  w.begin_object();
  w.key("format").value("hivecal-validation/1");
  w.key("calibration").value(options.get("calibration"));
  w.key("samples").value(options.get("samples"));
  if (run != nullptr) {
    write_registration(w, *run, facts, warnings);
    w.key("same_poses").value(v.same_poses);
  }
  w.key("metrics");
  record::write_error_stats(w, v.stats);
  w.key("poses").begin_array();
  for (const ScoredSample& s : v.samples) {
    w.begin_object();
    w.key("source").value(s.source);
    w.key("target").value(static_cast<long long>(s.target + 1));
    w.key("error_m").inline_array(s.error_m.data(), 3);
    w.key("error_3d_m").value(s.error_m.norm());
    if (v.has_uncertainty) {
      w.key("sigma_m").value(s.prediction.sigma_m);
      w.key("extrapolated").value(s.prediction.extrapolation.extrapolated());
    }
    w.end_object();
  }
  w.end_array();
  record::write_uncertainty(w, calibration.uncertainty, calibration.model);
  w.end_object();
  return w.text();
}

}  // namespace

Error validate_on_samples(const Options& options, std::vector<std::string>* warnings) {
  // parse
  if (options.given("truth"))
    return Error::usage("give --truth (fresh random poses) or --samples (measured), not both");
  if (options.get("calibration").empty()) return Error::usage("--calibration is required (see --help)");
  SampleReaderSettings reader;
  Error error = sample_reader_settings_from_options(options, &reader);
  RegistrationFit fit = RegistrationFit::base;
  const bool fitting = options.given("fit");
  if (error.ok() && fitting) error = registration_fit_option(options, &fit);
  std::size_t fit_poses = 0;
  if (error.ok() && options.given("fit-poses")) {
    if (!fitting) return Error::usage("--fit-poses N needs --fit base|frames (the registration it sizes)");
    error = count_option(options, "fit-poses", 3, 100000000, &fit_poses);
  }
  port::OutputSet outputs;
  std::size_t out_id = 0;
  const bool json_out = options.given("out");
  if (error.ok()) error = declare_inputs(options, {"out"}, &outputs);
  if (error.ok() && json_out) error = outputs.add_file(options.get("out"), "--out", &out_id);
  if (!error.ok()) return error;
  // load
  record::CalibrationFile calibration;
  std::string calibration_text;
  port::Error read = record::read_calibration_json(options.get("calibration"), &calibration, &calibration_text);
  if (!read.ok()) return read;
  if (!options.given("orientation-lever-m")) reader.orientation.lever_m = result_orientation_lever_m(calibration_text);
  const auto dataset = std::make_unique<HostDataset>();
  streams::SessionFacts facts;
  read = streams::load_session({options.get("samples"), "", ""}, sample_session_config(reader, calibration.model),
                               dataset.get(), &facts);
  if (!read.ok()) return read;
  const Span<const Sample> all = dataset->samples();
  if (target_count(all) > calibration.target_count) {
    return Error::input(options.get("calibration") + " holds " + std::to_string(calibration.target_count) +
                        " target(s); the samples have " + std::to_string(target_count(all)) +
                        " (a measured orientation makes 3: --orientation-lever-m 0 reads positions only)");
  }
  // run: the registration, then the scoring through the (registered) calibration
  Validation v;
  Span<const Sample> scored = all;
  std::unique_ptr<RegistrationRun> run;
  std::FILE* out = options.get("out") == "-" ? stderr : stdout;  // stdout carries the JSON then
  for (const std::string& line : facts.info_lines) std::fprintf(out, "%s\n", line.c_str());
  if (fitting) {
    const std::size_t poses = poses_in(all);
    if (options.given("fit-poses") && fit_poses >= poses) {
      return Error::usage("--fit-poses " + options.get("fit-poses") + " leaves none of the " + std::to_string(poses) +
                          " poses to score");
    }
    const std::size_t fit_end = fit_poses > 0 ? samples_of_first_poses(all, fit_poses) : all.size();
    run = std::make_unique<RegistrationRun>();
    error = register_calibration(calibration, Span<const Sample>(all.data(), fit_end), fit,
                                 options.given("keep-outliers"), reader.orientation.position_sigma_m, run.get());
    if (!error.ok()) return error;
    std::string note;
    apply_registration(*run, calibration_text, &calibration, &note);
    v.registered_poses = fit_poses > 0 ? fit_poses : poses;
    v.same_poses = fit_poses == 0;
    if (fit_poses > 0) scored = Span<const Sample>(all.data() + fit_end, all.size() - fit_end);
    std::fprintf(out, "registered on %s %zu pose(s) of %s, scored on %s\n", fit_poses > 0 ? "the first" : "all",
                 v.registered_poses, options.get("samples").c_str(),
                 v.same_poses ? "the same poses" : ("the other " + std::to_string(poses - fit_poses)).c_str());
    for (const std::string& line : registration_lines(*run, facts, warnings)) std::fprintf(out, "%s\n", line.c_str());
    if (!note.empty()) std::fprintf(out, "registration: %s\n", note.c_str());
  }
  for (const std::string& line : domain_lines(calibration.uncertainty, calibration.model.joint_count))
    std::fprintf(out, "%s\n", line.c_str());
  const Predictor predict_point(calibration);
  v.has_uncertainty = predict_point.has_uncertainty();
  v.stats = position_error_stats(calibration.model, calibration.base_to_tracker, scored);
  for (const Sample& s : scored) {
    ScoredSample row;
    row.source = streams::sample_source(facts, s.index);
    row.target = s.target;
    row.prediction = predict_point(s.q_rad, s.target, PredictionFrame::tracker);
    row.error_m = row.prediction.point_m - s.point_m;
    v.samples.push_back(row);
  }
  print_validation(out, options.get("samples"), v);
  // write
  if (!json_out) return Error{};
  error = outputs.stage_text(out_id, "", validation_json(options, calibration, v, run.get(), facts, *warnings));
  return error.ok() ? outputs.commit() : error;
}

}  // namespace hivecal::cli
