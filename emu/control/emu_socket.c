/* The control sockets: see emu_socket.h. */
#define _GNU_SOURCE /* accept4, MSG_NOSIGNAL, PATH_MAX and POSIX calls, as in every file of the Linux program */
#include "control/emu_socket.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "runtime/emu.h"
#include "runtime/emu_events.h"
#include "runtime/emu_output.h"
#include "control/emu_tcp.h"

void sockets_init(emu_sockets_t *k)
{
    memset(k, 0, sizeof *k);
    k->unix_fd = -1;
    k->tcp_fd = -1;
    k->next_number = 1U;
    log_limit_init(&k->refusals, "refused or closed control connections", LOG_QUIET);
}

int sockets_listen_unix(emu_sockets_t *k, const char *path, char *err, size_t errlen)
{
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    if (path[0] == '\0' || strlen(path) >= sizeof addr.sun_path) {
        (void)snprintf(err, errlen, "control socket path '%s' must have 1..%zu bytes", path, sizeof addr.sun_path - 1U);
        return EINVAL;
    }
    memcpy(addr.sun_path, path, strlen(path));
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISSOCK(st.st_mode)) {
            (void)snprintf(err, errlen, "control socket %s: the path exists and is not a socket", path);
            return EEXIST;
        }
        /* A socket file: in use by a running emulator (connect works), or left by one that was killed. */
        const int probe = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
        const bool live = probe >= 0 && connect(probe, (const struct sockaddr *)&addr, sizeof addr) == 0;
        if (probe >= 0) {
            (void)close(probe);
        }
        if (live) {
            (void)snprintf(err, errlen, "control socket %s is in use by another program", path);
            return EADDRINUSE;
        }
        (void)unlink(path);
    }
    const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        const int e = errno;
        (void)snprintf(err, errlen, "control socket: %s", strerror(e));
        return e;
    }
    /* 0600 from the start: between bind and a chmod another user could connect. */
    const mode_t old = umask(0177);
    const int bound = bind(fd, (const struct sockaddr *)&addr, sizeof addr);
    const int e_bind = errno;
    (void)umask(old);
    if (bound != 0 || listen(fd, MAX_CLIENTS) != 0) {
        const int e = bound != 0 ? e_bind : errno;
        (void)close(fd);
        (void)snprintf(err, errlen, "control socket %s: %s", path, strerror(e));
        return e;
    }
    k->unix_fd = fd;
    (void)snprintf(k->unix_path, sizeof k->unix_path, "%s", path);
    return 0;
}

int sockets_listen_tcp(emu_sockets_t *k, const char *host_port, bool *remote, char *err, size_t errlen)
{
    tcp_listener_t l;
    const int e = tcp_listen(&l, "--control-tcp", host_port, MAX_CLIENTS, err, errlen);
    if (e != 0) {
        return e;
    }
    k->tcp_fd = l.fd;
    (void)snprintf(k->tcp_name, sizeof k->tcp_name, "%s", l.name);
    *remote = l.remote;
    return 0;
}

int sockets_load_token(emu_sockets_t *k, const char *path, char *err, size_t errlen)
{
    const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
        const int e = errno;
        (void)snprintf(err, errlen, "--control-token-file %s: %s", path, strerror(e));
        return e;
    }
    char text[SOCKETS_TOKEN_MAX + 3U]; /* the token, "\r\n", and one more byte to see a longer file */
    struct stat st;
    ssize_t n = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? read(fd, text, sizeof text) : -1;
    (void)close(fd);
    if (n < 0) {
        (void)snprintf(err, errlen, "--control-token-file %s: not a readable regular file", path);
        return EINVAL;
    }
    size_t len = (size_t)n;
    if (len > 0U && text[len - 1U] == '\n') {
        len--;
    }
    if (len > 0U && text[len - 1U] == '\r') {
        len--;
    }
    bool printable = true;
    for (size_t i = 0U; i < len; i++) {
        printable = printable && text[i] > ' ' && text[i] < 0x7F;
    }
    if (len < SOCKETS_TOKEN_MIN || len > SOCKETS_TOKEN_MAX || !printable) {
        (void)snprintf(err, errlen, "--control-token-file %s: the token must be one line of %u to %u printable "
                       "characters without spaces (e.g. from: head -c 24 /dev/urandom | base64)", path,
                       SOCKETS_TOKEN_MIN, SOCKETS_TOKEN_MAX);
        return EINVAL;
    }
    memcpy(k->tcp_token_text, text, len);
    k->tcp_token_text[len] = '\0';
    k->tcp_token = k->tcp_token_text;
    if ((st.st_mode & (S_IRWXG | S_IRWXO)) != 0U) {
        logline(LOG_QUIET, "control: warning: --control-token-file %s can be read by other users (chmod 600 it)",
                path);
    }
    return 0;
}

