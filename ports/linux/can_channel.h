/**
 * @file can_channel.h
 * @brief The medium of one bus of canopen-emu, by python-can's interface names (docs/buses.md):
 *
 *   socketcan:IFACE (or IFACE alone)   a SocketCAN interface (socketcan.h)
 *   udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME]
 *                                      python-can's udp_multicast: frames as UDP datagrams to an IP multicast group
 *                                      (udp_multicast.h); no kernel CAN support, no root
 *   virtual:NAME                       no medium: the bus's nodes hear each other (emu_bus.c's local queue) and
 *                                      nothing else; the control protocol sees its frames
 *
 * Each bus has one channel; the main loop polls its descriptor, reads a bounded number of frames per pass and never
 * blocks on it, whatever the kind. The SocketCAN calls stay inline behind one test of the kind: every frame of the
 * common case comes this way (docs/performance.md).
 */
#ifndef CAN_CHANNEL_H
#define CAN_CHANNEL_H

#include <poll.h>
#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"
#include "socketcan.h"
#include "udp_multicast.h"

/** A bus's name: an interface's, a virtual bus's, or udp_multicast:GROUP:PORT. */
#define CAN_CHANNEL_NAME_MAX 80

typedef enum can_channel_kind {
    CAN_CHANNEL_SOCKETCAN,
    CAN_CHANNEL_UDP_MULTICAST,
    CAN_CHANNEL_VIRTUAL
} can_channel_kind_t;

typedef void (*can_channel_log_fn)(void *ctx, const char *line);

/** What one -i (or @BUS of a node) asks for. */
typedef struct can_channel_spec {
    can_channel_kind_t kind;
    bool kind_given;                  /**< KIND: was written; a bare name may name a bus of any kind */
    char name[CAN_CHANNEL_NAME_MAX];
    udp_multicast_config_t udp;       /**< udp_multicast only */
} can_channel_spec_t;

/** Parses KIND:ARGS or a bare interface name (see above). 0, or EINVAL with a message in err. */
int can_channel_parse(const char *text, can_channel_spec_t *spec, char *err, size_t errlen);

/** "socketcan", "udp_multicast", "virtual": python-can's interface names. Inline: the control path's fuzz target
 *  names a bus's kind without linking the channels. */
static inline const char *can_channel_kind_name(can_channel_kind_t kind)
{
    switch (kind) {
    case CAN_CHANNEL_UDP_MULTICAST:
        return "udp_multicast";
    case CAN_CHANNEL_VIRTUAL:
        return "virtual";
    default:
        return "socketcan";
    }
}

typedef struct can_channel {
    can_channel_kind_t kind;
    char name[CAN_CHANNEL_NAME_MAX];
    socketcan_t socketcan;
    udp_multicast_t udp;
    unsigned long virtual_frames;     /**< frames the nodes of a virtual bus sent */
} can_channel_t;

/** Opens the channel. Its problems later (an interface down, datagrams that are not frames, ...) go to log, one line
 *  each. 0, or an errno value with a message for the user in err. */
int can_channel_open(can_channel_t *c, const can_channel_spec_t *spec, can_channel_log_fn log, void *log_ctx,
                     char *err, size_t errlen);

/** What the user should know about the bus once it is open (where a multicast group is joined and that whoever is on
 *  that link is on the bus; that a virtual bus has no medium), in out; false when there is nothing to say. */
bool can_channel_describe(const can_channel_t *c, char *out, size_t len);

/** can_channel_send for the kinds other than SocketCAN. */
co_status_t can_channel_send_other(can_channel_t *c, const co_frame_t *frame);

/** co_port_t.send's work for the bus: CO_OK, CO_ERR_BUSY (the core keeps the frame and retries) or CO_ERR_IO. */
static inline co_status_t can_channel_send(can_channel_t *c, const co_frame_t *frame)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_send(&c->socketcan, frame);
    }
    return can_channel_send_other(c, frame);
}

/** Reads one frame for the nodes: 1 = a frame, 0 = none waiting, -1 = the medium went away (reported, reopened
 *  later). now: the time of the pass (the channels' log rates). See socketcan_read for reading ahead. */
static inline int can_channel_read(can_channel_t *c, co_frame_t *frame, co_time_us_t now)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_read(&c->socketcan, frame);
    }
    return c->kind == CAN_CHANNEL_UDP_MULTICAST ? udp_multicast_read(&c->udp, frame, now) : 0;
}

/** True when every frame read ahead is taken: the next read asks the kernel (socketcan_read_ahead_empty). */
static inline bool can_channel_read_ahead_empty(const can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_read_ahead_empty(&c->socketcan);
    }
    return c->kind != CAN_CHANNEL_UDP_MULTICAST || udp_multicast_read_ahead_empty(&c->udp);
}

/** With can_channel_read_ahead_empty(): the kernel's queue was empty at the last read (socketcan_read_drained). */
static inline bool can_channel_read_drained(const can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_read_drained(&c->socketcan);
    }
    return c->kind != CAN_CHANNEL_UDP_MULTICAST || udp_multicast_read_drained(&c->udp);
}

/** The descriptor to poll: -1 when there is none (a SocketCAN interface gone, a virtual bus): poll ignores it. */
static inline int can_channel_fd(const can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return c->socketcan.fd;
    }
    return c->kind == CAN_CHANNEL_UDP_MULTICAST ? c->udp.rx_fd : -1;
}

/** The events to poll it for (socketcan_poll_events; a datagram socket: POLLIN, a full send buffer is retried at the
 *  core's retry deadline). */
static inline short can_channel_poll_events(const can_channel_t *c, bool tx_pending)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_poll_events(&c->socketcan, tx_pending);
    }
    if (c->kind == CAN_CHANNEL_UDP_MULTICAST && udp_multicast_poll_out(&c->udp)) {
        return POLLIN | POLLOUT; /* the batch waits for room (a node's retried frame comes after it) */
    }
    return POLLIN;
}

/** Once per pass of the main loop, after the bus's nodes ran (socketcan_service; udp_multicast_tx_service, which sends
 *  the pass's frames, and udp_multicast_service): the next time it wants to run. */
static inline co_time_us_t can_channel_service(can_channel_t *c, co_time_us_t now)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return socketcan_service(&c->socketcan, now);
    }
    if (c->kind != CAN_CHANNEL_UDP_MULTICAST) {
        return CO_NEVER;
    }
    const co_time_us_t retry = udp_multicast_tx_service(&c->udp, now);
    const co_time_us_t summary = udp_multicast_service(&c->udp, now);
    return retry < summary ? retry : summary;
}

/** Logs what is counted and not reported yet (call before exit). */
void can_channel_flush_log(can_channel_t *c);

/** Received frames the kernel dropped because the receive buffer was full, all. */
unsigned long can_channel_rx_dropped(const can_channel_t *c);

void can_channel_close(can_channel_t *c);

#endif
