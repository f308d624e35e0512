/*
 * SYNC consumer (CiA 301 §7.2.5): COB-ID 0x1005, communication cycle period 0x1006 (timeout after 1.5
 * periods, EMCY 0x8100), synchronous window 0x1007, counter overflow value 0x1019 (0: SYNC has no data,
 * 2..240: one counter byte). A SYNC of the wrong length raises EMCY 0x8240 and is not processed.
 * Consumed in Pre-operational and Operational; synchronous PDOs act in Operational only (co_pdo.c).
 */
#include "priv/co_priv.h"

#if CO_CONFIG_SYNC

static const uint8_t sync_msef[5] = {0x03U, 0U, 0U, 0U, 0U};

static co_time_us_t timeout_after(const co_node_t *node)
{
    const co_time_us_t period = co_od_u32_or(node, 0x1006U, 0U, 0U);
    return period != 0U ? node->now + period + period / 2U : CO_NEVER;
}

void co_sync_reset(co_node_t *node)
{
    node->sync.timeout_due = CO_NEVER;
    node->sync.window_end = CO_NEVER;
    node->sync.timeout_error = false;
    node->sync.length_error = false;
}

bool co_sync_rx(co_node_t *node, const co_frame_t *f)
{
    const co_od_entry_t *e = co_od_find(node->od, 0x1005U, 0U);
    if (e == NULL || f->id != (co_od_entry_u32(node, e) & CO_COBID_CAN_ID)) {
        return false;
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        return true;
    }
    const uint32_t overflow = co_od_u32_or(node, 0x1019U, 0U, 0U);
    if (f->len != (overflow != 0U ? 1U : 0U)) {
        if (!node->sync.length_error) {
            node->sync.length_error = true;
            (void)co_emcy_raise(node, 0x8240U, 0x10U, sync_msef);
        }
        return true;
    }
    if (node->sync.length_error) {
        node->sync.length_error = false;
        (void)co_emcy_clear(node, 0x8240U, sync_msef);
    }
    if (node->sync.timeout_error) {
        node->sync.timeout_error = false;
        (void)co_emcy_clear(node, 0x8100U, sync_msef);
    }
    node->sync.timeout_due = timeout_after(node);
    const uint32_t window = co_od_u32_or(node, 0x1007U, 0U, 0U);
    node->sync.window_end = window != 0U ? node->now + window : CO_NEVER;
    co_pdo_on_sync(node, overflow != 0U ? f->data[0] : 0U);
    return true;
}

co_time_us_t co_sync_process(co_node_t *node)
{
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        node->sync.timeout_due = CO_NEVER; /* consumer off: monitoring restarts with the next SYNC */
        return CO_NEVER;
    }
    if (node->sync.timeout_error || node->sync.timeout_due == CO_NEVER) {
        return CO_NEVER;
    }
    if (node->now >= node->sync.timeout_due) {
        node->sync.timeout_error = true;
        (void)co_emcy_raise(node, 0x8100U, 0x10U, sync_msef);
        return CO_NEVER;
    }
    return node->sync.timeout_due;
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
    if (e->index == 0x1006U && node->sync.timeout_due != CO_NEVER) {
        node->sync.timeout_due = timeout_after(node);
    }
}

#endif /* CO_CONFIG_SYNC */
