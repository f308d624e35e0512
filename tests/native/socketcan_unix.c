/*
 * A test double of ports/linux/socketcan.c for running canopen-emu where there is no CAN (and under ASan, which
 * cannot run inside User-Mode Linux): the same API (socketcan.h), with the bus replaced by an AF_UNIX
 * SOCK_SEQPACKET connection to a test, one struct can_frame (16 bytes) per packet in each direction. The test
 * listens on the path in CO_FAKECAN_SOCKET; the interface name of -i is only kept for the log lines.
 * Linked into canopen-emu-fakecan (tests/native/CMakeLists.txt) instead of socketcan.c; everything else of the
 * program is the real one.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include "../../ports/linux/socketcan.h"

int socketcan_open(socketcan_t *c, const char *ifname, socketcan_log_fn log, void *log_ctx, char *err, size_t errlen)
{
    memset(c, 0, sizeof *c);
    c->fd = -1;
    c->log = log;
    c->log_ctx = log_ctx;
    (void)snprintf(c->ifname, sizeof c->ifname, "%s", ifname);
    const char *path = getenv("CO_FAKECAN_SOCKET");
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    if (path == NULL || strlen(path) >= sizeof addr.sun_path) {
        (void)snprintf(err, errlen, "CO_FAKECAN_SOCKET must name the test's socket (at most %zu bytes)",
                       sizeof addr.sun_path - 1U);
        return EINVAL;
    }
    memcpy(addr.sun_path, path, strlen(path));
    const int fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    if (fd < 0 || connect(fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        const int e = errno;
        if (fd >= 0) {
            (void)close(fd);
        }
        (void)snprintf(err, errlen, "cannot connect to the fake bus %s: %s", path, strerror(e));
        return e;
    }
    (void)fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    c->fd = fd;
    return 0;
}

void socketcan_close(socketcan_t *c)
{
    if (c->fd >= 0) {
        (void)close(c->fd);
        c->fd = -1;
    }
}

/* The part of socketcan_send (socketcan.h: the frame built and written there) that tells its result; the
 * interface is never down here and never refuses a send for a whole pass. */
co_status_t socketcan_send_slow(socketcan_t *c, const struct can_frame *cf, ssize_t n)
{
    if (c->fd < 0) {
        return CO_ERR_IO;
    }
    if (n == (ssize_t)sizeof *cf) {
        return CO_OK;
    }
    return (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS) ? CO_ERR_BUSY : CO_ERR_IO;
}

/* Reads ahead as the real channel does (ports/linux/socketcan.c): up to SOCKETCAN_RX_BATCH packets in one recvmmsg,
 * fewer meaning the queue ran empty (socketcan_read_drained), and plain data frames taken inline by socketcan_read
 * (rx_since_query always set: there is no drop count to ask for here). So the program's cost per frame read, which
 * the benches measure on this double (bench/scale_cost.py), is the real channel's, not one system call more per
 * frame and a slower path for every frame. */
int socketcan_read_ahead(socketcan_t *c)
{
    if (c->fd < 0) {
        return 0;
    }
    if (c->rx_msgs[0].msg_hdr.msg_iov != &c->rx_iov[0]) {
        socketcan_rx_setup(c);
        c->rx_since_query = true;
    }
    const int n = recvmmsg(c->fd, c->rx_msgs, SOCKETCAN_RX_BATCH, MSG_DONTWAIT, NULL);
    if (n < 0) {
        return 0; /* EAGAIN */
    }
    /* the test closed the bus (an empty packet: the end of the connection): nothing more arrives, sends fail */
    unsigned count = (unsigned)n;
    for (unsigned i = 0U; i < count; i++) {
        if (c->rx_msgs[i].msg_len == 0U) {
            count = i;
            (void)close(c->fd);
            c->fd = -1;
            break;
        }
    }
    c->rx_next = 0U;
    c->rx_count = count;
    c->rx_drained = count < SOCKETCAN_RX_BATCH;
    return (int)count;
}

int socketcan_read_other(socketcan_t *c, unsigned k, co_frame_t *frame)
{
    const struct can_frame *f = &c->rx_frames[k];
    if (c->rx_msgs[k].msg_len != sizeof *f || (f->can_id & CAN_ERR_FLAG) != 0U) {
        return 0; /* a packet of another size, or an error frame (the real channel logs those) */
    }
    memset(frame, 0, sizeof *frame);
    frame->id = f->can_id & CAN_EFF_MASK;
    frame->flags = (uint8_t)(((f->can_id & CAN_RTR_FLAG) != 0U ? CO_FRAME_RTR : 0U) |
                             ((f->can_id & CAN_EFF_FLAG) != 0U ? CO_FRAME_EFF : 0U));
    frame->len = f->can_dlc > 8U ? 8U : f->can_dlc;
    memcpy(frame->data, f->data, frame->len);
    return 1;
}

void socketcan_flush_log(socketcan_t *c) { (void)c; }

/* Nothing to service here, ever (socketcan_service() in socketcan.h calls this when service_at has come). */
co_time_us_t socketcan_service_run(socketcan_t *c, co_time_us_t now)
{
    (void)now;
    c->service_at = CO_NEVER;
    c->service_next = CO_NEVER;
    return CO_NEVER;
}
