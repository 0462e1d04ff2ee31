// UR controller deltas (model/ur_deltas.hpp): known deltas move the datasheet point as the DH
// convention says, a theta delta is a joint offset, deltas round-trip through the model they
// came from, the tool and compliance are kept, and any NaN/Inf delta is refused untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::ur_deltas_test {
namespace {

/// Random deltas of the given sizes [m], [rad].
UrCalibrationDeltas random_deltas(Random* random, double length_m, double angle_rad) {
  UrCalibrationDeltas d;
  for (int j = 0; j < kSixJoints; ++j) {
    d.delta_theta_rad[j] = angle_rad * random->normal();
    d.delta_a_m[j] = length_m * random->normal();
    d.delta_d_m[j] = length_m * random->normal();
    d.delta_alpha_rad[j] = angle_rad * random->normal();
  }
  return d;
}

/// The field of `d` numbered k = 4 j + f (f: 0 theta, 1 a, 2 d, 3 alpha).
double& field(UrCalibrationDeltas* d, int k) {
  const int j = k / 4;
  switch (k % 4) {
    case 0: return d->delta_theta_rad[j];
    case 1: return d->delta_a_m[j];
    case 2: return d->delta_d_m[j];
    default: return d->delta_alpha_rad[j];
  }
}

/// Its value, read-only.
double value(const UrCalibrationDeltas& d, int k) {
  UrCalibrationDeltas copy = d;
  return field(&copy, k);
}

TEST(UrDeltas, KnownDeltasMoveTheDatasheetPoint) {
  // UR5 at zero joints: every x axis is the base x axis, the point is
  // (a2 + a3, -(d4 + d6), d1 - d5) (tests/testkit/kinematics_checks.hpp).
  const RobotModel nominal = nominal_model(RobotType::ur5);
  UrCalibrationDeltas deltas;
  deltas.delta_a_m[1] = 1e-3;    // a2 + 1 mm: x + 1 mm
  deltas.delta_d_m[0] = -2e-3;   // d1 - 2 mm: z - 2 mm
  deltas.delta_d_m[3] = 0.5e-3;  // d4 + 0.5 mm: y - 0.5 mm
  RobotModel calibrated;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = apply_ur_deltas(nominal, deltas, &calibrated));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(calibrated.joints[1].a_m, -0.425 + 1e-3);
  EXPECT_EQ(calibrated.joints[0].d_m, 0.089159 - 2e-3);
  EXPECT_EQ(calibrated.joints[3].d_m, 0.10915 + 0.5e-3);
  const Vec3 moved = fk_tool_point(calibrated, JointVector::Zero()) - fk_tool_point(nominal, JointVector::Zero());
  EXPECT_NEAR(moved.x(), 1e-3, 1e-15);
  EXPECT_NEAR(moved.y(), -0.5e-3, 1e-15);
  EXPECT_NEAR(moved.z(), -2e-3, 1e-15);
  // Every other field keeps its bits.
  const ModelParams before = to_params(nominal);
  const ModelParams after = to_params(calibrated);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (i == model_param_index(1, DhField::a) || i == model_param_index(0, DhField::d) ||
        i == model_param_index(3, DhField::d)) {
      continue;
    }
    EXPECT_EQ(after(i), before(i)) << i;
  }
}

TEST(UrDeltas, ThetaDeltasAreJointOffsets) {
  // calibrated theta = nominal + delta enters the chain as q + delta (DH convention).
  Random random(701);
  for (RobotType type : {RobotType::ur3, RobotType::ur10e, RobotType::ur16e}) {
    const RobotModel nominal = nominal_model(type);
    UrCalibrationDeltas deltas;
    JointVector offset;
    for (int j = 0; j < kSixJoints; ++j) {
      deltas.delta_theta_rad[j] = random.uniform(-0.3, 0.3);
      offset(j) = deltas.delta_theta_rad[j];
    }
    RobotModel calibrated;
    ASSERT_EQ(apply_ur_deltas(nominal, deltas, &calibrated), Status::ok);
    for (int pose = 0; pose < 20; ++pose) {
      const JointVector q = test::random_joints(&random);
      EXPECT_LT((fk_tool_point(calibrated, q) - fk_tool_point(nominal, q + offset)).norm(), 1e-14);
    }
  }
  // A quarter turn of joint 1's offset turns the whole arm about the base z axis.
  const RobotModel nominal = nominal_model(RobotType::ur5);
  UrCalibrationDeltas quarter;
  quarter.delta_theta_rad[0] = 0.5 * math::kPi;
  RobotModel turned;
  ASSERT_EQ(apply_ur_deltas(nominal, quarter, &turned), Status::ok);
  const Vec3 p = fk_tool_point(nominal, JointVector::Zero());
  const Vec3 r = fk_tool_point(turned, JointVector::Zero());
  EXPECT_NEAR(r.x(), -p.y(), 1e-15);
  EXPECT_NEAR(r.y(), p.x(), 1e-15);
  EXPECT_NEAR(r.z(), p.z(), 1e-15);
}

