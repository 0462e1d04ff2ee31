#include "record/result_json.hpp"

#include <cmath>

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/solve/lm.hpp"
#include "record/report_json.hpp"
#include "textio/text_util.hpp"

namespace hivecal::record {
namespace {

using textio::JsonValue;
using textio::JsonWriter;

void write_axis_values(JsonWriter& json, const char* name, const double* values) {
  json.key(name).begin_object();
  for (int axis = 0; axis < kErrorAxisCount; ++axis) json.key(kErrorAxisKeys[axis]).value(values[axis]);
  json.end_object();
}

port::Error fail(const std::string& source, const std::string& what) {
  return port::Error::input(source + ": " + what);
}

port::Error parse_transform(const JsonValue& root, const std::string& source, RigidTransform* transform) {
  const JsonValue* rows = root.find("base_to_tracker");
  if (rows == nullptr || rows->kind != JsonValue::Kind::array || rows->array.size() != 4) {
    return fail(source, "\"base_to_tracker\" must be a 4x4 array of rows");
  }
  Eigen::Matrix4d m;
  for (std::size_t r = 0; r < 4; ++r) {
    double row[4];
    if (!read_json_numbers(&rows->array[r], 4, row))
      return fail(source, "\"base_to_tracker\" row " + std::to_string(r) + " must hold 4 numbers");
    for (std::size_t c = 0; c < 4; ++c) m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c];
  }
  const Mat3 rotation = m.block<3, 3>(0, 0);
  const bool last_row_ok = m(3, 0) == 0.0 && m(3, 1) == 0.0 && m(3, 2) == 0.0 && m(3, 3) == 1.0;
  const double orthonormality = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!last_row_ok || orthonormality > 1e-5 || rotation.determinant() <= 0.0) {
    return fail(source, "\"base_to_tracker\" is not a proper rigid transform");
  }
  transform->rotation = rotation_from_cross_covariance(rotation.transpose());  // nearest rotation
  transform->translation_m = m.block<3, 1>(0, 3);
  return port::Error{};
}

