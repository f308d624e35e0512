/*
 * The node: power-on, reset sequencing, frame dispatch to the services, the shared transmit queue, and
 * the process loop that collects every service's next deadline.
 */
#include "priv/co_priv.h"

/* CiA 305 bit-timing table (index -> kbit/s); index 9 (auto-detection) is not supported by an emulator. */
static const uint16_t cia305_bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};

uint32_t co_div_u32(uint32_t a, uint32_t b, uint32_t *rem)
{
    /* The dividend's bits leave a at the top into r while the quotient's bits enter a at the bottom. */
    uint32_t r = 0U;
    for (unsigned bit = 32U; bit > 0U; bit--) {
        const uint32_t carry = r >> 31; /* r < b, so 2r + 1 - b fits even when 2r does not */
        r = (r << 1) | (a >> 31);
        a <<= 1;
        if (carry != 0U || r >= b) {
            r -= b;
            a |= 1U;
        }
    }
    if (rem != NULL) {
        *rem = r;
    }
    return a;
}

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
    if (co_time_pending(node->now, node->lss.silent_until)) {
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
    co_txq_frame_t *q = &node->txq.frame[(unsigned)(node->txq.head + node->txq.count) % CO_TX_QUEUE_LEN];
    q->id = (uint16_t)frame->id;
    q->len = frame->len;
    memcpy(q->data, frame->data, 8U);
    node->txq.count++;
}

/* Sends queued frames in order until the port is busy (what is left makes the pass come again after
 * CO_TX_RETRY_US). */
static void txq_flush(co_node_t *node)
{
    while (node->txq.count > 0U) {
        const co_txq_frame_t *q = &node->txq.frame[node->txq.head];
        co_frame_t f = {q->id, q->len, 0U, {0U}};
        memcpy(f.data, q->data, 8U);
        const co_status_t st = node->port->send(node->port_ctx, &f);
        if (st == CO_ERR_BUSY) {
            return;
        }
        if (st == CO_OK) {
            node->stats.tx_frames++;
        } else {
            tx_dropped(node, &f);
        }
        node->txq.head = (uint8_t)((node->txq.head + 1U) % CO_TX_QUEUE_LEN);
        node->txq.count--;
    }
}

void co_node_set_state(co_node_t *node, co_nmt_state_t state)
{
    const co_nmt_state_t from = node->nmt_state;
    if (from == state) {
        return;
    }
    node->nmt_state = state;
    co_node_wake(node, CO_SVC_ALL); /* every service acts by the NMT state */
    co_pdo_on_state(node, from, state);
    co_node_event(node, CO_EV_NMT_STATE, 0U, 0U, (uint32_t)state, (uint32_t)from);
    if (node->hooks != NULL && node->hooks->on_nmt_change != NULL) {
        node->hooks->on_nmt_change(node->hooks_ctx, node, from, state);
    }
}

/* The device's on_reset hook, where it has one. */
static void reset_hook(co_node_t *node, co_reset_t what)
{
    if (node->hooks != NULL && node->hooks->on_reset != NULL) {
        node->hooks->on_reset(node->hooks_ctx, node, what);
    }
}

/* The start of a reset: the node-ID an LSS master configured takes effect (the dictionary's node-ID-relative
 * defaults use it). */
static void enter_initialising(co_node_t *node)
{
    node->nmt_state = CO_NMT_INITIALISING;
    node->node_id = node->lss.pending_node_id;
}

