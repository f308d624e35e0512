/* The sessions' waiting work and the pass's budget for it: see emu_session.h ("Work waiting").
 *
 * Why a budget for all sessions together: a transport's bound per client (bytes read per pass) does not bound a
 * pass when many clients ask for costly answers at once: 64 clients asking `objects` with values held the loop
 * over a second, and the nodes' heartbeats waited. Lines now wait in their session and run one at a time,
 * round-robin, until the pass's budget or the nodes' next deadline; a client whose output waits unread runs
 * nothing, so one that never reads costs no work at all. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include <string.h>

#include "runtime/emu.h"
#include "control/emu_session.h"

size_t session_input_room(const emu_session_t *s) { return SESSION_INPUT_MAX - s->in.len; }

void session_input(emu_t *emu, emu_session_t *s, const char *data, size_t n)
{
    if (n == 0U || s->hang_up != NULL) {
        return;
    }
    size_t lines = 0U;
    for (const char *p = data, *end = data + n; (p = memchr(p, '\n', (size_t)(end - p))) != NULL; p++) {
        lines++;
    }
    if (s->lines_waiting == 0U && lines == 0U) {
        /* No line to run before these bytes: they join the line being read at once (no newline, nothing runs), so
         * that a line of any length never fills the input and stops the session. */
        session_feed(emu, s, data, n);
        return;
    }
    if (n > session_input_room(s) || !byte_buffer_append(&s->in, data, n, SESSION_INPUT_MAX)) {
        s->hang_up = "its input did not fit (out of memory)"; /* callers give no more than the room */
        return;
    }
    s->lines_waiting += lines;
}

bool session_busy(const emu_session_t *s) { return s->stream.step != NULL || s->lines_waiting > 0U; }

/* Whether the session may do a unit of work now: it has some, it goes on, and its reader keeps up. */
static bool may_run(const emu_session_t *s)
{
    return session_busy(s) && s->hang_up == NULL && !s->overflow &&
           (s->unread == NULL || s->unread->len < s->output_high);
}

/* The stream's line is complete: the events held meanwhile follow it. */
static void stream_end(emu_session_t *s)
{
    s->stream.step = NULL;
    if (s->held.len > 0U) {
        s->transport_write(s->transport_ctx, s->held.data, s->held.len); /* whole lines, one after the other */
        s->held.len = 0U;
    }
}

/* One unit: the next piece of the stream, or the next line (then, once no whole line waits, the start of a line
 * not yet complete goes to the line reader, which holds it). */
static void session_step(emu_t *emu, emu_session_t *s)
{
    if (s->stream.step != NULL) {
        if (!s->stream.step(emu, s)) {
            stream_end(s);
        }
        return;
    }
    const char *nl = memchr(s->in.data, '\n', s->in.len);
    const size_t n = (size_t)(nl - s->in.data) + 1U;
    s->lines_waiting--;
    session_feed(emu, s, s->in.data, n);
    byte_buffer_consume(&s->in, n);
    if (s->lines_waiting == 0U && s->in.len > 0U) {
        session_feed(emu, s, s->in.data, s->in.len);
        s->in.len = 0U;
    }
    if (s->hang_up != NULL || emu->quit) {
        s->lines_waiting = 0U; /* nothing more of it runs */
        s->in.len = 0U;
    }
}

/* Whether any session may do a unit of work now. */
static bool any_may_run(const emu_t *emu)
{
    for (size_t j = 0U; j < emu->n_sessions; j++) {
        if (may_run(emu->sessions[j])) {
            return !emu->quit;
        }
    }
    return false;
}

bool sessions_work(emu_t *emu, co_time_us_t stop_at)
{
    bool did = true;
    while (did && !emu->quit) {
        did = false;
        const size_t n = emu->n_sessions;
        for (size_t k = 0U; k < n && !emu->quit; k++) {
            const size_t i = (emu->session_turn + k) % n;
            emu_session_t *s = emu->sessions[i];
            if (!may_run(s)) {
                continue;
            }
            session_step(emu, s);
            did = true;
            if (socketcan_now_us() >= stop_at) { /* after the unit: the first one always runs */
                emu->session_turn = (i + 1U) % n; /* the next pass begins with the next session */
                return any_may_run(emu);
            }
        }
    }
    return false;
}

void session_work_units(emu_t *emu, emu_session_t *s, unsigned max_units)
{
    for (unsigned k = 0U; k < max_units && may_run(s) && !emu->quit; k++) {
        session_step(emu, s);
    }
}

bool session_stream_start(emu_session_t *s, const session_stream_t *stream)
{
    if (s->unread == NULL) {
        return false;
    }
    s->stream = *stream;
    return true;
}

void session_stream_write(emu_session_t *s, const char *data, size_t n) { s->transport_write(s->transport_ctx, data, n); }
