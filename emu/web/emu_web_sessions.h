/*
 * The web view's sessions (emu_web.h): each a control session (emu_session.h) with an id of 128 random bits, the
 * request lines of its exchanges that still wait to run, and its output waiting for the next exchange. The HTTP
 * side (emu_web.c) only creates, finds and exchanges with them; the main loop's pass runs what waits and removes
 * the ones that expired or overflowed.
 */
#ifndef EMU_WEB_SESSIONS_H
#define EMU_WEB_SESSIONS_H

#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"
#include "control/emu_buffer.h"
#include "control/emu_session.h"
#include "web/emu_web.h"

struct emu;

typedef struct web_session {
    emu_session_t session;
    emu_web_t *web;
    unsigned long number;           /* for the log: "web session 3" */
    char id[WEB_ID_HEX + 1];
    byte_buffer_t out;              /* answers and events since the last exchange, or not yet on the stream */
    bool overflow;                  /* more than WEB_OUTPUT_MAX waited: dropped at the next pass */
    co_time_us_t last_exchange;     /* or the last pass, while it has a stream: it does not expire then */
    struct web_stream *stream;      /* its stream (emu_web_stream.h); NULL: none, the lines wait for an exchange */
    struct web_socket *socket;      /* its WebSocket (emu_web_socket.h), instead of a stream; NULL: none */
    co_time_us_t waiting_since;     /* when lines began to wait for the stream; CO_NEVER: none wait */
    co_time_us_t quiet_since;       /* when the stream was last woken (its keep-alive counts from there) */
    bool send_now;                  /* an exchange ran requests: their answers go at once, not after the batch */
    bool keepalive;                 /* the stream sends an empty line when nothing else waits */
} web_session_t;

/** Random bytes as lowercase hex (2 * n digits and a NUL into out). false when the system has no randomness. */
bool web_random_hex(char *out, size_t n);

/** A new session, registered for events; NULL when WEB_SESSIONS_MAX exist already (*full set) or it could not be
 *  made. */
web_session_t *web_session_open(struct emu *emu, emu_web_t *w, co_time_us_t now, bool *full);

/** The session with this id, or NULL (compared in constant time: an id is a credential). */
web_session_t *web_session_find(emu_web_t *w, const char *id);

/** An exchange's request lines: queued behind what still waits in the session (a last line without newline is
 *  ended), then up to WEB_EXCHANGE_UNITS units of its work run at once. false, with nothing queued, when they do not
 *  fit beside what waits. */
bool web_session_queue(struct emu *emu, web_session_t *s, const char *body, size_t len, co_time_us_t now);

/** What waits for the browser, handed over (free() it; NULL when nothing waits). */
char *web_session_take_output(web_session_t *s, size_t *len);

/** Removes a session: unregistered from events, freed. why (for the log) is NULL for a quiet removal. */
void web_session_remove(struct emu *emu, emu_web_t *w, web_session_t *s, int log_level, const char *why);

/** Once per pass: removes the sessions that overflowed or expired (logged; one with a stream does not expire) and
 *  wakes the streams whose lines are due (emu_web_stream.h). Their requests run in sessions_work. true when a
 *  stream was woken or ended: libmicrohttpd must run. */
bool web_sessions_service(struct emu *emu, emu_web_t *w, co_time_us_t now);

/** The sessions' next deadline: now when one overflowed, else the earliest expiry, batch end or keep-alive;
 *  CO_NEVER with none. Stamps when lines began to wait for a stream (called after the pass that wrote them). */
co_time_us_t web_sessions_deadline(emu_web_t *w, co_time_us_t now);

#endif /* EMU_WEB_SESSIONS_H */
