/*
 * The node: power-on, reset sequencing, frame dispatch to the services, the shared transmit queue, and
 * the process loop that collects every service's next deadline.
 */
#include "priv/co_priv.h"

/* CiA 305 bit-timing table (index -> kbit/s); index 9 (auto-detection) is not supported by an emulator. */
static const uint16_t cia305_bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};

bool co_cob_id_restricted(uint32_t can_id)
{
    return can_id <= 0x07FU || (can_id >= 0x101U && can_id <= 0x180U) || (can_id >= 0x581U && can_id <= 0x5FFU) ||
           (can_id >= 0x601U && can_id <= 0x67FU) || (can_id >= 0x6E0U && can_id <= 0x6FFU) || can_id >= 0x701U;
}

uint32_t co_cob_id_check(uint32_t v, uint32_t cur, bool in_use)
{
    if ((v & 0x3FFFF800UL) != 0U) {
        return CO_ABORT_INVALID_VALUE; /* 29-bit identifiers and reserved bits */
    }
    if ((v & CO_COBID_INVALID) != 0U) {
        return CO_ABORT_NONE;
    }
    if (co_cob_id_restricted(v & CO_COBID_CAN_ID)) {
        return CO_ABORT_INVALID_VALUE;
    }
    if (in_use && ((v ^ cur) & CO_COBID_CAN_ID) != 0U) {
        return CO_ABORT_INVALID_VALUE; /* the CAN-ID may only change while the COB-ID is not valid */
    }
    return CO_ABORT_NONE;
}

void co_node_event(co_node_t *node, co_event_kind_t kind, uint16_t index, uint8_t sub, uint32_t value,
                   uint32_t code)
{
    if (node->hooks != NULL && node->hooks->on_event != NULL) {
        const co_event_t ev = {kind, index, sub, value, code};
        node->hooks->on_event(node->hooks_ctx, node, &ev);
    }
}

static void tx_dropped(co_node_t *node, const co_frame_t *frame)
{
    node->stats.tx_dropped++;
    co_node_event(node, CO_EV_TX_DROPPED, 0U, 0U, frame->id, 0U);
}

void co_node_send(co_node_t *node, const co_frame_t *frame)
{
    if (node->lss.silent_until != 0U && node->now < node->lss.silent_until) {
        node->stats.tx_suppressed++; /* CiA 305: no frame during the bit-rate switch */
        return;
    }
    if (node->txq.count == 0U) {
        const co_status_t st = node->port->send(node->port_ctx, frame);
        if (st == CO_OK) {
            node->stats.tx_frames++;
            return;
        }
        if (st != CO_ERR_BUSY) {
            tx_dropped(node, frame);
            return;
        }
    }
    if (node->txq.count >= CO_TX_QUEUE_LEN) {
        tx_dropped(node, frame);
        return;
    }
    const uint8_t tail = (uint8_t)((node->txq.head + node->txq.count) % CO_TX_QUEUE_LEN);
    node->txq.frame[tail] = *frame;
    node->txq.count++;
}

/* Sends queued frames in order until the port is busy. Returns the retry deadline or CO_NEVER. */
static co_time_us_t txq_flush(co_node_t *node)
{
    if (node->txq.count > 0U && node->lss.silent_until != 0U && node->now < node->lss.silent_until) {
        return node->lss.silent_until; /* CiA 305 bit-rate switch: queued frames wait for its end */
    }
    while (node->txq.count > 0U) {
        const co_status_t st = node->port->send(node->port_ctx, &node->txq.frame[node->txq.head]);
        if (st == CO_ERR_BUSY) {
            return node->now + CO_TX_RETRY_US;
        }
        if (st == CO_OK) {
            node->stats.tx_frames++;
        } else {
            tx_dropped(node, &node->txq.frame[node->txq.head]);
        }
        node->txq.head = (uint8_t)((node->txq.head + 1U) % CO_TX_QUEUE_LEN);
        node->txq.count--;
    }
    return CO_NEVER;
}

void co_node_set_state(co_node_t *node, co_nmt_state_t state)
{
    const co_nmt_state_t from = node->nmt_state;
    if (from == state) {
        return;
    }
    node->nmt_state = state;
    co_pdo_on_state(node, from, state);
    co_node_event(node, CO_EV_NMT_STATE, 0U, 0U, (uint32_t)state, (uint32_t)from);
    if (node->hooks != NULL && node->hooks->on_nmt_change != NULL) {
        node->hooks->on_nmt_change(node->hooks_ctx, node, from, state);
    }
}

