// A calibration registered on new samples, for calibrate --fit and validate --fit
// (registration_io.hpp).
#include "commands/registration_io.hpp"

#include <cstdio>

#include "hivecal/solve/prediction_uncertainty.hpp"
#include "record/report_json.hpp"

namespace hivecal::cli {
namespace {

std::string mm_text(double value_m, const char* format = "%.3f") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value_m * 1e3);
  return buf;
}

std::string axes_text(const Vec3& v, double scale) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.3g, %.3g, %.3g", v.x() * scale, v.y() * scale, v.z() * scale);
  return buf;
}

/// The names of the registered parameters in `mask` of `model` ("base_rx, ...").
std::string registered_param_names(ParamMask mask, const RobotModel& model) {
  std::string names;
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(mask, k)) names += (names.empty() ? "" : ", ") + std::string(full_param_name(k, model));
  return names;
}

/// The training samples of a result's "report" (empty without one).
std::vector<Sample> training_samples(const std::string& calibration_text) {
  std::vector<Sample> samples;
  for (const report::SampleRow& row : record::report_training_samples(calibration_text, "")) {
    Sample s;
    for (int j = 0; j < row.joint_count; ++j) s.q_rad(j) = row.q_rad[j];
    s.point_m = row.measured_m;
    s.target = row.target;
    samples.push_back(s);
  }
  return samples;
}

}  // namespace

double result_orientation_lever_m(const std::string& result_text) {
  textio::JsonValue root;
  if (!textio::parse_json(result_text, &root).ok()) return -1.0;
  const textio::JsonValue* orientation = root.find("orientation");
  const textio::JsonValue* lever = orientation != nullptr ? orientation->find("lever_m") : nullptr;
  return lever != nullptr && lever->kind == textio::JsonValue::Kind::number ? lever->number : -1.0;
}

Error registration_fit_option(const Options& options, RegistrationFit* fit) {
  const std::string value = options.get("fit");
  if (value == "base") {
    *fit = RegistrationFit::base;
  } else if (value == "frames") {
    *fit = RegistrationFit::frames;
  } else {
    return Error::usage("--fit must be 'base' (the base -> tracker transform) or 'frames' (and the tool points), not " +
                        port::quoted(value));
  }
  return Error{};
}

Error register_calibration(const record::CalibrationFile& calibration, Span<const Sample> samples, RegistrationFit fit,
                           bool keep_outliers, double tracker_sigma_m, RegistrationRun* run) {
  run->samples.assign(samples.begin(), samples.end());
  RegistrationOptions options;
  options.fit = fit;
  options.find_blunders = !keep_outliers;
  options.blunder_test.tracker_sigma_m = tracker_sigma_m;
  auto workspace = std::make_unique<RegistrationWorkspace>();  // ~300 kB
  const Status status = register_frames(calibration.model, Span<Sample>(run->samples.data(), run->samples.size()),
                                        options, workspace.get(), run->result.get());
  const std::string what = std::string("--fit ") + registration_fit_name(fit);
  if (status == Status::too_few_samples) {
    return Error::input(what + ": " + std::to_string(samples.size()) + " samples are too few to fit " +
                        std::to_string(mask_count(registration_mask(fit, calibration.model))) +
                        " parameters (3 coordinates each): measure at least 3 poses (4 with --fit frames) at "
                        "non-collinear tool points");
  }
  if (status == Status::degenerate_geometry || status == Status::poses_not_distinct) {
    return Error::input(what + ": the points are collinear or coincide (" + status_message(status) +
                        "): the base needs at least 3 poses at non-collinear tool points");
  }
  if (status != Status::ok) return Error::failure(what + ": the registration failed: " + status_message(status));
  return Error{};
}

