/*
 * The emulator's text output: the log on stderr (one line per event, with the seconds since the start) and the
 * replies to control commands on stdout (one line each).
 *
 * Output never stops the nodes. A reader that does not read (`canopen-emu ... 2>&1 | less` left alone) fills the
 * pipe, and a write would then block the whole process: no SDO answers, no heartbeats. So each stream has a ring
 * buffer of OUTPUT_BUFFER_SIZE bytes; lines go there whole, and the main loop writes them out without ever blocking
 * (output_flush, and POLLOUT from output_poll_fds while bytes wait). When a line does not fit, it is dropped whole
 * and counted; once the buffer has drained to half, a log line says how many were dropped ("N log line(s) (M bytes)
 * dropped: output blocked ..."), and the totals are in the exit summary. At exit, what is buffered is written with
 * a bounded wait (OUTPUT_EXIT_WAIT_MS).
 *
 * Nothing is made non-blocking that other processes share: a pipe, FIFO or terminal is opened again through
 * /proc/self/fd as the program's own non-blocking file (another writer to the same pipe keeps a blocking one); a
 * socket is written with MSG_DONTWAIT; a regular file never waits for a reader and is written as it is. Where
 * /proc cannot be used, a pipe or terminal is written only when poll says it has room, at most PIPE_BUF bytes at
 * a time.
 */
#ifndef EMU_OUTPUT_H
#define EMU_OUTPUT_H

#include <poll.h>
#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"

enum { LOG_QUIET = 0, LOG_NORMAL = 1, LOG_VERBOSE = 2 };

/** Bytes each stream buffers while its reader does not read. */
#define OUTPUT_BUFFER_SIZE (64U * 1024U)
/** How long the exit waits at most for a reader to take what is buffered. */
#define OUTPUT_EXIT_WAIT_MS 1000

/** Sets up both streams; log lines above log_level are not written; times in the log count from start. Writes at
 *  exit what is buffered (registered with atexit). Before it, and for messages about the command line, stdio. */
void output_init(co_time_us_t start, int log_level);

/** One log line of the given level (no newline in fmt; escaped as text_escape.h says, line breaks too). */
void logline(int level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/** A fatal message, "canopen-emu: ..." on the log stream whatever the log level (no newline in fmt). */
void output_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/** Where the reply lines of a command go (an argument of every command: run_command, faults_command ...): write
 *  takes each reply as one call, escaped as text_escape.h says (its line breaks kept), without its newline (a
 *  multi-line reply has newlines inside), NUL-terminated after len. */
typedef struct reply_sink {
    void (*write)(void *ctx, const char *text, size_t len);
    void *ctx;
} reply_sink_t;

/** The reply stream: stdout, one line each. */
extern const reply_sink_t output_stdout_replies;

/** One reply to `to` (no newline in fmt). */
void reply(const reply_sink_t *to, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/** One whole line (newline included) on stdout as it is: the stdin session's output. */
void output_reply_line(const char *line, size_t len);

/** A line was put or dropped since output_flush last found both streams idle (read only: the output module's). */
extern bool output_busy;

/** output_flush's work when output_busy. */
bool output_flush_busy(void);

/** Writes what the streams can take now, without blocking. Call once per pass of the main loop. Returns whether
 *  bytes wait still (or drops wait to be reported): only then has output_poll_fds anything to add. Inline: the
 *  common pass, nothing logged, costs the loop a test, not a call. */
static inline bool output_flush(void) { return output_busy && output_flush_busy(); }

/** Adds a POLLOUT entry to pfd for each stream with bytes waiting (at most 2); returns how many. */
nfds_t output_poll_fds(struct pollfd *pfd);

/** The drop totals if any, then what is buffered, waiting at most OUTPUT_EXIT_WAIT_MS for the readers. */
void output_finish(void);

#endif /* EMU_OUTPUT_H */
