/*
 * bench-services: instructions per service call of the core, without sockets (docs/performance.md).
 *
 *   bench-services [N]          (N iterations per service, default 10000)
 *   valgrind --tool=callgrind --callgrind-out-file=F bench-services N
 *
 * One node of the Bürkert flow controller's object dictionary (the largest of the three: the binary
 * searches of co_od are deepest there) on the core alone: no device model, no hooks, a port whose send
 * only counts, simulated time. Each service runs in its own loop of N iterations, and each iteration is
 * one complete call as a runner makes it: co_node_rx(frame) and then co_node_process(now), or what the
 * service needs instead (a trigger, a due time). Under callgrind every loop is framed by
 * CALLGRIND_ZERO_STATS and CALLGRIND_DUMP_STATS_AT(name): one profile dump per service, whose total
 * divided by N is the cost of one call (the driver subtracts the "harness" loop, which does everything
 * but call the core). Outside valgrind the same program prints ns per call from CLOCK_MONOTONIC, which
 * is only indicative. It checks that every loop sent exactly the frames the service must send and exits
 * 1 otherwise, so a figure never describes a service that silently did nothing.
 *
 * Output: one line per service "name iterations frames ns_per_call" (then JSON-free: the driver parses
 * the callgrind dumps for the instruction counts).
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "buerkert_fc_od.h"
#include "co/co.h"

#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define HAVE_CALLGRIND 1
#endif
#endif
#ifndef HAVE_CALLGRIND
#define CALLGRIND_ZERO_STATS
#define CALLGRIND_DUMP_STATS_AT(name) ((void)(name))
#endif

#define NODE_ID 1U

typedef struct bench_port {
    unsigned long frames;
    unsigned long sdo_answers;
    co_frame_t last_sdo; /* the last SDO answer (other frames may follow it, e.g. a TPDO a write caused) */
} bench_port_t;

static co_node_t node;
static buerkert_fc_od_values_t values;
static bench_port_t port_state;
static co_time_us_t now_us = 1000000U;

static co_status_t port_send(void *ctx, const co_frame_t *f)
{
    bench_port_t *p = (bench_port_t *)ctx;
    p->frames++;
    if (f->id == 0x580U + NODE_ID) {
        p->sdo_answers++;
        p->last_sdo = *f;
    }
    return CO_OK;
}

static co_frame_t frame(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    return f;
}

static void rx_process(const co_frame_t *f)
{
    if (co_node_rx(&node, f, now_us)) {
        (void)co_node_process(&node, now_us);
    }
}

/* Setup writes go through the SDO server like a master's, so every protocol rule applies. */
static void sdo_write(uint16_t index, uint8_t sub, uint8_t size, uint32_t value)
{
    uint8_t d[8] = {(uint8_t)(0x23U | ((4U - size) << 2)), (uint8_t)index, (uint8_t)(index >> 8), sub,
                    (uint8_t)value, (uint8_t)(value >> 8), (uint8_t)(value >> 16), (uint8_t)(value >> 24)};
    const co_frame_t f = frame(0x600U + NODE_ID, 8U, d);
    const unsigned long before = port_state.sdo_answers;
    rx_process(&f);
    const co_frame_t *a = &port_state.last_sdo;
    if (port_state.sdo_answers != before + 1U || a->data[0] != 0x60U) {
        fprintf(stderr, "bench-services: setup write 0x%04X:%02X = %lu refused (answer %02X, abort 0x%02X%02X%02X%02X)\n",
                index, sub, (unsigned long)value, a->data[0], a->data[7], a->data[6], a->data[5], a->data[4]);
        exit(1);
    }
}

static int64_t mono_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
}

typedef enum svc {
    SVC_HARNESS,
    SVC_SDO_UPLOAD,
    SVC_SDO_DOWNLOAD,
    SVC_RPDO,
    SVC_TPDO_EVENT,
    SVC_HEARTBEAT,
    SVC_SYNC_TPDO,
    SVC_NMT,
    SVC_LSS_INQUIRY,
    SVC_FOREIGN,
    SVC_FOREIGN_HB,
    SVC_PROCESS_IDLE,
    SVC_COUNT
} svc_t;

