/*
 * PDOs (CiA 301 §7.2.2): RPDOs 0x1400+n/0x1600+n, TPDOs 0x1800+n/0x1A00+n, as many as the OD declares.
 * Mapping is resolved once (at reset and when a parameter changes) into (row, bytes) pairs. Event-driven
 * TPDOs (254/255) go out when a mapped value changes (compared with what was sent last, so the
 * application needs no call), when co_tpdo_trigger() asks, and when the event timer expires; always
 * subject to the inhibit time. Synchronous TPDOs (0..240) and RPDOs go with SYNC. Only in Operational.
 * Remote requests (CO_CONFIG_TPDO_RTR, a TPDO whose COB-ID bit 30 is clear): type 252 sends what the last SYNC sampled,
 * 253 samples and sends at once, 254/255 take it as an event (inhibit time permitting); 0..240 do not answer.
 * Mapping granularity is one byte; entries whose length is not a multiple of 8 bits are refused. A mapping whose
 * sub-index 0 is 0xFE or 0xFF makes the PDO a multiplexed PDO (co_mpdo.c, CO_CONFIG_MPDO).
 */
#include "priv/co_priv.h"

#define RPDO_COMM 0x1400U
#define RPDO_MAP 0x1600U
#define TPDO_COMM 0x1800U
#define TPDO_MAP 0x1A00U

static const uint8_t rpdo_msef[5] = {0x04U, 0U, 0U, 0U, 0U};

/* More PDOs than any node holds (its capacities are 16-bit): the area has what the node was built without. */
#define PDO_REFUSED 0x10000UL

/* 1 + the number of the highest PDO whose communication object exists (CiA 301: up to 512 each way), or PDO_REFUSED
 * when a communication object has one of timer_subs (bit n: sub-index n < 8), the timers compiled out: a dictionary
 * that has them would take values that change nothing. */
static uint32_t highest_pdo(const co_od_t *od, uint16_t base, unsigned timer_subs)
{
    uint32_t n = 0U;
    const co_od_entry_t *const end = od->entries + od->count;
    for (const co_od_entry_t *e = od->entries + co_od_first_row(od, base); e < end && e->index < base + 0x200U; e++) {
        const unsigned subs = e->count > 7U ? 0xFFU : ((1U << e->count) - 1U) | 1U; /* sub, sub + 1, ... (count 0: 1) */
        if (e->sub < 8U && ((timer_subs >> e->sub) & subs) != 0U) {
            return PDO_REFUSED;
        }
        n = (uint32_t)e->index - base + 1U;
    }
    return n;
}

co_status_t co_pdo_count(co_node_t *node)
{
    const unsigned rpdo_timers = CO_CONFIG_PDO_TIMERS ? 0U : 1U << 5;
    const unsigned tpdo_timers = CO_CONFIG_PDO_TIMERS ? 0U : (1U << 3) | (1U << 5);
    const uint32_t nr = highest_pdo(node->od, RPDO_COMM, rpdo_timers);
    const uint32_t nt = highest_pdo(node->od, TPDO_COMM, tpdo_timers);
    if (nr > node->rpdo_cap || nt > node->tpdo_cap) {
        return CO_ERR_RANGE;
    }
    node->n_rpdo = (uint16_t)nr;
    node->n_tpdo = (uint16_t)nt;
    return CO_OK;
}

/* Resolves one mapping value (index << 16 | sub << 8 | bits). Returns 0 or the abort code. */
static uint32_t resolve(const co_node_t *node, uint32_t value, bool receive, co_pdo_map_t *out)
{
    const uint16_t index = (uint16_t)(value >> 16);
    const uint8_t sub = (uint8_t)(value >> 8);
    const uint8_t bits = (uint8_t)value;
    if (bits == 0U || (bits % 8U) != 0U) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    out->len = (uint8_t)(bits / 8U);
    out->row = CO_PDO_MAP_DUMMY;
    if (receive && index >= 0x0001U && index <= 0x0007U && sub == 0U) {
        if ((node->od->dummy_usage & (1U << index)) == 0U) {
            return CO_ABORT_NOT_MAPPABLE; /* the device does not take dummy entries of this type ([DummyUsage]) */
        }
        /* a dummy entry skips the bytes of its type, exactly: 8 bits of a 32-bit dummy are no dummy */
        return out->len == co_od_type_size((uint8_t)index) ? CO_ABORT_NONE : CO_ABORT_NOT_MAPPABLE;
    }
    const co_od_entry_t *e = co_od_find_row(node->od, index, sub); /* flags and size: the sub-index's too */
    if (e == NULL) {
        return co_od_has_index(node->od, index) ? CO_ABORT_NOT_MAPPABLE : CO_ABORT_NO_OBJECT;
    }
    if ((e->flags & (receive ? CO_OD_RPDO : CO_OD_TPDO)) == 0U || e->size != out->len) {
        return CO_ABORT_NOT_MAPPABLE;
    }
    out->row = (uint16_t)(e - node->od->entries);
    out->k = (uint8_t)(sub - e->sub);
    return CO_ABORT_NONE;
}

