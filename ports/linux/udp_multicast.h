/**
 * @file udp_multicast.h
 * @brief A CAN bus of UDP datagrams to an IP multicast group: python-can's udp_multicast interface (each frame one
 * datagram, udp_datagram.h), so that python-can, python-canopen and other canopen-emu processes on the same group
 * and port share the bus without SocketCAN, root or a kernel module (docs/buses.md).
 *
 * Two sockets: one joined to the group and bound to its port reads (as python-can's does), one on a port of its own
 * sends. A datagram whose source is the sending socket's address and port is this process's own (multicast loopback
 * is on, so that other processes on this machine hear the bus) and is skipped: the bus's nodes already had it from
 * the emulator's local queue. A socket filter has the kernel drop them before they are queued (where it cannot be
 * attached, they are read and skipped). The group is joined on one interface, named in the log: the route to the group's, or
 * the one given with iface=; whoever is on that link is on the bus.
 *
 * Like socketcan.h: never blocks (a full send buffer answers CO_ERR_BUSY, the core retries), reads ahead up to
 * UDP_MULTICAST_RX_BATCH datagrams per system call, counts what it cannot use: datagrams that are not python-can
 * messages (logged at once, then summed up at most once a second), CAN FD and error frames (classic CAN only: logged
 * the first time, counted), datagrams the kernel dropped because the receive buffer was full (SO_RXQ_OVFL), sends
 * that failed (logged when they start and when they end).
 */
#ifndef UDP_MULTICAST_H
#define UDP_MULTICAST_H

#include <net/if.h>
#include <netinet/in.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/socket.h> /* struct mmsghdr: the includer defines _GNU_SOURCE, as every file of the Linux program */

#include "co/co.h"
#include "udp_datagram.h"

/** python-can's defaults (UdpMulticastBus.DEFAULT_GROUP_IPv4, DEFAULT_GROUP_IPv6, port). */
#define UDP_MULTICAST_DEFAULT_GROUP_V4 "239.74.163.2"
#define UDP_MULTICAST_DEFAULT_GROUP_V6 "ff15:7079:7468:6f6e:6465:6d6f:6d63:6173"
#define UDP_MULTICAST_DEFAULT_PORT 43113U

/** Datagrams one system call reads ahead (recvmmsg), as SOCKETCAN_RX_BATCH. */
#define UDP_MULTICAST_RX_BATCH 8U
/** Datagrams one system call sends (sendmmsg): the frames a pass of the bus's nodes sent, at most this many a call. */
#define UDP_MULTICAST_TX_BATCH 64U
/** Room for one datagram of a classic CAN frame in python-can's format (about 150 bytes). */
#define UDP_MULTICAST_TX_DATAGRAM 256U
/** A batch the socket did not take for a reason POLLOUT does not report (ENOBUFS) is tried again this much later. */
#define UDP_MULTICAST_TX_RETRY_US 1000U

typedef void (*udp_multicast_log_fn)(void *ctx, const char *line);

/** What -i udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME] asks for. */
typedef struct udp_multicast_config {
    struct sockaddr_storage group; /**< sockaddr_in or sockaddr_in6: the group and its port */
    socklen_t group_len;
    char group_text[48];           /**< as inet_ntop writes it */
    uint16_t port;
    uint8_t hop_limit;             /**< IPv4 TTL or IPv6 hop limit; 1 (this link) unless ttl= says otherwise */
    char iface[IF_NAMESIZE];       /**< the interface to join on; "" for the route's to the group */
} udp_multicast_config_t;

/** Parses what follows "udp_multicast" in -i: "", ":GROUP", ":GROUP:PORT", ":[IPV6]:PORT", then ",ttl=N" and
 *  ",iface=NAME" in any order. An IPv6 group without a port may go without brackets. Defaults: python-can's IPv4
 *  group and port, TTL 1. 0, or EINVAL with a message in err. */
int udp_multicast_parse(const char *text, udp_multicast_config_t *cfg, char *err, size_t errlen);

/** The bus's name: udp_multicast:GROUP:PORT (an IPv6 group in brackets). */
void udp_multicast_name(const udp_multicast_config_t *cfg, char *out, size_t len);

