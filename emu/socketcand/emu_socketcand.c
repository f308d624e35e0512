/* The socketcand server: see emu_socketcand.h (the protocol itself: socketcand_proto.c). */
#define _GNU_SOURCE /* accept4, MSG_NOSIGNAL, PATH_MAX and POSIX calls, as in every file of the Linux program */
#include "socketcand/emu_socketcand.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "runtime/emu.h"
#include "runtime/emu_bus.h"
#include "runtime/emu_output.h"

/* Bytes the kernel keeps for a client's unsent frames: with SOCKETCAND_OUTPUT_MAX, what a client that does not read
 * can make the emulator hold (a CAN bus at 1 Mbit/s fills it in a few seconds at the most). */
#define CLIENT_SNDBUF (64 * 1024)

static void update_wall_offset(emu_socketcand_t *s)
{
    struct timespec real, mono;
    (void)clock_gettime(CLOCK_REALTIME, &real);
    (void)clock_gettime(CLOCK_MONOTONIC, &mono);
    s->wall_offset_us = ((int64_t)real.tv_sec - (int64_t)mono.tv_sec) * 1000000 +
                        ((int64_t)real.tv_nsec - (int64_t)mono.tv_nsec) / 1000;
}

void socketcand_init(emu_socketcand_t *s)
{
    memset(s, 0, sizeof *s);
    s->listener.fd = -1;
    s->next_number = 1U;
    log_limit_init(&s->refusals, "refused or closed socketcand connections", LOG_QUIET);
    log_limit_init(&s->troubles, "socketcand frames not carried", LOG_QUIET);
}

int socketcand_start(emu_socketcand_t *s, const char *host_port, char *err, size_t errlen)
{
    update_wall_offset(s);
    return tcp_listen(&s->listener, "--socketcand", host_port, SOCKETCAND_CLIENTS_MAX, err, errlen);
}

/* ---- Output --------------------------------------------------------------------------------------------- */

static void client_write(socketcand_client_t *c, const char *text, size_t len)
{
    if (c->overflow || c->gone) {
        return;
    }
    if (!byte_buffer_append(&c->out, text, len, SOCKETCAND_OUTPUT_MAX)) {
        c->overflow = true; /* it does not read: cut off at the next pass, logged there */
    }
}

static void client_say(socketcand_client_t *c, const char *text)
{
    client_write(c, text, strlen(text));
}

static void client_flush(socketcand_client_t *c, co_time_us_t now)
{
    if (now < c->hold_until) {
        return; /* rawmode's "< ok >" left alone; its frames follow after the hold */
    }
    if (!c->gone && !byte_buffer_send(&c->out, c->fd)) {
        c->gone = true; /* EPIPE, ECONNRESET: the client went away */
    }
}

void socketcand_publish(emu_socketcand_t *s, const emu_bus_t *b, const co_frame_t *f, co_time_us_t at,
                        const socketcand_client_t *except)
{
    char text[SOCKETCAND_FRAME_TEXT_MAX];
    size_t len = 0U;
    for (size_t i = 0U; i < s->n_clients; i++) {
        socketcand_client_t *c = s->clients[i];
        if (c->bus != b || c->mode != SOCKETCAND_MODE_RAW || c == except) {
            continue;
        }
        if (len == 0U) { /* written once for all its readers */
            const int64_t wall = (int64_t)at + s->wall_offset_us;
            const uint64_t us = wall > 0 ? (uint64_t)wall : 0U;
            len = socketcand_format_frame(f, us / 1000000U, (uint32_t)(us % 1000000U), text, sizeof text);
        }
        client_write(c, text, len);
    }
}

/* ---- Clients -------------------------------------------------------------------------------------------- */

static void set_mode(socketcand_client_t *c, socketcand_mode_t mode)
{
    if (c->bus != NULL && c->mode == SOCKETCAND_MODE_RAW) {
        c->bus->socketcand_readers--;
    }
    c->mode = mode;
    if (c->bus != NULL && mode == SOCKETCAND_MODE_RAW) {
        c->bus->socketcand_readers++;
    }
}

/* Answers what it was told and closes it once the answer left (or SOCKETCAND_LINGER_US later). */
static void close_after(socketcand_client_t *c, const char *answer, const char *why, co_time_us_t now)
{
    if (answer != NULL) {
        client_say(c, answer);
    }
    c->why = why;
    c->closing_at = now + SOCKETCAND_LINGER_US;
}

