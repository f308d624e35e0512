/* Protocol fault injection: see emu_faults.h and docs/emulator.md "Protocol faults". */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "faults/emu_faults.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/emu.h"
#include "runtime/emu_bus.h"
#include "runtime/emu_events.h"
#include "runtime/emu_output.h"

static uint32_t bit(fault_kind_t k) { return (uint32_t)1U << (unsigned)k; }

void faults_init(node_faults_t *f)
{
    memset(f, 0, sizeof *f);
    for (unsigned i = 0U; i < CO_TPDO_MAX; i++) {
        f->tpdo[i].length = -1;
    }
}

/* xorshift64: a share of requests ignored, or a jitter, repeats with its seed. */
static uint64_t next_random(node_faults_t *f)
{
    uint64_t x = f->rng != 0U ? f->rng : UINT64_C(0x9E3779B97F4A7C15);
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    f->rng = x;
    return x;
}

/* ---- The node's COB-IDs, as its object dictionary has them now --------------------------------------------- */

static uint32_t od_cob(struct emu_node *n, uint16_t index, uint8_t sub, uint32_t fallback)
{
    co_node_t *node = &n->dev.node;
    co_od_entry_t one;
    if (co_od_find(n->dev.cls->od, index, sub, &one) == NULL) {
        return fallback;
    }
    const uint32_t v = co_od_get_u32(node, index, sub);
    return (v & 0x80000000UL) != 0U ? UINT32_MAX : (v & 0x7FFU); /* not valid: matches no frame */
}

static uint32_t sdo_request_cob(struct emu_node *n) { return od_cob(n, 0x1200U, 1U, 0x600U + co_node_id(&n->dev.node)); }
static uint32_t sdo_answer_cob(struct emu_node *n) { return od_cob(n, 0x1200U, 2U, 0x580U + co_node_id(&n->dev.node)); }

static int tpdo_of(struct emu_node *n, const co_frame_t *f)
{
    if ((f->flags & CO_FRAME_RTR) != 0U) {
        return -1;
    }
    for (uint8_t i = 0U; i < n->dev.node.n_tpdo && i < CO_TPDO_MAX; i++) {
        if (od_cob(n, (uint16_t)(0x1800U + i), 1U, UINT32_MAX) == f->id) {
            return i;
        }
    }
    return -1;
}

static bool bus_off(const node_faults_t *f, co_time_us_t now)
{
    return (f->active & bit(FAULT_BUS_OFF)) != 0U && now < f->bus_off_until;
}

/* ---- Frames ----------------------------------------------------------------------------------------------- */

static void hold(node_faults_t *f, const co_frame_t *frame, co_time_us_t due)
{
    f->delayed[f->n_delayed].due = due;
    f->delayed[f->n_delayed].frame = *frame;
    f->n_delayed++;
}

bool faults_rx(struct emu_node *n, const co_frame_t *frame, co_time_us_t now)
{
    node_faults_t *f = &n->faults;
    if (f->active == 0U) {
        return true;
    }
    if (bus_off(f, now) || ((f->active & bit(FAULT_LSS_SILENT)) != 0U && frame->id == 0x7E5U)) {
        f->dropped++;
        return false;
    }
    if ((frame->flags & CO_FRAME_RTR) != 0U || frame->id != sdo_request_cob(n) || frame->len == 0U) {
        return true;
    }
    if ((f->active & bit(FAULT_SDO_IGNORE)) != 0U && (frame->data[0] >> 5) != 4U) {
        /* A client's abort (ccs 4) expects no answer: it is no request to ignore, and passes. */
        bool ignore;
        if (f->sdo_ignore_ppm != 0U) {
            ignore = next_random(f) % 1000000U < f->sdo_ignore_ppm;
        } else {
            ignore = f->sdo_ignore_left > 0U;
            if (ignore && --f->sdo_ignore_left == 0U) {
                f->active &= ~bit(FAULT_SDO_IGNORE); /* the N requests have been ignored: the fault is over */
            }
        }
        if (ignore) {
            f->dropped++;
            return false;
        }
    }
    if ((f->active & bit(FAULT_SDO_ABORT)) != 0U && frame->len >= 4U) {
        const uint8_t ccs = (uint8_t)(frame->data[0] >> 5);
        const uint16_t index = (uint16_t)(frame->data[1] | (frame->data[2] << 8));
        const bool initiate = ccs == 1U || ccs == 2U || ccs == 5U || ccs == 6U; /* download, upload, block */
        if (initiate && index == f->abort_index && (f->abort_whole_object || frame->data[3] == f->abort_sub)) {
            co_frame_t a;
            memset(&a, 0, sizeof a);
            a.id = sdo_answer_cob(n);
            a.len = 8U;
            a.data[0] = 0x80U;
            memcpy(&a.data[1], &frame->data[1], 3U);
            for (unsigned i = 0U; i < 4U; i++) {
                a.data[4U + i] = (uint8_t)(f->abort_code >> (8U * i));
            }
            if (faults_tx(n, &a, now) == FAULT_TX_SEND) { /* an sdo-delay holds it like any answer */
                (void)bus_send(n->bus, n, &a);
            }
            return false;
        }
    }
    return true;
}