/* Mapping sub 0 of an MPDO this node serves: 0xFE both ways (SAM producer, SAM consumer), 0xFF for RPDOs (DAM
 * consumer). A DAM producer is a master's role: a TPDO with 0xFF is refused. */
static bool mpdo_mapping(uint32_t n, bool receive)
{
#if CO_CONFIG_MPDO
    return n == CO_MPDO_SAM || (n == CO_MPDO_DAM && receive);
#else
    (void)n;
    (void)receive;
    return false;
#endif
}

#if CO_CONFIG_MPDO
#define IS_MPDO(p) ((p)->mpdo != 0U)
#else
#define IS_MPDO(p) false
#endif

/* Resolves a whole mapping; returns the mapped byte count (8 for an MPDO), or -1 when invalid. */
static int resolve_all(const co_node_t *node, uint16_t map_index, bool receive, co_pdo_map_t map[8], uint8_t *n_out)
{
    const uint32_t n = co_od_u32_or(node, map_index, 0U, 0U);
    int total = 0;
    *n_out = 0U;
    if (mpdo_mapping(n, receive)) {
        return 8;
    }
    if (n > 8U) {
        return -1;
    }
    for (unsigned i = 1U; i <= n; i++) {
        if (resolve(node, co_od_u32_or(node, map_index, (uint8_t)i, 0U), receive, &map[i - 1U]) != CO_ABORT_NONE) {
            return -1;
        }
        total += map[i - 1U].len;
    }
    if (total > 8) {
        return -1;
    }
    *n_out = (uint8_t)n;
    return total;
}

static void configure_rpdo(co_node_t *node, unsigned n)
{
    co_rpdo_t *p = &node->rpdo[n];
    const uint16_t comm = (uint16_t)(RPDO_COMM + n);
    p->cob_id = co_od_u32_or(node, comm, 1U, CO_COBID_INVALID);
    p->type = (uint8_t)co_od_u32_or(node, comm, 2U, 255U);
    const int len = resolve_all(node, (uint16_t)(RPDO_MAP + n), true, p->map, &p->n_map);
#if CO_CONFIG_MPDO
    const uint32_t entries = co_od_u32_or(node, (uint16_t)(RPDO_MAP + n), 0U, 0U);
    p->mpdo = mpdo_mapping(entries, true) ? (uint8_t)entries : 0U;
#endif
    p->map_len = len > 0 ? (uint8_t)len : 0U;
    p->valid = (p->cob_id & CO_COBID_INVALID) == 0U && len > 0;
#if CO_CONFIG_PDO_TIMERS
    p->event_ms = (uint16_t)co_od_u32_or(node, comm, 5U, 0U);
    p->deadline = CO_NEVER;
#endif
#if CO_CONFIG_SYNC
    p->sync_pending = false;
#endif
}

