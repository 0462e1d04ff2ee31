// The fixed-capacity convergence trace (core/trace.hpp): values kept in push order up to the
// capacity, the excess counted as dropped, clear(), and use through the capacity-erased base.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/core/trace.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::trace_test {
namespace {

static_assert(!std::is_copy_constructible<Trace<4>>::value, "a trace is not copied");
static_assert(!std::is_copy_assignable<Trace<4>>::value, "a trace is not copied");
static_assert(!std::is_destructible<TraceBase>::value, "the base is only a view of a Trace<N>");
static_assert(std::is_base_of<TraceBase, Trace<4>>::value, "solvers write through TraceBase");

/// What a solver does: writes through the capacity-erased base.
void record(TraceBase* trace, const double* costs, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) trace->push(costs[i]);
}

TEST(Trace, StartsEmptyWithItsCapacity) {
  const Trace<8> trace;
  EXPECT_EQ(trace.size(), 0u);
  EXPECT_EQ(trace.capacity(), 8u);
  EXPECT_EQ(trace.dropped(), 0u);
  EXPECT_TRUE(trace.values().empty());
}

TEST(Trace, KeepsValuesInPushOrder) {
  Trace<4> trace;
  const double costs[3] = {9.0, 4.5, 1.25};
  EXPECT_NO_HEAP(record(&trace, costs, 3));
  EXPECT_EQ(trace.size(), 3u);
  EXPECT_EQ(trace.dropped(), 0u);
  const Span<const double> values = trace.values();
  ASSERT_EQ(values.size(), 3u);
  EXPECT_EQ(values[0], 9.0);
  EXPECT_EQ(values[1], 4.5);
  EXPECT_EQ(values[2], 1.25);
}

TEST(Trace, CountsButDoesNotStoreValuesPastCapacity) {
  Trace<3> trace;
  const double costs[7] = {7.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.0};
  EXPECT_NO_HEAP(record(&trace, costs, 7));
  EXPECT_EQ(trace.size(), 3u);
  EXPECT_EQ(trace.dropped(), 4u);
  const Span<const double> values = trace.values();
  ASSERT_EQ(values.size(), 3u);
  // The first iterations are kept (unlike a ring): the start of the convergence curve.
  EXPECT_EQ(values[0], 7.0);
  EXPECT_EQ(values[1], 6.0);
  EXPECT_EQ(values[2], 5.0);
}

TEST(Trace, CapacityOneKeepsTheFirstValue) {
  Trace<1> trace;
  trace.push(3.0);
  EXPECT_EQ(trace.dropped(), 0u);
  trace.push(2.0);
  trace.push(1.0);
  EXPECT_EQ(trace.size(), 1u);
  EXPECT_EQ(trace.dropped(), 2u);
  ASSERT_EQ(trace.values().size(), 1u);
  EXPECT_EQ(trace.values()[0], 3.0);
}

TEST(Trace, ClearForgetsValuesAndDropCount) {
  Trace<2> trace;
  trace.push(1.0);
  trace.push(2.0);
  trace.push(3.0);
  ASSERT_EQ(trace.dropped(), 1u);
  EXPECT_NO_HEAP(trace.clear());
  EXPECT_EQ(trace.size(), 0u);
  EXPECT_EQ(trace.dropped(), 0u);
  EXPECT_TRUE(trace.values().empty());
  EXPECT_EQ(trace.capacity(), 2u);
  trace.push(8.0);
  ASSERT_EQ(trace.values().size(), 1u);
  EXPECT_EQ(trace.values()[0], 8.0);
  EXPECT_EQ(trace.dropped(), 0u);
}

TEST(Trace, StoresSpecialCostsBitForBit) {
  Trace<3> trace;
  trace.push(-0.0);
  trace.push(std::numeric_limits<double>::infinity());
  trace.push(math::from_bits(0x7ff8000000000123ULL));  // a NaN with a payload
  ASSERT_EQ(trace.size(), 3u);
  EXPECT_EQ(math::bits_of(trace.values()[0]), 0x8000000000000000ULL);
  EXPECT_EQ(math::bits_of(trace.values()[1]), 0x7ff0000000000000ULL);
  EXPECT_EQ(math::bits_of(trace.values()[2]), 0x7ff8000000000123ULL);
}

TEST(Trace, SizeAndDropCountOverRandomLengths) {
  Random random(17);
  static Trace<16> trace;
  double costs[40];
  for (int trial = 0; trial < 200; ++trial) {
    trace.clear();
    const std::size_t count = static_cast<std::size_t>(random.below(41));
    for (std::size_t i = 0; i < count; ++i) costs[i] = random.uniform(0.0, 100.0);
    TraceBase& base = trace;
    EXPECT_NO_HEAP(record(&base, costs, count));
    const std::size_t kept = count < 16 ? count : 16;
    ASSERT_EQ(base.size(), kept) << count;
    ASSERT_EQ(base.dropped(), count - kept) << count;
    ASSERT_EQ(base.size() + base.dropped(), count);
    const Span<const double> values = base.values();
    ASSERT_EQ(values.size(), kept);
    for (std::size_t i = 0; i < kept; ++i) {
      ASSERT_EQ(values[i], costs[i]) << "trial " << trial << " i " << i;
    }
  }
}

}  // namespace
}  // namespace hivecal::trace_test