void apply_registration(const RegistrationRun& run, const std::string& calibration_text, record::CalibrationFile* file,
                        std::string* note) {
  const RegistrationResult& r = *run.result;
  file->model = r.model;
  file->base_to_tracker = r.base_to_tracker;
  file->fitted = registration_fit_name(r.fit);
  record::CalibrationUncertainty& u = file->uncertainty;
  if (!u.has_covariance()) {
    *note = "the calibration holds no covariance: the registered result has none either (predict writes no sigma_m)";
    return;
  }
  const auto scratch = std::make_unique<CorrelationScratch>();
  const auto covariance = std::make_unique<NormalMatrix>(u.covariance_matrix());
  ParamMask estimated = 0;
  const Status carried =
      carry_covariance(r, run.fitted(), u.estimated, *covariance, scratch.get(), covariance.get(), &estimated);
  if (carried != Status::ok) {
    *note = std::string("the covariance could not be carried through the registration (") + status_message(carried) +
            "): the registered result has none";
    u.covariance.clear();
    return;
  }
  u.set_covariance(*covariance);
  // The other targets' tool points: the registration's estimates with frames, else the calibration's.
  const ParamMask others = r.fit == RegistrationFit::frames ? r.estimated : u.estimated;
  u.estimated = estimated | (others & kOtherTargetTools);
  if (r.fit == RegistrationFit::frames) {
    for (int k = 0; k < kMaxTargets - 1; ++k) u.other_tools_sigma_m[k] = r.other_tools_sigma_m[k];
  }
  const std::vector<Sample> train = training_samples(calibration_text);
  CalibrationDomain domain;
  if (train.empty() ||
      calibration_domain(file->model, file->base_to_tracker, Span<const Sample>(train.data(), train.size()),
                         *covariance, u.estimated & ~kOtherTargetTools, u.other_tools_sigma_m, &domain) != Status::ok) {
    *note =
        "the calibration's training poses are not in it (no \"report\"): the domain's typical sigma is the "
        "calibration's, before the registration";
    return;
  }
  u.domain = domain;
  u.has_domain = true;
}

std::vector<std::string> registration_lines(const RegistrationRun& run, const streams::SessionFacts& facts,
                                            std::vector<std::string>* warnings) {
  const RegistrationResult& r = *run.result;
  std::vector<std::string> lines;
  char buf[600];
  std::snprintf(buf, sizeof buf,
                "registration: %s fitted on %zu poses (%zu samples), RMS %s mm, residual sigma %s mm per axis (%d "
                "degrees of freedom)",
                r.fit == RegistrationFit::frames ? "base and tool points" : "base", r.fitted_poses, r.fitted_samples,
                mm_text(r.rms_m).c_str(), mm_text(r.residual_sigma_m).c_str(), r.residual_dof);
  lines.push_back(buf);
  std::snprintf(buf, sizeof buf,
                "registration: the base's 1-sigma: rotation %s mrad about x, y, z; translation %s mm at the base "
                "origin; at its points %s mm per axis; condition %.3g; points spread %s mm (RMS from their centroid), "
                "the second principal spread %.0f %% of the first",
                axes_text(r.rotation_sigma_rad, 1e3).c_str(), axes_text(r.translation_sigma_m, 1e3).c_str(),
                mm_text(r.point_sigma_m, "%.4f").c_str(), r.condition, mm_text(r.spread_m, "%.0f").c_str(),
                100.0 * r.collinearity);
  lines.push_back(buf);
  if (r.fit == RegistrationFit::frames) {
    std::snprintf(buf, sizeof buf, "registration: tool point %s mm, 1-sigma %s mm",
                  axes_text(r.model.tool_m, 1e3).c_str(), axes_text(r.tool_sigma_m, 1e3).c_str());
    lines.push_back(buf);
  }
  for (std::size_t k = 0; k < r.blunder_count; ++k) {
    const RegistrationBlunder& b = r.blunders[k];
    std::snprintf(buf, sizeof buf, "registration: set aside as a blunder: %s, residual %s mm, w %.2f > %.2f",
                  streams::sample_source(facts, b.index).c_str(), mm_text(b.residual_m).c_str(), b.w, b.critical_w);
    lines.push_back(buf);
  }
  if (r.verdict == RegistrationBlunderVerdict::model_error) {
    std::snprintf(buf, sizeof buf,
                  "registration: %zu of %zu poses fail the w-test, more than the share a blunder search removes: the "
                  "calibration does not hold on these poses (another arm, another tool, the model's error), none set "
                  "aside",
                  r.failing_poses, r.fitted_poses);
    warnings->push_back(buf);
  }
  if (r.weakness & kRegistrationFewResiduals) {
    lines.push_back("registration: " + std::to_string(r.residual_dof) +
                    " residual degrees of freedom: its sigmas rest on few residuals (measure more poses)");
  }
  if (r.weakness & kRegistrationNearlyCollinear) {
    std::snprintf(buf, sizeof buf,
                  "registration weak: the points are nearly collinear (second principal spread %.1f %% of the first, "
                  "below %.0f %%): the rotation about their line is poorly determined; measure poses off that line",
                  100.0 * r.collinearity, 100.0 * kRegistrationCollinearRatio);
    warnings->push_back(buf);
  }
  if (r.weakness & kRegistrationSmallSpread) {
    std::snprintf(buf, sizeof buf,
                  "registration weak: the points spread only %s mm (RMS from their centroid, below %s mm): the "
                  "rotation's lever is short; spread the poses over the workspace",
                  mm_text(r.spread_m, "%.0f").c_str(), mm_text(kRegistrationMinSpread_m, "%.0f").c_str());
    warnings->push_back(buf);
  }
  if (r.weakness & kRegistrationIllConditioned) {
    std::snprintf(buf, sizeof buf,
                  "registration weak: condition number %.3g (above %.3g): the registered parameters are barely "
                  "separable on these poses",
                  r.condition, kRegistrationMaxCondition);
    warnings->push_back(buf);
  }
  if (r.weakness & kRegistrationUndetermined) {
    warnings->push_back("registration weak: the points do not determine " + registered_param_names(r.dropped, r.model) +
                        ": kept at the start (the rigid fit's, or the calibration's) value");
  }
  return lines;
}

