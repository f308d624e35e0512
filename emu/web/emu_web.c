/* The web view: libmicrohttpd run by the main loop, the routes and the API (see emu_web.h and docs/web.md). The
 * checks and answers of every request: emu_web_checks.c, emu_web_answers.c; the sessions: emu_web_sessions.c. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runtime/emu.h"
#include "runtime/emu_output.h"
#include "web/emu_web_files.h"
#include "web/emu_web_http.h"
#include "web/emu_web_sessions.h"
#include "web/emu_web_socket.h"
#include "web/emu_web_stream.h"

/* In web/index.html, where the token goes. */
#define TOKEN_PLACEHOLDER "@CANOPEN_EMU_TOKEN@"
#define API_SESSION "/api/session"
#define STREAM_SUFFIX "/stream"
#define SOCKET_SUFFIX "/socket"

typedef enum api_route { ROUTE_OPEN, ROUTE_EXCHANGE, ROUTE_STREAM, ROUTE_SOCKET } api_route_t;

/* An API request whose body is arriving (libmicrohttpd hands it over in pieces). */
typedef struct web_request {
    api_route_t route;
    char id[WEB_ID_HEX + 1];
    size_t len;
    bool too_large;             /* more than WEB_BODY_MAX came (a chunked body): the rest is discarded, then 413 */
    char body[WEB_BODY_MAX];
} web_request_t;

const char *web_request_id(const void *state) { return ((const web_request_t *)state)->id; }

/* ---- The API -------------------------------------------------------------------------------------------------- */

/* POST /api/session: a new session, its id in {"session":"ID"}. */
static enum MHD_Result open_session(emu_web_t *w, struct MHD_Connection *c, co_time_us_t now)
{
    bool full = false;
    web_session_t *s = web_session_open(w->emu, w, now, &full);
    if (s == NULL) {
        if (full) {
            log_limited(&w->refusals, now, "web: a session refused: %d are open already", WEB_SESSIONS_MAX);
        }
        return web_send_error(c, MHD_HTTP_SERVICE_UNAVAILABLE, true,
                              full ? "too many web sessions (at most 8)" : "cannot open a session", NULL);
    }
    char body[64];
    (void)snprintf(body, sizeof body, "{\"session\":\"%s\"}\n", s->id);
    struct MHD_Response *r = MHD_create_response_from_buffer(strlen(body), body, MHD_RESPMEM_MUST_COPY);
    if (r != NULL) {
        (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "application/json");
    }
    return web_send(c, MHD_HTTP_OK, r, true);
}

/* POST /api/session/ID: the body's request lines run as the session's (some maybe later: WEB_EXCHANGE_UNITS), then
 * everything that waits for the session comes back, one line each. */
static enum MHD_Result exchange(emu_web_t *w, struct MHD_Connection *c, const web_request_t *q, co_time_us_t now)
{
    web_session_t *s = web_session_find(w, q->id);
    if (s == NULL || s->overflow || s->session.overflow) { /* an overflowing one is removed, and logged, at the end of this pass */
        return web_send_error(c, MHD_HTTP_NOT_FOUND, true, "no such session (expired or dropped): open a new one",
                              NULL);
    }
    if (!web_session_queue(w->emu, s, q->body, q->len, now)) {
        return web_send_error(c, MHD_HTTP_TOO_MANY_REQUESTS, true,
                              "earlier requests of this session still wait to run: exchange with an empty body first",
                              NULL);
    }
    if (s->stream != NULL) { /* everything goes on the stream, in order: the answers at the end of this pass */
        s->send_now = s->send_now || q->len > 0U;
        return MHD_queue_response(c, MHD_HTTP_OK, w->empty_exchange);
    }
    size_t len = 0U;
    char *out = web_session_take_output(s, &len);
    if (out == NULL) { /* what an idle page gets four times a second: the answer made once, with its headers */
        return MHD_queue_response(c, MHD_HTTP_OK, w->empty_exchange);
    }
    struct MHD_Response *r = MHD_create_response_from_buffer(len, out, MHD_RESPMEM_MUST_FREE);
    if (r == NULL) {
        free(out);
        return MHD_NO;
    }
    (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "application/x-ndjson");
    return web_send(c, MHD_HTTP_OK, r, true);
}

