// The non-owning array view (core/span.hpp): construction from pointers and C arrays, the
// mutable-to-const conversion, access and iteration through the view, constexpr use, and
// subspan's clamping (element by element over random offsets and counts).
#include "hivecal/core/span.hpp"  // first, alone: it must not need or bring in Eigen

#if defined(EIGEN_CORE_H) || defined(EIGEN_WORLD_VERSION)
constexpr bool kSpanHeaderPullsEigen = true;
#else
constexpr bool kSpanHeaderPullsEigen = false;
#endif

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::span_test {
namespace {

static_assert(std::is_convertible<Span<int>, Span<const int>>::value, "mutable converts to const");

constexpr int kConstants[5] = {2, 3, 5, 7, 11};
constexpr int sum_of(Span<const int> s) {
  int total = 0;
  for (int v : s) total += v;
  return total;
}
static_assert(sum_of(kConstants) == 28, "usable in constant expressions");
static_assert(Span<const int>(kConstants).subspan(1, 2)[1] == 5, "subspan in constant expressions");

TEST(Span, DefaultIsEmptyAndNull) {
  const Span<int> s;
  EXPECT_EQ(s.data(), nullptr);
  EXPECT_EQ(s.size(), 0u);
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(s.begin(), s.end());
  EXPECT_TRUE(s.subspan(0, 10).empty());
}

TEST(Span, ViewsPointerAndCountOrAWholeArray) {
  double values[4] = {1.5, 2.5, 3.5, 4.5};
  const Span<double> part(values + 1, 2);
  EXPECT_EQ(part.data(), values + 1);
  EXPECT_EQ(part.size(), 2u);
  EXPECT_FALSE(part.empty());
  EXPECT_EQ(part[0], 2.5);
  EXPECT_EQ(part[1], 3.5);
  const Span<double> whole = values;  // implicit, size deduced from the array
  EXPECT_EQ(whole.data(), values);
  EXPECT_EQ(whole.size(), 4u);
  EXPECT_EQ(whole.end(), values + 4);
  const Span<double> none(values, 0);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(none.begin(), none.end());
}

TEST(Span, WritesThroughToTheArrayAndIterates) {
  int values[5] = {};
  const Span<int> s = values;  // a const view object still gives mutable elements
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<int>(10 * i);
  EXPECT_EQ(values[0], 0);
  EXPECT_EQ(values[4], 40);
  int sum = 0;
  int count = 0;
  for (int& v : s) {
    sum += v;
    ++count;
    v = -v;
  }
  EXPECT_EQ(count, 5);
  EXPECT_EQ(sum, 100);
  EXPECT_EQ(values[3], -30);
}

TEST(Span, MutableViewConvertsToConst) {
  int values[3] = {4, 5, 6};
  const Span<int> mutable_view = values;
  Span<const int> const_view;
  EXPECT_NO_HEAP(const_view = mutable_view);
  EXPECT_EQ(const_view.data(), values);
  EXPECT_EQ(const_view.size(), 3u);
  values[1] = 50;
  EXPECT_EQ(const_view[1], 50);  // a view, not a copy
}

TEST(Span, SubspanClampsToTheView) {
  int values[6] = {0, 1, 2, 3, 4, 5};
  const Span<int> s = values;
  Span<int> sub;
  EXPECT_NO_HEAP(sub = s.subspan(2, 3));
  EXPECT_EQ(sub.data(), values + 2);
  EXPECT_EQ(sub.size(), 3u);
  EXPECT_EQ(sub[0], 2);
  EXPECT_EQ(sub[2], 4);
  // Count past the end: clamped.
  sub = s.subspan(4, 100);
  EXPECT_EQ(sub.data(), values + 4);
  EXPECT_EQ(sub.size(), 2u);
  // Largest count: no overflow of offset + count.
  sub = s.subspan(1, std::numeric_limits<std::size_t>::max());
  EXPECT_EQ(sub.data(), values + 1);
  EXPECT_EQ(sub.size(), 5u);
  // Offset at and past the end: empty, at the end.
  sub = s.subspan(6, 1);
  EXPECT_TRUE(sub.empty());
  EXPECT_EQ(sub.data(), values + 6);
  sub = s.subspan(std::numeric_limits<std::size_t>::max(), 3);
  EXPECT_TRUE(sub.empty());
  EXPECT_EQ(sub.data(), values + 6);
  // Zero count.
  sub = s.subspan(3, 0);
  EXPECT_TRUE(sub.empty());
  EXPECT_EQ(sub.data(), values + 3);
}

// Element i of the view is in subspan(offset, count) exactly when offset <= i < offset + count.
TEST(Span, SubspanHoldsExactlyTheRequestedElementsOverRandomCases) {
  Random random(3);
  int values[32];
  for (int i = 0; i < 32; ++i) values[i] = 100 + i;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t size = static_cast<std::size_t>(random.below(33));
    const Span<int> s(values, size);
    const std::size_t offset = static_cast<std::size_t>(random.below(40));
    const std::size_t count = random.below(8) == 0 ? std::numeric_limits<std::size_t>::max() - random.below(4)
                                                   : static_cast<std::size_t>(random.below(40));
    const Span<int> sub = s.subspan(offset, count);
    ASSERT_GE(sub.data(), s.begin());
    ASSERT_LE(sub.end(), s.end());
    std::size_t expected_size = 0;
    for (std::size_t i = 0; i < size; ++i) {
      const bool wanted = i >= offset && i - offset < count;
      if (wanted) {
        ASSERT_LT(i - offset, sub.size()) << "size " << size << " offset " << offset << " count " << count;
        ASSERT_EQ(sub[i - offset], values[i]);
        ++expected_size;
      }
    }
    ASSERT_EQ(sub.size(), expected_size) << "size " << size << " offset " << offset << " count " << count;
  }
}

TEST(Span, HeaderDoesNotBringInEigen) {
  EXPECT_FALSE(kSpanHeaderPullsEigen);
}

}  // namespace
}  // namespace hivecal::span_test
