/*
 * Node guarding and life guarding, slave side (CiA 301 §7.2.8.3.2.1). The master sends a remote frame on
 * 0x700+node-ID; the slave answers with its state and a toggle bit. If guard time 0x100C x life time factor
 * 0x100D is non-zero, a missing request for that long is a life-guarding event (EMCY 0x8130).
 * Disabled while the heartbeat producer runs (0x1017 != 0): the two are mutually exclusive.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_NODE_GUARDING

static const uint8_t guard_msef[5] = {0x01U, 0U, 0U, 0U, 0U}; /* distinguishes life guarding from HB consumers */

void co_guard_written(co_node_t *node)
{
    co_guard_t *g = &node->guard;
    /* One look-up each: the row that holds sub-index 0 starts there, so its value is sub-index 0's. */
    const co_od_entry_t *guard_time = co_od_find_row(node->od, 0x100CU, 0U);
    const co_od_entry_t *life_factor = co_od_find_row(node->od, 0x100DU, 0U);
    g->present = guard_time != NULL && life_factor != NULL;
    g->guard_ms = guard_time != NULL ? (uint16_t)co_od_entry_u32(node, guard_time) : 0U;
    g->life_factor = life_factor != NULL ? (uint8_t)co_od_entry_u32(node, life_factor) : 0U;
}

void co_guard_reset(co_node_t *node)
{
    co_guard_written(node);
    node->guard.toggle = 0U;
    node->guard.armed = false;
    node->guard.failed = false;
    node->guard.deadline = CO_NEVER;
}

void co_guard_rx(co_node_t *node, const co_frame_t *f)
{
    (void)f; /* routed here only when the device has node guarding (co_node.c) */
    co_guard_t *g = &node->guard;
    if (node->hb.period_ms != 0U) {
        return; /* heartbeat producer active: node guarding disabled */
    }
    const co_frame_t reply = {0x700U + node->node_id, 1U, 0U, {(uint8_t)(g->toggle | (uint8_t)node->nmt_state)}};
    co_node_send(node, &reply);
    g->toggle ^= 0x80U;
    const uint32_t life = (uint32_t)g->guard_ms * g->life_factor;
    g->armed = life != 0U;
    g->deadline = life != 0U ? co_long_timer_start(node->now, life, &g->rest_ms) : CO_NEVER;
    co_node_due(node, CO_SVC_I_GUARD, g->deadline);
    if (g->failed) {
        g->failed = false;
        (void)co_emcy_clear(node, 0x8130U, guard_msef);
    }
}

co_time_us_t co_guard_process(co_node_t *node)
{
    co_guard_t *g = &node->guard;
    if (!g->armed || g->failed) {
        return CO_NEVER;
    }
    if (node->hb.period_ms != 0U) {
        g->armed = false;
        return CO_NEVER;
    }
    if (co_long_timer_expired(node->now, &g->deadline, &g->rest_ms)) {
        g->failed = true;
        co_node_event(node, CO_EV_GUARD_TIMEOUT, 0x100CU, 0U, 0U, 0U);
        (void)co_emcy_raise(node, 0x8130U, 0x10U, guard_msef);
        return CO_NEVER;
    }
    return g->deadline;
}

#endif /* CO_CONFIG_NODE_GUARDING */
