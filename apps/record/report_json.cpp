#include "record/report_json.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "record/result_json.hpp"
#include "textio/delimited.hpp"

namespace hivecal::record {
namespace {

// The report's tables and figures (report/report.hpp).
using namespace report;  // NOLINT(google-build-using-namespace)

using textio::JsonValue;
using textio::JsonWriter;

void write_accuracy(JsonWriter& json, const AccuracyReport& r) {
  json.begin_object();
  json.key("train");
  write_error_stats(json, r.train);
  json.key("test");
  write_error_stats(json, r.test);
  json.key("overall");
  write_error_stats(json, r.overall);
  json.end_object();
}

/// A model and transform: "params" (the 4 DH values per joint and the tool point, kinematics.hpp
/// order: 27 for six joints), "prismatic" (the 1-based prismatic joints, when there are any),
/// "rotation" (3 rows) and "translation_m"; exact bits, no re-orthonormalisation.
void write_model(JsonWriter& json, const PredictionSet& set) {
  const ModelParams params = to_params(set.model);
  json.key("params").inline_array(params.data(), static_cast<std::size_t>(model_param_count(set.model)));
  if (!all_revolute(set.model)) {
    std::vector<double> prismatic;
    for (int j = 0; j < set.model.joint_count; ++j) {
      if (joint_type(set.model, j) == JointType::prismatic) prismatic.push_back(j + 1);
    }
    json.key("prismatic").inline_array(prismatic.data(), prismatic.size());
  }
  json.key("rotation").begin_array();
  for (int r = 0; r < 3; ++r) {
    const Vec3 row = set.base_to_tracker.rotation.row(r).transpose();
    json.inline_array(row.data(), 3);
  }
  json.end_array();
  json.key("translation_m").inline_array(set.base_to_tracker.translation_m.data(), 3);
  if (set.model.compliance.term_count > 0) {  // rigid models: the key is left out (the bytes stay as before)
    json.key("compliance");
    textio::write_compliance(json, set.model, Mat3::Identity());
  }
  bool several_targets = false;  // one reflector: the key is left out (the bytes stay as before)
  for (const Vec3& tool_m : set.model.other_tools_m) several_targets = several_targets || !tool_m.isZero();
  if (!several_targets) return;
  json.key("other_tools_m").begin_array();
  for (const Vec3& tool_m : set.model.other_tools_m) json.inline_array(tool_m.data(), 3);
  json.end_array();
}

void write_identifiability(JsonWriter& json, const IdentifiabilityTable& id) {
  json.begin_object();
  json.key("free_count").value(static_cast<long long>(id.free_count));
  json.key("estimated").begin_array();
  for (const std::string& name : id.estimated) json.value(name);
  json.end_array();
  json.key("dropped").begin_array();
  for (const DroppedRow& d : id.dropped) {
    json.begin_object();
    json.key("param").value(d.param);
    json.key("reason").value(d.reason);
    json.key("singular_ratio").value(d.singular_ratio);
    json.key("combination").value(d.combination);
    json.end_object();
  }
  json.end_array();
  json.key("condition_before").value(id.condition_before);
  json.key("condition_after").value(id.condition_after);
  json.key("fixed").begin_array();
  for (const std::string& name : id.fixed) json.value(name);
  json.end_array();
  json.key("significance_t").value(id.significance_t);
  json.end_object();
}

void write_outliers(JsonWriter& json, const OutlierTable& o) {
  json.key("outliers").begin_object();
  json.key("searched").value(o.searched);
  json.key("verdict").value(o.verdict);
  json.key("critical_w").value(o.critical_w);
  json.key("alpha").value(o.alpha);
  json.key("sigma_source").value(o.sigma_source);
  json.key("sigma_m").value(o.sigma_m);
  if (o.pooled_correlation) json.key("pooled_correlation").value(true);  // only then: other results keep their bytes
  json.key("set_aside").begin_array();
  for (const OutlierRow& r : o.rows) {
    json.begin_object();
    json.key("source").value(r.source);
    json.key("residual_m").value(r.residual_m);
    json.key("w").value(r.w);
    json.end_object();
  }
  json.end_array();
  json.key("uncontrolled").begin_array();
  for (const std::string& source : o.uncontrolled) json.value(source);
  json.end_array();
  json.key("kept_w").begin_array();
  for (double w : o.kept_w) json.value(w);
  json.end_array();
  if (o.kept_total > 0) json.key("kept_total").value(static_cast<long long>(o.kept_total));  // only then: bytes kept
  json.end_object();
}

void write_cross_validation(JsonWriter& json, const CrossValidationTable& cv) {
  json.key("cross_validation").begin_object();
  json.key("samples").value(static_cast<long long>(cv.sample_count));
  json.key("mae_3d_m").value(cv.mae_3d_m);
  json.key("baseline_mae_3d_m").value(cv.baseline_mae_3d_m);
  if (!cv.held_out_of.empty()) json.key("held_out_of").value(cv.held_out_of);
  json.key("folds").begin_array();
  for (const FoldRow& f : cv.folds) {
    json.begin_object();
    json.key("train_count").value(static_cast<long long>(f.train_count));
    json.key("test_count").value(static_cast<long long>(f.test_count));
    json.key("train_mae_3d_m").value(f.train_mae_m);
    json.key("test_mae_3d_m").value(f.test_mae_m);
    if (!cv.held_out_of.empty()) json.key("held_out").value(f.held_out);
    json.end_object();
  }
  json.end_array();
  json.end_object();
}

// --- reading: each helper returns false on a wrong kind; the caller names the key ---------------

/// A number; null (how the writer stores NaN / Inf) reads as +Inf.
bool get_number(const JsonValue* v, double* out) {
  if (v != nullptr && v->kind == JsonValue::Kind::null) {
    *out = std::numeric_limits<double>::infinity();
    return true;
  }
  if (v == nullptr || v->kind != JsonValue::Kind::number) return false;
  *out = v->number;
  return true;
}

bool get_string(const JsonValue* v, std::string* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::string) return false;
  *out = v->string;
  return true;
}

bool get_bool(const JsonValue* v, bool* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::boolean) return false;
  *out = v->boolean;
  return true;
}