/* ---- Clients ---------------------------------------------------------------------------------------------- */

static void client_write(void *ctx, const char *line, size_t len)
{
    control_client_t *c = (control_client_t *)ctx;
    if (c->overflow || c->gone) {
        return;
    }
    if (!byte_buffer_append(&c->out, line, len, CLIENT_OUTPUT_MAX)) {
        c->overflow = true; /* it does not read: closed at the next pass, logged there */
    }
}

static void client_flush(control_client_t *c)
{
    if (!c->gone && !byte_buffer_send(&c->out, c->fd)) {
        c->gone = true; /* EPIPE, ECONNRESET: the client went away */
    }
}

static void accept_clients(emu_t *emu, emu_sockets_t *k, int listen_fd, const char *how)
{
    for (int i = 0; i < 16; i++) {
        const int fd = accept4(listen_fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            return; /* EAGAIN: all taken; anything else (EMFILE...) will be retried at the next POLLIN */
        }
        if (k->n_clients == MAX_CLIENTS || emu->n_sessions == MAX_SESSIONS) {
            static const char full[] = "{\"id\":null,\"ok\":false,\"error\":\"too many control clients (at most 64)\"}\n";
            (void)send(fd, full, sizeof full - 1U, MSG_NOSIGNAL | MSG_DONTWAIT);
            (void)close(fd);
            log_limited(&k->refusals, socketcan_now_us(), "control: a %s client refused: %d are connected already",
                        how, MAX_CLIENTS);
            continue;
        }
        control_client_t *c = calloc(1U, sizeof *c);
        if (c == NULL) {
            (void)close(fd);
            continue;
        }
        c->fd = fd;
        char name[64];
        (void)snprintf(name, sizeof name, "client %lu (%s)", k->next_number++, how);
        session_init(&c->session, name, client_write, c);
        c->session.unread = &c->out;
        c->session.refuse_http = true; /* on both sockets: a browser may reach a Unix socket through a proxy too */
        if (listen_fd == k->tcp_fd) {
            c->session.token = k->tcp_token;
        }
        k->clients[k->n_clients++] = c;
        events_add_session(emu, &c->session);
        logline(LOG_VERBOSE, "control: %s connected", name);
    }
}

static void client_close(emu_t *emu, emu_sockets_t *k, size_t i)
{
    control_client_t *c = k->clients[i];
    if (c->overflow || c->session.overflow) {
        log_limited(&k->refusals, socketcan_now_us(), "control: %s disconnected: it left more than %u bytes unread",
                    c->session.name, CLIENT_OUTPUT_MAX);
    } else if (c->session.hang_up != NULL) {
        log_limited(&k->refusals, socketcan_now_us(), "control: %s closed: %s", c->session.name, c->session.hang_up);
    } else {
        logline(LOG_VERBOSE, "control: %s disconnected", c->session.name);
    }
    events_remove_session(emu, &c->session);
    session_free(&c->session);
    (void)close(c->fd);
    byte_buffer_free(&c->out);
    free(c);
    k->clients[i] = k->clients[--k->n_clients];
}

nfds_t sockets_poll_fds(const emu_sockets_t *k, struct pollfd *pfd, nfds_t max)
{
    nfds_t n = 0U;
    const int listeners[2] = {k->unix_fd, k->tcp_fd};
    for (size_t i = 0U; i < 2U && n < max; i++) {
        if (listeners[i] >= 0) {
            pfd[n].fd = listeners[i];
            pfd[n].events = POLLIN;
            pfd[n].revents = 0;
            n++;
        }
    }
    for (size_t i = 0U; i < k->n_clients && n < max; i++) {
        const control_client_t *c = k->clients[i];
        /* No POLLIN while its input is full or it ended: what it sends waits in the kernel, and it is not read. */
        const bool reading = !c->eof && c->session.hang_up == NULL && session_input_room(&c->session) > 0U;
        pfd[n].fd = c->fd;
        pfd[n].events = (short)((reading ? POLLIN : 0) | (c->out.len > 0U ? POLLOUT : 0));
        pfd[n].revents = 0;
        n++;
    }
    return n;
}

