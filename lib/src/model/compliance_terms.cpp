// Building, checking and naming a model's joint terms: the setup of a job, run once (compiled
// for size on bare metal, lib/CMakeLists.txt); their evaluation at a pose is compliance.cpp.
#include "hivecal/model/compliance.hpp"

#include <algorithm>
#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/model/kinematics.hpp"
#include "core/names.hpp"
#include "model/kinematics_detail.hpp"

namespace hivecal {
namespace {

/// The cosine of 45 degrees: an axis is horizontal when it is closer to the horizontal plane than to gravity.
constexpr double kHorizontalCos = 0.70710678118654752440;

bool finite_vec(const Vec3& v) {
  return math::is_finite(v.x()) && math::is_finite(v.y()) && math::is_finite(v.z());
}

Status check_masses(const ArmMasses& masses, int joint_count) {
  for (int link = 0; link < joint_count; ++link) {
    if (!math::is_finite(masses.link_mass_kg[link]) || !finite_vec(masses.link_com_m[link]))
      return Status::non_finite_input;
    if (masses.link_mass_kg[link] < 0.0) return Status::invalid_argument;
  }
  if (!math::is_finite(masses.payload_kg) || !finite_vec(masses.payload_com_m)) return Status::non_finite_input;
  return masses.payload_kg < 0.0 ? Status::invalid_argument : Status::ok;
}

Status check_term(const ComplianceModel& compliance, const RobotModel& model, const ComplianceTerm& term) {
  if (term.joint < 0 || term.joint >= model.joint_count) return Status::invalid_argument;
  if (term.kind == JointTermKind::harmonic_sin || term.kind == JointTermKind::harmonic_cos) {
    const bool revolute = joint_type(model, term.joint) == JointType::revolute;
    return revolute && term.order >= 1 && term.order <= kMaxHarmonicOrder ? Status::ok : Status::invalid_argument;
  }
  if (term.kind != JointTermKind::gravity) return Status::invalid_argument;
  if (compliance.load == ComplianceLoad::arm_masses) return Status::ok;
  const bool dh_frame = term.frame > term.joint && term.frame <= model.joint_count;
  return dh_frame || term.frame == kToolLoadFrame ? Status::ok : Status::invalid_argument;
}

// Universal Robots, "DH Parameters for calculations of kinematics and dynamics"
// (universal-robots.com/articles/ur/application-installation/dh-parameters-for-calculations-of-kinematics-and-dynamics):
// link mass [kg] and centre of mass [m] in the link's DH frame (the frame at the link's end). The
// UR3e and UR5e tables are that page's. The others are Universal Robots' own ROS 2 description
// (github.com/UniversalRobots/Universal_Robots_ROS2_Description, config/<arm>/physical_parameters.yaml),
// whose comments map each centre back to the page's frame (e.g. "x: model.x - upper_arm_length"):
// mapped back, its UR5e file gives the page's UR5e table to the digit, and its UR10e file the page's
// UR10e rows (links 1 to 5; link 6 is the file's). The UR10e's centres are the UR10's, the UR3's
// the UR3e's.
constexpr double kUr3eMass_kg[kSixJoints] = {1.98, 3.4445, 1.437, 0.871, 0.805, 0.261};
constexpr double kUr3eCom_m[kSixJoints][3] = {{0.0, -0.02, 0.0}, {0.13, 0.0, 0.1157}, {0.05, 0.0, 0.0238},
                                              {0.0, 0.0, 0.01},  {0.0, 0.0, 0.01},    {0.0, 0.0, -0.02}};
constexpr double kUr5eMass_kg[kSixJoints] = {3.761, 8.058, 2.846, 1.37, 1.3, 0.365};
constexpr double kUr5eCom_m[kSixJoints][3] = {{0.0, -0.02561, 0.00193}, {0.2125, 0.0, 0.11336}, {0.15, 0.0, 0.0265},
                                              {0.0, -0.0018, 0.01634},  {0.0, 0.0018, 0.01634}, {0.0, 0.0, -0.001159}};

// The UR5's centres of mass are the UR5e's (both sources give the same numbers): its masses only.
constexpr double kUr5Mass_kg[kSixJoints] = {3.7, 8.393, 2.33, 1.219, 1.219, 0.1879};
constexpr double kUr10Mass_kg[kSixJoints] = {7.1, 12.7, 4.27, 2.0, 2.0, 0.365};
constexpr double kUr10Com_m[kSixJoints][3] = {{0.021, 0.0, 0.027}, {0.38, 0.0, 0.158},  {0.24, 0.0, 0.068},
                                              {0.0, 0.007, 0.018}, {0.0, 0.007, 0.018}, {0.0, 0.0, -0.026}};
constexpr double kUr3Mass_kg[kSixJoints] = {2.0, 3.42, 1.26, 0.8, 0.8, 0.35};
constexpr double kUr10eMass_kg[kSixJoints] = {7.369, 13.051, 3.989, 2.1, 1.98, 0.615};
constexpr double kUr16eMass_kg[kSixJoints] = {7.369, 10.45, 4.321, 2.18, 2.033, 0.907};
constexpr double kUr16eCom_m[kSixJoints][3] = {{0.0, -0.016, 0.03},  {0.302, 0.0, 0.16},  {0.194, 0.0, 0.065},
                                               {0.0, -0.009, 0.011}, {0.0, 0.018, 0.012}, {0.0, 0.0, -0.044}};

/// One arm's published table: its link masses [kg] and centres of mass [m].
struct PublishedArm {
  RobotType type;
  const double* mass_kg;
  const double (*com_m)[3];
};
constexpr PublishedArm kPublishedArms[] = {
    {RobotType::ur5e, kUr5eMass_kg, kUr5eCom_m},   {RobotType::ur3e, kUr3eMass_kg, kUr3eCom_m},
    {RobotType::ur5, kUr5Mass_kg, kUr5eCom_m},     {RobotType::ur10, kUr10Mass_kg, kUr10Com_m},
    {RobotType::ur3, kUr3Mass_kg, kUr3eCom_m},     {RobotType::ur10e, kUr10eMass_kg, kUr10Com_m},
    {RobotType::ur16e, kUr16eMass_kg, kUr16eCom_m}};

/// Column of a joint's name row that names its arm-mass term; the point frames 1 .. kMaxJoints
/// come first, then the tool (kToolLoadFrame).
constexpr int kMassNameColumn = kToolLoadFrame;

/// "c_j<joint>_o<frame>", "c_j<joint>_tool", "c_j<joint>_mass" for every joint and frame the build holds.
struct TermNames {
  detail::Name name[kMaxJoints][kMassNameColumn + 1];
};
constexpr TermNames term_names() {
  TermNames names;
  for (int j = 0; j < kMaxJoints; ++j) {
    for (int frame = 1; frame <= kMaxJoints; ++frame)
      names.name[j][frame - 1] = detail::numbered_name("c_j", j + 1, "_o", frame);
    names.name[j][kToolLoadFrame - 1] = detail::numbered_name("c_j", j + 1, "_tool");
    names.name[j][kMassNameColumn] = detail::numbered_name("c_j", j + 1, "_mass");
  }
  return names;
}
constexpr TermNames kTermNames = term_names();

/// "h_j<joint>_sin<order>", "h_j<joint>_cos<order>" for every joint the build holds.
struct HarmonicNames {
  detail::Name name[kMaxJoints][2][kMaxHarmonicOrder];
};
constexpr HarmonicNames harmonic_names() {
  HarmonicNames names;
  for (int j = 0; j < kMaxJoints; ++j) {
    for (int k = 1; k <= kMaxHarmonicOrder; ++k) {
      names.name[j][0][k - 1] = detail::numbered_name("h_j", j + 1, "_sin", k);
      names.name[j][1][k - 1] = detail::numbered_name("h_j", j + 1, "_cos", k);
    }
  }
  return names;
}
constexpr HarmonicNames kHarmonicNames = harmonic_names();

}  // namespace

// Out of line: every RobotModel builds one, and the firmware's flash holds one copy.
ArmMasses::ArmMasses() {
  for (Vec3& com_m : link_com_m) com_m.setZero();
}

Status check_compliance(const ComplianceModel& compliance, const RobotModel& model) {
  if (compliance.term_count < 0 || compliance.term_count > kMaxComplianceTerms) return Status::invalid_argument;
  if (compliance.term_count == 0) return Status::ok;  // rigid: the other fields are not read
  if (compliance.load != ComplianceLoad::point && compliance.load != ComplianceLoad::arm_masses) {
    return Status::invalid_argument;
  }
  if (!finite_vec(compliance.gravity_direction)) return Status::non_finite_input;
  if (std::fabs(compliance.gravity_direction.norm() - 1.0) > 1e-9) return Status::invalid_argument;
  for (int t = 0; t < compliance.term_count; ++t) {
    if (!math::is_finite(compliance.coefficient[t])) return Status::non_finite_input;
    const Status term = check_term(compliance, model, compliance.terms[t]);
    if (term != Status::ok) return term;
  }
  return compliance.load == ComplianceLoad::arm_masses ? check_masses(compliance.masses, model.joint_count)
                                                       : Status::ok;
}

Status default_compliance_terms(const RobotModel& model, const Vec3& gravity_direction, ComplianceLoad load,
                                ComplianceModel* compliance) {
  if (!finite_vec(gravity_direction)) return Status::invalid_argument;
  const double norm = gravity_direction.norm();
  if (!(norm > 0.0)) return Status::invalid_argument;
  const Vec3 g = gravity_direction / norm;
  RigidTransform frame[kMaxJoints + 1];
  detail::rigid_frames(model, JointVector::Zero(), frame);
  int horizontal[kMaxJoints];
  int count = 0;
  for (int j = 0; j < model.joint_count; ++j) {
    const bool revolute = joint_type(model, j) == JointType::revolute;
    if (revolute && std::fabs(frame[j].rotation.col(2).dot(g)) < kHorizontalCos) horizontal[count++] = j;
  }
  ComplianceModel out = *compliance;
  for (double& c : out.coefficient) c = 0.0;
  for (ComplianceTerm& term : out.terms) term = ComplianceTerm{};
  out.gravity_direction = g;
  out.load = load;
  out.term_count = 0;
  if (load == ComplianceLoad::point) {
    if (count < 2) return Status::invalid_argument;
    const int shoulder = horizontal[0];
    const int elbow = horizontal[1];
    // The wrist is DH frame 4 (a UR's), or the elbow's link end when the elbow comes later (and
    // at most the flange of a shorter arm).
    const int wrist = std::min(elbow + 1 > 4 ? elbow + 1 : 4, model.joint_count);
    constexpr int kPointTermCount = 4;
    const ComplianceTerm terms[kPointTermCount] = {
        {shoulder, shoulder + 1}, {shoulder, wrist}, {elbow, wrist}, {elbow, kToolLoadFrame}};
    for (int t = 0; t < kPointTermCount; ++t) out.terms[t] = terms[t];
    out.term_count = kPointTermCount;
  } else {
    for (int k = 0; k < count && horizontal[k] < 4; ++k) out.terms[out.term_count++] = ComplianceTerm{horizontal[k], 0};
    if (out.term_count == 0) return Status::invalid_argument;
  }
  *compliance = out;
  return Status::ok;
}

Status append_harmonic_terms(int orders, const RobotModel& model, ComplianceModel* compliance) {
  if (orders < 1 || orders > kMaxHarmonicOrder) return Status::invalid_argument;
  const int added = harmonic_term_count(model, orders);
  if (compliance->term_count < 0 || compliance->term_count + added > kMaxComplianceTerms)
    return Status::invalid_argument;
  for (int j = 0; j < model.joint_count; ++j) {
    if (joint_type(model, j) != JointType::revolute) continue;
    for (int k = 1; k <= orders; ++k) {
      for (const JointTermKind kind : {JointTermKind::harmonic_sin, JointTermKind::harmonic_cos}) {
        compliance->terms[compliance->term_count] = ComplianceTerm{j, 0, kind, k};
        compliance->coefficient[compliance->term_count++] = 0.0;
      }
    }
  }
  return Status::ok;
}

int harmonic_term_count(const RobotModel& model, int orders) {
  int revolute = 0;
  for (int j = 0; j < model.joint_count; ++j) revolute += joint_type(model, j) == JointType::revolute ? 1 : 0;
  return 2 * revolute * orders;
}

Status nominal_arm_masses(RobotType type, ArmMasses* masses) {
  for (const PublishedArm& arm : kPublishedArms) {
    if (arm.type != type) continue;
    for (int link = 0; link < kSixJoints; ++link) {
      masses->link_mass_kg[link] = arm.mass_kg[link];
      masses->link_com_m[link] = Vec3(arm.com_m[link][0], arm.com_m[link][1], arm.com_m[link][2]);
    }
    return Status::ok;
  }
  return Status::invalid_argument;
}

const char* compliance_term_name(const ComplianceModel& compliance, int t) {
  if (t < 0 || t >= compliance.term_count) return "?";
  const ComplianceTerm& term = compliance.terms[t];
  if (term.joint < 0 || term.joint >= kMaxJoints) return "?";
  if (is_harmonic(term)) {
    if (term.order < 1 || term.order > kMaxHarmonicOrder) return "?";
    return kHarmonicNames.name[term.joint][term.kind == JointTermKind::harmonic_sin ? 0 : 1][term.order - 1].text;
  }
  if (compliance.load == ComplianceLoad::arm_masses) return kTermNames.name[term.joint][kMassNameColumn].text;
  if (term.frame < 1 || term.frame > kToolLoadFrame) return "?";
  return kTermNames.name[term.joint][term.frame - 1].text;
}

}  // namespace hivecal
