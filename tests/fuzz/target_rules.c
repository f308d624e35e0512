/*
 * Fuzz target "rules": rules files (--rules, devices/eds_class/rules.c, libyaml) for the device of tests/eds/files/drive.eds
 * (a CiA 402 drive with process values), then the device running them, as canopen-emu runs a device read from an EDS.
 *
 * Input: the rules file's text up to the first NUL byte (all of it when there is none), then records until the input
 * ends (at most 64): [0] kind, then its bytes:
 *   0x00-0x3F time passes by (u8 + 1) x 10 ms, in steps at the deadlines the rules return, like the program's loop
 *             (at most 2.56 s a record: with 1 ms ticks that is 2,560 steps; longer spans are the clock jumps' job);
 *   0x40-0x7F a controlword written by SDO (u16), as a master drives the CiA 402 machine;
 *   0x80-0xBF an SDO write to one of the drive's writable objects (u8 selects it) of the next 3 bytes (a 4-byte
 *             object gets a zero high byte);
 *   0xC0-0xDF an NMT reset application (the rules start again);
 *   0xE0-0xFF a jump of the clock by (u16) x 10 s (catching up, never spinning).
 * Invariants (a violation prints "==fuzz== INVARIANT VIOLATION [rules]" and aborts):
 *  - a rules file is either loaded or refused with at least one "FILE:LINE:COLUMN: error:" line, never both or
 *    neither, and with at most 21 lines (20 errors and one that says more were found);
 *  - what the YAML reader refuses (rules_yaml.h: anchors, aliases, nesting past 16 levels, more than 65,536
 *    values, duplicate keys, a second document) is refused as it comes: libFuzzer's timeout and RSS limit hold it;
 *  - a step returns a deadline after now (or CO_NEVER), never one in the past (a loop would spin);
 *  - the same input runs the same way twice: every object of the device holds the same value after both runs
 *    (the rules are deterministic in simulated time: a random walk by its seed);
 *  - no crash, leak, hang or undefined behaviour (ASan, UBSan, LeakSanitizer, libFuzzer's timeout).
 */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "eds_class/eds_class.h"
#include "eds_class/rules.h"
#include "fake_port.h"
#include "fuzz_abort.h"

