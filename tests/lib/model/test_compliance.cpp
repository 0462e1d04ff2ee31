// Joint compliance (model/compliance.hpp): zero coefficients give the rigid bits, a deflection
// is the rigid FK at q + dq with dq from frames computed another way, the basis is the
// horizontal lever arm of a unit mass, and it vanishes about a vertical axis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/model/kinematics.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::compliance_test {
namespace {

bool same_bits(const Vec3& a, const Vec3& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0;
}

RobotModel compliant_ur5e(ComplianceLoad load) {
  RobotModel model = nominal_model(RobotType::ur5e);
  model.tool_m << 0.01, -0.02, 0.15;
  model.other_tools_m[0] << -0.03, 0.04, 0.12;
  EXPECT_EQ(nominal_arm_masses(RobotType::ur5e, &model.compliance.masses), Status::ok);
  model.compliance.masses.payload_kg = 1.5;
  model.compliance.masses.payload_com_m << 0.0, 0.01, 0.05;
  EXPECT_EQ(default_compliance_terms(model, Vec3(0.0, 0.0, -1.0), load, &model.compliance), Status::ok);
  return model;
}

/// Origin and z axis of DH frame k at q, from fk_flange of the chain cut after joint k (the
/// later links made identities): another route than the library's frame recursion.
RigidTransform frame_by_truncation(const RobotModel& model, const JointVector& q, int k) {
  RobotModel cut = model;
  cut.compliance.term_count = 0;
  for (int j = k; j < kSixJoints; ++j) cut.joints[j] = DhJoint{};
  JointVector q_cut = q;
  for (int j = k; j < kSixJoints; ++j) q_cut(j) = 0.0;
  return fk_flange(cut, q_cut);
}

TEST(Compliance, ZeroCoefficientsGiveTheRigidBits) {
  Random random(161);
  for (ComplianceLoad load : {ComplianceLoad::point, ComplianceLoad::arm_masses}) {
    const RobotModel compliant = compliant_ur5e(load);
    ASSERT_GT(compliant.compliance.term_count, 0);
    RobotModel rigid = compliant;
    rigid.compliance.term_count = 0;
    const ModelTrig trig = model_trig(rigid);
    for (int i = 0; i < 50; ++i) {
      const JointVector q = test::random_joints(&random);
      Vec3 a;
      Vec3 b;
      EXPECT_NO_HEAP(a = fk_tool_point(compliant, q));
      b = fk_tool_point(rigid, q);
      EXPECT_TRUE(same_bits(a, b));
      EXPECT_NO_HEAP(a = fk_tool_point(compliant, trig, q));
      EXPECT_TRUE(same_bits(a, fk_tool_point(rigid, trig, q)));
      EXPECT_NO_HEAP(a = fk_target_point(compliant, q, 1));
      EXPECT_TRUE(same_bits(a, fk_target_point(rigid, q, 1)));
      RigidTransform fa;
      EXPECT_NO_HEAP(fa = fk_flange(compliant, q));
      const RigidTransform fb = fk_flange(rigid, q);
      EXPECT_EQ(std::memcmp(&fa, &fb, sizeof fa), 0);
      ToolPointJacobian ja;
      ToolPointJacobian jb;
      EXPECT_NO_HEAP(a = tool_point_jacobian(compliant, q, &ja));
      EXPECT_TRUE(same_bits(a, tool_point_jacobian(rigid, q, &jb)));
      EXPECT_EQ(std::memcmp(ja.data(), jb.data(), sizeof(double) * ja.size()), 0);
    }
  }
}

TEST(Compliance, DeflectionIsTheRigidChainAtQPlusDqComputedByHand) {
  Random random(162);
  for (ComplianceLoad load : {ComplianceLoad::point, ComplianceLoad::arm_masses}) {
    RobotModel model = compliant_ur5e(load);
    model.compliance.gravity_direction = Vec3(0.3, -0.2, -1.0).normalized();  // a tilted mount
    const double scale = load == ComplianceLoad::point ? 1e-3 : 1e-4;
    for (int t = 0; t < model.compliance.term_count; ++t) model.compliance.coefficient[t] = scale * (1.0 + 0.5 * t);
    ASSERT_EQ(check_compliance(model.compliance, model), Status::ok);
    RobotModel rigid = model;
    rigid.compliance.term_count = 0;
    const Vec3& g = model.compliance.gravity_direction;
    const ArmMasses& masses = model.compliance.masses;
    for (int i = 0; i < 30; ++i) {
      const JointVector q = test::random_joints(&random);
      RigidTransform frame[kSixJoints + 1];
      for (int k = 0; k <= kSixJoints; ++k) frame[k] = frame_by_truncation(model, q, k);
      JointVector dq = JointVector::Zero();
      for (int t = 0; t < model.compliance.term_count; ++t) {
        const ComplianceTerm& term = model.compliance.terms[t];
        const Vec3 z = frame[term.joint].rotation.col(2);
        const Vec3 o = frame[term.joint].translation_m;
        double basis = 0.0;
        if (load == ComplianceLoad::point) {
          const Vec3 p =
              term.frame == kToolLoadFrame ? frame[kSixJoints].apply(model.tool_m) : frame[term.frame].translation_m;
          basis = z.dot((p - o).cross(g));
        } else {
          for (int link = term.joint; link < kSixJoints; ++link) {
            basis += masses.link_mass_kg[link] * z.dot((frame[link + 1].apply(masses.link_com_m[link]) - o).cross(g));
          }
          basis += masses.payload_kg * z.dot((frame[kSixJoints].apply(masses.payload_com_m) - o).cross(g));
        }
        dq(term.joint) += model.compliance.coefficient[t] * basis;
      }
      JointVector library_dq;
      EXPECT_NO_HEAP(library_dq = compliance_deflection(model, q));
      EXPECT_LT((library_dq - dq).cwiseAbs().maxCoeff(), 1e-15);
      EXPECT_GT(dq.cwiseAbs().maxCoeff(), 1e-5);  // the test deflects: > 5 um at the tool
      const Vec3 expected = fk_tool_point(rigid, q + dq);
      EXPECT_LT((fk_tool_point(model, q) - expected).norm(), 1e-13);
      EXPECT_LT((fk_target_point(model, q, 1) - fk_target_point(rigid, q + dq, 1)).norm(), 1e-13);
      EXPECT_LT((fk_flange(model, q).apply(model.tool_m) - expected).norm(), 1e-13);
      ToolPointJacobian jacobian;
      EXPECT_LT((tool_point_jacobian(model, q, &jacobian) - expected).norm(), 1e-13);
      EXPECT_GT((fk_tool_point(model, q) - fk_tool_point(rigid, q)).norm(), 5e-6);
    }
  }
}

TEST(Compliance, UnitMassBasisIsTheHorizontalLeverArmOfAPlanarArm) {
  // Every axis along base z, gravity along -y: a planar arm in a vertical plane (x horizontal).
  RobotModel model;
  const double a_m[kSixJoints] = {0.4, 0.3, 0.2, 0.0, 0.0, 0.0};
  for (int j = 0; j < kSixJoints; ++j) model.joints[j] = DhJoint{0.0, 0.0, a_m[j], 0.0};
  model.tool_m << 0.05, 0.0, 0.0;
  ComplianceModel& c = model.compliance;
  ASSERT_EQ(default_compliance_terms(model, Vec3(0.0, -2.0, 0.0), ComplianceLoad::point, &c), Status::ok);
  EXPECT_EQ(c.gravity_direction, Vec3(0.0, -1.0, 0.0));
  c.term_count = 3;
  c.terms[0] = ComplianceTerm{0, kToolLoadFrame};
  c.terms[1] = ComplianceTerm{1, 2};
  c.terms[2] = ComplianceTerm{1, kToolLoadFrame};
  Random random(163);
  for (int i = 0; i < 20; ++i) {
    const JointVector q = test::random_joints(&random);
    double x[4] = {0.0, 0.0, 0.0, 0.0};  // x of frame 1, 2, 3 origins, and of the tool
    double angle = 0.0;
    for (int j = 0; j < 3; ++j) {
      angle += q(j);
      x[j] = (j > 0 ? x[j - 1] : 0.0) + a_m[j] * math::cos(angle);
    }
    angle += q(3) + q(4) + q(5);
    x[3] = x[2] + 0.05 * math::cos(angle);
    double basis[kMaxComplianceTerms];
    EXPECT_NO_HEAP(compliance_basis(model, q, basis));
    // torque of a unit weight about +z: -(horizontal lever arm) for gravity along -y.
    EXPECT_NEAR(basis[0], -x[3], 1e-14);
    EXPECT_NEAR(basis[1], -(x[1] - x[0]), 1e-14);
    EXPECT_NEAR(basis[2], -(x[3] - x[0]), 1e-14);
    EXPECT_EQ(basis[3], 0.0);
  }
}

TEST(Compliance, BasisVanishesAboutAVerticalAxis) {
  RobotModel model = compliant_ur5e(ComplianceLoad::point);
  model.compliance.terms[0] = ComplianceTerm{0, kToolLoadFrame};  // UR joint 1: a vertical axis
  model.compliance.load = ComplianceLoad::point;
  Random random(164);
  for (int i = 0; i < 20; ++i) {
    double basis[kMaxComplianceTerms];
    compliance_basis(model, test::random_joints(&random), basis);
    EXPECT_EQ(basis[0], 0.0);
    EXPECT_NE(basis[3], 0.0);  // the elbow's lever to the tool does not vanish
  }
}

TEST(Compliance, DefaultTermsOfAUrArmAndTheirNames) {
  const RobotModel point = compliant_ur5e(ComplianceLoad::point);
  ASSERT_EQ(point.compliance.term_count, 4);
  const int point_terms[4][2] = {{1, 2}, {1, 4}, {2, 4}, {2, kToolLoadFrame}};
  const char* point_names[4] = {"c_j2_o2", "c_j2_o4", "c_j3_o4", "c_j3_tool"};
  for (int t = 0; t < 4; ++t) {
    EXPECT_EQ(point.compliance.terms[t].joint, point_terms[t][0]);
    EXPECT_EQ(point.compliance.terms[t].frame, point_terms[t][1]);
    EXPECT_STREQ(compliance_term_name(point.compliance, t), point_names[t]);
  }
  EXPECT_STREQ(compliance_term_name(point.compliance, 4), "?");
  const RobotModel masses = compliant_ur5e(ComplianceLoad::arm_masses);
  ASSERT_EQ(masses.compliance.term_count, 3);  // joints 2, 3, 4: horizontal at q = 0
  const char* mass_names[3] = {"c_j2_mass", "c_j3_mass", "c_j4_mass"};
  for (int t = 0; t < 3; ++t) EXPECT_STREQ(compliance_term_name(masses.compliance, t), mass_names[t]);
  EXPECT_EQ(masses.compliance.masses.link_mass_kg[1], 8.058);
  // A wall mount (gravity along base x): the base joint becomes the shoulder.
  RobotModel wall = nominal_model(RobotType::ur5e);
  ASSERT_EQ(default_compliance_terms(wall, Vec3(1.0, 0.0, 0.0), ComplianceLoad::point, &wall.compliance), Status::ok);
  EXPECT_EQ(wall.compliance.terms[0].joint, 0);
  EXPECT_EQ(wall.compliance.terms[2].joint, 1);
  ArmMasses unknown;
  EXPECT_EQ(nominal_arm_masses(static_cast<RobotType>(-1), &unknown), Status::invalid_argument);
  EXPECT_EQ(default_compliance_terms(wall, Vec3::Zero(), ComplianceLoad::point, &wall.compliance),
            Status::invalid_argument);
}

// The tables are typed in from Universal Robots' publications: each must be its arm's (a digit
// dropped or a row of another arm shows here). The links weigh 75-100 % of the arm's datasheet
// weight (the base's housing is not a link), and the upper arm's and forearm's centres of mass lie
// along their links: in the frame at the link's end, between that end (x = 0) and the link's
// other joint (x = -a, the DH a being negative on a UR).
TEST(Compliance, PublishedMassTablesMatchTheirArms) {
  struct Arm {
    RobotType type;
    double datasheet_kg;
  };
  const Arm arms[] = {{RobotType::ur3, 11.0},  {RobotType::ur5, 18.4},  {RobotType::ur10, 28.9},
                      {RobotType::ur3e, 11.2}, {RobotType::ur5e, 20.6}, {RobotType::ur10e, 33.5},
                      {RobotType::ur16e, 33.1}};
  for (const Arm& arm : arms) {
    SCOPED_TRACE(robot_type_name(arm.type));
    ArmMasses masses;
    ASSERT_EQ(nominal_arm_masses(arm.type, &masses), Status::ok);
    double sum_kg = 0.0;
    for (const double m : masses.link_mass_kg) sum_kg += m;
    EXPECT_GE(sum_kg, 0.75 * arm.datasheet_kg);
    EXPECT_LE(sum_kg, arm.datasheet_kg);
    const RobotModel model = nominal_model(arm.type);
    for (const int link : {1, 2}) {
      EXPECT_GT(masses.link_com_m[link].x(), 0.0) << "link " << link + 1;
      EXPECT_LT(masses.link_com_m[link].x(), -model.joints[link].a_m) << "link " << link + 1;
    }
    EXPECT_EQ(masses.payload_kg, 0.0);
  }
}

TEST(Compliance, MassesBasisIsTheWeightedSumOfPointBases) {
  // With every centre of mass at its frame's origin and the payload at the flange, the masses
  // basis is the masses times the point bases of frames j + 1 .. 6.
  RobotModel masses = compliant_ur5e(ComplianceLoad::arm_masses);
  for (Vec3& com : masses.compliance.masses.link_com_m) com = Vec3::Zero();
  masses.compliance.masses.payload_com_m = Vec3::Zero();
  RobotModel point = masses;
  point.compliance.load = ComplianceLoad::point;
  point.compliance.term_count = 1;
  Random random(165);
  for (int i = 0; i < 10; ++i) {
    const JointVector q = test::random_joints(&random);
    double mass_basis[kMaxComplianceTerms];
    compliance_basis(masses, q, mass_basis);
    for (int t = 0; t < masses.compliance.term_count; ++t) {
      const int joint = masses.compliance.terms[t].joint;
      double expected = 0.0;
      for (int frame = joint + 1; frame <= kSixJoints; ++frame) {
        point.compliance.terms[0] = ComplianceTerm{joint, frame};
        double b[kMaxComplianceTerms];
        compliance_basis(point, q, b);
        const double m = masses.compliance.masses.link_mass_kg[frame - 1] +
                         (frame == kSixJoints ? masses.compliance.masses.payload_kg : 0.0);
        expected += m * b[0];
      }
      EXPECT_NEAR(mass_basis[t], expected, 1e-13);
    }
  }
}

TEST(Compliance, CheckRejectsWhatTheModelCannotUse) {
  ComplianceModel c = compliant_ur5e(ComplianceLoad::point).compliance;
  EXPECT_EQ(check_compliance(c, RobotModel{}), Status::ok);
  EXPECT_EQ(check_compliance(ComplianceModel{}, RobotModel{}), Status::ok);
  ComplianceModel rigid;
  rigid.gravity_direction = Vec3::Zero();  // not read without terms
  EXPECT_EQ(check_compliance(rigid, RobotModel{}), Status::ok);
  ComplianceModel bad = c;
  bad.term_count = kMaxComplianceTerms + 1;
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = c;
  bad.term_count = 5;  // a term left at its defaults: a point load at frame 0, not beyond joint 1
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = c;
  bad.terms[1].frame = 1;  // not beyond joint 1 (0-based)
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = c;
  bad.terms[3].frame = kToolLoadFrame + 1;
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = c;
  bad.coefficient[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::non_finite_input);
  bad = c;
  bad.gravity_direction = Vec3(0.0, 0.0, -2.0);
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = compliant_ur5e(ComplianceLoad::arm_masses).compliance;
  bad.masses.link_mass_kg[2] = -1.0;
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad = c;
  bad.terms[0] = ComplianceTerm{1, 0, JointTermKind::harmonic_sin, 0};  // order 0: a constant
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad.terms[0].order = kMaxHarmonicOrder + 1;
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
  bad.terms[0].order = kMaxHarmonicOrder;
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::ok);  // a harmonic needs no frame
  bad.terms[0].kind = static_cast<JointTermKind>(3);
  EXPECT_EQ(check_compliance(bad, RobotModel{}), Status::invalid_argument);
}

