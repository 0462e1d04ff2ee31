// Every status code has its own message.
#include <gtest/gtest.h>

#include "hivecal/core/status.hpp"

namespace hivecal::status_test {
namespace {

TEST(Status, EveryCodeHasAMessage) {
  for (int code = 0; code <= static_cast<int>(Status::read_failed); ++code) {  // the last code
    const char* message = status_message(static_cast<Status>(code));
    EXPECT_STRNE(message, "unknown status") << code;
  }
}

}  // namespace
}  // namespace hivecal::status_test