static void peer_name(const struct sockaddr_storage *a, char *out, size_t len)
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0U;
    if (a->ss_family == AF_INET) {
        const struct sockaddr_in *v4 = (const struct sockaddr_in *)(const void *)a;
        (void)inet_ntop(AF_INET, &v4->sin_addr, host, sizeof host);
        port = ntohs(v4->sin_port);
    } else if (a->ss_family == AF_INET6) {
        const struct sockaddr_in6 *v6 = (const struct sockaddr_in6 *)(const void *)a;
        (void)inet_ntop(AF_INET6, &v6->sin6_addr, host, sizeof host);
        port = ntohs(v6->sin6_port);
    }
    (void)snprintf(out, len, strchr(host, ':') != NULL ? "[%s]:%u" : "%s:%u", host, port);
}

static void accept_clients(emu_socketcand_t *s, co_time_us_t now)
{
    for (int i = 0; i < 16; i++) {
        struct sockaddr_storage addr;
        socklen_t addrlen = sizeof addr;
        memset(&addr, 0, sizeof addr);
        const int fd = accept4(s->listener.fd, (struct sockaddr *)&addr, &addrlen, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            return; /* EAGAIN: all taken; anything else (EMFILE...) will be retried at the next POLLIN */
        }
        char peer[64];
        peer_name(&addr, peer, sizeof peer);
        if (s->n_clients == SOCKETCAND_CLIENTS_MAX) {
            static const char full[] = "< error too many clients >";
            (void)send(fd, full, sizeof full - 1U, MSG_NOSIGNAL | MSG_DONTWAIT);
            (void)close(fd);
            log_limited(&s->refusals, now, "socketcand: a client (%s) refused: %d are connected already", peer,
                        SOCKETCAND_CLIENTS_MAX);
            continue;
        }
        socketcand_client_t *c = calloc(1U, sizeof *c);
        if (c == NULL) {
            (void)close(fd);
            continue;
        }
        const int sndbuf = CLIENT_SNDBUF, one = 1, idle = 30, interval = 10, count = 3;
        (void)setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
        (void)setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one); /* a frame is worth sending at once */
        /* a peer that vanished without a word (its machine off, a cable out) is found within about a minute */
        (void)setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
        (void)setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
        (void)setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
        (void)setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
        c->fd = fd;
        (void)snprintf(c->name, sizeof c->name, "client %lu (%s)", s->next_number++, peer);
        socketcand_reader_init(&c->reader);
        s->clients[s->n_clients++] = c;
        client_say(c, "< hi >");
        client_flush(c, now);
        logline(LOG_VERBOSE, "socketcand: %s connected", c->name);
    }
}

static void client_close(emu_socketcand_t *s, size_t i, co_time_us_t now)
{
    socketcand_client_t *c = s->clients[i];
    if (c->overflow) {
        log_limited(&s->refusals, now, "socketcand: %s cut off: it left more than %u bytes unread", c->name,
                    SOCKETCAND_OUTPUT_MAX);
    } else if (c->why != NULL) {
        log_limited(&s->refusals, now, "socketcand: %s closed: %s", c->name, c->why);
    } else {
        logline(LOG_VERBOSE, "socketcand: %s disconnected", c->name);
    }
    set_mode(c, SOCKETCAND_MODE_NO_BUS);
    (void)close(c->fd);
    byte_buffer_free(&c->out);
    free(c);
    s->clients[i] = s->clients[--s->n_clients];
}

static bool client_ended(const socketcand_client_t *c, co_time_us_t now)
{
    if (c->gone || c->overflow) {
        return true;
    }
    if (c->closing_at != 0U) {
        return c->out.len == 0U || now >= c->closing_at;
    }
    return c->eof && c->in_pos == c->in_len && c->out.len == 0U;
}

/* Whether it is to be read: what it sent before is used, and it neither ended nor is being closed. */
static bool client_reading(const socketcand_client_t *c)
{
    return !c->eof && !c->gone && c->closing_at == 0U && c->in_pos == c->in_len;
}