static void configure_tpdo(co_node_t *node, unsigned n)
{
    co_tpdo_t *p = &node->tpdo[n];
    const uint16_t comm = (uint16_t)(TPDO_COMM + n);
    p->cob_id = co_od_u32_or(node, comm, 1U, CO_COBID_INVALID);
    p->type = (uint8_t)co_od_u32_or(node, comm, 2U, 255U);
#if CO_CONFIG_PDO_TIMERS
    p->inhibit_us = co_od_u32_or(node, comm, 3U, 0U) * 100U;
    p->event_us = co_od_u32_or(node, comm, 5U, 0U) * 1000U;
    p->next_allowed = CO_NEVER;
    p->event_due = CO_NEVER;
#endif
    const int len = resolve_all(node, (uint16_t)(TPDO_MAP + n), false, p->map, &p->n_map);
#if CO_CONFIG_MPDO
    const uint32_t entries = co_od_u32_or(node, (uint16_t)(TPDO_MAP + n), 0U, 0U);
    p->mpdo = mpdo_mapping(entries, false) ? (uint8_t)entries : 0U;
    p->scan_next = 0U;
#endif
    p->map_len = len > 0 ? (uint8_t)len : 0U;
    p->valid = (p->cob_id & CO_COBID_INVALID) == 0U && len > 0;
    p->sent_once = false;
    p->event = false;
#if CO_CONFIG_SYNC
    p->sync_start = (uint8_t)co_od_u32_or(node, comm, 6U, 0U);
    p->sync_count = 0U;
    p->sync_started = p->sync_start == 0U;
#endif
}

void co_pdo_reset(co_node_t *node)
{
    for (unsigned n = 0U; n < node->n_rpdo; n++) {
        node->rpdo[n].length_error = false;
#if CO_CONFIG_PDO_TIMERS
        node->rpdo[n].timeout_error = false;
#endif
        configure_rpdo(node, n);
    }
    for (unsigned n = 0U; n < node->n_tpdo; n++) {
        configure_tpdo(node, n);
    }
}

static void rpdo_apply(co_node_t *node, co_rpdo_t *p, const uint8_t *data)
{
    unsigned pos = 0U; /* unsigned: no narrowing at each step */
    for (unsigned i = 0U; i < p->n_map; i++) {
        if (p->map[i].row != CO_PDO_MAP_DUMMY) {
            /* The device hook may refuse a value; an RPDO has no way to answer, so it is dropped. */
            co_od_entry_t one;
            const co_od_entry_t *e = &node->od->entries[p->map[i].row];
            e = p->map[i].k == 0U ? e : co_od_entry_at(e, p->map[i].k, &one); /* a sub-index inside a run */
            (void)co_od_write_entry(node, e, &data[pos], p->map[i].len, CO_ORIGIN_RPDO);
        }
        pos += p->map[i].len;
    }
}

void co_rpdo_rx(co_node_t *node, uint16_t n, const co_frame_t *f)
{
    co_rpdo_t *p = &node->rpdo[n];
    if (node->nmt_state != CO_NMT_OPERATIONAL) {
        return; /* dropped, not applied later */
    }
    if (f->len != p->map_len) {
        const bool short_frame = f->len < p->map_len;
        if (!p->length_error) {
            p->length_error = true;
            (void)co_emcy_raise(node, short_frame ? 0x8210U : 0x8220U, 0x10U, rpdo_msef);
        }
        if (short_frame) {
            return; /* data discarded (too long: the first mapped bytes are applied) */
        }
    } else if (p->length_error) {
        p->length_error = false;
        if (!co_emcy_clear(node, 0x8210U, rpdo_msef)) {
            (void)co_emcy_clear(node, 0x8220U, rpdo_msef);
        }
    }
#if CO_CONFIG_MPDO
    if (p->mpdo != 0U) {
        /* event-driven whatever the transmission type (CiA 301) */
        const int written = co_mpdo_receive(node, p, f->data);
        if (written < 0 && !p->mpdo_error) {
            p->mpdo_error = true;
            (void)co_emcy_raise(node, 0x8230U, 0x10U, rpdo_msef); /* DAM-MPDO not processed: destination */
        } else if (written > 0 && p->mpdo_error) {
            p->mpdo_error = false;
            (void)co_emcy_clear(node, 0x8230U, rpdo_msef);
        }
    } else
#endif
    if (p->type <= 240U) {
#if CO_CONFIG_SYNC
        memcpy(p->sync_data, f->data, p->map_len);
        p->sync_pending = true;
#endif
        /* without SYNC support no SYNC comes to apply it: dropped */
    } else {
        rpdo_apply(node, p, f->data);
    }
#if CO_CONFIG_PDO_TIMERS
    p->deadline = p->event_ms != 0U ? co_time_after(node->now, (uint32_t)p->event_ms * 1000U) : CO_NEVER;
    co_node_due(node, CO_SVC_I_PDO, p->deadline);
    if (p->timeout_error) {
        p->timeout_error = false;
        (void)co_emcy_clear(node, 0x8250U, rpdo_msef);
    }
#endif
}

