/*
 * bench-echo: the floor of the SDO round trip (docs/performance.md). Answers every frame on 0x600+ID
 * (ID in A..B) with a fixed 8-byte frame on 0x580+ID, with nothing else in between: one blocking read,
 * one write. What a round trip against it costs is what the kernel, the sockets and the scheduler cost
 * alone, so the emulator's round trip divided by this one holds across machines.
 *
 *   bench-echo [-i IFACE] A[-B]        runs until SIGTERM/SIGINT; prints the number of answers
 */
#define _GNU_SOURCE
#include <errno.h>
#include <linux/can/raw.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "bench_can.h"

static volatile sig_atomic_t stop;

static void on_signal(int sig) { stop = sig; }

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    int i = 1;
    if (argc > 2 && strcmp(argv[1], "-i") == 0) {
        iface = argv[2];
        i = 3;
    }
    if (i + 1 != argc) {
        fprintf(stderr, "usage: bench-echo [-i IFACE] A[-B]\n");
        return 2;
    }
    long long a;
    long long b;
    bench_range(argv[i], 1, 127, &a, &b, "node range");
    bench_can_t can;
    if (bench_can_open(&can, iface, 0) != 0) {
        return 1;
    }
    /* The kernel filters: only requests wake us. */
    const struct can_filter flt = {0x600U, CAN_SFF_MASK & ~0x7FU};
    (void)setsockopt(can.fd, SOL_CAN_RAW, CAN_RAW_FILTER, &flt, sizeof flt);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: the blocking read returns EINTR */
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    unsigned long answers = 0U;
    struct can_frame f;
    while (stop == 0) {
        /* Wait as canopen-emu waits (ppoll, then a non-blocking read), so that the floor differs from it only in the
         * work done per frame: inside User-Mode Linux a blocking read wakes up measurably later than ppoll. */
        struct pollfd pfd = {can.fd, POLLIN, 0};
        if (ppoll(&pfd, 1U, NULL, NULL) < 0) {
            continue; /* EINTR: the loop condition sees the signal */
        }
        const ssize_t r = recv(can.fd, &f, sizeof f, MSG_DONTWAIT);
        if (r != (ssize_t)sizeof f) {
            if (r < 0 && errno != EINTR && errno != EAGAIN) {
                fprintf(stderr, "bench-echo: read: %s\n", strerror(errno));
                return 1;
            }
            continue;
        }
        const uint32_t id = f.can_id & CAN_SFF_MASK;
        if ((f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) != 0U || id < 0x600U + (uint32_t)a ||
            id > 0x600U + (uint32_t)b) {
            continue;
        }
        struct can_frame ans;
        memset(&ans, 0, sizeof ans);
        ans.can_id = id - 0x80U;
        ans.can_dlc = 8U;
        ans.data[0] = 0x60U; /* fixed, not an SDO answer to anything in particular */
        if (write(can.fd, &ans, sizeof ans) != (ssize_t)sizeof ans) {
            fprintf(stderr, "bench-echo: write: %s\n", strerror(errno));
            return 1;
        }
        answers++;
    }
    printf("{\"answers\": %lu}\n", answers);
    bench_can_close(&can);
    return 0;
}
