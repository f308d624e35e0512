/* Linux SocketCAN channel: see socketcan.h. */
#define _GNU_SOURCE
#include "socketcan.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/if_arp.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <linux/sock_diag.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define REOPEN_INTERVAL_US 500000U

static void logf_(socketcan_t *c, const char *fmt, const char *detail)
{
    if (c->log != NULL) {
        char line[256];
        (void)snprintf(line, sizeof line, fmt, c->ifname, detail);
        c->log(c->log_ctx, line);
    }
}

static int open_socket(socketcan_t *c, char *err, size_t errlen)
{
    const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        const int e = errno;
        if (err != NULL) {
            if (e == EAFNOSUPPORT || e == EPROTONOSUPPORT) {
                (void)snprintf(err, errlen, "this kernel has no SocketCAN support (%s); on Linux with CAN: "
                               "sudo modprobe can_raw; without it see docs/vcan.md (tools/vcan-run)", strerror(e));
            } else if (e == EPERM || e == EACCES) {
                (void)snprintf(err, errlen, "no permission to open a CAN socket (%s)", strerror(e));
            } else {
                (void)snprintf(err, errlen, "cannot open a CAN socket: %s", strerror(e));
            }
        }
        return e;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", c->ifname);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        const int e = errno;
        (void)close(fd);
        if (err != NULL) {
            if (e == ENODEV) {
                (void)snprintf(err, errlen, "interface %s does not exist; create a virtual one with:\n"
                               "  sudo modprobe vcan\n  sudo ip link add dev %s type vcan\n  sudo ip link set up %s\n"
                               "(a kernel without CAN support: tools/vcan-run, see docs/vcan.md)",
                               c->ifname, c->ifname, c->ifname);
            } else {
                (void)snprintf(err, errlen, "interface %s: %s", c->ifname, strerror(e));
            }
        }
        return e;
    }
    /* Binding a CAN socket to another kind of interface fails with ENODEV, "No such device", for one that is
     * there (-i lo): its link type tells. */
    struct ifreq hw;
    memset(&hw, 0, sizeof hw);
    (void)snprintf(hw.ifr_name, sizeof hw.ifr_name, "%s", c->ifname);
    if (ioctl(fd, SIOCGIFHWADDR, &hw) == 0 && hw.ifr_hwaddr.sa_family != ARPHRD_CAN) {
        (void)close(fd);
        if (err != NULL) {
            (void)snprintf(err, errlen, "interface %s is not a CAN interface (link type %u; CAN is %u); the CAN "
                           "interfaces are those of: ip link show type can; ip link show type vcan",
                           c->ifname, (unsigned)hw.ifr_hwaddr.sa_family, (unsigned)ARPHRD_CAN);
        }
        return ENODEV;
    }
    const can_err_mask_t errors = CAN_ERR_MASK;
    (void)setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
    /* One socket sends for every emulated node: 127 nodes whose heartbeats and TPDOs fall due together send a burst
     * of 254 frames, more than the default send buffer (~200 KiB, a few hundred frames at the kernel's per-frame
     * cost) holds while the receivers have not taken them yet; the rest waited for room (EAGAIN) and went out late.
     * SO_SNDBUFFORCE (CAP_NET_ADMIN) may exceed net.core.wmem_max; without it SO_SNDBUF is capped there. The
     * receive buffer stays at its default: a flood beyond what the nodes can answer is better dropped (the master
     * sees a timeout) than queued for seconds on a virtual bus that, unlike a real one, has no bit rate. */
    c->rx_drops_socket = 0U; /* a new socket counts its drops from 0 */
    const int sndbuf = 4 << 20;
    if (setsockopt(fd, SOL_SOCKET, SO_SNDBUFFORCE, &sndbuf, sizeof sndbuf) != 0) {
        (void)setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        const int e = errno;
        (void)close(fd);
        if (err != NULL) {
            (void)snprintf(err, errlen, "cannot bind to %s: %s", c->ifname, strerror(e));
        }
        return e;
    }
    c->fd = fd;
    c->rx_next = 0U; /* nothing read ahead from a socket before this one is returned */
    c->rx_count = 0U;
    c->rx_drained = false;
    return 0;
}