void co_node_reset(co_node_t *node, co_reset_t what, co_time_us_t now)
{
    node->now = now;
    co_node_wake(node, CO_SVC_ALL);
    enter_initialising(node);
    if (what == CO_RESET_APPLICATION) {
        /* Both areas from one pass over the stored records, so that one refused record refuses them all. */
        co_od_reset_area(node, 0x1000U, 0x9FFFU);
        co_node_event(node, CO_EV_NVM_LOADED, 0x1010U, 0U, (uint32_t)node->nvm_status, 0U);
        reset_hook(node, CO_RESET_APPLICATION);
        enter_initialising(node); /* again: the hook may have set a pending node-ID */
    } else {
        /* The communication area loaded again, unless the stored parameters were refused (their records passed no
         * write check). */
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
#if CO_CONFIG_HB_CONSUMER
    co_hbc_reset(node);
#endif
#if CO_CONFIG_SYNC
    co_sync_reset(node);
#endif
    co_pdo_reset(node);
    reset_hook(node, CO_RESET_COMMUNICATION);
    if (node->node_id != CO_NODE_ID_UNCONFIGURED) { /* CiA 305: an unconfigured node runs LSS only, no boot-up */
        co_hb_send(node, CO_NMT_INITIALISING); /* the boot-up */
        co_node_set_state(node, CO_NMT_PRE_OPERATIONAL);
    }
    co_node_routes_update(node);
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
#if !CO_CONFIG_OD_COMPACT
    /* A caller's own hash of the objects: a size outside 1..17 bits would shift by 32 or more in every look-up. */
    if (cfg->od->object_slots != NULL && (cfg->od->object_slot_bits < 1U || cfg->od->object_slot_bits > 17U)) {
        return CO_ERR_ARG;
    }
#endif
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
    if (cfg->routes != NULL) {
        node->route = cfg->routes;
        node->route_cap = cfg->route_count;
    } else {
        node->route = node->route_own;
        node->route_cap = (uint16_t)(sizeof node->route_own / sizeof node->route_own[0]);
    }
    if (co_pdo_count(node) != CO_OK || co_sdo_count(node, cfg->sdo_servers, cfg->sdo_server_count) != CO_OK ||
        co_od_sub_count(node->od, 0x1016U) > (CO_CONFIG_HB_CONSUMER ? CO_HB_CONSUMER_MAX : 0U) ||
        (!CO_CONFIG_EMCY_HISTORY && co_od_has_index(node->od, 0x1003U)) ||
        (!CO_CONFIG_EMCY_INHIBIT && co_od_has_index(node->od, 0x1015U)) ||
        node->route_cap < CO_RX_ROUTES_FIXED + node->n_rpdo + node->n_sdo_extra) {
        return CO_ERR_RANGE;
    }
    co_od_copy_defaults(node->od, 0U, (size_t)node->od->values_size, node->values);
    co_lss_init(node); /* the node-ID and bit timing */
    co_node_reset(node, CO_RESET_APPLICATION, now);
    return CO_OK;
}

static bool services_run(const co_node_t *node)
{
    return node->node_id != CO_NODE_ID_UNCONFIGURED && node->nmt_state != CO_NMT_INITIALISING;
}

/* ---- Frame routing: a table of the COB-IDs the node takes, sorted, built when one of them changes ---------- */

static uint16_t route_target(enum co_rx_kind kind, uint16_t n) { return (uint16_t)(((unsigned)kind << 12) | n); }

/* Adds an id in order. An id already taken keeps its service: the order of the calls is the priority, as the order
 * of the tests was before the table (SYNC, then the SDO servers, then the RPDOs). */
static void route_add(co_node_t *node, uint16_t id, uint16_t target)
{
    co_rx_route_t *const route = node->route;
    const unsigned n = node->n_route;
    unsigned i = n;
    while (i > 0U && route[i - 1U].id > id) {
        i--;
    }
    if ((i > 0U && route[i - 1U].id == id) || n >= node->route_cap) {
        return; /* the capacity is checked at co_node_init: never full */
    }
    for (unsigned k = n; k > i; k--) {
        route[k].id = route[k - 1U].id;
        route[k].target = route[k - 1U].target;
    }
    route[i].id = id;
    route[i].target = target;
    node->n_route = (uint16_t)(n + 1U);
}

/* A heartbeat (0x701..0x77F) of a node this one monitors. */
static bool monitored(const co_node_t *node, uint32_t id)
{
#if CO_CONFIG_HB_CONSUMER
    const uint32_t other = id - 0x700U;
    return other - 1U < 127U && (node->hbc.monitored[other >> 3] & (1U << (other & 7U))) != 0U;
#else
    (void)node;
    (void)id;
    return false;
#endif
}

void co_node_routes_update(co_node_t *node)
{
    node->n_route = 0U;
    if ((node->options & CO_OPT_NO_LSS) == 0U) {
        route_add(node, 0x7E5U, route_target(CO_RX_LSS, 0U));
    }
    if (services_run(node)) {
        route_add(node, 0x000U, route_target(CO_RX_NMT, 0U));
#if CO_CONFIG_SYNC
        if (co_sync_rx_id(node) != CO_NO_CAN_ID) {
            route_add(node, co_sync_rx_id(node), route_target(CO_RX_SYNC, 0U));
        }
#endif
        route_add(node, node->sdo.rx_id, route_target(CO_RX_SDO, 0U));
#if CO_CONFIG_SDO_SERVERS
        for (uint8_t i = 0U; i < node->n_sdo_extra; i++) {
            if (node->sdo_extra[i].rx_id != CO_SDO_NO_ID) {
                route_add(node, node->sdo_extra[i].rx_id, route_target(CO_RX_SDO, (uint16_t)(i + 1U)));
            }
        }
#endif
        for (uint16_t n = 0U; n < node->n_rpdo; n++) {
            if (node->rpdo[n].valid) {
                route_add(node, (uint16_t)(node->rpdo[n].cob_id & CO_COBID_CAN_ID), route_target(CO_RX_RPDO, n));
            }
        }
    }
    memset(node->route_hash, 0, sizeof node->route_hash);
    for (uint16_t i = 0U; i < node->n_route; i++) {
        uint8_t *b = &node->route_hash[CO_ROUTE_HASH(node->route[i].id)];
        *b = (*b == 0U && i < 0xFEU) ? (uint8_t)(i + 1U) : 0xFFU;
    }
    for (uint16_t id = 0x701U; id <= 0x77FU; id++) {
        if (monitored(node, id)) {
            node->route_hash[CO_ROUTE_HASH(id)] = 0xFFU; /* a consumed heartbeat: not in the table, looked at */
        }
    }
    node->rx_ids_version++;
    co_node_event(node, CO_EV_RX_FILTER, 0U, 0U, node->n_route, 0U);
}

/* A remote frame on 0x700 + node-ID asks for the node-guarding answer, when the OD has node guarding. */
static bool guarding_request(const co_node_t *node, const co_frame_t *frame)
{
#if CO_CONFIG_NODE_GUARDING
    return frame->flags == CO_FRAME_RTR && frame->id == 0x700U + node->node_id && node->guard.present &&
           services_run(node);
#else
    (void)node;
    (void)frame;
    return false;
#endif
}

static void put_one(uint16_t *ids, uint16_t cap, uint16_t *n, uint32_t *from, uint32_t id)
{
    if (*n < cap) {
        ids[*n] = (uint16_t)id;
    }
    (*n)++;
    *from = id + 1U;
}

/* Puts id (0x800: none) in order: after the ids below it of the TPDOs answering remote requests (co_tpdo_rtr_next from
 * *from, the lowest id not yet put), once. */
static void put_id(const co_node_t *node, uint16_t *ids, uint16_t cap, uint16_t *n, uint32_t *from, uint32_t id)
{
#if CO_CONFIG_TPDO_RTR
    for (uint32_t t; services_run(node) && (t = co_tpdo_rtr_next(node, *from)) < id;) {
        put_one(ids, cap, n, from, t);
    }
    if (id < 0x800U && id >= *from) {
        put_one(ids, cap, n, from, id);
    }
#else
    (void)node;
    if (id < 0x800U) {
        put_one(ids, cap, n, from, id);
    }
#endif
}

uint16_t co_node_rx_ids(const co_node_t *node, uint16_t *ids, uint16_t cap)
{
    uint16_t n = 0U;
    uint16_t r = 0U;
    uint32_t from = 0U;
    for (; r < node->n_route && node->route[r].id <= 0x700U; r++) {
        put_id(node, ids, cap, &n, &from, node->route[r].id);
    }
    if (services_run(node)) { /* heartbeats consumed and the guard request, between the table's ids */
        for (uint16_t id = 0x701U; id <= 0x77FU; id++) {
            const co_frame_t guard = {id, 0U, CO_FRAME_RTR, {0U}};
            if (guarding_request(node, &guard) || monitored(node, id)) {
                put_id(node, ids, cap, &n, &from, id);
            }
        }
    }
    for (; r < node->n_route; r++) {
        put_id(node, ids, cap, &n, &from, node->route[r].id);
    }
    put_id(node, ids, cap, &n, &from, 0x800U); /* the TPDOs' ids above the others */
    return n;
}

static const co_rx_route_t *route_find(const co_node_t *node, uint16_t id)
{
    const unsigned b = node->route_hash[CO_ROUTE_HASH(id)];
    if (b != 0xFFU) {
        return (b != 0U && node->route[b - 1U].id == id) ? &node->route[b - 1U] : NULL;
    }
    unsigned lo = 0U;
    unsigned hi = node->n_route;
    while (lo < hi) {
        const unsigned mid = (lo + hi) >> 1;
        if (node->route[mid].id < id) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return (lo < node->n_route && node->route[lo].id == id) ? &node->route[lo] : NULL;
}

bool co_node_rx(co_node_t *node, const co_frame_t *frame, co_time_us_t now)
{
    node->now = now;
    node->stats.rx_frames++;
    const uint32_t id = frame->id;
    if (frame->flags == 0U && id <= 0x7FFU && node->route_hash[CO_ROUTE_HASH(id)] == 0U) {
        return false; /* a data frame in a bucket of no route and no heartbeat it consumes: for other nodes */
    }
    return co_node_take(node, frame);
}

/* Out of co_node_rx (CO_NOINLINE: since RTR TPDOs GCC inlined it there though it is not static), so that the early
 * return there saves no registers. */
bool co_node_take(co_node_t *node, const co_frame_t *frame)
{
    if (frame->flags != 0U || frame->len > 8U || frame->id > 0x7FFU) {
#if CO_CONFIG_TPDO_RTR
        if (frame->flags == CO_FRAME_RTR && frame->id <= 0x7FFU && services_run(node) &&
            co_tpdo_rtr(node, (uint16_t)frame->id)) {
            return true; /* a remote request of a TPDO */
        }
#endif
        if (!guarding_request(node, frame)) {
            return false; /* extended, error and remote frames but a guard request or a TPDO's */
        }
#if CO_CONFIG_NODE_GUARDING
        co_guard_rx(node, frame);
#endif
        return true;
    }
    const uint16_t id = (uint16_t)frame->id;
    const co_rx_route_t *route = route_find(node, id);
    if (route == NULL) {
#if CO_CONFIG_HB_CONSUMER
        return monitored(node, id) && services_run(node) && co_hbc_rx(node, frame);
#else
        return false;
#endif
    }
    const uint16_t target = route->target;
    const uint16_t n = (uint16_t)(target & 0x0FFFU);
    switch ((enum co_rx_kind)(target >> 12)) {
    case CO_RX_LSS:
        co_node_wake(node, CO_SVC_LSS);
        co_lss_rx(node, frame);
        break;
    case CO_RX_NMT:
        co_nmt_rx(node, frame); /* a change of state wakes every service */
        break;
#if CO_CONFIG_SYNC
    case CO_RX_SYNC:
        co_sync_rx(node, frame);
        break;
#endif
    case CO_RX_SDO: {
#if CO_CONFIG_SDO_SERVERS
        co_sdo_server_t *s = n == 0U ? &node->sdo : &node->sdo_extra[n - 1U];
#else
        co_sdo_server_t *s = &node->sdo;
#endif
        co_sdo_rx(node, s, frame);
        break;
    }
    default:
        co_rpdo_rx(node, n, frame);
        break;
    }
    return true;
}

typedef co_time_us_t (*service_process_t)(co_node_t *node);

/* What a processing pass carries from one service to the next. */
typedef struct pass {
    co_node_t *node;
    bool at_deadline;  /* next_due has come: the services whose own deadline came run */
    co_time_us_t next; /* the earliest deadline so far */
} pass_t;

/* Runs a service if it is marked since it last ran or its deadline has come, and keeps its new deadline. The mark is
 * taken before the service runs, so that what the service itself causes (a hook's write) marks it again. */
static void run_service(pass_t *pass, enum co_service_index index, service_process_t process)
{
    co_node_t *node = pass->node;
    const unsigned service = 1U << index;
    if ((node->wake & service) != 0U || (pass->at_deadline && co_time_reached(node->now, node->svc_due[index]))) {
        node->wake = (uint8_t)(node->wake & ~service);
        /* what it returns is its earliest timer, those it gives co_node_due() while it runs included */
        const co_time_us_t due = process(node);
        node->svc_due[index] = due;
        pass->next = co_min_time(pass->next, due);
    } else if (pass->at_deadline) {
        pass->next = co_min_time(pass->next, node->svc_due[index]); /* the exact earliest, taken afresh */
    }
}

co_time_us_t co_node_process(co_node_t *node, co_time_us_t now)
{
    node->now = now;
    if (node->wake == 0U && !co_time_reached(now, node->next_due) && node->txq.count == 0U) {
        return node->next_due; /* nothing happened since the last pass and nothing is due */
    }
    return co_node_pass(node, now);
}

/* Not static, so that the compiler keeps it out of co_node_process: the early return above then saves no
 * registers. */
co_time_us_t co_node_pass(co_node_t *node, co_time_us_t now)
{
    /* A service runs when marked or when its own deadline has come: at a heartbeat's deadline the heartbeat runs,
     * not every service (each keeps its deadline in svc_due). At a deadline the earliest of all is taken afresh;
     * otherwise the others' deadlines are as they were, none earlier than next_due, which therefore stays a bound
     * (at worst early, when a marked service's deadline moved later: that pass then finds nothing due and takes
     * the earliest afresh). */
    const bool at_deadline = co_time_reached(now, node->next_due);
    pass_t pass = {node, at_deadline, at_deadline ? CO_NEVER : node->next_due};
    node->next_due = CO_NEVER; /* what co_node_due() gives during the pass is kept below */
    if (node->txq.count > 0U && co_time_pending(now, node->lss.silent_until)) {
        pass.next = co_min_time(pass.next, node->lss.silent_until); /* CiA 305 bit-rate switch: the queue waits */
    } else {
        txq_flush(node);
    }
    run_service(&pass, CO_SVC_I_LSS, co_lss_process);
    if (services_run(node)) {
        run_service(&pass, CO_SVC_I_HB, co_hb_process);
#if CO_CONFIG_NODE_GUARDING
        run_service(&pass, CO_SVC_I_GUARD, co_guard_process);
#endif
#if CO_CONFIG_HB_CONSUMER
        run_service(&pass, CO_SVC_I_HBC, co_hbc_process);
#endif
        run_service(&pass, CO_SVC_I_SDO, co_sdo_process);
#if CO_CONFIG_SYNC
        run_service(&pass, CO_SVC_I_SYNC, co_sync_process);
#endif
        run_service(&pass, CO_SVC_I_PDO, co_pdo_process);
        run_service(&pass, CO_SVC_I_EMCY, co_emcy_process);
    } else {
        node->wake = 0U; /* nothing but LSS runs; a reset that starts the services wakes them all */
    }
    if (node->txq.count > 0U) {
        pass.next = co_min_time(pass.next, co_time_after(now, CO_TX_RETRY_US));
    }
    if (node->wake != 0U) {
        pass.next = now; /* a service earlier in the order was marked meanwhile (by a hook): call again at once */
    }
    node->next_due = co_min_time(node->next_due, pass.next);
    return node->next_due;
}

void co_node_values_changed(co_node_t *node)
{
    co_node_wake(node, CO_SVC_PDO);
    node->cos_pending = true;
}

co_nmt_state_t co_node_state(const co_node_t *node) { return node->nmt_state; }

uint8_t co_node_id(const co_node_t *node) { return node->node_id; }
