// A calibration registered on new samples (lib's register_frames, hivecal/registration.hpp)
// for the commands: `calibrate --fit` writes it as a result, `validate --fit` scores through
// it. Here: the run, the registered calibration (base, tool points, the covariance carried,
// the domain's sigma again), its console lines and its "registration" member.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/registration.hpp"
#include "record/result_json.hpp"
#include "streams/session.hpp"
#include "textio/json.hpp"

namespace hivecal::cli {

/// A registration and the samples it ran on.
struct RegistrationRun {
  std::unique_ptr<RegistrationResult> result = std::make_unique<RegistrationResult>();  ///< ~45 kB
  std::vector<Sample> samples;  ///< its samples, the fitted ones first (register_frames' order)
  /// The fitted samples.
  Span<const Sample> fitted() const { return Span<const Sample>(samples.data(), result->fitted_samples); }
};

/// The lever a result's measured orientation was read with ("orientation"."lever_m"), so that
/// samples read again give the same virtual targets 2 and 3; < 0 when it has none [m].
double result_orientation_lever_m(const std::string& result_text);

/// --fit base|frames into *fit; a usage error otherwise.
Error registration_fit_option(const Options& options, RegistrationFit* fit);

/// Registers `calibration` on a copy of `samples` (lib's register_frames; the w-test of each
/// pose unless `keep_outliers`, at `tracker_sigma_m`). Errors name what the samples lack.
Error register_calibration(const record::CalibrationFile& calibration, Span<const Sample> samples, RegistrationFit fit,
                           bool keep_outliers, double tracker_sigma_m, RegistrationRun* run);

/// The registered calibration into *file (a copy of the calibration): the registered base and
/// tool points, the covariance carried through the registration (carry_covariance) and the
/// domain's sigmas again over the calibration's training poses (its "report" samples, in
/// `calibration_text`); *note says what could not be carried.
void apply_registration(const RegistrationRun& run, const std::string& calibration_text, record::CalibrationFile* file,
                        std::string* note);

/// What the registration found, for the console: poses fitted, residual, the base's 1-sigma
/// and condition, the points' spread, the poses set aside (by `facts`' sources); *warnings
/// gets a line per weakness (a weak registration, model_error).
std::vector<std::string> registration_lines(const RegistrationRun& run, const streams::SessionFacts& facts,
                                            std::vector<std::string>* warnings);

/// The "registration" member: what was fitted on how many poses, the base's sigmas, the
/// condition, spread, weakness, the poses set aside and `warnings` (registration_lines').
void write_registration(textio::JsonWriter& json, const RegistrationRun& run, const streams::SessionFacts& facts,
                        const std::vector<std::string>& warnings);

}  // namespace hivecal::cli
