/* Vector table, reset handler and fault handlers for the Cortex-M MPS2 boards under QEMU.
 * Reset order matters: the FPU is enabled before any code that may use VFP registers, .data and
 * .bss are initialised before constructors, and the stack is painted before main so its
 * high-water mark can be measured (stack.c). */
#include <stdint.h>

#include "baremetal/board.h"
#include "stack.h"

/* Linker script symbols (mps2.ld). */
extern uint32_t __data_load_start[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern void (*__preinit_array_start[])(void);
extern void (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void);
extern void (*__init_array_end[])(void);
extern uint32_t __stack_top[];

int main(void);
void Reset_Handler(void);
_Noreturn void hivecal_reset_continue(void);

static void copy_data(void) {
  const uint32_t* source = __data_load_start;
  for (uint32_t* word = __data_start; word < __data_end; ++word) *word = *source++;
}

static void zero_bss(void) {
  for (uint32_t* word = __bss_start; word < __bss_end; ++word) *word = 0;
}

/* C++ static constructors (the test registry relies on them); no crt0 does it for us. */
static void run_constructors(void) {
  for (void (**init)(void) = __preinit_array_start; init < __preinit_array_end; ++init) (*init)();
  for (void (**init)(void) = __init_array_start; init < __init_array_end; ++init) (*init)();
}

/* Called from Reset_Handler once the FPU is on; never returns. */
_Noreturn void hivecal_reset_continue(void) {
  copy_data();
  zero_bss();
  stack_guard_enable();
  stack_paint();
  run_constructors();
  board_exit(main());
}

/* Naked: no prologue may touch VFP registers before CPACR grants CP10/CP11 access (with
 * -mfloat-abi=hard the compiler is free to use them anywhere, even for integer copies). */
__attribute__((naked, noreturn)) void Reset_Handler(void) {
#if defined(__ARM_FP)
  __asm__ volatile(
      "movw r0, #0xED88\n\t" /* CPACR = 0xE000ED88 */
      "movt r0, #0xE000\n\t"
      "ldr r1, [r0]\n\t"
      "orr r1, r1, #(0xF << 20)\n\t" /* CP10, CP11: full access */
      "str r1, [r0]\n\t"
      "dsb\n\t"
      "isb\n\t");
#endif
  __asm__ volatile("b hivecal_reset_continue");
}

static _Noreturn void fault(const char* name) {
  board_write("\n*** ");
  board_write(name);
  board_write(": firmware stopped\n");
  board_exit(BOARD_EXIT_FAULT);
}

/* Fault entries first move SP back to the top of the stack: after an overflow into the guard
 * the old stack is unusable, and the report only needs a fresh frame (the run ends anyway). */
#define FAULT_ENTRY(entry, report)                 \
  __attribute__((naked)) static void entry(void) { \
    __asm__ volatile(                              \
        "movw r0, #:lower16:__stack_top\n\t"       \
        "movt r0, #:upper16:__stack_top\n\t"       \
        "mov sp, r0\n\t"                           \
        "b " #report);                             \
  }

__attribute__((used)) static void report_nmi(void) {
  fault("NMI");
}
__attribute__((used)) static void report_hard_fault(void) {
  fault("HardFault");
}
/* MemManage is what a stack overflow into the MPU guard region raises (stack.c). */
__attribute__((used)) static void report_mem_manage(void) {
  fault("MemManage (stack overflow?)");
}
__attribute__((used)) static void report_bus_fault(void) {
  fault("BusFault");
}
__attribute__((used)) static void report_usage_fault(void) {
  fault("UsageFault");
}
__attribute__((used)) static void report_unexpected(void) {
  fault("unexpected exception");
}

FAULT_ENTRY(nmi_handler, report_nmi)
FAULT_ENTRY(hard_fault_handler, report_hard_fault)
FAULT_ENTRY(mem_manage_handler, report_mem_manage)
FAULT_ENTRY(bus_fault_handler, report_bus_fault)
FAULT_ENTRY(usage_fault_handler, report_usage_fault)
FAULT_ENTRY(unexpected_handler, report_unexpected)

/* The Cortex-M vector table: initial SP, then handlers. Only the 16 system exceptions: the
 * firmware enables no interrupt, so no device vector is ever taken. */
typedef void (*Handler)(void);
struct VectorTable {
  uint32_t* initial_stack_pointer;
  Handler handlers[15];
};

__attribute__((section(".isr_vector"), used)) const struct VectorTable hivecal_vector_table = {
    __stack_top,
    {
        Reset_Handler, nmi_handler, hard_fault_handler, mem_manage_handler, bus_fault_handler, usage_fault_handler, 0,
        0, 0, 0,            /* reserved */
        unexpected_handler, /* SVCall */
        unexpected_handler, /* DebugMonitor */
        0,                  /* reserved */
        unexpected_handler, /* PendSV */
        unexpected_handler, /* SysTick */
    },
};
