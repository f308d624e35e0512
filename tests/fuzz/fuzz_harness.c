/*
 * The fuzzing engine: decodes the input (format in docs/fuzzing.md) into calls on one node and checks the
 * invariants after every call. A violation prints "==fuzz== INVARIANT VIOLATION ..." and aborts, so
 * libFuzzer keeps the input as a crash.
 *
 * Invariants (docs/fuzzing.md has the reasoning):
 *  - frames on the bus: well-formed 11-bit data frames; each belongs to a service of the node (LSS, boot-up,
 *    heartbeat, guard reply, SDO, EMCY, TPDO) and that service may send in the NMT state of the moment and
 *    from that kind of call; nothing but LSS while the node-ID is unconfigured; nothing during the silence of
 *    an LSS bit-rate switch;
 *  - SDO: at most one response per request, exactly one when the node is Pre-operational/Operational and the
 *    port takes the frame at once; responses from process calls only as the timeout abort of an open
 *    transfer; over the whole run never more responses than requests plus timeouts;
 *  - NMT: a command has its effect, other frames and process calls do not change the state or node-ID;
 *    the state is one of the four legal values, INITIALISING exactly while the node-ID is unconfigured;
 *  - bounded internal counters (TX queue, EMCY queue and active list, SDO buffer position, LSS indices);
 *  - 0x1001 is the OR of the active errors' bits (+ bit 0); 0x1003:00 never exceeds the array;
 *  - read-only rows (no CO_OD_WRITE) never change, except 0x1001/0x1003, the target's exempt rows, local
 *    writes of the application/commands, and re-initialisation at resets (then: the power-on value, the
 *    node-ID-relative rows moved to the new node-ID, stored rows as loaded);
 *  - deadlines: process never returns a time before now; returning now is allowed once, the next call at
 *    the same time must return a later deadline (otherwise a main loop spins).
 */
#include <stdarg.h>
#include <string.h>

#include "fuzz_abort.h"
#include "fuzz.h"
#include "priv/co_priv.h" /* enum co_sdo_state: the SDO server's states the oracle tells apart */

#define FZ_TIME_MAX (UINT64_C(1) << 60) /* 36,000 years: far below any overflow of now + period */
#define FZ_MAX_RECORDS 3000U
#define FZ_LOOP_BUDGET 20000U
#define FZ_LOOP_CAP 16U
#define FZ_SLOW_JUMP (UINT64_C(600) * 1000000U) /* "sds-catch-up": time steps capped at 10 minutes */

static fz_t g_fz; /* libFuzzer runs one input at a time */
static co_status_t (*g_fake_send)(void *ctx, const co_frame_t *frame);

/* ---- Input ------------------------------------------------------------------------------------------- */

uint8_t fz_u8(fz_in_t *in) { return in->pos < in->n ? in->p[in->pos++] : 0U; }
uint16_t fz_u16(fz_in_t *in)
{
    const uint16_t lo = fz_u8(in);
    return (uint16_t)(lo | (uint16_t)(fz_u8(in) << 8));
}
uint32_t fz_u32(fz_in_t *in)
{
    const uint32_t lo = fz_u16(in);
    return lo | ((uint32_t)fz_u16(in) << 16);
}
uint64_t fz_u64(fz_in_t *in)
{
    const uint64_t lo = fz_u32(in);
    return lo | ((uint64_t)fz_u32(in) << 32);
}

/* ---- Known bugs --------------------------------------------------------------------------------------------
 * FUZZ_IGNORE=tag,tag,... (environment) switches off the check of a known, reported bug so that a long run
 * can look for others; by default every check is on. Tags: docs/fuzzing.md, "Known bugs". */

bool fz_known(const char *tag)
{
    static const char *list;
    static bool looked;
    if (!looked) {
        list = getenv("FUZZ_IGNORE");
        looked = true;
    }
    const size_t n = strlen(tag);
    for (const char *p = list; p != NULL && *p != '\0';) {
        const char *end = strchr(p, ',');
        const size_t l = end != NULL ? (size_t)(end - p) : strlen(p);
        if (l == n && strncmp(p, tag, n) == 0) {
            return true;
        }
        p = end != NULL ? end + 1 : NULL;
    }
    return false;
}

static bool tracing(void)
{
    static int on = -1;
    if (on < 0) {
        on = getenv("FUZZ_TRACE") != NULL ? 1 : 0;
    }
    return on == 1;
}

static void trace_frame(const char *what, co_time_us_t t, const co_frame_t *f)
{
    fprintf(stderr, "%12llu %s %03lX [%u]%s%s%s", (unsigned long long)t, what, (unsigned long)f->id, (unsigned)f->len,
            (f->flags & CO_FRAME_RTR) != 0U ? " RTR" : "", (f->flags & CO_FRAME_EFF) != 0U ? " EFF" : "",
            (f->flags & CO_FRAME_ERR) != 0U ? " ERR" : "");
    for (unsigned i = 0U; i < 8U && i < f->len; i++) {
        fprintf(stderr, " %02X", f->data[i]);
    }
    fprintf(stderr, "\n");
}

/* ---- Reporting ----------------------------------------------------------------------------------------- */

static const char *call_name(fz_call_t c)
{
    static const char *const names[] = {"none", "init", "rx", "process", "app/command", "power cycle"};
    return (unsigned)c < sizeof names / sizeof names[0] ? names[c] : "?";
}

void fz_fail(const fz_t *h, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "\n==fuzz== INVARIANT VIOLATION [%s] record %u, t = %llu us, during %s", h->target,
            (unsigned)h->step, (unsigned long long)h->now, call_name(h->call));
    if (h->call == FZ_CALL_RX) {
        fprintf(stderr, " of %03lX [%u]%s%s%s", (unsigned long)h->rx.id, (unsigned)h->rx.len,
                (h->rx.flags & CO_FRAME_RTR) != 0U ? " RTR" : "", (h->rx.flags & CO_FRAME_EFF) != 0U ? " EFF" : "",
                (h->rx.flags & CO_FRAME_ERR) != 0U ? " ERR" : "");
        for (unsigned i = 0U; i < 8U && i < h->rx.len; i++) {
            fprintf(stderr, " %02X", h->rx.data[i]);
        }
    }
    if (h->node != NULL && h->call != FZ_CALL_INIT) {
        fprintf(stderr, " (node-ID %u, NMT 0x%02X before: node-ID %u, NMT 0x%02X)", h->node->node_id,
                (unsigned)h->node->nmt_state, h->id0, (unsigned)h->state0);
    }
    fprintf(stderr, ":\n==fuzz==   ");
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

/* ---- Helpers ------------------------------------------------------------------------------------------- */

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_le32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0U; i < 4U; i++) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
}