nfds_t socketcand_poll_fds(emu_t *emu, emu_socketcand_t *s, struct pollfd *pfd, nfds_t max, co_time_us_t now,
                           co_time_us_t *next)
{
    (void)emu;
    update_wall_offset(s);
    for (size_t j = s->n_clients; j > 0U; j--) {
        socketcand_client_t *c = s->clients[j - 1U];
        client_flush(c, now);
        if (client_ended(c, now)) {
            client_close(s, j - 1U, now);
        }
    }
    log_limit_tick(&s->refusals, now);
    log_limit_tick(&s->troubles, now);
    nfds_t n = 0U;
    if (max == 0U) {
        return 0U;
    }
    pfd[n].fd = s->listener.fd;
    pfd[n].events = POLLIN;
    pfd[n].revents = 0;
    n++;
    for (size_t i = 0U; i < s->n_clients && n < max; i++) {
        socketcand_client_t *c = s->clients[i];
        const bool held = now < c->hold_until;
        if (held && c->out.len > 0U && c->hold_until < *next) {
            *next = c->hold_until;
        }
        if (c->closing_at != 0U && c->closing_at < *next) {
            *next = c->closing_at;
        }
        pfd[n].fd = c->fd;
        pfd[n].events = (short)((client_reading(c) ? POLLIN : 0) | (c->out.len > 0U && !held ? POLLOUT : 0));
        pfd[n].revents = 0;
        n++;
    }
    return n;
}

static void client_read(socketcand_client_t *c)
{
    const ssize_t r = recv(c->fd, c->in, sizeof c->in, MSG_DONTWAIT);
    if (r > 0) {
        c->in_len = (size_t)r;
        c->in_pos = 0U;
    } else if (r == 0) {
        c->eof = true;
    } else if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        c->gone = true;
    }
}

/* ---- Commands ------------------------------------------------------------------------------------------- */

static emu_bus_t *find_bus(emu_t *emu, const char *name)
{
    for (size_t i = 0U; i < emu->n_buses; i++) {
        if (strcmp(emu->buses[i]->can.name, name) == 0) {
            return emu->buses[i];
        }
    }
    return NULL;
}

static void refuse(emu_socketcand_t *s, socketcand_client_t *c, const char *why, co_time_us_t now)
{
    char text[160];
    (void)snprintf(text, sizeof text, "< error %s >", why);
    client_say(c, text);
    if (++c->errors_in_a_row >= SOCKETCAND_ERRORS_MAX) {
        close_after(c, NULL, "too many malformed or unknown commands in a row", now);
    }
    (void)s;
}

/* A client's frame: to the bus's medium, its nodes (as a frame read from the medium) and its other clients. */
static void send_frame(emu_socketcand_t *s, socketcand_client_t *c, const co_frame_t *f, co_time_us_t now)
{
    emu_bus_t *b = c->bus;
    if (can_channel_send(&b->can, f) != CO_OK) {
        /* an interface down, a full queue: the nodes and the other clients have it all the same */
        s->medium_refused++;
        log_limited(&s->troubles, now, "socketcand: %s: a frame of %s did not reach the bus's medium (%lu so far)",
                    b->can.name, c->name, s->medium_refused);
    }
    /* to the other clients first: a node answers inside bus_frame_in, and a watching client must see the request
     * before its answer, as on the wire */
    if (b->socketcand_readers > 0U) {
        socketcand_publish(s, b, f, now, c);
    }
    bus_frame_in(b, f, now);
}

static void run_command(emu_t *emu, emu_socketcand_t *s, socketcand_client_t *c, co_time_us_t now)
{
    socketcand_command_t cmd;
    socketcand_parse(c->reader.cmd, c->reader.len, &cmd);
    if (cmd.verb == SOCKETCAND_BAD || cmd.verb == SOCKETCAND_UNSUPPORTED) {
        refuse(s, c, cmd.why, now);
        return;
    }
    if (cmd.verb == SOCKETCAND_ECHO) {
        c->errors_in_a_row = 0U;
        client_say(c, "< echo >");
        return;
    }
    if (cmd.verb == SOCKETCAND_OPEN) {
        if (c->bus != NULL) {
            refuse(s, c, "a channel is open already", now);
            return;
        }
        c->bus = find_bus(emu, cmd.channel);
        if (c->bus == NULL) {
            /* socketcand's answer, and it closes the connection too */
            close_after(c, "< error could not open bus >", "it asked for a channel that is not one of the buses", now);
            return;
        }
        c->errors_in_a_row = 0U;
        c->mode = SOCKETCAND_MODE_BCM;
        client_say(c, "< ok >");
        logline(LOG_VERBOSE, "socketcand: %s opened %s", c->name, c->bus->can.name);
        return;
    }
    if (c->bus == NULL) {
        refuse(s, c, "open a channel first", now);
        return;
    }
    c->errors_in_a_row = 0U;
    switch (cmd.verb) {
    case SOCKETCAND_RAWMODE:
        client_say(c, "< ok >");
        client_flush(c, now);
        if (c->mode != SOCKETCAND_MODE_RAW) {
            set_mode(c, SOCKETCAND_MODE_RAW);
            c->hold_until = now + SOCKETCAND_RAWMODE_HOLD_US;
        }
        break;
    case SOCKETCAND_BCMMODE:
        set_mode(c, SOCKETCAND_MODE_BCM);
        client_say(c, "< ok >");
        break;
    case SOCKETCAND_SEND:
        send_frame(s, c, &cmd.frame, now);
        break;
    default: /* SOCKETCAND_FD */
        if (s->fd_frames++ == 0U) {
            logline(LOG_QUIET, "socketcand: %s sent a CAN FD frame: FD frames are not carried (counted, the count "
                    "is logged at exit)", c->name);
        }
        break;
    }
}