bool get_count(const JsonValue* v, long long* out) {
  double d = 0.0;
  if (!get_number(v, &d) || !(d >= 0.0 && d < 9.007199254740992e15) || d != std::floor(d)) return false;
  *out = static_cast<long long>(d);
  return true;
}

bool is_array(const JsonValue* v) {
  return v != nullptr && v->kind == JsonValue::Kind::array;
}

bool get_numbers(const JsonValue* v, std::size_t n, double* out) {
  if (!is_array(v) || v->array.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (!get_number(&v->array[i], &out[i])) return false;
  return true;
}

bool get_axes(const JsonValue* v, double* out) {
  if (v == nullptr || v->kind != JsonValue::Kind::object) return false;
  for (int axis = 0; axis < kErrorAxisCount; ++axis)
    if (!get_number(v->find(kErrorAxisKeys[axis]), &out[axis])) return false;
  return true;
}

bool get_stats(const JsonValue* v, ErrorStats* out) {
  long long count = 0;
  if (v == nullptr || !get_count(v->find(kErrorCountKey), &count)) return false;
  out->count = static_cast<std::size_t>(count);
  for (const ErrorStatsField& field : kErrorStatsFields)
    if (!get_axes(v->find(field.key), out->*field.values)) return false;
  return true;
}

bool get_accuracy(const JsonValue* v, AccuracyReport* out) {
  return v != nullptr && get_stats(v->find("train"), &out->train) && get_stats(v->find("test"), &out->test) &&
         get_stats(v->find("overall"), &out->overall);
}

/// The joints of a "params" array of 4 values per joint and the tool point's 3; 0 when its
/// length is not that of a model the build holds.
int joint_count_of(const JsonValue* params) {
  if (!is_array(params) || params->array.size() < 3 || (params->array.size() - 3) % kParamsPerJoint != 0) return 0;
  const auto joints = static_cast<int>((params->array.size() - 3) / kParamsPerJoint);
  return joints >= 1 && joints <= kMaxJoints ? joints : 0;
}

/// The joint types of "prismatic" (1-based joint numbers; absent: all revolute) into *model.
bool get_joint_types(const JsonValue* prismatic, RobotModel* model) {
  if (prismatic == nullptr) return true;
  if (!is_array(prismatic)) return false;
  for (const JsonValue& joint : prismatic->array) {
    if (joint.kind != JsonValue::Kind::number || !(joint.number >= 1.0) ||
        !(joint.number <= static_cast<double>(model->joint_count)) || joint.number != std::floor(joint.number)) {
      return false;
    }
    set_joint_type(model, static_cast<int>(joint.number) - 1, JointType::prismatic);
  }
  return true;
}

bool get_model(const JsonValue& v, RobotModel* model, RigidTransform* transform) {
  ModelParams params = ModelParams::Zero();
  const JsonValue* rotation = v.find("rotation");
  const int joints = joint_count_of(v.find("params"));
  if (joints == 0 ||
      !get_numbers(v.find("params"), static_cast<std::size_t>(model_param_count(joints)), params.data()) ||
      !is_array(rotation) || rotation->array.size() != 3 ||
      !get_numbers(v.find("translation_m"), 3, transform->translation_m.data())) {
    return false;
  }
  for (std::size_t r = 0; r < 3; ++r) {
    double row[3];
    if (!get_numbers(&rotation->array[r], 3, row)) return false;
    for (std::size_t c = 0; c < 3; ++c)
      transform->rotation(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c];
  }
  *model = RobotModel{};
  model->joint_count = joints;
  set_model_params(params, model);
  if (!get_joint_types(v.find("prismatic"), model)) return false;
  if (const JsonValue* compliance = v.find("compliance"); compliance != nullptr) {  // compliant models only
    std::string what;
    if (!textio::read_compliance(*compliance, Mat3::Identity(), *model, &model->compliance, &what)) return false;
  }
  if (const JsonValue* others = v.find("other_tools_m"); others != nullptr) {  // several reflectors only
    if (!is_array(others) || others->array.size() != static_cast<std::size_t>(kMaxTargets - 1)) return false;
    for (std::size_t k = 0; k < others->array.size(); ++k) {
      if (!get_numbers(&others->array[k], 3, model->other_tools_m[k].data())) return false;
      if (!model->other_tools_m[k].allFinite()) return false;
    }
  }
  return params.allFinite() && transform->rotation.allFinite() &&
         transform->translation_m.norm() <= textio::kMaxPointDistance_m;  // the result's own bound (NaN fails)
}

bool get_methods(const JsonValue* v, std::vector<MethodRow>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& m : v->array) {
    MethodRow row;
    if (!get_string(m.find("method"), &row.method) || !get_string(m.find("params"), &row.parameters) ||
        !get_count(m.find("evaluations"), &row.evaluations) || !get_stats(m.find("train"), &row.train) ||
        !get_stats(m.find("test"), &row.test)) {
      return false;
    }
    out->push_back(row);
  }
  return true;
}

