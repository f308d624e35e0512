/* A web session's WebSocket: see emu_web_socket.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web_socket.h"

#include <errno.h>
#include <fcntl.h>
#include <nettle/base64.h>
#include <nettle/sha1.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <wslay/wslay.h>

#include "control/emu_buffer.h"
#include "runtime/emu.h"
#include "web/emu_web_http.h"
#include "web/emu_web_sessions.h"
#include "web/emu_web_stream.h"

#define SUBPROTOCOL_PREFIX "canopen-emu."
/* RFC 6455 4.2.2: the key's answer is SHA-1 of the key and this, in base64. */
#define HANDSHAKE_GUID "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"
/* A key is 16 random bytes in base64 (RFC 6455 4.1): 24 characters. */
#define KEY_LEN 24U

struct web_socket {
    web_session_t *session;
    emu_web_t *web;
    int fd;
    struct MHD_UpgradeResponseHandle *urh;
    wslay_event_context_ptr ctx;
    char *early;                /* bytes libmicrohttpd read past the handshake: read before the socket */
    size_t early_len, early_pos;
    byte_buffer_t held;         /* request lines of messages that did not fit beside what waits in the session */
    size_t read_room;           /* bytes the reading may still take in this pass */
    co_time_us_t now;           /* of the pass reading (the time its requests run at) */
    co_time_us_t linger_until;  /* closing: its close frame sent and FIN too, what comes is read and dropped until
                                 * the page closes or this time (a close with unread bytes would be a reset that
                                 * can lose the close frame); 0: open */
};

/* ---- The handshake ---------------------------------------------------------------------------------------------- */

/* Whether a comma-separated header value has this token (case-insensitive, as Connection and Upgrade are). */
static bool has_token(const char *value, const char *token)
{
    const size_t n = strlen(token);
    for (const char *p = value; p != NULL && *p != '\0'; p = strchr(p, ',') != NULL ? strchr(p, ',') + 1 : NULL) {
        p += strspn(p, " \t");
        if (strncasecmp(p, token, n) == 0 && (p[n] == '\0' || p[n] == ',' || p[n] == ' ' || p[n] == '\t')) {
            return true;
        }
    }
    return false;
}

const char *web_socket_check(const emu_web_t *w, struct MHD_Connection *c, const char *host, bool *forbidden)
{
    *forbidden = false;
    const char *upgrade = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_UPGRADE);
    const char *connection = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONNECTION);
    const char *version = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Version");
    const char *key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Key");
    if (upgrade == NULL || !has_token(upgrade, "websocket") || connection == NULL ||
        !has_token(connection, "Upgrade")) {
        return "the socket is a WebSocket: Upgrade: websocket and Connection: Upgrade";
    }
    if (version == NULL || strcmp(version, "13") != 0) {
        return "WebSocket version 13 only (Sec-WebSocket-Version: 13)";
    }
    if (key == NULL || strlen(key) != KEY_LEN) {
        return "no Sec-WebSocket-Key of 24 characters";
    }
    /* A WebSocket is not under the browser's same-origin rules: a page of another site may open one. Only this
     * server's own page may: its Origin names the host its Host header names (checked by the caller). */
    const char *origin = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Origin");
    *forbidden = true;
    if (origin == NULL || strncmp(origin, "http://", 7U) != 0 || host == NULL || strcmp(origin + 7, host) != 0) {
        return "the Origin is not this server's page";
    }
    const char *protocol = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Protocol");
    if (protocol == NULL || strncmp(protocol, SUBPROTOCOL_PREFIX, sizeof SUBPROTOCOL_PREFIX - 1U) != 0 ||
        !web_token_ok(w, protocol + sizeof SUBPROTOCOL_PREFIX - 1U)) {
        return "missing or wrong token: the subprotocol is canopen-emu.TOKEN (load the page again)";
    }
    *forbidden = false;
    return NULL;
}

/* ---- The socket's I/O, libwslay's callbacks ----------------------------------------------------------------- */