/* One item of a client's input (a command, a refusal); false when its input is used up. */
static bool client_step(emu_t *emu, emu_socketcand_t *s, socketcand_client_t *c, co_time_us_t now)
{
    if (c->in_pos == c->in_len || c->gone || c->closing_at != 0U) {
        c->in_pos = c->in_len; /* a client being closed: what it sends is not run */
        return false;
    }
    size_t used = 0U;
    const socketcand_item_t item = socketcand_reader_take(&c->reader, c->in + c->in_pos, c->in_len - c->in_pos,
                                                          &used);
    const size_t at = c->in_pos;
    c->in_pos += used;
    switch (item) {
    case SOCKETCAND_MORE:
        return false;
    case SOCKETCAND_FOREIGN:
        c->why = socketcand_looks_like_http(c->in + at, c->in_len - at)
                     ? "its first bytes are an HTTP request (a web page may send one): nothing of it was done"
                     : "its first bytes are not a socketcand command: nothing of it was done";
        c->gone = true;
        c->in_pos = c->in_len;
        return false;
    case SOCKETCAND_OVERLONG:
        refuse(s, c, "command too long", now);
        return true;
    case SOCKETCAND_JUNK:
        refuse(s, c, "bytes outside a command", now);
        return true;
    default:
        run_command(emu, s, c, now);
        return true;
    }
}

bool socketcand_service(emu_t *emu, emu_socketcand_t *s, const struct pollfd *pfd, nfds_t n, co_time_us_t due)
{
    co_time_us_t now = socketcan_now_us();
    for (nfds_t i = 0U; i < n; i++) {
        if (pfd[i].revents == 0) {
            continue;
        }
        if (pfd[i].fd == s->listener.fd) {
            accept_clients(s, now);
            continue;
        }
        for (size_t j = 0U; j < s->n_clients; j++) {
            socketcand_client_t *c = s->clients[j];
            if (c->fd != pfd[i].fd) {
                continue;
            }
            if ((pfd[i].revents & (POLLIN | POLLHUP | POLLERR)) != 0 && client_reading(c)) {
                client_read(c);
            } else if ((pfd[i].revents & (POLLHUP | POLLERR)) != 0) {
                c->gone = true; /* nobody reads what it is sent any more */
            }
            break;
        }
    }
    /* The clients' commands by turns, one at a time, within the pass's bounds (the first always runs). */
    const co_time_us_t stop = now + SESSION_PASS_BUDGET_US < due ? now + SESSION_PASS_BUDGET_US : due;
    unsigned done = 0U;
    bool progress = true;
    while (progress && s->n_clients > 0U) {
        progress = false;
        for (size_t k = 0U; k < s->n_clients; k++) {
            if (done > 0U && (done >= SOCKETCAND_PASS_COMMANDS || now >= stop)) {
                return true; /* what is left waits for the next pass */
            }
            const size_t j = (s->turn + k) % s->n_clients;
            if (client_step(emu, s, s->clients[j], now)) {
                progress = true;
                done++;
                s->turn = (j + 1U) % s->n_clients;
                now = socketcan_now_us();
            }
        }
    }
    return false;
}

void socketcand_stop(emu_t *emu, emu_socketcand_t *s)
{
    (void)emu;
    const co_time_us_t now = socketcan_now_us();
    while (s->n_clients > 0U) {
        client_close(s, s->n_clients - 1U, now);
    }
    if (s->listener.fd >= 0) {
        (void)close(s->listener.fd);
        s->listener.fd = -1;
    }
    if (s->fd_frames > 0U) {
        logline(LOG_QUIET, "socketcand: %lu CAN FD frame(s) of clients were not carried", s->fd_frames);
    }
    if (s->medium_refused > 0U) {
        logline(LOG_QUIET, "socketcand: %lu frame(s) of clients did not reach their bus's medium", s->medium_refused);
    }
}
