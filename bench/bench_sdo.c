/*
 * bench-sdo: a scripted raw-socket CANopen master for the benchmarks (docs/performance.md).
 *
 *   bench-sdo [-i IFACE] [--any-reply] [--timeout-ms MS] COMMAND ARGS... [COMMAND ARGS...]...
 *
 *   ready A[-B] [DRAIN_MS]        wait until node A answers an SDO upload of 0x1000:00 (probed every 0.5 s:
 *                                 the server may start after us), then ask each of A+1..B once; then wait
 *                                 DRAIN_MS (default 300) for answers to probes that crossed the start-up
 *   w ID IDX:SUB SIZE VALUE       expedited download; anything but the confirmation is an error
 *   r ID IDX:SUB                  expedited upload; prints the value
 *   nmt CS ID                     NMT command (ID 0 = all)
 *   sleep MS                      receive (and count) frames for MS milliseconds
 *   up ID IDX:SUB N               N sequential uploads: round-trip p50/p99/max; every answer must equal the
 *                                 first one byte for byte (an expedited upload answer, not an abort)
 *   down ID IDX:SUB SIZE VALUE N  N sequential downloads: round trip; every answer must be the confirmation
 *
 * --any-reply: any 8-byte frame on 0x580+ID counts as the answer (for bench-echo, the floor).
 * --user-time: the answer's arrival time is the clock read after the read returned (as the socketcand client must),
 * not the kernel's time stamp; to compare a raw socket with a socketcand connection on equal terms.
 * -i takes a SocketCAN interface, udp_multicast:GROUP:PORT or socketcand:HOST:PORT:BUS (bench_can.h).
 * --gap-ms MS: pause MS after each answer of up/down (callgrind runs: a server that runs slowly would otherwise
 * find the next request already waiting and serve several per wake-up, which changes what one request costs).
 * Round trip = kernel arrival time of the answer (SO_TIMESTAMPNS) - CLOCK_REALTIME just before write().
 * At the end it prints one JSON object: the results, every frame counted per COB-ID over the whole run and
 * the number of SDO answers received (0x581..0x5FF): the callgrind difference method divides by it, so
 * start-up probes that the server answered are counted exactly. Exit status 1 on any failure.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_can.h"

typedef struct result {
    char op[8];
    unsigned node;
    unsigned index;
    unsigned sub;
    bench_samples_t rtt_ns;
} result_t;

static bench_can_t can;
static unsigned long counts[2048];
static unsigned long sdo_answers;
static bool any_reply;
static bool user_time;
static int64_t timeout_ns = 2000000000LL;
static int64_t gap_ns;
static result_t results[64];
static size_t n_results;

static void count(const struct can_frame *f)
{
    const uint32_t id = f->can_id & CAN_SFF_MASK;
    if ((f->can_id & (CAN_EFF_FLAG | CAN_ERR_FLAG)) != 0U) {
        return;
    }
    counts[id]++;
    if (id >= 0x581U && id <= 0x5FFU) {
        sdo_answers++;
    }
}

/* Receives until a frame with this COB-ID arrives (counting everything) or deadline; 1, 0 or -1. */
static int wait_id(uint32_t id, int64_t deadline, struct can_frame *f, int64_t *t)
{
    for (;;) {
        const int r = bench_can_recv(&can, f, t, deadline);
        if (r <= 0) {
            return r;
        }
        count(f);
        if ((f->can_id & CAN_SFF_MASK) == id && (f->can_id & (CAN_RTR_FLAG | CAN_EFF_FLAG)) == 0U) {
            return 1;
        }
    }
}

/* Waits gap_ns, still counting what arrives. */
static int pause_gap(void)
{
    if (gap_ns == 0) {
        return 0;
    }
    const int64_t end = bench_mono_ns() + gap_ns;
    struct can_frame f;
    int64_t t;
    int r;
    while ((r = bench_can_recv(&can, &f, &t, end)) == 1) {
        count(&f);
    }
    return r;
}