static void tpdo_sample(co_node_t *node, co_tpdo_t *p, uint8_t buf[8])
{
    unsigned pos = 0U; /* unsigned: no narrowing at each step */
    memset(buf, 0, 8U);
    for (unsigned i = 0U; i < p->n_map; i++) {
        co_od_entry_t one;
        const co_od_entry_t *e = &node->od->entries[p->map[i].row];
        e = p->map[i].k == 0U ? e : co_od_entry_at(e, p->map[i].k, &one); /* a sub-index inside a run */
        (void)co_od_sample(node, e, &buf[pos], p->map[i].len);
        pos += p->map[i].len;
    }
}

static void tpdo_send(co_node_t *node, co_tpdo_t *p, const uint8_t buf[8])
{
    co_frame_t f;
    f.id = p->cob_id & CO_COBID_CAN_ID;
    f.len = p->map_len;
    f.flags = 0U;
    memcpy(f.data, buf, 8U); /* zero past map_len: sampled into a cleared buffer (an MPDO fills all 8) */
    co_node_send(node, &f);
    memcpy(p->last, buf, 8U);
    p->sent_once = true;
    p->event = false;
#if CO_CONFIG_PDO_TIMERS
    p->next_allowed = p->inhibit_us != 0U ? co_time_after(node->now, p->inhibit_us) : CO_NEVER;
#endif
}

/* The TPDO timers, or what they are without them (CO_CONFIG_PDO_TIMERS 0): never due, never waiting. */
#if CO_CONFIG_PDO_TIMERS
static bool tpdo_timer_due(const co_node_t *node, const co_tpdo_t *p) { return co_time_reached(node->now, p->event_due); }
static co_time_us_t tpdo_inhibit_end(const co_tpdo_t *p)
{
    (void)p; /* with 64-bit time CO_TIME32_RETIRE drops it */
    return CO_TIME32_RETIRE(p->next_allowed);
}
static co_time_us_t tpdo_timers_next(const co_tpdo_t *p) { return co_min_time(p->event_due, tpdo_inhibit_end(p)); }
#else
static bool tpdo_timer_due(const co_node_t *node, const co_tpdo_t *p) { (void)node, (void)p; return false; }
static co_time_us_t tpdo_inhibit_end(const co_tpdo_t *p) { (void)p; return CO_NEVER; }
static co_time_us_t tpdo_timers_next(const co_tpdo_t *p) { (void)p; return CO_NEVER; }
#endif

/* An event-driven TPDO with something to look at: values written (node->cos_pending, co_node_values_changed), a
 * first transmission, an event, or its timer due (timer). */
static co_time_us_t tpdo_event_driven(co_node_t *node, co_tpdo_t *p, bool timer)
{
    uint8_t buf[8];
    bool cos = false;
    if (!IS_MPDO(p)) {
        tpdo_sample(node, p, buf);
        cos = (node->options & CO_OPT_TPDO_NO_COS) == 0U && memcmp(buf, p->last, 8U) != 0;
    }
    const bool changed = !p->sent_once || p->event || cos;
    if (changed || timer) {
#if CO_CONFIG_PDO_TIMERS
        if (co_time_pending(node->now, p->next_allowed)) {
            p->event = true; /* waits for the inhibit time; the timer (if it fired) is served with it */
            return p->next_allowed;
        }
#endif
#if CO_CONFIG_MPDO
        if (p->mpdo != 0U && !co_mpdo_sam_next(node, p, buf)) {
            p->sent_once = true; /* an empty scanner list: nothing to send at this event */
            p->event = false;
        } else
#endif
        {
            tpdo_send(node, p, buf);
        }
#if CO_CONFIG_PDO_TIMERS
        if (p->event_us == 0U) {
            p->event_due = CO_NEVER;
        } else if (timer && !changed) {
            /* Timer-driven: stay on the original grid so late calls do not accumulate drift. */
            p->event_due = co_next_on_grid(p->event_due, p->event_us, node->now);
        } else {
            p->event_due = co_time_after(node->now, p->event_us); /* the event timer restarts at every transmission */
        }
#endif
    }
    return tpdo_timers_next(p);
}

