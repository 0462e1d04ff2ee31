// Fixed-capacity convergence trace: the best cost after each iteration of a solver,
// kept for reports (the paper's convergence figures). No heap.
#pragma once

#include <cstddef>

#include "hivecal/core/types.hpp"

namespace hivecal {

/// Capacity-erased view of a trace, what solvers write into.
class TraceBase {
 public:
  TraceBase(const TraceBase&) = delete;
  TraceBase& operator=(const TraceBase&) = delete;

  /// Appends the best cost after one iteration; past capacity the value is not stored
  /// but counted (dropped() tells how many).
  void push(double best_cost) {
    if (size_ < capacity_) {
      values_[size_++] = best_cost;
    } else {
      ++dropped_;
    }
  }
  void clear() {  ///< forgets every value
    size_ = 0;
    dropped_ = 0;
  }
  std::size_t size() const { return size_; }                                        ///< values stored
  std::size_t capacity() const { return capacity_; }                                ///< values it can hold
  std::size_t dropped() const { return dropped_; }                                  ///< values pushed past capacity
  Span<const double> values() const { return Span<const double>(values_, size_); }  ///< stored values

 protected:
  TraceBase(double* values, std::size_t capacity) : values_(values), capacity_(capacity) {}
  ~TraceBase() = default;

 private:
  double* values_;
  std::size_t capacity_;
  std::size_t size_ = 0;
  std::size_t dropped_ = 0;
};

/// A trace with storage for `Capacity` iterations.
template <std::size_t Capacity>
class Trace final : public TraceBase {
 public:
  Trace() : TraceBase(values_, Capacity) {}

 private:
  double values_[Capacity] = {};
};

}  // namespace hivecal