/* POST /api/session/ID/stream: the session's lines from now on, as they come (emu_web_stream.h). */
static enum MHD_Result open_stream(emu_web_t *w, struct MHD_Connection *c, const web_request_t *q)
{
    web_session_t *s = web_session_find(w, q->id);
    if (s == NULL || s->overflow || s->session.overflow) {
        return web_send_error(c, MHD_HTTP_NOT_FOUND, true, "no such session (expired or dropped): open a new one",
                              NULL);
    }
    struct MHD_Response *r = web_stream_open(s, c);
    if (r == NULL) {
        return MHD_NO;
    }
    const enum MHD_Result result = MHD_queue_response(c, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return result;
}

/* GET /api/session/ID/socket, its handshake checked: the session's WebSocket (emu_web_socket.h). */
static enum MHD_Result open_socket(emu_web_t *w, struct MHD_Connection *c, const web_request_t *q)
{
    if (web_session_find(w, q->id) == NULL) {
        return web_send_error(c, MHD_HTTP_NOT_FOUND, true, "no such session (expired or dropped): open a new one",
                              NULL);
    }
    struct MHD_Response *r = web_socket_answer(w, c);
    if (r == NULL) {
        return MHD_NO;
    }
    const enum MHD_Result result = MHD_queue_response(c, MHD_HTTP_SWITCHING_PROTOCOLS, r);
    MHD_destroy_response(r);
    return result;
}

/* The answer of an exchange with nothing to give (no body, every API header), made once by web_start. */
static struct MHD_Response *make_empty_exchange(void)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(0U, (void *)"", MHD_RESPMEM_PERSISTENT);
    if (r != NULL && (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "application/x-ndjson") != MHD_YES ||
                      !web_add_headers(r, true))) {
        MHD_destroy_response(r);
        r = NULL;
    }
    return r;
}

/* /api/session, /api/session/ID or /api/session/ID/stream (ID: 32 lowercase hex digits); false for any other
 * path. */
static bool api_route(const char *path, api_route_t *route, char *id)
{
    if (strcmp(path, API_SESSION) == 0) {
        *route = ROUTE_OPEN;
        return true;
    }
    const size_t prefix = sizeof API_SESSION; /* "/api/session/" */
    if (strncmp(path, API_SESSION "/", prefix) != 0 || strspn(path + prefix, "0123456789abcdef") != WEB_ID_HEX) {
        return false;
    }
    const char *rest = path + prefix + WEB_ID_HEX;
    if (*rest == '\0') {
        *route = ROUTE_EXCHANGE;
    } else if (strcmp(rest, STREAM_SUFFIX) == 0) {
        *route = ROUTE_STREAM;
    } else if (strcmp(rest, SOCKET_SUFFIX) == 0) {
        *route = ROUTE_SOCKET;
    } else {
        return false;
    }
    memcpy(id, path + prefix, WEB_ID_HEX);
    id[WEB_ID_HEX] = '\0';
    return true;
}

/* ---- libmicrohttpd's callbacks -------------------------------------------------------------------------------- */

/* The first call of a request, its headers read: everything is checked that can be. A refusal is answered now (the
 * connection is then closed: any body is not read); otherwise the state for the next calls, which take the body
 * and answer (an answer queued at the first call would close the connection, keep-alive lost). */
