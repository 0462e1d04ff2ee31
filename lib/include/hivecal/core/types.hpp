// Fixed-size value types shared by the whole library (Eigen fixed sizes only: no heap).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <Eigen/LU>        // fixed-size determinants (closed form)
#include <cstddef>

#include "hivecal/core/joints.hpp"
#include "hivecal/core/span.hpp"

namespace hivecal {

using Vec3 = Eigen::Matrix<double, 3, 1>;                   ///< a point or direction [m] or [-]
using Mat3 = Eigen::Matrix<double, 3, 3>;                   ///< a rotation or 3x3 moment
using JointVector = Eigen::Matrix<double, kJointCount, 1>;  ///< joint positions [rad]

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
