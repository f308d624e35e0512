/* The emulator's log and replies, never blocking: see emu_output.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_output.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "socketcan.h"
#include "text_escape.h"

/* Longest line (the log's time prefix and text, or a multi-line reply) with its newline: one write of at most
 * PIPE_BUF bytes takes it whole. */
#define LINE_BYTES PIPE_BUF

typedef enum write_method {
    WRITE_PLAIN,       /* a regular file, or a private non-blocking file of a pipe, FIFO or terminal */
    WRITE_SEND,        /* a socket: send(MSG_DONTWAIT) */
    WRITE_AFTER_POLL,  /* a shared blocking pipe or terminal: only when poll says it has room, PIPE_BUF at most */
    WRITE_NOWHERE      /* closed at the start, or its reader has gone: discarded */
} write_method_t;

typedef struct output_stream {
    const char *name;       /* "stderr", "stdout" */
    const char *what;       /* "log", "reply": for the drop report */
    int fd;
    write_method_t how;
    char ring[OUTPUT_BUFFER_SIZE];
    size_t head;            /* first byte waiting */
    size_t len;             /* bytes waiting */
    bool dropping;          /* lines are dropped until the ring has drained to half */
    unsigned long dropped_lines, dropped_bytes;             /* since the last report */
    unsigned long dropped_lines_total, dropped_bytes_total;
} output_stream_t;

enum { STREAM_LOG = 0, STREAM_REPLY = 1, N_STREAMS = 2 };

static output_stream_t streams[N_STREAMS] = {{.name = "stderr", .what = "log", .fd = STDERR_FILENO},
                                             {.name = "stdout", .what = "reply", .fd = STDOUT_FILENO}};
static co_time_us_t output_start;
static int output_log_level;
static bool output_ready;
/* See emu_output.h. */
bool output_busy;

