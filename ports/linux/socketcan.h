/**
 * @file socketcan.h
 * @brief Linux SocketCAN channel for one emulated node: a non-blocking raw CAN socket on an interface.
 *
 * send never blocks: a full transmit queue (ENOBUFS/EAGAIN) answers CO_ERR_BUSY, so the core keeps the
 * frame and retries; an interface that is down answers CO_ERR_IO (the frame is lost, as on a real bus
 * that is off) and is reported once, and its return once. A vanished interface is reopened by
 * socketcan_service() until it is back. Classic CAN only; error frames and received frames the kernel dropped
 * (receive buffer full) are reported through the log callback. Error frames are logged one line each up to
 * SOCKETCAN_ERROR_LINES per second; beyond that they are counted and summed up in one line a second (a lone
 * node on a real bus, unacknowledged, gets thousands a second).
 *
 * The main loop polls the socket for socketcan_poll_events(): POLLOUT only helps when the socket's own buffer
 * was full (EAGAIN). ENOBUFS means the interface's queue is full, which poll does not report: the socket stays
 * writable, so polling for POLLOUT then returns at once and the loop spins; the core's retry deadline
 * (CO_TX_RETRY_US after the refusal) wakes the loop instead.
 */
#ifndef SOCKETCAN_H
#define SOCKETCAN_H

#include <linux/can.h>
#include <net/if.h>
#include <poll.h>
#include <stdbool.h>
#include <string.h>
#include <sys/socket.h> /* struct mmsghdr: the includer defines _GNU_SOURCE, as every file of the Linux program */
#include <time.h>
#include <unistd.h>

#include "co/co.h"

typedef void (*socketcan_log_fn)(void *ctx, const char *line);

/** Error frames logged one line each per second; the rest of that second's go into one summary line. */
#define SOCKETCAN_ERROR_LINES 10U

/** Frames one system call reads ahead (recvmmsg): a wake-up for one frame costs one call instead of two (the second
 *  read only to learn that the queue is empty), a flood one call per this many frames. */
#define SOCKETCAN_RX_BATCH 8U

typedef struct socketcan {
    char ifname[IF_NAMESIZE];
    int fd;                   /**< -1 while the interface is gone. */
    bool down;                /**< Sends fail because the interface is down (reported once). */
    bool gone;                /**< The interface disappeared; reopened by socketcan_service(). */
    bool tx_full;             /**< The last send met a full interface queue (ENOBUFS). */
    bool tx_full_hold;        /**< ... in this pass of the main loop: further sends are refused at once. */
    co_time_us_t next_reopen;
    unsigned long lost_while_down;
    unsigned long error_frames;        /**< CAN error frames received, all. */
    unsigned long error_frames_unlogged; /**< ... of them not logged one by one, not yet summed up either. */
    uint32_t error_lines_left;         /**< Error frames that may still be logged one by one in this second. */
    co_time_us_t error_window_end;     /**< When the second of error_lines_left ends. */
    char error_last[64];               /**< The last unlogged error frame's class and data, for the summary. */
    unsigned long rx_dropped;          /**< Received frames the kernel dropped (receive buffer full), all sockets. */
    unsigned long rx_dropped_reported; /**< ... of them already logged. */
    uint32_t rx_drops_socket;          /**< The current socket's own count (SO_MEMINFO), from 0 at open. */
    bool rx_since_query;               /**< Frames were read since the count was last asked for. */
    bool rx_query_again;               /**< Ask once more a second after the last ask (drops after the last frame). */
    co_time_us_t rx_next_query;
    /* The earliest time socketcan_service() has anything to do (roll the error frames' second, ask for the drop
     * count, reopen), whether or not it wakes the loop for it, and what it returned last: before service_at, and
     * with no send refused in this pass (tx_full_hold), it would return service_next again and change nothing. A
     * frame read, an error frame and a socket gone bring both forward. */
    co_time_us_t service_at;
    co_time_us_t service_next;
    socketcan_log_fn log;
    void *log_ctx;
    /* Read ahead by socketcan_read(): rx_frames[rx_next..rx_count) not returned yet. rx_drained: the call that read
     * them got fewer than SOCKETCAN_RX_BATCH, so the kernel's queue was empty then. rx_msgs point into this struct:
     * set up again when it is found moved. */
    struct can_frame rx_frames[SOCKETCAN_RX_BATCH];
    struct iovec rx_iov[SOCKETCAN_RX_BATCH];
    struct mmsghdr rx_msgs[SOCKETCAN_RX_BATCH];
    unsigned rx_next;
    unsigned rx_count;
    bool rx_drained;
} socketcan_t;

