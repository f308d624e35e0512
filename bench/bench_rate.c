/*
 * bench-rate: the highest SDO request rate a set of nodes sustains with no lost answer
 * (docs/performance.md, "Scale").
 *
 *   bench-rate [-i IFACE] [--pid PID] [--step-ms MS] [--grace-ms MS] --nodes A-B RATE [RATE ...]
 *
 * First it reads 0x1018:01 and 0x1018:02 of every node once, sequentially, to learn the exact answers.
 * Then, for each RATE (requests per second, ascending), it sends expedited uploads open-loop: request k
 * leaves at start + k / RATE whatever the answers do, round-robin over the nodes, for MS milliseconds,
 * and then waits GRACE milliseconds for the last answers. Steps alternate between sub-index 1 and 2, so an
 * answer to the previous step that arrives late is recognised (counted "late", not as an answer).
 * A step loses when an answer is missing or wrong; it stops at the first such step, or when it cannot
 * itself send at 90% of the rate (then the client, not the server, is the limit: "client_limited").
 * With --pid it also reports the server's CPU share (utime+stime of /proc/PID/stat) during each step.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <linux/can/raw.h>
#include <sys/socket.h>

#include "bench_can.h"

static bench_can_t can;
static uint8_t expect[128][2][8];

static int learn(unsigned a, unsigned b)
{
    for (unsigned n = a; n <= b; n++) {
        for (unsigned s = 0U; s < 2U; s++) {
            uint8_t req[8];
            sdo_upload_req(req, 0x1018U, (uint8_t)(s + 1U));
            if (bench_can_send(&can, 0x600U + n, 8U, req) != 0) {
                return -1;
            }
            struct can_frame f;
            int64_t t;
            int r;
            do {
                r = bench_can_recv(&can, &f, &t, bench_mono_ns() + 2000000000LL);
            } while (r == 1 && (f.can_id & CAN_SFF_MASK) != 0x580U + n);
            if (r != 1 || f.can_dlc != 8U || (f.data[0] & 0xE2U) != 0x42U) {
                fprintf(stderr, "bench-rate: node %u does not answer an upload of 0x1018:%02u\n", n, s + 1U);
                return -1;
            }
            memcpy(expect[n][s], f.data, 8);
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    int pid = 0;
    long long step_ms = 2000;
    long long grace_ms = 1000;
    long long a = 0;
    long long b = 0;
    long long rates[64];
    size_t n_rates = 0U;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-i") == 0 && i + 1 < argc) {
            iface = argv[++i];
        } else if (strcmp(argv[i], "--pid") == 0 && i + 1 < argc) {
            pid = (int)bench_num(argv[++i], 1, 1 << 30, "pid");
        } else if (strcmp(argv[i], "--step-ms") == 0 && i + 1 < argc) {
            step_ms = bench_num(argv[++i], 10, 600000, "step");
        } else if (strcmp(argv[i], "--grace-ms") == 0 && i + 1 < argc) {
            grace_ms = bench_num(argv[++i], 10, 600000, "grace");
        } else if (strcmp(argv[i], "--nodes") == 0 && i + 1 < argc) {
            bench_range(argv[++i], 1, 127, &a, &b, "node range");
        } else if (n_rates < sizeof rates / sizeof rates[0]) {
            rates[n_rates++] = bench_num(argv[i], 1, 10000000, "rate");
        }
    }
    if (a == 0 || n_rates == 0U) {
        fprintf(stderr, "usage: bench-rate [-i IFACE] [--pid PID] [--step-ms MS] [--grace-ms MS] --nodes A-B RATE...\n");
        return 2;
    }
    if (bench_can_open(&can, iface, 16 * 1024 * 1024) != 0) {
        return 1;
    }
    /* Only SDO answers (0x580-0x5FF) reach this socket: the 127 nodes' heartbeats and TPDOs (2,540 frames/s in
     * the scale run) would cost a system call each and, in User-Mode Linux, made this client the bottleneck
     * (its own socket dropped frames) before the emulator was. */
    const struct can_filter answers = {.can_id = 0x580U, .can_mask = 0x780U | CAN_EFF_FLAG | CAN_RTR_FLAG};
    if (setsockopt(can.fd, SOL_CAN_RAW, CAN_RAW_FILTER, &answers, sizeof answers) != 0) {
        perror("bench-rate: CAN_RAW_FILTER");
        return 1;
    }
    if (learn((unsigned)a, (unsigned)b) != 0) {
        return 1;
    }
    const unsigned n_nodes = (unsigned)(b - a + 1);
    const double tck = (double)sysconf(_SC_CLK_TCK);
    long long best = 0;
    long long first_lossy = 0;
    bool client_limited = false;
    printf("{\"nodes\": %u, \"step_ms\": %lld, \"grace_ms\": %lld, \"steps\": [", n_nodes, step_ms, grace_ms);
    for (size_t k = 0U; k < n_rates; k++) {
        const unsigned s = (unsigned)(k % 2U);
        uint8_t req[8];
        sdo_upload_req(req, 0x1018U, (uint8_t)(s + 1U));
        const long long total = rates[k] * step_ms / 1000;
        const double gap_ns = 1e9 / (double)rates[k];
        unsigned long good = 0U;
        unsigned long late = 0U;
        unsigned long wrong = 0U;
        long long sent = 0;
        const long long cpu0 = pid > 0 ? bench_proc_cpu_ticks(pid, NULL, NULL) : -1;
        const int64_t start = bench_mono_ns();
        int64_t send_end = start;
        int64_t end = -1;
        unsigned next_node = 0U;
        long long cpu1 = -1;
        for (;;) {
            const int64_t now = bench_mono_ns();
            while (sent < total && start + (int64_t)((double)sent * gap_ns) <= now) {
                if (bench_can_send(&can, 0x600U + (unsigned)a + next_node, 8U, req) != 0) {
                    return 1;
                }
                next_node = (next_node + 1U) % n_nodes;
                sent++;
            }
            if (sent == total && end < 0) {
                send_end = bench_mono_ns();
                cpu1 = pid > 0 ? bench_proc_cpu_ticks(pid, NULL, NULL) : -1;
                end = send_end + grace_ms * 1000000LL;
            }
            if (end >= 0 && (long long)good + (long long)wrong >= total) {
                break; /* everything answered: no need to sit out the grace time */
            }
            if (end >= 0 && bench_mono_ns() >= end) {
                break; /* checked here too: with 127 nodes' heartbeats and TPDOs a frame is always waiting, so the
                        * receive below may never time out */
            }
            const int64_t deadline = end >= 0 ? end : start + (int64_t)((double)sent * gap_ns);
            struct can_frame f;
            int64_t t;
            const int r = bench_can_recv(&can, &f, &t, deadline);
            if (r < 0) {
                return 1;
            }
            if (r == 0) {
                if (end >= 0 && bench_mono_ns() >= end) {
                    break;
                }
                continue;
            }
            const uint32_t id = f.can_id & CAN_SFF_MASK;
            if (id < 0x580U + (uint32_t)a || id > 0x580U + (uint32_t)b) {
                continue; /* heartbeats, PDOs */
            }
            const unsigned n = id - 0x580U;
            if (f.can_dlc == 8U && memcmp(f.data, expect[n][s], 8) == 0) {
                good++;
            } else if (f.can_dlc == 8U && memcmp(f.data, expect[n][1U - s], 8) == 0) {
                late++;
            } else {
                wrong++;
            }
        }
        const double secs = (double)(send_end - start) / 1e9;
        const double achieved = secs > 0.0 ? (double)sent / secs : 0.0;
        const long long lost = total - (long long)good;
        const double cpu = (cpu0 >= 0 && cpu1 >= 0 && secs > 0.0) ? (double)(cpu1 - cpu0) / tck / secs : -1.0;
        printf("%s{\"rate\": %lld, \"sent\": %lld, \"achieved_rate\": %.1f, \"answered\": %lu, \"lost\": %lld, "
               "\"late\": %lu, \"wrong\": %lu, \"cpu_share\": %.4f}",
               k > 0U ? ", " : "", rates[k], sent, achieved, good, lost, late, wrong, cpu);
        fflush(stdout);
        if (achieved < 0.9 * (double)rates[k]) {
            client_limited = true;
            break;
        }
        if (lost != 0 || wrong != 0U) {
            first_lossy = rates[k];
            break;
        }
        best = rates[k];
    }
    printf("], \"max_lossless_rate\": %lld, \"first_lossy_rate\": %lld, \"client_limited\": %s, \"rx_drops\": %lu}\n", best,
           first_lossy, client_limited ? "true" : "false", (unsigned long)can.drops);
    bench_can_close(&can);
    return 0;
}