static const char *const svc_name[SVC_COUNT] = {"harness", "sdo_upload", "sdo_download", "rpdo_receive", "tpdo_event",
                                                "heartbeat", "sync_tpdo", "nmt_command", "lss_inquiry",
                                                "foreign_frame", "foreign_heartbeat", "process_idle"};
/* Frames each call must send. */
static const unsigned svc_frames[SVC_COUNT] = {0U, 1U, 1U, 0U, 1U, 1U, 1U, 0U, 1U, 0U, 0U, 0U};

/* Does nothing, but the compiler cannot know: the harness loop pays for the call like the others. */
__attribute__((noinline)) static void harness_sink(const co_frame_t *f) { __asm__ volatile("" : : "r"(f) : "memory"); }

static int run(svc_t s, long n)
{
    static const uint8_t up[8] = {0x40U, 0x18U, 0x10U, 0x01U, 0U, 0U, 0U, 0U};
    static const uint8_t down[8] = {0x2BU, 0x17U, 0x10U, 0x00U, 0U, 0U, 0U, 0U};
    static const uint8_t flow[4] = {0x00U, 0x00U, 0x80U, 0x3FU}; /* 1.0f, set-point 0x2540:01 */
    static const uint8_t preop[2] = {0x80U, NODE_ID};
    static const uint8_t start[2] = {0x01U, NODE_ID};
    static const uint8_t inquire[8] = {0x5EU, 0U, 0U, 0U, 0U, 0U, 0U, 0U};
    const co_frame_t f_up = frame(0x600U + NODE_ID, 8U, up);
    const co_frame_t f_down = frame(0x600U + NODE_ID, 8U, down);
    const co_frame_t f_rpdo = frame(0x200U + NODE_ID, 4U, flow);
    const co_frame_t f_sync = frame(0x080U, 0U, NULL);
    const co_frame_t f_preop = frame(0x000U, 2U, preop);
    const co_frame_t f_start = frame(0x000U, 2U, start);
    const co_frame_t f_lss = frame(0x7E5U, 8U, inquire);
    const co_frame_t f_foreign = frame(0x600U + NODE_ID + 1U, 8U, up);
    static const uint8_t operational = 0x05U;
    const co_frame_t f_foreign_hb = frame(0x700U + NODE_ID + 1U, 1U, &operational);

    /* Per-service setup, outside the measured loop. */
    if (s == SVC_HEARTBEAT) {
        sdo_write(0x1017U, 0U, 2U, 1U); /* 1 ms: the loop steps time to each deadline */
        now_us = co_node_process(&node, now_us);
    } else if (s == SVC_SYNC_TPDO) {
        sdo_write(0x1800U, 2U, 1U, 1U); /* synchronous, every SYNC */
    } else if (s == SVC_LSS_INQUIRY) {
        static const uint8_t global_cfg[8] = {0x04U, 0x01U, 0U, 0U, 0U, 0U, 0U, 0U};
        const co_frame_t f = frame(0x7E5U, 8U, global_cfg);
        rx_process(&f);
    }
    const unsigned long frames0 = port_state.frames;
    const int64_t t0 = mono_ns();
    CALLGRIND_ZERO_STATS;
    for (long i = 0; i < n; i++) {
        switch (s) {
        case SVC_HARNESS:
            harness_sink(&f_up);
            break;
        case SVC_SDO_UPLOAD:
            rx_process(&f_up);
            break;
        case SVC_SDO_DOWNLOAD:
            rx_process(&f_down);
            break;
        case SVC_RPDO:
            rx_process(&f_rpdo);
            break;
        case SVC_TPDO_EVENT:
            co_tpdo_trigger(&node, 0U);
            (void)co_node_process(&node, now_us);
            break;
        case SVC_HEARTBEAT:
            now_us = co_node_process(&node, now_us); /* sends the heartbeat due now, returns the next one */
            break;
        case SVC_SYNC_TPDO:
            rx_process(&f_sync);
            break;
        case SVC_NMT:
            rx_process((i & 1) == 0 ? &f_preop : &f_start);
            break;
        case SVC_LSS_INQUIRY:
            rx_process(&f_lss);
            break;
        case SVC_FOREIGN:
            rx_process(&f_foreign); /* co_node_rx says "not mine": no processing, as canopen-emu does */
            break;
        case SVC_FOREIGN_HB:
            rx_process(&f_foreign_hb); /* another node's heartbeat, not monitored here (0x1016 empty) */
            break;
        case SVC_PROCESS_IDLE:
            (void)co_node_process(&node, now_us);
            break;
        default:
            break;
        }
    }
    CALLGRIND_DUMP_STATS_AT(svc_name[s]);
    const int64_t t1 = mono_ns();
    unsigned long expect = svc_frames[s] * (unsigned long)n;
    if (s == SVC_NMT) {
        expect = (unsigned long)n / 2U; /* every start sends TPDO1 once (entering Operational) */
    }
    const unsigned long sent = port_state.frames - frames0;
    printf("%s %ld %lu %.1f\n", svc_name[s], n, sent, (double)(t1 - t0) / (double)n);
    if (s == SVC_HEARTBEAT) {
        sdo_write(0x1017U, 0U, 2U, 0U);
    } else if (s == SVC_SYNC_TPDO) {
        sdo_write(0x1800U, 2U, 1U, 0xFEU);
    } else if (s == SVC_LSS_INQUIRY) {
        static const uint8_t global_wait[8] = {0x04U, 0x00U, 0U, 0U, 0U, 0U, 0U, 0U};
        const co_frame_t f = frame(0x7E5U, 8U, global_wait);
        rx_process(&f);
    }
    if (sent != expect || co_node_state(&node) != CO_NMT_OPERATIONAL) {
        fprintf(stderr, "bench-services: %s: %lu frames sent, %lu expected (state %s)\n", svc_name[s], sent, expect,
                co_nmt_state_name(co_node_state(&node)));
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    long n = 10000;
    if (argc > 1) {
        n = strtol(argv[1], NULL, 0);
        if (n < 2 || (n & 1) != 0) {
            fprintf(stderr, "usage: bench-services [N]   (N even, >= 2)\n");
            return 2;
        }
    }
    static const co_port_t port = {port_send, NULL, NULL, NULL, NULL};
    co_node_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.od = &buerkert_fc_od;
    cfg.values = &values;
    cfg.port = &port;
    cfg.port_ctx = &port_state;
    cfg.node_id = NODE_ID;
    cfg.bit_timing = 4U;
    cfg.options = CO_OPT_SDO_SEGMENTED | CO_OPT_LSS_NO_UNCONFIGURE; /* as the Bürkert device runs it */
    if (co_node_init(&node, &cfg, now_us) != CO_OK) {
        fprintf(stderr, "bench-services: co_node_init failed\n");
        return 1;
    }
    (void)co_node_process(&node, now_us);
    /* Quiet node: no heartbeat, TPDO1 without inhibit time or event timer (it sends when asked to). */
    sdo_write(0x1017U, 0U, 2U, 0U);
    sdo_write(0x1800U, 1U, 4U, 0x80000180UL + NODE_ID);
    sdo_write(0x1800U, 3U, 2U, 0U);
    sdo_write(0x1800U, 5U, 2U, 0U);
    sdo_write(0x1800U, 1U, 4U, 0x180UL + NODE_ID);
    const co_frame_t f_start = frame(0x000U, 2U, (const uint8_t[]){0x01U, NODE_ID});
    rx_process(&f_start);
    if (co_node_state(&node) != CO_NMT_OPERATIONAL || !node.rpdo[0].valid || !node.tpdo[0].valid) {
        fprintf(stderr, "bench-services: the node is not operational with RPDO1 and TPDO1 valid\n");
        return 1;
    }
    printf("# service iterations frames ns_per_call\n");
    int status = 0;
    for (int s = 0; s < (int)SVC_COUNT; s++) {
        status |= run((svc_t)s, n);
    }
    return status;
}