bool get_convergence(const JsonValue* v, std::vector<ConvergenceSeries>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& c : v->array) {
    ConvergenceSeries series;
    const JsonValue* costs = c.find("best_cost_m");
    if (!get_string(c.find("method"), &series.method) || !get_bool(c.find("per_iteration"), &series.per_iteration) ||
        !is_array(costs)) {
      return false;
    }
    series.best_cost_m.resize(costs->array.size());
    if (!get_numbers(costs, costs->array.size(), series.best_cost_m.data())) return false;
    out->push_back(series);
  }
  return true;
}

bool get_samples(const JsonValue* v, std::vector<SampleRow>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& s : v->array) {
    SampleRow row;
    double xyz[3];
    const JsonValue* joints = s.find("q_rad");  // one per joint of the arm
    row.joint_count = is_array(joints) ? static_cast<int>(joints->array.size()) : 0;
    if (row.joint_count < 1 || row.joint_count > kMaxJoints ||
        !get_numbers(joints, static_cast<std::size_t>(row.joint_count), row.q_rad) ||
        !get_numbers(s.find("measured_m"), 3, xyz) || !get_bool(s.find("test"), &row.test)) {
      return false;
    }
    row.measured_m = Vec3(xyz[0], xyz[1], xyz[2]);
    if (!(row.measured_m.norm() <= textio::kMaxPointDistance_m)) return false;  // the text inputs' bounds
    for (const double q : row.q_rad)
      if (!(std::fabs(q) <= textio::kMaxJointLimit_rad)) return false;
    if (const JsonValue* target = s.find("target"); target != nullptr) {  // several reflectors only
      long long k = 0;
      if (!get_count(target, &k) || k >= kMaxTargets) return false;
      row.target = static_cast<int>(k);
    }
    out->push_back(row);
  }
  return true;
}