static void parse_mux(const char *text, unsigned *index, unsigned *sub)
{
    char buf[32];
    (void)snprintf(buf, sizeof buf, "%s", text);
    char *colon = strchr(buf, ':');
    *sub = 0U;
    if (colon != NULL) {
        *colon = '\0';
        *sub = (unsigned)bench_num(colon + 1, 0, 255, "sub-index");
    }
    *index = (unsigned)bench_num(buf, 0, 0xFFFF, "index");
}

/* One request, one answer; returns the round trip in ns or -1 (message printed). */
static int64_t transfer(unsigned node, const uint8_t req[8], uint8_t ans[8])
{
    struct can_frame f;
    int64_t t_rx = 0;
    const int64_t t_tx = bench_real_ns();
    if (bench_can_send(&can, 0x600U + node, 8U, req) != 0) {
        return -1;
    }
    const int r = wait_id(0x580U + node, bench_mono_ns() + timeout_ns, &f, &t_rx);
    if (r <= 0) {
        fprintf(stderr, "bench-sdo: node %u: no SDO answer within %lld ms\n", node, (long long)(timeout_ns / 1000000LL));
        return -1;
    }
    if (f.can_dlc != 8U) {
        fprintf(stderr, "bench-sdo: node %u: SDO answer with DLC %u\n", node, f.can_dlc);
        return -1;
    }
    memcpy(ans, f.data, 8);
    return t_rx - t_tx;
}

static bool mux_matches(const uint8_t a[8], unsigned index, unsigned sub)
{
    return a[1] == (uint8_t)index && a[2] == (uint8_t)(index >> 8) && a[3] == (uint8_t)sub;
}

static int do_download(unsigned node, unsigned index, unsigned sub, uint8_t size, uint32_t value, int64_t *rtt)
{
    uint8_t req[8];
    uint8_t ans[8];
    sdo_download_req(req, (uint16_t)index, (uint8_t)sub, size, value);
    *rtt = transfer(node, req, ans);
    if (*rtt < 0) {
        return -1;
    }
    if (!any_reply && (ans[0] != 0x60U || !mux_matches(ans, index, sub))) {
        fprintf(stderr, "bench-sdo: node %u: download 0x%04X:%02X = %lu: answer %02X %02X %02X %02X %02X %02X %02X %02X\n",
                node, index, sub, (unsigned long)value, ans[0], ans[1], ans[2], ans[3], ans[4], ans[5], ans[6], ans[7]);
        return -1;
    }
    return 0;
}

static int do_upload(unsigned node, unsigned index, unsigned sub, uint8_t ans[8], int64_t *rtt)
{
    uint8_t req[8];
    sdo_upload_req(req, (uint16_t)index, (uint8_t)sub);
    *rtt = transfer(node, req, ans);
    if (*rtt < 0) {
        return -1;
    }
    if (!any_reply && ((ans[0] & 0xE2U) != 0x42U || !mux_matches(ans, index, sub))) {
        fprintf(stderr, "bench-sdo: node %u: upload 0x%04X:%02X: answer %02X %02X %02X %02X %02X %02X %02X %02X\n", node,
                index, sub, ans[0], ans[1], ans[2], ans[3], ans[4], ans[5], ans[6], ans[7]);
        return -1;
    }
    return 0;
}

static int cmd_ready(unsigned a, unsigned b, int64_t drain_ms)
{
    uint8_t req[8];
    struct can_frame f;
    int64_t t;
    sdo_upload_req(req, 0x1000U, 0U);
    const int64_t give_up = bench_mono_ns() + 120LL * 1000000000LL; /* valgrind in UML starts slowly */
    int r = 0;
    while (r == 0) {
        if (bench_can_send(&can, 0x600U + a, 8U, req) != 0) {
            return -1;
        }
        int64_t until = bench_mono_ns() + 500000000LL;
        if (until > give_up) {
            until = give_up;
        }
        r = wait_id(0x580U + a, until, &f, &t);
        if (r < 0) {
            return -1;
        }
        if (r == 0 && bench_mono_ns() >= give_up) {
            fprintf(stderr, "bench-sdo: node %u did not answer within 120 s\n", a);
            return -1;
        }
    }
    /* The server runs its loop only after every node is up: the others answer at once. */
    for (unsigned n = a + 1U; n <= b; n++) {
        if (bench_can_send(&can, 0x600U + n, 8U, req) != 0) {
            return -1;
        }
        if (wait_id(0x580U + n, bench_mono_ns() + timeout_ns, &f, &t) <= 0) {
            fprintf(stderr, "bench-sdo: node %u did not answer\n", n);
            return -1;
        }
    }
    const int64_t end = bench_mono_ns() + drain_ms * 1000000LL;
    while (bench_can_recv(&can, &f, &t, end) == 1) {
        count(&f);
    }
    return 0;
}

