#include "co_bm_port.h"

static co_status_t port_send(void *ctx, const co_frame_t *frame)
{
    co_bm_port_t *p = (co_bm_port_t *)ctx;
    return p->can->send(p->can->ctx, frame);
}

static co_status_t port_bit_rate(void *ctx, uint32_t kbit)
{
    co_bm_port_t *p = (co_bm_port_t *)ctx;
    return p->can->set_bit_rate(p->can->ctx, kbit);
}

static co_status_t port_nvm_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    return co_bm_nvm_write(((co_bm_port_t *)ctx)->nvm, area, offset, data, len);
}

/* Two slots per area make each area's commit atomic, but not several areas together: a store of several areas
 * (co_port.h, CO_NVM_MORE) is committed area by area, and an abandoned one (CO_NVM_DISCARD) keeps the areas
 * already committed. A board that needs multi-area stores atomic keeps them in one area of its own layout. A
 * background commit (CO_NVM_BACKGROUND) is committed at once: no thread here to do it later. */
static co_status_t port_nvm_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    if (total_len == CO_NVM_DISCARD) {
        return CO_OK;
    }
    return co_bm_nvm_commit(((co_bm_port_t *)ctx)->nvm, area, total_len & ~CO_NVM_FLAGS);
}

static co_status_t port_nvm_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    return co_bm_nvm_read(((co_bm_port_t *)ctx)->nvm, area, offset, data, len);
}

void co_bm_port_init(co_bm_port_t *p, const co_bm_can_t *can, co_bm_nvm_t *nvm, co_bm_clock_t *clock)
{
    p->can = can;
    p->nvm = nvm;
    p->clock = clock;
    p->port.send = port_send;
    p->port.set_bit_rate = can->set_bit_rate != NULL ? port_bit_rate : NULL;
    p->port.nvm_write = nvm != NULL ? port_nvm_write : NULL;
    p->port.nvm_commit = nvm != NULL ? port_nvm_commit : NULL;
    p->port.nvm_read = nvm != NULL ? port_nvm_read : NULL;
    co_bm_ring_init(&p->rx);
    p->filters_set = false;
}

/* The controller takes the node's CAN-IDs only: fewer frames to read and to reject in software. */
static void update_filters(co_bm_port_t *p, const co_node_t *node)
{
    const uint16_t n = co_node_rx_ids(node, p->filter_ids, CO_BM_FILTER_MAX);
    if (n > CO_BM_FILTER_MAX || p->can->set_filters(p->can->ctx, p->filter_ids, n) != CO_OK) {
        (void)p->can->set_filters(p->can->ctx, NULL, 0U); /* more than the filters hold: every frame */
    }
    p->filters_version = node->rx_ids_version;
    p->filters_set = true;
}

bool co_bm_port_rx_isr(co_bm_port_t *p, const co_frame_t *frame) { return co_bm_ring_push(&p->rx, frame); }

co_time_us_t co_bm_port_poll(co_bm_port_t *p, co_node_t *node)
{
    if (p->can->set_filters != NULL && (!p->filters_set || p->filters_version != node->rx_ids_version)) {
        update_filters(p, node);
    }
    co_frame_t f;
    while (co_bm_ring_pop(&p->rx, &f)) {
        co_node_rx(node, &f, co_bm_clock_now(p->clock));
    }
    return co_node_process(node, co_bm_clock_now(p->clock));
}
