/*
 * Fuzz target "core": the bare core with the unit tests' object dictionary (tests/support/test_od.c) and
 * hooks whose behaviour the input chooses (refuse writes, hide reads, raise EMCY or write objects from
 * inside hooks). Application calls exercise the public API (EMCY, local reads/writes, TPDO trigger, the
 * LSS configuration API, resets). The read-only check is strict here: only 0x1001 and 0x1003 may move by
 * themselves.
 *
 * Header: [0] bits 0-2 CO_OPT_* options 0x01-0x04, bit 3 no NVM functions, bit 4 no set_bit_rate, bit 5 custom
 *         bit-rate table, bit 6 CO_OPT_TPDO_NO_COS, bit 7 CO_OPT_SDO_BLOCK; [1] node-ID (0 = 5; 128..254 must be
 *         refused); [2] bits 0-4 hook actions, bits 5-7 refusal preset; [3] node-ID the on_reset hook
 *         makes pending (action bit 4).
 */
#include <string.h>

#include "fuzz.h"
#include "test_od.h"

enum {
    ACT_WRITE_EMCY = 0x01,  /* on_write raises EMCY 0xFF00 (a write of 0x2003 clears it) */
    ACT_READ_BUMP = 0x02,   /* on_read writes 0x6300:01 (a live value that changes at every sampling) */
    ACT_RESET_EMCY = 0x04,  /* on_reset raises a persisting error 0x5000 again */
    ACT_NMT_TRIGGER = 0x08, /* on_nmt_change triggers TPDO 1 */
    ACT_RESET_ID = 0x10     /* on_reset (communication) makes reset_id the pending node-ID */
};

typedef struct core_ctx {
    fz_t *h;
    co_node_cfg_t cfg;
    co_node_t *node;
    test_od_values_t *values;
    uint32_t refuse_code;
    uint16_t refuse_index;
    uint16_t hide_index;
    uint8_t actions;
    uint8_t reset_id;
    int depth;
    uint32_t counter;
} core_ctx_t;

static core_ctx_t g_core;

static const uint16_t custom_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 0U, 500U, 250U, 125U, 100U, 50U, 20U, 10U, 0U};

static const uint32_t refuse_codes[] = {0U, CO_ABORT_READ_ONLY, CO_ABORT_VALUE_HIGH, CO_ABORT_DEVICE_STATE,
                                        CO_ABORT_GENERAL, CO_ABORT_LOCAL_CONTROL, 0x12345678UL, CO_ABORT_NO_SUBINDEX};

static const uint16_t indices[] = {0x1000, 0x1001, 0x1003, 0x1005, 0x1006, 0x1007, 0x1008, 0x1009, 0x100C,
                                   0x100D, 0x1010, 0x1011, 0x1014, 0x1015, 0x1016, 0x1017, 0x1018, 0x1019,
                                   0x1200, 0x1400, 0x1401, 0x1600, 0x1601, 0x1800, 0x1801, 0x1A00, 0x1A01,
                                   0x2000, 0x2001, 0x2002, 0x2003, 0x2004, 0x2005, 0x2006, 0x6000, 0x6200,
                                   0x6300, 0x6401, 0x2100, 0x0000, 0xFFFF, 0x1402, 0x1802};

static uint16_t pick_index(fz_in_t *in)
{
    const uint8_t k = fz_u8(in);
    return k < sizeof indices / sizeof indices[0] ? indices[k] : fz_u16(in);
}

static bool is_bytes(const co_od_entry_t *e)
{
    return e->type == CO_T_VISIBLE_STRING || e->type == CO_T_OCTET_STRING || e->type == CO_T_DOMAIN;
}

static void check_entry(const core_ctx_t *c, const co_node_t *node, const co_od_entry_t *e, const char *hook)
{
    if (node != c->node) {
        fz_fail(c->h, "%s hook called with another node", hook);
    }
    co_od_entry_t one;
    const co_od_entry_t *own = e != NULL ? co_od_find(&test_od, e->index, e->sub, &one) : NULL;
    if (own == NULL || own->offset != e->offset || own->size != e->size || own->flags != e->flags ||
        own->type != e->type) {
        fz_fail(c->h, "%s hook called with an entry that is not one of the object dictionary's", hook);
    }
    if (e != NULL && e->index < node->hooks->first_index) {
        fz_fail(c->h, "%s hook called for 0x%04X, below the hooks' first index 0x%04X", hook, e->index,
                node->hooks->first_index);
    }
}

