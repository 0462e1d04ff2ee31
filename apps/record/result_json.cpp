#include "record/result_json.hpp"

#include <cmath>

#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/solve/lm.hpp"
#include "record/report_json.hpp"
#include "textio/delimited.hpp"
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
  // The tracker sees the robot within the distance the text inputs allow a point: farther is no
  // cell (a damaged or hand-made file), and would predict, export and score in silence.
  const Vec3 translation_m = m.block<3, 1>(0, 3);
  const double distance_m = std::hypot(translation_m.x(), translation_m.y(), translation_m.z());  // no overflow
  if (!(distance_m <= textio::kMaxPointDistance_m)) {
    return fail(source, "\"base_to_tracker\" puts the robot's base " + textio::format_double(distance_m) +
                            " m from the tracker, beyond " + textio::format_double(textio::kMaxPointDistance_m) +
                            " m: not a tracker's frame");
  }
  transform->rotation = rotation_from_cross_covariance(rotation.transpose());  // nearest rotation
  transform->translation_m = translation_m;
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
    write_w_test_members(w, streams::sample_source(sources, o.index), o.residual_m, o.w, o.critical_w);
    w.end_object();
  }
  w.end_array();
}

void write_cross_validation(JsonWriter& w, const CalibrationRecord& record) {
  const CrossValidationResult& cv = *record.cv;
  w.key("cross_validation").begin_object();
  w.key("folds").value(static_cast<long long>(cv.fold_count));
  w.key("samples").value(static_cast<long long>(cv.sample_count));
  w.key("mae_3d_m").value(cv.mae_3d_m);
  w.key("baseline_mae_3d_m").value(cv.baseline_mae_3d_m);
  w.key("fold_mae_3d_mean_m").value(cv.fold_mae_3d_mean_m);
  w.key("fold_mae_3d_max_m").value(cv.fold_mae_3d_max_m);
  if (!record.cv_held_out.empty()) w.key("held_out_of").value(record.cv_held_out_of);
  w.key("per_fold").begin_array();
  for (std::size_t k = 0; k < cv.fold_count; ++k) {
    w.begin_object();
    w.key("train_count").value(static_cast<long long>(cv.folds[k].train_count));
    w.key("test_count").value(static_cast<long long>(cv.folds[k].test.count));
    w.key("train_mae_3d_m").value(cv.folds[k].train.mae(ErrorAxis::norm_3d));
    w.key("test_mae_3d_m").value(cv.folds[k].test.mae(ErrorAxis::norm_3d));
    if (k < record.cv_held_out.size()) w.key("held_out").value(record.cv_held_out[k]);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

void write_joint_vector(JsonWriter& w, const char* name, const JointVector& q, int joints) {
  w.key(name).inline_array(q.data(), static_cast<std::size_t>(joints));
}

/// The full-model index of a parameter named as full_param_name(k, model) writes it; -1: none.
int param_index_of(const std::string& name, const RobotModel& model) {
  for (int k = 0; k < kFullParamCount; ++k)
    if (name == full_param_name(k, model)) return k;
  return -1;
}

port::Error parse_covariance(const JsonValue& c, const std::string& source, const RobotModel& model,
                             CalibrationUncertainty* u) {
  const auto bad = [&](const std::string& what) { return fail(source, "\"covariance\": " + what); };
  const JsonValue* names = c.find("parameters");
  const JsonValue* rows = c.find("matrix");
  if (names == nullptr || names->kind != JsonValue::Kind::array || rows == nullptr ||
      rows->kind != JsonValue::Kind::array || rows->array.size() != names->array.size()) {
    return bad("needs \"parameters\" and a square \"matrix\" of as many rows");
  }
  const std::size_t n = names->array.size();
  std::vector<int> index(n);
  for (std::size_t a = 0; a < n; ++a) {
    const JsonValue& name = names->array[a];
    index[a] = name.kind == JsonValue::Kind::string ? param_index_of(name.string, model) : -1;
    if (index[a] < 0) return bad("unknown parameter " + port::quoted(name.string));
    u->estimated |= param_bit(index[a]);
  }
  NormalMatrix m = NormalMatrix::Zero();
  std::vector<double> row(n);
  for (std::size_t a = 0; a < n; ++a) {
    if (!read_json_numbers(&rows->array[a], n, row.data()))
      return bad("row " + std::to_string(a) + " must hold " + std::to_string(n) + " numbers");
    for (std::size_t b = 0; b < n; ++b) m(index[a], index[b]) = row[b];
  }
  if (!m.allFinite()) return bad("not finite");
  u->set_covariance(m);
  if (const JsonValue* other = c.find("other_tools_sigma_m"); other != nullptr) {
    if (other->kind != JsonValue::Kind::array || other->array.size() > kMaxTargets - 1)
      return bad("other_tools_sigma_m");
    for (std::size_t k = 0; k < other->array.size(); ++k)
      if (!read_json_numbers(&other->array[k], 3, u->other_tools_sigma_m[k].data())) return bad("other_tools_sigma_m");
    u->estimated |= kOtherTargetTools;
  }
  const JsonValue* sigma = c.find("residual_sigma_m");
  const JsonValue* dof = c.find("residual_dof");
  if (sigma != nullptr && sigma->kind == JsonValue::Kind::number) u->residual_sigma_m = sigma->number;
  if (dof != nullptr && dof->kind == JsonValue::Kind::number) u->residual_dof = static_cast<int>(dof->number);
  return port::Error{};
}

port::Error parse_domain(const JsonValue& d, const std::string& source, int joints, CalibrationDomain* domain) {
  const auto number = [&](const char* key, double* value) {
    const JsonValue* v = d.find(key);
    if (v == nullptr || v->kind != JsonValue::Kind::number || !std::isfinite(v->number)) return false;
    *value = v->number;
    return true;
  };
  double poses = 0.0;
  double term_joints = 0.0;
  const bool ok =
      number("poses", &poses) &&
      read_json_numbers(d.find("joint_min_rad"), static_cast<std::size_t>(joints), domain->joint_min_rad.data()) &&
      read_json_numbers(d.find("joint_max_rad"), static_cast<std::size_t>(joints), domain->joint_max_rad.data()) &&
      read_json_numbers(d.find("tool_axis_mean"), 3, domain->tool_axis_mean.data()) &&
      number("tool_axis_spread_rad", &domain->tool_axis_spread_rad) &&
      number("tool_axis_rms_rad", &domain->tool_axis_rms_rad) && number("typical_sigma_m", &domain->typical_sigma_m) &&
      number("max_sigma_m", &domain->max_sigma_m) && number("term_joints", &term_joints) &&
      number("sigma_factor", &domain->sigma_factor) && number("joint_margin_rad", &domain->joint_margin_rad) &&
      number("tool_axis_margin_rad", &domain->tool_axis_margin_rad);
  if (!ok || poses < 0.0 || !(term_joints >= 0.0 && term_joints < 64.0)) {
    return fail(source,
                "\"domain\" needs poses, joint_min_rad, joint_max_rad (" + std::to_string(joints) +
                    " numbers each, one per joint), tool_axis_mean (3), "
                    "tool_axis_spread_rad, tool_axis_rms_rad, typical_sigma_m, max_sigma_m, term_joints (0 .. 63), "
                    "sigma_factor, joint_margin_rad and tool_axis_margin_rad");
  }
  domain->term_joints = static_cast<unsigned>(term_joints);
  domain->poses = static_cast<std::size_t>(poses);
  return port::Error{};
}

/// The optional "covariance", "domain" and "fitted" of a result.
port::Error parse_uncertainty(const JsonValue& root, const std::string& source, CalibrationFile* file) {
  if (const JsonValue* c = root.find("covariance"); c != nullptr) {
    const port::Error r = parse_covariance(*c, source, file->model, &file->uncertainty);
    if (!r.ok()) return r;
  }
  if (const JsonValue* d = root.find("domain"); d != nullptr) {
    const port::Error r = parse_domain(*d, source, file->model.joint_count, &file->uncertainty.domain);
    if (!r.ok()) return r;
    file->uncertainty.has_domain = true;
  }
  if (const JsonValue* f = root.find("fitted"); f != nullptr && f->kind == JsonValue::Kind::string)
    file->fitted = f->string;
  return port::Error{};
}

}  // namespace

NormalMatrix CalibrationUncertainty::covariance_matrix() const {
  if (covariance.size() != static_cast<std::size_t>(kFullParamCount * kFullParamCount)) return NormalMatrix::Zero();
  return Eigen::Map<const NormalMatrix>(covariance.data());
}

void CalibrationUncertainty::set_covariance(const NormalMatrix& matrix) {
  covariance.assign(matrix.data(), matrix.data() + matrix.size());
}

void write_uncertainty(JsonWriter& w, const CalibrationUncertainty& u, const RobotModel& model) {
  if (u.has_covariance()) {
    const NormalMatrix c = u.covariance_matrix();
    int index[kFullParamCount];
    const int n = mask_indices(u.estimated, index);
    w.key("covariance").begin_object();
    w.key("parameters").begin_array();
    for (int a = 0; a < n; ++a) w.value(full_param_name(index[a], model));
    w.end_array();
    w.key("matrix").begin_array();
    std::vector<double> row(static_cast<std::size_t>(n));
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) row[static_cast<std::size_t>(b)] = c(index[a], index[b]);
      w.inline_array(row.data(), row.size());
    }
    w.end_array();
    if ((u.estimated & kOtherTargetTools) != 0) {
      w.key("other_tools_sigma_m").begin_array();
      for (const Vec3& sigma : u.other_tools_sigma_m) w.inline_array(sigma.data(), 3);
      w.end_array();
    }
    w.key("residual_sigma_m").value(u.residual_sigma_m);
    w.key("residual_dof").value(static_cast<long long>(u.residual_dof));
    w.end_object();
  }
  if (u.has_domain) {
    const CalibrationDomain& d = u.domain;
    w.key("domain").begin_object();
    w.key("poses").value(static_cast<long long>(d.poses));
    write_joint_vector(w, "joint_min_rad", d.joint_min_rad, model.joint_count);
    write_joint_vector(w, "joint_max_rad", d.joint_max_rad, model.joint_count);
    w.key("tool_axis_mean").inline_array(d.tool_axis_mean.data(), 3);
    w.key("tool_axis_spread_rad").value(d.tool_axis_spread_rad);
    w.key("tool_axis_rms_rad").value(d.tool_axis_rms_rad);
    w.key("typical_sigma_m").value(d.typical_sigma_m);
    w.key("max_sigma_m").value(d.max_sigma_m);
    w.key("term_joints").value(static_cast<long long>(d.term_joints));
    w.key("sigma_factor").value(d.sigma_factor);
    w.key("joint_margin_rad").value(d.joint_margin_rad);
    w.key("tool_axis_margin_rad").value(d.tool_axis_margin_rad);
    w.end_object();
  }
}

void write_w_test_members(JsonWriter& json, const std::string& source, double residual_m, double w, double critical_w) {
  json.key("source").value(source);
  json.key("residual_m").value(residual_m);
  json.key("w").value(w);
  json.key("critical_w").value(critical_w);
}

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
    if (record.ur_shape) write_ur_deltas(w, record.ur_deltas);  // calibration.conf is a UR's
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
    if (record.cv != nullptr) write_cross_validation(w, record);
    if (!record.warnings.empty()) {
      w.key("warnings").begin_array();
      for (const std::string& warning : record.warnings) w.value(warning);
      w.end_array();
    }
    if (record.report != nullptr) {
      w.key("report");  // what `hivecal report` draws the page from
      write_report_data(w, *record.report);
    }
    write_uncertainty(w, record.file.uncertainty, record.file.model);
  });
}

port::Error parse_calibration_json(const std::string& text, const std::string& source_name, CalibrationFile* file) {
  JsonValue root;
  CalibrationFile parsed;
  port::Error r = textio::parse_description_document(text, source_name, true, &parsed, &root);
  if (r.ok()) r = parse_transform(root, source_name, &parsed.base_to_tracker);
  if (r.ok()) r = parse_uncertainty(root, source_name, &parsed);
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