co_time_us_t co_pdo_process(co_node_t *node)
{
    co_time_us_t next = CO_NEVER;
    if (node->nmt_state != CO_NMT_OPERATIONAL) {
        node->cos_pending = false; /* entering Operational sends every event-driven TPDO anyway */
        return next;
    }
#if CO_CONFIG_PDO_TIMERS
    for (unsigned n = 0U; n < node->n_rpdo; n++) {
        co_rpdo_t *p = &node->rpdo[n];
        if (!p->valid || p->deadline == CO_NEVER) {
            continue;
        }
        if (co_time_reached(node->now, p->deadline)) {
            p->deadline = CO_NEVER;
            p->timeout_error = true;
            (void)co_emcy_raise(node, 0x8250U, 0x10U, rpdo_msef);
        } else {
            next = co_min_time(next, p->deadline);
        }
    }
#endif
    const bool cos = node->cos_pending;
    co_tpdo_t *const end = node->tpdo + node->n_tpdo;
    for (co_tpdo_t *p = node->tpdo; p < end; p++) {
#if CO_CONFIG_PDO_TIMERS
        co_time_retire(node->now, &p->next_allowed);
#endif
        co_time_us_t t;
        if (!p->valid || p->type < 254U) {
            t = tpdo_inhibit_end(p);
        } else if (!cos && p->sent_once && !p->event && !tpdo_timer_due(node, p)) {
            t = tpdo_timers_next(p); /* nothing to compare, nothing asked for, the timer not due */
        } else {
            t = tpdo_event_driven(node, p, tpdo_timer_due(node, p));
        }
        next = co_min_time(next, t);
    }
    /* Consumed: the values were compared. A read hook's write during the sampling is taken as sampled. */
    node->cos_pending = false;
    node->wake = (uint8_t)(node->wake & ~(unsigned)CO_SVC_PDO);
    return next;
}

#if CO_CONFIG_SYNC
void co_pdo_on_sync(co_node_t *node, uint8_t counter)
{
    if (node->nmt_state != CO_NMT_OPERATIONAL) {
        return;
    }
    for (unsigned n = 0U; n < node->n_rpdo; n++) {
        co_rpdo_t *p = &node->rpdo[n];
        if (p->valid && p->sync_pending) {
            p->sync_pending = false;
            rpdo_apply(node, p, p->sync_data);
        }
    }
    for (unsigned n = 0U; n < node->n_tpdo; n++) {
        co_tpdo_t *p = &node->tpdo[n];
        if (!p->valid || (p->type > 240U && (!CO_CONFIG_TPDO_RTR || p->type != 252U)) || IS_MPDO(p)) {
            continue; /* an MPDO is event-driven only (CiA 301) */
        }
        if (!p->sync_started) {
            if (counter != 0U && counter != p->sync_start) {
                continue;
            }
            p->sync_started = true;
            p->sync_count = p->type; /* the first transmission is at the SYNC carrying the start value */
        }
        uint8_t buf[8];
        tpdo_sample(node, p, buf);
#if CO_CONFIG_TPDO_RTR
        if (p->type == 252U) {
            memcpy(p->last, buf, 8U); /* sent on the next remote request */
            p->sent_once = true;
            continue;
        }
#endif
        if (p->type == 0U) {
            if (p->event || !p->sent_once || memcmp(buf, p->last, 8U) != 0) {
                tpdo_send(node, p, buf); /* acyclic: only when something changed */
            }
            continue;
        }
        p->sync_count++;
        if (p->sync_count >= p->type) {
            p->sync_count = 0U;
            tpdo_send(node, p, buf);
        }
    }
}
#endif

void co_pdo_on_state(co_node_t *node, co_nmt_state_t from, co_nmt_state_t to)
{
    if (from != CO_NMT_OPERATIONAL && to != CO_NMT_OPERATIONAL) {
        return;
    }
    /* Entering or leaving Operational: timers and SYNC counts restart; on entering, every event-driven
     * TPDO is sent once at once (its first "change"), as CANopenNode does. */
    co_tpdo_t *const end = node->tpdo + node->n_tpdo;
    for (co_tpdo_t *p = node->tpdo; p < end; p++) {
        p->sent_once = false;
        p->event = false;
#if CO_CONFIG_PDO_TIMERS
        p->next_allowed = CO_NEVER;
        p->event_due = CO_NEVER;
#endif
#if CO_CONFIG_SYNC
        p->sync_count = 0U;
        p->sync_started = p->sync_start == 0U;
#endif
    }
    for (unsigned n = 0U; n < node->n_rpdo; n++) {
#if CO_CONFIG_SYNC
        node->rpdo[n].sync_pending = false;
#endif
#if CO_CONFIG_PDO_TIMERS
        node->rpdo[n].deadline = CO_NEVER;
#endif
    }
}