static enum MHD_Result begin(emu_web_t *w, struct MHD_Connection *c, const char *path, const char *method,
                             void **state)
{
    const bool api = strcmp(path, "/api") == 0 || strncmp(path, "/api/", 5U) == 0;
    web_request_headers_t h;
    web_read_headers(c, &h);
    if (!web_host_ok(w, c, h.host)) {
        return web_send_error(c, MHD_HTTP_MISDIRECTED_REQUEST, api, "the Host header does not name this server",
                              NULL);
    }
    if (!api) {
        if (strcmp(method, MHD_HTTP_METHOD_GET) != 0) {
            return web_send_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, false, "only GET", MHD_HTTP_METHOD_GET);
        }
        *state = w; /* a GET that passed: it has no body to keep, its state is the web itself */
        return MHD_YES;
    }
    api_route_t route;
    char id[WEB_ID_HEX + 1] = "";
    const bool routed = api_route(path, &route, id);
    if (routed && route == ROUTE_SOCKET) { /* a WebSocket's handshake: a GET, its token in the subprotocol */
        if (strcmp(method, MHD_HTTP_METHOD_GET) != 0) {
            return web_send_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, true, "the socket is opened with GET",
                                  MHD_HTTP_METHOD_GET);
        }
        bool forbidden = false;
        const char *why = web_socket_check(w, c, h.host, &forbidden);
        if (why != NULL) {
            return web_send_error(c, forbidden ? MHD_HTTP_FORBIDDEN : MHD_HTTP_BAD_REQUEST, true, why, NULL);
        }
    } else if (strcmp(method, MHD_HTTP_METHOD_POST) != 0) {
        return web_send_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, true, "the API takes POST only", MHD_HTTP_METHOD_POST);
    } else if (!web_token_ok(w, h.token)) {
        return web_send_error(c, MHD_HTTP_FORBIDDEN, true,
                              "missing or wrong " WEB_TOKEN_HEADER " token: load the page again", NULL);
    }
    if (!routed) {
        return web_send_error(c, MHD_HTTP_NOT_FOUND, true, "no such API path", NULL);
    }
    const char *length = h.content_length;
    if (length != NULL && (strlen(length) > 9U || strtoul(length, NULL, 10) > WEB_BODY_MAX)) {
        return web_send_error(c, MHD_HTTP_CONTENT_TOO_LARGE, true, "a request body has at most 16384 bytes", NULL);
    }
    /* A state of an ended request if one is kept (at most one per connection is in use: no malloc per request). */
    web_request_t *q = w->n_spare_requests > 0U ? w->spare_requests[--w->n_spare_requests] : malloc(sizeof *q);
    if (q == NULL) {
        return MHD_NO;
    }
    q->route = route;
    memcpy(q->id, id, sizeof q->id);
    q->len = 0U;
    q->too_large = false;
    *state = q;
    return MHD_YES;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url, const char *method,
                                  const char *version, const char *upload_data, size_t *upload_data_size, void **state)
{
    emu_web_t *w = (emu_web_t *)cls;
    (void)version;
    if (*state == NULL) {
        return begin(w, c, url, method, state);
    }
    if (*state == w) { /* a GET */
        if (*upload_data_size > 0U) {
            *upload_data_size = 0U; /* a GET's body means nothing: discarded */
            return MHD_YES;
        }
        return web_serve_file(w, c, url);
    }
    web_request_t *q = (web_request_t *)*state;
    if (*upload_data_size > 0U) {
        if (*upload_data_size > sizeof q->body - q->len) {
            q->too_large = true; /* read on and discarded: answered when it has ended */
        } else if (!q->too_large) {
            memcpy(q->body + q->len, upload_data, *upload_data_size);
            q->len += *upload_data_size;
        }
        *upload_data_size = 0U;
        return MHD_YES;
    }
    if (q->too_large) {
        return web_send_error(c, MHD_HTTP_CONTENT_TOO_LARGE, true, "a request body has at most 16384 bytes", NULL);
    }
    const co_time_us_t now = socketcan_now_us();
    switch (q->route) {
    case ROUTE_OPEN:
        return open_session(w, c, now);
    case ROUTE_STREAM:
        return open_stream(w, c, q); /* its body, if any, means nothing */
    case ROUTE_SOCKET:
        return open_socket(w, c, q);
    case ROUTE_EXCHANGE:
    default:
        return exchange(w, c, q, now);
    }
}

static void on_completed(void *cls, struct MHD_Connection *c, void **state, enum MHD_RequestTerminationCode why)
{
    emu_web_t *w = (emu_web_t *)cls;
    (void)c;
    (void)why;
    if (*state != NULL && *state != w) { /* an API request's (a GET's is the web itself): kept for the next one */
        if (w->n_spare_requests < WEB_CONNECTIONS_MAX) {
            w->spare_requests[w->n_spare_requests++] = (web_request_t *)*state;
        } else {
            free(*state);
        }
    }
    *state = NULL;
}

