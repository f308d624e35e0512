/*
 * The emulator's text output: the log on stderr (one line per event, with the seconds since the start) and the
 * replies to control commands on stdout (one line each).
 */
#ifndef EMU_OUTPUT_H
#define EMU_OUTPUT_H

#include "co/co.h"

enum { LOG_QUIET = 0, LOG_NORMAL = 1, LOG_VERBOSE = 2 };

/** Log lines above log_level are not written; times in the log count from start. */
void output_init(co_time_us_t start, int log_level);

/** One log line of the given level (no newline in fmt). */
void logline(int level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/** One reply line on stdout (no newline in fmt). */
void reply(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#endif /* EMU_OUTPUT_H */
