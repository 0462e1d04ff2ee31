// Modified-DH descriptions mapped exactly onto the standard-DH model (model/dh_convention.hpp),
// checked against a plain 4x4 modified-DH chain written from the definition; and the
// e-Series tables.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <string>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "hivecal/model/kinematics.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::dh_convention_test {
namespace {

using Mat4 = Eigen::Matrix4d;

Mat4 rot_x(double a) {
  Mat4 m = Mat4::Identity();
  m(1, 1) = std::cos(a), m(1, 2) = -std::sin(a), m(2, 1) = std::sin(a), m(2, 2) = std::cos(a);
  return m;
}
Mat4 rot_z(double a) {
  Mat4 m = Mat4::Identity();
  m(0, 0) = std::cos(a), m(0, 1) = -std::sin(a), m(1, 0) = std::sin(a), m(1, 1) = std::cos(a);
  return m;
}
Mat4 trans(double x, double y, double z) {
  Mat4 m = Mat4::Identity();
  m(0, 3) = x, m(1, 3) = y, m(2, 3) = z;
  return m;
}

/// The modified-DH tool point from its definition, in libm double precision [m].
Vec3 reference_modified_fk(const ModifiedDhRow (&rows)[kSixJoints], const Vec3& tool_m, const JointVector& q) {
  Mat4 t = Mat4::Identity();
  for (int j = 0; j < kSixJoints; ++j) {
    t = t * rot_x(rows[j].alpha_prev_rad) * trans(rows[j].a_prev_m, 0, 0) * rot_z(q(j) + rows[j].theta_offset_rad) *
        trans(0, 0, rows[j].d_m);
  }
  return (t * Eigen::Vector4d(tool_m.x(), tool_m.y(), tool_m.z(), 1.0)).head<3>();
}

void random_rows(Random* r, ModifiedDhRow (&rows)[kSixJoints]) {
  for (ModifiedDhRow& row : rows)
    row = ModifiedDhRow{r->uniform(-3.1, 3.1), r->uniform(-0.5, 0.5), r->uniform(-3.1, 3.1), r->uniform(-0.5, 0.5)};
}

JointVector random_joints(Random* r) {
  JointVector q;
  for (int j = 0; j < kSixJoints; ++j) q(j) = r->uniform(-3.1, 3.1);
  return q;
}

TEST(DhConvention, ModifiedArmsHaveTheirToolPointsInTheStandardModel) {
  Random random(41);
  for (int arm = 0; arm < 200; ++arm) {
    ModifiedDhRow rows[kSixJoints];
    random_rows(&random, rows);
    const Vec3 tool(random.uniform(-0.1, 0.1), random.uniform(-0.1, 0.1), random.uniform(0.0, 0.2));
    RobotModel model;
    ModifiedDhBase base;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = model_from_modified_dh(rows, tool, &model, &base));
    ASSERT_EQ(status, Status::ok);
    for (int pose = 0; pose < 10; ++pose) {
      const JointVector q = random_joints(&random);
      const Vec3 expected = reference_modified_fk(rows, tool, q);
      const Vec3 got = base.transform().apply(fk_tool_point(model, q));
      ASSERT_LT((got - expected).norm(), 1e-12) << "arm " << arm << " pose " << pose;
    }
  }
}

TEST(DhConvention, RowsComeBackAsTheyWereAndCalibratedWristLinksFoldIntoTheTool) {
  Random random(42);
  for (int arm = 0; arm < 100; ++arm) {
    ModifiedDhRow rows[kSixJoints];
    random_rows(&random, rows);
    const Vec3 tool(0.01, -0.02, 0.12);
    RobotModel model;
    ModifiedDhBase base;
    ASSERT_EQ(model_from_modified_dh(rows, tool, &model, &base), Status::ok);
    ModifiedDhRow back[kSixJoints];
    Vec3 back_tool;
    EXPECT_NO_HEAP(modified_dh_from_model(model, base, back, &back_tool));
    EXPECT_EQ(std::memcmp(back, rows, sizeof rows), 0) << "arm " << arm;
    EXPECT_EQ(back_tool, tool);
    // A calibration moves joint 6's a and alpha, which modified DH has no row for.
    model.joints[5].a_m = 0.003;
    model.joints[5].alpha_rad = 0.002;
    modified_dh_from_model(model, base, back, &back_tool);
    RobotModel again;
    ModifiedDhBase again_base;
    ASSERT_EQ(model_from_modified_dh(back, back_tool, &again, &again_base), Status::ok);
    for (int pose = 0; pose < 10; ++pose) {
      const JointVector q = random_joints(&random);
      EXPECT_LT(
          (again_base.transform().apply(fk_tool_point(again, q)) - base.transform().apply(fk_tool_point(model, q)))
              .norm(),
          1e-12);
    }
  }
}

