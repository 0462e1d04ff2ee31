// The shared value types (core/types.hpp): the right-handed elementary rotations against hand
// values and libm, RigidTransform's apply/then_after/inverse against each other on random
// motions and a hand-computed case, and all_finite on every coefficient position.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/core/types.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::types_test {
namespace {

/// Largest absolute coefficient difference.
template <typename A, typename B>
double max_diff(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

/// A random proper rigid motion: Z-Y-X angles in (-pi, pi), translation within 2 m.
RigidTransform random_motion(Random* random) {
  RigidTransform t;
  t.rotation = rotation_z(random->uniform(-math::kPi, math::kPi)) * rotation_y(random->uniform(-math::kPi, math::kPi)) *
               rotation_x(random->uniform(-math::kPi, math::kPi));
  t.translation_m = Vec3(random->uniform(-2.0, 2.0), random->uniform(-2.0, 2.0), random->uniform(-2.0, 2.0));
  return t;
}

Vec3 random_point(Random* random) {
  return Vec3(random->uniform(-3.0, 3.0), random->uniform(-3.0, 3.0), random->uniform(-3.0, 3.0));
}

TEST(Types, JointVectorHasRoomForEveryJointTheBuildHolds) {
  EXPECT_EQ(JointVector::RowsAtCompileTime, kMaxJoints);
  EXPECT_EQ(Vec3::RowsAtCompileTime, 3);
  EXPECT_EQ(Mat3::RowsAtCompileTime, 3);
  EXPECT_EQ(Mat3::ColsAtCompileTime, 3);
}

TEST(Types, RotationsAtZeroAreExactlyTheIdentity) {
  Mat3 rx;
  Mat3 ry;
  Mat3 rz;
  EXPECT_NO_HEAP(rx = rotation_x(0.0));
  EXPECT_NO_HEAP(ry = rotation_y(0.0));
  EXPECT_NO_HEAP(rz = rotation_z(0.0));
  EXPECT_EQ(rx, Mat3::Identity());
  EXPECT_EQ(ry, Mat3::Identity());
  EXPECT_EQ(rz, Mat3::Identity());
}

// Right-handed: a quarter turn about x takes y to z, about y takes z to x, about z takes x to y.
TEST(Types, QuarterTurnsAreRightHanded) {
  const Vec3 ex = Vec3::UnitX();
  const Vec3 ey = Vec3::UnitY();
  const Vec3 ez = Vec3::UnitZ();
  const double q = math::kHalfPi;
  EXPECT_LT(max_diff(rotation_x(q) * ey, ez), 1e-15);
  EXPECT_LT(max_diff(rotation_x(q) * ez, -ey), 1e-15);
  EXPECT_LT(max_diff(rotation_y(q) * ez, ex), 1e-15);
  EXPECT_LT(max_diff(rotation_y(q) * ex, -ez), 1e-15);
  EXPECT_LT(max_diff(rotation_z(q) * ex, ey), 1e-15);
  EXPECT_LT(max_diff(rotation_z(q) * ey, -ex), 1e-15);
  // Each leaves its own axis exactly where it was.
  EXPECT_EQ(rotation_x(q) * ex, ex);
  EXPECT_EQ(rotation_y(q) * ey, ey);
  EXPECT_EQ(rotation_z(q) * ez, ez);
}

TEST(Types, ThirtyDegreeRotationsHaveTheHandComputedEntries) {
  const double h = std::sqrt(3.0) / 2.0;  // cos 30 deg
  Mat3 expected;
  expected << h, -0.5, 0.0,  //
      0.5, h, 0.0,           //
      0.0, 0.0, 1.0;
  EXPECT_LT(max_diff(rotation_z(math::kPi / 6.0), expected), 2e-16);
  Mat3 expected_x;
  expected_x << 1.0, 0.0, 0.0,  //
      0.0, h, -0.5,             //
      0.0, 0.5, h;
  EXPECT_LT(max_diff(rotation_x(math::kPi / 6.0), expected_x), 2e-16);
  Mat3 expected_y;
  expected_y << h, 0.0, 0.5,  //
      0.0, 1.0, 0.0,          //
      -0.5, 0.0, h;
  EXPECT_LT(max_diff(rotation_y(math::kPi / 6.0), expected_y), 2e-16);
}

TEST(Types, RotationsMatchLibmAndAreProperOverRandomAngles) {
  Random random(31);
  for (int i = 0; i < 500; ++i) {
    const double a = random.uniform(-4.0 * math::kPi, 4.0 * math::kPi);
    const double s = std::sin(a);
    const double c = std::cos(a);
    Mat3 rx;
    Mat3 ry;
    Mat3 rz;
    EXPECT_NO_HEAP(rx = rotation_x(a));
    EXPECT_NO_HEAP(ry = rotation_y(a));
    EXPECT_NO_HEAP(rz = rotation_z(a));
    Mat3 lx;
    lx << 1, 0, 0, 0, c, -s, 0, s, c;
    Mat3 ly;
    ly << c, 0, s, 0, 1, 0, -s, 0, c;
    Mat3 lz;
    lz << c, -s, 0, s, c, 0, 0, 0, 1;
    ASSERT_LT(max_diff(rx, lx), 4e-16) << a;
    ASSERT_LT(max_diff(ry, ly), 4e-16) << a;
    ASSERT_LT(max_diff(rz, lz), 4e-16) << a;
    for (const Mat3* r : {&rx, &ry, &rz}) {
      ASSERT_LT(max_diff(*r * r->transpose(), Mat3::Identity()), 1e-15) << a;
      ASSERT_NEAR(r->determinant(), 1.0, 1e-15) << a;
    }
    // Angles add about a fixed axis.
    const double b = random.uniform(-math::kPi, math::kPi);
    ASSERT_LT(max_diff(rotation_z(a) * rotation_z(b), rotation_z(a + b)), 1e-14) << a << " " << b;
    ASSERT_LT(max_diff(rotation_x(-a), rx.transpose()), 1e-15) << a;
  }
}

TEST(Types, DefaultTransformIsTheIdentity) {
  const RigidTransform identity;
  EXPECT_EQ(identity.rotation, Mat3::Identity());
  EXPECT_EQ(identity.translation_m, Vec3::Zero());
  const Vec3 p(1.25, -2.5, 3.75);
  EXPECT_EQ(identity.apply(p), p);
}

TEST(Types, TransformHandComputedCase) {
  // a: quarter turn about z, then move +1 m along x.  b: move +2 m along y.
  const RigidTransform a{rotation_z(math::kHalfPi), Vec3(1.0, 0.0, 0.0)};
  const RigidTransform b{Mat3::Identity(), Vec3(0.0, 2.0, 0.0)};
  Vec3 p;
  EXPECT_NO_HEAP(p = a.apply(Vec3(1.0, 0.0, 0.0)));
  EXPECT_LT(max_diff(p, Vec3(1.0, 1.0, 0.0)), 1e-15);
  // a after b: (0, 0, 0) -> (0, 2, 0) -> (-2, 0, 0) + (1, 0, 0).
  RigidTransform ab;
  EXPECT_NO_HEAP(ab = a.then_after(b));
  EXPECT_LT(max_diff(ab.apply(Vec3::Zero()), Vec3(-1.0, 0.0, 0.0)), 1e-15);
  // b after a differs: (0, 0, 0) -> (1, 0, 0) -> (1, 2, 0).
  EXPECT_LT(max_diff(b.then_after(a).apply(Vec3::Zero()), Vec3(1.0, 2.0, 0.0)), 1e-15);
  // The inverse of a takes (1, 0, 0) back to the origin and (1, 1, 0) to (1, 0, 0).
  RigidTransform inv;
  EXPECT_NO_HEAP(inv = a.inverse());
  EXPECT_LT(max_diff(inv.apply(Vec3(1.0, 0.0, 0.0)), Vec3::Zero()), 1e-15);
  EXPECT_LT(max_diff(inv.apply(Vec3(1.0, 1.0, 0.0)), Vec3(1.0, 0.0, 0.0)), 1e-15);
  EXPECT_LT(max_diff(inv.translation_m, Vec3(0.0, 1.0, 0.0)), 1e-15);
}

TEST(Types, ComposeAndInvertAgreeOnRandomMotions) {
  Random random(47);
  for (int i = 0; i < 300; ++i) {
    const RigidTransform a = random_motion(&random);
    const RigidTransform b = random_motion(&random);
    const RigidTransform c = random_motion(&random);
    const Vec3 p = random_point(&random);
    // then_after applies the argument first.
    ASSERT_LT(max_diff(a.then_after(b).apply(p), a.apply(b.apply(p))), 1e-14) << i;
    // Associative.
    const RigidTransform left = a.then_after(b).then_after(c);
    const RigidTransform right = a.then_after(b.then_after(c));
    ASSERT_LT(max_diff(left.rotation, right.rotation), 1e-14) << i;
    ASSERT_LT(max_diff(left.translation_m, right.translation_m), 1e-14) << i;
    // The inverse undoes the motion, on either side.
    const RigidTransform inv = a.inverse();
    ASSERT_LT(max_diff(inv.apply(a.apply(p)), p), 1e-14) << i;
    ASSERT_LT(max_diff(a.apply(inv.apply(p)), p), 1e-14) << i;
    const RigidTransform none = a.then_after(inv);
    ASSERT_LT(max_diff(none.rotation, Mat3::Identity()), 1e-15) << i;
    ASSERT_LT(max_diff(none.translation_m, Vec3::Zero()), 1e-14) << i;
    // Rigid: distances are kept.
    const Vec3 q = random_point(&random);
    ASSERT_NEAR((a.apply(p) - a.apply(q)).norm(), (p - q).norm(), 1e-14) << i;
    // (a b)^-1 = b^-1 a^-1.
    const RigidTransform inv_ab = a.then_after(b).inverse();
    const RigidTransform inv_b_inv_a = b.inverse().then_after(inv);
    ASSERT_LT(max_diff(inv_ab.rotation, inv_b_inv_a.rotation), 1e-14) << i;
    ASSERT_LT(max_diff(inv_ab.translation_m, inv_b_inv_a.translation_m), 1e-14) << i;
  }
}

TEST(Types, AllFiniteChecksEveryCoefficient) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  Mat3 m;
  m << 1.0, -0.0, std::numeric_limits<double>::max(),                                          //
      -std::numeric_limits<double>::max(), std::numeric_limits<double>::denorm_min(), 1e-300,  //
      3.0, 4.0, 5.0;
  bool finite = false;
  EXPECT_NO_HEAP(finite = all_finite(m));
  EXPECT_TRUE(finite);
  for (Eigen::Index r = 0; r < 3; ++r) {
    for (Eigen::Index c = 0; c < 3; ++c) {
      for (double bad : {nan, inf, -inf, -nan}) {
        Mat3 broken = m;
        broken(r, c) = bad;
        EXPECT_FALSE(all_finite(broken)) << r << "," << c << " " << bad;
      }
    }
  }
  JointVector q = JointVector::Zero();
  EXPECT_TRUE(all_finite(q));
  q(kSixJoints - 1) = nan;
  EXPECT_FALSE(all_finite(q));
  // Expressions and blocks: the NaN outside the block is not seen.
  Mat3 with_nan = Mat3::Identity();
  with_nan(2, 2) = nan;
  EXPECT_TRUE(all_finite(with_nan.topLeftCorner<2, 2>()));
  EXPECT_FALSE(all_finite(with_nan.col(2)));
  EXPECT_FALSE(all_finite(2.0 * with_nan));
  // Overflow in an expression is caught.
  EXPECT_FALSE(all_finite(Vec3(1e308, 0.0, 0.0) * 10.0));
}

}  // namespace
}  // namespace hivecal::types_test