fault_tx_t faults_tx(struct emu_node *n, co_frame_t *frame, co_time_us_t now)
{
    node_faults_t *f = &n->faults;
    if (f->active == 0U) {
        return FAULT_TX_SEND;
    }
    if (bus_off(f, now) || ((f->active & bit(FAULT_LSS_SILENT)) != 0U && frame->id == 0x7E4U)) {
        f->dropped++;
        return FAULT_TX_DROP;
    }
    const bool heartbeat = frame->id == 0x700U + co_node_id(&n->dev.node) && frame->len == 1U &&
                           (frame->flags & CO_FRAME_RTR) == 0U && frame->data[0] != 0x00U; /* not the boot-up */
    if (heartbeat) {
        if ((f->active & bit(FAULT_HB_STOP)) != 0U) {
            f->dropped++;
            return FAULT_TX_DROP;
        }
        if ((f->active & bit(FAULT_HB_STATE)) != 0U) {
            frame->data[0] = f->hb_state;
        }
        if ((f->active & bit(FAULT_HB_JITTER)) != 0U && f->n_delayed < FAULT_DELAYED_MAX) {
            hold(f, frame, now + next_random(f) % ((co_time_us_t)f->hb_jitter_ms * 1000U + 1U));
            return FAULT_TX_HELD;
        }
        return FAULT_TX_SEND;
    }
    if ((f->active & bit(FAULT_SDO_DELAY)) != 0U && frame->id == sdo_answer_cob(n) && f->n_delayed < FAULT_DELAYED_MAX) {
        hold(f, frame, now + (co_time_us_t)f->sdo_delay_ms * 1000U);
        return FAULT_TX_HELD;
    }
    const int t = (f->active & (bit(FAULT_TPDO_FREEZE) | bit(FAULT_TPDO_DROP) | bit(FAULT_TPDO_LENGTH))) != 0U ? tpdo_of(n, frame) : -1;
    if (t >= 0) {
        fault_tpdo_t *p = &f->tpdo[t];
        if (p->drop_every != 0U && ++p->drop_count >= p->drop_every) {
            p->drop_count = 0U;
            f->dropped++;
            return FAULT_TX_DROP;
        }
        if (p->freeze) {
            if (!p->have_frozen) {
                memcpy(p->frozen, frame->data, sizeof p->frozen);
                p->frozen_len = frame->len;
                p->have_frozen = true;
            }
            memcpy(frame->data, p->frozen, sizeof p->frozen);
            frame->len = p->frozen_len;
        }
        if (p->length >= 0) {
            for (uint8_t i = frame->len; i < 8U; i++) {
                frame->data[i] = 0U;
            }
            frame->len = (uint8_t)p->length;
        }
    }
    return FAULT_TX_SEND;
}