int socketcan_open(socketcan_t *c, const char *ifname, socketcan_log_fn log, void *log_ctx, char *err, size_t errlen)
{
    memset(c, 0, sizeof *c);
    c->fd = -1;
    c->log = log;
    c->log_ctx = log_ctx;
    if (strlen(ifname) >= sizeof c->ifname) {
        (void)snprintf(err, errlen, "interface name '%s' is too long", ifname);
        return EINVAL;
    }
    (void)snprintf(c->ifname, sizeof c->ifname, "%s", ifname);
    c->error_lines_left = SOCKETCAN_ERROR_LINES; /* until the first socketcan_service starts the count of seconds */
    return open_socket(c, err, errlen);
}

void socketcan_close(socketcan_t *c)
{
    if (c->fd >= 0) {
        (void)close(c->fd);
        c->fd = -1;
    }
}

/* IFF_UP of the interface (true when it cannot be asked: the send or read that follows tells). */
static bool iface_up(const socketcan_t *c)
{
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", c->ifname);
    if (c->fd < 0 || ioctl(c->fd, SIOCGIFFLAGS, &ifr) < 0) {
        return true;
    }
    return (ifr.ifr_flags & IFF_UP) != 0;
}

static void set_down(socketcan_t *c, const char *what)
{
    if (!c->down) {
        c->down = true;
        logf_(c, "%s: interface is down%s", what);
    }
}

static void set_up(socketcan_t *c)
{
    if (c->down) {
        c->down = false;
        logf_(c, "%s: interface is up again%s", "");
    }
}

/* Received frames the kernel dropped because the socket's receive buffer was full: the socket's own count
 * (SO_MEMINFO, cumulative since it was opened), asked for by socketcan_service() after frames were read and
 * before the socket is closed. New drops are added to the total and logged; the asking is rate-limited, so
 * are the lines. */
static void log_rx_drops(socketcan_t *c)
{
    if (c->rx_dropped > c->rx_dropped_reported) {
        char detail[160];
        (void)snprintf(detail, sizeof detail, " %lu received frame(s) lost (%lu in all): the receive buffer was full, "
                       "the emulator fell behind", c->rx_dropped - c->rx_dropped_reported, c->rx_dropped);
        c->rx_dropped_reported = c->rx_dropped;
        logf_(c, "%s:%s", detail);
    }
}

static void query_rx_drops(socketcan_t *c)
{
#ifdef SO_MEMINFO
    uint32_t meminfo[SK_MEMINFO_VARS];
    socklen_t len = sizeof meminfo;
    if (c->fd >= 0 && getsockopt(c->fd, SOL_SOCKET, SO_MEMINFO, meminfo, &len) == 0 &&
        len > (socklen_t)(SK_MEMINFO_DROPS * sizeof meminfo[0]) && meminfo[SK_MEMINFO_DROPS] > c->rx_drops_socket) {
        c->rx_dropped += (uint32_t)(meminfo[SK_MEMINFO_DROPS] - c->rx_drops_socket);
        c->rx_drops_socket = meminfo[SK_MEMINFO_DROPS];
        log_rx_drops(c);
    }
#else
    (void)c; /* headers older than Linux 4.6: drops are not counted */
#endif
}

/* The error frames of the ended second that were not logged one by one, in one line. */
static void log_error_summary(socketcan_t *c)
{
    if (c->error_frames_unlogged > 0U) {
        char line[160];
        (void)snprintf(line, sizeof line, " %lu more CAN error frame(s) not logged one by one (the last: %s; "
                       "%lu in all)", c->error_frames_unlogged, c->error_last, c->error_frames);
        c->error_frames_unlogged = 0U;
        logf_(c, "%s:%s", line);
    }
}

void socketcan_flush_log(socketcan_t *c)
{
    query_rx_drops(c);
    log_error_summary(c);
}

static void went_away(socketcan_t *c, int e)
{
    if (!c->gone) {
        logf_(c, "%s: interface gone (%s); waiting for it to come back", strerror(e));
    }
    query_rx_drops(c); /* the socket's count goes with it */
    socketcan_close(c);
    c->gone = true;
    c->next_reopen = 0U;
    c->service_at = 0U;
}

