// Results of a check body shared by the host tests (GoogleTest) and the firmware image
// (tests/firmware/harness.hpp): the body records every check here, each harness asserts that
// the log holds no failure and prints the ones it does. No gtest, no iostream, no heap.
#pragma once

#include <cstddef>
#include <cstring>
#include <limits>

#include "hivecal/core/status.hpp"

namespace hivecal::test {

/// One failed check: what was checked and the two numbers compared (NaN where none).
struct CheckFailure {
  const char* what = "";
  double value = 0.0;
  double limit = 0.0;
};

/// Every check a shared body made: how many, and the first failures in order.
class CheckLog {
 public:
  /// Failures kept for the report; later ones are only counted.
  static constexpr std::size_t kMaxKept = 8;

  /// Records one check; returns `ok` (a body stops early on a failed precondition).
  bool check(bool ok, const char* what, double value = kNone, double limit = kNone) {
    ++checks_;
    if (ok) return true;
    if (failures_ < kMaxKept) kept_[failures_] = CheckFailure{what, value, limit};
    ++failures_;
    return false;
  }
  bool less(double value, double limit, const char* what) { return check(value < limit, what, value, limit); }
  bool less_equal(double value, double limit, const char* what) { return check(value <= limit, what, value, limit); }
  bool greater(double value, double limit, const char* what) { return check(value > limit, what, value, limit); }
  /// |value - expected| <= tolerance; false for NaN.
  bool near(double value, double expected, double tolerance, const char* what) {
    const double distance = value > expected ? value - expected : expected - value;
    return check(distance <= tolerance, what, value, expected);
  }
  /// Exact equality of two numbers (bits need not match for +0/-0).
  bool equal(double value, double expected, const char* what) {
    return check(value == expected, what, value, expected);
  }
  /// The status a call returned against the one it should have.
  bool status(Status actual, Status expected, const char* what) {
    return check(actual == expected, what, static_cast<double>(actual), static_cast<double>(expected));
  }
  /// Equal C strings (both non-null).
  bool same_text(const char* actual, const char* expected, const char* what) {
    return check(actual != nullptr && expected != nullptr && std::strcmp(actual, expected) == 0, what);
  }

  bool ok() const { return failures_ == 0; }          ///< no check failed
  std::size_t checks() const { return checks_; }      ///< checks made
  std::size_t failures() const { return failures_; }  ///< checks failed
  /// Failures kept (the first kMaxKept).
  std::size_t kept() const { return failures_ < kMaxKept ? failures_ : kMaxKept; }
  const CheckFailure& failure(std::size_t i) const { return kept_[i]; }  ///< i < kept()

  /// The value shown for a check that compares no numbers.
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

 private:
  std::size_t checks_ = 0;
  std::size_t failures_ = 0;
  CheckFailure kept_[kMaxKept];
};

}  // namespace hivecal::test