bool get_predictions(const JsonValue* v, const std::vector<SampleRow>& samples, std::vector<PredictionSet>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& p : v->array) {
    std::string method;
    RobotModel model;
    RigidTransform transform;
    if (!get_string(p.find("method"), &method) || !get_model(p, &model, &transform)) return false;
    out->push_back(predict_samples(method, model, transform, samples));
  }
  return true;
}

bool get_identifiability(const JsonValue* v, IdentifiabilityTable* out) {
  if (v == nullptr) return true;  // no LM stage
  long long free_count = 0;
  const JsonValue* estimated = v->find("estimated");
  const JsonValue* dropped = v->find("dropped");
  if (!get_count(v->find("free_count"), &free_count) || !is_array(estimated) || !is_array(dropped) ||
      !get_number(v->find("condition_before"), &out->condition_before) ||
      !get_number(v->find("condition_after"), &out->condition_after)) {
    return false;
  }
  out->present = true;
  out->free_count = static_cast<int>(free_count);
  for (const JsonValue& name : estimated->array) {
    out->estimated.emplace_back();
    if (!get_string(&name, &out->estimated.back())) return false;
  }
  for (const JsonValue& d : dropped->array) {
    DroppedRow row;
    if (!get_string(d.find("param"), &row.param) || !get_string(d.find("reason"), &row.reason) ||
        !get_number(d.find("singular_ratio"), &row.singular_ratio) ||
        !get_string(d.find("combination"), &row.combination)) {
      return false;
    }
    out->dropped.push_back(row);
  }
  const JsonValue* fixed = v->find("fixed");
  if (fixed == nullptr) return true;  // written before the significance test was reported
  if (!is_array(fixed) || !get_number(v->find("significance_t"), &out->significance_t)) return false;
  for (const JsonValue& name : fixed->array) {
    out->fixed.emplace_back();
    if (!get_string(&name, &out->fixed.back())) return false;
  }
  return true;
}

bool get_outliers(const JsonValue* v, OutlierTable* out) {
  if (v == nullptr) return true;  // written before blunders were reported: no search shown
  const JsonValue* rows = v->find("set_aside");
  const JsonValue* uncontrolled = v->find("uncontrolled");
  const JsonValue* kept_w = v->find("kept_w");
  if (!get_bool(v->find("searched"), &out->searched) || !get_string(v->find("verdict"), &out->verdict) ||
      !get_number(v->find("critical_w"), &out->critical_w) || !get_number(v->find("alpha"), &out->alpha) ||
      !get_string(v->find("sigma_source"), &out->sigma_source) || !get_number(v->find("sigma_m"), &out->sigma_m) ||
      !is_array(rows) || !is_array(uncontrolled) || !is_array(kept_w)) {
    return false;
  }
  const JsonValue* pooled = v->find("pooled_correlation");
  if (pooled != nullptr && !get_bool(pooled, &out->pooled_correlation)) return false;
  for (const JsonValue& r : rows->array) {
    OutlierRow row;
    if (!get_string(r.find("source"), &row.source) || !get_number(r.find("residual_m"), &row.residual_m) ||
        !get_number(r.find("w"), &row.w)) {
      return false;
    }
    out->rows.push_back(row);
  }
  for (const JsonValue& u : uncontrolled->array) {
    std::string source;
    if (!get_string(&u, &source)) return false;
    out->uncontrolled.push_back(source);
  }
  for (const JsonValue& w : kept_w->array) {
    double value = 0.0;
    if (!get_number(&w, &value)) return false;
    out->kept_w.push_back(value);
  }
  if (const JsonValue* total = v->find("kept_total"); total != nullptr) {  // a thinned report only
    long long count = 0;
    if (!get_count(total, &count) || static_cast<std::size_t>(count) <= out->kept_w.size()) return false;
    out->kept_total = static_cast<std::size_t>(count);
  }
  return true;
}