/* CRC-32 (IEEE, reflected), as the core's store uses: written here again so the harness does not depend on
 * the implementation it checks. */
static uint32_t crc32_ieee(uint32_t crc, const uint8_t *d, size_t n)
{
    crc = ~crc;
    for (size_t i = 0U; i < n; i++) {
        crc ^= d[i];
        for (unsigned b = 0U; b < 8U; b++) {
            crc = (crc >> 1) ^ (0xEDB88320UL & (0U - (crc & 1U)));
        }
    }
    return ~crc;
}

static bool is_legal_state(co_nmt_state_t s)
{
    return s == CO_NMT_INITIALISING || s == CO_NMT_STOPPED || s == CO_NMT_OPERATIONAL || s == CO_NMT_PRE_OPERATIONAL;
}

static bool sdo_or_op(co_nmt_state_t s) { return s == CO_NMT_PRE_OPERATIONAL || s == CO_NMT_OPERATIONAL; }

static bool is_sdo_request(const co_frame_t *f, uint8_t id)
{
    return id >= 1U && id <= 127U && f->id == 0x600U + id && f->len == 8U &&
           (f->flags & (CO_FRAME_RTR | CO_FRAME_EFF | CO_FRAME_ERR)) == 0U;
}

/* The request that lets a block upload send segments from the state it found: start (0xA3) after the initiate, a
 * block confirmation (0xA2) while a block is out. */
static bool starts_upload_block(const co_frame_t *f, uint8_t state0)
{
    return (state0 == CO_SDO_BLK_UPLOAD_START && (f->data[0] & 0xE3U) == 0xA3U) ||
           (state0 == CO_SDO_BLK_UPLOAD && (f->data[0] & 0xE3U) == 0xA2U);
}

static bool is_plain(const co_frame_t *f) { return (f->flags & (CO_FRAME_EFF | CO_FRAME_ERR)) == 0U && f->len <= 8U; }

static uint8_t own_id(const fz_t *h)
{
    if (h->node->node_id >= 1U && h->node->node_id <= 127U) {
        return h->node->node_id;
    }
    return (h->poweron_id >= 1U && h->poweron_id <= 127U) ? h->poweron_id : 5U;
}

static uint32_t od_u32(fz_t *h, uint16_t index, uint8_t sub, uint32_t fallback)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(h->od, index, sub, &one);
    if (e == NULL) {
        return fallback;
    }
    uint32_t v = 0U;
    switch (e->size) {
    case 1U:
        v = co_od_get_u8(h->node, index, sub);
        break;
    case 2U:
        v = co_od_get_u16(h->node, index, sub);
        break;
    case 4U:
        v = co_od_get_u32(h->node, index, sub);
        break;
    default:
        v = fallback;
        break;
    }
    return v;
}

/* ---- Events from the target's hooks ---------------------------------------------------------------------- */

void fz_note_reset(fz_t *h, co_reset_t what)
{
    h->resets |= what == CO_RESET_APPLICATION ? 2U : 1U;
    h->reset_in_call = true;
    h->er_skip = false;
}

void fz_note_event(fz_t *h, const co_event_t *ev)
{
    if (ev == NULL || ev->kind < CO_EV_NMT_STATE || ev->kind > CO_EV_RX_FILTER) {
        fz_fail(h, "on_event with an unknown event kind");
    }
    if (ev->kind == CO_EV_SDO_ABORT && ev->code == CO_ABORT_TIMEOUT) {
        h->sdo_timeouts++;
        h->sdo_timeout_total++;
    }
    if (ev->kind == CO_EV_EMCY) {
        h->emcy_events++;
        h->er_skip = false; /* the core recomputed 0x1001 */
    }
    if (ev->kind == CO_EV_NMT_STATE && !is_legal_state((co_nmt_state_t)ev->value)) {
        fz_fail(h, "NMT event reports state 0x%lX", (unsigned long)ev->value);
    }
}

/* ---- The port: every frame the node puts on the bus is checked here ---------------------------------------- */