static result_t *new_result(const char *op, unsigned node, unsigned index, unsigned sub)
{
    if (n_results == sizeof results / sizeof results[0]) {
        fprintf(stderr, "bench-sdo: too many measurements\n");
        exit(2);
    }
    result_t *r = &results[n_results++];
    memset(r, 0, sizeof *r);
    (void)snprintf(r->op, sizeof r->op, "%s", op);
    r->node = node;
    r->index = index;
    r->sub = sub;
    return r;
}

static void print_json(void)
{
    printf("{\"sdo_answers\": %lu, \"rx_drops\": %lu, \"results\": [", sdo_answers, (unsigned long)can.drops);
    for (size_t i = 0U; i < n_results; i++) {
        result_t *r = &results[i];
        printf("%s{\"op\": \"%s\", \"node\": %u, \"index\": %u, \"sub\": %u, ", i > 0U ? ", " : "", r->op, r->node, r->index,
               r->sub);
        json_stats(stdout, "rtt_us", &r->rtt_ns, 1e-3, true);
        printf("}");
    }
    printf("], \"frames\": {");
    bool first = true;
    for (unsigned id = 0U; id < 2048U; id++) {
        if (counts[id] > 0U) {
            printf("%s\"0x%03X\": %lu", first ? "" : ", ", id, counts[id]);
            first = false;
        }
    }
    printf("}}\n");
}