static ssize_t on_recv(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, int flags, void *user)
{
    web_socket_t *ws = (web_socket_t *)user;
    (void)flags;
    if (ws->early_pos < ws->early_len) {
        const size_t n = len < ws->early_len - ws->early_pos ? len : ws->early_len - ws->early_pos;
        memcpy(buf, ws->early + ws->early_pos, n);
        ws->early_pos += n;
        return (ssize_t)n;
    }
    if (ws->read_room == 0U || ws->held.len > 0U) {
        wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK); /* this pass's share is read, or a message waits */
        return -1;
    }
    const ssize_t r = recv(ws->fd, buf, len < ws->read_room ? len : ws->read_room, 0);
    if (r > 0) {
        ws->read_room -= (size_t)r;
        return r;
    }
    wslay_event_set_error(ctx, r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)
                                   ? WSLAY_ERR_WOULDBLOCK : WSLAY_ERR_CALLBACK_FAILURE);
    return -1; /* 0: the page closed the connection */
}

static ssize_t on_send(wslay_event_context_ptr ctx, const uint8_t *data, size_t len, int flags, void *user)
{
    web_socket_t *ws = (web_socket_t *)user;
    const ssize_t r = send(ws->fd, data, len, MSG_NOSIGNAL | ((flags & WSLAY_MSG_MORE) != 0 ? MSG_MORE : 0));
    if (r >= 0) {
        return r;
    }
    wslay_event_set_error(ctx, errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR ? WSLAY_ERR_WOULDBLOCK
                                                                                          : WSLAY_ERR_CALLBACK_FAILURE);
    return -1;
}

/* Request lines queued for the session, or held (the socket then not read) until they fit beside what waits. */
static void take_lines(web_socket_t *ws, const char *lines, size_t len)
{
    web_session_t *s = ws->session;
    if (ws->held.len == 0U && web_session_queue(ws->web->emu, s, lines, len, ws->now)) {
        s->send_now = s->send_now || len > 0U; /* their answers go at once */
        return;
    }
    const bool end_line = len > 0U && lines[len - 1U] != '\n'; /* a line never spans two messages */
    if (!byte_buffer_append(&ws->held, lines, len, 2U * WEB_BODY_MAX) ||
        (end_line && !byte_buffer_append(&ws->held, "\n", 1U, 2U * WEB_BODY_MAX))) {
        (void)wslay_event_queue_close(ws->ctx, WSLAY_CODE_POLICY_VIOLATION, NULL, 0U); /* a page that floods */
    }
}

/* As many whole held lines as the session has room for now are queued (held ends with a newline; a line is at most
 * a message, 16 KiB, which is the session's room when nothing waits). */
static void run_held(web_socket_t *ws)
{
    web_session_t *s = ws->session;
    const size_t room = session_input_room(&s->session);
    size_t n = ws->held.len < room ? ws->held.len : room;
    while (n > 0U && ws->held.data[n - 1U] != '\n') {
        n--;
    }
    if (n > 0U && web_session_queue(ws->web->emu, s, ws->held.data, n, ws->now)) {
        byte_buffer_consume(&ws->held, n);
        s->send_now = true;
    }
}

static void on_message(wslay_event_context_ptr ctx, const struct wslay_event_on_msg_recv_arg *arg, void *user)
{
    web_socket_t *ws = (web_socket_t *)user;
    if (arg->opcode == WSLAY_TEXT_FRAME && ws->session != NULL) {
        take_lines(ws, (const char *)arg->msg, arg->msg_length);
    } else if (arg->opcode == WSLAY_BINARY_FRAME) {
        (void)wslay_event_queue_close(ctx, WSLAY_CODE_UNSUPPORTED_DATA, NULL, 0U); /* request lines are text */
    }
}

/* ---- Open, flush, close ------------------------------------------------------------------------------------------ */

static void socket_close(web_socket_t *ws)
{
    emu_web_t *w = ws->web;
    if (ws->session != NULL) {
        ws->session->socket = NULL;
    }
    for (size_t i = 0U; i < w->n_sockets; i++) {
        if (w->sockets[i] == ws) {
            w->sockets[i] = w->sockets[--w->n_sockets];
            break;
        }
    }
    wslay_event_context_free(ws->ctx);
    (void)MHD_upgrade_action(ws->urh, MHD_UPGRADE_ACTION_CLOSE); /* libmicrohttpd closes it at its next run */
    w->run_again = true;
    byte_buffer_free(&ws->held);
    free(ws->early);
    free(ws);
}

