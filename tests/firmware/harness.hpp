// A tiny test harness for the firmware image (GoogleTest needs an OS and a heap). Tests register
// themselves through static objects (no heap: an intrusive list), checks count and print their
// failures over semihosting, and run_all_tests() ends with the line "N passed, M failed".
//
//   FW_TEST(Suite, Name) { FW_CHECK_EQ(f(), 3); FW_ASSERT(ok); FW_CHECK_NEAR(x, 1.0, 1e-12); }
//   FW_TEST(Suite, Shared) { FW_CHECK_LOG(test::some_shared_check_body(10)); }  // tests/testkit
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "hivecal/core/status.hpp"
#include "testkit/check_log.hpp"

namespace hivecal::fw {

/// One registered test; lives in static storage, linked in registration order.
struct TestCase {
  const char* suite;
  const char* name;
  void (*run)();
  TestCase* next;
};

/// Appends a test to the registry (called by FW_TEST's static registrar).
struct Registrar {
  explicit Registrar(TestCase* test);
};

/// Runs every registered test; prints one line per test. Returns the number of failed tests.
std::size_t run_all_tests();
/// Prints the "N passed, M failed" summary line of the last run_all_tests().
void print_summary();

// --- console ----------------------------------------------------------------------------
void print(const char* text);
void print_unsigned(std::uint64_t value);
void print_signed(std::int64_t value);
void print_hex(std::uint64_t value);
/// Approximate decimal (for diagnostics) followed by the exact bits in hex.
void print_double(double value);

/// Prints any value a check can compare.
template <typename T>
void print_value(const T& value) {
  if constexpr (std::is_same_v<T, Status>) {
    print(status_message(value));
  } else if constexpr (std::is_same_v<T, bool>) {
    print(value ? "true" : "false");
  } else if constexpr (std::is_enum_v<T>) {
    print_signed(static_cast<std::int64_t>(value));
  } else if constexpr (std::is_floating_point_v<T>) {
    print_double(static_cast<double>(value));
  } else if constexpr (std::is_integral_v<T> && std::is_signed_v<T>) {
    print_signed(static_cast<std::int64_t>(value));
  } else if constexpr (std::is_integral_v<T>) {
    print_unsigned(static_cast<std::uint64_t>(value));
  } else {
    print("<value>");
  }
}

// --- checks -----------------------------------------------------------------------------
/// Records a check result; on failure prints where and what. Returns `ok`.
bool record(bool ok, const char* expression, const char* file, int line);
/// Prints "  lhs: <a>  rhs: <b>" under a failed comparison.
template <typename A, typename B>
void print_operands(const A& a, const B& b) {
  print("    left:  ");
  print_value(a);
  print("\n    right: ");
  print_value(b);
  print("\n");
}

template <typename A, typename B, typename Compare>
bool compare(const A& a, const B& b, Compare holds, const char* expression, const char* file, int line) {
  const bool ok = holds(a, b);
  if (!record(ok, expression, file, line)) print_operands(a, b);
  return ok;
}

/// |a - b| <= tolerance (false for NaN).
bool check_near(double a, double b, double tolerance, const char* expression, const char* file, int line);

/// Counts a shared check body's checks (tests/testkit/check_log.hpp); on failure prints each
/// failed check with its numbers. Returns log.ok().
bool check_log(const test::CheckLog& log, const char* expression, const char* file, int line);

}  // namespace hivecal::fw

#define FW_TEST(suite, name)                                                                                  \
  static void fw_test_##suite##_##name();                                                                     \
  static ::hivecal::fw::TestCase fw_case_##suite##_##name{#suite, #name, &fw_test_##suite##_##name, nullptr}; \
  static const ::hivecal::fw::Registrar fw_registrar_##suite##_##name(&fw_case_##suite##_##name);             \
  static void fw_test_##suite##_##name()

#define FW_CHECK(condition) ::hivecal::fw::record(static_cast<bool>(condition), #condition, __FILE__, __LINE__)
#define FW_CHECK_OP(a, b, op)                                                                                        \
  ::hivecal::fw::compare((a), (b), [](const auto& x, const auto& y) { return x op y; }, #a " " #op " " #b, __FILE__, \
                         __LINE__)
#define FW_CHECK_EQ(a, b) FW_CHECK_OP(a, b, ==)
#define FW_CHECK_NE(a, b) FW_CHECK_OP(a, b, !=)
#define FW_CHECK_LT(a, b) FW_CHECK_OP(a, b, <)
#define FW_CHECK_LE(a, b) FW_CHECK_OP(a, b, <=)
#define FW_CHECK_GT(a, b) FW_CHECK_OP(a, b, >)
#define FW_CHECK_GE(a, b) FW_CHECK_OP(a, b, >=)
#define FW_CHECK_NEAR(a, b, tolerance) \
  ::hivecal::fw::check_near((a), (b), (tolerance), #a " ~ " #b " within " #tolerance, __FILE__, __LINE__)
#define FW_CHECK_LOG(log) ::hivecal::fw::check_log((log), #log, __FILE__, __LINE__)
/// Stops the current test when the check fails (later checks would read garbage).
#define FW_ASSERT(condition)          \
  do {                                \
    if (!FW_CHECK(condition)) return; \
  } while (0)
#define FW_ASSERT_EQ(a, b)          \
  do {                              \
    if (!FW_CHECK_EQ(a, b)) return; \
  } while (0)
