/*
 * Reference bare-metal port: one CAN controller, a receive ring filled by the CAN interrupt, a clock,
 * optional flash storage. Ties co_bm_ring, co_bm_clock and co_bm_nvm to the core's co_port_t.
 *
 *   CAN RX interrupt ──► co_bm_port_rx_isr() ──► ring ──► co_bm_port_poll() in the main loop
 *                                                           ├─► co_node_rx(node, frame, now)
 *                                                           └─► co_node_process(node, now) ─► next deadline
 *
 * The board supplies co_bm_can_t: send() puts a frame into a free TX mailbox/FIFO slot and returns
 * CO_ERR_BUSY when there is none (the core keeps the frame and retries), CO_ERR_IO when the controller
 * is bus-off or the frame can never go out. It is called from the main loop only.
 */
#ifndef CO_BM_PORT_H
#define CO_BM_PORT_H

#include "co/co.h"
#include "co_bm_clock.h"
#include "co_bm_nvm.h"
#include "co_bm_ring.h"

/** CAN-IDs the port can give the controller's acceptance filters; a node that takes more gets every frame. */
#ifndef CO_BM_FILTER_MAX
#define CO_BM_FILTER_MAX 32U
#endif

typedef struct co_bm_can {
    co_status_t (*send)(void *ctx, const co_frame_t *frame);      /**< Mandatory; never blocks. */
    co_status_t (*set_bit_rate)(void *ctx, uint32_t kbit_per_s);  /**< NULL: the bit rate is fixed. */
    void *ctx;
    /**
     * Programs the acceptance filters: take exactly the frames (data or remote) with these 11-bit CAN-IDs, sorted;
     * n == 0 with ids == NULL: take every frame (the node takes more than CO_BM_FILTER_MAX IDs, or the controller
     * has fewer filters than n: it may return CO_ERR_RANGE, and the port then asks for every frame). Called from
     * co_bm_port_poll() when the node's IDs change (co_node_rx_ids); never needed for correctness, as the core
     * ignores what is not its own. NULL: no hardware filters.
     */
    co_status_t (*set_filters)(void *ctx, const uint16_t *ids, uint16_t n);
} co_bm_can_t;

typedef struct co_bm_port {
    co_port_t port;          /**< Give &port.port and port_ctx = &port to co_node_init(). */
    const co_bm_can_t *can;
    co_bm_nvm_t *nvm;        /**< NULL: no storage (0x1010 answers 0x06060000, LSS store "not supported"). */
    co_bm_clock_t *clock;
    co_bm_ring_t rx;
    bool filters_set;        /**< The filters follow the node's rx_ids_version below. */
    uint16_t filters_version;
    uint16_t filter_ids[CO_BM_FILTER_MAX];
} co_bm_port_t;

/** Sets up the port (empties the ring). Call before enabling the CAN receive interrupt. */
void co_bm_port_init(co_bm_port_t *p, const co_bm_can_t *can, co_bm_nvm_t *nvm, co_bm_clock_t *clock);

/** From the CAN receive interrupt, once per received frame. False when the ring was full (frame dropped). */
bool co_bm_port_rx_isr(co_bm_port_t *p, const co_frame_t *frame);

/**
 * One main-loop step: reprograms the acceptance filters when the node's CAN-IDs changed (can->set_filters), feeds
 * every queued frame to the node (with the current time), runs co_node_process() and returns its next deadline
 * (CO_NEVER when nothing is pending). Call it again when a frame arrives (the interrupt wakes the CPU) or when the
 * deadline is reached.
 */
co_time_us_t co_bm_port_poll(co_bm_port_t *p, co_node_t *node);

#endif /* CO_BM_PORT_H */