/** Opens the channel. Returns 0, or an errno value with a message for the user in err. */
int socketcan_open(socketcan_t *c, const char *ifname, socketcan_log_fn log, void *log_ctx, char *err, size_t errlen);
void socketcan_close(socketcan_t *c);

/** socketcan_send's other cases: no socket, a send refused in this pass (tx_full_hold), or the write of cf that
 *  returned n (errno set when it failed) and is not a plain success on an interface known to be up. */
co_status_t socketcan_send_slow(socketcan_t *c, const struct can_frame *cf, ssize_t n);

/* CO_FRAME_RTR (bit 0) moved to CAN_RTR_FLAG (bit 30) and back with a shift: no branch per frame; CO_FRAME_EFF
 * (bit 1) to CAN_EFF_FLAG (bit 31) with the same shift. */
#define SOCKETCAN_RTR_SHIFT 30U
typedef char socketcan_rtr_flags_line_up[(CO_FRAME_RTR << SOCKETCAN_RTR_SHIFT) == CAN_RTR_FLAG ? 1 : -1];
typedef char socketcan_eff_flags_line_up[((canid_t)CO_FRAME_EFF << SOCKETCAN_RTR_SHIFT) == CAN_EFF_FLAG ? 1 : -1];

/** co_port_t.send for this channel (ctx = socketcan_t *). Inline, the write and its plain success: every frame a
 *  node sends comes this way, and a layer of call for it cost as much as the rest of the success path. */
static inline co_status_t socketcan_send(void *ctx, const co_frame_t *frame)
{
    socketcan_t *c = (socketcan_t *)ctx;
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    /* the nodes send 11-bit frames only, but a socketcand client's 29-bit frame comes this way too: it stays one */
    const canid_t flags = (canid_t)(frame->flags & (CO_FRAME_RTR | CO_FRAME_EFF)) << SOCKETCAN_RTR_SHIFT;
    cf.can_id = (frame->id & ((flags & CAN_EFF_FLAG) != 0U ? CAN_EFF_MASK : CAN_SFF_MASK)) | flags;
    cf.can_dlc = frame->len;
    memcpy(cf.data, frame->data, sizeof cf.data); /* all 8: bytes past len are zero on transmit (co_frame_t) */
    ssize_t n = -1;
    if (c->fd >= 0 && !c->tx_full_hold) {
        n = write(c->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf && !c->down) {
            c->tx_full = false;
            return CO_OK;
        }
    }
    return socketcan_send_slow(c, &cf, n);
}

/** The events to poll the socket for: POLLIN, and POLLOUT when frames wait (tx_pending) for room in the
 * socket's buffer; not after ENOBUFS (see above). */
static inline short socketcan_poll_events(const socketcan_t *c, bool tx_pending)
{
    return (short)(POLLIN | (tx_pending && !c->tx_full ? POLLOUT : 0)); /* inline: the loop asks before every sleep */
}

/** Points each message of the read-ahead at its frame, for recvmmsg; again whenever the struct moved since (its
 *  iovecs point into it). For socketcan_read_ahead, and for a test double of it. */
static inline void socketcan_rx_setup(socketcan_t *c)
{
    for (unsigned i = 0U; i < SOCKETCAN_RX_BATCH; i++) {
        c->rx_iov[i].iov_base = &c->rx_frames[i];
        c->rx_iov[i].iov_len = sizeof c->rx_frames[i];
        memset(&c->rx_msgs[i], 0, sizeof c->rx_msgs[i]);
        c->rx_msgs[i].msg_hdr.msg_iov = &c->rx_iov[i];
        c->rx_msgs[i].msg_hdr.msg_iovlen = 1U;
    }
}