static void check_frame(fz_t *h, const co_frame_t *f)
{
    co_node_t *n = h->node;
    if (n == NULL) {
        fz_fail(h, "frame sent before the node exists");
    }
    if (f->len > 8U || f->flags != 0U || f->id > 0x7FFU) {
        fz_fail(h, "malformed frame sent: id 0x%lX len %u flags 0x%X", (unsigned long)f->id, f->len, f->flags);
    }
    for (unsigned i = f->len; i < 8U; i++) {
        if (f->data[i] != 0U) {
            fz_fail(h, "frame %03lX [%u]: byte %u past the length is not zero", (unsigned long)f->id, f->len, i);
        }
    }
    if (n->lss.silent_until != CO_NEVER && n->now < n->lss.silent_until &&
        !(n->txq.count > 0U && fz_known("lss-silence-flush"))) {
        fz_fail(h, "frame %03lX sent at %llu us, inside the LSS bit-rate switch silence (until %llu us)",
                (unsigned long)f->id, (unsigned long long)n->now, (unsigned long long)n->lss.silent_until);
    }
    if (n->txq.count > CO_TX_QUEUE_LEN) {
        fz_fail(h, "TX queue holds %u frames (size %u)", n->txq.count, (unsigned)CO_TX_QUEUE_LEN);
    }
    if (f->id >= 0x581U && f->id <= 0x5FFU) {
        h->sdo_resp_total++; /* checked against the requests at the end of the call */
    }
    if (h->call == FZ_CALL_NONE) {
        fz_fail(h, "frame %03lX sent outside any call into the node", (unsigned long)f->id);
    }
    if (n->txq.count > 0U) {
        return; /* flushed from the TX queue: generated by an earlier call; only the ledger applies */
    }
    const uint8_t id = n->node_id;
    const co_nmt_state_t st = n->nmt_state;
    if (f->id == 0x7E4U) {
        if (f->len != 8U) {
            fz_fail(h, "LSS response with DLC %u", f->len);
        }
        if (h->call != FZ_CALL_RX || h->rx.id != 0x7E5U) {
            fz_fail(h, "LSS response %02X without an LSS request", f->data[0]);
        }
        if (++h->lss_resp > 1U) {
            fz_fail(h, "two LSS responses to one request");
        }
        return;
    }
    if (id == CO_NODE_ID_UNCONFIGURED) {
        fz_fail(h, "frame %03lX from a node whose node-ID is unconfigured (only LSS may answer)", (unsigned long)f->id);
    }
    if (id < 1U || id > 127U) {
        fz_fail(h, "frame sent with node-ID %u", id);
    }
    if (f->id == 0x700U + id) {
        const uint8_t b = f->data[0];
        if (f->len != 1U) {
            fz_fail(h, "error-control frame with DLC %u", f->len);
        }
        if (st == CO_NMT_INITIALISING) {
            /* A process call resets only when the device asked for it (the Buerkert's 0x2001:04, carried out in
             * its step after the SDO confirmation): its on_reset hook has been seen then, before the boot-up. */
            if (b != 0U || (h->call == FZ_CALL_PROCESS && !h->reset_in_call)) {
                fz_fail(h, "error-control frame %02X while Initialising (only the boot-up 00 of a reset)", b);
            }
            h->bootups++;
            return;
        }
        if ((b & 0x7FU) != (uint8_t)st) {
            fz_fail(h, "error-control frame carries state 0x%02X, NMT state is 0x%02X", b & 0x7FU, (unsigned)st);
        }
        if (h->call == FZ_CALL_RX && (h->rx.flags & CO_FRAME_RTR) != 0U && h->rx.id == 0x700U + h->id0) {
            if (++h->guard_resp > 1U) {
                fz_fail(h, "two node-guarding replies to one remote frame");
            }
            if (od_u32(h, 0x1017U, 0U, 0U) != 0U) {
                fz_fail(h, "node-guarding reply while the heartbeat producer runs (0x1017 = %lu)",
                        (unsigned long)od_u32(h, 0x1017U, 0U, 0U));
            }
            return;
        }
        if (h->call != FZ_CALL_PROCESS || (b & 0x80U) != 0U) {
            fz_fail(h, "heartbeat %02X outside a process call or with the toggle bit", b);
        }
        if (od_u32(h, 0x1017U, 0U, 0U) == 0U) {
            fz_fail(h, "heartbeat while 0x1017 = 0");
        }
        return;
    }
    if (f->id == 0x580U + id) {
        if (f->len != 8U) {
            fz_fail(h, "SDO response with DLC %u", f->len);
        }
        if (!sdo_or_op(st)) {
            fz_fail(h, "SDO response %02X in NMT state 0x%02X", f->data[0], (unsigned)st);
        }
        if (n->sdo.state == CO_SDO_BLK_UPLOAD) { /* a segment of a block upload, not a response */
            const bool from_request = h->call == FZ_CALL_RX && is_sdo_request(&h->rx, h->id0) &&
                                      starts_upload_block(&h->rx, h->sdo_state0);
            const bool continued = h->call == FZ_CALL_PROCESS && h->sdo_state0 == CO_SDO_BLK_UPLOAD;
            if (!from_request && !continued) {
                fz_fail(h, "block upload segment %02X from a %s call in SDO state %u", f->data[0],
                        call_name(h->call), (unsigned)h->sdo_state0);
            }
            return;
        }
        h->sdo_resp++;
        if (h->call == FZ_CALL_RX) {
            if (!is_sdo_request(&h->rx, h->id0)) {
                fz_fail(h, "SDO response %02X to a frame that is not an SDO request", f->data[0]);
            }
            if (h->sdo_resp > 1U) {
                fz_fail(h, "SDO request answered %u times", (unsigned)h->sdo_resp);
            }
        } else if (h->call == FZ_CALL_PROCESS) {
            if (!h->sdo_open0 || f->data[0] != 0x80U || le32(&f->data[4]) != CO_ABORT_TIMEOUT || h->sdo_resp > 1U) {
                fz_fail(h, "SDO frame %02X .. %08lX from a process call, not the one timeout abort of an open transfer",
                        f->data[0], (unsigned long)le32(&f->data[4]));
            }
        } else {
            fz_fail(h, "SDO response from a %s call", call_name(h->call));
        }
        return;
    }
    /* EMCY and TPDOs: their COB-IDs are configurable (and may even coincide); allowed if any owner may send. */
    bool known = false;
    bool ok = false;
    const uint32_t emcy = od_u32(h, 0x1014U, 0U, 0x80U + (uint32_t)id);
    if ((emcy & 0x80000000UL) == 0U && (emcy & 0x7FFU) == f->id) {
        known = true;
        ok = ok || (f->len == 8U && sdo_or_op(st) && h->call == FZ_CALL_PROCESS);
    }
    const uint32_t sync_cob_id = od_u32(h, 0x1005U, 0U, 0x80U);
    const uint32_t sync_id = sync_cob_id & 0x7FFU;
#if CO_CONFIG_SYNC && CO_CONFIG_SYNC_PRODUCER
    if ((sync_cob_id & 0x40000000UL) != 0U && sync_id == f->id) { /* a SYNC producer's SYNC */
        known = true;
        ok = ok || (f->len == (n->sync.overflow != 0U ? 1U : 0U) && sdo_or_op(st) && h->call == FZ_CALL_PROCESS);
    }
#endif
    for (uint8_t k = 0U; k < n->n_tpdo && k < CO_TPDO_MAX; k++) {
        const co_tpdo_t *p = &n->tpdo[k];
        if (!p->valid || (p->cob_id & 0x7FFU) != f->id) {
            continue;
        }
        known = true;
        /* at a pass (a timer, a SYNC produced), at a SYNC taken, or at a remote request of it (types 252/253) */
        const bool rtr = h->call == FZ_CALL_RX && (h->rx.flags & CO_FRAME_RTR) != 0U && h->rx.id == f->id;
        const bool from = h->call == FZ_CALL_PROCESS || (h->call == FZ_CALL_RX && h->rx.id == sync_id) || rtr;
        ok = ok || (st == CO_NMT_OPERATIONAL && f->len == p->map_len && f->len >= 1U && from);
    }
    if (!known) {
        fz_fail(h, "frame %03lX [%u] belongs to no service of the node", (unsigned long)f->id, f->len);
    }
    if (!ok) {
        fz_fail(h, "frame %03lX [%u] (EMCY/TPDO) sent in NMT state 0x%02X from a %s call", (unsigned long)f->id,
                f->len, (unsigned)st, call_name(h->call));
    }
}

static co_status_t fz_send(void *ctx, const co_frame_t *frame)
{
    fz_t *h = (fz_t *)ctx; /* ctx is &h->fp, the first member */
    if (frame == NULL) {
        fz_fail(h, "send(NULL)");
    }
    h->sends++;
    if (h->fp.busy_count == 0U && !h->fp.send_io_error) {
        if (tracing()) {
            trace_frame(h->node != NULL && h->node->txq.count > 0U ? "  tx (queued)" : "  tx", h->now, frame);
        }
        check_frame(h, frame); /* the frame goes on the bus */
    }
    return g_fake_send(ctx, frame);
}

/* ---- Invariants after a call ---------------------------------------------------------------------------- */