/// The modified-DH tool point of `count` rows from the definition, q adding to d on the joints
/// whose bit of `prismatic` is set [m].
Vec3 reference_modified_fk(const ModifiedDhRow* rows, int count, std::uint32_t prismatic, const Vec3& tool_m,
                           const JointVector& q) {
  Mat4 t = Mat4::Identity();
  for (int j = 0; j < count; ++j) {
    const bool slides = (prismatic >> j & 1U) != 0;
    t = t * rot_x(rows[j].alpha_prev_rad) * trans(rows[j].a_prev_m, 0, 0) *
        rot_z(rows[j].theta_offset_rad + (slides ? 0.0 : q(j))) * trans(0, 0, rows[j].d_m + (slides ? q(j) : 0.0));
  }
  return (t * Eigen::Vector4d(tool_m.x(), tool_m.y(), tool_m.z(), 1.0)).head<3>();
}

TEST(DhConvention, AnyJointCountAndPrismaticJointsConvertExactly) {
  Random random(43);
  for (int arm = 0; arm < 200; ++arm) {
    const int count = 1 + static_cast<int>(random.below(static_cast<std::uint64_t>(kMaxJoints)));
    const auto prismatic = static_cast<std::uint32_t>(random.below(std::uint64_t{1} << count));
    ModifiedDhRow rows[kMaxJoints];
    for (int j = 0; j < count; ++j) {
      rows[j] = ModifiedDhRow{random.uniform(-3.1, 3.1), random.uniform(-0.5, 0.5), random.uniform(-3.1, 3.1),
                              random.uniform(-0.5, 0.5)};
    }
    const Vec3 tool(0.01, -0.02, 0.12);
    RobotModel model;
    ModifiedDhBase base;
    Status status = Status::invalid_argument;
    const Span<const ModifiedDhRow> given(rows, static_cast<std::size_t>(count));
    EXPECT_NO_HEAP(status = model_from_modified_dh(given, tool, &model, &base, prismatic));
    ASSERT_EQ(status, Status::ok);
    EXPECT_EQ(model.joint_count, count);
    EXPECT_EQ(model.prismatic_joints, prismatic);
    EXPECT_EQ(check_joint_layout(model), Status::ok);
    for (int pose = 0; pose < 5; ++pose) {
      JointVector q;
      for (int j = 0; j < count; ++j) q(j) = random.uniform(-3.1, 3.1);
      const Vec3 expected = reference_modified_fk(rows, count, prismatic, tool, q);
      EXPECT_LT((base.transform().apply(fk_tool_point(model, q)) - expected).norm(), 1e-12) << count;
    }
    ModifiedDhRow back[kMaxJoints];
    Vec3 back_tool;
    EXPECT_EQ(modified_dh_from_model(model, base, Span<ModifiedDhRow>(back), &back_tool), count);
    EXPECT_EQ(std::memcmp(back, rows, sizeof(ModifiedDhRow) * static_cast<std::size_t>(count)), 0) << "arm " << arm;
    EXPECT_EQ(back_tool, tool);
    EXPECT_EQ(
        modified_dh_from_model(model, base, Span<ModifiedDhRow>(back, static_cast<std::size_t>(count - 1)), &back_tool),
        0);  // no room for the rows: nothing written
  }
  ModifiedDhRow rows[kMaxJoints + 1];
  RobotModel model;
  ModifiedDhBase base;
  EXPECT_EQ(model_from_modified_dh(Span<const ModifiedDhRow>(), Vec3::Zero(), &model, &base), Status::invalid_argument);
  EXPECT_EQ(model_from_modified_dh(rows, Vec3::Zero(), &model, &base), Status::invalid_argument);  // one too many
  EXPECT_EQ(model_from_modified_dh(Span<const ModifiedDhRow>(rows, 2), Vec3::Zero(), &model, &base, 0b100),
            Status::invalid_argument);  // a third joint's type for two rows
}

