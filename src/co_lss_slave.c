/*
 * LSS slave (CiA 305): switch state global/selective, configure node-ID and bit timing, activate bit
 * timing, store configuration, inquire identity and node-ID, identify remote / non-configured slave,
 * fastscan. Master -> slave on 0x7E5, slave -> master on 0x7E4, always 8 bytes. Works in every NMT state.
 * The LSS address is 0x1018 sub 1..4 (vendor, product, revision, serial).
 */
#include "priv/co_priv.h"

enum { LSS_WAITING = 0, LSS_CONFIGURATION = 1 };

static uint32_t identity(const co_node_t *node, uint8_t i)
{
    return co_od_u32_or(node, 0x1018U, (uint8_t)(i + 1U), 0U);
}

/* Every answer is cs and at most a 32-bit number in bytes 1..4 (an error code in byte 1, an identity number, the
 * node-ID), the rest zero: one frame builder for all of them. */
static void reply(co_node_t *node, uint8_t cs, uint32_t v)
{
    co_frame_t f = {0x7E4U, 8U, 0U, {cs, 0U, 0U, 0U, 0U, 0U, 0U, 0U}};
    co_put_u32(&f.data[1], v);
    co_node_send(node, &f);
}

/* Power-on (the node zeroed: waiting state, no sequence under way): the node-ID and bit timing an LSS master stored,
 * else the configured ones. */
void co_lss_init(co_node_t *node)
{
    co_lss_slave_t *l = &node->lss;
    node->node_id = node->default_node_id;
    l->active_bit_timing = node->default_bit_timing;
    const co_nvm_status_t st = co_store_lss_load(node, &node->node_id, &l->active_bit_timing);
    if (st == CO_NVM_LOADED && node->port->set_bit_rate != NULL && node->bit_rates_kbit[l->active_bit_timing] != 0U) {
        (void)node->port->set_bit_rate(node->port_ctx, node->bit_rates_kbit[l->active_bit_timing]);
    }
    if (l->active_bit_timing >= CO_LSS_BIT_TIMING_COUNT) {
        l->active_bit_timing = 0U; /* a bad configured default: index 0 of the table, never past its end */
    }
    co_node_event(node, CO_EV_NVM_LOADED, 0x7E5U, 0U, (uint32_t)st, 0U); /* the LSS area, once at power-on */
    l->pending_node_id = node->node_id;
    l->pending_bit_timing = l->active_bit_timing;
    l->silent_until = CO_NEVER;
}

bool co_lss_set_pending_node_id(co_node_t *node, uint8_t node_id)
{
    const bool unconfigure_ok = (node->options & CO_OPT_LSS_NO_UNCONFIGURE) == 0U;
    if ((node_id < 1U || node_id > 127U) && !(node_id == CO_NODE_ID_UNCONFIGURED && unconfigure_ok)) {
        return false;
    }
    node->lss.pending_node_id = node_id;
    return true;
}

bool co_lss_set_pending_bit_timing(co_node_t *node, uint8_t index)
{
    if (index >= CO_LSS_BIT_TIMING_COUNT || node->bit_rates_kbit[index] == 0U) {
        return false;
    }
    node->lss.pending_bit_timing = index;
    return true;
}

co_status_t co_lss_store(co_node_t *node)
{
    return co_store_lss_save(node, node->lss.pending_node_id, node->lss.pending_bit_timing); /* CO_ERR_IO without NVM */
}

co_status_t co_lss_apply_bit_timing(co_node_t *node)
{
    co_lss_slave_t *l = &node->lss;
    const uint16_t kbit = l->pending_bit_timing < CO_LSS_BIT_TIMING_COUNT ? node->bit_rates_kbit[l->pending_bit_timing] : 0U;
    if (kbit == 0U) {
        return CO_ERR_ARG;
    }
    l->active_bit_timing = l->pending_bit_timing;
    if (node->port->set_bit_rate != NULL) {
        (void)node->port->set_bit_rate(node->port_ctx, kbit);
    }
    co_node_event(node, CO_EV_LSS_ACTIVATE, 0U, 0U, kbit, 0U);
    return CO_OK;
}