/* loaded: the communication area was just loaded with the application area (a reset application). Otherwise
 * it is loaded again, unless the stored parameters were refused (their records passed no write check). */
static void reset_communication(co_node_t *node, bool loaded)
{
    node->nmt_state = CO_NMT_INITIALISING;
    node->node_id = node->lss.pending_node_id;
    if (!loaded) {
        co_od_defaults_area(node, 0x1000U, 0x1FFFU);
        if (node->nvm_status != CO_NVM_REFUSED) {
            co_store_load_area(node, 0x1000U, 0x1FFFU);
        }
    }
    co_emcy_reset(node);
    co_sdo_reset(node);
    co_hb_reset(node);
#if CO_CONFIG_NODE_GUARDING
    co_guard_reset(node);
#endif
    co_hbc_reset(node);
#if CO_CONFIG_SYNC
    co_sync_reset(node);
#endif
    co_pdo_reset(node);
    if (node->hooks != NULL && node->hooks->on_reset != NULL) {
        node->hooks->on_reset(node->hooks_ctx, node, CO_RESET_COMMUNICATION);
    }
    if (node->node_id == CO_NODE_ID_UNCONFIGURED) {
        return; /* CiA 305: an unconfigured node runs LSS only and sends no boot-up */
    }
    const co_frame_t bootup = {0x700U + node->node_id, 1U, 0U, {0U}};
    co_node_send(node, &bootup);
    co_node_set_state(node, CO_NMT_PRE_OPERATIONAL);
}

void co_node_reset(co_node_t *node, co_reset_t what, co_time_us_t now)
{
    node->now = now;
    const bool application = what == CO_RESET_APPLICATION;
    if (application) {
        /* Both areas from one pass over the stored records, so that one refused record refuses them all. */
        node->nmt_state = CO_NMT_INITIALISING;
        node->node_id = node->lss.pending_node_id;
        co_od_reset_area(node, 0x1000U, 0x9FFFU);
        co_node_event(node, CO_EV_NVM_LOADED, 0x1010U, 0U, (uint32_t)node->nvm_status, 0U);
        if (node->hooks != NULL && node->hooks->on_reset != NULL) {
            node->hooks->on_reset(node->hooks_ctx, node, CO_RESET_APPLICATION);
        }
    }
    reset_communication(node, application);
}

co_status_t co_node_init(co_node_t *node, const co_node_cfg_t *cfg, co_time_us_t now)
{
    if (node == NULL || cfg == NULL || cfg->od == NULL || cfg->values == NULL || cfg->port == NULL ||
        cfg->port->send == NULL) {
        return CO_ERR_ARG;
    }
    if (cfg->node_id == 0U || (cfg->node_id > 127U && cfg->node_id != CO_NODE_ID_UNCONFIGURED)) {
        return CO_ERR_ARG;
    }
    memset(node, 0, sizeof *node);
    node->od = cfg->od;
    node->values = (uint8_t *)cfg->values;
    node->port = cfg->port;
    node->port_ctx = cfg->port_ctx;
    node->hooks = cfg->hooks;
    node->hooks_ctx = cfg->hooks_ctx;
    node->bit_rates_kbit = cfg->bit_rates_kbit != NULL ? cfg->bit_rates_kbit : cia305_bit_rates;
    node->options = cfg->options;
    node->now = now;
    node->default_node_id = cfg->node_id;
    node->default_bit_timing = cfg->bit_timing;
    node->nmt_state = CO_NMT_INITIALISING;
    if (cfg->rpdo != NULL) {
        node->rpdo = cfg->rpdo;
        node->rpdo_cap = cfg->rpdo_count;
    } else {
        node->rpdo = node->rpdo_own;
        node->rpdo_cap = CO_RPDO_MAX;
    }
    if (cfg->tpdo != NULL) {
        node->tpdo = cfg->tpdo;
        node->tpdo_cap = cfg->tpdo_count;
    } else {
        node->tpdo = node->tpdo_own;
        node->tpdo_cap = CO_TPDO_MAX;
    }
    if (co_pdo_count(node) != CO_OK || co_sdo_count(node, cfg->sdo_servers, cfg->sdo_server_count) != CO_OK ||
        co_od_sub_count(node->od, 0x1016U) > CO_HB_CONSUMER_MAX) {
        return CO_ERR_RANGE;
    }
    memcpy(node->values, node->od->defaults, node->od->values_size);
    uint8_t node_id = cfg->node_id;
    uint8_t bit_timing = cfg->bit_timing;
    const co_nvm_status_t lss = co_store_lss_load(node, &node_id, &bit_timing);
    if (lss == CO_NVM_LOADED) {
        if (node->port->set_bit_rate != NULL && node->bit_rates_kbit[bit_timing] != 0U) {
            (void)node->port->set_bit_rate(node->port_ctx, node->bit_rates_kbit[bit_timing]);
        }
    }
    if (bit_timing >= CO_LSS_BIT_TIMING_COUNT) {
        bit_timing = 0U; /* a bad configured default: index 0 of the table, never past its end */
    }
    node->node_id = node_id;
    node->lss.active_bit_timing = bit_timing;
    co_node_event(node, CO_EV_NVM_LOADED, 0x7E5U, 0U, (uint32_t)lss, 0U); /* the LSS area, once at power-on */
    co_lss_init(node);
    co_node_reset(node, CO_RESET_APPLICATION, now);
    return CO_OK;
}