bool get_cross_validation(const JsonValue* v, CrossValidationTable* out) {
  if (v == nullptr) return true;  // no --cv
  long long samples = 0;
  const JsonValue* folds = v->find("folds");
  if (!get_count(v->find("samples"), &samples) || !get_number(v->find("mae_3d_m"), &out->mae_3d_m) ||
      !get_number(v->find("baseline_mae_3d_m"), &out->baseline_mae_3d_m) || !is_array(folds)) {
    return false;
  }
  out->present = true;
  out->sample_count = static_cast<std::size_t>(samples);
  // The held-out lines: in results written since issue 54, absent in older ones (no column then).
  const JsonValue* held_out_of = v->find("held_out_of");
  if (held_out_of != nullptr && !get_string(held_out_of, &out->held_out_of)) return false;
  for (const JsonValue& f : folds->array) {
    FoldRow row;
    long long train = 0, test = 0;
    if (!get_count(f.find("train_count"), &train) || !get_count(f.find("test_count"), &test) ||
        !get_number(f.find("train_mae_3d_m"), &row.train_mae_m) ||
        !get_number(f.find("test_mae_3d_m"), &row.test_mae_m) ||
        (held_out_of != nullptr && !get_string(f.find("held_out"), &row.held_out))) {
      return false;
    }
    row.train_count = static_cast<std::size_t>(train);
    row.test_count = static_cast<std::size_t>(test);
    out->folds.push_back(row);
  }
  return true;
}

bool get_parameters(const JsonValue* v, std::vector<ParameterRow>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& p : v->array) {
    ParameterRow row;
    if (!get_string(p.find("name"), &row.name) || !get_bool(p.find("angle"), &row.angle) ||
        !get_number(p.find("start"), &row.start) || !get_number(p.find("value"), &row.value) ||
        !get_number(p.find("sigma"), &row.sigma) || !get_string(p.find("correlated_with"), &row.correlated_with) ||
        !get_number(p.find("correlation"), &row.correlation) ||
        (p.find("unit") != nullptr && !get_string(p.find("unit"), &row.compliance_unit))) {
      return false;
    }
    out->push_back(row);
  }
  return true;
}

bool get_drops(const JsonValue* v, std::vector<std::pair<std::string, std::uint64_t>>* out) {
  if (!is_array(v)) return false;
  for (const JsonValue& d : v->array) {
    std::string reason;
    long long count = 0;
    if (!get_string(d.find("reason"), &reason) || !get_count(d.find("count"), &count)) return false;
    out->emplace_back(reason, static_cast<std::uint64_t>(count));
  }
  return true;
}

bool get_timeline(const JsonValue* v, PointTimeline* out) {
  if (v == nullptr) return true;  // not stream input
  const JsonValue* reasons = v->find("reasons");
  const JsonValue* counts = v->find("counts");
  if (!get_number(v->find("duration_s"), &out->duration_s) || !is_array(reasons) || !is_array(counts) ||
      counts->array.size() != reasons->array.size()) {
    return false;
  }
  for (std::size_t r = 0; r < reasons->array.size(); ++r) {
    out->reasons.emplace_back();
    if (!get_string(&reasons->array[r], &out->reasons.back()) || !is_array(&counts->array[r])) return false;
    out->counts.emplace_back();
    for (const JsonValue& c : counts->array[r].array) {
      long long n = 0;
      if (!get_count(&c, &n) || n > 0xffffffffLL) return false;
      out->counts.back().push_back(static_cast<std::uint32_t>(n));
    }
  }
  return true;
}

bool get_clock_match(const JsonValue* v, ClockMatchSeries* out) {
  if (v == nullptr) return true;  // not stream input
  if (!get_number(v->find("speed_gain"), &out->speed_gain)) return false;
  const JsonValue* t = v->find("t_s");
  if (!is_array(t)) return false;
  const std::size_t n = t->array.size();
  std::pair<const char*, std::vector<double>*> columns[] = {{"t_s", &out->t_s},
                                                            {"robot_speed_m_s", &out->robot_speed_m_s},
                                                            {"tracker_speed_m_s", &out->tracker_speed_m_s},
                                                            {"residual_m_s", &out->residual_m_s}};
  for (auto& [key, column] : columns) {
    const JsonValue* c = v->find(key);
    if (!is_array(c) || c->array.size() != n) return false;
    column->resize(n);
    if (!get_numbers(c, n, column->data())) return false;
  }
  return true;
}

}  // namespace