/* libmicrohttpd's own messages go to the log as ours do (never blocking). */
static void on_log(void *cls, const char *fmt, va_list ap) __attribute__((format(printf, 2, 0)));
static void on_log(void *cls, const char *fmt, va_list ap)
{
    emu_web_t *w = (emu_web_t *)cls;
    char text[512];
    (void)vsnprintf(text, sizeof text, fmt, ap);
    text[strcspn(text, "\n")] = '\0';
    log_limited(&w->server_log, socketcan_now_us(), "web: %s", text); /* a client's bad requests, at a bounded rate */
}

/* ---- Start, main loop, stop ------------------------------------------------------------------------------------- */

void web_init(emu_web_t *w)
{
    memset(w, 0, sizeof *w);
    w->epoll_fd = -1;
    w->listener.fd = -1;
    w->next_number = 1U;
    log_limit_init(&w->refusals, "refused web sessions", LOG_QUIET);
    log_limit_init(&w->server_log, "lines of the web server", LOG_NORMAL);
}

/* web/index.html with the token where the placeholder is. */
static bool make_index(emu_web_t *w, char *err, size_t errlen)
{
    const char *page = NULL;
    for (size_t i = 0U; i < web_files_count && page == NULL; i++) {
        page = strcmp(web_files[i].path, "/index.html") == 0 ? (const char *)web_files[i].data : NULL;
    }
    const char *at = page != NULL ? strstr(page, TOKEN_PLACEHOLDER) : NULL;
    if (at == NULL) {
        (void)snprintf(err, errlen, "--web: web/index.html has no %s (a build error)", TOKEN_PLACEHOLDER);
        return false;
    }
    const size_t before = (size_t)(at - page), after = strlen(at + strlen(TOKEN_PLACEHOLDER));
    w->index_len = before + WEB_ID_HEX + after;
    w->index_html = malloc(w->index_len + 1U);
    if (w->index_html == NULL) {
        (void)snprintf(err, errlen, "--web: out of memory");
        return false;
    }
    memcpy(w->index_html, page, before);
    memcpy(w->index_html + before, w->token, WEB_ID_HEX);
    memcpy(w->index_html + before + WEB_ID_HEX, at + strlen(TOKEN_PLACEHOLDER), after + 1U);
    return true;
}

int web_start(emu_t *emu, emu_web_t *w, const char *host_port, char *err, size_t errlen)
{
    w->emu = emu;
    if (!web_random_hex(w->token, WEB_ID_HEX / 2)) {
        (void)snprintf(err, errlen, "--web: no random numbers for the token: %s", strerror(errno));
        return EIO;
    }
    if (!make_index(w, err, errlen)) {
        return ENOMEM;
    }
    w->empty_exchange = make_empty_exchange();
    if (w->empty_exchange == NULL) {
        (void)snprintf(err, errlen, "--web: out of memory");
        return ENOMEM;
    }
    if (MHD_is_feature_supported(MHD_FEATURE_EPOLL) != MHD_YES) {
        (void)snprintf(err, errlen, "--web: this libmicrohttpd has no epoll support");
        return ENOTSUP;
    }
    const int e = tcp_listen(&w->listener, "--web", host_port, (int)WEB_CONNECTIONS_MAX, err, errlen);
    if (e != 0) {
        return e;
    }
    /* No thread of its own (MHD_USE_INTERNAL_POLLING_THREAD not given): everything runs in MHD_run, called by the
     * main loop, so the callbacks touch the nodes on the loop's thread as every other control session does. */
    /* Suspend and resume: a stream's connection waits out of the polling while nothing is to be sent. */
    w->daemon = MHD_start_daemon(MHD_USE_EPOLL | MHD_USE_ERROR_LOG | MHD_ALLOW_SUSPEND_RESUME | MHD_ALLOW_UPGRADE, 0U, NULL, NULL, on_request, w,
                                 MHD_OPTION_EXTERNAL_LOGGER, on_log, w, /* first: it covers the options' messages */
                                 MHD_OPTION_LISTEN_SOCKET, (MHD_socket)w->listener.fd,
                                 MHD_OPTION_CONNECTION_LIMIT, (unsigned int)WEB_CONNECTIONS_MAX,
                                 MHD_OPTION_PER_IP_CONNECTION_LIMIT, (unsigned int)WEB_CONNECTIONS_PER_ADDRESS,
                                 MHD_OPTION_CONNECTION_TIMEOUT, (unsigned int)WEB_CONNECTION_TIMEOUT_S,
                                 MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)WEB_CONNECTION_MEMORY,
                                 MHD_OPTION_NOTIFY_COMPLETED, on_completed, w,
                                 MHD_OPTION_END);
    const union MHD_DaemonInfo *info = w->daemon != NULL ? MHD_get_daemon_info(w->daemon, MHD_DAEMON_INFO_EPOLL_FD)
                                                         : NULL;
    if (info == NULL) {
        if (w->daemon != NULL) {
            MHD_stop_daemon(w->daemon);
            w->daemon = NULL;
        } else if (fcntl(w->listener.fd, F_GETFD) >= 0) {
            (void)close(w->listener.fd);
        }
        w->listener.fd = -1;
        (void)snprintf(err, errlen, "--web %s: libmicrohttpd did not start (see the log)", host_port);
        return EIO;
    }
    w->epoll_fd = info->epoll_fd;
    return 0;
}