#if CO_CONFIG_TPDO_RTR
/* A TPDO that answers remote requests: valid, RTR allowed by its COB-ID, an RTR-only or event-driven type. */
static bool answers_rtr(const co_tpdo_t *p)
{
    return p->valid && (p->cob_id & CO_COBID_NO_RTR) == 0U && p->type >= 252U && !IS_MPDO(p);
}

bool co_tpdo_rtr(co_node_t *node, uint16_t id)
{
    bool taken = false;
    co_tpdo_t *const end = node->tpdo + node->n_tpdo;
    for (co_tpdo_t *p = node->tpdo; p < end; p++) {
        if (!answers_rtr(p) || (p->cob_id & CO_COBID_CAN_ID) != id) {
            continue;
        }
        taken = true;
        if (node->nmt_state != CO_NMT_OPERATIONAL) {
            continue;
        }
        uint8_t buf[8];
        if (p->type >= 254U) {
            p->event = true; /* event-driven: a transmission asked for, inhibit time permitting */
            co_node_wake(node, CO_SVC_PDO);
            continue;
        }
        if (p->type == 252U && p->sent_once) {
            memcpy(buf, p->last, 8U); /* what the last SYNC sampled */
        } else {
            tpdo_sample(node, p, buf); /* 253, or 252 before its first SYNC */
        }
        tpdo_send(node, p, buf);
    }
    return taken;
}

uint32_t co_tpdo_rtr_next(const co_node_t *node, uint32_t from)
{
    uint32_t next = 0x800U;
    const co_tpdo_t *const end = node->tpdo + node->n_tpdo;
    for (const co_tpdo_t *p = node->tpdo; p < end; p++) {
        const uint32_t id = p->cob_id & CO_COBID_CAN_ID;
        if (answers_rtr(p) && id >= from && id < next) {
            next = id;
        }
    }
    return next;
}
#endif

void co_tpdo_trigger(co_node_t *node, uint16_t n)
{
    if (n < node->n_tpdo) {
        node->tpdo[n].event = true;
        co_node_wake(node, CO_SVC_PDO);
    }
}

static bool pdo_is_valid(const co_node_t *node, uint16_t comm_index)
{
    return (co_od_u32_or(node, comm_index, 1U, CO_COBID_INVALID) & CO_COBID_INVALID) == 0U;
}

static uint32_t check_comm(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool receive, bool stored)
{
    const bool valid = !stored && pdo_is_valid(node, e->index); /* stored: a value, not a change while valid */
    switch (e->sub) {
    case 1: {
        const uint32_t v = co_get_u32(data);
        const uint32_t r = co_cob_id_check(v, co_od_entry_u32(node, e), valid);
        if (r != CO_ABORT_NONE || (v & CO_COBID_INVALID) != 0U) {
            return r;
        }
        if (stored) {
            return CO_ABORT_NONE; /* its mapping loads after it (records in index order): checked at configuration */
        }
        const uint16_t map = (uint16_t)(e->index + 0x200U);
        co_pdo_map_t tmp[8];
        uint8_t n;
        if (resolve_all(node, map, receive, tmp, &n) < 0) {
            return CO_ABORT_INVALID_VALUE; /* a PDO whose mapping is invalid cannot be valid */
        }
        /* An empty mapping is taken, as from a file (vendor files have valid PDOs mapping nothing): the PDO stays
         * silent until mapped, which starts with making it invalid again (the mapping procedure). */
        return CO_ABORT_NONE;
    }
    case 2: {
        /* 241..251 reserved; 252/253 RTR-only, for a TPDO that answers RTR (CO_CONFIG_TPDO_RTR) */
        const uint8_t type = data[0];
        const bool rtr_only = !receive && CO_CONFIG_TPDO_RTR && type >= 252U;
        return (type >= 241U && type <= 253U && !rtr_only) ? CO_ABORT_INVALID_VALUE : CO_ABORT_NONE;
    }
    case 3:
    case 6:
        return (!receive && valid) ? CO_ABORT_INVALID_VALUE : CO_ABORT_NONE;
    default:
        return CO_ABORT_NONE;
    }
}