/// A UR5e with only harmonic terms: orders 1 .. `orders` of every joint, given coefficients.
RobotModel harmonic_ur5e(int orders, Random* random) {
  RobotModel model = nominal_model(RobotType::ur5e);
  model.tool_m << 0.01, -0.02, 0.15;
  EXPECT_EQ(append_harmonic_terms(orders, model, &model.compliance), Status::ok);
  for (int t = 0; t < model.compliance.term_count; ++t) model.compliance.coefficient[t] = random->uniform(-2e-4, 2e-4);
  return model;
}

TEST(Compliance, HarmonicsDeflectTheirJointBySinAndCosOfItsOwnReading) {
  Random random(2501);
  const RobotModel model = harmonic_ur5e(1, &random);
  ASSERT_EQ(model.compliance.term_count, 12);
  EXPECT_EQ(check_compliance(model.compliance, model), Status::ok);
  for (int i = 0; i < 50; ++i) {
    const JointVector q = test::random_joints(&random);
    JointVector dq;
    EXPECT_NO_HEAP(dq = compliance_deflection(model, q));
    for (int j = 0; j < kSixJoints; ++j) {
      // Terms 2j, 2j + 1: the sine and the cosine of joint j (append_harmonic_terms' order).
      const double expected = model.compliance.coefficient[2 * j] * std::sin(q(j)) +
                              model.compliance.coefficient[2 * j + 1] * std::cos(q(j));
      EXPECT_NEAR(dq(j), expected, 1e-18) << j;
    }
    RobotModel rigid = model;
    rigid.compliance.term_count = 0;
    EXPECT_TRUE(same_bits(fk_tool_point(model, q), fk_tool_point(rigid, q + dq)));
  }
}

