// Firmware test image: runs every FW_TEST under semihosting, reports the measured stack
// high-water mark, and ends with "N passed, M failed". Exit status 0 only if all passed.
#include "baremetal/board.h"
#include "harness.hpp"

int main() {
  using namespace hivecal::fw;
  print("hivecal firmware tests\n");
  const std::size_t failed = run_all_tests();
  print("stack high-water: ");
  print_unsigned(board_stack_used_bytes());
  print(" of ");
  print_unsigned(board_stack_size_bytes());
  print(" bytes\n");
  print_summary();
  return failed == 0 ? 0 : 1;
}