/* The close frame is sent: FIN after it, then what the page still sends is read and dropped until it closes too
 * (or WEB_SOCKET_LINGER_US). A close frame not sent (the page does not read): closed at once. */
static void socket_linger(web_socket_t *ws, co_time_us_t now)
{
    if (ws->session != NULL) {
        ws->session->socket = NULL;
        ws->session = NULL;
    }
    if (wslay_event_want_write(ws->ctx) || shutdown(ws->fd, SHUT_WR) != 0) {
        socket_close(ws);
        return;
    }
    ws->linger_until = now + WEB_SOCKET_LINGER_US;
}

/* A closing socket's pass: what came is dropped; the page's close (or the time) ends it. */
static void linger_pass(web_socket_t *ws, short revents, co_time_us_t now)
{
    char sink[4096];
    ssize_t r = 1;
    for (size_t taken = 0U; (revents & (POLLIN | POLLHUP | POLLERR)) != 0 && taken < WEB_SOCKET_READ_PASS &&
                            (r = recv(ws->fd, sink, sizeof sink, 0)) > 0;
         taken += (size_t)r) {
    }
    if (r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) || now >= ws->linger_until) {
        socket_close(ws);
    }
}

/* libmicrohttpd sent the 101 answer: the socket is ours. state is the request's (its session id). */
static void on_upgraded(void *cls, struct MHD_Connection *c, void *state, const char *extra_in, size_t extra_len,
                        MHD_socket sock, struct MHD_UpgradeResponseHandle *urh)
{
    emu_web_t *w = (emu_web_t *)cls;
    (void)c;
    web_session_t *s = web_session_find(w, web_request_id(state));
    web_socket_t *ws = calloc(1U, sizeof *ws);
    static const struct wslay_event_callbacks callbacks = {on_recv, on_send, NULL, NULL, NULL, NULL, on_message};
    if (ws == NULL || s == NULL || w->n_sockets == WEB_SOCKETS_MAX ||
        wslay_event_context_server_init(&ws->ctx, &callbacks, ws) != 0) {
        free(ws);
        (void)MHD_upgrade_action(urh, MHD_UPGRADE_ACTION_CLOSE); /* its session ended meanwhile, or no memory */
        w->run_again = true;
        return;
    }
    wslay_event_config_set_max_recv_msg_length(ws->ctx, WEB_BODY_MAX); /* more: closed with 1009 */
    ws->web = w;
    ws->fd = sock;
    ws->urh = urh;
    ws->now = socketcan_now_us();
    if (extra_len > 0U && (ws->early = malloc(extra_len)) != NULL) {
        memcpy(ws->early, extra_in, extra_len);
        ws->early_len = extra_len;
    }
    (void)fcntl(sock, F_SETFL, fcntl(sock, F_GETFL) | O_NONBLOCK);
    if (s->socket != NULL) {
        web_socket_end(s->socket); /* a second socket of the session: the first ends */
    }
    if (s->stream != NULL && web_stream_end(s->stream)) {
        w->run_again = true; /* one way out at a time: the lines go on the socket now */
    }
    ws->session = s;
    s->socket = ws;
    s->keepalive = false;
    s->send_now = s->out.len > 0U;
    w->sockets[w->n_sockets++] = ws;
}

struct MHD_Response *web_socket_answer(emu_web_t *w, struct MHD_Connection *c)
{
    const char *key = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Key");
    const char *protocol = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Sec-WebSocket-Protocol");
    uint8_t digest[SHA1_DIGEST_SIZE];
    struct sha1_ctx sha;
    sha1_init(&sha);
    sha1_update(&sha, KEY_LEN, (const uint8_t *)key);
    sha1_update(&sha, sizeof HANDSHAKE_GUID - 1U, (const uint8_t *)HANDSHAKE_GUID);
    sha1_digest(&sha, sizeof digest, digest);
    char accept[BASE64_ENCODE_RAW_LENGTH(SHA1_DIGEST_SIZE) + 1];
    base64_encode_raw(accept, sizeof digest, digest);
    accept[sizeof accept - 1U] = '\0';
    struct MHD_Response *r = MHD_create_response_for_upgrade(on_upgraded, w);
    if (r != NULL && (MHD_add_response_header(r, MHD_HTTP_HEADER_UPGRADE, "websocket") != MHD_YES ||
                      MHD_add_response_header(r, "Sec-WebSocket-Accept", accept) != MHD_YES ||
                      MHD_add_response_header(r, "Sec-WebSocket-Protocol", protocol) != MHD_YES)) {
        MHD_destroy_response(r);
        r = NULL;
    }
    return r;
}