nfds_t web_poll_fds(emu_web_t *w, struct pollfd *pfd, co_time_us_t now, co_time_us_t *next)
{
    if (w->daemon == NULL) {
        return 0U;
    }
    pfd->fd = w->epoll_fd;
    pfd->events = POLLIN;
    pfd->revents = 0;
    MHD_UNSIGNED_LONG_LONG ms = 0U;
    /* MHD_YES: it must run at the latest in ms (a connection's timeout; 0: work it holds), woken or not. */
    w->run_at = CO_NEVER;
    if (MHD_get_timeout(w->daemon, &ms) == MHD_YES) {
        w->run_at = now + (co_time_us_t)(ms < 3600000U ? ms : 3600000U) * 1000U;
        *next = w->run_at < *next ? w->run_at : *next;
    }
    const co_time_us_t sessions = web_sessions_deadline(w, now); /* expiries, streams' batches and keep-alives */
    const co_time_us_t sockets = web_sockets_deadline(w, now);  /* closing ones, held lines */
    *next = sessions < *next ? sessions : *next;
    *next = sockets < *next ? sockets : *next;
    return 1U + web_sockets_poll_fds(w, pfd + 1);
}

void web_service(emu_t *emu, emu_web_t *w, const struct pollfd *pfd, nfds_t n, co_time_us_t now)
{
    if (w->daemon == NULL) {
        return;
    }
    /* Only when its descriptor woke the loop or its time came: a pass for the buses' frames (a trace of a busy bus)
     * does not pay for a run of libmicrohttpd that finds nothing (about 600 instructions). */
    if ((n > 0U && pfd[0].revents != 0) || now >= w->run_at) {
        w->run_at = CO_NEVER;
        (void)MHD_run(w->daemon); /* accepts, reads, answers: the callbacks above, without blocking */
    }
    if (n > 1U) {
        web_sockets_service(w, pfd + 1, n - 1U, now);
    }
    if (web_sessions_service(emu, w, now)) {
        (void)MHD_run(w->daemon); /* the streams woken send now, not at the next wake-up */
    }
    log_limit_tick(&w->refusals, now);
    log_limit_tick(&w->server_log, now);
}

void web_stop(emu_t *emu, emu_web_t *w)
{
    while (w->n_sessions > 0U) {
        web_session_remove(emu, w, w->sessions[w->n_sessions - 1U], LOG_QUIET, NULL); /* streams ended, resumed */
    }
    web_sockets_close_all(w); /* their close frames sent as far as the sockets took them */
    if (w->daemon != NULL) {
        (void)MHD_run(w->daemon); /* libmicrohttpd's rule: no connection suspended when it stops */
        MHD_stop_daemon(w->daemon); /* closes its connections and the listening socket */
        w->daemon = NULL;
        w->listener.fd = -1;
    }
    if (w->empty_exchange != NULL) {
        MHD_destroy_response(w->empty_exchange); /* after the daemon: no connection holds it any more */
        w->empty_exchange = NULL;
    }
    while (w->n_spare_requests > 0U) {
        free(w->spare_requests[--w->n_spare_requests]);
    }
    free(w->index_html);
    w->index_html = NULL;
}