TEST(Compliance, HarmonicsAppendAfterTheGravityTermsUpToTheBuildsCapacity) {
  ComplianceModel c = compliant_ur5e(ComplianceLoad::point).compliance;
  ASSERT_EQ(c.term_count, 4);
  EXPECT_EQ(append_harmonic_terms(0, RobotModel{}, &c), Status::invalid_argument);
  EXPECT_EQ(append_harmonic_terms(kMaxHarmonicOrder + 1, RobotModel{}, &c), Status::invalid_argument);
  EXPECT_EQ(c.term_count, 4);  // a refusal leaves the model as it was
  const int needed = 4 + 2 * kSixJoints * 2;
  if (needed > kMaxComplianceTerms) {  // the bare-metal capacity holds the gravity terms only
    EXPECT_EQ(append_harmonic_terms(2, RobotModel{}, &c), Status::invalid_argument);
    EXPECT_EQ(c.term_count, 4);
    return;
  }
  ASSERT_EQ(append_harmonic_terms(2, RobotModel{}, &c), Status::ok);
  EXPECT_EQ(c.term_count, needed);
  EXPECT_EQ(check_compliance(c, RobotModel{}), Status::ok);
  EXPECT_STREQ(compliance_term_name(c, 3), "c_j3_tool");
  EXPECT_STREQ(compliance_term_name(c, 4), "h_j1_sin1");
  EXPECT_STREQ(compliance_term_name(c, 5), "h_j1_cos1");
  EXPECT_STREQ(compliance_term_name(c, 6), "h_j1_sin2");
  EXPECT_STREQ(compliance_term_name(c, 7), "h_j1_cos2");
  EXPECT_STREQ(compliance_term_name(c, 8), "h_j2_sin1");
  EXPECT_STREQ(compliance_term_name(c, needed - 1), "h_j6_cos2");
  EXPECT_EQ(append_harmonic_terms(kMaxHarmonicOrder, RobotModel{}, &c), Status::invalid_argument);  // over capacity
  // Three orders of six joints with the gravity terms: the hosted builds' 40.
  ComplianceModel third = compliant_ur5e(ComplianceLoad::point).compliance;
  const int needed_third = 4 + kMaxHarmonicOrder * kSixJoints * 2;
  if (needed_third > kMaxComplianceTerms) {
    EXPECT_EQ(append_harmonic_terms(kMaxHarmonicOrder, RobotModel{}, &third), Status::invalid_argument);
    return;
  }
  ASSERT_EQ(append_harmonic_terms(kMaxHarmonicOrder, RobotModel{}, &third), Status::ok);
  EXPECT_EQ(third.term_count, needed_third);
  EXPECT_EQ(check_compliance(third, RobotModel{}), Status::ok);
  EXPECT_STREQ(compliance_term_name(third, 8), "h_j1_sin3");
  EXPECT_STREQ(compliance_term_name(third, 9), "h_j1_cos3");
  EXPECT_STREQ(compliance_term_name(third, needed_third - 1), "h_j6_cos3");
}