static void client_read(emu_t *emu, control_client_t *c)
{
    /* Only what its session has room for: lines run later, within the pass's budget (emu_session_work.c). */
    const size_t room = session_input_room(&c->session);
    char chunk[CLIENT_READ_MAX];
    const ssize_t r = recv(c->fd, chunk, room < sizeof chunk ? room : sizeof chunk, MSG_DONTWAIT);
    if (r > 0) {
        session_input(emu, &c->session, chunk, (size_t)r);
    } else if (r == 0) {
        c->eof = true; /* its lines still run and are answered (a half-closed client reads); a partial one does not */
    } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        c->gone = true;
    }
}

void sockets_service(emu_t *emu, emu_sockets_t *k, const struct pollfd *pfd, nfds_t n)
{
    for (nfds_t i = 0U; i < n; i++) {
        if (pfd[i].revents == 0) {
            continue;
        }
        if (pfd[i].fd == k->unix_fd) {
            accept_clients(emu, k, k->unix_fd, "unix");
            continue;
        }
        if (pfd[i].fd == k->tcp_fd) {
            accept_clients(emu, k, k->tcp_fd, "tcp");
            continue;
        }
        for (size_t j = 0U; j < k->n_clients; j++) {
            control_client_t *c = k->clients[j];
            if (c->fd != pfd[i].fd) {
                continue;
            }
            const bool can_read = !c->eof && session_input_room(&c->session) > 0U;
            if ((pfd[i].revents & (POLLIN | POLLHUP | POLLERR)) != 0 && can_read) {
                client_read(emu, c);
            } else if ((pfd[i].revents & (POLLHUP | POLLERR)) != 0 && c->eof) {
                c->gone = true; /* it hung up after its input ended: nobody reads the answers any more */
            }
            break;
        }
    }
    sockets_tidy(emu, k);
}

static void sockets_flush(emu_sockets_t *k)
{
    for (size_t j = 0U; j < k->n_clients; j++) {
        client_flush(k->clients[j]);
    }
}

/* Whether a client ended: gone, overflowing, hung up by its session (after its last answer left, if it reads), or
 * done after the end of its input. */
static bool client_ended(const control_client_t *c)
{
    if (c->gone || c->overflow || c->session.overflow) {
        return true;
    }
    if (c->session.hang_up != NULL || c->eof) {
        return !session_busy(&c->session) && c->out.len == 0U;
    }
    return false;
}

void sockets_tidy(emu_t *emu, emu_sockets_t *k)
{
    sockets_flush(k);
    for (size_t j = k->n_clients; j > 0U; j--) {
        if (client_ended(k->clients[j - 1U])) {
            client_close(emu, k, j - 1U);
        }
    }
    log_limit_tick(&k->refusals, socketcan_now_us());
}

void sockets_close(emu_t *emu, emu_sockets_t *k)
{
    /* The answer to a `quit` and the last events: up to 200 ms for the clients to take them. */
    struct timespec t0;
    (void)clock_gettime(CLOCK_MONOTONIC, &t0);
    for (;;) {
        sockets_flush(k);
        bool waiting = false;
        for (size_t j = 0U; j < k->n_clients; j++) {
            waiting = waiting || (k->clients[j]->out.len > 0U && !k->clients[j]->gone);
        }
        struct timespec t;
        (void)clock_gettime(CLOCK_MONOTONIC, &t);
        const long ms = (long)(t.tv_sec - t0.tv_sec) * 1000L + (t.tv_nsec - t0.tv_nsec) / 1000000L;
        if (!waiting || ms >= 200L) {
            break;
        }
        (void)poll(NULL, 0U, 5);
    }
    while (k->n_clients > 0U) {
        client_close(emu, k, k->n_clients - 1U);
    }
    if (k->unix_fd >= 0) {
        (void)close(k->unix_fd);
        (void)unlink(k->unix_path);
        k->unix_fd = -1;
    }
    if (k->tcp_fd >= 0) {
        (void)close(k->tcp_fd);
        k->tcp_fd = -1;
    }
}
