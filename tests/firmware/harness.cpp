#include "harness.hpp"

#include <cstring>

#include "baremetal/board.h"

namespace hivecal::fw {
namespace {

TestCase* g_first = nullptr;
TestCase* g_last = nullptr;
std::size_t g_checks_failed_in_test = 0;
std::size_t g_checks_total = 0;
std::size_t g_tests_passed = 0;
std::size_t g_tests_failed = 0;

/// Writes the digits of `value` in `base` (2..16) at the end of `buffer`; returns the first.
char* format_unsigned(std::uint64_t value, unsigned base, std::size_t min_digits, char* buffer_end) {
  char* p = buffer_end;
  *--p = '\0';
  std::size_t digits = 0;
  do {
    const auto digit = static_cast<unsigned>(value % base);
    *--p = static_cast<char>(digit < 10 ? '0' + digit : 'a' + (digit - 10));
    value /= base;
    ++digits;
  } while (value != 0 || digits < min_digits);
  return p;
}

/// The "FAILED file:line: expression" line of a failed check.
void print_failure_at(const char* expression, const char* file, int line) {
  print("  FAILED ");
  print(file);
  print(":");
  print_signed(line);
  print(": ");
  print(expression);
  print("\n");
}

}  // namespace

Registrar::Registrar(TestCase* test) {
  test->next = nullptr;
  if (g_last == nullptr) {
    g_first = test;
  } else {
    g_last->next = test;
  }
  g_last = test;
}

void print(const char* text) {
  board_write(text);
}

void print_unsigned(std::uint64_t value) {
  char buffer[24];
  print(format_unsigned(value, 10, 1, buffer + sizeof buffer));
}

void print_signed(std::int64_t value) {
  if (value < 0) {
    print("-");
    print_unsigned(0ULL - static_cast<std::uint64_t>(value));
  } else {
    print_unsigned(static_cast<std::uint64_t>(value));
  }
}

void print_hex(std::uint64_t value) {
  char buffer[20];
  print("0x");
  print(format_unsigned(value, 16, 16, buffer + sizeof buffer));
}

void print_double(double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  if (value != value || value - value != 0.0) {  // NaN or Inf: the bits say which
    print(value != value ? "nan" : (value > 0.0 ? "inf" : "-inf"));
  } else {
    // Scientific notation with 9 digits, for reading only: the bits below are exact.
    if (value < 0.0) print("-");
    double magnitude = value < 0.0 ? -value : value;
    int exponent = 0;
    while (magnitude >= 10.0) {
      magnitude /= 10.0;
      ++exponent;
    }
    while (magnitude != 0.0 && magnitude < 1.0) {
      magnitude *= 10.0;
      --exponent;
    }
    const auto scaled = static_cast<std::uint64_t>(magnitude * 1e8 + 0.5);
    char buffer[24];
    const char* digits = format_unsigned(scaled, 10, 9, buffer + sizeof buffer);
    board_write_char(digits[0]);
    print(".");
    print(digits + 1);
    print("e");
    print_signed(exponent);
  }
  print(" [");
  print_hex(bits);
  print("]");
}

bool record(bool ok, const char* expression, const char* file, int line) {
  ++g_checks_total;
  if (ok) return true;
  ++g_checks_failed_in_test;
  print_failure_at(expression, file, line);
  return false;
}

bool check_near(double a, double b, double tolerance, const char* expression, const char* file, int line) {
  const double difference = a > b ? a - b : b - a;
  const bool ok = difference <= tolerance;
  if (!record(ok, expression, file, line)) print_operands(a, b);
  return ok;
}

bool check_log(const test::CheckLog& log, const char* expression, const char* file, int line) {
  // Every check of the shared body counts, as if it had been written here.
  g_checks_total += log.checks();
  if (log.ok()) return true;
  g_checks_failed_in_test += log.failures();
  print_failure_at(expression, file, line);
  for (std::size_t i = 0; i < log.kept(); ++i) {
    const test::CheckFailure& failure = log.failure(i);
    print("    ");
    print(failure.what);
    print("\n");
    print_operands(failure.value, failure.limit);
  }
  return false;
}

std::size_t run_all_tests() {
  for (TestCase* test = g_first; test != nullptr; test = test->next) {
    g_checks_failed_in_test = 0;
    const std::size_t checks_before = g_checks_total;
    test->run();
    const bool passed = g_checks_failed_in_test == 0;
    print(passed ? "[  OK  ] " : "[ FAIL ] ");
    print(test->suite);
    print(".");
    print(test->name);
    print(" (");
    print_unsigned(g_checks_total - checks_before);
    print(" checks)\n");
    if (passed) {
      ++g_tests_passed;
    } else {
      ++g_tests_failed;
    }
  }
  return g_tests_failed;
}

void print_summary() {
  print_unsigned(g_tests_passed);
  print(" passed, ");
  print_unsigned(g_tests_failed);
  print(" failed\n");
}

}  // namespace hivecal::fw