static uint32_t hk_write(void *ctx, co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                         co_od_origin_t origin)
{
    core_ctx_t *c = (core_ctx_t *)ctx;
    check_entry(c, node, e, "on_write");
    if (len > e->size || (!is_bytes(e) && len != e->size) || (len > 0U && data == NULL) ||
        (unsigned)origin > (unsigned)CO_ORIGIN_NVM) {
        fz_fail(c->h, "on_write of 0x%04X:%02X with %lu bytes (size %u), origin %d", e->index, e->sub,
                (unsigned long)len, e->size, (int)origin);
    }
    if ((e->flags & CO_OD_CONST) != 0U || (origin == CO_ORIGIN_SDO && (e->flags & CO_OD_WRITE) == 0U) ||
        (origin == CO_ORIGIN_RPDO && (e->flags & CO_OD_RPDO) == 0U)) {
        fz_fail(c->h, "on_write of 0x%04X:%02X (flags 0x%X) from origin %d passed the access check", e->index,
                e->sub, e->flags, (int)origin);
    }
    if (origin == CO_ORIGIN_NVM && (e->flags & CO_OD_STORE) == 0U) {
        fz_fail(c->h, "on_write of 0x%04X:%02X (flags 0x%X) as a stored value, which it never is", e->index, e->sub,
                e->flags);
    }
    if (c->refuse_code != 0U && (c->refuse_index == 0U || c->refuse_index == e->index)) {
        return c->refuse_code;
    }
    /* A stored value being loaded is only checked (co_od.h: the hook must not act). */
    if ((c->actions & ACT_WRITE_EMCY) != 0U && c->depth == 0 && origin != CO_ORIGIN_NVM) {
        c->depth++;
        if (e->index == 0x2003U) {
            (void)co_emcy_clear(node, 0xFF00U, NULL);
        } else {
            (void)co_emcy_raise(node, 0xFF00U, 0x80U, NULL);
        }
        c->depth--;
    }
    return 0U;
}

static uint32_t hk_read(void *ctx, co_node_t *node, const co_od_entry_t *e)
{
    core_ctx_t *c = (core_ctx_t *)ctx;
    check_entry(c, node, e, "on_read");
    if (c->hide_index != 0U && c->hide_index == e->index) {
        return CO_ABORT_NO_SUBINDEX;
    }
    if ((c->actions & ACT_READ_BUMP) != 0U && c->depth == 0 && e->index != 0x6300U) {
        c->depth++;
        (void)co_od_set_u32(node, 0x6300U, 1U, ++c->counter);
        c->depth--;
    }
    return 0U;
}

static void hk_nmt(void *ctx, co_node_t *node, co_nmt_state_t from, co_nmt_state_t to)
{
    core_ctx_t *c = (core_ctx_t *)ctx;
    if (node != c->node || from == to || node->nmt_state != to) {
        fz_fail(c->h, "on_nmt_change(0x%02X -> 0x%02X) with the node in 0x%02X", (unsigned)from, (unsigned)to,
                (unsigned)node->nmt_state);
    }
    if ((c->actions & ACT_NMT_TRIGGER) != 0U) {
        co_tpdo_trigger(node, 0U);
    }
}

static void hk_reset(void *ctx, co_node_t *node, co_reset_t what)
{
    core_ctx_t *c = (core_ctx_t *)ctx;
    if (node != c->node) {
        fz_fail(c->h, "on_reset with another node");
    }
    fz_note_reset(c->h, what);
    if ((c->actions & ACT_RESET_EMCY) != 0U) {
        (void)co_emcy_raise(node, 0x5000U, 0x02U, NULL);
    }
    if ((c->actions & ACT_RESET_ID) != 0U && what == CO_RESET_COMMUNICATION) {
        (void)co_lss_set_pending_node_id(node, c->reset_id);
    }
}

static void hk_event(void *ctx, co_node_t *node, const co_event_t *ev)
{
    core_ctx_t *c = (core_ctx_t *)ctx;
    if (node != c->node) {
        fz_fail(c->h, "on_event with another node");
    }
    fz_note_event(c->h, ev);
}

static const co_hooks_t hooks = {
    .on_write = hk_write, .on_read = hk_read, .on_nmt_change = hk_nmt, .on_reset = hk_reset, .on_event = hk_event};
/* The same for the objects from 0x2000 on only (record 10's bit 5): no read or write hook below. */
static const co_hooks_t hooks_from_0x2000 = {.on_write = hk_write,
                                             .on_read = hk_read,
                                             .on_nmt_change = hk_nmt,
                                             .on_reset = hk_reset,
                                             .on_event = hk_event,
                                             .first_index = 0x2000U};

static void set_refusal(core_ctx_t *c, uint8_t preset)
{
    c->refuse_code = 0U;
    c->refuse_index = 0U;
    c->hide_index = 0U;
    switch (preset & 7U) {
    case 1:
        c->refuse_code = CO_ABORT_VALUE_HIGH;
        c->refuse_index = 0x2004U;
        break;
    case 2:
        c->refuse_code = CO_ABORT_DEVICE_STATE;
        c->refuse_index = 0x6300U;
        break;
    case 3:
        c->hide_index = 0x2005U;
        break;
    case 4:
        c->refuse_code = CO_ABORT_GENERAL;
        break;
    case 5:
        c->hide_index = 0x1001U;
        break;
    case 6:
        c->refuse_code = CO_ABORT_LOCAL_CONTROL;
        c->refuse_index = 0x1017U;
        break;
    default:
        break;
    }
}