static void setup(output_stream_t *s)
{
    struct stat st;
    if (fstat(s->fd, &st) != 0) {
        s->how = WRITE_NOWHERE; /* closed when the program started */
        return;
    }
    if (S_ISREG(st.st_mode) || S_ISBLK(st.st_mode)) {
        s->how = WRITE_PLAIN;
        return;
    }
    if (S_ISSOCK(st.st_mode)) {
        s->how = WRITE_SEND;
        return;
    }
    /* O_NONBLOCK on the inherited file would be seen by every process sharing it (the shell on a terminal, another
     * writer to the same pipe): a file of our own on the same pipe or terminal instead. */
    char path[64];
    (void)snprintf(path, sizeof path, "/proc/self/fd/%d", s->fd);
    const int own = open(path, O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (own >= 0) {
        s->fd = own;
        s->how = WRITE_PLAIN;
    } else {
        s->how = WRITE_AFTER_POLL;
    }
}

void output_init(co_time_us_t start, int log_level)
{
    output_start = start;
    output_log_level = log_level;
    signal(SIGPIPE, SIG_IGN); /* a reader that has gone is an error of the write, not the end of the program */
    for (int i = 0; i < N_STREAMS; i++) {
        setup(&streams[i]);
    }
    output_ready = true;
    (void)atexit(output_finish);
}

static void ring_put(output_stream_t *s, const char *data, size_t n)
{
    const size_t tail = (s->head + s->len) % OUTPUT_BUFFER_SIZE;
    const size_t first = n < OUTPUT_BUFFER_SIZE - tail ? n : OUTPUT_BUFFER_SIZE - tail;
    memcpy(s->ring + tail, data, first);
    memcpy(s->ring, data + first, n - first);
    s->len += n;
    output_busy = true;
}

static void drop(output_stream_t *s, unsigned long lines, size_t bytes)
{
    output_busy = true;
    s->dropped_lines += lines;
    s->dropped_bytes += bytes;
    s->dropped_lines_total += lines;
    s->dropped_bytes_total += bytes;
}

static unsigned long newlines(const char *text, size_t n)
{
    unsigned long count = 0U;
    for (size_t i = 0U; i < n; i++) {
        count += text[i] == '\n' ? 1U : 0U;
    }
    return count;
}

/* A stream that has drained to half takes lines again; the report of its gap goes to the log once the log has room
 * for it (the log may be the stream that is still full), until then the counts wait and add up. */
static void report_gap(output_stream_t *s);

static void resume_once_drained(output_stream_t *s)
{
    if (s->dropping && s->len <= OUTPUT_BUFFER_SIZE / 2U) {
        s->dropping = false;
    }
    const output_stream_t *log = &streams[STREAM_LOG];
    if (s->dropped_lines == 0U || s->dropping || log->dropping || log->how == WRITE_NOWHERE) {
        return;
    }
    report_gap(s);
}

/* Out of line: the common case (nothing dropped) must not pay for the line buffer's stack frame. */
static __attribute__((noinline)) void report_gap(output_stream_t *s)
{
    output_stream_t *log = &streams[STREAM_LOG];
    char line[LINE_BYTES];
    const co_time_us_t t = socketcan_now_us() - output_start;
    const int n = s->how == WRITE_NOWHERE
                      ? snprintf(line, sizeof line, "[%8.3f] %lu %s line(s) (%lu bytes) dropped: %s cannot be written\n",
                                 (double)t / 1e6, s->dropped_lines, s->what, s->dropped_bytes, s->name)
                      : snprintf(line, sizeof line, "[%8.3f] %lu %s line(s) (%lu bytes) dropped: output blocked (%s was "
                                 "not read)\n", (double)t / 1e6, s->dropped_lines, s->what, s->dropped_bytes, s->name);
    if (n <= 0 || (size_t)n > OUTPUT_BUFFER_SIZE - log->len) {
        return;
    }
    ring_put(log, line, (size_t)n);
    s->dropped_lines = 0U;
    s->dropped_bytes = 0U;
}

/* A whole line (with its newline) to a stream, or dropped whole. */
static void append(int stream, const char *line, size_t n)
{
    output_stream_t *s = &streams[stream];
    if (s->how == WRITE_NOWHERE) {
        drop(s, newlines(line, n), n);
        return;
    }
    resume_once_drained(s);
    if (s->dropping || n > OUTPUT_BUFFER_SIZE - s->len) {
        s->dropping = true;
        drop(s, newlines(line, n), n);
        return;
    }
    ring_put(s, line, n);
}

/* Formats "prefix" + fmt (escaped: text_escape.h) + newline and appends it; a line cut to LINE_BYTES still ends with
 * its newline. */
static void append_formatted(int stream, const char *prefix, text_lines_t lines, const char *fmt, va_list ap)
{
    char text[LINE_BYTES];
    const int n = vsnprintf(text, sizeof text, fmt, ap);
    const size_t text_len = n < 0 ? 0U : (size_t)n < sizeof text ? (size_t)n : sizeof text - 1U;
    char line[LINE_BYTES];
    const size_t p = strlen(prefix);
    memcpy(line, prefix, p);
    size_t len = p + text_escape(line + p, sizeof line - p - 1U, text, text_len, lines);
    line[len++] = '\n';
    if (!output_ready) { /* not set up yet: the program has not started its nodes */
        (void)fwrite(line, 1U, len, stream == STREAM_LOG ? stderr : stdout);
        return;
    }
    append(stream, line, len);
}

void logline(int level, const char *fmt, ...)
{
    if (level > output_log_level) {
        return;
    }
    char prefix[32];
    const co_time_us_t t = socketcan_now_us() - output_start;
    (void)snprintf(prefix, sizeof prefix, "[%8.3f] ", (double)t / 1e6);
    va_list ap;
    va_start(ap, fmt);
    append_formatted(STREAM_LOG, prefix, TEXT_ONE_LINE, fmt, ap);
    va_end(ap);
}

void output_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    append_formatted(STREAM_LOG, "canopen-emu: ", TEXT_ONE_LINE, fmt, ap);
    va_end(ap);
}

void output_reply_line(const char *line, size_t len)
{
    if (!output_ready) {
        (void)fwrite(line, 1U, len, stdout);
        return;
    }
    append(STREAM_REPLY, line, len);
}

/* output_stdout_replies: the reply and its newline, a whole line of the reply stream. */
static void write_stdout_reply(void *ctx, const char *text, size_t len)
{
    (void)ctx;
    char line[LINE_BYTES];
    if (len > sizeof line - 1U) {
        len = sizeof line - 1U;
    }
    memcpy(line, text, len);
    line[len++] = '\n';
    output_reply_line(line, len);
}

const reply_sink_t output_stdout_replies = {write_stdout_reply, NULL};

void reply(const reply_sink_t *to, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char text[LINE_BYTES];
    const int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    const size_t text_len = n < 0 ? 0U : (size_t)n < sizeof text ? (size_t)n : sizeof text - 1U;
    char shown[LINE_BYTES];
    const size_t len = text_escape(shown, sizeof shown - 1U, text, text_len, TEXT_LINES);
    shown[len] = '\0'; /* a sink may read it as a string */
    to->write(to->ctx, shown, len);
}

static bool has_room(int fd)
{
    struct pollfd p = {fd, POLLOUT, 0};
    return poll(&p, 1U, 0) == 1 && (p.revents & POLLOUT) != 0;
}

/* Writes the next whole lines, at most PIPE_BUF bytes: a pipe takes such a write whole or not at all, so lines of
 * stdout and stderr sharing one pipe (2>&1) never cut into each other. false when the file takes no more for now. */
