/*
 * --socketcand HOST:PORT: every bus of canopen-emu served as a channel of its name in linux-can socketcand's protocol
 * (socketcand_proto.h has the commands; docs/buses.md), so that python-can's socketcand interface, and a
 * python-canopen master on it, reach the emulated nodes over TCP with nothing installed and no kernel CAN support.
 *
 * A client greeted with "< hi >" opens a channel, switches to rawmode and sends frames: a frame it sends reaches the
 * bus's nodes, the other clients in rawmode on that channel and the bus's medium (the SocketCAN interface, the
 * multicast group; nothing for a virtual bus); every frame of the bus (its nodes', its medium's, other clients')
 * goes to each client in rawmode on it. A client does not get its own frames back (as SocketCAN's raw sockets).
 *
 * Bound as --control-tcp (emu_tcp.h): loopback unless another address is named, which is warned about, since whoever
 * reaches the port is on the bus. Nothing a client does can hold the nodes (docs/robustness.md):
 *  - sockets are non-blocking; at most SOCKETCAND_READ_MAX bytes of a client are read at a time, and more only once
 *    they are used up: what it sends meanwhile waits in the kernel;
 *  - the commands of all clients of one pass are at most SOCKETCAND_PASS_COMMANDS and stop at the nodes' earliest
 *    deadline (the first always runs); the rest run in the next pass, taken by turns;
 *  - a client that lets more than SOCKETCAND_OUTPUT_MAX bytes pile up unread is cut off (logged);
 *  - a malformed or unknown command is answered "< error WHY >" (as socketcand does); SOCKETCAND_ERRORS_MAX of them
 *    in a row close the connection; a command that names a channel that does not exist gets socketcand's
 *    "< error could not open bus >" and the connection is closed;
 *  - a connection whose first byte other than white space is not '<' (a browser's request: any web page may send a
 *    cross-origin POST to a local port) is closed with nothing of it done;
 *  - at most SOCKETCAND_CLIENTS_MAX clients: the next one is told "< error too many clients >" and closed;
 *  - CAN FD frames are not carried: counted, logged once, not answered (python-can would take an error line for an
 *    error frame it cannot read).
 * Refusals and cut-offs are logged at a bounded rate (emu_log_limit.h).
 *
 * python-can's client reads "< ok >" of rawmode with one recv() and fails if a frame came in the same read: frames
 * for a client wait SOCKETCAND_RAWMODE_HOLD_US after that "< ok >" left, then go (none is lost).
 */
#ifndef EMU_SOCKETCAND_H
#define EMU_SOCKETCAND_H

#include <poll.h>
#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"
#include "control/emu_buffer.h"
#include "runtime/emu_log_limit.h"
#include "control/emu_tcp.h"
#include "socketcand/socketcand_proto.h"

struct emu;
struct emu_bus;

#define SOCKETCAND_CLIENTS_MAX 16
#define SOCKETCAND_OUTPUT_MAX (256U * 1024U)
#define SOCKETCAND_READ_MAX 4096U
#define SOCKETCAND_PASS_COMMANDS 256U
#define SOCKETCAND_ERRORS_MAX 16U
#define SOCKETCAND_RAWMODE_HOLD_US 100000U
/** A client closed by the server (bad channel, too many errors) gets this long to take its last answer. */
#define SOCKETCAND_LINGER_US 1000000U

typedef enum socketcand_mode {
    SOCKETCAND_MODE_NO_BUS,   /* greeted, no channel open */
    SOCKETCAND_MODE_BCM,      /* a channel open: sends, takes no frames (the BCM's subscriptions are not served) */
    SOCKETCAND_MODE_RAW       /* takes every frame of its channel */
} socketcand_mode_t;

typedef struct socketcand_client {
    int fd;
    char name[80];              /* "client 3 (127.0.0.1:40112)" */
    socketcand_reader_t reader;
    char in[SOCKETCAND_READ_MAX];
    size_t in_len;              /* bytes read */
    size_t in_pos;              /* of which used */
    byte_buffer_t out;          /* bytes waiting for the client */
    struct emu_bus *bus;        /* the channel opened; NULL before */
    socketcand_mode_t mode;
    co_time_us_t hold_until;    /* its frames wait until then (rawmode's "< ok >" goes alone) */
    unsigned errors_in_a_row;
    bool overflow;              /* more than SOCKETCAND_OUTPUT_MAX waited: cut off */
    bool gone;                  /* the peer vanished, or it is closed at once (a foreign connection) */
    bool eof;                   /* the peer sent all it will: closed once its input is used */
    co_time_us_t closing_at;    /* non-zero: closed once its answers left, or at this time */
    const char *why;            /* why the server closed it (logged) */
} socketcand_client_t;

typedef struct emu_socketcand {
    tcp_listener_t listener;    /* fd -1: no --socketcand */
    socketcand_client_t *clients[SOCKETCAND_CLIENTS_MAX];
    size_t n_clients;
    size_t turn;                /* the client the next pass's commands begin with */
    unsigned long next_number;
    int64_t wall_offset_us;     /* CLOCK_REALTIME - CLOCK_MONOTONIC: frames' times as socketcand gives them */
    unsigned long fd_frames;    /* CAN FD frames of clients, not carried */
    unsigned long medium_refused; /* clients' frames the bus's medium did not take (reached the nodes all the same) */
    log_limit_t refusals;       /* refused, closed and cut-off clients */
    log_limit_t troubles;       /* frames not carried */
} emu_socketcand_t;

void socketcand_init(emu_socketcand_t *s);

/** Listens on host_port (emu_tcp.h). 0, or an errno with a message in err; s->listener says what was bound. */
int socketcand_start(emu_socketcand_t *s, const char *host_port, char *err, size_t errlen);

static inline bool socketcand_active(const emu_socketcand_t *s)
{
    return s->listener.fd >= 0;
}

/** Writes what waits for the clients, closes those that ended, and adds the listener and the clients to pfd (at most
 *  max entries; returns how many). *next is brought forward to the end of a hold with frames waiting. */
nfds_t socketcand_poll_fds(struct emu *emu, emu_socketcand_t *s, struct pollfd *pfd, nfds_t max, co_time_us_t now,
                           co_time_us_t *next);

/** After poll: accepts, reads, and runs the clients' commands within the pass's bounds, stopping at due (the nodes'
 *  earliest deadline) after the first. pfd, n as socketcand_poll_fds gave (n 0: no poll since). Returns true when
 *  commands wait for the next pass (the loop then does not sleep). */
bool socketcand_service(struct emu *emu, emu_socketcand_t *s, const struct pollfd *pfd, nfds_t n, co_time_us_t due);

/** A frame of bus b at time at (monotonic) for the clients in rawmode on it, but except. Called where
 *  b->socketcand_readers is non-zero only. */
void socketcand_publish(emu_socketcand_t *s, const struct emu_bus *b, const co_frame_t *f, co_time_us_t at,
                        const socketcand_client_t *except);

/** Closes everything (what waits for the clients is not waited for); logs the frames not carried. */
void socketcand_stop(struct emu *emu, emu_socketcand_t *s);

#endif /* EMU_SOCKETCAND_H */
