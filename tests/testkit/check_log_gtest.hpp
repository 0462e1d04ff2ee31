// GoogleTest side of check_log.hpp: EXPECT_CHECKS(log) passes when every check in the log
// passed, and otherwise lists the failures. Host tests only.
#pragma once

#include <gtest/gtest.h>

#include "testkit/check_log.hpp"

namespace hivecal::test {

/// Success, or a failure message naming each failed check with its numbers.
inline ::testing::AssertionResult all_checks_passed(const CheckLog& log) {
  if (log.ok()) return ::testing::AssertionSuccess();
  ::testing::AssertionResult result = ::testing::AssertionFailure();
  result << log.failures() << " of " << log.checks() << " checks failed:";
  for (std::size_t i = 0; i < log.kept(); ++i) {
    const CheckFailure& failure = log.failure(i);
    result << "\n  " << failure.what << " (" << failure.value << " vs " << failure.limit << ")";
  }
  return result;
}

}  // namespace hivecal::test

/// Fails the test (and goes on) when a shared check body recorded a failure.
#define EXPECT_CHECKS(log) EXPECT_TRUE(::hivecal::test::all_checks_passed(log))
