/*
 * A web session's WebSocket (GET /api/session/ID/socket, docs/web.md): the page's request lines come as text
 * messages (each as an exchange's body) and the session's lines go out as text messages, so that a request costs no
 * HTTP exchange (about 20,000 instructions of libmicrohttpd's each: docs/decisions.md "The idle web exchange").
 *
 * libmicrohttpd reads the handshake (checked here: Origin, version, key, the token as the subprotocol) and hands the
 * socket over after its 101 answer; the frames are libwslay's; the main loop polls the socket (web_poll_fds).
 * Work per pass is bounded (WEB_SOCKET_READ_PASS bytes read); a message whose lines do not fit beside what still
 * waits in the session is held, and the socket not read, until they fit (backpressure, nothing dropped). The
 * session's lines go out as the stream's do (emu_web_stream.h): when they have waited WEB_STREAM_BATCH_US, at once
 * after a message that ran requests, an empty message after WEB_STREAM_KEEPALIVE_US of silence; while a message is
 * still being sent, the lines wait in the session (its 1 MiB bound drops a page that does not read).
 */
#ifndef EMU_WEB_SOCKET_H
#define EMU_WEB_SOCKET_H

#include <poll.h>
#include <stdbool.h>

#include "co/co.h"
#include "web/emu_web.h"

struct MHD_Connection;
struct MHD_Response;
struct web_session;

/** Bytes one socket's reading takes in one pass of the main loop at most (a flood waits for the next passes). */
#define WEB_SOCKET_READ_PASS (16U * 1024U)
/** How long a closing socket waits for the page to close its side (what comes meanwhile is dropped). */
#define WEB_SOCKET_LINGER_US (2U * 1000000U)
/** How soon a message that did not fit beside what waits in its session is tried again. */
#define WEB_HELD_RETRY_US 10000U

typedef struct web_socket web_socket_t;

/** Whether the request on c is a WebSocket handshake this server takes (GET checked by the caller): Upgrade
 *  websocket, Sec-WebSocket-Version 13, a key, an Origin that names this server as the Host header does, the
 *  subprotocol "canopen-emu.TOKEN". NULL when it is; else what is wrong, for the 400 or 403 answer (*forbidden:
 *  the Origin or the token). */
const char *web_socket_check(const emu_web_t *w, struct MHD_Connection *c, const char *host, bool *forbidden);

/** The 101 answer that hands c's socket over to a WebSocket of the session whose id is the request's (state: the
 *  request's state, given back to the upgrade). NULL: out of memory. The caller queues it and releases it. */
struct MHD_Response *web_socket_answer(emu_web_t *w, struct MHD_Connection *c);

/** The session's lines as one message (and, keepalive, an empty one when none wait); nothing while the last one
 *  is still being sent. */
void web_socket_flush(web_socket_t *ws, bool keepalive);

/** Its session ends: a close frame is sent if the socket takes it, and the socket closed. */
void web_socket_end(web_socket_t *ws);

/** Adds the sockets to pfd (returns how many; at most WEB_SOCKETS_MAX): POLLIN while they may read, POLLOUT while
 *  a message waits to be sent. */
nfds_t web_sockets_poll_fds(emu_web_t *w, struct pollfd *pfd);

/** After poll: reads and sends as the sockets woke, runs held messages that now fit, closes the sockets that ended
 *  (pfd, n as web_sockets_poll_fds gave; a closed socket's connection sets w->run_again). */
void web_sockets_service(emu_web_t *w, const struct pollfd *pfd, nfds_t n, co_time_us_t now);

/** Closes every socket at once, those still closing too (the program ends). */
void web_sockets_close_all(emu_web_t *w);

/** The sockets' next deadline: a closing one's end, soon when one holds request lines that did not fit yet;
 *  CO_NEVER: none. */
co_time_us_t web_sockets_deadline(const emu_web_t *w, co_time_us_t now);

#endif /* EMU_WEB_SOCKET_H */
