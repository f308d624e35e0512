/*
 * EMCY producer (CiA 301 §7.2.7): error code, error register 0x1001, pre-defined error field 0x1003,
 * COB-ID 0x1014, inhibit time 0x1015. Errors are kept in a small active list so the error register
 * can be recomputed when one of several errors clears. Frames are queued while the NMT state forbids
 * EMCY (Stopped, Initialising) or the inhibit time runs, and sent in order afterwards.
 */
#include "priv/co_priv.h"

static const uint8_t zero_msef[5] = {0U, 0U, 0U, 0U, 0U};

static bool same_error(const co_emcy_error_t *a, uint16_t code, const uint8_t *msef)
{
    return a->code == code && a->msef[0] == msef[0] && a->msef[1] == msef[1];
}

static uint8_t error_register(const co_node_t *node)
{
    uint8_t reg = 0U;
    for (unsigned i = 0U; i < node->emcy.n_active; i++) {
        reg |= node->emcy.active[i].reg;
    }
    /* Bit 0 (generic) is set whenever any error is present (CiA 301; see docs/decisions.md). */
    return node->emcy.n_active > 0U ? (uint8_t)(reg | 0x01U) : 0U;
}

/* 0x1001 from the active list; returns the register. */
static uint8_t update_register(co_node_t *node)
{
    const uint8_t reg = error_register(node);
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, 0x1001U, 0U, &one);
    if (e != NULL) {
        co_od_entry_set_u32(node, e, reg);
    }
    return reg;
}

#if CO_CONFIG_EMCY_HISTORY
/* 0x1003: newest error at sub 1, older ones move up, the oldest falls out when the array is full. One pass from
 * sub 1 up: each sub-index takes the value the one below held (a sub-index the table lacks moves nothing). */
static void push_history(co_node_t *node, uint16_t code, const uint8_t *msef)
{
    const uint8_t size = co_od_sub_count(node->od, 0x1003U);
    co_od_entry_t count_one;
    const co_od_entry_t *count_e = co_od_find(node->od, 0x1003U, 0U, &count_one);
    if (size == 0U || count_e == NULL) {
        return;
    }
    const uint32_t was_count = co_od_entry_u32(node, count_e);
    const uint32_t count = was_count < size ? was_count + 1U : size; /* full: the oldest falls out */
    uint32_t carry = (uint32_t)code | ((uint32_t)msef[0] << 16) | ((uint32_t)msef[1] << 24);
    co_od_entry_t one;
    /* The sub-index below the one at hand, NULL where the table lacks it: only tested, never read (sub 1 takes the
     * new error). */
    const co_od_entry_t *below = count_e;
    for (unsigned i = 1U; i <= count; i++) {
        const co_od_entry_t *e = co_od_find(node->od, 0x1003U, (uint8_t)i, &one);
        if (e != NULL) {
            const uint32_t was = co_od_entry_u32(node, e);
            if (below != NULL) {
                co_od_entry_set_u32(node, e, carry);
            }
            carry = was;
        }
        below = e;
    }
    co_od_entry_set_u32(node, count_e, count);
}
#endif

/* Queues the 8 bytes of an EMCY (code 0: an error reset) with the error register reg. */
static void enqueue(co_node_t *node, uint16_t code, uint8_t reg, const uint8_t *msef)
{
    co_emcy_t *em = &node->emcy;
    unsigned slot = em->q_head;
    if (em->q_count == CO_EMCY_QUEUE_LEN) { /* full: the oldest report gives way, its slot takes the new one */
        em->q_head = (uint8_t)((slot + 1U) % CO_EMCY_QUEUE_LEN);
        em->lost++;
    } else {
        slot = (slot + em->q_count) % CO_EMCY_QUEUE_LEN;
        em->q_count++;
    }
    uint8_t *data = em->queue[slot];
    co_put_u16(data, code);
    data[2] = reg;
    memcpy(&data[3], msef, 5U);
    co_node_event(node, CO_EV_EMCY, 0x1014U, 0U, code, reg);
}

/* The active list changed (an error raised, or cleared: code 0): 0x1001 follows and the EMCY is queued. */
static void report(co_node_t *node, uint16_t code, const uint8_t *msef)
{
    co_node_wake(node, CO_SVC_EMCY);
    enqueue(node, code, update_register(node), msef);
}

/* Where the error (code, msef) is in the active list, or n_active when it is not active. */
static unsigned find_active(const co_emcy_t *em, uint16_t code, const uint8_t *msef)
{
    unsigned i = 0U;
    while (i < em->n_active && !same_error(&em->active[i], code, msef)) {
        i++;
    }
    return i;
}

bool co_emcy_raise(co_node_t *node, uint16_t code, uint8_t reg_bits, const uint8_t *msef)
{
    co_emcy_t *em = &node->emcy;
    const uint8_t *m = msef != NULL ? msef : zero_msef;
    if (code == 0x0000U) {
        return false; /* 0x0000 is the error reset, never an error (and never logged in 0x1003) */
    }
    if (find_active(em, code, m) < em->n_active) {
        return true;
    }
    if (em->n_active >= CO_EMCY_ACTIVE_MAX) {
        return false;
    }
    co_emcy_error_t *a = &em->active[em->n_active++];
    a->code = code;
    a->reg = reg_bits;
    memcpy(a->msef, m, 5U);
#if CO_CONFIG_EMCY_HISTORY
    push_history(node, code, m);
#endif
    report(node, code, m);
    return true;
}