co_time_us_t faults_run(struct emu_node *n, co_time_us_t now)
{
    node_faults_t *f = &n->faults;
    /* Held frames in the order they are due (a heartbeat with jitter may overtake an older one, as it would). */
    for (;;) {
        uint32_t first = f->n_delayed;
        for (uint32_t i = 0U; i < f->n_delayed; i++) {
            if (f->delayed[i].due <= now && (first == f->n_delayed || f->delayed[i].due < f->delayed[first].due)) {
                first = i;
            }
        }
        if (first == f->n_delayed) {
            break;
        }
        const co_frame_t frame = f->delayed[first].frame;
        f->delayed[first] = f->delayed[--f->n_delayed];
        if (bus_off(f, now)) {
            f->dropped++;
        } else {
            (void)bus_send(n->bus, n, &frame);
        }
    }
    if ((f->active & bit(FAULT_BUS_OFF)) != 0U && now >= f->bus_off_until) {
        /* Back on the bus (CiA 301): the node reports it, error register bit 4 (communication). */
        f->active &= ~bit(FAULT_BUS_OFF);
        const uint8_t msef[5] = {0U, 0U, 0U, 0U, 0U};
        (void)co_emcy_raise(&n->dev.node, 0x8140U, 0x10U, msef);
        node_mark_dirty(n);
        events_fault(n, "bus-off", "ended", "recovered from bus-off: EMCY 0x8140");
    }
    co_time_us_t next = CO_NEVER;
    for (uint32_t i = 0U; i < f->n_delayed; i++) {
        next = f->delayed[i].due < next ? f->delayed[i].due : next;
    }
    if ((f->active & bit(FAULT_BUS_OFF)) != 0U && f->bus_off_until < next) {
        next = f->bus_off_until;
    }
    return next;
}

/* ---- Commands --------------------------------------------------------------------------------------------- */

static unsigned node_id(const struct emu_node *n) { return co_node_id(&n->dev.node); }

static int refuse(const struct emu_node *n, const reply_sink_t *to, const char *usage)
{
    reply(to, "node %u: error: usage: %s", node_id(n), usage);
    return 1;
}

/* "fault NODE sdo-delay MS (1..600000)": a kind's usage in a refusal, from the table the control protocol serves the
 * web view's forms from (fault_kinds.h). One buffer: the program is one thread, and a refusal is written at once. */
static const char *usage_of(fault_kind_t k)
{
    static char text[256];
    const fault_kind_info_t *info = fault_kind_info(k);
    const bool limits = info->limits[0] != '\0';
    (void)snprintf(text, sizeof text, "fault NODE %s%s%s%s%s%s", info->name, info->args[0] != '\0' ? " " : "",
                   info->args, limits ? " (" : "", info->limits, limits ? ")" : "");
    return text;
}

/* "fault NODE KIND [ARGS] (kinds: sdo-ignore ... lss-silent)": what `fault NODE` answers, the kinds of the table. */
static const char *kinds_usage(void)
{
    static char text[512];
    size_t used = (size_t)snprintf(text, sizeof text, "fault NODE KIND [ARGS] (kinds:");
    for (int k = 0; k < (int)FAULT_KIND_COUNT && used < sizeof text; k++) {
        used += (size_t)snprintf(text + used, sizeof text - used, " %s", fault_kind_name((fault_kind_t)k));
    }
    if (used < sizeof text) {
        (void)snprintf(text + used, sizeof text - used, ")");
    }
    return text;
}

/* "30%", "12.5%" -> parts per million (0 < share <= 100 %). */
static bool parse_share(const char *s, uint32_t *ppm)
{
    unsigned long whole = 0U, frac = 0U, scale = 1U;
    const char *p = s;
    if (*p < '0' || *p > '9') {
        return false;
    }
    for (; *p >= '0' && *p <= '9'; p++) {
        whole = whole * 10U + (unsigned long)(*p - '0');
        if (whole > 100U) {
            return false;
        }
    }
    if (*p == '.') {
        for (p++; *p >= '0' && *p <= '9' && scale < 10000U; p++) {
            frac = frac * 10U + (unsigned long)(*p - '0');
            scale *= 10U;
        }
    }
    if (p[0] != '%' || p[1] != '\0') {
        return false;
    }
    const unsigned long v = whole * 10000U + frac * (10000U / scale);
    if (v == 0U || v > 1000000U) {
        return false;
    }
    *ppm = (uint32_t)v;
    return true;
}

static bool tpdo_number(const struct emu_node *n, const char *s, unsigned *t)
{
    long long v;
    if (!device_parse_int(s, 1, CO_TPDO_MAX, &v) || (uint8_t)v > n->dev.node.n_tpdo) {
        return false;
    }
    *t = (unsigned)v - 1U;
    return true;
}