bool fzt_init(fz_t *h, const uint8_t hdr[4])
{
    core_ctx_t *c = &g_core;
    memset(c, 0, sizeof *c);
    c->h = h;
    c->node = (co_node_t *)calloc(1U, sizeof *c->node);
    c->values = (test_od_values_t *)calloc(1U, sizeof *c->values);
    if (c->node == NULL || c->values == NULL) {
        abort();
    }
    h->target = "core";
    h->node = c->node;
    h->od = &test_od;
    h->values = (uint8_t *)c->values;
    h->options = (hdr[0] & 0x07U) | ((hdr[0] & 0x40U) != 0U ? (uint32_t)CO_OPT_TPDO_NO_COS : 0U) |
                 ((hdr[0] & 0x80U) != 0U ? (uint32_t)CO_OPT_SDO_BLOCK : 0U);
    if ((hdr[0] & 0x08U) != 0U) {
        h->port.nvm_write = NULL;
        h->port.nvm_commit = NULL;
        h->port.nvm_read = NULL;
    }
    if ((hdr[0] & 0x10U) != 0U) {
        h->port.set_bit_rate = NULL;
    }
    c->actions = (uint8_t)(hdr[2] & 0x1FU);
    set_refusal(c, (uint8_t)(hdr[2] >> 5));
    c->reset_id = (hdr[3] & 0x7FU) != 0U ? (uint8_t)(hdr[3] & 0x7FU) : CO_NODE_ID_UNCONFIGURED;
    const uint8_t id = hdr[1] == 0U ? 5U : hdr[1];
    c->cfg.od = &test_od;
    c->cfg.values = c->values;
    c->cfg.port = &h->port;
    c->cfg.port_ctx = &h->fp;
    c->cfg.hooks = &hooks;
    c->cfg.hooks_ctx = c;
    c->cfg.node_id = id;
    c->cfg.bit_timing = 4U;
    c->cfg.bit_rates_kbit = (hdr[0] & 0x20U) != 0U ? custom_rates : NULL;
    c->cfg.options = h->options;
    const co_status_t st = co_node_init(c->node, &c->cfg, h->now);
    if (id > 127U && id != CO_NODE_ID_UNCONFIGURED) {
        if (st != CO_ERR_ARG) {
            fz_fail(h, "co_node_init accepted node-ID %u (status %d)", id, (int)st);
        }
        return false;
    }
    if (st != CO_OK) {
        fz_fail(h, "co_node_init failed with status %d", (int)st);
    }
    return true;
}

void fzt_fini(fz_t *h)
{
    (void)h;
    free(g_core.node);
    free(g_core.values);
    g_core.node = NULL;
    g_core.values = NULL;
}

bool fzt_rx(fz_t *h, const co_frame_t *f, bool *pending)
{
    const bool taken = co_node_rx(g_core.node, f, h->now);
    *pending = taken && !co_node_settled(g_core.node, h->next);
    return taken;
}

co_time_us_t fzt_process(fz_t *h, bool direct)
{
    (void)direct;
    return co_node_process(g_core.node, h->now);
}

bool fzt_power_cycle(fz_t *h) { return co_node_init(g_core.node, &g_core.cfg, h->now) == CO_OK; }

bool fzt_ro_exempt(const co_od_entry_t *e)
{
    (void)e;
    return false; /* strict: the test OD has no live values besides 0x1001/0x1003 */
}