static uint32_t get_native(const uint8_t *p, uint16_t size)
{
    uint8_t b1;
    uint16_t b2;
    uint32_t b4 = 0U;
    switch (size) {
    case 1U:
        memcpy(&b1, p, 1U);
        return b1;
    case 2U:
        memcpy(&b2, p, 2U);
        return b2;
    case 4U:
        memcpy(&b4, p, 4U);
        return b4;
    default:
        return 0U;
    }
}

static void fail_row(const fz_t *h, const co_od_entry_t *e, const uint8_t *want, const char *why)
{
    char a[80], b[80];
    size_t pa = 0U, pb = 0U;
    for (uint16_t i = 0U; i < e->size && i < 24U; i++) {
        pa += (size_t)snprintf(a + pa, sizeof a - pa, "%02X", want[i]);
        pb += (size_t)snprintf(b + pb, sizeof b - pb, "%02X", h->values[e->offset + i]);
    }
    a[pa] = '\0';
    b[pb] = '\0';
    fz_fail(h, "read-only object 0x%04X:%02X %s: expected %s, holds %s (native bytes)", e->index, e->sub, why, a, b);
}

static void check_read_only(fz_t *h, bool legit)
{
    if (!legit) {
        for (uint16_t k = 0U; k < h->n_ro; k++) {
            const co_od_entry_t *e = &h->ro_subs[k];
            const bool comm = e->index >= 0x1000U && e->index <= 0x1FFFU;
            const bool app = e->index >= 0x2000U && e->index <= 0x9FFFU;
            const bool reset = (h->resets & 4U) != 0U || (comm && (h->resets & 1U) != 0U) || (app && (h->resets & 2U) != 0U);
            if (!reset) {
                if (memcmp(h->values + e->offset, h->expect + e->offset, e->size) != 0) {
                    fail_row(h, e, h->expect + e->offset, "changed");
                }
                continue;
            }
            if ((e->flags & CO_OD_STORE) != 0U) {
                continue; /* loaded from NVM at the reset */
            }
            uint8_t want[256];
            const uint16_t size = e->size < sizeof want ? e->size : (uint16_t)sizeof want;
            memcpy(want, h->poweron + e->offset, size);
            if ((e->flags & CO_OD_NODEID) != 0U && (size == 1U || size == 2U || size == 4U)) {
                uint32_t v = get_native(want, size);
                if (h->poweron_id != CO_NODE_ID_UNCONFIGURED) {
                    v -= h->poweron_id;
                }
                if (h->node->node_id != CO_NODE_ID_UNCONFIGURED) {
                    v += h->node->node_id;
                }
                const uint8_t v1 = (uint8_t)v;
                const uint16_t v2 = (uint16_t)v;
                memcpy(want, size == 1U ? (const void *)&v1 : size == 2U ? (const void *)&v2 : (const void *)&v, size);
            }
            if (memcmp(h->values + e->offset, want, size) != 0) {
                fail_row(h, e, want, "is not its power-on value after a reset");
            }
        }
    }
    memcpy(h->expect, h->values, h->od->values_size);
}

static void begin_call(fz_t *h, fz_call_t call, const co_frame_t *f)
{
    co_node_t *n = h->node;
    h->call = call;
    h->after_process = false; /* do_process sets it after its call */
    if (f != NULL) {
        h->rx = *f;
    } else {
        memset(&h->rx, 0, sizeof h->rx);
    }
    h->state0 = n->nmt_state;
    h->id0 = n->node_id;
    h->reset_in_call = false;
    h->sdo_open0 = n->sdo.state != 0U;
    h->sdo_state0 = n->sdo.state;
    h->clean0 = h->fp.busy_count == 0U && !h->fp.send_io_error && n->txq.count == 0U &&
                !(n->lss.silent_until != CO_NEVER && h->now < n->lss.silent_until);
    h->sdo_resp = 0U;
    h->lss_resp = 0U;
    h->guard_resp = 0U;
    h->bootups = 0U;
    h->resets = 0U;
    h->sdo_timeouts = 0U;
    h->emcy_events = 0U;
    if (call == FZ_CALL_RX && is_sdo_request(f, h->id0)) {
        h->sdo_req_total++;
        if (starts_upload_block(f, h->sdo_state0)) {
            h->sdo_segments_allowed += 127U;
        }
    }
}

static void check_rx_effects(fz_t *h)
{
    co_node_t *n = h->node;
    const co_frame_t *f = &h->rx;
    const bool configured0 = h->id0 != CO_NODE_ID_UNCONFIGURED && h->state0 != CO_NMT_INITIALISING;
    if (is_sdo_request(f, h->id0) && configured0 && sdo_or_op(h->state0) && h->clean0 && f->data[0] != 0x80U) {
        /* Exactly one response, except inside a block transfer: a download segment is confirmed only at the end of
         * its block, an upload block's start and the end response get none, a block confirmation one if it ends
         * the upload or is refused. */
        const uint8_t st0 = h->sdo_state0;
        const uint8_t cs = (uint8_t)(f->data[0] & 0xE3U);
        uint32_t least = 1U;
        uint32_t most = 1U;
        if (st0 == CO_SDO_BLK_DOWNLOAD || (st0 == CO_SDO_BLK_UPLOAD && cs == 0xA2U)) {
            least = 0U;
        } else if ((st0 == CO_SDO_BLK_UPLOAD_START && cs == 0xA3U) || (st0 == CO_SDO_BLK_UPLOAD_END && cs == 0xA1U)) {
            least = 0U;
            most = 0U;
        }
        if (h->sdo_resp < least || h->sdo_resp > most) {
            fz_fail(h, "SDO request %02X %02X%02X:%02X in SDO state %u got %u responses (expected %u..%u)",
                    f->data[0], f->data[2], f->data[1], f->data[3], (unsigned)st0, (unsigned)h->sdo_resp,
                    (unsigned)least, (unsigned)most);
        }
    }
    if (f->id == 0x000U && is_plain(f) && (f->flags & CO_FRAME_RTR) == 0U && configured0) {
        const bool accepted = f->len == 2U || (f->len > 2U && (h->options & CO_OPT_NMT_ACCEPT_LONG) != 0U);
        if (accepted && (f->data[1] == 0U || f->data[1] == h->id0)) {
            co_nmt_state_t want = h->state0;
            switch (f->data[0]) {
            case 0x01:
                want = CO_NMT_OPERATIONAL;
                break;
            case 0x02:
                want = CO_NMT_STOPPED;
                break;
            case 0x80:
                want = CO_NMT_PRE_OPERATIONAL;
                break;
            case 0x81:
            case 0x82:
                want = n->node_id == CO_NODE_ID_UNCONFIGURED ? CO_NMT_INITIALISING : CO_NMT_PRE_OPERATIONAL;
                if ((h->resets & (f->data[0] == 0x81U ? 3U : 1U)) != (f->data[0] == 0x81U ? 3U : 1U)) {
                    fz_fail(h, "NMT %02X did not re-initialise its areas (resets 0x%X)", f->data[0], (unsigned)h->resets);
                }
                if (h->clean0 && n->node_id != CO_NODE_ID_UNCONFIGURED && h->bootups != 1U) {
                    fz_fail(h, "NMT %02X: %u boot-up frames (expected one)", f->data[0], (unsigned)h->bootups);
                }
                break;
            default:
                break;
            }
            if (n->nmt_state != want) {
                fz_fail(h, "NMT command %02X: state 0x%02X, expected 0x%02X", f->data[0], (unsigned)n->nmt_state,
                        (unsigned)want);
            }
            if (f->data[0] != 0x81U && f->data[0] != 0x82U && n->node_id != h->id0) {
                fz_fail(h, "NMT command %02X changed the node-ID", f->data[0]);
            }
            return;
        }
    }
    if (f->id == 0x7E5U && is_plain(f)) {
        return; /* LSS may start an unconfigured node */
    }
    if (n->nmt_state != h->state0 || n->node_id != h->id0) {
        fz_fail(h, "a frame that is no NMT command changed NMT state 0x%02X -> 0x%02X / node-ID %u -> %u",
                (unsigned)h->state0, (unsigned)n->nmt_state, h->id0, n->node_id);
    }
}