TEST(DhConvention, RefusesNonFiniteRows) {
  ModifiedDhRow rows[kSixJoints];
  rows[3].d_m = std::nan("");
  RobotModel model;
  ModifiedDhBase base;
  EXPECT_EQ(model_from_modified_dh(rows, Vec3::Zero(), &model, &base), Status::non_finite_input);
  rows[3].d_m = 0.0;
  EXPECT_EQ(model_from_modified_dh(rows, Vec3(0, std::nan(""), 0), &model, &base), Status::non_finite_input);
  EXPECT_EQ(model_from_modified_dh(rows, Vec3::Zero(), &model, &base), Status::ok);
}

TEST(RobotTables, EverySeriesByNameWithUniversalRobotsLengths) {
  struct Case {
    const char* name;
    double d1_m, a2_m, a3_m, d4_m, d5_m, d6_m;
  };
  const Case cases[] = {
      {"ur3", 0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819},
      {"ur5", 0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823},
      {"ur10", 0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922},
      {"ur3e", 0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921},
      {"ur5e", 0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996},
      {"ur10e", 0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655},
      {"ur16e", 0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655},
  };
  for (const Case& c : cases) {
    RobotType type = RobotType::ur5;
    ASSERT_EQ(robot_type_from_name(c.name, &type), Status::ok) << c.name;
    EXPECT_STREQ(robot_type_name(type), c.name);
    EXPECT_NE(std::strstr(robot_type_names(), c.name), nullptr) << c.name;
    const RobotModel m = nominal_model(type);
    EXPECT_EQ(m.joints[0].d_m, c.d1_m) << c.name;
    EXPECT_EQ(m.joints[1].a_m, c.a2_m) << c.name;
    EXPECT_EQ(m.joints[2].a_m, c.a3_m) << c.name;
    EXPECT_EQ(m.joints[3].d_m, c.d4_m) << c.name;
    EXPECT_EQ(m.joints[4].d_m, c.d5_m) << c.name;
    EXPECT_EQ(m.joints[5].d_m, c.d6_m) << c.name;
  }
  RobotType type = RobotType::ur5;
  EXPECT_EQ(robot_type_from_name("ur20", &type), Status::invalid_argument);
}

TEST(RobotTables, EachBuiltinTypeInItsMakersConvention) {
  for (const RobotType type : builtin_robot_types()) {
    ModifiedDhBase base{1.0, 1.0};
    DhConvention convention = DhConvention::standard;
    EXPECT_NO_HEAP(convention = nominal_convention(type, &base));
    const std::string name = robot_type_name(type);
    const bool franka = name == "panda" || name == "fr3";
    EXPECT_EQ(convention, franka || name == "gen3" ? DhConvention::modified : DhConvention::standard) << name;
    EXPECT_EQ(base.a0_m, 0.0) << name;
    EXPECT_EQ(base.alpha0_rad, name == "gen3" ? math::kPi : 0.0) << name;  // Kinova's base to frame 0
  }
}

#if HIVECAL_MAX_JOINTS >= 7
TEST(RobotTables, FrankasRowsComeBackAsFrankaPublishesThem) {
  // frankaemika.github.io/docs/control_parameters.html: (a, d, alpha) of joints 1 .. 7, the
  // flange's d 0.107 on joint 7's row (Tz after Rz(q7) Tz(0): the same frame).
  const double h = math::kHalfPi;
  const ModifiedDhRow published[7] = {{0.0, 0.0, 0.0, 0.333}, {-h, 0.0, 0.0, 0.0},       {h, 0.0, 0.0, 0.316},
                                      {h, 0.0825, 0.0, 0.0},  {-h, -0.0825, 0.0, 0.384}, {h, 0.0, 0.0, 0.0},
                                      {h, 0.088, 0.0, 0.107}};
  for (const RobotType type : {RobotType::panda, RobotType::fr3}) {
    ModifiedDhBase base;
    ASSERT_EQ(nominal_convention(type, &base), DhConvention::modified);
    ModifiedDhRow rows[kMaxJoints];
    Vec3 tool_m = Vec3::Ones();
    ASSERT_EQ(modified_dh_from_model(nominal_model(type), base, rows, &tool_m), 7);
    for (int j = 0; j < 7; ++j) {
      EXPECT_EQ(std::memcmp(&rows[j], &published[j], sizeof published[j]), 0) << "row " << j + 1;
    }
    EXPECT_EQ(tool_m, Vec3::Zero());
  }
}
#endif

}  // namespace
}  // namespace hivecal::dh_convention_test
