/*
 * bench-gen: the ideal periodic sender (docs/performance.md). Sleeps to absolute deadlines
 * (clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC, deadline k = start + k * PERIOD) and sends one
 * 1-byte frame on COB-ID at each. Recorded next to the emulator's heartbeat and TPDO in the same run, it
 * shows what the machine's timers and scheduler allow at all: the emulator cannot do better than this.
 *
 *   bench-gen [-i IFACE] -p PERIOD_US -d SECONDS COB-ID
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <string.h>

#include "bench_can.h"

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    long long period_us = 0;
    long long seconds = 0;
    long long cob = -1;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-i") == 0 && i + 1 < argc) {
            iface = argv[++i];
        } else if (strcmp(argv[i], "-p") == 0 && i + 1 < argc) {
            period_us = bench_num(argv[++i], 100, 3600000000LL, "period");
        } else if (strcmp(argv[i], "-d") == 0 && i + 1 < argc) {
            seconds = bench_num(argv[++i], 1, 86400, "duration");
        } else if (cob < 0) {
            cob = bench_num(argv[i], 0, 0x7FF, "COB-ID");
        } else {
            cob = -2;
        }
    }
    if (period_us == 0 || seconds == 0 || cob < 0) {
        fprintf(stderr, "usage: bench-gen [-i IFACE] -p PERIOD_US -d SECONDS COB-ID\n");
        return 2;
    }
    bench_can_t can;
    if (bench_can_open(&can, iface, 0) != 0) {
        return 1;
    }
    const int64_t period_ns = period_us * 1000LL;
    const int64_t start = bench_mono_ns();
    const long long n = seconds * 1000000LL / period_us;
    bench_samples_t late;
    memset(&late, 0, sizeof late);
    for (long long k = 1; k <= n; k++) {
        const int64_t due = start + k * period_ns;
        bench_sleep_until(due);
        late.sorted = false;
        samples_add(&late, (double)(bench_mono_ns() - due)); /* wake-up latency, as the process saw it */
        const uint8_t d = (uint8_t)k;
        if (bench_can_send(&can, (uint32_t)cob, 1U, &d) != 0) {
            return 1;
        }
    }
    printf("{\"sent\": %lld, ", n);
    json_stats(stdout, "wakeup_late_us", &late, 1e-3, true);
    printf("}\n");
    bench_can_close(&can);
    return 0;
}