static void switch_global(co_node_t *node, uint8_t mode)
{
    co_lss_slave_t *l = &node->lss;
    if (mode == LSS_CONFIGURATION || mode == LSS_WAITING) {
        l->state = mode;
    }
    /* An unconfigured node that got a node-ID starts at once (reset communication, boot-up) rather than waiting for
     * NMT 0x82, as CANopenNode does; see docs/decisions.md. */
    if (mode == LSS_WAITING && node->node_id == CO_NODE_ID_UNCONFIGURED &&
        l->pending_node_id != CO_NODE_ID_UNCONFIGURED) {
        co_node_reset(node, CO_RESET_COMMUNICATION, node->now);
    }
    l->select_step = 0U;
}

/* Steps of a sequence come in order, the first at any time; any other frame of it starts the sequence again.
 * True when step is the one expected (the next is then expected). */
static bool next_in_sequence(uint8_t *expected, uint8_t step)
{
    if (step != 0U && step != *expected) {
        *expected = 0U;
        return false;
    }
    *expected = (uint8_t)(step + 1U);
    return true;
}

/* A number of a sequence checked: one that is not ours ends the sequence at once (its later frames are then out of
 * order and answered by nothing, as a full sequence with one wrong number would be), and so does the last. True when
 * the last was ours: the whole sequence matched. */
static bool last_in_sequence(uint8_t *expected, bool ours, bool last)
{
    if (!ours || last) {
        *expected = 0U;
    }
    return ours && last;
}

/* Switch state selective, cs 0x40..0x43: vendor, product, revision, serial. */
static void switch_selective(co_node_t *node, uint8_t cs, uint32_t v)
{
    co_lss_slave_t *l = &node->lss;
    const uint8_t step = (uint8_t)(cs - 0x40U);
    if (l->state != LSS_WAITING || !next_in_sequence(&l->select_step, step)) {
        return;
    }
    if (last_in_sequence(&l->select_step, v == identity(node, step), step == 3U)) {
        l->state = LSS_CONFIGURATION;
        reply(node, 0x44U, 0U);
    }
}

/* Identify remote slave, cs 0x46..0x4B in order: vendor, product, revision low/high, serial low/high. An exact number
 * (vendor, product) is checked as the range [v, v]; the low bound of a range is kept until its high bound comes. */
static void identify_remote(co_node_t *node, uint8_t cs, uint32_t v)
{
    co_lss_slave_t *l = &node->lss;
    const uint8_t step = (uint8_t)(cs - 0x46U);
    if (!next_in_sequence(&l->ident_step, step)) {
        return;
    }
    if (step != 3U && step != 5U) { /* not a high bound */
        l->ident_low = v;
        if (step >= 2U) {
            return; /* a low bound: its high bound follows */
        }
    }
    const uint32_t id = identity(node, (uint8_t)((step + 1U) >> 1)); /* steps 0, 1, 3, 5: 0x1018 sub 1..4 */
    if (last_in_sequence(&l->ident_step, l->ident_low <= id && id <= v, step == 5U)) {
        reply(node, 0x4FU, 0U);
    }
}

#if CO_CONFIG_LSS_FASTSCAN
static void fastscan(co_node_t *node, const uint8_t *d, uint32_t id_number)
{
    co_lss_slave_t *l = &node->lss;
    const uint8_t bit_checked = d[5];
    const uint8_t lss_sub = d[6];
    const uint8_t lss_next = d[7];
    /* Only unconfigured slaves in waiting state take part (CANopenNode's rule; decisions.md). */
    if (l->state != LSS_WAITING || node->node_id != CO_NODE_ID_UNCONFIGURED) {
        return;
    }
    if (bit_checked == 0x80U) {
        l->fastscan_pos = 0U; /* a new scan: every slave taking part answers */
    } else {
        /* lss_sub is checked by its equality with fastscan_pos, which is never above 3 */
        if (bit_checked > 31U || lss_next > 3U || lss_sub != l->fastscan_pos) {
            return;
        }
        if (((id_number ^ identity(node, lss_sub)) >> bit_checked) != 0U) {
            return; /* a bit from bit_checked up differs */
        }
        if (bit_checked == 0U) {
            l->fastscan_pos = lss_next;
            if (lss_next < lss_sub) {
                l->state = LSS_CONFIGURATION; /* all four numbers matched */
                l->fastscan_pos = 0U;
            }
        }
    }
    reply(node, 0x4FU, 0U);
}
#endif