/// A UR5e lifted by a vertical linear axis (a prismatic joint 1 along the base z, then the arm's
/// six joints): the lift carries the whole arm's weight along its axis.
RobotModel lifted_ur5e() {
  const RobotModel ur5e = nominal_model(RobotType::ur5e);
  RobotModel model;
  model.joint_count = 7;
  set_joint_type(&model, 0, JointType::prismatic);
  for (int j = 0; j < kSixJoints; ++j) model.joints[j + 1] = ur5e.joints[j];
  model.tool_m << 0.01, -0.02, 0.15;
  return model;
}

TEST(Compliance, APrismaticJointCarriesTheWeightAlongItsAxis) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints";
  Random random(163);
  for (ComplianceLoad load : {ComplianceLoad::point, ComplianceLoad::arm_masses}) {
    RobotModel model = lifted_ur5e();
    ComplianceModel& c = model.compliance;
    c.load = load;
    c.gravity_direction = Vec3(0.0, 0.0, -1.0);
    c.term_count = 1;
    c.terms[0] = ComplianceTerm{0, load == ComplianceLoad::point ? kToolLoadFrame : 0};
    c.coefficient[0] = 2e-6;  // [m/kg]: the lift's stiffness
    if (load == ComplianceLoad::arm_masses) {
      ASSERT_EQ(nominal_arm_masses(RobotType::ur5e, &c.masses), Status::ok);  // links 1 .. 6 of the arm
      for (int link = kSixJoints; link > 0; --link) {  // one link on: the carriage carries the arm's six
        c.masses.link_mass_kg[link] = c.masses.link_mass_kg[link - 1];
        c.masses.link_com_m[link] = c.masses.link_com_m[link - 1];
      }
      c.masses.link_mass_kg[0] = 0.0;
      c.masses.payload_kg = 1.5;
    }
    ASSERT_EQ(check_compliance(c, model), Status::ok);
    double total_kg = 1.0;  // the point load's unit mass
    if (load == ComplianceLoad::arm_masses) {
      total_kg = c.masses.payload_kg;
      for (int link = 0; link < model.joint_count; ++link) total_kg += c.masses.link_mass_kg[link];
    }
    RobotModel rigid = model;
    rigid.compliance.term_count = 0;
    for (int i = 0; i < 20; ++i) {
      JointVector q = test::random_joints(&random);
      for (int j = kSixJoints; j > 0; --j) q(j) = q(j - 1);
      q(0) = random.uniform(0.0, 1.0);
      double basis[kMaxComplianceTerms];
      JointVector dq;
      EXPECT_NO_HEAP(dq = compliance_deflection(model, q, basis));
      // The weight along the axis, whatever the arm's pose: z0 . g = -1 per kg.
      EXPECT_NEAR(basis[0], -total_kg, 1e-12 * total_kg);
      EXPECT_EQ(dq(0), c.coefficient[0] * basis[0]);
      for (int j = 1; j < model.joint_count; ++j) EXPECT_EQ(dq(j), 0.0);
      EXPECT_TRUE(same_bits(fk_tool_point(model, q), fk_tool_point(rigid, q + dq)));
    }
  }
}

