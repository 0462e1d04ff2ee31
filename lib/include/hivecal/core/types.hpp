// Fixed-size value types shared by the whole library (Eigen fixed sizes only: no heap).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <Eigen/LU>        // fixed-size determinants (closed form)
#include <cstddef>

#include "hivecal/core/joints.hpp"
#include "hivecal/core/span.hpp"

namespace hivecal {

using Vec3 = Eigen::Matrix<double, 3, 1>;  ///< a point or direction [m] or [-]
using Mat3 = Eigen::Matrix<double, 3, 3>;  ///< a rotation or 3x3 moment

/// Joint positions of one pose: entry j is joint j + 1's reading, [rad] for a revolute joint,
/// [m] for a prismatic one. Room for kMaxJoints; a model of fewer joints reads the first
/// RobotModel::joint_count and the rest stay 0 (a default-built vector is all zeros), so that
/// whole vectors compare, copy and check as the model's joints do.
class JointVector : public Eigen::Matrix<double, kMaxJoints, 1> {
 public:
  using Base = Eigen::Matrix<double, kMaxJoints, 1>;  ///< the storage

  JointVector() : Base(Base::Zero()) {}
  // Implicit on purpose: Eigen expressions of joint vectors convert as they do between matrices.
  template <typename OtherDerived>
  JointVector(const Eigen::MatrixBase<OtherDerived>& other) : Base(other) {}  // NOLINT(google-explicit-constructor)
  template <typename OtherDerived>
  JointVector& operator=(const Eigen::MatrixBase<OtherDerived>& other) {
    Base::operator=(other);
    return *this;
  }

  /// The readings of `q << q1, q2, ...`: joints 1, 2, ... in order (evaluated in that order), at
  /// most kMaxJoints; the joints after the last one given are 0.
  class Readings {
   public:
    Readings(JointVector* vector, double first) : vector_(vector) {
      vector_->setZero();
      (*vector_)(0) = first;
    }
    /// The next joint's reading.
    Readings& operator,(double value) {
      eigen_assert(next_ < kMaxJoints && "no more readings than the build's joints");
      if (next_ < kMaxJoints) (*vector_)(next_++) = value;
      return *this;
    }
    /// The vector filled.
    JointVector& finished() { return *vector_; }

   private:
    JointVector* vector_;
    int next_ = 1;
  };
  /// Starts `q << q1, q2, ...` (Readings).
  Readings operator<<(double first) { return Readings(this, first); }
};

/// The joint vector of the readings q[0 .. count - 1] (count <= kMaxJoints), zeros after them.
template <std::size_t kCount>
JointVector joint_vector(const double (&q)[kCount]) {
  static_assert(kCount <= static_cast<std::size_t>(kMaxJoints), "no more readings than the build's joints");
  JointVector v;
  for (std::size_t j = 0; j < kCount; ++j) v(static_cast<Eigen::Index>(j)) = q[j];
  return v;
}

/// Proper rigid motion y = rotation * x + translation_m.
struct RigidTransform {
  Mat3 rotation = Mat3::Identity();   ///< orthonormal, det = +1
  Vec3 translation_m = Vec3::Zero();  ///< [m]

  /// Applies the transform to a point [m].
  Vec3 apply(const Vec3& point_m) const { return rotation * point_m + translation_m; }
  /// The composition this * other (apply other first).
  RigidTransform then_after(const RigidTransform& other) const {
    return RigidTransform{rotation * other.rotation, rotation * other.translation_m + translation_m};
  }
  /// The inverse motion.
  RigidTransform inverse() const {
    const Mat3 rt = rotation.transpose();
    return RigidTransform{rt, -(rt * translation_m)};
  }
};

/// Rotation about the x axis by `angle_rad` [rad] (the library's own sincos).
Mat3 rotation_x(double angle_rad);
/// Rotation about the y axis by `angle_rad` [rad] (the library's own sincos).
Mat3 rotation_y(double angle_rad);
/// Rotation about the z axis by `angle_rad` [rad] (the library's own sincos).
Mat3 rotation_z(double angle_rad);

/// True when every coefficient of an Eigen object is finite.
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m);

}  // namespace hivecal

#include "hivecal/core/math.hpp"

template <typename Derived>
bool hivecal::all_finite(const Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      if (!math::is_finite(m(r, c))) return false;
  return true;
}
