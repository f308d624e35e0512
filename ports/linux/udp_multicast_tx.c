/* A udp_multicast bus's sending side: the frames of a pass in one batch, sent with sendmmsg (udp_multicast.h). */
#define _GNU_SOURCE
#include "udp_multicast.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>

static void tx_log(udp_multicast_t *u, const char *text)
{
    if (u->log != NULL) {
        char line[sizeof u->name + 260]; /* the name, ": " and the longest text (below 250) */
        (void)snprintf(line, sizeof line, "%s: %s", u->name, text);
        u->log(u->log_ctx, line);
    }
}

/* The messages point into this struct: set up again when it is found moved (as the read-ahead's). */
static void tx_setup(udp_multicast_t *u)
{
    for (unsigned i = 0U; i < UDP_MULTICAST_TX_BATCH; i++) {
        memset(&u->tx_msgs[i], 0, sizeof u->tx_msgs[i]);
        u->tx_iov[i].iov_base = u->tx_buf[i];
        u->tx_msgs[i].msg_hdr.msg_iov = &u->tx_iov[i];
        u->tx_msgs[i].msg_hdr.msg_iovlen = 1U;
    }
}

/* The first `done` datagrams left the batch: the rest move to its front, in order. */
static void tx_take(udp_multicast_t *u, unsigned done)
{
    const unsigned rest = u->tx_count - done;
    if (rest > 0U) {
        memmove(u->tx_buf[0], u->tx_buf[done], (size_t)rest * sizeof u->tx_buf[0]);
        for (unsigned i = 0U; i < rest; i++) {
            u->tx_iov[i].iov_len = u->tx_iov[done + i].iov_len;
        }
    }
    u->tx_count = rest;
}

void udp_multicast_flush(udp_multicast_t *u)
{
    u->tx_blocked = false;
    while (u->tx_count > 0U) {
        const int n = u->tx_fd >= 0 ? sendmmsg(u->tx_fd, u->tx_msgs, u->tx_count, MSG_DONTWAIT | MSG_NOSIGNAL) : -1;
        if (n > 0) {
            u->tx_frames += (unsigned)n;
            tx_take(u, (unsigned)n);
            if (u->tx_failing) {
                u->tx_failing = false;
                char text[120];
                (void)snprintf(text, sizeof text, "sending works again (%lu frame(s) lost)", u->tx_lost);
                tx_log(u, text);
            }
            continue;
        }
        const int e = u->tx_fd >= 0 ? errno : EBADF;
        if (e == EAGAIN || e == EWOULDBLOCK || e == ENOBUFS || e == EINTR) {
            /* the socket's buffer is full: the batch waits (POLLOUT; ENOBUFS and EINTR: the retry of
             * udp_multicast_tx_service, as POLLOUT would come at once and spin) */
            u->tx_blocked = e == EAGAIN || e == EWOULDBLOCK;
            return;
        }
        /* This datagram can never go (no route, the interface gone): lost, as a frame on a bus that never
         * carried it; the ones after it are tried. */
        u->tx_lost++;
        tx_take(u, 1U);
        if (!u->tx_failing) {
            u->tx_failing = true;
            char text[250];
            (void)snprintf(text, sizeof text, "cannot send to group %s on %s: %s; frames are lost until it works again",
                           u->cfg.group_text, u->ifname, strerror(e));
            tx_log(u, text);
        }
    }
}

co_status_t udp_multicast_send(udp_multicast_t *u, const co_frame_t *frame)
{
    if (u->tx_count == UDP_MULTICAST_TX_BATCH) {
        udp_multicast_flush(u);
        if (u->tx_count == UDP_MULTICAST_TX_BATCH) {
            return CO_ERR_BUSY; /* the batch and the socket's buffer are full: the core keeps the frame and retries */
        }
    }
    if (u->tx_msgs[0].msg_hdr.msg_iov != &u->tx_iov[0]) {
        tx_setup(u);
    }
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts); /* python-can's time stamps are time.time() */
    const size_t n = udp_datagram_encode(frame, (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9, u->tx_buf[u->tx_count],
                                         sizeof u->tx_buf[0]);
    if (n == 0U) {
        /* an error frame: the format has python-can's error messages only, and a node's error frame is not one */
        if (u->tx_not_carried++ == 0U) {
            tx_log(u, "an error frame from a node is not put on the bus (it carries data frames only); such frames "
                      "are counted, not logged again");
        }
        return CO_OK;
    }
    u->tx_iov[u->tx_count].iov_len = n;
    u->tx_count++;
    return CO_OK;
}

co_time_us_t udp_multicast_tx_service(udp_multicast_t *u, co_time_us_t now)
{
    udp_multicast_flush(u);
    return u->tx_count > 0U && !u->tx_blocked ? now + UDP_MULTICAST_TX_RETRY_US : CO_NEVER;
}