static bool write_some(output_stream_t *s)
{
    char chunk[PIPE_BUF];
    size_t n = s->len < sizeof chunk ? s->len : sizeof chunk;
    const size_t first = n < OUTPUT_BUFFER_SIZE - s->head ? n : OUTPUT_BUFFER_SIZE - s->head;
    memcpy(chunk, s->ring + s->head, first);
    memcpy(chunk + first, s->ring, n - first);
    while (n > 0U && chunk[n - 1U] != '\n') {
        n--; /* every line ends with its newline and is at most LINE_BYTES <= PIPE_BUF long: one fits */
    }
    if (s->how == WRITE_AFTER_POLL && !has_room(s->fd)) {
        return false; /* a pipe has room for PIPE_BUF bytes when poll says so, a terminal for some */
    }
    const ssize_t w = s->how == WRITE_SEND ? send(s->fd, chunk, n, MSG_DONTWAIT | MSG_NOSIGNAL) : write(s->fd, chunk, n);
    if (w > 0) {
        s->head = (s->head + (size_t)w) % OUTPUT_BUFFER_SIZE;
        s->len -= (size_t)w;
        return true;
    }
    if (w < 0 && errno == EINTR) {
        return true;
    }
    if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
        return false;
    }
    /* The reader has gone (EPIPE) or the file fails: nothing more can be written there, ever. */
    const size_t end = s->len < OUTPUT_BUFFER_SIZE - s->head ? s->len : OUTPUT_BUFFER_SIZE - s->head;
    drop(s, newlines(s->ring + s->head, end) + newlines(s->ring, s->len - end), s->len);
    s->len = 0U;
    s->how = WRITE_NOWHERE;
    return false;
}

bool output_flush_busy(void)
{
    for (int i = 0; i < N_STREAMS; i++) {
        output_stream_t *s = &streams[i];
        while (s->len > 0U && s->how != WRITE_NOWHERE && write_some(s)) {
        }
    }
    for (int i = 0; i < N_STREAMS; i++) { /* the log first: the reports of both go there */
        resume_once_drained(&streams[i]);
    }
    bool idle = true;
    for (int i = 0; i < N_STREAMS; i++) {
        idle = idle && streams[i].len == 0U && !streams[i].dropping && streams[i].dropped_lines == 0U;
    }
    output_busy = !idle;
    return output_busy;
}

nfds_t output_poll_fds(struct pollfd *pfd)
{
    nfds_t n = 0U;
    if (!output_busy) {
        return 0U; /* both streams empty (output_flush found them so) */
    }
    for (int i = 0; i < N_STREAMS; i++) {
        if (streams[i].len > 0U && streams[i].how != WRITE_NOWHERE) {
            pfd[n].fd = streams[i].fd;
            pfd[n].events = POLLOUT;
            pfd[n].revents = 0;
            n++;
        }
    }
    return n;
}

static bool anything_waiting(void)
{
    for (int i = 0; i < N_STREAMS; i++) {
        if (streams[i].len > 0U && streams[i].how != WRITE_NOWHERE) {
            return true;
        }
    }
    return false;
}

/* Flushes until nothing waits or the deadline passes, sleeping in poll meanwhile. */
static void drain_until(co_time_us_t deadline)
{
    for (;;) {
        (void)output_flush();
        const co_time_us_t now = socketcan_now_us();
        if (!anything_waiting() || now >= deadline) {
            return;
        }
        struct pollfd pfd[N_STREAMS];
        const nfds_t n = output_poll_fds(pfd);
        const co_time_us_t wait_ms = (deadline - now + 999U) / 1000U;
        (void)poll(pfd, n, (int)wait_ms);
    }
}

void output_finish(void)
{
    if (!output_ready) {
        return;
    }
    const co_time_us_t deadline = socketcan_now_us() + (co_time_us_t)OUTPUT_EXIT_WAIT_MS * 1000U;
    drain_until(deadline); /* first what waits, so that the totals find room */
    const output_stream_t *log = &streams[STREAM_LOG];
    const output_stream_t *rep = &streams[STREAM_REPLY];
    if (log->dropped_lines_total > 0U || rep->dropped_lines_total > 0U) {
        const unsigned long log_lines = log->dropped_lines_total, log_bytes = log->dropped_bytes_total;
        streams[STREAM_LOG].dropping = false; /* the last word: in if there is room at all */
        logline(LOG_QUIET, "%lu log line(s) (%lu bytes) and %lu reply line(s) (%lu bytes) dropped in all: output "
                "blocked", log_lines, log_bytes, rep->dropped_lines_total, rep->dropped_bytes_total);
    }
    drain_until(deadline);
    output_ready = false;
}
