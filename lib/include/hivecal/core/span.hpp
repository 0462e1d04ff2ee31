// Non-owning view of a contiguous array (C++17 has no std::span). No Eigen, no heap: the wire
// code and the records use it without pulling in the linear algebra.
#pragma once

#include <cstddef>

namespace hivecal {

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

  constexpr T* data() const { return data_; }                        ///< first element
  constexpr std::size_t size() const { return size_; }               ///< element count
  constexpr bool empty() const { return size_ == 0; }                ///< no elements
  constexpr T& operator[](std::size_t i) const { return data_[i]; }  ///< unchecked access
  constexpr T* begin() const { return data_; }                       ///< range-for support
  constexpr T* end() const { return data_ + size_; }                 ///< range-for support
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

}  // namespace hivecal
