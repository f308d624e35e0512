/* One bus and its nodes: see emu_bus.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_bus.h"

#include <stdio.h>
#include <string.h>

#include "runtime/emu_events.h"
#include "runtime/emu_output.h"

/* The channel's lines are all problems or their end (interface down / up again, gone / back, error frames, frames
 * lost, a failed send, datagrams that are not frames): shown with -q too, which keeps only problems. */
static void can_log(void *ctx, const char *line)
{
    logline(LOG_QUIET, "%s", line);
    events_interface((emu_bus_t *)ctx, line);
}

int bus_open(emu_bus_t *b, const can_channel_spec_t *spec, int log_level, char *err, size_t errlen)
{
    b->n_nodes = 0U;
    b->local_head = 0U;
    b->local_count = 0U;
    b->local_lost = 0UL;
    b->log_level = log_level;
    schedule_init(&b->schedule);
    const int e = can_channel_open(&b->can, spec, can_log, b, err, errlen);
    char about[320];
    if (e == 0 && can_channel_describe(&b->can, about, sizeof about)) {
        logline(LOG_NORMAL, "%s", about);
    }
    return e;
}

void bus_add_node(emu_bus_t *b, emu_node_t *n)
{
    n->bus = b;
    n->index = b->n_nodes;
    b->nodes[b->n_nodes++] = n;
    schedule_add(&b->schedule, (uint32_t)n->index, 0U); /* due at once: its first pass runs it */
}

void bus_remove_last_node(emu_bus_t *b, emu_node_t *n)
{
    bus_routes_remove(b, n);
    schedule_remove_last(&b->schedule, (uint32_t)n->index);
    b->n_nodes--;
}

void bus_routes_remove(emu_bus_t *b, const emu_node_t *n)
{
    const uint64_t bit = (uint64_t)1U << (n->index & 63U);
    for (size_t id = 0U; id < 0x800U; id++) {
        b->takes[id][n->index >> 6] &= ~bit;
    }
}

void bus_routes_update(emu_bus_t *b, const emu_node_t *n)
{
    static uint16_t ids[0x800];
    bus_routes_remove(b, n);
    const uint16_t count = co_node_rx_ids(&n->dev.node, ids, (uint16_t)(sizeof ids / sizeof ids[0]));
    for (uint16_t i = 0U; i < count && i < sizeof ids / sizeof ids[0]; i++) {
        b->takes[ids[i] & 0x7FFU][n->index >> 6] |= (uint64_t)1U << (n->index & 63U);
    }
}

/* Out of line: -v only; its buffer would otherwise cost every frame sent a larger stack frame. */
static __attribute__((noinline)) void log_sent(const emu_node_t *from, const co_frame_t *f)
{
    char hex[24] = "";
    for (uint8_t i = 0U; i < f->len; i++) {
        (void)snprintf(hex + 2U * i, sizeof hex - 2U * i, "%02X", f->data[i]);
    }
    logline(LOG_VERBOSE, "node %u tx %03X#%s", co_node_id(&from->dev.node), (unsigned)f->id, hex);
}

/* Whether a local node but from takes CAN-ID id (an 11-bit one). */
static inline bool others_take(const emu_bus_t *b, const emu_node_t *from, uint32_t id)
{
    uint64_t low = b->takes[id][0];
    uint64_t high = b->takes[id][1];
    const uint64_t bit = (uint64_t)1U << (from->index & 63U);
    if (from->index < 64U) {
        low &= ~bit;
    } else {
        high &= ~bit;
    }
    return (low | high) != 0U;
}

/* What a sent frame means beyond the interface: an event, the sender's heartbeat age, the copy for the other
 * local nodes, the socketcand clients' copies, the -v line. */
static inline __attribute__((always_inline)) void frame_sent(emu_bus_t *b, emu_node_t *from, const co_frame_t *f)
{
    const co_time_us_t at = from->dev.now != 0U ? from->dev.now : socketcan_now_us();
    events_frame(b, from, f, at);
    if (f->id == 0x700U + (uint32_t)from->dev.node.node_id) {
        from->last_heartbeat = at; /* its age in show: what a master's heartbeat consumer would see */
    }
    /* Queued only when another local node takes its CAN-ID now (the routing table as a frame on the bus would find
     * it): most frames a node sends (heartbeats, SDO answers, TPDOs) concern no other local node. */
    if (b->n_nodes > 1U && f->id <= 0x7FFU && (f->flags & (CO_FRAME_EFF | CO_FRAME_ERR)) == 0U &&
        others_take(b, from, f->id)) {
        if (b->local_count == LOCAL_QUEUE_LEN) {
            b->local_lost++; /* the other local nodes miss this frame; counted, reported at exit */
        } else {
            local_frame_t *l = &b->local[(b->local_head + b->local_count) % LOCAL_QUEUE_LEN];
            l->frame = *f;
            l->sender = from->index;
            b->local_count++;
        }
    }
    if (b->socketcand_readers > 0U) {
        socketcand_publish(&b->emu->socketcand, b, f, at, NULL);
    }
    if (b->log_level >= LOG_VERBOSE) {
        log_sent(from, f);
    }
}

co_status_t bus_send(emu_bus_t *b, emu_node_t *from, const co_frame_t *f)
{
    const co_status_t st = can_channel_send(&b->can, f);
    if (st == CO_OK) {
        frame_sent(b, from, f);
    }
    return st;
}

/* The faults' part of a node's frame: out of line, a node without faults never comes here. */
static __attribute__((noinline)) co_status_t send_through_faults(emu_node_t *n, const co_frame_t *f)
{
    co_frame_t frame = *f;
    switch (faults_tx(n, &frame, n->dev.now)) {
    case FAULT_TX_DROP:
        return CO_OK; /* lost on the way, as on a bus that never carried it */
    case FAULT_TX_HELD:
        return CO_OK; /* bus_run asks faults_run when it is due */
    default:
        return bus_send(n->bus, n, &frame);
    }
}

co_status_t bus_node_send(void *ctx, const co_frame_t *f)
{
    emu_node_t *n = (emu_node_t *)ctx;
    /* A store is durable before the core answers it: the port's last commit of the store does it (nvm_file.h). */
    if (!faults_none(&n->faults)) {
        return send_through_faults(n, f);
    }
    emu_bus_t *b = n->bus;
    const co_status_t st = can_channel_send(&b->can, f);
    if (st == CO_OK) {
        frame_sent(b, n, f);
    }
    return st;
}

void bus_close(emu_bus_t *b, unsigned long *sent, unsigned long *dropped, unsigned long *rx_lost)
{
    if (b->local_lost > 0U) {
        logline(LOG_QUIET, "%s: %lu frame(s) between local nodes were lost (queue full)", b->can.name, b->local_lost);
    }
    for (size_t i = 0U; i < b->n_nodes; i++) {
        const co_node_stats_t *st = &b->nodes[i]->dev.node.stats;
        *sent += st->tx_frames;
        *dropped += st->tx_dropped;
        if (st->tx_dropped > 0U) {
            logline(LOG_QUIET, "node %u (%s): %lu frame(s) could not be sent", co_node_id(&b->nodes[i]->dev.node),
                    b->nodes[i]->dev.cls->name, (unsigned long)st->tx_dropped);
        }
    }
    can_channel_flush_log(&b->can);
    *rx_lost += can_channel_rx_dropped(&b->can);
    can_channel_close(&b->can);
}