/** socketcan_read's call to the kernel, with nothing read ahead: reads ahead up to SOCKETCAN_RX_BATCH frames (one
 *  system call); their count, 0 when none waits, -1 when the interface went away (reported, reopened later). */
int socketcan_read_ahead(socketcan_t *c);

/** socketcan_read's other frames, rx_frames[k] (already taken from the read-ahead): not a classic CAN frame, an
 *  error frame (logged), the first frame since the drop count was last asked for, or one read while the interface
 *  was known to be down. 1 with frame set, 0 when it is not one for the nodes. */
int socketcan_read_other(socketcan_t *c, unsigned k, co_frame_t *frame);

/** Reads one frame: 1 = a frame, 0 = none pending, -1 = the interface went away (reported, reopened later).
 * Frames come from a read-ahead of up to SOCKETCAN_RX_BATCH, which only a call with nothing read ahead refills
 * (one system call). A reader may stop before 0 only where socketcan_read_ahead_empty() holds: frames read ahead
 * wake no poll. Frames the kernel dropped because the receive buffer was full are counted (rx_dropped) and
 * logged, at most once a second (see socketcan_service). Inline, the plain data frame: every frame read comes this
 * way, and a layer of call cost it as much as taking it. */
static inline int socketcan_read(socketcan_t *c, co_frame_t *frame)
{
    for (;;) {
        if (c->rx_next == c->rx_count) {
            const int n = socketcan_read_ahead(c);
            if (n <= 0) {
                return n;
            }
        }
        const unsigned k = c->rx_next++;
        const struct can_frame *cf = &c->rx_frames[k];
        if (c->rx_msgs[k].msg_len == sizeof *cf && (cf->can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG)) == 0U &&
            c->rx_since_query && !c->down) {
            frame->id = cf->can_id & CAN_SFF_MASK;
            frame->flags = (uint8_t)((cf->can_id >> SOCKETCAN_RTR_SHIFT) & CO_FRAME_RTR);
            frame->len = cf->can_dlc > 8U ? 8U : cf->can_dlc;
            memcpy(frame->data, cf->data, sizeof frame->data); /* all 8: bytes past len are undefined on receive */
            return 1;
        }
        if (socketcan_read_other(c, k, frame) == 1) {
            return 1;
        }
    }
}

/** True when every frame read ahead is returned: the next socketcan_read() asks the kernel. */
static inline bool socketcan_read_ahead_empty(const socketcan_t *c) { return c->rx_next == c->rx_count; }

/** With socketcan_read_ahead_empty(): the kernel's queue was empty when the last frames were read, so the next
 *  socketcan_read() would most likely return 0: a reader that stops here spares that system call (what arrived
 *  since wakes the next poll). */
static inline bool socketcan_read_drained(const socketcan_t *c) { return c->rx_drained; }

/** Asks the kernel for the drop count and logs received frames lost and not reported yet (call before exit). */
void socketcan_flush_log(socketcan_t *c);

/** socketcan_service()'s work, when it has any. */
co_time_us_t socketcan_service_run(socketcan_t *c, co_time_us_t now);

/** Call once per pass of the main loop. Reopens a vanished interface when due, asks for the receive drop count
 * after frames were read (at once, then at most once a second, and once more a second after the last ask);
 * returns the next time it wants to run, or CO_NEVER. After ENOBUFS, sends are refused (CO_ERR_BUSY) without a
 * system call until this call. Inline: most passes find nothing due and cost a comparison. */
static inline co_time_us_t socketcan_service(socketcan_t *c, co_time_us_t now)
{
    if (!c->tx_full_hold && now < c->service_at) {
        return c->service_next;
    }
    return socketcan_service_run(c, now);
}

#ifdef SOCKETCAN_NOW_US_EXTERN
/** The clock, given by a test harness that replaces it (tests/fuzz/target_control.c: repeatable runs). */
co_time_us_t socketcan_now_us(void);
#else
/** CLOCK_MONOTONIC in µs. Inline: the main loop reads it at every wake-up. */
static inline co_time_us_t socketcan_now_us(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (co_time_us_t)ts.tv_sec * 1000000U + (co_time_us_t)ts.tv_nsec / 1000U;
}
#endif

#endif
