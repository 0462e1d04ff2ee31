/* Stack guard and paint, used by the reset handler. Internal to the port. */
#ifndef HIVECAL_BAREMETAL_STACK_H
#define HIVECAL_BAREMETAL_STACK_H

/* Makes the guard below the stack inaccessible (MPU region 0) so an overflow faults. */
void stack_guard_enable(void);
/* Fills the unused part of the stack with a pattern (below the current stack pointer). */
void stack_paint(void);

#endif
