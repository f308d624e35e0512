/*
 * SYNC consumer and producer (CiA 301 §7.2.5): COB-ID 0x1005, communication cycle period 0x1006 (timeout after 1.5
 * periods, EMCY 0x8100), synchronous window 0x1007, counter overflow value 0x1019 (0: SYNC has no data,
 * 2..240: one counter byte). A SYNC of the wrong length raises EMCY 0x8240 and is not processed.
 * Consumed in Pre-operational and Operational; synchronous PDOs act in Operational only (co_pdo.c).
 * With 0x1005 bit 30 (gen, CO_CONFIG_SYNC_PRODUCER) the node produces the SYNC instead, every 0x1006 µs on its grid,
 * in Pre-operational and Operational, its counter from 1 up to 0x1019 and again from 1; it takes no SYNC from the bus
 * then and consumes its own (its synchronous PDOs), as CANopenNode does.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_SYNC

static const uint8_t sync_msef[5] = {0x03U, 0U, 0U, 0U, 0U};

/* One period after t (the producer's next SYNC), or 1.5 periods (half: the consumer's timeout): exact to the µs up to
 * 11 minutes, to the ms beyond (a long timer, co_priv.h); CO_NEVER without a period. */
static co_time_us_t periods_after(co_sync_t *sync, co_time_us_t t, bool half)
{
    const uint32_t period = sync->period_us;
    sync->rest_ms = 0U;
    if (period == 0U) {
        return CO_NEVER;
    }
    if (period <= CO_TIME_STEP_MS / 3U * 2000U) {
        return co_time_after(t, period + (half ? period / 2U : 0U));
    }
    const uint32_t ms = co_div_u32(period, 1000U, NULL);
    return co_long_timer_start(t, ms + (half ? ms / 2U : 0U), &sync->rest_ms);
}

static co_time_us_t timeout_after(co_node_t *node) { return periods_after(&node->sync, node->now, true); }

/* The parameters the consumer uses at every SYNC, from the OD (at a reset and when one is written). The
 * synchronous window 0x1007 needs no copy: synchronous TPDOs go out at the SYNC itself, inside any window. */
static void load_parameters(co_node_t *node)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, 0x1005U, 0U, &one);
    const uint32_t cob_id = e != NULL ? co_od_entry_u32(node, e) : 0U;
    node->sync.can_id = e != NULL ? (uint16_t)(cob_id & CO_COBID_CAN_ID) : CO_NO_CAN_ID;
#if CO_CONFIG_SYNC_PRODUCER
    node->sync.producer = e != NULL && (cob_id & CO_COBID_SYNC_GEN) != 0U;
#endif
    node->sync.period_us = co_od_u32_or(node, 0x1006U, 0U, 0U);
    node->sync.overflow = (uint8_t)co_od_u32_or(node, 0x1019U, 0U, 0U);
}

void co_sync_reset(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    load_parameters(node);
    sync->due = CO_NEVER;
    sync->timeout_error = false;
    sync->length_error = false;
}

void co_sync_rx(co_node_t *node, const co_frame_t *f)
{
    co_sync_t *sync = &node->sync;
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        return;
    }
    const uint8_t overflow = sync->overflow;
    if (f->len != (overflow != 0U ? 1U : 0U)) {
        if (!sync->length_error) {
            sync->length_error = true;
            (void)co_emcy_raise(node, 0x8240U, 0x10U, sync_msef);
        }
        return;
    }
    if (sync->length_error) {
        sync->length_error = false;
        (void)co_emcy_clear(node, 0x8240U, sync_msef);
    }
    if (sync->timeout_error) {
        sync->timeout_error = false;
        (void)co_emcy_clear(node, 0x8100U, sync_msef);
    }
    sync->due = timeout_after(node);
    co_node_due(node, CO_SVC_I_SYNC, sync->due);
    co_pdo_on_sync(node, overflow != 0U ? f->data[0] : 0U);
}

#if CO_CONFIG_SYNC_PRODUCER
/* The producer: a SYNC when one is due, then the node's synchronous PDOs at it. A period starts when production does
 * (a reset, Pre-operational from Stopped, 0x1005 or 0x1006 written: due is CO_NEVER), the counter from 1 again. */
