// Fixed-size value types shared by the whole library (Eigen fixed sizes only: no heap).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <Eigen/LU>        // fixed-size determinants (closed form)
#include <cstddef>

namespace hivecal {

/// Number of joints of the kinematic chains the library models (UR arms).
inline constexpr int kJointCount = 6;

using Vec3 = Eigen::Matrix<double, 3, 1>;               ///< a point or direction [m] or [-]
using Mat3 = Eigen::Matrix<double, 3, 3>;               ///< a rotation or 3x3 moment
using JointVector = Eigen::Matrix<double, kJointCount, 1>;  ///< joint positions [rad]

/// Proper rigid motion y = rotation * x + translation_m.
struct RigidTransform {
  Mat3 rotation = Mat3::Identity();         ///< orthonormal, det = +1
  Vec3 translation_m = Vec3::Zero();        ///< [m]

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

/// Non-owning view of a contiguous array (C++17 has no std::span).
template <typename T>
class Span {
 public:
  constexpr Span() = default;
  /// View of `count` elements starting at `data`.
  constexpr Span(T* data, std::size_t count) : data_(data), size_(count) {}
  /// View of a whole C array.
  template <std::size_t N>
  constexpr Span(T (&array)[N]) : data_(array), size_(N) {}  // NOLINT: implicit by design
  /// A mutable view converts to a const one.
  template <typename U>
  constexpr Span(const Span<U>& other) : data_(other.data()), size_(other.size()) {}  // NOLINT

  constexpr T* data() const { return data_; }                 ///< first element
  constexpr std::size_t size() const { return size_; }        ///< element count
  constexpr bool empty() const { return size_ == 0; }         ///< no elements
  constexpr T& operator[](std::size_t i) const { return data_[i]; }  ///< unchecked access
  constexpr T* begin() const { return data_; }                ///< range-for support
  constexpr T* end() const { return data_ + size_; }          ///< range-for support
  /// Elements [offset, offset + count), clamped to the view.
  constexpr Span subspan(std::size_t offset, std::size_t count) const {
    if (offset > size_) offset = size_;
    if (count > size_ - offset) count = size_ - offset;
    return Span(data_ + offset, count);
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

/// True when every coefficient of an Eigen object is finite.
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m);

}  // namespace hivecal

#include "hivecal/math.hpp"

template <typename Derived>
bool hivecal::all_finite(const Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      if (!math::is_finite(m(r, c))) return false;
  return true;
}