static void end_call(fz_t *h, bool legit)
{
    co_node_t *n = h->node;
    if (!is_legal_state(n->nmt_state)) {
        fz_fail(h, "NMT state 0x%02X is not one of the four legal states", (unsigned)n->nmt_state);
    }
    if ((n->node_id < 1U || n->node_id > 127U) && n->node_id != CO_NODE_ID_UNCONFIGURED) {
        fz_fail(h, "node-ID %u", n->node_id);
    }
    if ((n->node_id == CO_NODE_ID_UNCONFIGURED) != (n->nmt_state == CO_NMT_INITIALISING)) {
        fz_fail(h, "node-ID %u with NMT state 0x%02X (INITIALISING must mean unconfigured)", n->node_id,
                (unsigned)n->nmt_state);
    }
    if (n->txq.count > CO_TX_QUEUE_LEN || n->txq.head >= CO_TX_QUEUE_LEN) {
        fz_fail(h, "TX queue count %u head %u (size %u)", n->txq.count, n->txq.head, (unsigned)CO_TX_QUEUE_LEN);
    }
    if (n->emcy.q_count > CO_EMCY_QUEUE_LEN || n->emcy.q_head >= CO_EMCY_QUEUE_LEN ||
        n->emcy.n_active > CO_EMCY_ACTIVE_MAX) {
        fz_fail(h, "EMCY queue %u/%u, active %u", n->emcy.q_count, n->emcy.q_head, n->emcy.n_active);
    }
    /* A block transfer counts whole segments: up to 6 bytes past the object, or past the buffer before the end
     * request refuses the download. */
    const bool block = n->sdo.state >= CO_SDO_BLK_DOWNLOAD;
    if (n->sdo.state > CO_SDO_BLK_UPLOAD_END || n->sdo.pos > CO_SDO_BUF_SIZE + (block ? 6U : 0U) ||
        n->sdo.size > CO_SDO_BUF_SIZE ||
        (block && (n->sdo.blksize == 0U || n->sdo.blksize > 127U || n->sdo.seq > n->sdo.blksize))) {
        fz_fail(h, "SDO server state %u pos %lu size %lu seq %u blksize %u", n->sdo.state, (unsigned long)n->sdo.pos,
                (unsigned long)n->sdo.size, n->sdo.seq, n->sdo.blksize);
    }
    if ((n->lss.active_bit_timing >= CO_LSS_BIT_TIMING_COUNT || n->lss.pending_bit_timing >= CO_LSS_BIT_TIMING_COUNT) &&
        !fz_known("lss-bit-timing")) {
        fz_fail(h, "LSS bit-timing index active %u / pending %u outside the %u-entry table", n->lss.active_bit_timing,
                n->lss.pending_bit_timing, (unsigned)CO_LSS_BIT_TIMING_COUNT);
    }
    if (n->hbc.count > CO_HB_CONSUMER_MAX) {
        fz_fail(h, "heartbeat consumer count %u", n->hbc.count);
    }
    if (h->sdo_resp_total > h->sdo_req_total + h->sdo_timeout_total + h->sdo_segments_allowed) {
        fz_fail(h, "%llu SDO frames on the bus for %llu requests, %llu timeouts and %llu block segments allowed",
                (unsigned long long)h->sdo_resp_total, (unsigned long long)h->sdo_req_total,
                (unsigned long long)h->sdo_timeout_total, (unsigned long long)h->sdo_segments_allowed);
    }
    switch (h->call) {
    case FZ_CALL_RX:
        check_rx_effects(h);
        break;
    case FZ_CALL_PROCESS:
        if (h->sdo_resp > h->sdo_timeouts) {
            fz_fail(h, "%u SDO frames from a process call with %u timeouts", (unsigned)h->sdo_resp,
                    (unsigned)h->sdo_timeouts);
        }
        if ((n->nmt_state != h->state0 || n->node_id != h->id0) && !h->reset_in_call) {
            fz_fail(h, "a process call changed NMT state 0x%02X -> 0x%02X / node-ID %u -> %u", (unsigned)h->state0,
                    (unsigned)n->nmt_state, h->id0, n->node_id);
        }
        break;
    default:
        break;
    }
    co_od_entry_t one;
    if (co_od_find(h->od, 0x1001U, 0U, &one) != NULL && !h->er_skip) {
        uint8_t want = 0U;
        for (uint8_t i = 0U; i < n->emcy.n_active && i < CO_EMCY_ACTIVE_MAX; i++) {
            want |= n->emcy.active[i].reg;
        }
        if (n->emcy.n_active > 0U) {
            want |= 0x01U;
        }
        const uint8_t er = co_od_get_u8(n, 0x1001U, 0U);
        if (er != want) {
            if (h->call != FZ_CALL_APP) {
                fz_fail(h, "0x1001 = 0x%02X, the %u active errors make 0x%02X", er, n->emcy.n_active, want);
            }
            h->er_skip = true; /* a local write of 0x1001 */
        }
    }
    if (h->has_history && co_od_get_u8(n, 0x1003U, 0U) > h->history_subs) {
        fz_fail(h, "0x1003:00 = %u but the history has %u entries", co_od_get_u8(n, 0x1003U, 0U), h->history_subs);
    }
    check_read_only(h, legit);
    fake_port_clear(&h->fp);
    h->call = FZ_CALL_NONE;
}