TEST(Compliance, TermsMustBeOfTheModelsJointsAndHarmonicsOfItsRevoluteOnes) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints";
  const RobotModel lifted = lifted_ur5e();
  ComplianceModel c;
  EXPECT_EQ(append_harmonic_terms(1, lifted, &c), Status::ok);
  EXPECT_EQ(c.term_count, 2 * kSixJoints);  // the six revolute joints, not the lift
  EXPECT_EQ(harmonic_term_count(lifted, 2), 4 * kSixJoints);
  for (int t = 0; t < c.term_count; ++t) EXPECT_NE(c.terms[t].joint, 0) << t;
  EXPECT_STREQ(compliance_term_name(c, 0), "h_j2_sin1");
  EXPECT_STREQ(compliance_term_name(c, c.term_count - 1), "h_j7_cos1");
  EXPECT_EQ(check_compliance(c, lifted), Status::ok);
  ComplianceModel bad = c;
  bad.terms[0].joint = 0;  // a harmonic of the lift's length
  EXPECT_EQ(check_compliance(bad, lifted), Status::invalid_argument);
  bad = c;
  bad.terms[0].joint = 7;  // beyond the model's joints
  EXPECT_EQ(check_compliance(bad, lifted), Status::invalid_argument);
  EXPECT_EQ(check_compliance(c, nominal_model(RobotType::ur5e)), Status::invalid_argument);  // j7 of a six-joint arm
  ComplianceModel point;
  point.term_count = 2;
  point.terms[0] = ComplianceTerm{1, 7};  // the flange frame of seven joints
  point.terms[1] = ComplianceTerm{1, 8};  // no eighth DH frame (but in a build of seven, the tool's number)
  EXPECT_EQ(check_compliance(point, lifted), kToolLoadFrame == 8 ? Status::ok : Status::invalid_argument);
  point.term_count = 1;
  EXPECT_EQ(check_compliance(point, lifted), Status::ok);
  EXPECT_STREQ(compliance_term_name(point, 0), "c_j2_o7");
}

}  // namespace
}  // namespace hivecal::compliance_test
