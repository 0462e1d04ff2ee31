/* Heap trap of the capture calibration image. The LM's identifiability analysis instantiates
 * Eigen's SelfAdjointEigenSolver<Matrix<double, 33, 33>>, whose Householder products on
 * dynamic-size blocks declare their temporaries with ei_declare_aligned_stack_constructed_variable.
 * Off Linux/Windows Eigen has no alloca, so that macro keeps a branch to aligned_malloc ->
 * malloc/free, taken only when no buffer was passed (never so far in these runs).
 * The reference alone would pull newlib's malloc and fail the link (no _sbrk). Until lib/ stops
 * instantiating it (docs/firmware.md), this image defines malloc/free as traps: any call ends
 * the run as a fault, so a test run also proves at run time that no allocation happens.
 * CTest hivecal_firmware_capture_job.heap_only_trapped checks these two are the only heap symbols. */
#include <cstddef>

#include "baremetal/board.h"

extern "C" {

void* malloc(std::size_t size);
void free(void* pointer);

void* malloc(std::size_t size) {
  (void)size;
  board_write("heap trap: malloc called\n");
  board_exit(BOARD_EXIT_FAULT);
}

void free(void* pointer) {
  if (pointer == nullptr) return;
  board_write("heap trap: free called\n");
  board_exit(BOARD_EXIT_FAULT);
}

}  // extern "C"