void web_socket_flush(web_socket_t *ws, bool keepalive)
{
    if (wslay_event_get_queued_msg_count(ws->ctx) > 0U) {
        return; /* the last message is still going out: the lines wait in the session */
    }
    size_t len = 0U;
    char *lines = web_session_take_output(ws->session, &len);
    if (lines == NULL && !keepalive) {
        return;
    }
    const struct wslay_event_msg msg = {WSLAY_TEXT_FRAME, (const uint8_t *)(lines != NULL ? lines : "\n"),
                                        lines != NULL ? len : 1U};
    (void)wslay_event_queue_msg(ws->ctx, &msg); /* copied; failing (closing, no memory): the socket ends */
    free(lines);
    (void)wslay_event_send(ws->ctx); /* what the socket takes now; the rest when it is writable */
}

void web_socket_end(web_socket_t *ws)
{
    if (wslay_event_queue_close(ws->ctx, WSLAY_CODE_GOING_AWAY, NULL, 0U) == 0) {
        (void)wslay_event_send(ws->ctx); /* as far as the socket takes it now: nothing waits for the page */
    }
    socket_linger(ws, socketcan_now_us());
}

/* ---- The main loop ------------------------------------------------------------------------------------------------ */

nfds_t web_sockets_poll_fds(emu_web_t *w, struct pollfd *pfd)
{
    for (size_t i = 0U; i < w->n_sockets; i++) {
        const web_socket_t *ws = w->sockets[i];
        pfd[i].fd = ws->fd;
        pfd[i].events = ws->linger_until != 0 ? POLLIN
                                               : (short)((wslay_event_want_read(ws->ctx) && ws->held.len == 0U
                                                              ? POLLIN : 0) |
                                                         (wslay_event_want_write(ws->ctx) ? POLLOUT : 0));
        pfd[i].revents = 0;
    }
    return (nfds_t)w->n_sockets;
}

void web_sockets_service(emu_web_t *w, const struct pollfd *pfd, nfds_t n, co_time_us_t now)
{
    for (size_t i = w->n_sockets; i > 0U; i--) {
        web_socket_t *ws = w->sockets[i - 1U];
        short revents = 0;
        for (nfds_t k = 0U; k < n; k++) {
            revents = pfd[k].fd == ws->fd ? pfd[k].revents : revents;
        }
        if (ws->linger_until != 0) {
            linger_pass(ws, revents, now);
            continue;
        }
        ws->now = now;
        if (ws->held.len > 0U && ws->session != NULL) { /* held lines first: they came before what is unread */
            run_held(ws);
        }
        ws->read_room = WEB_SOCKET_READ_PASS;
        const bool failed = ((revents & (POLLIN | POLLHUP | POLLERR)) != 0 && wslay_event_recv(ws->ctx) != 0) ||
                            (wslay_event_want_write(ws->ctx) && wslay_event_send(ws->ctx) != 0);
        if (failed) {
            socket_close(ws); /* the page went away */
        } else if (!wslay_event_want_read(ws->ctx) && !wslay_event_want_write(ws->ctx)) {
            socket_linger(ws, now); /* the closing handshake is done, or a close for a message out of bounds sent */
        }
    }
}

void web_sockets_close_all(emu_web_t *w)
{
    while (w->n_sockets > 0U) {
        socket_close(w->sockets[w->n_sockets - 1U]);
    }
}

co_time_us_t web_sockets_deadline(const emu_web_t *w, co_time_us_t now)
{
    co_time_us_t next = CO_NEVER;
    for (size_t i = 0U; i < w->n_sockets; i++) {
        const web_socket_t *ws = w->sockets[i];
        const co_time_us_t due = ws->linger_until != 0 ? ws->linger_until
                                 : ws->held.len > 0U ? now + WEB_HELD_RETRY_US : CO_NEVER;
        next = due < next ? due : next;
    }
    return next;
}
