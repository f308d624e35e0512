/* A web session's stream: see emu_web_stream.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web_stream.h"

#include <stdlib.h>
#include <string.h>

#include "web/emu_web_http.h"
#include "web/emu_web_sessions.h"

struct web_stream {
    web_session_t *session;         /* NULL once the session ended: the answer ends */
    struct MHD_Connection *connection;
    char *chunk;                    /* lines taken from the session, being sent */
    size_t len, sent;
    bool suspended;                 /* nothing waited: its connection is out of libmicrohttpd's polling */
};

/* libmicrohttpd asks for the next bytes of the answer (the socket can take them). */
static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    web_stream_t *st = (web_stream_t *)cls;
    (void)pos;
    if (st->sent == st->len) {
        free(st->chunk);
        st->chunk = NULL;
        st->len = st->sent = 0U;
        if (st->session == NULL) {
            return MHD_CONTENT_READER_END_OF_STREAM;
        }
        st->chunk = web_session_take_output(st->session, &st->len);
        if (st->chunk == NULL) {
            if (st->session->keepalive) {
                st->session->keepalive = false;
                buf[0] = '\n';
                return 1;
            }
            /* Nothing waits: out of the polling until the sessions' pass wakes it (0: nothing now). */
            st->suspended = true;
            MHD_suspend_connection(st->connection);
            return 0;
        }
    }
    const size_t n = st->len - st->sent < max ? st->len - st->sent : max;
    memcpy(buf, st->chunk + st->sent, n);
    st->sent += n;
    return (ssize_t)n;
}

/* The answer is done with (ended, or its connection closed): the session no longer has a stream. */
static void stream_free(void *cls)
{
    web_stream_t *st = (web_stream_t *)cls;
    if (st->session != NULL) {
        st->session->stream = NULL;
    }
    free(st->chunk);
    free(st);
}

struct MHD_Response *web_stream_open(web_session_t *s, struct MHD_Connection *c)
{
    web_stream_t *st = calloc(1U, sizeof *st);
    if (st == NULL) {
        return NULL;
    }
    /* MHD_SIZE_UNKNOWN: chunked; the block size is what libmicrohttpd asks at most per call of stream_read. */
    struct MHD_Response *r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 4096U, stream_read, st, stream_free);
    if (r == NULL) {
        free(st);
        return NULL;
    }
    if (MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "application/x-ndjson") != MHD_YES ||
        !web_add_headers(r, true)) {
        MHD_destroy_response(r); /* frees st */
        return NULL;
    }
    if (s->stream != NULL && web_stream_end(s->stream)) {
        s->web->run_again = true;
    }
    st->session = s;
    st->connection = c;
    s->stream = st;
    s->keepalive = false;
    return r;
}

bool web_stream_wake(web_stream_t *st)
{
    if (!st->suspended) {
        return false;
    }
    st->suspended = false;
    MHD_resume_connection(st->connection);
    return true;
}

bool web_stream_end(web_stream_t *st)
{
    if (st->session != NULL) {
        st->session->stream = NULL;
        st->session = NULL;
    }
    return web_stream_wake(st);
}