static uint32_t check_map(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool receive, bool stored)
{
#if CO_CONFIG_PDO_DYNAMIC_MAPPING
    if (!stored && pdo_is_valid(node, (uint16_t)(e->index - 0x200U))) {
        return CO_ABORT_UNSUPPORTED_ACCESS; /* step 1 of the mapping procedure: make the PDO invalid */
    }
    if (e->sub == 0U) {
        const uint8_t n = data[0];
        if (mpdo_mapping(n, receive)) {
            return CO_ABORT_NONE; /* an MPDO: the entries are not used */
        }
        if (n > 8U || n > co_od_sub_count(node->od, e->index)) {
            return CO_ABORT_PDO_LENGTH;
        }
        if (stored) {
            return CO_ABORT_NONE; /* its entries load after it: each is checked on its own, the sum at configuration */
        }
        uint32_t bytes = 0U;
        for (unsigned i = 1U; i <= n; i++) {
            co_pdo_map_t m;
            const uint32_t r = resolve(node, co_od_u32_or(node, e->index, (uint8_t)i, 0U), receive, &m);
            if (r != CO_ABORT_NONE) {
                return r;
            }
            bytes += m.len;
        }
        return bytes > 8U ? CO_ABORT_PDO_LENGTH : CO_ABORT_NONE;
    }
    const uint32_t count = co_od_u32_or(node, e->index, 0U, 0U);
    if (!stored && count != 0U) {
        return CO_ABORT_UNSUPPORTED_ACCESS; /* step 2: sub 0 must be 0 while entries change */
    }
    if (stored && (e->sub > count || mpdo_mapping(count, receive))) {
        return CO_ABORT_NONE; /* CiA 301 checks the entries up to the count: those above it may name anything */
    }
    const uint32_t v = co_get_u32(data);
    if (v == 0U) {
        return CO_ABORT_NONE;
    }
    if ((v & 0xFFU) > 64U) {
        return CO_ABORT_PDO_LENGTH;
    }
    co_pdo_map_t m;
    return resolve(node, v, receive, &m);
#else
    (void)node;
    (void)e;
    (void)data;
    (void)receive;
    return stored ? CO_ABORT_NONE : CO_ABORT_READ_ONLY; /* a fixed mapping: a stored copy of it is no change */
#endif
}

/* The four areas by two bits of the index (0x1400..0x1BFF only, co_od.c): 0x0800 a TPDO, 0x0200 a mapping. */
static bool is_receive(uint16_t index) { return (index & 0x0800U) == 0U; }
static bool is_mapping(uint16_t index) { return (index & 0x0200U) != 0U; }

uint32_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored)
{
    const bool receive = is_receive(e->index);
    if ((e->index & 0x01FFU) >= (receive ? node->n_rpdo : node->n_tpdo)) {
        return CO_ABORT_NONE; /* beyond the PDOs the node counted: no rules */
    }
    if (is_mapping(e->index)) {
        return check_map(node, e, data, receive, stored);
    }
    return check_comm(node, e, data, receive, stored);
}

void co_pdo_written(co_node_t *node, const co_od_entry_t *e)
{
    const unsigned n = e->index & 0x01FFU;
    if (!is_receive(e->index)) {
        if (n < node->n_tpdo) {
#if CO_CONFIG_TPDO_RTR
            const co_tpdo_t *p = &node->tpdo[n];
            const uint32_t was = answers_rtr(p) ? p->cob_id & CO_COBID_CAN_ID : CO_NO_CAN_ID;
            configure_tpdo(node, n);
            if ((answers_rtr(p) ? p->cob_id & CO_COBID_CAN_ID : CO_NO_CAN_ID) != was) {
                co_node_routes_update(node); /* the remote requests it answers changed (co_node_rx_ids) */
            }
#else
            configure_tpdo(node, n);
#endif
        }
    } else if (n < node->n_rpdo) {
        const co_rpdo_t *p = &node->rpdo[n];
        const uint32_t was = p->valid ? p->cob_id & CO_COBID_CAN_ID : CO_NO_CAN_ID;
        configure_rpdo(node, n);
        if ((p->valid ? p->cob_id & CO_COBID_CAN_ID : CO_NO_CAN_ID) != was) {
            co_node_routes_update(node); /* the frames it takes changed */
        }
    }
}