static void describe(struct emu_node *n, fault_kind_t k, co_time_us_t now, const reply_sink_t *to)
{
    const node_faults_t *f = &n->faults;
    const unsigned id = node_id(n);
    switch (k) {
    case FAULT_SDO_IGNORE:
        if (f->sdo_ignore_ppm != 0U) {
            reply(to, "node %u: fault sdo-ignore: %lu.%04lu %% of SDO requests get no answer", id,
                  (unsigned long)(f->sdo_ignore_ppm / 10000U), (unsigned long)(f->sdo_ignore_ppm % 10000U));
        } else {
            reply(to, "node %u: fault sdo-ignore: the next %lu SDO request(s) get no answer", id,
                  (unsigned long)f->sdo_ignore_left);
        }
        break;
    case FAULT_SDO_DELAY:
        reply(to, "node %u: fault sdo-delay: SDO answers %lu ms late", id, (unsigned long)f->sdo_delay_ms);
        break;
    case FAULT_SDO_ABORT:
        if (f->abort_whole_object) {
            reply(to, "node %u: fault sdo-abort: requests for 0x%04X answered with abort 0x%08lX", id, f->abort_index,
                  (unsigned long)f->abort_code);
        } else {
            reply(to, "node %u: fault sdo-abort: requests for 0x%04X:%02X answered with abort 0x%08lX", id, f->abort_index,
                  f->abort_sub, (unsigned long)f->abort_code);
        }
        break;
    case FAULT_HB_STOP:
        reply(to, "node %u: fault heartbeat-stop: no heartbeat (nor node-guarding answer)", id);
        break;
    case FAULT_HB_JITTER:
        reply(to, "node %u: fault heartbeat-jitter: each heartbeat 0..%lu ms late", id, (unsigned long)f->hb_jitter_ms);
        break;
    case FAULT_HB_STATE:
        reply(to, "node %u: fault heartbeat-state: heartbeats say 0x%02X", id, f->hb_state);
        break;
    case FAULT_TPDO_FREEZE:
    case FAULT_TPDO_DROP:
    case FAULT_TPDO_LENGTH:
        for (unsigned t = 0U; t < CO_TPDO_MAX; t++) {
            const fault_tpdo_t *p = &f->tpdo[t];
            if (k == FAULT_TPDO_FREEZE && p->freeze) {
                reply(to, "node %u: fault tpdo-freeze: TPDO%u keeps the data it had%s", id, t + 1U,
                      p->have_frozen ? "" : " (from its next frame)");
            } else if (k == FAULT_TPDO_DROP && p->drop_every != 0U) {
                reply(to, "node %u: fault tpdo-drop: every %lu. frame of TPDO%u dropped", id, (unsigned long)p->drop_every,
                      t + 1U);
            } else if (k == FAULT_TPDO_LENGTH && p->length >= 0) {
                reply(to, "node %u: fault tpdo-length: TPDO%u sent with %d data byte(s)", id, t + 1U, (int)p->length);
            }
        }
        break;
    case FAULT_BUS_OFF:
        reply(to, "node %u: fault bus-off: no frame out or in for %lu ms more", id,
              (unsigned long)((f->bus_off_until > now ? f->bus_off_until - now : 0U) / 1000U));
        break;
    case FAULT_LSS_SILENT:
        reply(to, "node %u: fault lss-silent: no answer to LSS", id);
        break;
    default:
        break;
    }
}

static void list(struct emu_node *n, co_time_us_t now, const reply_sink_t *to)
{
    const node_faults_t *f = &n->faults;
    if (f->active == 0U) {
        reply(to, "node %u: no protocol faults (%lu frame(s) dropped by faults so far)", node_id(n), f->dropped);
        return;
    }
    for (int k = 0; k < (int)FAULT_KIND_COUNT; k++) {
        if ((f->active & bit((fault_kind_t)k)) != 0U) {
            describe(n, (fault_kind_t)k, now, to);
        }
    }
    reply(to, "node %u: %lu frame(s) dropped by faults so far", node_id(n), f->dropped);
}

static void clear_kind(node_faults_t *f, fault_kind_t k, co_time_us_t now)
{
    switch (k) {
    case FAULT_TPDO_FREEZE:
    case FAULT_TPDO_DROP:
    case FAULT_TPDO_LENGTH:
        for (unsigned t = 0U; t < CO_TPDO_MAX; t++) {
            if (k == FAULT_TPDO_FREEZE) {
                f->tpdo[t].freeze = false;
                f->tpdo[t].have_frozen = false;
            } else if (k == FAULT_TPDO_DROP) {
                f->tpdo[t].drop_every = 0U;
                f->tpdo[t].drop_count = 0U;
            } else {
                f->tpdo[t].length = -1;
            }
        }
        break;
    case FAULT_BUS_OFF:
        f->bus_off_until = now; /* recovers at the next run, with its EMCY */
        return;                 /* stays active until then */
    default:
        break;
    }
    f->active &= ~bit(k);
}