TEST(UrDeltas, DeltasRoundTripThroughTheModelTheyMade) {
  Random random(702);
  for (int trial = 0; trial < 100; ++trial) {
    const RobotModel nominal = nominal_model(static_cast<RobotType>(trial % 7));
    const UrCalibrationDeltas deltas = random_deltas(&random, 1e-3, 1e-3);
    RobotModel calibrated;
    ASSERT_EQ(apply_ur_deltas(nominal, deltas, &calibrated), Status::ok);
    UrCalibrationDeltas back;
    EXPECT_NO_HEAP(back = ur_deltas_between(nominal, calibrated));
    for (int k = 0; k < 4 * kSixJoints; ++k) {
      // (n + d) - n differs from d by at most half an ulp of n + d (|n| < 2 m).
      EXPECT_NEAR(value(back, k), value(deltas, k), 2.3e-16) << trial << " " << k;
    }
  }
}

TEST(UrDeltas, DeltasBetweenAreFieldDifferencesAndIgnoreTheTool) {
  const RobotModel nominal = nominal_model(RobotType::ur10);
  RobotModel calibrated = nominal;
  calibrated.joints[2].theta_offset_rad += 0.25;  // exact in binary
  calibrated.joints[4].alpha_rad -= 0.125;
  calibrated.joints[5].d_m += 0.0625;
  calibrated.joints[0].a_m = 0.5;  // nominal a1 is 0
  calibrated.tool_m << 0.1, 0.2, 0.3;
  calibrated.other_tools_m[1] << 0.0, 0.0, 0.1;
  UrCalibrationDeltas d;
  EXPECT_NO_HEAP(d = ur_deltas_between(nominal, calibrated));
  for (int k = 0; k < 4 * kSixJoints; ++k) {
    double expected = 0.0;
    if (k == 4 * 2 + 0) expected = 0.25;
    if (k == 4 * 4 + 3) expected = -0.125;
    if (k == 4 * 5 + 2) expected = 0.0625;
    if (k == 4 * 0 + 1) expected = 0.5;
    EXPECT_EQ(value(d, k), expected) << k;
  }
  // Same model: all zero.
  const UrCalibrationDeltas none = ur_deltas_between(calibrated, calibrated);
  UrCalibrationDeltas zero;
  EXPECT_EQ(std::memcmp(&none, &zero, sizeof zero), 0);
}

TEST(UrDeltas, ApplyKeepsToolOtherTargetsAndCompliance) {
  Random random(703);
  RobotModel nominal = nominal_model(RobotType::ur5e);
  nominal.tool_m << 0.01, -0.02, 0.15;
  nominal.other_tools_m[0] << 0.05, 0.0, 0.1;
  ASSERT_EQ(default_compliance_terms(nominal, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &nominal.compliance),
            Status::ok);
  nominal.compliance.coefficient[1] = 3e-4;
  RobotModel calibrated;
  ASSERT_EQ(apply_ur_deltas(nominal, random_deltas(&random, 1e-3, 1e-3), &calibrated), Status::ok);
  EXPECT_EQ(calibrated.tool_m, nominal.tool_m);
  EXPECT_EQ(calibrated.other_tools_m[0], nominal.other_tools_m[0]);
  EXPECT_EQ(calibrated.other_tools_m[1], nominal.other_tools_m[1]);
  EXPECT_EQ(std::memcmp(&calibrated.compliance, &nominal.compliance, sizeof nominal.compliance), 0);
  // Zero deltas give the nominal model, bit for bit.
  ASSERT_EQ(apply_ur_deltas(nominal, UrCalibrationDeltas{}, &calibrated), Status::ok);
  EXPECT_EQ(std::memcmp(&calibrated, &nominal, sizeof nominal), 0);
}

TEST(UrDeltas, AnyNonFiniteDeltaIsRefusedAndTheOutputLeftAlone) {
  const RobotModel nominal = nominal_model(RobotType::ur10e);
  Random random(704);
  const UrCalibrationDeltas good = random_deltas(&random, 1e-3, 1e-3);
  const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity()};
  RobotModel sentinel = nominal_model(RobotType::ur3);
  sentinel.tool_m << 7.0, 8.0, 9.0;
  for (int k = 0; k < 4 * kSixJoints; ++k) {
    for (const double bad : bad_values) {
      UrCalibrationDeltas deltas = good;
      field(&deltas, k) = bad;
      RobotModel out = sentinel;
      Status status = Status::ok;
      EXPECT_NO_HEAP(status = apply_ur_deltas(nominal, deltas, &out));
      EXPECT_EQ(status, Status::non_finite_input) << k;
      EXPECT_EQ(std::memcmp(&out, &sentinel, sizeof out), 0) << k;
    }
  }
  RobotModel out;
  EXPECT_EQ(apply_ur_deltas(nominal, good, &out), Status::ok);  // the same deltas, all finite
}

}  // namespace
}  // namespace hivecal::ur_deltas_test