static void need(int argc, int i, int n, const char *cmd)
{
    if (i + n >= argc) {
        fprintf(stderr, "bench-sdo: '%s' needs %d argument(s)\n", cmd, n);
        exit(2);
    }
}

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    int i = 1;
    for (; i < argc && argv[i][0] == '-'; i++) {
        if (strcmp(argv[i], "-i") == 0 && i + 1 < argc) {
            iface = argv[++i];
        } else if (strcmp(argv[i], "--any-reply") == 0) {
            any_reply = true;
        } else if (strcmp(argv[i], "--user-time") == 0) {
            user_time = true;
        } else if (strcmp(argv[i], "--gap-ms") == 0 && i + 1 < argc) {
            gap_ns = bench_num(argv[++i], 0, 60000, "gap") * 1000000LL;
        } else if (strcmp(argv[i], "--timeout-ms") == 0 && i + 1 < argc) {
            timeout_ns = bench_num(argv[++i], 1, 600000, "timeout") * 1000000LL;
        } else {
            fprintf(stderr, "usage: bench-sdo [-i IFACE] [--any-reply] [--user-time] [--gap-ms MS] [--timeout-ms MS] COMMAND ARGS...\n");
            return 2;
        }
    }
    if (bench_can_open(&can, iface, 4 * 1024 * 1024) != 0) {
        return 1;
    }
    can.user_time = can.user_time || user_time;
    int status = 0;
    while (i < argc && status == 0) {
        const char *cmd = argv[i];
        unsigned index;
        unsigned sub;
        int64_t rtt;
        uint8_t ans[8];
        if (strcmp(cmd, "ready") == 0) {
            need(argc, i, 1, cmd);
            long long a;
            long long b;
            bench_range(argv[i + 1], 1, 127, &a, &b, "node range");
            int64_t drain = 300;
            int used = 2;
            if (i + 2 < argc && argv[i + 2][0] >= '0' && argv[i + 2][0] <= '9') {
                drain = bench_num(argv[i + 2], 0, 60000, "drain time");
                used = 3;
            }
            status = cmd_ready((unsigned)a, (unsigned)b, drain);
            i += used;
        } else if (strcmp(cmd, "w") == 0) {
            need(argc, i, 4, cmd);
            const unsigned node = (unsigned)bench_num(argv[i + 1], 1, 127, "node");
            parse_mux(argv[i + 2], &index, &sub);
            const uint8_t size = (uint8_t)bench_num(argv[i + 3], 1, 4, "size");
            const uint32_t value = (uint32_t)bench_num(argv[i + 4], 0, 0xFFFFFFFFLL, "value");
            status = do_download(node, index, sub, size, value, &rtt);
            i += 5;
        } else if (strcmp(cmd, "r") == 0) {
            need(argc, i, 2, cmd);
            const unsigned node = (unsigned)bench_num(argv[i + 1], 1, 127, "node");
            parse_mux(argv[i + 2], &index, &sub);
            status = do_upload(node, index, sub, ans, &rtt);
            if (status == 0) {
                fprintf(stderr, "bench-sdo: node %u 0x%04X:%02X = 0x%02X%02X%02X%02X\n", node, index, sub, ans[7], ans[6],
                        ans[5], ans[4]);
            }
            i += 3;
        } else if (strcmp(cmd, "nmt") == 0) {
            need(argc, i, 2, cmd);
            const uint8_t d[2] = {(uint8_t)bench_num(argv[i + 1], 1, 255, "NMT command"),
                                  (uint8_t)bench_num(argv[i + 2], 0, 127, "node")};
            status = bench_can_send(&can, 0U, 2U, d);
            i += 3;
        } else if (strcmp(cmd, "sleep") == 0) {
            need(argc, i, 1, cmd);
            const int64_t end = bench_mono_ns() + bench_num(argv[i + 1], 0, 3600000, "sleep") * 1000000LL;
            struct can_frame f;
            int64_t t;
            int r;
            while ((r = bench_can_recv(&can, &f, &t, end)) == 1) {
                count(&f);
            }
            status = r < 0 ? -1 : 0;
            i += 2;
        } else if (strcmp(cmd, "up") == 0) {
            need(argc, i, 3, cmd);
            const unsigned node = (unsigned)bench_num(argv[i + 1], 1, 127, "node");
            parse_mux(argv[i + 2], &index, &sub);
            const long long n = bench_num(argv[i + 3], 1, 100000000, "count");
            result_t *res = new_result("up", node, index, sub);
            uint8_t first[8];
            for (long long k = 0; k < n && status == 0; k++) {
                status = do_upload(node, index, sub, ans, &rtt);
                if (status == 0 && k == 0) {
                    memcpy(first, ans, 8);
                } else if (status == 0 && !any_reply && memcmp(first, ans, 8) != 0) {
                    fprintf(stderr, "bench-sdo: node %u: upload %lld answered differently\n", node, k);
                    status = -1;
                }
                if (status == 0) {
                    samples_add(&res->rtt_ns, (double)rtt);
                    status = pause_gap();
                }
            }
            i += 4;
        } else if (strcmp(cmd, "down") == 0) {
            need(argc, i, 5, cmd);
            const unsigned node = (unsigned)bench_num(argv[i + 1], 1, 127, "node");
            parse_mux(argv[i + 2], &index, &sub);
            const uint8_t size = (uint8_t)bench_num(argv[i + 3], 1, 4, "size");
            const uint32_t value = (uint32_t)bench_num(argv[i + 4], 0, 0xFFFFFFFFLL, "value");
            const long long n = bench_num(argv[i + 5], 1, 100000000, "count");
            result_t *res = new_result("down", node, index, sub);
            for (long long k = 0; k < n && status == 0; k++) {
                status = do_download(node, index, sub, size, value, &rtt);
                if (status == 0) {
                    samples_add(&res->rtt_ns, (double)rtt);
                    status = pause_gap();
                }
            }
            i += 6;
        } else {
            fprintf(stderr, "bench-sdo: unknown command '%s'\n", cmd);
            return 2;
        }
    }
    print_json();
    bench_can_close(&can);
    return status == 0 ? 0 : 1;
}
