// Counts heap allocations made while a trap is armed (see tests/CMakeLists.txt).
#pragma once

#include <gtest/gtest.h>

#include <cstddef>

namespace hivecal::test {

/// Allocations seen since the trap was last armed.
std::size_t armed_allocation_count();
/// Starts counting (resets the count).
void arm_allocation_trap();
/// Stops counting; returns the count.
std::size_t disarm_allocation_trap();

/// Runs f() with the trap armed and returns how many allocations it made.
template <typename F>
std::size_t count_allocations(F&& f) {
  arm_allocation_trap();
  f();
  return disarm_allocation_trap();
}

}  // namespace hivecal::test

/// Runs a statement under the allocation trap and fails the test if it allocated.
#define EXPECT_NO_HEAP(statement)                                                               \
  do {                                                                                          \
    const std::size_t hivecal_allocs_ = ::hivecal::test::count_allocations([&] { statement; }); \
    EXPECT_EQ(hivecal_allocs_, 0u) << "heap allocation inside: " #statement;                    \
  } while (0)

namespace hivecal::test {

/// Runs a library call under the allocation trap (failing the test if it allocated) and
/// returns its result.
template <typename Call>
auto no_heap(Call&& call) {
  decltype(call()) result{};
  EXPECT_NO_HEAP(result = call());
  return result;
}

}  // namespace hivecal::test
