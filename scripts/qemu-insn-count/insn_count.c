/* insn_count: a QEMU TCG plugin that counts the guest instructions a run executes and
 * prints "insns: <count>" when the guest exits (through QEMU's log: pass -d plugin).
 *
 * Why a plugin: executed instructions are exact and repeatable for one binary and input,
 * where wall time under emulation is neither (scripts/footprint.sh).
 *
 * How: when QEMU translates a block, the plugin asks it to add the block's instruction count
 * to one 64-bit counter every time the block runs. The add is inlined into the translated
 * code (no call per block), so counting costs little. The guests here are single-core, so
 * one counter is exact.
 *
 * Build (scripts/footprint.sh does it): cc -shared -fPIC -O2 insn_count.c -o libinsn_count.so
 * Use:   qemu-system-arm ... -plugin libinsn_count.so -d plugin
 *
 * Debian's QEMU packages (7.2, bookworm) install no qemu-plugin.h, so the part of the plugin
 * API (version 1, QEMU 4.2 .. 8.x) used here is declared below. The plugin's symbols are
 * resolved against the QEMU binary when it loads the plugin.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* --- the plugin API, as far as used ---------------------------------------------------- */
typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t; /* opaque here: not read */
struct qemu_plugin_tb;                  /* a translation block being translated */

/* Inline operations QEMU can insert into translated code; only the add is used. */
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 = 0 };

typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op, void* ptr,
                                              uint64_t imm);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);
void qemu_plugin_outs(const char* string);

#define PLUGIN_EXPORT __attribute__((visibility("default")))

/* QEMU refuses a plugin built for another API version. */
PLUGIN_EXPORT int qemu_plugin_version = 1;

/* --- the counter ----------------------------------------------------------------------- */
static uint64_t executed_insns;

/* Every execution of the block adds its instruction count to the counter. */
static void count_block(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  const uint64_t insns = (uint64_t)qemu_plugin_tb_n_insns(tb);
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &executed_insns, insns);
}

static void report(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  char text[48];
  snprintf(text, sizeof text, "insns: %llu\n", (unsigned long long)executed_insns);
  qemu_plugin_outs(text);
}

PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc, char** argv) {
  (void)info;
  (void)argv;
  if (argc != 0) {
    fprintf(stderr, "insn_count: takes no arguments\n");
    return -1;
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, count_block);
  qemu_plugin_register_atexit_cb(id, report, NULL);
  return 0;
}
