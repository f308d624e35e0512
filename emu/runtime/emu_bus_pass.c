/* One pass of the main loop for a bus: its frames in, then its nodes: see emu_bus.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_bus.h"

#include <errno.h>
#include <poll.h>
#include <string.h>
#include <time.h>

#include "runtime/emu_events.h"
#include "runtime/emu_output.h"
#include "nvm_writer.h"

/* Gives a frame to the nodes of one word of the routing table (bits: the nodes base + 0..63 that take it). */
static inline void deliver_word(emu_bus_t *b, const co_frame_t *f, size_t base, uint64_t bits, size_t sender,
                                co_time_us_t now)
{
    while (bits != 0U) {
        const size_t i = base + (size_t)__builtin_ctzll(bits);
        bits &= bits - 1U;
        emu_node_t *n = b->nodes[i];
        if (i != sender && i < b->n_nodes && (faults_none(&n->faults) || faults_rx(n, f, now))) {
            if (device_rx(&n->dev, f, now) && !device_settled(&n->dev)) {
                node_mark_dirty(n); /* not for an SDO request answered whole: the pass would find nothing */
            }
        }
    }
}

/* Gives a frame to the nodes that take its CAN-ID (but its sender's): the core would ignore it everywhere else.
 * Inline: every frame read and every frame between local nodes comes this way. */
static inline void deliver(emu_bus_t *b, const co_frame_t *f, size_t sender, co_time_us_t now)
{
    if ((f->flags & (CO_FRAME_EFF | CO_FRAME_ERR)) != 0U || f->id > 0x7FFU) {
        return; /* CANopen nodes take 11-bit frames only */
    }
    /* each word copied as it is taken: a node's reset may change the table meanwhile */
    deliver_word(b, f, 0U, b->takes[f->id][0], sender, now);
    deliver_word(b, f, 64U, b->takes[f->id][1], sender, now); /* nodes 64..126 */
}

/* A frame from outside the program: read from the medium, or a socketcand client's. Inline: every frame read comes
 * this way. */
static inline __attribute__((always_inline)) void frame_in(emu_bus_t *b, const co_frame_t *f, co_time_us_t now)
{
    if (b->log_level >= LOG_VERBOSE) {
        /* 8 digits for a 29-bit identifier, as candump: an extended 0x181 must not read as TPDO1 of node 1 */
        logline(LOG_VERBOSE, "rx %0*X [%u]%s", (f->flags & CO_FRAME_EFF) != 0U ? 8 : 3, (unsigned)f->id, f->len,
                (f->flags & CO_FRAME_RTR) != 0U ? " RTR" : "");
    }
    events_frame(b, NULL, f, now);
    if ((f->id & 0x780U) == 0x700U && f->id != 0x700U && f->len >= 1U &&
        (f->flags & (CO_FRAME_RTR | CO_FRAME_EFF | CO_FRAME_ERR)) == 0U) {
        /* another node's heartbeat, boot-up or guarding answer: the overview lists the nodes heard */
        b->heard[f->id & 0x7FU] = (heard_node_t){now, (uint8_t)(f->data[0] & 0x7FU)};
    }
    deliver(b, f, MAX_NODES, now);
}

void bus_frame_in(emu_bus_t *b, const co_frame_t *f, co_time_us_t now)
{
    frame_in(b, f, now);
}

/* Runs one node, marked or due: its device, then its faults (frames held back, this run's too; a bus-off's end). */
static inline void run_node(emu_bus_t *b, emu_node_t *n, co_time_us_t now)
{
    const uint32_t i = (uint32_t)n->index;
    co_time_us_t d = device_process(&n->dev, now);
    if (!faults_none(&n->faults)) {
        const co_time_us_t held = faults_run(n, now);
        if (schedule_take_mark(&b->schedule, i)) {
            d = device_process(&n->dev, now); /* the faults changed the node: a recovery EMCY goes out now */
        }
        d = held < d ? held : d;
    }
    schedule_set(&b->schedule, i, d);
    if (d <= now) {
        schedule_set_again(&b->schedule, i); /* not again in this round */
    }
    schedule_set_tx_waiting(&b->schedule, i, n->dev.node.txq.count > 0U);
}

/* The marked nodes, in the order of the bus; an entry whose mark was taken already (a node its faults marked again
 * while it ran) is skipped. */
static void run_marked(emu_bus_t *b, co_time_us_t now)
{
    emu_schedule_t *s = &b->schedule;
    schedule_sort_marked(s);
    for (size_t k = 0U; k < s->n_marked; k++) {
        const uint32_t i = s->marked[k];
        if (schedule_take_mark(s, i)) {
            run_node(b, b->nodes[i], now);
        }
    }
    s->n_marked = 0U;
}

/* Offers the local frames to the other nodes and runs the nodes marked or due, until no local frame waits: the pass
 * bus_run's gating lets through. Only these nodes run, found without a scan (emu_schedule.h): with 127 nodes on one
 * bus, a scan of every node at every wake-up cost more than the node's own work (docs/performance.md "Scale"). */
static inline __attribute__((always_inline)) void run_nodes(emu_bus_t *b, co_time_us_t now)
{
    emu_schedule_t *s = &b->schedule;
    do {
        while (b->local_count > 0U) {
            const local_frame_t l = b->local[b->local_head];
            b->local_head = (b->local_head + 1U) % LOCAL_QUEUE_LEN;
            b->local_count--;
            deliver(b, &l.frame, l.sender, now);
        }
        schedule_new_round(s);
        if (s->n_marked > 0U || s->marked_overflow) {
            run_marked(b, now);
        }
        for (int i = schedule_due(s, now); i >= 0; i = schedule_due(s, now)) {
            run_node(b, b->nodes[i], now);
        }
        if (s->n_marked > 0U) { /* the rare case of schedule_due: the rest of those due, once each */
            run_marked(b, now);
        }
    } while (b->local_count > 0U); /* the others may have answered: loop until quiet */
}