static co_time_us_t produce(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    if (sync->due == CO_NEVER) {
        sync->counter = 0U;
        sync->due = periods_after(sync, node->now, false); /* CO_NEVER again with 0x1006 = 0 */
        return sync->due;
    }
    if (!co_long_timer_expired(node->now, &sync->due, &sync->rest_ms)) {
        return sync->due;
    }
    co_frame_t f = {sync->can_id, 0U, 0U, {0U}};
    if (sync->overflow != 0U) {
        sync->counter = sync->counter >= sync->overflow ? 1U : (uint8_t)(sync->counter + 1U);
        f.len = 1U;
        f.data[0] = sync->counter;
    }
    co_node_send(node, &f);
    /* On the grid (a late call skips whole periods); a long period from its deadline, to the ms. */
    sync->due = sync->period_us <= CO_TIME_STEP_MS / 3U * 2000U ? co_next_on_grid(sync->due, sync->period_us, node->now)
                                                                 : periods_after(sync, sync->due, false);
    co_pdo_on_sync(node, f.data[0]);
    return sync->due;
}
#endif

co_time_us_t co_sync_process(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        sync->due = CO_NEVER; /* consumer off: monitoring restarts with the next SYNC; producer: a new start */
        return CO_NEVER;
    }
#if CO_CONFIG_SYNC_PRODUCER
    if (sync->producer) {
        return produce(node);
    }
#endif
    if (sync->timeout_error) {
        return CO_NEVER;
    }
    if (co_long_timer_expired(node->now, &sync->due, &sync->rest_ms)) { /* CO_NEVER never expires */
        sync->timeout_error = true;
        (void)co_emcy_raise(node, 0x8100U, 0x10U, sync_msef);
        return CO_NEVER;
    }
    return sync->due;
}

uint32_t co_sync_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len, bool stored)
{
    const uint32_t v = len >= 4U ? co_get_u32(data) : data[0];
    switch (e->index) {
    case 0x1005:
        /* 29-bit IDs unsupported; bit 30 (gen) only where the producer is compiled in; bit 31 is not looked at */
        if ((v & (CO_CONFIG_SYNC_PRODUCER ? 0x3FFFF800UL : 0x7FFFF800UL)) != 0U) {
            return CO_ABORT_INVALID_VALUE;
        }
        if (co_cob_id_restricted(v & CO_COBID_CAN_ID)) {
            return CO_ABORT_INVALID_VALUE;
        }
#if CO_CONFIG_SYNC_PRODUCER
        if (!stored && node->sync.producer && (v & CO_COBID_SYNC_GEN) != 0U &&
            (v & CO_COBID_CAN_ID) != node->sync.can_id) {
            return CO_ABORT_INVALID_VALUE; /* CiA 301: the CAN-ID of a SYNC being produced does not change */
        }
#endif
        return CO_ABORT_NONE;
    case 0x1019:
        if (v == 1U || v > 240U) {
            return CO_ABORT_INVALID_VALUE;
        }
        if (!stored && co_od_u32_or(node, 0x1006U, 0U, 0U) != 0U) {
            return CO_ABORT_DEVICE_STATE; /* may only change while the cycle period is 0 */
        }
        return CO_ABORT_NONE;
    default:
        return CO_ABORT_NONE;
    }
}

void co_sync_written(co_node_t *node, const co_od_entry_t *e)
{
    co_sync_t *sync = &node->sync;
    const uint16_t rx_id = co_sync_rx_id(node);
    load_parameters(node);
#if CO_CONFIG_SYNC_PRODUCER
    if (sync->producer) {
        if (e->index != 0x1007U) {
            sync->due = CO_NEVER; /* production (re)starts at the next pass, with a full period */
        }
        if (sync->timeout_error) {
            sync->timeout_error = false; /* a producer does not watch its own SYNC */
            (void)co_emcy_clear(node, 0x8100U, sync_msef);
        }
    } else if (rx_id == CO_NO_CAN_ID) {
        sync->due = CO_NEVER; /* a producer no more: monitoring starts with the first SYNC */
    }
#endif
    if (e->index == 0x1006U && sync->due != CO_NEVER) {
        sync->due = timeout_after(node);
    }
    if (co_sync_rx_id(node) != rx_id) {
        co_node_routes_update(node);
    }
}

#endif /* CO_CONFIG_SYNC */
