// A model's joint terms at a pose, for every FK: their basis and the joints' deflection.
// Building, checking and naming the terms: compliance_terms.cpp.
#include "hivecal/model/compliance.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/model/kinematics.hpp"
#include "model/kinematics_detail.hpp"

namespace hivecal {
namespace {

/// Gravity torque about the axis `z` through `origin_m` of a mass at `point_m`, per unit g and
/// unit mass: z . ((P - o) x g_hat) [m].
double lever_m(const Vec3& z, const Vec3& origin_m, const Vec3& point_m, const Vec3& gravity) {
  return z.dot((point_m - origin_m).cross(gravity));
}

/// The basis of a harmonic term at joint readings q: sin or cos of order * q_j [-], from sin q_j
/// and cos q_j (`trig`, the readings' joint trig, or computed here when null) by the angle sums.
double harmonic_basis(const ComplianceTerm& term, const JointVector& q_rad, const JointTrig* trig) {
  const int j = term.joint;
  double sin_q = 0.0;
  double cos_q = 1.0;
  if (trig != nullptr) {
    sin_q = trig->sin_q[j];
    cos_q = trig->cos_q[j];
  } else {
    math::sincos(q_rad(j), &sin_q, &cos_q);
  }
  double sin_kq = sin_q;
  double cos_kq = cos_q;
  for (int k = 1; k < term.order; ++k) {
    const double next_sin = sin_kq * cos_q + cos_kq * sin_q;
    cos_kq = cos_kq * cos_q - sin_kq * sin_q;
    sin_kq = next_sin;
  }
  return term.kind == JointTermKind::harmonic_sin ? sin_kq : cos_kq;
}

/// What a unit mass at `point_m` loads a joint with, per unit g: the torque about its axis `z`
/// through `origin_m` (revolute, [m]), or the weight along its axis (prismatic, [-]).
double joint_load(JointType type, const Vec3& z, const Vec3& origin_m, const Vec3& point_m, const Vec3& gravity) {
  return type == JointType::revolute ? lever_m(z, origin_m, point_m, gravity) : z.dot(gravity);
}

/// The basis of one gravity term over the rigid frames at the pose.
double gravity_basis(const RobotModel& model, const ComplianceTerm& term,
                     const RigidTransform (&frame)[kMaxJoints + 1]) {
  const ComplianceModel& compliance = model.compliance;
  const int joints = model.joint_count;
  const JointType type = joint_type(model, term.joint);
  const Vec3 z = frame[term.joint].rotation.col(2);
  const Vec3& origin_m = frame[term.joint].translation_m;
  const Vec3& g = compliance.gravity_direction;
  if (compliance.load == ComplianceLoad::point) {
    const Vec3 point_m =
        term.frame == kToolLoadFrame ? frame[joints].apply(model.tool_m) : frame[term.frame].translation_m;
    return joint_load(type, z, origin_m, point_m, g);
  }
  // Every mass joint j carries: the links it moves (j + 1 .. joint_count), then the payload.
  const ArmMasses& masses = compliance.masses;
  double sum = 0.0;
  for (int link = term.joint; link < joints; ++link) {
    sum += masses.link_mass_kg[link] * joint_load(type, z, origin_m, frame[link + 1].apply(masses.link_com_m[link]), g);
  }
  return sum + masses.payload_kg * joint_load(type, z, origin_m, frame[joints].apply(masses.payload_com_m), g);
}

/// True when any of the model's terms is a gravity term (its basis needs the rigid frames).
bool has_gravity_term(const ComplianceModel& compliance) {
  for (int t = 0; t < compliance.term_count; ++t) {
    if (!is_harmonic(compliance.terms[t])) return true;
  }
  return false;
}

}  // namespace

void compliance_basis(const RobotModel& model, const JointVector& q_rad, double (&basis)[kMaxComplianceTerms],
                      const JointTrig* trig) {
  for (double& b : basis) b = 0.0;
  const ComplianceModel& compliance = model.compliance;
  if (compliance.term_count == 0) return;
  RigidTransform frame[kMaxJoints + 1];
  if (has_gravity_term(compliance)) detail::rigid_frames(model, q_rad, frame);
  for (int t = 0; t < compliance.term_count; ++t) {
    const ComplianceTerm& term = compliance.terms[t];
    basis[t] = is_harmonic(term) ? harmonic_basis(term, q_rad, trig) : gravity_basis(model, term, frame);
  }
}

JointVector compliance_deflection(const RobotModel& model, const JointVector& q_rad) {
  double basis[kMaxComplianceTerms];
  return compliance_deflection(model, q_rad, basis);
}

JointVector compliance_deflection(const RobotModel& model, const JointVector& q_rad,
                                  double (&basis)[kMaxComplianceTerms], const JointTrig* trig) {
  JointVector dq = JointVector::Zero();
  compliance_basis(model, q_rad, basis, trig);
  const ComplianceModel& compliance = model.compliance;
  for (int t = 0; t < compliance.term_count; ++t) dq(compliance.terms[t].joint) += compliance.coefficient[t] * basis[t];
  return dq;
}

}  // namespace hivecal
