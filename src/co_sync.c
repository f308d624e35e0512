/*
 * SYNC consumer (CiA 301 §7.2.5): COB-ID 0x1005, communication cycle period 0x1006 (timeout after 1.5
 * periods, EMCY 0x8100), synchronous window 0x1007, counter overflow value 0x1019 (0: SYNC has no data,
 * 2..240: one counter byte). A SYNC of the wrong length raises EMCY 0x8240 and is not processed.
 * Consumed in Pre-operational and Operational; synchronous PDOs act in Operational only (co_pdo.c).
 */
#include "priv/co_priv.h"

#if CO_CONFIG_SYNC

static const uint8_t sync_msef[5] = {0x03U, 0U, 0U, 0U, 0U};

/* 1.5 periods after now: exact to the µs up to 16.7 minutes, to the ms beyond (a long timer, co_priv.h). */
static co_time_us_t timeout_after(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    const uint32_t period = sync->period_us;
    sync->rest_ms = 0U;
    if (period == 0U) {
        return CO_NEVER;
    }
    if (period <= CO_TIME_STEP_MS / 3U * 2000U) {
        return co_time_after(node->now, period + period / 2U);
    }
    const uint32_t ms = co_div_u32(period, 1000U, NULL);
    return co_long_timer_start(node->now, ms + ms / 2U, &sync->rest_ms);
}

/* The parameters the consumer uses at every SYNC, from the OD (at a reset and when one is written). The
 * synchronous window 0x1007 needs no copy: synchronous TPDOs go out at the SYNC itself, inside any window. */
static void load_parameters(co_node_t *node)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, 0x1005U, 0U, &one);
    node->sync.can_id = e != NULL ? (uint16_t)(co_od_entry_u32(node, e) & CO_COBID_CAN_ID) : CO_NO_CAN_ID;
    node->sync.period_us = co_od_u32_or(node, 0x1006U, 0U, 0U);
    node->sync.overflow = (uint8_t)co_od_u32_or(node, 0x1019U, 0U, 0U);
}

void co_sync_reset(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    load_parameters(node);
    sync->timeout_due = CO_NEVER;
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
    sync->timeout_due = timeout_after(node);
    co_node_due(node, sync->timeout_due);
    co_pdo_on_sync(node, overflow != 0U ? f->data[0] : 0U);
}

co_time_us_t co_sync_process(co_node_t *node)
{
    co_sync_t *sync = &node->sync;
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        sync->timeout_due = CO_NEVER; /* consumer off: monitoring restarts with the next SYNC */
        return CO_NEVER;
    }
    if (sync->timeout_error) {
        return CO_NEVER;
    }
    if (co_long_timer_expired(node->now, &sync->timeout_due, &sync->rest_ms)) { /* CO_NEVER never expires */
        sync->timeout_error = true;
        (void)co_emcy_raise(node, 0x8100U, 0x10U, sync_msef);
        return CO_NEVER;
    }
    return sync->timeout_due;
}

uint32_t co_sync_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len, bool stored)
{
    const uint32_t v = len >= 4U ? co_get_u32(data) : data[0];
    switch (e->index) {
    case 0x1005:
        if ((v & 0x7FFFF800UL) != 0U) {
            return CO_ABORT_INVALID_VALUE; /* bit 30 (produce SYNC): a slave here only consumes; 29-bit IDs unsupported */
        }
        if (co_cob_id_restricted(v & CO_COBID_CAN_ID)) {
            return CO_ABORT_INVALID_VALUE;
        }
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
    const uint16_t can_id = sync->can_id;
    load_parameters(node);
    if (e->index == 0x1006U && sync->timeout_due != CO_NEVER) {
        sync->timeout_due = timeout_after(node);
    }
    if (sync->can_id != can_id) {
        co_node_routes_update(node);
    }
}

#endif /* CO_CONFIG_SYNC */
