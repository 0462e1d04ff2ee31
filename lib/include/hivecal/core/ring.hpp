// Fixed-capacity FIFO ring over storage owned elsewhere (the owner is a class template
// with the capacity as parameter; algorithms see only this size-erased view). No heap.
#pragma once

#include <cstddef>

namespace hivecal {

/// FIFO of at most capacity() elements; push() overwrites the oldest element when full.
template <typename T>
class RingView {
 public:
  /// A ring over `capacity` elements at `storage` (capacity 0 holds nothing).
  RingView(T* storage, std::size_t capacity) : storage_(storage), capacity_(capacity) {}
  RingView(const RingView&) = delete;
  RingView& operator=(const RingView&) = delete;

  /// Appends `value`; returns true when the oldest element had to be overwritten.
  bool push(const T& value) {
    if (capacity_ == 0) return true;
    const bool evicts = size_ == capacity_;
    storage_[slot(evicts ? 0 : size_)] = value;
    if (evicts) {
      head_ = slot(1);
    } else {
      ++size_;
    }
    return evicts;
  }
  /// Removes the oldest element (no effect when empty).
  void pop_front() {
    if (size_ == 0) return;
    head_ = slot(1);
    --size_;
  }
  /// Removes every element.
  void clear() {
    head_ = 0;
    size_ = 0;
  }

  std::size_t size() const { return size_; }          ///< elements held
  std::size_t capacity() const { return capacity_; }  ///< elements it can hold
  bool empty() const { return size_ == 0; }           ///< holds nothing
  bool full() const { return size_ == capacity_; }    ///< the next push() evicts
  /// The i-th oldest element (0 = oldest); unchecked.
  const T& operator[](std::size_t i) const { return storage_[slot(i)]; }
  /// The i-th oldest element (0 = oldest); unchecked.
  T& operator[](std::size_t i) { return storage_[slot(i)]; }
  const T& front() const { return (*this)[0]; }         ///< oldest element; unchecked
  const T& back() const { return (*this)[size_ - 1]; }  ///< newest element; unchecked

 private:
  std::size_t slot(std::size_t i) const {
    const std::size_t s = head_ + i;
    return s >= capacity_ ? s - capacity_ : s;
  }

  T* storage_;
  std::size_t capacity_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace hivecal
