/*
 * bench-record: period statistics of cyclic frames (docs/performance.md).
 *
 *   bench-record [-i IFACE] [-b BATCH_MS] [-p PERIOD_US] [-t LATE_US] -d SECONDS NAME=IDS[@PERIOD_US] ...
 *
 * -b: it reads in batches, sleeping BATCH_MS (default 20) whenever nothing is pending, never woken per frame. 127
 * nodes send 254 frames at once every 100 ms; a recorder woken for each of them took the single CPU of
 * User-Mode Linux away from the sender in the middle of its burst (a context switch there costs tens of µs)
 * and made the sender late: the measurement disturbed what it measured. Kernel time stamps and a deep
 * receive buffer make batches exact.
 *
 * IDS is a COB-ID or a range (0x701-0x77F). For SECONDS it records the kernel arrival time
 * (SO_TIMESTAMPNS) of every frame whose COB-ID is in a group; each COB-ID is its own stream and an
 * interval is the time between two consecutive frames of one stream. Per group it prints (JSON, µs):
 * intervals, streams seen, mean error = mean(interval) - PERIOD, and p50/p99/max of |interval - PERIOD|,
 * plus the intervals longer than 1.5 periods (a missing frame). Kernel timestamps leave out the
 * recorder's own wake-up latency; they do include the sender's (that is what is measured).
 *
 * A group's own period (@PERIOD_US) replaces -p for it, so that streams of different periods (heartbeats at 100 ms,
 * TPDOs at 50 ms) are judged in one recording. Also per group: the worst lateness, max(interval - period) (µs;
 * negative when every interval was short), and with -t the intervals longer than period + LATE_US (a missed
 * deadline as the caller defines it).
 */
#define _GNU_SOURCE
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_can.h"

#define MAX_GROUPS 8

typedef struct group {
    char name[32];
    uint32_t lo;
    uint32_t hi;
    long long period_us;      /* 0: the -p period */
    bench_samples_t dev_ns;   /* |interval - period| */
    double sum_interval_ns;
    unsigned long n_frames;
    unsigned long missing;
    unsigned long late;       /* intervals > period + LATE_US (-t) */
    double late_max_ns;       /* max(interval - period) */
} group_t;

