/*
 * Log lines at a bounded rate: those a client outside the program causes at will (a refused connection, a control
 * client hung up, a refused web request). One looping client wrote 89 KiB/s of "refused" lines, also with -q,
 * which buried everything else and filled the disk of a CI job. Per kind of line: the first LOG_LIMIT_LINES of
 * each LOG_LIMIT_WINDOW_US are written; the rest are counted, and the count is written once the window ends.
 */
#ifndef EMU_LOG_LIMIT_H
#define EMU_LOG_LIMIT_H

#include <stdbool.h>

#include "co/co.h"

#define LOG_LIMIT_WINDOW_US 5000000U
#define LOG_LIMIT_LINES 3U

typedef struct log_limit {
    const char *what;           /* names the lines in the count: "refused control connections" */
    int level;                  /* the log level of the lines and their count */
    co_time_us_t window_start;
    unsigned logged;            /* lines written in this window */
    unsigned long suppressed;   /* lines not written in this window */
} log_limit_t;

/** A limiter of lines named what (in the count's line), at level (emu_output.h: LOG_QUIET...). */
void log_limit_init(log_limit_t *l, const char *what, int level);

/** Writes the line (as logline) unless LOG_LIMIT_LINES were written in this window; counts it then. now: the
 *  program's clock (socketcan_now_us). */
void log_limited(log_limit_t *l, co_time_us_t now, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/** Writes the count of the lines not written once their window ended (call once per pass; cheap). */
void log_limit_tick(log_limit_t *l, co_time_us_t now);

#endif /* EMU_LOG_LIMIT_H */