static bool services_run(const co_node_t *node)
{
    return node->node_id != CO_NODE_ID_UNCONFIGURED && node->nmt_state != CO_NMT_INITIALISING;
}

bool co_node_rx(co_node_t *node, const co_frame_t *frame, co_time_us_t now)
{
    node->now = now;
    node->stats.rx_frames++;
    if ((frame->flags & (CO_FRAME_EFF | CO_FRAME_ERR)) != 0U || frame->len > 8U) {
        return false;
    }
    if (frame->id == 0x7E5U) {
        if ((node->options & CO_OPT_NO_LSS) != 0U) {
            return false; /* a device without LSS (EDS LSS_Supported=0) ignores the master's requests */
        }
        co_lss_rx(node, frame);
        return true;
    }
    if (!services_run(node)) {
        return false;
    }
    if (frame->id == 0x000U) {
        if ((frame->flags & CO_FRAME_RTR) != 0U) {
            return false;
        }
        co_nmt_rx(node, frame);
        return true;
    }
    if ((frame->flags & CO_FRAME_RTR) != 0U) {
#if CO_CONFIG_NODE_GUARDING
        if (frame->id == 0x700U + node->node_id) {
            co_guard_rx(node, frame);
            return true;
        }
#endif
        return false; /* RTR for TPDOs (types 252/253) is not supported */
    }
#if CO_CONFIG_SYNC
    if (co_sync_rx(node, frame)) {
        return true;
    }
#endif
    if (frame->id == 0x600U + node->node_id) {
        co_sdo_rx(node, &node->sdo, frame);
        return true;
    }
#if CO_CONFIG_SDO_SERVERS
    if (node->n_sdo_extra != 0U && co_sdo_rx_extra(node, frame)) {
        return true;
    }
#endif
    if (co_pdo_rx(node, frame)) {
        return true;
    }
    return co_hbc_rx(node, frame);
}

co_time_us_t co_node_process(co_node_t *node, co_time_us_t now)
{
    node->now = now;
    co_time_us_t next = txq_flush(node);
    next = co_min_time(next, co_lss_process(node));
    if (services_run(node)) {
        next = co_min_time(next, co_hb_process(node));
#if CO_CONFIG_NODE_GUARDING
        next = co_min_time(next, co_guard_process(node));
#endif
        next = co_min_time(next, co_hbc_process(node));
        next = co_min_time(next, co_sdo_process(node));
#if CO_CONFIG_SYNC
        next = co_min_time(next, co_sync_process(node));
#endif
        next = co_min_time(next, co_pdo_process(node));
        next = co_min_time(next, co_emcy_process(node));
    }
    if (node->txq.count > 0U) {
        next = co_min_time(next, now + CO_TX_RETRY_US);
    }
    return next;
}

co_nmt_state_t co_node_state(const co_node_t *node) { return node->nmt_state; }

uint8_t co_node_id(const co_node_t *node) { return node->node_id; }