static bool t_end_passed(int64_t end) { return bench_mono_ns() >= end; }

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    long long period_us = 0;
    long long seconds = 0;
    long long batch_ms = 20;
    long long late_us = -1; /* -t: none given, no count */
    group_t groups[MAX_GROUPS];
    size_t n_groups = 0U;
    memset(groups, 0, sizeof groups);
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-i") == 0 && i + 1 < argc) {
            iface = argv[++i];
        } else if (strcmp(argv[i], "-p") == 0 && i + 1 < argc) {
            period_us = bench_num(argv[++i], 1, 3600000000LL, "period");
        } else if (strcmp(argv[i], "-d") == 0 && i + 1 < argc) {
            seconds = bench_num(argv[++i], 1, 86400, "duration");
        } else if (strcmp(argv[i], "-b") == 0 && i + 1 < argc) {
            batch_ms = bench_num(argv[++i], 1, 1000, "batch");
        } else if (strcmp(argv[i], "-t") == 0 && i + 1 < argc) {
            late_us = bench_num(argv[++i], 0, 3600000000LL, "lateness");
        } else if (strchr(argv[i], '=') != NULL && n_groups < MAX_GROUPS) {
            group_t *g = &groups[n_groups++];
            const char *eq = strchr(argv[i], '=');
            (void)snprintf(g->name, sizeof g->name, "%.*s", (int)(eq - argv[i]), argv[i]);
            char ids[64];
            const char *at = strchr(eq + 1, '@');
            (void)snprintf(ids, sizeof ids, "%.*s", at != NULL ? (int)(at - eq - 1) : (int)strlen(eq + 1), eq + 1);
            if (at != NULL) {
                g->period_us = bench_num(at + 1, 1, 3600000000LL, "group period");
            }
            long long lo;
            long long hi;
            bench_range(ids, 0, 0x7FF, &lo, &hi, "COB-ID range");
            g->lo = (uint32_t)lo;
            g->hi = (uint32_t)hi;
        } else {
            fprintf(stderr, "usage: bench-record [-i IFACE] [-b BATCH_MS] [-p PERIOD_US] [-t LATE_US] -d SECONDS "
                            "NAME=ID[-ID][@PERIOD_US] ...\n");
            return 2;
        }
    }
    bool periods_known = n_groups > 0U;
    for (size_t g = 0U; g < n_groups; g++) {
        if (groups[g].period_us == 0) {
            groups[g].period_us = period_us;
        }
        periods_known = periods_known && groups[g].period_us > 0;
    }
    if (!periods_known || seconds == 0) {
        fprintf(stderr, "bench-record: -d, at least one NAME=IDS and a period for each (-p or @PERIOD_US) are needed\n");
        return 2;
    }
    bench_can_t can;
    if (bench_can_open(&can, iface, 16 * 1024 * 1024) != 0) {
        return 1;
    }
    static int64_t last[2048];
    static int8_t owner[2048];
    memset(owner, -1, sizeof owner);
    for (size_t g = 0U; g < n_groups; g++) {
        for (uint32_t id = groups[g].lo; id <= groups[g].hi; id++) {
            owner[id] = (int8_t)g;
        }
    }
    for (size_t g = 0U; g < n_groups; g++) {
        groups[g].late_max_ns = -(double)groups[g].period_us * 1000.0;
    }
    const int64_t end = bench_mono_ns() + seconds * 1000000000LL;
    struct can_frame fs[64];
    int64_t ts[64];
    const struct timespec nap = {.tv_sec = 0, .tv_nsec = (long)batch_ms * 1000000L};
    int n;
    /* Everything pending in as few system calls as possible, then a nap while the next burst piles up (kernel time
     * stamps keep each frame's arrival exact); the window ends also while frames keep coming. */
    while ((n = bench_can_recv_many(&can, fs, ts, 64)) >= 0 && !t_end_passed(end)) {
        if (n == 0) {
            (void)nanosleep(&nap, NULL);
            continue;
        }
        for (int k = 0; k < n; k++) {
            const struct can_frame *f = &fs[k];
            const int64_t t = ts[k];
            if ((f->can_id & (CAN_EFF_FLAG | CAN_ERR_FLAG | CAN_RTR_FLAG)) != 0U) {
                continue;
            }
            const uint32_t id = f->can_id & CAN_SFF_MASK;
            if (owner[id] < 0) {
                continue;
            }
            group_t *g = &groups[owner[id]];
            const double period_ns = (double)g->period_us * 1000.0;
            g->n_frames++;
            if (last[id] != 0) {
                const double iv = (double)(t - last[id]);
                if (iv - period_ns > g->late_max_ns) {
                    g->late_max_ns = iv - period_ns;
                }
                if (late_us >= 0 && iv > period_ns + (double)late_us * 1000.0) {
                    g->late++;
                }
                g->sum_interval_ns += iv;
                samples_add(&g->dev_ns, iv > period_ns ? iv - period_ns : period_ns - iv);
                if (iv > 1.5 * period_ns) {
                    g->missing++;
                }
            }
            last[id] = t;
        }
    }
    if (n < 0) {
        return 1;
    }
    printf("{\"period_us\": %lld, \"seconds\": %lld, \"late_us\": %lld, \"rx_drops\": %lu, \"rcvbuf\": %d, "
           "\"groups\": {",
           period_us, seconds, late_us, (unsigned long)can.drops, can.rcvbuf);
    for (size_t gi = 0U; gi < n_groups; gi++) {
        group_t *g = &groups[gi];
        unsigned streams = 0U;
        for (uint32_t id = g->lo; id <= g->hi; id++) {
            streams += last[id] != 0 ? 1U : 0U;
        }
        const double period_ns = (double)g->period_us * 1000.0;
        const double mean_err = g->dev_ns.n > 0U ? g->sum_interval_ns / (double)g->dev_ns.n - period_ns : 0.0;
        printf("%s\"%s\": {\"period_us\": %lld, \"streams\": %u, \"frames\": %lu, \"intervals\": %zu, "
               "\"missing\": %lu, \"late\": %lu, \"late_max_us\": %.3f, \"mean_error_us\": %.3f, ",
               gi > 0U ? ", " : "", g->name, g->period_us, streams, g->n_frames, g->dev_ns.n, g->missing, g->late,
               g->dev_ns.n > 0U ? g->late_max_ns / 1000.0 : 0.0, mean_err / 1000.0);
        json_stats(stdout, "abs_dev_us", &g->dev_ns, 1e-3, true);
        printf("}");
    }
    printf("}}\n");
    bench_can_close(&can);
    return 0;
}
