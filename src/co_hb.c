/*
 * Heartbeat producer (CiA 301 §7.2.8.3.2.2): 0x700+node-ID [1] state, every 0x1017 ms (0 = off).
 * Deadlines are absolute: a late call does not shift the following heartbeats (no drift).
 */
#include "priv/co_priv.h"

static uint32_t period_us(const co_node_t *node) { return (uint32_t)node->hb.period_ms * 1000U; }

/* A state byte on 0x700 + node-ID: the heartbeat, and the boot-up (state Initialising, 0). */
void co_hb_send(co_node_t *node, co_nmt_state_t state)
{
    const co_frame_t f = {0x700U + node->node_id, 1U, 0U, {(uint8_t)state}};
    co_node_send(node, &f);
}

co_time_us_t co_hb_process(co_node_t *node)
{
    /* hb.due is CO_NEVER exactly when 0x1017 is 0 (co_hb_written sets both), and CO_NEVER is never reached. */
    if (co_time_reached(node->now, node->hb.due)) {
        co_hb_send(node, node->nmt_state);
        /* Next deadline on the original grid; periods missed entirely (a very late call) are skipped. */
        node->hb.due = co_next_on_grid(node->hb.due, period_us(node), node->now);
    }
    return node->hb.due;
}

/* 0x1017 took a value (e NULL: at a reset, the dictionary's): a new period starts now. */
void co_hb_written(co_node_t *node, const co_od_entry_t *e)
{
    const uint32_t ms = e != NULL ? co_od_entry_u32(node, e) : co_od_u32_or(node, 0x1017U, 0U, 0U);
    node->hb.period_ms = (uint16_t)ms;
    const uint32_t p = period_us(node);
    node->hb.due = p != 0U ? co_time_after(node->now, p) : CO_NEVER;
    co_node_due(node, CO_SVC_I_HB, node->hb.due);
}