void write_stage_list(JsonWriter& json, const std::vector<report::MethodRow>& rows) {
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

void write_lm_details(JsonWriter& json, const LmResult& lm, const RobotModel& model) {
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

void write_ur_deltas(JsonWriter& json, const UrCalibrationDeltas& deltas) {
  json.key("ur_deltas").begin_object();
  json.key("delta_theta").inline_array(deltas.delta_theta_rad, kSixJoints);
  json.key("delta_a").inline_array(deltas.delta_a_m, kSixJoints);
  json.key("delta_d").inline_array(deltas.delta_d_m, kSixJoints);
  json.key("delta_alpha").inline_array(deltas.delta_alpha_rad, kSixJoints);
  json.end_object();
}

void write_input_facts(JsonWriter& json, const streams::SessionFacts& facts) {
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

void write_outliers(JsonWriter& w, const streams::SessionFacts* facts, const CalibrationResult& result) {
  const streams::SessionFacts no_facts;  // sources then read "sample N"
  const streams::SessionFacts& sources = facts != nullptr ? *facts : no_facts;
  w.key("outlier_search").value(result.outlier_rounds > 0);
  w.key("blunder_verdict").value(blunder_verdict_name(result.blunder_verdict));
  w.key("outliers").begin_array();
  for (const CalibrationOutlier& o : result.outlier_list()) {
    w.begin_object();
    w.key("index").value(static_cast<long long>(o.index));
    w.key("source").value(streams::sample_source(sources, o.index));
    w.key("residual_m").value(o.residual_m);
    w.key("w").value(o.w);
    w.key("critical_w").value(o.critical_w);
    w.end_object();
  }
  w.end_array();
}

void write_cross_validation(JsonWriter& w, const CrossValidationResult& cv) {
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

void write_error_stats(JsonWriter& json, const ErrorStats& stats) {
  json.begin_object();
  json.key(kErrorCountKey).value(static_cast<long long>(stats.count));
  for (const ErrorStatsField& field : kErrorStatsFields) write_axis_values(json, field.key, stats.*field.values);
  json.end_object();
}

std::string format_calibration_json(const CalibrationFile& file,
                                    const std::function<void(JsonWriter&)>& extra_members) {
  JsonWriter json;
  json.begin_object();
  textio::write_description_members(json, file, file.compliance_sigma);
  // A modified-DH file's base is the frame before Rx(alpha_0) Tx(a_0).
  const RigidTransform base_to_tracker = file.convention == DhConvention::modified
                                             ? file.base_to_tracker.then_after(file.modified_base.transform().inverse())
                                             : file.base_to_tracker;
  json.key("base_to_tracker").begin_array();
  for (int r = 0; r < 4; ++r) {
    double row[4] = {0.0, 0.0, 0.0, 1.0};
    if (r < 3) {
      for (int c = 0; c < 3; ++c) row[c] = base_to_tracker.rotation(r, c);
      row[3] = base_to_tracker.translation_m(r);
    }
    json.inline_array(row, 4);
  }
  json.end_array();
  if (file.has_metrics) {
    json.key("metrics").begin_object();
    json.key("train");
    write_error_stats(json, file.metrics.train);
    json.key("test");
    write_error_stats(json, file.metrics.test);
    json.key("overall");
    write_error_stats(json, file.metrics.overall);
    json.end_object();
  }
  if (extra_members) extra_members(json);
  json.end_object();
  return json.text();
}

std::string format_result_json(const CalibrationRecord& record) {
  return format_calibration_json(record.file, [&](JsonWriter& w) {
    w.key("method").value(record.method);
    w.key("params").value(record.params);
    w.key("seed").value(static_cast<unsigned long long>(record.seed));
    w.key("split").value(record.split);
    w.key("uncalibrated_metrics").begin_object();
    w.key("train");
    write_error_stats(w, record.uncalibrated.train);
    w.key("test");
    write_error_stats(w, record.uncalibrated.test);
    w.end_object();
    if (record.report != nullptr) write_stage_list(w, record.report->methods);
    if (record.final_lm != nullptr && record.result != nullptr) {
      write_lm_details(w, *record.final_lm, record.file.model);
      w.key("significance_t").value(record.result->significance_t);
      if (!record.result->geometry_tested && record.result->significance_t > 0.0)
        w.key("significance_geometry_tested").value(false);  // a larger set
      w.key("not_significant").begin_array();
      for (int k = 0; k < kFullParamCount; ++k)
        if (mask_has(record.result->lm_pruned_mask, k)) w.value(full_param_name(k, record.file.model));
      w.end_array();
      if (record.joint_sigma_rad > 0.0) {  // only when given: the results of the default stay byte for byte
        w.key("joint_sigma_rad").value(record.joint_sigma_rad);
        w.key("joint_sigma_position_sigma_m").value(record.joint_sigma_position_sigma_m);
      }
      if (record.controller_tcp) {  // only when given, likewise
        w.key("known").value("base (identity) and tool points: the controller's TCP readings (--controller-tcp)");
      }
      const ControllerFramesTest& frames = record.result->frames_test;
      if (frames.tested) {  // only when the fitted base was near the identity, likewise
        if (frames.adopted) {
          w.key("known").value("base (identity) and tool points: the controller's TCP readings (--frames auto)");
        }
        w.key("frames_test").begin_object();
        w.key("adopted").value(frames.adopted);
        w.key("status").value(status_message(frames.status));
        w.key("residual_sigma_m").value(frames.residual_sigma_m);
        w.key("noise_sigma_m").value(frames.noise_sigma_m);
        w.key("critical_sigma_m").value(frames.critical_sigma_m);
        w.end_object();
      }
    }
    write_ur_deltas(w, record.ur_deltas);
    if (record.facts != nullptr) {
      const streams::SessionFacts& facts = *record.facts;
      write_input_facts(w, facts);
      if (facts.orientation.poses > 0) {
        w.key("orientation").begin_object();
        w.key("poses").value(static_cast<long long>(facts.orientation.poses));
        w.key("lever_m").value(facts.orientation.lever_m);
        w.key("position_sigma_m").value(facts.orientation_input.position_sigma_m);
        w.key("angle_sigma_rad").value(facts.orientation_input.angle_sigma_rad);
        if (facts.orientation.joint_sigma_rad > 0.0) {  // the joints' reading noise the lever took in
          w.key("lever_joint_sigma_rad").value(facts.orientation.joint_sigma_rad);
        }
        w.key("targets").value("2 and 3 are the measured point moved by lever_m along the measured x and y axes");
        w.end_object();
      }
    }
    if (record.result != nullptr) write_outliers(w, record.facts, *record.result);
    if (record.cv != nullptr) write_cross_validation(w, *record.cv);
    if (!record.warnings.empty()) {
      w.key("warnings").begin_array();
      for (const std::string& warning : record.warnings) w.value(warning);
      w.end_array();
    }
    if (record.report != nullptr) {
      w.key("report");  // what `hivecal report` draws the page from
      write_report_data(w, *record.report);
    }
  });
}

port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file) {
  JsonValue root;
  CalibrationFile parsed;
  port::Error r = textio::parse_description_document(text, source_name, true, &parsed, &root);
  if (r.ok()) r = parse_transform(root, source_name, &parsed.base_to_tracker);
  if (!r.ok()) return r;
  if (parsed.convention == DhConvention::modified) {
    parsed.base_to_tracker = parsed.base_to_tracker.then_after(parsed.modified_base.transform());
  }
  *file = parsed;
  return port::Error{};
}

port::Error read_calibration_json(const std::string& path, CalibrationFile* file, std::string* text) {
  std::string own;
  std::string& content = text != nullptr ? *text : own;
  const port::Error read = port::read_whole_file(path, port::kMaxTextInputBytes, &content);
  if (!read.ok()) return read;
  if (textio::trim(content).empty()) return port::Error::input(path + ": empty file");
  return parse_calibration_json(content, path, file);
}

}  // namespace hivecal::record