typedef struct udp_multicast {
    udp_multicast_config_t cfg;
    char name[80];
    int rx_fd;                      /**< joined, bound to the group's port; -1 when closed */
    int tx_fd;                      /**< connected to the group, on its own port */
    struct sockaddr_storage self;   /**< tx_fd's address: the source of this process's own datagrams */
    socklen_t self_len;
    char ifname[IF_NAMESIZE];       /**< where the group is joined */
    udp_multicast_log_fn log;
    void *log_ctx;
    unsigned long tx_frames;        /**< datagrams sent */
    unsigned long tx_lost;          /**< frames lost: a send failed other than for a full buffer (never counted
                                         by the node: it failed after the node's send returned, in the flush) */
    bool tx_failing;                /**< sends fail (reported once, and their end) */
    unsigned long tx_not_carried;   /**< error frames the nodes sent: not put on the bus */
    unsigned long rx_frames;        /**< frames read from the bus for the nodes */
    unsigned long rx_own;           /**< this process's own datagrams, skipped (those the kernel did not drop) */
    bool rx_own_filtered;           /**< the kernel drops this process's own datagrams (a socket filter) */
    unsigned long rx_fd_frames;     /**< CAN FD frames read: not for the nodes */
    unsigned long rx_error_frames;  /**< error frames read: not for the nodes */
    unsigned long malformed;        /**< datagrams that are not python-can messages, all */
    unsigned long malformed_unlogged; /**< ... not logged one by one and not summed up yet */
    char malformed_last[200];       /**< the last of them: its sender and what is wrong */
    co_time_us_t malformed_window_end; /**< the second after a logged one: those in it are summed up at its end */
    unsigned long rx_dropped;       /**< datagrams the kernel dropped (receive buffer full) */
    unsigned long rx_dropped_reported;
    uint32_t rx_overflow_socket;    /**< the socket's own count (SO_RXQ_OVFL), from 0 at open */
    unsigned long rx_kernel_drops;  /**< all the kernel counted: rx_dropped and the own datagrams drop_own refused */
    /* Read ahead: rx_buf[rx_next..rx_count) not returned yet; rx_drained: the call that read them got fewer than a
     * batch. The messages point into this struct: set up again when it is found moved (as socketcan_t). */
    uint8_t rx_buf[UDP_MULTICAST_RX_BATCH][UDP_DATAGRAM_MAX];
    struct sockaddr_storage rx_from[UDP_MULTICAST_RX_BATCH];
    union {
        size_t align; /* a control message header's */
        char bytes[64];
    } rx_control[UDP_MULTICAST_RX_BATCH];
    struct iovec rx_iov[UDP_MULTICAST_RX_BATCH];
    struct mmsghdr rx_msgs[UDP_MULTICAST_RX_BATCH];
    unsigned rx_next;
    unsigned rx_count;
    bool rx_drained;
    /* The batch: tx_buf[0..tx_count) encoded and not sent yet, in the order sent; tx_blocked: the last flush found
     * the socket's buffer full (EAGAIN: POLLOUT tells when to go on). */
    uint8_t tx_buf[UDP_MULTICAST_TX_BATCH][UDP_MULTICAST_TX_DATAGRAM];
    struct iovec tx_iov[UDP_MULTICAST_TX_BATCH];
    struct mmsghdr tx_msgs[UDP_MULTICAST_TX_BATCH];
    unsigned tx_count;
    bool tx_blocked;
} udp_multicast_t;

/** Opens both sockets and joins the group; logs where (LOG through log). 0, or an errno with a message in err. */
int udp_multicast_open(udp_multicast_t *u, const udp_multicast_config_t *cfg, const char *name,
                       udp_multicast_log_fn log, void *log_ctx, char *err, size_t errlen);
void udp_multicast_close(udp_multicast_t *u);

/** co_port_t.send's work for this bus: the frame's datagram joins the batch, which udp_multicast_tx_service sends at
 *  the end of the pass (one sendmmsg for up to UDP_MULTICAST_TX_BATCH: a system call per frame was a seventh of the
 *  emulator's time at 8 x 127 nodes). A full batch is sent first; CO_ERR_BUSY when the socket's buffer does not take
 *  it either (the core keeps the frame and retries). A datagram the socket refuses for good (no route) is lost at
 *  the flush, counted in tx_lost and logged. (udp_multicast_tx.c) */
co_status_t udp_multicast_send(udp_multicast_t *u, const co_frame_t *frame);
/** Sends the batch, in order, as far as the socket's buffer takes it. */
void udp_multicast_flush(udp_multicast_t *u);
/** Once per pass, after the bus's nodes ran: udp_multicast_flush; then the time to try again, CO_NEVER when all went
 *  or POLLOUT is to tell (udp_multicast_poll_out). */
co_time_us_t udp_multicast_tx_service(udp_multicast_t *u, co_time_us_t now);
/** The batch waits for room in the socket's buffer: poll for POLLOUT. */
static inline bool udp_multicast_poll_out(const udp_multicast_t *u) { return u->tx_blocked && u->tx_count > 0U; }

/** Reads one frame for the nodes: 1 = a frame, 0 = none waiting. Datagrams that are not one are counted (above);
 *  `now` times the summary of malformed ones. */
int udp_multicast_read(udp_multicast_t *u, co_frame_t *frame, co_time_us_t now);

/** True when every datagram read ahead is taken: the next read asks the kernel. */
static inline bool udp_multicast_read_ahead_empty(const udp_multicast_t *u) { return u->rx_next == u->rx_count; }

/** With udp_multicast_read_ahead_empty(): the kernel's queue was empty at the last read. */
static inline bool udp_multicast_read_drained(const udp_multicast_t *u) { return u->rx_drained; }

/** Once per pass of the main loop: sums up the malformed datagrams of the second that ended. Returns when it wants
 *  to run next, or CO_NEVER. */
co_time_us_t udp_multicast_service(udp_multicast_t *u, co_time_us_t now);

/** Logs what is counted and not reported yet (call before exit). */
void udp_multicast_flush_log(udp_multicast_t *u);

#endif
