/* Stack overflow guard (MPU) and high-water measurement (paint pattern).
 * Layout (mps2.ld): [__stack_guard_start, __stack_limit) guard, [__stack_limit, __stack_top)
 * stack, growing down towards the guard. The guard sits at the start of RAM: below it QEMU maps
 * only an unimplemented-device hole, where stray writes would vanish silently. */
#include <stdint.h>

#include "baremetal/board.h"
#include "stack.h"

extern uint32_t __stack_guard_start[];
extern uint32_t __stack_limit[];
extern uint32_t __stack_top[];

#define STACK_PAINT_WORD 0xDEADBEEFu

/* Armv7-M system control and PMSAv7 MPU registers. */
#define SCB_SHCSR (*(volatile uint32_t*)0xE000ED24u)
#define MPU_TYPE (*(volatile uint32_t*)0xE000ED90u)
#define MPU_CTRL (*(volatile uint32_t*)0xE000ED94u)
#define MPU_RNR (*(volatile uint32_t*)0xE000ED98u)
#define MPU_RBAR (*(volatile uint32_t*)0xE000ED9Cu)
#define MPU_RASR (*(volatile uint32_t*)0xE000EDA0u)

#define SHCSR_MEMFAULTENA (1u << 16)
#define SHCSR_BUSFAULTENA (1u << 17)
#define SHCSR_USGFAULTENA (1u << 18)
#define MPU_CTRL_ENABLE (1u << 0)
#define MPU_CTRL_PRIVDEFENA (1u << 2) /* default memory map for everything else */
#define MPU_RASR_ENABLE (1u << 0)
#define MPU_RASR_SIZE_32_BYTES (4u << 1) /* region size 2^(SIZE+1) */
#define MPU_RASR_AP_NO_ACCESS (0u << 24)
#define MPU_RASR_XN (1u << 28)

void stack_guard_enable(void) {
  /* Report faults by their own handlers instead of escalating all to HardFault. */
  SCB_SHCSR |= SHCSR_MEMFAULTENA | SHCSR_BUSFAULTENA | SHCSR_USGFAULTENA;
  if (((MPU_TYPE >> 8) & 0xFFu) == 0) return; /* no MPU: paint check only */
  MPU_RNR = 0;
  MPU_RBAR = (uint32_t)(uintptr_t)__stack_guard_start; /* 32-byte aligned by mps2.ld */
  MPU_RASR = MPU_RASR_XN | MPU_RASR_AP_NO_ACCESS | MPU_RASR_SIZE_32_BYTES | MPU_RASR_ENABLE;
  MPU_CTRL = MPU_CTRL_PRIVDEFENA | MPU_CTRL_ENABLE;
  __asm__ volatile("dsb\n\tisb" ::: "memory");
}

void stack_paint(void) {
  uint32_t* stack_pointer;
  __asm__ volatile("mov %0, sp" : "=r"(stack_pointer));
  /* Everything below the live stack pointer is free; this function's own frame is above it. */
  for (volatile uint32_t* word = __stack_limit; word < stack_pointer; ++word) *word = STACK_PAINT_WORD;
}

size_t board_stack_size_bytes(void) {
  return (size_t)((uintptr_t)__stack_top - (uintptr_t)__stack_limit);
}

size_t board_stack_used_bytes(void) {
  const uint32_t* word = __stack_limit;
  while (word < __stack_top && *word == STACK_PAINT_WORD) ++word;
  return (size_t)((uintptr_t)__stack_top - (uintptr_t)word);
}