void write_registration(textio::JsonWriter& w, const RegistrationRun& run, const streams::SessionFacts& facts,
                        const std::vector<std::string>& warnings) {
  const RegistrationResult& r = *run.result;
  w.key("registration").begin_object();
  w.key("fitted").value(registration_fit_name(r.fit));
  w.key("poses").value(static_cast<long long>(r.fitted_poses));
  w.key("samples").value(static_cast<long long>(r.fitted_samples));
  w.key("rms_m").value(r.rms_m);
  w.key("residual_sigma_m").value(r.residual_sigma_m);
  w.key("residual_dof").value(static_cast<long long>(r.residual_dof));
  w.key("rotation_sigma_rad").inline_array(r.rotation_sigma_rad.data(), 3);
  w.key("translation_sigma_m").inline_array(r.translation_sigma_m.data(), 3);
  if (r.fit == RegistrationFit::frames) w.key("tool_sigma_m").inline_array(r.tool_sigma_m.data(), 3);
  w.key("point_sigma_m").value(r.point_sigma_m);
  w.key("condition").value(r.condition);
  w.key("spread_m").value(r.spread_m);
  w.key("collinearity").value(r.collinearity);
  w.key("weak").begin_array();
  const std::pair<unsigned, const char*> weaknesses[] = {{kRegistrationNearlyCollinear, "nearly_collinear"},
                                                         {kRegistrationSmallSpread, "small_spread"},
                                                         {kRegistrationFewResiduals, "few_residuals"},
                                                         {kRegistrationIllConditioned, "ill_conditioned"},
                                                         {kRegistrationUndetermined, "undetermined"}};
  for (const auto& [bit, name] : weaknesses)
    if (r.weakness & bit) w.value(name);
  w.end_array();
  w.key("blunder_verdict").value(registration_blunder_verdict_name(r.verdict));
  w.key("set_aside").begin_array();
  for (std::size_t k = 0; k < r.blunder_count; ++k) {
    const RegistrationBlunder& b = r.blunders[k];
    w.begin_object();
    record::write_w_test_members(w, streams::sample_source(facts, b.index), b.residual_m, b.w, b.critical_w);
    w.end_object();
  }
  w.end_array();
  if (!warnings.empty()) {
    w.key("warnings").begin_array();
    for (const std::string& warning : warnings) w.value(warning);
    w.end_array();
  }
  w.end_object();
}

}  // namespace hivecal::cli