bool co_emcy_clear(co_node_t *node, uint16_t code, const uint8_t *msef)
{
    co_emcy_t *em = &node->emcy;
    const uint8_t *m = msef != NULL ? msef : zero_msef;
    const unsigned i = find_active(em, code, m);
    if (i >= em->n_active) {
        return false;
    }
    em->active[i] = em->active[em->n_active - 1U];
    em->n_active--;
    report(node, 0x0000U, m); /* error reset, with the register of what remains */
    return true;
}

bool co_emcy_is_active(const co_node_t *node, uint16_t code)
{
    for (unsigned i = 0U; i < node->emcy.n_active; i++) {
        if (node->emcy.active[i].code == code) {
            return true;
        }
    }
    return false;
}

void co_emcy_written(co_node_t *node)
{
    node->emcy.cob_id = co_od_u32_or(node, 0x1014U, 0U, 0x80U + (uint32_t)node->node_id);
#if CO_CONFIG_EMCY_INHIBIT
    node->emcy.inhibit_100us = (uint16_t)co_od_u32_or(node, 0x1015U, 0U, 0U);
#endif
}

void co_emcy_reset(co_node_t *node)
{
    co_emcy_written(node);
    /* Communication reset: the error state starts afresh (0x1001/0x1003 were re-initialised with the
     * 0x1000 area); device errors that persist are raised again by the device's on_reset hook. */
    node->emcy.n_active = 0U;
    node->emcy.q_count = 0U;
    node->emcy.q_head = 0U;
#if CO_CONFIG_EMCY_INHIBIT
    node->emcy.next_allowed = CO_NEVER;
#endif
    (void)update_register(node);
}

#if CO_CONFIG_EMCY_INHIBIT
#define INHIBIT_END(em) CO_TIME32_RETIRE((em)->next_allowed)
#else
#define INHIBIT_END(em) CO_NEVER /* no inhibit time: nothing to wait for */
#endif

co_time_us_t co_emcy_process(co_node_t *node)
{
    co_emcy_t *em = &node->emcy;
#if CO_CONFIG_EMCY_INHIBIT
    co_time_retire(node->now, &em->next_allowed);
#endif
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        return INHIBIT_END(em); /* kept until the node leaves Stopped */
    }
    while (em->q_count > 0U) {
#if CO_CONFIG_EMCY_INHIBIT
        if (co_time_pending(node->now, em->next_allowed)) {
            return em->next_allowed;
        }
#endif
        const uint8_t *data = em->queue[em->q_head];
        em->q_head = (uint8_t)((em->q_head + 1U) % CO_EMCY_QUEUE_LEN);
        em->q_count--;
        if ((em->cob_id & CO_COBID_INVALID) == 0U) { /* else EMCY is disabled: the report is dropped */
            co_frame_t f;
            f.id = em->cob_id & CO_COBID_CAN_ID;
            f.len = 8U;
            f.flags = 0U;
            memcpy(f.data, data, 8U);
            co_node_send(node, &f);
#if CO_CONFIG_EMCY_INHIBIT
            em->next_allowed =
                em->inhibit_100us != 0U ? co_time_after(node->now, (uint32_t)em->inhibit_100us * 100U) : CO_NEVER;
#endif
        }
    }
    return INHIBIT_END(em);
}

uint32_t co_emcy_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored)
{
    if (e->index != 0x1014U) {
        return CO_ABORT_NONE;
    }
    const uint32_t v = co_get_u32(data);
    const uint32_t cur = co_od_entry_u32(node, e);
    if ((v & CO_COBID_NO_RTR) != 0U) {
        return CO_ABORT_INVALID_VALUE; /* bit 30 is reserved here */
    }
    /* the PDOs' rules otherwise: 11-bit, not restricted, the CAN-ID changed only while bit 31 is set */
    return co_cob_id_check(v, cur, !stored && (cur & CO_COBID_INVALID) == 0U);
}

#if CO_CONFIG_EMCY_HISTORY
uint32_t co_emcy_check_read(co_node_t *node, const co_od_entry_t *e)
{
    if (e->sub == 0U) {
        return CO_ABORT_NONE;
    }
    const uint32_t count = co_od_u32_or(node, 0x1003U, 0U, 0U);
    return e->sub > count ? CO_ABORT_NO_DATA : CO_ABORT_NONE;
}

bool co_emcy_write_action(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    (void)e; /* 0x1003:00, found again as the loop's sub-index 0 */
    (void)len;
    if (data[0] != 0U) {
        return false; /* only 0 (clear the history) may be written to 0x1003:00 */
    }
    const uint8_t size = co_od_sub_count(node->od, 0x1003U);
    for (unsigned i = 0U; i <= size; i++) { /* the count and every error */
        co_od_entry_t one;
        const co_od_entry_t *s = co_od_find(node->od, 0x1003U, (uint8_t)i, &one);
        if (s != NULL) {
            co_od_entry_set_u32(node, s, 0U);
        }
    }
    return true;
}
#endif /* CO_CONFIG_EMCY_HISTORY */