co_status_t socketcan_send_slow(socketcan_t *c, const struct can_frame *cf, ssize_t n)
{
    int e = errno; /* of the write, when it failed */
    if (c->fd < 0) {
        c->lost_while_down++;
        return CO_ERR_IO;
    }
    if (c->tx_full_hold) {
        /* The queue was full earlier in this pass of the main loop: with many nodes on one socket, each
         * retrying its frame every CO_TX_RETRY_US, asking again would cost one failing system call per node. */
        return CO_ERR_BUSY;
    }
    if (n < 0 && e == ENETDOWN && iface_up(c)) {
        /* A socket error is delivered once, to the next read or write, whenever that comes: this ENETDOWN can
         * report an outage that is already over (down and up while the loop did not look). The outage is
         * reported, and the frame is not lost for it. */
        set_down(c, "; frames are lost until it is up again");
        n = write(c->fd, cf, sizeof *cf);
        e = errno;
    }
    if (n == (ssize_t)sizeof *cf) {
        c->tx_full = false;
        set_up(c);
        return CO_OK;
    }
    if (e == ENOBUFS) {
        /* The interface's queue is full (a real controller that cannot send: bus busy, no acknowledgement).
         * The core keeps the frame and retries CO_TX_RETRY_US later; POLLOUT would not wait for this, as the
         * socket itself stays writable (socketcan_poll_events). */
        c->tx_full = true;
        c->tx_full_hold = true;
        return CO_ERR_BUSY;
    }
    if (e == EAGAIN || e == EINTR) {
        c->tx_full = false;
        return CO_ERR_BUSY; /* the socket's buffer is full: kept by the core, sent when POLLOUT says so */
    }
    if (e == ENETDOWN) {
        set_down(c, "; frames are lost until it is up again");
        c->lost_while_down++;
        return CO_ERR_IO;
    }
    if (e == ENODEV || e == ENXIO) {
        went_away(c, e);
        return CO_ERR_IO;
    }
    logf_(c, "%s: send failed: %s", strerror(e));
    return CO_ERR_IO;
}

/* Out of line: an error frame is rare, and its text buffer would otherwise cost every read a larger stack frame. */
static __attribute__((noinline)) void error_frame(socketcan_t *c, const struct can_frame *cf)
{
    char detail[64];
    c->error_frames++;
    (void)snprintf(detail, sizeof detail, "class 0x%03X, data %02X %02X %02X %02X",
                   (unsigned)(cf->can_id & CAN_ERR_MASK), cf->data[1], cf->data[2], cf->data[3], cf->data[4]);
    if (c->error_lines_left > 0U) {
        c->error_lines_left--;
        logf_(c, "%s: CAN error frame (%s)", detail);
    } else {
        c->error_frames_unlogged++; /* summed up by socketcan_service at the end of the second */
        (void)memcpy(c->error_last, detail, sizeof detail);
        if (c->error_window_end < c->service_next) {
            c->service_next = c->error_window_end; /* the summary wakes the loop, even on a bus gone quiet */
        }
    }
}

/* Out of line: what a failed read means (nothing waiting is the common case, and cheap). */
static __attribute__((noinline)) int read_failed(socketcan_t *c, int e)
{
    if (e == EAGAIN || e == EINTR) {
        return 0;
    }
    if (e == ENETDOWN) {
        set_down(c, "");
        return 0;
    }
    went_away(c, e);
    return -1;
}

int socketcan_read_ahead(socketcan_t *c)
{
    if (c->fd < 0) {
        return 0;
    }
    if (c->rx_msgs[0].msg_hdr.msg_iov != &c->rx_iov[0]) {
        socketcan_rx_setup(c);
    }
    /* Fewer than asked for: the queue ran empty (or an error came after the first frames, which the next call
     * returns). */
    const int n = recvmmsg(c->fd, c->rx_msgs, SOCKETCAN_RX_BATCH, MSG_DONTWAIT, NULL);
    if (n < 0) {
        return read_failed(c, errno);
    }
    c->rx_next = 0U;
    c->rx_count = (unsigned)n;
    c->rx_drained = (unsigned)n < SOCKETCAN_RX_BATCH;
    return n;
}

