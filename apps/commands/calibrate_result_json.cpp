// hivecal calibrate: a run written as result.json (robot-calibration/1, docs/formats.md).
#include <string>
#include <vector>

#include "hivecal/calibration.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "report/report.hpp"
#include "report/report_json.hpp"
#include "streams/session.hpp"
#include "textio/calibration_json.hpp"
#include "commands/calibrate_parts.hpp"

namespace hivecal::cli {
namespace {

void write_stage_list(textio::JsonWriter& json, const std::vector<report::MethodRow>& rows) {
  json.key("methods").begin_array();
  for (const report::MethodRow& row : rows) {
    json.begin_object();
    json.key("method").value(row.method);
    json.key("params").value(row.parameters);
    json.key("train_mae_m").value(row.train.mae(ErrorAxis::norm_3d));
    if (row.test.count > 0) json.key("test_mae_m").value(row.test.mae(ErrorAxis::norm_3d));  // --split 1: none
    json.key("evaluations").value(row.evaluations);
    json.end_object();
  }
  json.end_array();
}

void write_lm_details(textio::JsonWriter& json, const LmResult& lm, const RobotModel& model) {
  const IdentifiabilityReport& id = lm.identifiability;
  json.key("identifiability").begin_object();
  json.key("estimated").begin_array();
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) json.value(full_param_name(k, model));
  for (int target = 1; target < kMaxTargets; ++target) {  // several targets: their tool points
    if (lm.other_tools_sigma_m[target - 1].isZero()) continue;
    for (int axis = 0; axis < 3; ++axis) json.value(other_tool_param_name(target, axis));
  }
  json.end_array();
  json.key("dropped").begin_array();
  for (int k = 0; k < id.dropped_count; ++k) {
    const DroppedParam& d = id.dropped[k];
    json.begin_object();
    json.key("param").value(full_param_name(d.index, model));
    json.key("reason").value(unidentifiable_reason_name(d.reason));
    json.key("singular_ratio").value(d.singular_ratio);
    json.key("combination").begin_object();
    for (int c = 0; c < kNullComponentCount; ++c)
      if (d.component_index[c] >= 0) json.key(full_param_name(d.component_index[c], model)).value(d.component[c]);
    json.end_object();
    json.end_object();
  }
  json.end_array();
  json.key("singular_values")
      .inline_array(id.singular_values_before, static_cast<std::size_t>(id.singular_count_before));
  json.key("condition_before").value(id.condition_before);
  json.key("condition_after").value(id.condition_after);
  json.end_object();
  json.key("sigma").begin_object();
  for (int k = 0; k < kFullParamCount; ++k)
    if (mask_has(id.kept_mask, k)) json.key(full_param_name(k, model)).value(lm.sigma(k));
  for (int target = 1; target < kMaxTargets; ++target) {
    const Vec3& sigma_m = lm.other_tools_sigma_m[target - 1];
    if (sigma_m.isZero()) continue;
    for (int axis = 0; axis < 3; ++axis) json.key(other_tool_param_name(target, axis)).value(sigma_m(axis));
  }
  json.end_object();
  json.key("lm").begin_object();
  json.key("iterations").value(static_cast<long long>(lm.iterations));
  json.key("termination").value(lm_termination_name(lm.termination));
  json.key("rms_m").value(lm.rms_m);
  json.key("residual_sigma_m").value(lm.residual_sigma_m);
  json.end_object();
}

void write_ur_deltas(textio::JsonWriter& json, const UrCalibrationDeltas& deltas) {
  json.key("ur_deltas").begin_object();
  json.key("delta_theta").inline_array(deltas.delta_theta_rad, kJointCount);
  json.key("delta_a").inline_array(deltas.delta_a_m, kJointCount);
  json.key("delta_d").inline_array(deltas.delta_d_m, kJointCount);
  json.key("delta_alpha").inline_array(deltas.delta_alpha_rad, kJointCount);
  json.end_object();
}

void write_input_facts(textio::JsonWriter& json, const streams::SessionFacts& facts) {
  if (!facts.has_stream) return;
  const ClockFit& clock = facts.run.clock;
  json.key("clock").begin_object();
  json.key("offset_at_reference_s").value(clock.offset_at_reference_us * 1e-6);
  json.key("offset_sigma_s").value(clock.sigma_offset_at_reference_us * 1e-6);
  json.key("drift").value(clock.drift);
  json.key("drift_sigma").value(clock.sigma_drift);
  json.end_object();
  json.key("extraction").begin_object();
  json.key("tracker_points").value(static_cast<long long>(facts.run.counts.tracker_points));
  json.key("kept").value(static_cast<long long>(facts.run.counts.kept));
  json.key("dropped").begin_object();
  for (const auto& [reason, count] : facts.dropped) json.key(reason).value(static_cast<long long>(count));
  json.end_object();
  json.end_object();
}

void write_outliers(textio::JsonWriter& w, const streams::SessionFacts& facts, const Run& run) {
  w.key("outlier_search").value(run.result.outlier_rounds > 0);
  w.key("blunder_verdict").value(blunder_verdict_name(run.result.blunder_verdict));
  w.key("outliers").begin_array();
  for (const CalibrationOutlier& o : run.result.outlier_list()) {
    w.begin_object();
    w.key("index").value(static_cast<long long>(o.index));
    w.key("source").value(sample_source(facts, o.index));
    w.key("residual_m").value(o.residual_m);
    w.key("w").value(o.w);
    w.key("critical_w").value(o.critical_w);
    w.end_object();
  }
  w.end_array();
}

void write_cross_validation(textio::JsonWriter& w, const CrossValidationResult& cv) {
  w.key("cross_validation").begin_object();
  w.key("folds").value(static_cast<long long>(cv.fold_count));
  w.key("samples").value(static_cast<long long>(cv.sample_count));
  w.key("mae_3d_m").value(cv.mae_3d_m);
  w.key("baseline_mae_3d_m").value(cv.baseline_mae_3d_m);
  w.key("fold_mae_3d_mean_m").value(cv.fold_mae_3d_mean_m);
  w.key("fold_mae_3d_max_m").value(cv.fold_mae_3d_max_m);
  w.key("per_fold").begin_array();
  for (std::size_t k = 0; k < cv.fold_count; ++k) {
    w.begin_object();
    w.key("train_count").value(static_cast<long long>(cv.folds[k].train_count));
    w.key("test_count").value(static_cast<long long>(cv.folds[k].test.count));
    w.key("train_mae_3d_m").value(cv.folds[k].train.mae(ErrorAxis::norm_3d));
    w.key("test_mae_3d_m").value(cv.folds[k].test.mae(ErrorAxis::norm_3d));
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

}  // namespace

/// `warnings`: the fit's plausibility warnings, a "warnings" array when there are any.
std::string calibration_result_json(const CalibrateSettings& settings, const report::ReportData& data,
                                    const streams::SessionFacts& facts, const Run& run,
                                    const std::vector<std::string>& warnings) {
  const CalibrationStage& final_stage = run.final_stage();
  textio::CalibrationFile file;
  static_cast<textio::RobotDescription&>(file) = settings.robot;  // name and convention as given
  file.model = final_stage.model;
  file.target_count = run.target_count;
  file.base_to_tracker = final_stage.base_to_tracker;
  file.has_metrics = true;
  file.metrics = data.calibrated;
  for (int t = 0; run.final_lm() != nullptr && t < final_stage.model.compliance.term_count; ++t) {
    const int k = compliance_param_index(t);
    if (mask_has(run.final_lm()->identifiability.kept_mask, k)) file.compliance_sigma[t] = run.final_lm()->sigma(k);
  }
  const UrCalibrationDeltas deltas = ur_deltas_between(settings.robot.model, final_stage.model);
  return textio::format_calibration_json(file, [&](textio::JsonWriter& w) {
    w.key("method").value(run.final_method());
    w.key("params").value(settings.paper_params ? "paper" : "full");
    w.key("seed").value(static_cast<unsigned long long>(settings.seed));
    w.key("split").value(settings.train_fraction);
    w.key("uncalibrated_metrics").begin_object();
    w.key("train");
    textio::write_error_stats(w, data.uncalibrated.train);
    w.key("test");
    textio::write_error_stats(w, data.uncalibrated.test);
    w.end_object();
    write_stage_list(w, data.methods);
    if (run.final_lm() != nullptr) {
      write_lm_details(w, *run.final_lm(), final_stage.model);
      w.key("significance_t").value(run.result.significance_t);
      w.key("not_significant").begin_array();
      for (int k = 0; k < kFullParamCount; ++k)
        if (mask_has(run.result.lm_pruned_mask, k)) w.value(full_param_name(k, final_stage.model));
      w.end_array();
      if (settings.joint_sigma_rad > 0.0) {  // only when given: the results of the default stay byte for byte
        w.key("joint_sigma_rad").value(settings.joint_sigma_rad);
        w.key("joint_sigma_position_sigma_m").value(settings.orientation.position_sigma_m);
      }
      if (settings.controller_tcp) {  // only when given, likewise
        w.key("known").value("base (identity) and tool points: the controller's TCP readings (--controller-tcp)");
      }
    }
    write_ur_deltas(w, deltas);
    write_input_facts(w, facts);
    if (facts.orientation.poses > 0) {
      w.key("orientation").begin_object();
      w.key("poses").value(static_cast<long long>(facts.orientation.poses));
      w.key("lever_m").value(facts.orientation.lever_m);
      w.key("position_sigma_m").value(facts.orientation_input.position_sigma_m);
      w.key("angle_sigma_rad").value(facts.orientation_input.angle_sigma_rad);
      w.key("targets").value("2 and 3 are the measured point moved by lever_m along the measured x and y axes");
      w.end_object();
    }
    write_outliers(w, facts, run);
    if (run.has_cv) write_cross_validation(w, run.cv);
    if (!warnings.empty()) {
      w.key("warnings").begin_array();
      for (const std::string& warning : warnings) w.value(warning);
      w.end_array();
    }
    w.key("report");  // what `hivecal report` draws the page from
    report::write_report_data(w, data);
  });
}

}  // namespace hivecal::cli