void write_report_data(JsonWriter& json, const ReportData& data) {
  json.begin_object();
  json.key("title").value(data.title);
  json.key("info").begin_array();
  for (const std::string& line : data.info_lines) json.value(line);
  json.end_array();
  json.key("methods").begin_array();
  for (const MethodRow& row : data.methods) {
    json.begin_object();
    json.key("method").value(row.method);
    json.key("params").value(row.parameters);
    json.key("evaluations").value(row.evaluations);
    json.key("train");
    write_error_stats(json, row.train);
    json.key("test");
    write_error_stats(json, row.test);
    json.end_object();
  }
  json.end_array();
  json.key("uncalibrated");
  write_accuracy(json, data.uncalibrated);
  json.key("calibrated");
  write_accuracy(json, data.calibrated);
  json.key("convergence").begin_array();
  for (const ConvergenceSeries& c : data.convergence) {
    json.begin_object();
    json.key("method").value(c.method);
    json.key("per_iteration").value(c.per_iteration);
    json.key("best_cost_m").inline_array(c.best_cost_m.data(), c.best_cost_m.size());
    json.end_object();
  }
  json.end_array();
  json.key("samples").begin_array();
  for (const SampleRow& s : data.samples) {
    json.begin_object();
    json.key("q_rad").inline_array(s.q_rad, static_cast<std::size_t>(s.joint_count));
    json.key("measured_m").inline_array(s.measured_m.data(), 3);
    json.key("test").value(s.test);
    if (s.target != 0) json.key("target").value(static_cast<long long>(s.target));
    json.end_object();
  }
  json.end_array();
  if (data.sample_total > 0) json.key("sample_total").value(static_cast<long long>(data.sample_total));  // thinned only
  json.key("predictions").begin_array();
  for (const PredictionSet& p : data.predictions) {
    json.begin_object();
    json.key("method").value(p.method);
    write_model(json, p);
    json.end_object();
  }
  json.end_array();
  json.key("noise_sigma_m").value(data.noise_sigma_m);
  if (data.noise_source != "stated") json.key("noise_source").value(data.noise_source);  // measured only
  json.key("fit_sigma_m").value(data.fit_sigma_m);
  if (data.identifiability.present) {
    json.key("identifiability");
    write_identifiability(json, data.identifiability);
  }
  json.key("parameters").begin_array();
  for (const ParameterRow& p : data.parameters) {
    json.begin_object();
    json.key("name").value(p.name);
    json.key("angle").value(p.angle);
    json.key("start").value(p.start);
    json.key("value").value(p.value);
    json.key("sigma").value(p.sigma);
    json.key("correlated_with").value(p.correlated_with);
    json.key("correlation").value(p.correlation);
    if (!p.compliance_unit.empty()) json.key("unit").value(p.compliance_unit);  // compliance terms only
    json.end_object();
  }
  json.end_array();
  json.key("has_stream").value(data.has_stream);
  json.key("drops").begin_array();
  for (const auto& [reason, count] : data.drops) {
    json.begin_object();
    json.key("reason").value(reason);
    json.key("count").value(static_cast<long long>(count));
    json.end_object();
  }
  json.end_array();
  if (!data.timeline.reasons.empty()) {
    json.key("timeline").begin_object();
    json.key("duration_s").value(data.timeline.duration_s);
    json.key("reasons").begin_array();
    for (const std::string& r : data.timeline.reasons) json.value(r);
    json.end_array();
    json.key("counts").begin_array();
    for (const std::vector<std::uint32_t>& bins : data.timeline.counts) {
      const std::vector<double> values(bins.begin(), bins.end());
      json.inline_array(values.data(), values.size());
    }
    json.end_array();
    json.end_object();
  }
  const ClockMatchSeries& match = data.clock_match;
  if (!match.t_s.empty()) {
    json.key("clock_match").begin_object();
    json.key("speed_gain").value(match.speed_gain);
    json.key("t_s").inline_array(match.t_s.data(), match.t_s.size());
    json.key("robot_speed_m_s").inline_array(match.robot_speed_m_s.data(), match.robot_speed_m_s.size());
    json.key("tracker_speed_m_s").inline_array(match.tracker_speed_m_s.data(), match.tracker_speed_m_s.size());
    json.key("residual_m_s").inline_array(match.residual_m_s.data(), match.residual_m_s.size());
    json.end_object();
  }
  write_outliers(json, data.outliers);
  if (data.cross_validation.present) write_cross_validation(json, data.cross_validation);
  json.end_object();
}