/* ---- Calls ----------------------------------------------------------------------------------------------- */

/* Known bug "tpdo-inhibit-deadline": an event-driven TPDO whose event timer expired while its inhibit time
 * runs returns the expired timer as the next deadline. Returns the deadline the TPDO should have given. */
static co_time_us_t known_tpdo_deadline(const fz_t *h, co_time_us_t next)
{
#if CO_CONFIG_PDO_TIMERS
    const co_node_t *n = h->node;
    if (!fz_known("tpdo-inhibit-deadline")) {
        return 0U;
    }
    for (uint8_t k = 0U; k < n->n_tpdo && k < CO_TPDO_MAX; k++) {
        const co_tpdo_t *p = &n->tpdo[k];
        if (p->valid && p->type >= 254U && p->event_due == next && p->next_allowed != CO_NEVER && h->now < p->next_allowed) {
            return p->next_allowed;
        }
    }
#else
    (void)h;
    (void)next;
#endif
    return 0U;
}

static co_time_us_t do_process(fz_t *h, bool direct)
{
    begin_call(h, FZ_CALL_PROCESS, NULL);
    co_time_us_t next = fzt_process(h, direct);
    end_call(h, false);
    if (tracing()) {
        fprintf(stderr, "%12llu process%s -> %llu\n", (unsigned long long)h->now, direct ? " (core only)" : "",
                (unsigned long long)next);
    }
    if (next <= h->now && known_tpdo_deadline(h, next) != 0U) {
        next = known_tpdo_deadline(h, next);
    }
    if (next < h->now) {
        fz_fail(h, "process(%llu) returned the deadline %llu, in the past", (unsigned long long)h->now,
                (unsigned long long)next);
    }
    if (next == h->now) {
        begin_call(h, FZ_CALL_PROCESS, NULL);
        next = fzt_process(h, direct);
        end_call(h, false);
        if (next <= h->now && known_tpdo_deadline(h, next) != 0U) {
            next = known_tpdo_deadline(h, next);
        }
        if (next <= h->now) {
            fz_fail(h, "process(%llu) returned %llu twice in a row: a main loop would spin", (unsigned long long)h->now,
                    (unsigned long long)next);
        }
    }
    h->next = next;
    h->dirty = false;
    h->after_process = !direct; /* a core-only call's deadline leaves the model's out */
    return next;
}

static void deliver(fz_t *h, const co_frame_t *f, bool process_after)
{
    if (tracing()) {
        trace_frame("rx", h->now, f);
    }
    /* The router's oracle: a frame is taken only on a COB-ID the node lists, and a data frame on a listed one
     * (a heartbeat aside: one of the wrong length is not taken) always is. */
    uint16_t ids[CO_RX_ROUTES_FIXED + 512U + 130U];
    const uint16_t n = co_node_rx_ids(h->node, ids, (uint16_t)(sizeof ids / sizeof ids[0]));
    bool listed = false;
    for (uint16_t i = 0U; i < n && i < sizeof ids / sizeof ids[0]; i++) {
        listed = listed || ids[i] == f->id;
    }
    /* The pass of the last process call still holds: no other call since, its deadline ahead, no frame queued (a
     * runner retries those when the port has room). */
    const bool settled = h->after_process && !h->dirty && h->next > h->now && h->node->txq.count == 0U;
    begin_call(h, FZ_CALL_RX, f);
    bool pending = true;
    const bool taken = fzt_rx(h, f, &pending);
    end_call(h, false);
    if (taken && !listed) {
        fz_fail(h, "co_node_rx took a frame on 0x%03lX, which co_node_rx_ids does not list", (unsigned long)f->id);
    }
#if CO_CONFIG_TPDO_RTR
    /* listed for the remote requests of a TPDO: only remote frames are taken on it */
    const bool remote_only = listed && co_tpdo_rtr_next(h->node, f->id) == f->id;
#else
    const bool remote_only = false;
#endif
    if (!taken && listed && !remote_only && f->flags == 0U && f->len <= 8U && (f->id < 0x701U || f->id > 0x77FU)) {
        fz_fail(h, "co_node_rx ignored a data frame on 0x%03lX, which co_node_rx_ids lists", (unsigned long)f->id);
    }
    if (!pending && settled) {
        /* The skip oracle: after a frame ignored, or taken and settled (co_node_settled, device_settled), a runner
         * of many nodes skips the pass, so the pass must find nothing to do: no frame, the deadline it gave before. */
        const co_time_us_t before = h->next;
        const unsigned long sends = h->sends;
        const co_time_us_t next = do_process(h, false);
        if (h->sends != sends || next != before) {
            fz_fail(h, "the frame on 0x%03lX left nothing for the pass (%s), but the pass sent %lu frame(s) and "
                       "returned %llu (before: %llu)", (unsigned long)f->id, taken ? "settled" : "ignored",
                    h->sends - sends, (unsigned long long)next, (unsigned long long)before);
        }
        return;
    }
    h->dirty = true;
    if (process_after) {
        (void)do_process(h, false);
    }
}

/* Moves the clock to target: through every deadline on the way (at most FZ_LOOP_CAP, then a late wake-up),
 * or in one jump. */
static void advance(fz_t *h, co_time_us_t target, bool jump, bool final_process)
{
    if (target > FZ_TIME_MAX) {
        target = FZ_TIME_MAX;
    }
    if (target > h->now + FZ_SLOW_JUMP && fz_known("sds-catch-up")) {
        target = h->now + FZ_SLOW_JUMP; /* the SDS model needs time linear in the gap */
    }
    if (target <= h->now) {
        if (final_process) {
            (void)do_process(h, false);
        }
        return;
    }
    if (!jump) {
        if (h->dirty || h->next < h->now) {
            (void)do_process(h, false);
        }
        for (unsigned i = 0U; i < FZ_LOOP_CAP && h->loop_budget > 0U && h->next <= target; i++) {
            h->now = h->next;
            h->loop_budget--;
            (void)do_process(h, false);
        }
    }
    h->now = target;
    if (final_process) {
        (void)do_process(h, false);
    }
}

/* ---- Records --------------------------------------------------------------------------------------------- */

