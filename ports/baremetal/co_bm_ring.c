#include "co_bm_ring.h"

void co_bm_ring_init(co_bm_ring_t *r)
{
    r->head = 0U;
    r->tail = 0U;
    r->overruns = 0U;
}

bool co_bm_ring_push(co_bm_ring_t *r, const co_frame_t *frame)
{
    const uint32_t head = r->head;
    if (head - r->tail >= CO_BM_RING_LEN) {
        r->overruns = r->overruns + 1U;
        return false;
    }
    r->slot[head & (CO_BM_RING_LEN - 1U)] = *frame;
    CO_BM_FENCE(); /* the slot is complete before the consumer can see it */
    r->head = head + 1U;
    return true;
}

bool co_bm_ring_pop(co_bm_ring_t *r, co_frame_t *frame)
{
    const uint32_t tail = r->tail;
    if (r->head == tail) {
        return false;
    }
    CO_BM_FENCE(); /* read the slot only after seeing the head that published it */
    *frame = r->slot[tail & (CO_BM_RING_LEN - 1U)];
    CO_BM_FENCE(); /* the slot is copied out before the producer may reuse it */
    r->tail = tail + 1U;
    return true;
}

uint32_t co_bm_ring_count(const co_bm_ring_t *r) { return r->head - r->tail; }
