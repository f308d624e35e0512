/*
 * Heartbeat consumer (CiA 301 §7.2.8.3.2.2, object 0x1016): each sub-index names a node-ID (bits 23..16)
 * and a time in ms (bits 15..0). Monitoring of a node starts with its first heartbeat (a boot-up does not
 * start it); a missing heartbeat raises EMCY 0x8130, the next heartbeat clears it again.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_HB_CONSUMER

/* EMCY 0x8130 of the slot monitoring node_id, raised or cleared: the manufacturer-specific field names the
 * heartbeat consumer (2) and the node. */
static void slot_emcy(co_node_t *node, uint8_t node_id, bool raise)
{
    const uint8_t msef[5] = {0x02U, node_id, 0U, 0U, 0U};
    if (raise) {
        (void)co_emcy_raise(node, 0x8130U, 0x10U, msef);
    } else {
        (void)co_emcy_clear(node, 0x8130U, msef);
    }
}

/* Slot s from its entry of 0x1016 (sub-index sub). */
static void slot_configure(co_node_t *node, co_hb_consumer_slot_t *s, uint8_t sub)
{
    const uint32_t v = co_od_u32_or(node, 0x1016U, sub, 0U);
    const uint8_t id = (uint8_t)(v >> 16);
    if (s->state == 3U) {
        slot_emcy(node, s->node_id, false);
    }
    s->node_id = (id >= 1U && id <= 127U && (v & 0xFFFFU) != 0U) ? id : 0U;
    s->state = s->node_id != 0U ? 1U : 0U;
    s->time_ms = (uint16_t)v;
    s->deadline = CO_NEVER;
    s->remote_state = 0U;
}

/* 0x1016 often has many entries (127 in the Bürkert dictionary) and few or none in use, while rx runs for
 * every heartbeat on the bus and process at every wake-up: both look only at what is configured (measured:
 * docs/performance.md, "the core alone"). */
static void update_index(co_node_t *node)
{
    co_hb_consumer_t *hbc = &node->hbc;
    hbc->used = 0U;
    memset(hbc->monitored, 0, sizeof hbc->monitored);
    for (unsigned i = 0U; i < hbc->count; i++) {
        const uint8_t id = hbc->slot[i].node_id;
        if (id != 0U) {
            hbc->used = (uint8_t)(i + 1U);
            hbc->monitored[id >> 3] = (uint8_t)(hbc->monitored[id >> 3] | (1U << (id & 7U)));
        }
    }
}

void co_hbc_reset(co_node_t *node)
{
    co_hb_consumer_t *hbc = &node->hbc;
    uint8_t n = co_od_sub_count(node->od, 0x1016U);
    hbc->count = n;
    for (unsigned i = 0U; i < n; i++) {
        hbc->slot[i].state = 0U;
        slot_configure(node, &hbc->slot[i], (uint8_t)(i + 1U));
    }
    update_index(node);
}

bool co_hbc_rx(co_node_t *node, const co_frame_t *f)
{
    co_hb_consumer_t *hbc = &node->hbc;
    if (f->len != 1U) { /* f->id is 0x701..0x77F (co_node_rx) */
        return false;
    }
    const uint8_t id = (uint8_t)(f->id - 0x700U);
    if ((hbc->monitored[id >> 3] & (1U << (id & 7U))) == 0U) {
        return false;
    }
    bool used = false;
    for (unsigned i = 0U; i < hbc->used; i++) {
        co_hb_consumer_slot_t *s = &hbc->slot[i];
        if (s->node_id != id) {
            continue; /* (a slot not in use has node-ID 0, never a heartbeat's: the node-ID alone tells) */
        }
        used = true;
        s->remote_state = f->data[0];
        if (f->data[0] == 0U) {
            if (s->state == 2U) { /* boot-up: the node restarted; monitoring resumes with its first heartbeat */
                s->state = 1U;
                s->deadline = CO_NEVER;
            }
            continue;
        }
        if (s->state == 3U) {
            slot_emcy(node, id, false);
        }
        s->state = 2U;
        s->deadline = co_time_after(node->now, (uint32_t)s->time_ms * 1000U);
        co_node_due(node, CO_SVC_I_HBC, s->deadline);
    }
    return used;
}

co_time_us_t co_hbc_process(co_node_t *node)
{
    co_hb_consumer_t *hbc = &node->hbc;
    co_time_us_t next = CO_NEVER;
    for (unsigned i = 0U; i < hbc->used; i++) {
        co_hb_consumer_slot_t *s = &hbc->slot[i];
        if (s->state != 2U) {
            continue;
        }
        if (co_time_reached(node->now, s->deadline)) {
            s->state = 3U;
            co_node_event(node, CO_EV_HB_TIMEOUT, 0x1016U, (uint8_t)(i + 1U), s->node_id, 0U);
            slot_emcy(node, s->node_id, true);
        } else {
            next = co_min_time(next, s->deadline);
        }
    }
    return next;
}

uint32_t co_hbc_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    (void)len;
    if (e->sub == 0U) {
        return CO_ABORT_NONE;
    }
    const uint32_t v = co_get_u32(data);
    const uint32_t id = (v >> 16) & 0xFFU;
    if (id == 0U || id > 127U || (v & 0xFFFFU) == 0U) {
        return CO_ABORT_NONE; /* an unused entry */
    }
    const uint8_t n = co_od_sub_count(node->od, 0x1016U);
    for (unsigned k = 1U; k <= n; k++) {
        const uint32_t other = co_od_u32_or(node, 0x1016U, (uint8_t)k, 0U);
        if (k != e->sub && ((other >> 16) & 0xFFU) == id && (other & 0xFFFFU) != 0U) {
            return CO_ABORT_PARAM_INCOMPATIBLE; /* one node-ID monitored twice */
        }
    }
    return CO_ABORT_NONE;
}

void co_hbc_written(co_node_t *node, const co_od_entry_t *e)
{
    if (e->sub >= 1U && e->sub <= node->hbc.count) {
        slot_configure(node, &node->hbc.slot[e->sub - 1U], e->sub);
        update_index(node);
        co_node_routes_update(node); /* the heartbeats it takes changed */
    }
}

#endif /* CO_CONFIG_HB_CONSUMER */