static void frame_record(fz_t *h, fz_in_t *in, uint8_t t)
{
    const uint8_t cls = (uint8_t)(t & 0x0FU);
    co_time_us_t dt = 0U;
    switch (t >> 4) {
    case 4:
        dt = (co_time_us_t)fz_u8(in) * 100U;
        break;
    case 5:
        dt = (co_time_us_t)fz_u8(in) * 1000U;
        break;
    case 6:
        dt = (co_time_us_t)fz_u16(in) * 1000U;
        break;
    case 7:
        dt = (co_time_us_t)fz_u16(in) * 10000U;
        break;
    case 8:
        dt = (co_time_us_t)fz_u16(in) * 1000000U;
        break;
    case 9:
        dt = fz_u32(in);
        break;
    default:
        break;
    }
    const uint32_t own = own_id(h);
    uint32_t id;
    switch (cls) {
    case 0:
        id = 0x000U;
        break;
    case 1:
        id = 0x080U;
        break;
    case 2:
        id = 0x100U;
        break;
    case 3:
    case 4:
    case 5:
    case 6:
        id = 0x200U + 0x100U * (uint32_t)(cls - 3U) + own; /* RPDO1..4 */
        break;
    case 7:
    case 8:
    case 9:
        id = 0x600U + own;
        break;
    case 10:
        id = 0x700U + own;
        break;
    case 11:
        id = 0x700U + (fz_u8(in) & 0x7FU); /* heartbeats of other nodes (0x700: none) */
        break;
    case 12:
    case 13:
        id = 0x7E5U;
        break;
    case 14:
        id = 0x080U * (uint32_t)(fz_u8(in) & 0x0FU) + own; /* any function code with the own node-ID */
        break;
    default:
        id = fz_u16(in); /* raw: may exceed 11 bits */
        break;
    }
    const uint8_t fl = fz_u8(in);
    co_frame_t f;
    memset(&f, 0xA5, sizeof f); /* bytes past the length are undefined on receive */
    f.id = id;
    f.len = (uint8_t)(fl & 0x0FU);
    f.flags = (uint8_t)(((fl & 0x10U) != 0U ? CO_FRAME_RTR : 0U) | ((fl & 0x20U) != 0U ? CO_FRAME_EFF : 0U) |
                        ((fl & 0x40U) != 0U ? CO_FRAME_ERR : 0U));
    for (unsigned i = 0U; i < f.len && i < 8U; i++) {
        f.data[i] = fz_u8(in);
    }
    if (dt != 0U) {
        advance(h, h->now + dt, false, false);
    }
    deliver(h, &f, (fl & 0x80U) == 0U);
}

static void time_record(fz_t *h, fz_in_t *in, uint8_t t)
{
    co_time_us_t target = h->now;
    switch (t & 0x07U) {
    case 0:
        target += (co_time_us_t)fz_u8(in) * 10U;
        break;
    case 1:
        target += (co_time_us_t)fz_u8(in) * 1000U;
        break;
    case 2:
        target += (co_time_us_t)fz_u16(in) * 1000U;
        break;
    case 3:
        target += (co_time_us_t)fz_u16(in) * 100000U;
        break;
    case 4:
        target += (co_time_us_t)fz_u16(in) * 1000000U;
        break;
    case 5:
        target += fz_u32(in);
        break;
    case 6:
        if (h->next != CO_NEVER && h->next > h->now) {
            target = h->next; /* exactly the deadline */
        }
        break;
    default: {
        const uint64_t d = fz_u64(in);
        target = d >= FZ_TIME_MAX - h->now ? FZ_TIME_MAX : h->now + d;
        break;
    }
    }
    advance(h, target, (t & 0x08U) != 0U, (t & 0x10U) == 0U);
}

static void nvm_reseal(fz_t *h, fake_nvm_area_t *a, co_nvm_area_t area, bool own_signature)
{
    if (area == CO_NVM_PARAMS) {
        if (a->stored_len < 16U) {
            memset(a->stored, 0, 16U);
            a->stored_len = 16U;
            own_signature = true;
        }
        memcpy(a->stored, "COS1", 4U);
        if (own_signature) {
            put_le32(&a->stored[4], h->od->signature);
        }
        put_le32(&a->stored[8], a->stored_len - 16U);
        put_le32(&a->stored[12], crc32_ieee(0U, &a->stored[16], a->stored_len - 16U));
    } else if (area == CO_NVM_LSS) {
        if (a->stored_len < 12U) {
            memset(&a->stored[a->stored_len], 0, 12U - a->stored_len);
            a->stored_len = 12U;
        }
        if (own_signature) {
            memcpy(a->stored, "COL1", 4U);
        }
        if (fz_known("lss-bit-timing")) {
            a->stored[5] = (uint8_t)(a->stored[5] % CO_LSS_BIT_TIMING_COUNT); /* avoid the known out-of-bounds read */
        }
        put_le32(&a->stored[8], crc32_ieee(0U, a->stored, 8U));
    }
}

static void nvm_record(fz_t *h, fz_in_t *in)
{
    const co_nvm_area_t area = (co_nvm_area_t)(fz_u8(in) % 3U);
    fake_nvm_area_t *a = &h->fp.nvm[area];
    switch (fz_u8(in) % 6U) {
    case 0: { /* flip bits of one byte */
        const uint16_t off = fz_u16(in);
        const uint8_t x = (uint8_t)(fz_u8(in) | 1U);
        if (a->stored_len > 0U) {
            a->stored[off % a->stored_len] ^= x;
        }
        break;
    }
    case 1: /* truncate */
        a->stored_len = fz_u16(in) % (a->stored_len + 1U);
        break;
    case 2: { /* replace with garbage */
        const uint8_t len = fz_u8(in);
        for (unsigned i = 0U; i < len; i++) {
            a->stored[i] = fz_u8(in);
        }
        a->stored_len = len;
        break;
    }
    case 3: /* make the header, length and CRC consistent again: the content's parser gets the bytes */
        nvm_reseal(h, a, area, (fz_u8(in) & 1U) != 0U);
        break;
    case 4: /* a well-formed blob with chosen content */
        if (area == CO_NVM_PARAMS) {
            nvm_reseal(h, a, area, true);
            const uint8_t how = fz_u8(in);
            uint16_t index = fz_u16(in);
            uint8_t sub = fz_u8(in);
            uint8_t len = fz_u8(in);
            if ((how & 1U) == 0U && h->od->count > 0U) { /* an existing row, with its own size unless told */
                const co_od_entry_t *e = &h->od->entries[index % h->od->count];
                index = e->index;
                sub = e->sub;
                len = (how & 2U) != 0U ? len : (uint8_t)(e->size > 255U ? 255U : e->size);
            }
            if (a->stored_len + 4U + len <= FAKE_NVM_SIZE) {
                uint8_t *r = &a->stored[a->stored_len];
                r[0] = (uint8_t)index;
                r[1] = (uint8_t)(index >> 8);
                r[2] = sub;
                r[3] = len;
                for (unsigned i = 0U; i < len; i++) {
                    r[4 + i] = fz_u8(in);
                }
                a->stored_len += 4U + len;
            }
            nvm_reseal(h, a, area, true);
        } else if (area == CO_NVM_LSS) {
            a->stored_len = 12U;
            memset(a->stored, 0, 12U);
            a->stored[4] = fz_u8(in); /* node-ID */
            a->stored[5] = fz_u8(in); /* bit-timing index */
            nvm_reseal(h, a, area, true);
        } else {
            for (unsigned i = 0U, k = fz_u8(in) % 8U; i <= k && a->stored_len > 0U; i++) {
                a->stored[fz_u16(in) % a->stored_len] = fz_u8(in);
            }
        }
        break;
    default: /* erase */
        a->stored_len = 0U;
        break;
    }
}