int socketcan_read_other(socketcan_t *c, unsigned k, co_frame_t *frame)
{
    if (c->rx_msgs[k].msg_len != sizeof c->rx_frames[k]) {
        return 0; /* not a classic CAN frame */
    }
    if (c->down && iface_up(c)) {
        /* Not on any frame: frames received before the interface went down may still be queued. */
        set_up(c);
    }
    if (!c->rx_since_query) {
        /* The drop count is to be asked for at rx_next_query: socketcan_service runs and wakes the loop then. */
        c->rx_since_query = true;
        c->service_at = c->rx_next_query < c->service_at ? c->rx_next_query : c->service_at;
        c->service_next = c->rx_next_query < c->service_next ? c->rx_next_query : c->service_next;
    }
    const struct can_frame *cf = &c->rx_frames[k];
    const canid_t id = cf->can_id;
    if ((id & CAN_ERR_FLAG) != 0U) {
        error_frame(c, cf);
        return 0;
    }
    const bool eff = (id & CAN_EFF_FLAG) != 0U;
    frame->id = id & (eff ? CAN_EFF_MASK : CAN_SFF_MASK);
    frame->flags = (uint8_t)(((id & CAN_RTR_FLAG) != 0U ? CO_FRAME_RTR : 0U) | (eff ? CO_FRAME_EFF : 0U));
    frame->len = cf->can_dlc > 8U ? 8U : cf->can_dlc;
    memcpy(frame->data, cf->data, sizeof frame->data); /* all 8: bytes past len are undefined on receive */
    return 1;
}

/* socketcan_service() proper; returns the next time it wants to run (a wake-up), or CO_NEVER. */
static co_time_us_t service(socketcan_t *c, co_time_us_t now)
{
    c->tx_full_hold = false; /* a new pass of the main loop: the next send asks the kernel again */
    co_time_us_t next = CO_NEVER;
    if (now >= c->error_window_end) {
        log_error_summary(c);
        c->error_lines_left = SOCKETCAN_ERROR_LINES;
        c->error_window_end = now + 1000000U;
    } else if (c->error_frames_unlogged > 0U) {
        next = c->error_window_end; /* the summary is due then, even on a bus that went quiet */
    }
    if (c->rx_since_query || c->rx_query_again) {
        /* Frames were read: ask for the socket's drop count (one system call) at once, then at most once a second
         * while frames keep coming, and once more a second after the last ask: drops after the last frame queued
         * (a burst into a stalled reader, and silence after it) or a burst the kernel delivers in parts. */
        if (now >= c->rx_next_query) {
            c->rx_query_again = c->rx_since_query;
            c->rx_since_query = false;
            c->rx_next_query = now + 1000000U;
            query_rx_drops(c);
        } else if (c->rx_next_query < next) {
            next = c->rx_next_query;
        }
    }
    if (!c->gone) {
        return next;
    }
    if (now >= c->next_reopen) {
        if (open_socket(c, NULL, 0U) == 0) {
            c->gone = false;
            c->down = false;
            c->tx_full = false;
            logf_(c, "%s: interface is back%s", "");
            return next;
        }
        c->next_reopen = now + REOPEN_INTERVAL_US;
    }
    return c->next_reopen < next ? c->next_reopen : next;
}

co_time_us_t socketcan_service_run(socketcan_t *c, co_time_us_t now)
{
    const co_time_us_t next = service(c, now);
    /* Each of its branches is due again at one of these times (the error second rolls over at its end even when
     * nothing waits for it); a frame read or a socket gone bring it forward (socketcan_read, went_away). */
    co_time_us_t at = c->error_window_end;
    if ((c->rx_since_query || c->rx_query_again) && c->rx_next_query < at) {
        at = c->rx_next_query;
    }
    if (c->gone && c->next_reopen < at) {
        at = c->next_reopen;
    }
    c->service_at = at;
    c->service_next = next;
    return next;
}