static inline __attribute__((always_inline)) co_time_us_t bus_run(emu_bus_t *b, co_time_us_t now, bool *tx_pending,
                                                                  bool *ran)
{
    /* With no local frame waiting and no node marked or due, a pass would change nothing. */
    *ran = b->local_count > 0U || schedule_has_work(&b->schedule, now);
    if (*ran) {
        run_nodes(b, now);
    }
    const co_time_us_t next = schedule_next(&b->schedule);
    *tx_pending = schedule_any_tx_waiting(&b->schedule);
    const co_time_us_t r = can_channel_service(&b->can, now);
    return r < next ? r : next;
}

/* Reads what the interface has; returns the time it last read from the clock (now, later after a flood). Always
 * inline, as the pass: a call here costs bus_run_alone's loop its registers (about 35 instructions a frame). */
static inline __attribute__((always_inline)) co_time_us_t bus_receive(emu_bus_t *b, co_time_us_t now, co_time_us_t due)
{
    co_frame_t f;
    for (unsigned k = 0U; k < 1024U && can_channel_read(&b->can, &f, now) == 1; k++) {
        if (b->socketcand_readers > 0U) { /* before the nodes' answers to it, which frame_in may send */
            socketcand_publish(&b->emu->socketcand, b, &f, now, NULL);
        }
        frame_in(b, &f, now);
        /* Clients that send a request as soon as an answer is out keep the socket from running dry: without this a
         * flood could hold every heartbeat back until 1024 frames were read (a 350 ms gap failed test_bus_faults'
         * flood test in a loaded run). Looked at once a read-ahead batch is used up, where stopping loses nothing;
         * a batch that emptied the kernel's queue ends the reading without another call. */
        if (can_channel_read_ahead_empty(&b->can)) {
            if (can_channel_read_drained(&b->can)) {
                break;
            }
            now = socketcan_now_us();
            if (now >= due) {
                break;
            }
        }
    }
    return now;
}

/* Room in the socket's buffer again: the nodes with queued frames retry in this pass. Without this the loop would
 * poll again, get POLLOUT at once, and spin until the nodes' retry deadline. */
static void tx_ready(emu_bus_t *b)
{
    for (uint32_t w = 0U; w < 2U; w++) {
        for (uint64_t bits = b->schedule.tx_waiting[w]; bits != 0U; bits &= bits - 1U) {
            schedule_mark(&b->schedule, 64U * w + (uint32_t)__builtin_ctzll(bits));
        }
    }
}

/* Inline into both callers: bus_run_alone's loop then keeps the pass's time and state in registers. */
static inline __attribute__((always_inline)) co_time_us_t pass(emu_bus_t *b, co_time_us_t *now, short revents,
                                                               co_time_us_t due, bool *tx_pending, bool *ran)
{
    if ((revents & (POLLIN | POLLERR | POLLHUP)) != 0) {
        *now = bus_receive(b, *now, due);
    }
    if ((revents & POLLOUT) != 0) {
        tx_ready(b);
    }
    return bus_run(b, *now, tx_pending, ran);
}

co_time_us_t bus_pass(emu_bus_t *b, co_time_us_t *now, short revents, co_time_us_t due, bool *tx_pending)
{
    bool ran = false;
    return pass(b, now, revents, due, tx_pending, &ran);
}

/* The same pass and sleep as loop_run's for this case, in one function with the pass inlined: the pass per frame
 * costs no call and no round trip of the time and state through memory. */
int bus_run_alone(emu_t *emu, const volatile sig_atomic_t *stop, co_time_us_t *now, co_time_us_t *next, short revents)
{
    emu_bus_t *b = emu->buses[0];
    struct pollfd pfd = {can_channel_fd(&b->can), POLLIN, revents};
    /* The time and the deadline in locals, given back at the end: the inlined pass keeps them in registers. */
    co_time_us_t t = *now;
    co_time_us_t deadline = *next;
    int status = 0;
    while (!emu->quit && *stop == 0) {
        bool tx_pending = false;
        bool ran = false;
        deadline = pass(b, &t, pfd.revents, deadline, &tx_pending, &ran);
        if (output_flush()) {
            break; /* output waits: loop_run polls for it */
        }
        pfd.fd = can_channel_fd(&b->can);
        pfd.events = can_channel_poll_events(&b->can, tx_pending);
        pfd.revents = 0;
        /* The sleep ends at the deadline, not late by the pass's work: the clock is read again after nodes ran (a
         * flood's reading reads it itself). A pass that only read a frame no node takes took less than a
         * microsecond: the time it woke at serves, and spares a clock read per frame. */
        if (ran) {
            t = socketcan_now_us();
            nvm_writer_poll(); /* a node may have saved: see loop_run */
        }
        struct timespec ts;
        if (ppoll(&pfd, 1U, emu_poll_timeout(deadline, t, &ts), NULL) < 0) {
            if (errno != EINTR) {
                output_error("poll: %s", strerror(errno));
                status = 1;
                break;
            }
            pfd.revents = 0; /* a signal: nothing is ready */
        }
        t = socketcan_now_us();
    }
    *now = t;
    *next = deadline;
    return status;
}