static void port_record(fz_t *h, fz_in_t *in, uint8_t t)
{
    switch (t & 0x03U) {
    case 0:
        h->fp.busy_count = fz_u8(in) % 24U;
        break;
    case 1:
        h->fp.send_io_error = !h->fp.send_io_error;
        break;
    case 2:
        h->fp.nvm_fail_write = !h->fp.nvm_fail_write;
        break;
    default:
        h->fp.nvm_fail_commit = !h->fp.nvm_fail_commit;
        break;
    }
}

static void quick_frame(fz_t *h, fz_in_t *in, uint32_t id, bool process_after)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = 8U;
    for (unsigned i = 0U; i < 8U; i++) {
        f.data[i] = fz_u8(in);
    }
    deliver(h, &f, process_after);
}

static bool record(fz_t *h, fz_in_t *in)
{
    const uint8_t t = fz_u8(in);
    if (t < 0xA0U) {
        frame_record(h, in, t);
    } else if (t < 0xC0U) {
        time_record(h, in, t);
    } else if (t < 0xD0U) {
        (void)do_process(h, (t & 1U) != 0U);
    } else if (t < 0xE0U) {
        if (tracing()) {
            fprintf(stderr, "%12llu app/command\n", (unsigned long long)h->now);
        }
        begin_call(h, FZ_CALL_APP, NULL);
        const bool legit = fzt_app(h, in);
        end_call(h, legit);
    } else if (t < 0xE2U) {
        if (tracing()) {
            fprintf(stderr, "%12llu power cycle\n", (unsigned long long)h->now);
        }
        begin_call(h, FZ_CALL_POWER, NULL);
        if (!fzt_power_cycle(h)) {
            fz_fail(h, "a power cycle with the configuration that powered the node on failed");
        }
        h->resets |= 7U;
        end_call(h, false);
        h->dirty = true;
    } else if (t < 0xE8U) {
        if (tracing()) {
            fprintf(stderr, "%12llu NVM corruption\n", (unsigned long long)h->now);
        }
        nvm_record(h, in);
    } else if (t < 0xECU) {
        port_record(h, in, t);
    } else if (t < 0xF0U) {
        quick_frame(h, in, 0x7E5U, true);
    } else {
        quick_frame(h, in, 0x600U + own_id(h), (t & 1U) == 0U);
    }
    return true;
}

/* ---- Entry point ----------------------------------------------------------------------------------------- */

static void build_read_only(fz_t *h)
{
    h->n_ro = 0U;
    size_t subs = 1U;
    for (uint16_t i = 0U; i < h->od->count; i++) {
        subs += co_od_entry_subs(&h->od->entries[i]);
    }
    h->ro_subs = (co_od_entry_t *)malloc(sizeof(co_od_entry_t) * subs);
    h->expect = (uint8_t *)malloc(h->od->values_size + 1U);
    h->poweron = (uint8_t *)malloc(h->od->values_size + 1U);
    if (h->ro_subs == NULL || h->expect == NULL || h->poweron == NULL) {
        abort();
    }
    for (uint16_t i = 0U; i < h->od->count; i++) {
        for (uint8_t k = 0U; k < co_od_entry_subs(&h->od->entries[i]); k++) { /* a run's sub-indices one by one */
            co_od_entry_t one;
            const co_od_entry_t *e = co_od_entry_at(&h->od->entries[i], k, &one);
            if ((e->flags & CO_OD_WRITE) != 0U || e->index == 0x1001U || e->index == 0x1003U || fzt_ro_exempt(e)) {
                continue;
            }
            h->ro_subs[h->n_ro++] = *e;
        }
    }
    /* 0x1003:00 may not exceed the sub-indices the history has (counted once: an OD scan after every call
     * was a tenth of a run). */
    co_od_entry_t one;
    h->has_history = co_od_find(h->od, 0x1003U, 0U, &one) != NULL;
    h->history_subs = 0U;
    for (uint16_t i = 0U; i < h->od->count; i++) {
        const co_od_entry_t *row = &h->od->entries[i];
        if (row->index == 0x1003U) {
            h->history_subs = (uint8_t)(h->history_subs + co_od_entry_subs(row) - (row->sub == 0U ? 1U : 0U));
        }
    }
    memcpy(h->expect, h->values, h->od->values_size);
    memcpy(h->poweron, h->values, h->od->values_size);
    h->poweron_id = h->node->node_id;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t *h = &g_fz;
    memset(h, 0, sizeof *h);
    fz_in_t in = {data, size, 0U};
    uint8_t hdr[4];
    for (unsigned i = 0U; i < 4U; i++) {
        hdr[i] = fz_u8(&in);
    }
    fake_port_init(&h->fp, &h->now);
    g_fake_send = h->fp.port.send;
    h->port = h->fp.port;
    h->port.send = fz_send;
    h->loop_budget = FZ_LOOP_BUDGET;
    h->now = 0U;
    h->next = CO_NEVER;
    h->call = FZ_CALL_INIT;
    if (!fzt_init(h, hdr)) {
        h->call = FZ_CALL_NONE;
        fzt_fini(h);
        return 0;
    }
    h->call = FZ_CALL_NONE;
    build_read_only(h);
    h->id0 = h->node->node_id;
    h->state0 = h->node->nmt_state;
    if ((h->node->node_id == CO_NODE_ID_UNCONFIGURED) != (h->node->nmt_state == CO_NMT_INITIALISING)) {
        fz_fail(h, "after power-on: node-ID %u, NMT state 0x%02X", h->node->node_id, (unsigned)h->node->nmt_state);
    }
    fake_port_clear(&h->fp);
    (void)do_process(h, false);
    for (h->step = 1U; in.pos < in.n && h->step <= FZ_MAX_RECORDS; h->step++) {
        if (!record(h, &in)) {
            break;
        }
    }
    fzt_fini(h);
    free(h->ro_subs);
    free(h->expect);
    free(h->poweron);
    return 0;
}
