/*
 * A web session's stream (POST /api/session/ID/stream, docs/web.md): one HTTP answer that does not end on its own
 * and carries every line that waits for the session as the emulator makes it: the events it subscribed to and the
 * answers to the requests its exchanges posted. A page with a stream posts only when it has requests, so an idle
 * page makes no exchanges at all (an exchange costs about 20,000 instructions of libmicrohttpd's whatever it
 * carries: docs/decisions.md "The idle web exchange").
 *
 * While nothing waits, the stream's connection is suspended: libmicrohttpd neither polls it nor times it out. The
 * sessions' pass (emu_web_sessions.c) wakes it when lines have waited WEB_STREAM_BATCH_US (a busy trace's events go
 * in batches, not one write per frame), at once after an exchange that ran requests (their answers), and after
 * WEB_STREAM_KEEPALIVE_US of silence with an empty line: a suspended connection does not notice its peer leave,
 * the write does, and the page tells a stopped emulator from a quiet one. Once woken, the stream sends everything
 * that waits and is suspended again.
 */
#ifndef EMU_WEB_STREAM_H
#define EMU_WEB_STREAM_H

#include <stdbool.h>

struct MHD_Connection;
struct MHD_Response;
struct web_session;

typedef struct web_stream web_stream_t;

/** The answer (200, chunked, never ending by itself) of a stream request on connection c for session s; a stream
 *  s had before ends. NULL: out of memory. The caller queues it on c and releases it. */
struct MHD_Response *web_stream_open(struct web_session *s, struct MHD_Connection *c);

/** Lets the stream send what waits (and s->keepalive's empty line): resumes its connection. true when it was
 *  suspended: libmicrohttpd must run for it to send. */
bool web_stream_wake(web_stream_t *st);

/** Its session ends: the answer ends once what it holds is sent (woken: true as web_stream_wake). */
bool web_stream_end(web_stream_t *st);

#endif /* EMU_WEB_STREAM_H */
