/*
 * The web view of canopen-emu: --web HOST:PORT serves a page (web/, embedded at build time) and an HTTP API that
 * makes control sessions of the browser (docs/web.md). HTTP is libmicrohttpd's, run by the main loop: no thread of
 * its own, its epoll descriptor in the loop's poll, its timeout among the loop's deadlines.
 *
 * The socket is bound as --control-tcp's (emu_tcp.h): loopback unless another address is named, which the caller
 * warns about. Every request must name this server in its Host header (against DNS rebinding), every API request
 * must carry the per-run token the page was served with (against other sites and local programs that did not load
 * the page).
 *
 * A web session is a control session (emu_session.h) whose output waits in a buffer of its own for the browser's
 * next exchange, or goes out on the session's WebSocket (emu_web_socket.h) or stream (emu_web_stream.h) while one
 * is open; commands take exactly the path of the control socket's, but a web session may not stop the
 * emulator or write a file (emu_session_t.restricted). Nothing a browser does blocks the nodes: sockets are
 * non-blocking, an exchange runs at most WEB_EXCHANGE_UNITS of its requests at once and the rest wait for the
 * main loop's budget of all sessions' work (emu_session_work.c), and the limits below bound what any number of
 * browsers can hold.
 */
#ifndef EMU_WEB_H
#define EMU_WEB_H

#include <poll.h>
#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"
#include "runtime/emu_log_limit.h"
#include "control/emu_tcp.h"

struct emu;
struct MHD_Daemon;
struct MHD_Response;
struct web_request;
struct web_session;
struct web_socket;

/** Web sessions at once; one more gets 503. */
#define WEB_SESSIONS_MAX 8
/** A session not exchanged with for this long is removed. */
#define WEB_SESSION_IDLE_US (10U * 1000000U)
/** How long lines wait for a session's stream before it is woken to send them (emu_web_stream.h): the events of a
 *  busy trace go in batches, a few exchanges' worth of libmicrohttpd's work a second, not one write per frame. */
#define WEB_STREAM_BATCH_US 50000U
/** A stream silent for this long sends an empty line (a page gives a stream up after 15 s without a byte). */
#define WEB_STREAM_KEEPALIVE_US (5U * 1000000U)
/** WebSockets at once: one per session, and as many closing. */
#define WEB_SOCKETS_MAX (2U * WEB_SESSIONS_MAX)
/** Bytes of one request's body (request lines); more gets 413. */
#define WEB_BODY_MAX (16U * 1024U)
/** Units of work (request lines, pieces of a streamed answer) an exchange runs at once, so that its answers come
 *  back with it; the rest run within the main loop's budget and come with a later exchange. */
#define WEB_EXCHANGE_UNITS 16U
/** Bytes of answers and events one session may have waiting; more and it is dropped (as CLIENT_OUTPUT_MAX). */
#define WEB_OUTPUT_MAX (1024U * 1024U)
/** HTTP connections at once, and from one address (a WebSocket counts: a browser holds up to 6 HTTP connections to
 *  a host and one WebSocket per page, and a reloaded page's old socket may still be closing). */
#define WEB_CONNECTIONS_MAX 24U
#define WEB_CONNECTIONS_PER_ADDRESS 12U
/** Seconds an idle HTTP connection stays open. */
#define WEB_CONNECTION_TIMEOUT_S 30U
/** Memory of one HTTP connection (request line, headers, the body as it arrives, the answer's headers):
 *  libmicrohttpd zeroes all of it for every request, the largest part of an idle exchange's cost. 8 KiB hold a
 *  browser's headers (about 700 bytes) and about 2 KiB of cookies; more gets 431 (docs/decisions.md, "The idle
 *  web exchange"). */
#define WEB_CONNECTION_MEMORY (8U * 1024U)
/** Hex digits of a session id and of the token (128 random bits each). */
#define WEB_ID_HEX 32

typedef struct emu_web {
    struct MHD_Daemon *daemon;      /* NULL: no --web */
    int epoll_fd;                   /* libmicrohttpd's: readable when it has work */
    bool run_again;                 /* a stream ended outside libmicrohttpd's run: it must run to end its answer */
    co_time_us_t run_at;            /* when libmicrohttpd asked to run at the latest, without a wake-up of its
                                     * descriptor (a connection's timeout; now: work it holds); CO_NEVER: none */
    tcp_listener_t listener;        /* what was bound (fd owned by libmicrohttpd once it runs) */
    char token[WEB_ID_HEX + 1];
    char *index_html;               /* web/index.html with the token in it */
    size_t index_len;
    struct MHD_Response *empty_exchange; /* the answer of an exchange with nothing to give, made once */
    struct web_request *spare_requests[WEB_CONNECTIONS_MAX]; /* API requests' states ended, kept for the next */
    size_t n_spare_requests;
    struct web_socket *sockets[WEB_SOCKETS_MAX]; /* the sessions' WebSockets and those closing (emu_web_socket.h) */
    size_t n_sockets;
    struct web_session *sessions[WEB_SESSIONS_MAX];
    size_t n_sessions;
    unsigned long next_number;      /* sessions are numbered from 1 in the log */
    struct emu *emu;                /* for libmicrohttpd's callbacks */
    log_limit_t refusals;           /* "a session refused" lines, rate-limited */
    log_limit_t server_log;         /* libmicrohttpd's own lines (a client's bad requests), rate-limited */
} emu_web_t;

void web_init(emu_web_t *w);

/** Binds host_port and starts serving. 0, or an errno with a message in err; w->listener says what was bound
 *  (name, remote). */
int web_start(struct emu *emu, emu_web_t *w, const char *host_port, char *err, size_t errlen);

/** Adds libmicrohttpd's descriptor and the WebSockets' to pfd (0 .. 1 + WEB_SOCKETS_MAX entries, returned) and brings *next forward to the web's next
 *  deadline: libmicrohttpd's timeout, a session's expiry, now when requests of a session wait to run. */
nfds_t web_poll_fds(emu_web_t *w, struct pollfd *pfd, co_time_us_t now, co_time_us_t *next);

/** After poll: lets libmicrohttpd serve (when its descriptor woke or it asked to run; an exchange runs some of its
 *  session's requests), removes expired and overflowing sessions. pfd, n as web_poll_fds gave. */
void web_service(struct emu *emu, emu_web_t *w, const struct pollfd *pfd, nfds_t n, co_time_us_t now);

/** Ends every session and connection, closes the socket (nothing waits: a browser asks again). */
void web_stop(struct emu *emu, emu_web_t *w);

#endif /* EMU_WEB_H */
