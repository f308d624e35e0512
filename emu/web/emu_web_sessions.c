/* The web view's sessions: see emu_web_sessions.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web_sessions.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>

#include "runtime/emu.h"
#include "runtime/emu_events.h"
#include "runtime/emu_output.h"
#include "web/emu_web_socket.h"
#include "web/emu_web_stream.h"

bool web_random_hex(char *out, size_t n)
{
    unsigned char bytes[64];
    if (n > sizeof bytes || getrandom(bytes, n, 0) != (ssize_t)n) {
        return false;
    }
    static const char digits[] = "0123456789abcdef";
    for (size_t i = 0U; i < n; i++) {
        out[2U * i] = digits[bytes[i] >> 4];
        out[2U * i + 1U] = digits[bytes[i] & 0x0FU];
    }
    out[2U * n] = '\0';
    return true;
}

/* emu_session_t.write of a web session: the line waits for the next exchange. */
static void session_write(void *ctx, const char *line, size_t len)
{
    web_session_t *s = (web_session_t *)ctx;
    if (!s->overflow && !byte_buffer_append(&s->out, line, len, WEB_OUTPUT_MAX)) {
        s->overflow = true; /* the browser does not ask: dropped at the next pass, logged there */
    }
}

web_session_t *web_session_open(emu_t *emu, emu_web_t *w, co_time_us_t now, bool *full)
{
    *full = w->n_sessions == WEB_SESSIONS_MAX || emu->n_sessions == MAX_SESSIONS;
    if (*full) {
        return NULL;
    }
    web_session_t *s = calloc(1U, sizeof *s);
    if (s == NULL) {
        return NULL;
    }
    if (!web_random_hex(s->id, WEB_ID_HEX / 2)) {
        free(s);
        return NULL;
    }
    s->web = w;
    s->number = w->next_number++;
    s->last_exchange = now;
    s->waiting_since = CO_NEVER;
    s->quiet_since = now;
    char name[64];
    (void)snprintf(name, sizeof name, "web session %lu", s->number);
    session_init(&s->session, name, session_write, s);
    s->session.restricted = true;
    s->session.unread = &s->out;
    s->session.output_high = WEB_OUTPUT_MAX / 4U; /* the browser takes all of it with each exchange */
    w->sessions[w->n_sessions++] = s;
    events_add_session(emu, &s->session);
    logline(LOG_VERBOSE, "web: %s opened", name);
    return s;
}

web_session_t *web_session_find(emu_web_t *w, const char *id)
{
    if (strlen(id) != WEB_ID_HEX) {
        return NULL;
    }
    web_session_t *found = NULL;
    for (size_t i = 0U; i < w->n_sessions; i++) {
        unsigned char diff = 0U;
        for (size_t k = 0U; k < WEB_ID_HEX; k++) {
            diff |= (unsigned char)(w->sessions[i]->id[k] ^ id[k]);
        }
        if (diff == 0U) {
            found = w->sessions[i];
        }
    }
    return found;
}

bool web_session_queue(emu_t *emu, web_session_t *s, const char *body, size_t len, co_time_us_t now)
{
    s->last_exchange = now;
    const bool end_line = len > 0U && body[len - 1U] != '\n'; /* a line never spans two exchanges */
    if (len + (end_line ? 1U : 0U) > session_input_room(&s->session)) {
        return false;
    }
    session_input(emu, &s->session, body, len);
    if (end_line) {
        session_input(emu, &s->session, "\n", 1U);
    }
    session_work_units(emu, &s->session, WEB_EXCHANGE_UNITS);
    return true;
}

char *web_session_take_output(web_session_t *s, size_t *len) { return byte_buffer_take(&s->out, len); }

void web_session_remove(emu_t *emu, emu_web_t *w, web_session_t *s, int log_level, const char *why)
{
    if (why != NULL) {
        logline(log_level, "web: %s %s", s->session.name, why);
    }
    if (s->stream != NULL && web_stream_end(s->stream)) {
        w->run_again = true; /* the stream's answer ends when libmicrohttpd runs */
    }
    if (s->socket != NULL) {
        web_socket_end(s->socket);
    }
    events_remove_session(emu, &s->session);
    session_free(&s->session);
    for (size_t i = 0U; i < w->n_sessions; i++) {
        if (w->sessions[i] == s) {
            w->sessions[i] = w->sessions[--w->n_sessions];
            break;
        }
    }
    byte_buffer_free(&s->out);
    free(s);
}

/* A streamed session's lines due, or its keep-alive: its stream woken, or a message on its socket. true:
 * libmicrohttpd must run. */
static bool stream_due(web_session_t *s, co_time_us_t now)
{
    const bool lines = s->out.len > 0U;
    if (lines ? !s->send_now && (s->waiting_since == CO_NEVER || now < s->waiting_since + WEB_STREAM_BATCH_US)
              : now < s->quiet_since + WEB_STREAM_KEEPALIVE_US) {
        return false;
    }
    s->keepalive = !lines;
    s->send_now = false;
    s->waiting_since = CO_NEVER;
    s->quiet_since = now;
    if (s->socket != NULL) {
        web_socket_flush(s->socket, s->keepalive);
        s->keepalive = false;
        return false;
    }
    return web_stream_wake(s->stream);
}

bool web_sessions_service(emu_t *emu, emu_web_t *w, co_time_us_t now)
{
    bool run = false;
    for (size_t i = w->n_sessions; i > 0U; i--) {
        web_session_t *s = w->sessions[i - 1U];
        if (s->overflow || s->session.overflow) {
            char why[96];
            (void)snprintf(why, sizeof why, "dropped: more than %u bytes waited for its next exchange", WEB_OUTPUT_MAX);
            web_session_remove(emu, w, s, LOG_QUIET, why);
        } else if (s->stream != NULL || s->socket != NULL) {
            s->last_exchange = now; /* in use while its stream is open: a page that does not post is idle, not gone */
            run = stream_due(s, now) || run;
        } else if (now > s->last_exchange && now - s->last_exchange >= WEB_SESSION_IDLE_US) {
            char why[64]; /* (an exchange during this pass is stamped after now) */
            (void)snprintf(why, sizeof why, "removed: no exchange for %u s", WEB_SESSION_IDLE_US / 1000000U);
            web_session_remove(emu, w, s, LOG_NORMAL, why);
        }
    }
    run = run || w->run_again;
    w->run_again = false;
    return run;
}

co_time_us_t web_sessions_deadline(emu_web_t *w, co_time_us_t now)
{
    co_time_us_t next = CO_NEVER;
    for (size_t i = 0U; i < w->n_sessions; i++) {
        web_session_t *s = w->sessions[i];
        if (s->overflow || s->session.overflow) {
            return now;
        }
        co_time_us_t due = s->last_exchange + WEB_SESSION_IDLE_US;
        if (s->stream != NULL || s->socket != NULL) {
            if (s->out.len == 0U) {
                due = s->quiet_since + WEB_STREAM_KEEPALIVE_US;
            } else if (s->send_now) {
                due = now;
            } else {
                s->waiting_since = s->waiting_since == CO_NEVER ? now : s->waiting_since;
                due = s->waiting_since + WEB_STREAM_BATCH_US;
            }
        }
        next = due < next ? due : next;
    }
    return next;
}