port::Error parse_report_data(const JsonValue& value, const std::string& source, ReportData* data) {
  if (value.kind != JsonValue::Kind::object) return port::Error::input(source + ": \"report\" must be an object");
  ReportData parsed;
  const auto bad = [&](const char* key) {
    return port::Error::input(source + ": \"report\".\"" + key + "\" is malformed");
  };
  if (!get_string(value.find("title"), &parsed.title)) return bad("title");
  parsed.title = port::printable(parsed.title, 4096);  // it carries the robot's name: printable, as calibrate wrote it
  const JsonValue* info = value.find("info");
  if (!is_array(info)) return bad("info");
  for (const JsonValue& line : info->array) {
    parsed.info_lines.emplace_back();
    if (!get_string(&line, &parsed.info_lines.back())) return bad("info");
  }
  if (!get_methods(value.find("methods"), &parsed.methods)) return bad("methods");
  if (!get_accuracy(value.find("uncalibrated"), &parsed.uncalibrated)) return bad("uncalibrated");
  if (!get_accuracy(value.find("calibrated"), &parsed.calibrated)) return bad("calibrated");
  if (!get_convergence(value.find("convergence"), &parsed.convergence)) return bad("convergence");
  if (!get_samples(value.find("samples"), &parsed.samples)) return bad("samples");
  if (const JsonValue* total = value.find("sample_total"); total != nullptr) {  // a thinned report only
    long long count = 0;
    if (!get_count(total, &count) || static_cast<std::size_t>(count) <= parsed.samples.size())
      return bad("sample_total");
    parsed.sample_total = static_cast<std::size_t>(count);
  }
  if (!get_predictions(value.find("predictions"), parsed.samples, &parsed.predictions)) return bad("predictions");
  if (!get_number(value.find("noise_sigma_m"), &parsed.noise_sigma_m)) return bad("noise_sigma_m");
  if (const JsonValue* noise_source = value.find("noise_source"); noise_source != nullptr) {  // measured noise only
    if (!get_string(noise_source, &parsed.noise_source)) return bad("noise_source");
  }
  if (!get_number(value.find("fit_sigma_m"), &parsed.fit_sigma_m)) return bad("fit_sigma_m");
  if (!get_identifiability(value.find("identifiability"), &parsed.identifiability)) return bad("identifiability");
  if (!get_parameters(value.find("parameters"), &parsed.parameters)) return bad("parameters");
  if (!get_bool(value.find("has_stream"), &parsed.has_stream)) return bad("has_stream");
  if (!get_drops(value.find("drops"), &parsed.drops)) return bad("drops");
  if (!get_timeline(value.find("timeline"), &parsed.timeline)) return bad("timeline");
  if (!get_clock_match(value.find("clock_match"), &parsed.clock_match)) return bad("clock_match");
  if (!get_outliers(value.find("outliers"), &parsed.outliers)) return bad("outliers");
  if (!get_cross_validation(value.find("cross_validation"), &parsed.cross_validation)) return bad("cross_validation");
  *data = parsed;
  return port::Error{};
}

std::vector<report::SampleRow> report_training_samples(const std::string& result_text, const std::string& source) {
  textio::JsonValue root;
  report::ReportData data;
  const textio::JsonValue* saved = nullptr;
  if (!textio::parse_json(result_text, &root).ok() || (saved = root.find("report")) == nullptr ||
      !parse_report_data(*saved, source, &data).ok()) {
    return {};
  }
  std::vector<report::SampleRow> train;
  for (const report::SampleRow& sample : data.samples)
    if (!sample.test) train.push_back(sample);
  return train;
}

}  // namespace hivecal::record
