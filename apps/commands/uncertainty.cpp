// The covariance and domain a result carries, and the domain statement (uncertainty.hpp).
#include "commands/uncertainty.hpp"

#include <cstdio>
#include <memory>

#include "hivecal/core/math.hpp"
#include "hivecal/solve/parameter_correlation.hpp"
#include "hivecal/solve/prediction_uncertainty.hpp"

namespace hivecal::cli {

void compute_uncertainty(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> train,
                         const PointLoss& loss, const LmPrior& prior, ParamMask estimated,
                         const Vec3 (&other_tools_sigma_m)[kMaxTargets - 1],
                         record::CalibrationUncertainty* uncertainty, std::string* note) {
  *uncertainty = record::CalibrationUncertainty{};
  const auto scratch = std::make_unique<CorrelationScratch>();  // ~220 kB: not on the stack
  const auto covariance = std::make_unique<NormalMatrix>();
  int dof = 0;
  const Status status = parameter_covariance(model, base_to_tracker, train, loss, estimated, scratch.get(),
                                             covariance.get(), &dof, prior);
  if (status == Status::ok) {
    uncertainty->set_covariance(*covariance);
    uncertainty->estimated = estimated;
    for (int k = 0; k < kMaxTargets - 1; ++k) uncertainty->other_tools_sigma_m[k] = other_tools_sigma_m[k];
    uncertainty->residual_dof = dof;
    uncertainty->residual_sigma_m = std::sqrt(scratch->equations.weighted_squares_m2 / static_cast<double>(dof));
  } else {
    covariance->setZero();
    *note = std::string("uncertainty: no parameter covariance (") + status_message(status) +
            "): predict writes no sigma_m, and the domain is the joint ranges alone";
  }
  CalibrationDomain domain;
  if (calibration_domain(model, base_to_tracker, train, *covariance, uncertainty->estimated & ~kOtherTargetTools,
                         uncertainty->other_tools_sigma_m, &domain) == Status::ok) {
    uncertainty->domain = domain;
    uncertainty->has_domain = true;
  }
}

std::string extrapolation_rule(const CalibrationDomain& d) {
  std::string joints;                   // the joints whose ranges count
  for (int j = 0; j < kMaxJoints; ++j)  // the bits of the arm's joints
    if (d.term_joints & (1U << static_cast<unsigned>(j)))
      joints += (joints.empty() ? "q" : ", q") + std::to_string(j + 1);
  char buf[200];
  std::string rule;
  if (d.typical_sigma_m > 0.0) {
    std::snprintf(buf, sizeof buf, "its sigma exceeds %.3gx the training poses' typical %.4f mm, or ", d.sigma_factor,
                  d.typical_sigma_m * 1e3);
    rule = buf;
  }
  std::snprintf(buf, sizeof buf, "the tool axis lies more than %.3g deg beyond their spread (%.1f deg)",
                d.tool_axis_margin_rad / math::kRadPerDeg, d.tool_axis_spread_rad / math::kRadPerDeg);
  rule += buf;
  if (!joints.empty()) {
    std::snprintf(buf, sizeof buf, ", or a joint of the model's terms (%s) more than %.3g deg beyond its range",
                  joints.c_str(), d.joint_margin_rad / math::kRadPerDeg);
    rule += buf;
  }
  return rule;
}

std::vector<std::string> domain_lines(const record::CalibrationUncertainty& u, int joints) {
  std::vector<std::string> lines;
  if (!u.has_domain) return lines;
  const CalibrationDomain& d = u.domain;
  std::string ranges;
  char buf[400];
  for (int j = 0; j < joints; ++j) {
    std::snprintf(buf, sizeof buf, "%sq%d %.1f..%.1f", j == 0 ? "" : ", ", j + 1, d.joint_min_rad(j) / math::kRadPerDeg,
                  d.joint_max_rad(j) / math::kRadPerDeg);
    ranges += buf;
  }
  std::snprintf(buf, sizeof buf, "domain: made on %zu poses, joints [deg] %s", d.poses, ranges.c_str());
  lines.push_back(buf);
  std::snprintf(buf, sizeof buf,
                "domain: the tool axis (flange z) within %.1f deg of its mean direction (RMS %.1f deg)%s",
                d.tool_axis_spread_rad / math::kRadPerDeg, d.tool_axis_rms_rad / math::kRadPerDeg,
                d.tool_axis_spread_rad < 10.0 * math::kRadPerDeg
                    ? ": nearly one tool orientation, the tool point and the wrist barely separated"
                    : "");
  lines.push_back(buf);
  const std::string rule = extrapolation_rule(d);
  if (d.typical_sigma_m > 0.0) {
    std::snprintf(buf, sizeof buf,
                  "domain: predictions there have a typical 1-sigma of %.4f mm per axis (largest %.4f mm); a pose is "
                  "extrapolated when ",
                  d.typical_sigma_m * 1e3, d.max_sigma_m * 1e3);
    lines.push_back(buf + rule);
  } else {
    lines.push_back("domain: a pose is extrapolated when " + rule + " (no covariance: no sigma)");
  }
  return lines;
}

void ExtrapolationCount::add(const Extrapolation& e) {
  ++poses;
  flagged += e.extrapolated() ? 1U : 0U;
  sigma += e.sigma_beyond ? 1U : 0U;
  tool_axis += e.tool_axis_beyond ? 1U : 0U;
  joint += e.joint >= 0 ? 1U : 0U;
}

std::string ExtrapolationCount::text() const {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "%zu of %zu poses extrapolated (by their sigma %zu, the tool axis %zu, a joint's range %zu)", flagged,
                poses, sigma, tool_axis, joint);
  return buf;
}

Predictor::Predictor(const record::CalibrationFile& calibration)
    : calibration_(calibration), covariance_(std::make_unique<NormalMatrix>()) {
  const record::CalibrationUncertainty& u = calibration.uncertainty;
  has_uncertainty_ = u.has_covariance() && u.has_domain;
  *covariance_ = u.covariance_matrix();
}

Prediction Predictor::operator()(const JointVector& q_rad, int target, PredictionFrame frame) const {
  const record::CalibrationFile& c = calibration_;
  Prediction p;
  const Vec3 chain_point = fk_target_point(c.model, q_rad, target);
  // The file's own base frame: for modified DH the frame before Rx(alpha_0) Tx(a_0).
  const RigidTransform file_base =
      c.convention == DhConvention::modified ? c.modified_base.transform() : RigidTransform{};
  p.point_m = frame == PredictionFrame::base ? file_base.apply(chain_point) : c.base_to_tracker.apply(chain_point);
  if (!has_uncertainty_) return p;
  const record::CalibrationUncertainty& u = c.uncertainty;
  const ParamMask estimated = u.estimated & ~kOtherTargetTools;
  const Vec3 tool_sigma_m = target > 0 ? u.other_tools_sigma_m[target - 1] : Vec3(Vec3::Zero());
  const double tracker_sigma_m = prediction_sigma_m(c.model, c.base_to_tracker, q_rad, target, *covariance_, estimated,
                                                    PredictionFrame::tracker, tool_sigma_m);
  p.sigma_m = frame == PredictionFrame::tracker ? tracker_sigma_m
                                                : prediction_sigma_m(c.model, c.base_to_tracker, q_rad, target,
                                                                     *covariance_, estimated, frame, tool_sigma_m);
  // The domain's typical sigma is the tracker frame's: so is the test, whatever the frame written.
  p.extrapolation = extrapolation(u.domain, c.model, q_rad, tracker_sigma_m);
  return p;
}

}  // namespace hivecal::cli