/* The configuration services but the inquiries: configure node-ID (0x11) and bit timing (0x13), activate bit timing
 * (0x15), store configuration (0x17). All but activate bit timing answer with cs and an error code. */
static void configure(co_node_t *node, uint8_t cs, const uint8_t *d)
{
    co_lss_slave_t *l = &node->lss;
    uint32_t error = 0U;
    if (cs == 0x11U || cs == 0x13U) { /* node-ID: d[1]; bit timing: d[1] the table (0: CiA 301's), d[2] the index */
        const bool node_id = cs == 0x11U;
        const uint8_t value = node_id ? d[1] : d[2];
        const bool ok = node_id ? co_lss_set_pending_node_id(node, value)
                                : d[1] == 0U && co_lss_set_pending_bit_timing(node, value);
        if (ok) {
            co_node_event(node, node_id ? CO_EV_LSS_NODE_ID : CO_EV_LSS_BIT_TIMING, 0U, 0U, value, 0U);
        } else {
            error = 1U; /* out of range, not supported */
        }
    } else if (cs == 0x15U) {
        const uint32_t delay = (uint32_t)co_get_u16(&d[1]) * 1000U;
        l->switch_pending = true;
        l->switch_at = co_time_after(node->now, delay);
        l->silent_until = co_time_after(node->now, 2U * delay);
        return; /* no answer */
    } else if (cs == 0x17U) {
        if (node->port->nvm_write == NULL || node->port->nvm_commit == NULL) {
            error = 1U; /* storing not supported */
        } else if (co_store_lss_save(node, l->pending_node_id, l->pending_bit_timing) != CO_OK) {
            error = 2U; /* storage media access error */
        }
        co_node_event(node, CO_EV_STORE, 0x7E5U, 0x17U, l->pending_node_id, error);
    } else {
        return;
    }
    reply(node, cs, error);
}

void co_lss_rx(co_node_t *node, const co_frame_t *f)
{
    if (f->len != 8U) {
        return; /* (always a data frame: co_node_take routes no remote frame) */
    }
    const uint8_t cs = f->data[0];
    const uint32_t v = co_get_u32(&f->data[1]);
    if (cs == 0x04U) {
        switch_global(node, f->data[1]);
    } else if (cs >= 0x40U && cs <= 0x43U) {
        switch_selective(node, cs, v);
    } else if (cs >= 0x46U && cs <= 0x4BU) {
        identify_remote(node, cs, v);
    } else if (cs == 0x4CU) {
        if (node->node_id == CO_NODE_ID_UNCONFIGURED) {
            reply(node, 0x50U, 0U);
        }
#if CO_CONFIG_LSS_FASTSCAN
    } else if (cs == 0x51U) {
        fastscan(node, f->data, v);
#endif
    } else if (node->lss.state != LSS_CONFIGURATION) {
        return; /* the services below are the configuration state's */
    } else if (cs >= 0x5AU && cs <= 0x5EU) {
        /* inquire vendor, product, revision, serial (0x1018 sub 1..4), node-ID */
        reply(node, cs, cs == 0x5EU ? node->node_id : identity(node, (uint8_t)(cs - 0x5AU)));
    } else {
        configure(node, cs, f->data);
    }
}

co_time_us_t co_lss_process(co_node_t *node)
{
    co_lss_slave_t *l = &node->lss;
    if (l->switch_pending) {
        if (!co_time_reached(node->now, l->switch_at)) {
            return l->switch_at;
        }
        l->switch_pending = false;
        l->active_bit_timing = l->pending_bit_timing < CO_LSS_BIT_TIMING_COUNT ? l->pending_bit_timing : 0U;
        const uint16_t kbit = node->bit_rates_kbit[l->active_bit_timing];
        if (node->port->set_bit_rate != NULL) {
            (void)node->port->set_bit_rate(node->port_ctx, kbit);
        }
        co_node_event(node, CO_EV_LSS_ACTIVATE, 0U, 0U, kbit, 0U);
    }
    if (co_time_pending(node->now, l->silent_until)) {
        return l->silent_until;
    }
    l->silent_until = CO_NEVER; /* over (retired: a past time would look ahead again once 32-bit time wraps) */
    return CO_NEVER;
}