bool fzt_app(fz_t *h, fz_in_t *in)
{
    core_ctx_t *c = &g_core;
    co_node_t *node = c->node;
    uint8_t buf[96];
    uint8_t msef[5];
    switch (fz_u8(in) % 16U) {
    case 0: {
        const uint16_t code = fz_u16(in);
        const uint8_t reg = fz_u8(in);
        const bool with = (fz_u8(in) & 1U) != 0U;
        for (unsigned i = 0U; i < 5U; i++) {
            msef[i] = fz_u8(in);
        }
        const bool ok = co_emcy_raise(node, code, reg, with ? msef : NULL);
        if (ok && code == 0U) {
            fz_fail(h, "co_emcy_raise accepted the error-reset code 0x0000");
        }
        return false;
    }
    case 1: {
        const uint16_t code = fz_u16(in);
        const bool with = (fz_u8(in) & 1U) != 0U;
        for (unsigned i = 0U; i < 5U; i++) {
            msef[i] = fz_u8(in);
        }
        (void)co_emcy_clear(node, code, with ? msef : NULL);
        return false;
    }
    case 2:
        (void)co_od_set_u8(node, 0x6000U, (uint8_t)(1U + fz_u8(in) % 2U), fz_u8(in));
        return true;
    case 3:
        (void)co_od_set_u16(node, 0x6401U, (uint8_t)(1U + fz_u8(in) % 2U), fz_u16(in));
        return true;
    case 4: { /* local write of anything: may legitimately change read-only rows */
        const uint16_t index = pick_index(in);
        const uint8_t sub = fz_u8(in);
        const size_t len = fz_u8(in) % (sizeof buf + 1U);
        for (size_t i = 0U; i < len; i++) {
            buf[i] = fz_u8(in);
        }
        (void)co_od_write(node, index, sub, buf, len, CO_ORIGIN_LOCAL);
        return true;
    }
    case 5: { /* reads: nothing may change, the length never exceeds the room given */
        const uint16_t index = pick_index(in);
        const uint8_t sub = fz_u8(in);
        const co_od_origin_t origin = (co_od_origin_t)(fz_u8(in) % 3U);
        const size_t cap = fz_u8(in) % (sizeof buf + 1U);
        size_t len = 12345U;
        const uint32_t r = co_od_read(node, index, sub, buf, cap, &len, origin);
        if ((r == 0U && len > cap) || (r != 0U && len != 0U)) {
            fz_fail(h, "co_od_read(0x%04X:%02X, cap %lu) = 0x%08lX with length %lu", index, sub, (unsigned long)cap,
                    (unsigned long)r, (unsigned long)len);
        }
        return false;
    }
    case 6:
        co_tpdo_trigger(node, fz_u8(in));
        return false;
    case 7: { /* the LSS configuration API (pending node-ID / bit timing, store, apply) */
        const uint8_t how = fz_u8(in);
        const uint8_t v = fz_u8(in);
        if ((how & 3U) == 0U) {
            const bool ok = co_lss_set_pending_node_id(node, v);
            if (ok && !((v >= 1U && v <= 127U) || v == CO_NODE_ID_UNCONFIGURED)) {
                fz_fail(h, "co_lss_set_pending_node_id accepted %u", v);
            }
        } else if ((how & 3U) == 1U) {
            const bool ok = co_lss_set_pending_bit_timing(node, v);
            if (ok && (v >= CO_LSS_BIT_TIMING_COUNT || node->bit_rates_kbit[v] == 0U)) {
                fz_fail(h, "co_lss_set_pending_bit_timing accepted index %u", v);
            }
        } else if ((how & 3U) == 2U) {
            (void)co_lss_store(node);
        } else {
            (void)co_lss_apply_bit_timing(node);
        }
        return false;
    }
    case 8:
        co_node_reset(node, (fz_u8(in) & 1U) != 0U ? CO_RESET_COMMUNICATION : CO_RESET_APPLICATION, h->now);
        return false;
    case 9: {
        const uint16_t index = pick_index(in);
        const uint8_t sub = fz_u8(in);
        (void)co_od_get_u8(node, index, sub);
        (void)co_od_get_u16(node, index, sub);
        (void)co_od_get_u32(node, index, sub);
        (void)co_od_value(node, index, sub);
        (void)co_emcy_is_active(node, fz_u16(in));
        (void)co_node_state(node);
        (void)co_nmt_state_name((co_nmt_state_t)fz_u8(in));
        (void)co_abort_text(fz_u32(in));
        return false;
    }
    case 10: {
        const uint8_t b = fz_u8(in);
        c->actions = (uint8_t)(b & 0x1FU);
        /* co_hooks_t.first_index; kept in the configuration too, so a power cycle keeps the choice. */
        c->cfg.hooks = (b & 0x20U) != 0U ? &hooks_from_0x2000 : &hooks;
        node->hooks = c->cfg.hooks;
        set_refusal(c, fz_u8(in));
        return false;
    }
    case 11: {
        const uint8_t k = fz_u8(in);
        c->refuse_code = refuse_codes[k % (sizeof refuse_codes / sizeof refuse_codes[0])];
        c->refuse_index = (k & 0x80U) != 0U ? 0U : pick_index(in);
        return false;
    }
    case 12:
    case 13: { /* the SDO/RPDO write path without the SDO server: access rules keep read-only rows */
        const uint16_t index = pick_index(in);
        const uint8_t sub = fz_u8(in);
        const size_t len = fz_u8(in) % 12U;
        for (size_t i = 0U; i < len; i++) {
            buf[i] = fz_u8(in);
        }
        (void)co_od_write(node, index, sub, buf, len, (fz_u8(in) & 1U) != 0U ? CO_ORIGIN_RPDO : CO_ORIGIN_SDO);
        return false;
    }
    default:
        (void)co_od_set_u32(node, 0x6300U, 1U, fz_u32(in));
        return false;
    }
}