static int inject(struct emu_node *n, int argc, char **argv, co_time_us_t now, const reply_sink_t *to)
{
    node_faults_t *f = &n->faults;
    if (argc < 2) {
        return refuse(n, to, kinds_usage());
    }
    const int k = fault_kind_of(argv[1]);
    long long a = 0, b = 0;
    unsigned t = 0U;
    switch (k) {
    case FAULT_SDO_IGNORE:
        f->sdo_ignore_ppm = 0U;
        f->sdo_ignore_left = 1U;
        if (argc >= 3 && strchr(argv[2], '%') != NULL) {
            if (argc > 4 || !parse_share(argv[2], &f->sdo_ignore_ppm) ||
                (argc == 4 && !device_parse_int(argv[3], 0, INT64_MAX, &b))) {
                f->sdo_ignore_ppm = 0U;
                return refuse(n, to, usage_of(FAULT_SDO_IGNORE));
            }
            f->rng = (uint64_t)(argc == 4 ? b : 1);
        } else if (argc > 3 || (argc == 3 && !device_parse_int(argv[2], 1, 1000000, &a))) {
            return refuse(n, to, usage_of(FAULT_SDO_IGNORE));
        } else if (argc == 3) {
            f->sdo_ignore_left = (uint32_t)a;
        }
        break;
    case FAULT_SDO_DELAY:
        if (argc != 3 || !device_parse_int(argv[2], 1, 600000, &a)) {
            return refuse(n, to, usage_of(FAULT_SDO_DELAY));
        }
        f->sdo_delay_ms = (uint32_t)a;
        break;
    case FAULT_SDO_ABORT: {
        uint16_t index;
        uint8_t sub;
        if (argc != 4 || !device_parse_address(argv[2], &index, &sub) || !device_parse_int(argv[3], 1, 0xFFFFFFFFLL, &a)) {
            return refuse(n, to, usage_of(FAULT_SDO_ABORT));
        }
        f->abort_index = index;
        f->abort_sub = sub;
        f->abort_whole_object = strchr(argv[2], ':') == NULL;
        f->abort_code = (uint32_t)a;
        break;
    }
    case FAULT_HB_STOP:
    case FAULT_LSS_SILENT:
        if (argc != 2) {
            return refuse(n, to, usage_of((fault_kind_t)k));
        }
        break;
    case FAULT_HB_JITTER:
        if (argc != 3 || !device_parse_int(argv[2], 1, 60000, &a)) {
            return refuse(n, to, usage_of(FAULT_HB_JITTER));
        }
        f->hb_jitter_ms = (uint32_t)a;
        f->rng = f->rng != 0U ? f->rng : 1U;
        break;
    case FAULT_HB_STATE:
        if (argc != 3 || !device_parse_int(argv[2], 0, 0xFF, &a)) {
            return refuse(n, to, usage_of(FAULT_HB_STATE));
        }
        f->hb_state = (uint8_t)a;
        break;
    case FAULT_TPDO_FREEZE:
        if (argc != 3 || !tpdo_number(n, argv[2], &t)) {
            return refuse(n, to, usage_of(FAULT_TPDO_FREEZE));
        }
        f->tpdo[t].freeze = true;
        f->tpdo[t].have_frozen = false;
        break;
    case FAULT_TPDO_DROP:
        if (argc != 4 || !tpdo_number(n, argv[2], &t) || !device_parse_int(argv[3], 1, 1000000, &a)) {
            return refuse(n, to, usage_of(FAULT_TPDO_DROP));
        }
        f->tpdo[t].drop_every = (uint32_t)a;
        f->tpdo[t].drop_count = 0U;
        break;
    case FAULT_TPDO_LENGTH:
        if (argc != 4 || !tpdo_number(n, argv[2], &t) || !device_parse_int(argv[3], 0, 8, &a)) {
            return refuse(n, to, usage_of(FAULT_TPDO_LENGTH));
        }
        f->tpdo[t].length = (int16_t)a;
        break;
    case FAULT_EMCY_BURST: {
        if (argc < 3 || argc > 4 || !device_parse_int(argv[2], 1, 100, &a) ||
            (argc == 4 && !device_parse_int(argv[3], 0, 0xFFFF, &b))) {
            return refuse(n, to, usage_of(FAULT_EMCY_BURST));
        }
        const uint32_t cob = od_cob(n, 0x1014U, 0U, 0x80U + node_id(n));
        const uint16_t code = (uint16_t)(argc == 4 ? b : 0x1000);
        unsigned long sent = 0U;
        for (long long i = 0; i < a && cob != UINT32_MAX; i++) {
            /* Raw frames past the core (its inhibit time, 0x1001, 0x1003 see none of them): a device gone wild. */
            co_frame_t e;
            memset(&e, 0, sizeof e);
            e.id = cob;
            e.len = 8U;
            e.data[0] = (uint8_t)code;
            e.data[1] = (uint8_t)(code >> 8);
            e.data[2] = (uint8_t)(co_od_get_u8(&n->dev.node, 0x1001U, 0U) | 0x01U);
            e.data[3] = (uint8_t)i; /* the burst's sequence, in the first manufacturer byte */
            if (faults_tx(n, &e, now) == FAULT_TX_SEND && bus_send(n->bus, n, &e) == CO_OK) {
                sent++;
            }
        }
        reply(to, "node %u: fault emcy-burst: %lu of %lld EMCY frame(s) 0x%04X sent", node_id(n), sent, a, code);
        events_fault(n, "emcy-burst", "injected", "EMCY burst sent");
        return 0;
    }
    case FAULT_REBOOT:
        if (argc != 2) {
            return refuse(n, to, usage_of(FAULT_REBOOT));
        }
        events_fault(n, "reboot", "injected", "silent reboot (brown-out): the node restarts and sends its boot-up");
        if (device_power_cycle(&n->dev, now) != CO_OK) {
            reply(to, "node %u: error: the node did not restart", node_id(n));
            return 1;
        }
        node_mark_dirty(n);
        reply(to, "node %u: fault reboot: restarted", node_id(n));
        return 0;
    case FAULT_BUS_OFF:
        if (argc != 3 || !device_parse_int(argv[2], 1, 3600000, &a)) {
            return refuse(n, to, usage_of(FAULT_BUS_OFF));
        }
        f->bus_off_until = now + (co_time_us_t)a * 1000U;
        node_mark_dirty(n); /* its deadline now includes the recovery */
        break;
    default:
        reply(to, "node %u: error: unknown fault '%s' (try: fault %u)", node_id(n), argv[1], node_id(n));
        return 1;
    }
    f->active |= bit((fault_kind_t)k);
    node_mark_dirty(n);
    describe(n, (fault_kind_t)k, now, to);
    char text[160];
    (void)snprintf(text, sizeof text, "fault %s injected", argv[1]);
    events_fault(n, argv[1], "injected", text);
    return 0;
}

int faults_command(struct emu_node *n, int argc, char **argv, co_time_us_t now, const reply_sink_t *to)
{
    if (strcmp(argv[0], "faults") == 0) {
        if (argc != 1) {
            return refuse(n, to, "faults NODE");
        }
        list(n, now, to);
        return 0;
    }
    if (strcmp(argv[0], "fault-clear") == 0) {
        int k = -1;
        if (argc > 2 || (argc == 2 && strcmp(argv[1], "all") != 0 && (k = fault_kind_of(argv[1])) < 0)) {
            return refuse(n, to, "fault-clear NODE [KIND | all]");
        }
        for (int i = 0; i < (int)FAULT_KIND_COUNT; i++) {
            if ((k < 0 || k == i) && (n->faults.active & bit((fault_kind_t)i)) != 0U) {
                clear_kind(&n->faults, (fault_kind_t)i, now);
                if (i != FAULT_BUS_OFF) {
                    events_fault(n, fault_kind_name((fault_kind_t)i), "cleared", "fault cleared");
                }
            }
        }
        node_mark_dirty(n);
        reply(to, "node %u: fault-clear: %s", node_id(n), k < 0 ? "all faults cleared" : "cleared");
        return 0;
    }
    return inject(n, argc, argv, now, to);
}