#ifndef FZ_DRIVE_EDS
#error FZ_DRIVE_EDS: the path of tests/eds/files/drive.eds
#endif

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void violation(const char *fmt, ...)
{
    fprintf(stderr, "==fuzz== INVARIANT VIOLATION [rules] ");
    va_list ap;
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

static const device_class_t *drive;
static char rules_path[256];
static const uint16_t WRITABLE[] = {0x2005, 0x6060, 0x607A, 0x607C, 0x6081, 0x60FF, 0x1017};

typedef struct run {
    fake_port_t port;
    co_time_us_t now;
    device_t dev;
    uint8_t *values;
    uint8_t *model;
} run_t;

/* Runs the records on a fresh device with the rules; the values block is left in r->values. */
static void run_once(const rules_t *rules, const uint8_t *p, size_t n, run_t *r)
{
    memset(r, 0, sizeof *r);
    fake_port_init(&r->port, &r->now);
    r->values = calloc(1U, drive->od->values_size);
    const size_t core = device_core_state_size(drive), state = rules_state_size(rules);
    r->model = calloc(1U, core + state + 1U);
    if (r->values == NULL || r->model == NULL) {
        abort();
    }
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = 5U;
    cfg.port = &r->port.port;
    cfg.port_ctx = &r->port;
    if (device_init(&r->dev, drive, r->values, r->model, &cfg, r->now) != CO_OK) {
        violation("the drive does not start");
    }
    void *st = r->model + core;
    rules_power_on(rules, st, &r->dev, r->now);
    size_t pos = 0U;
    for (int records = 0; pos < n && records < 64; records++) {
        const uint8_t kind = p[pos++];
        uint8_t b[4] = {0};
        for (size_t i = 0; i < 4U && pos < n; i++) {
            b[i] = p[pos++];
        }
        const uint16_t u16 = (uint16_t)(b[0] | (b[1] << 8));
        if (kind < 0x40U) {
            const co_time_us_t end = r->now + ((co_time_us_t)b[0] + 1U) * 10000U;
            while (r->now < end) {
                const co_time_us_t next = rules_step(rules, st, &r->dev, r->now);
                if (next <= r->now) {
                    violation("a step at %llu returned the deadline %llu", (unsigned long long)r->now,
                              (unsigned long long)next);
                }
                (void)device_process(&r->dev, r->now);
                r->now = next < end ? next : end;
            }
        } else if (kind < 0x80U) {
            (void)co_od_write(&r->dev.node, 0x6040U, 0U, b, 2U, CO_ORIGIN_SDO);
            co_od_entry_t one;
            (void)rules_on_write(rules, st, &r->dev, co_od_find(drive->od, 0x6040U, 0U, &one), b, 2U);
        } else if (kind < 0xC0U) {
            co_od_entry_t one;
            const co_od_entry_t *e = co_od_find(drive->od, WRITABLE[b[0] % (sizeof WRITABLE / sizeof WRITABLE[0])], 0U, &one);
            const uint8_t value[4] = {b[1], b[2], b[3], 0U};
            if (e != NULL) {
                (void)co_od_write(&r->dev.node, e->index, 0U, value, e->size <= 4U ? e->size : 4U, CO_ORIGIN_SDO);
            }
        } else if (kind < 0xE0U) {
            rules_power_on(rules, st, &r->dev, r->now);
        } else {
            r->now += (co_time_us_t)u16 * 10000000U;
            (void)rules_step(rules, st, &r->dev, r->now);
        }
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    FILE *quiet = fopen("/dev/null", "w");
    drive = eds_class_load(FZ_DRIVE_EDS, quiet != NULL ? quiet : stderr, true);
    if (quiet != NULL) {
        fclose(quiet);
    }
    if (drive == NULL) {
        fprintf(stderr, "fuzz_rules: cannot load %s\n", FZ_DRIVE_EDS);
        abort();
    }
    const char *tmp = getenv("TMPDIR");
    snprintf(rules_path, sizeof rules_path, "%s/fuzz-rules-%ld.yaml", tmp != NULL && tmp[0] != '\0' ? tmp : "/tmp",
             (long)getpid());
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nul = memchr(data, 0, size);
    const size_t text = nul != NULL ? (size_t)(nul - data) : size;
    FILE *f = fopen(rules_path, "wb");
    if (f == NULL || fwrite(data, 1U, text, f) != text || fclose(f) != 0) {
        abort();
    }
    char *log = NULL;
    size_t log_len = 0U;
    FILE *msg = open_memstream(&log, &log_len);
    const char *device = NULL;
    rules_t *rules = rules_load(rules_path, drive->od, msg, &device);
    fclose(msg);
    const bool said_error = log != NULL && strstr(log, ": error: ") != NULL;
    if ((rules == NULL) != said_error) {
        violation("rules %s but the log says: %s", rules == NULL ? "refused" : "loaded", log != NULL ? log : "");
    }
    size_t lines = 0U;
    for (const char *c = log; c != NULL && *c != '\0'; c++) {
        lines += *c == '\n' ? 1U : 0U;
    }
    if (lines > 21U) {
        violation("%zu lines of errors (at most 20 and one more): %.2000s", lines, log);
    }
    free(log);
    if (rules != NULL) {
        const uint8_t *records = data + text + (nul != NULL ? 1U : 0U);
        const size_t n = size - text - (nul != NULL ? 1U : 0U);
        run_t *a = calloc(1U, sizeof *a), *b = calloc(1U, sizeof *b);
        if (a == NULL || b == NULL) {
            abort();
        }
        run_once(rules, records, n, a);
        run_once(rules, records, n, b);
        if (memcmp(a->values, b->values, drive->od->values_size) != 0) {
            violation("the same input ran two ways: the objects differ");
        }
        free(a->values), free(a->model), free(b->values), free(b->model);
        free(a), free(b);
        rules_free(rules);
    }
    return 0;
}
