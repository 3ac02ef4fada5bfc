/* QEMU 7.2 TCG plugin: executed instructions per guest address, in
 * segments. Derived from the project's shared `qemu-prof/pcprof.c`.
 *
 * Every instruction below 4 MB (the boards' flash) is counted by an inline
 * add. Executing the instruction at `line=ADDR` (the firmware's
 * `tilerast_report_line`, called after each line of its report) or at
 * `lap=ADDR` (`tilerast_lap`, called as the firmware reads SysTick) closes
 * the current segment: its non-zero counts are written to `out=PATH` as
 * `segment K INSTRUCTIONS line|lap` followed by `ADDRESS COUNT` lines, and
 * zeroed. At exit the rest is written as a last segment (`exit`) and
 * `total N`.
 * Minimal declarations of the 7.2 plugin API (QEMU_PLUGIN_VERSION 1): no
 * QEMU headers needed. Build: `cc -shared -fPIC -O2 segprof.c -o lib.so`. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stddef.h>
typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef struct qemu_info_t qemu_info_t;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t, struct qemu_plugin_tb *);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t, void *);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int, void *);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, qemu_plugin_vcpu_tb_trans_cb_t);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *, enum qemu_plugin_op,
                                                void *, uint64_t);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *, qemu_plugin_vcpu_udata_cb_t,
                                            enum qemu_plugin_cb_flags, void *);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t, qemu_plugin_udata_cb_t, void *);
__attribute__((visibility("default"))) int qemu_plugin_version = 1;

#define SPAN (1u << 22)
static uint64_t *cnt;
static uint64_t total, line = UINT64_MAX, lap = UINT64_MAX;
static unsigned segment;
static FILE *out;

/* Writes the counts gathered since the last mark and zeroes them. */
static void flush_segment(const char *end) {
    uint64_t sum = 0;
    for (uint32_t i = 0; i < SPAN / 2; i++)
        sum += cnt[i];
    fprintf(out, "segment %u %llu %s\n", segment++, (unsigned long long)sum, end);
    for (uint32_t i = 0; i < SPAN / 2; i++)
        if (cnt[i]) {
            fprintf(out, "%x %llu\n", i << 1, (unsigned long long)cnt[i]);
            cnt[i] = 0;
        }
}

static void on_mark(unsigned int vcpu, void *end) { flush_segment(end); }

static void tb_trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *in = qemu_plugin_tb_get_insn(tb, i);
        uint64_t va = qemu_plugin_insn_vaddr(in);
        qemu_plugin_register_vcpu_insn_exec_inline(in, QEMU_PLUGIN_INLINE_ADD_U64, &total, 1);
        if (va < SPAN)
            qemu_plugin_register_vcpu_insn_exec_inline(in, QEMU_PLUGIN_INLINE_ADD_U64,
                                                       &cnt[va >> 1], 1);
        if (va == line || va == lap)
            qemu_plugin_register_vcpu_insn_exec_cb(in, on_mark, QEMU_PLUGIN_CB_NO_REGS,
                                                   va == line ? "line" : "lap");
    }
}

static void at_exit(qemu_plugin_id_t id, void *p) {
    flush_segment("exit");
    fprintf(out, "total %llu\n", (unsigned long long)total);
    fclose(out);
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id,
                                                               const qemu_info_t *info,
                                                               int argc, char **argv) {
    const char *path = "prof.txt";
    for (int i = 0; i < argc; i++) {
        if (!strncmp(argv[i], "line=", 5))
            line = strtoull(argv[i] + 5, NULL, 0);
        else if (!strncmp(argv[i], "lap=", 4))
            lap = strtoull(argv[i] + 4, NULL, 0);
        else if (!strncmp(argv[i], "out=", 4))
            path = argv[i] + 4;
    }
    out = fopen(path, "w");
    cnt = calloc(SPAN / 2, sizeof(uint64_t));
    if (!out || !cnt)
        return -1;
    qemu_plugin_register_vcpu_tb_trans_cb(id, tb_trans);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
