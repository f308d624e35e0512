/* Log lines at a bounded rate: see emu_log_limit.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_log_limit.h"

#include <stdarg.h>
#include <stdio.h>

#include "runtime/emu_output.h"

void log_limit_init(log_limit_t *l, const char *what, int level)
{
    l->what = what;
    l->level = level;
    l->window_start = 0U;
    l->logged = 0U;
    l->suppressed = 0U;
}

void log_limit_tick(log_limit_t *l, co_time_us_t now)
{
    if (l->logged == 0U || now - l->window_start < LOG_LIMIT_WINDOW_US) {
        return;
    }
    if (l->suppressed > 0U) {
        logline(l->level, "%lu more %s in %u s (not shown one by one)", l->suppressed, l->what,
                LOG_LIMIT_WINDOW_US / 1000000U);
    }
    l->logged = 0U;
    l->suppressed = 0U;
}

void log_limited(log_limit_t *l, co_time_us_t now, const char *fmt, ...)
{
    log_limit_tick(l, now);
    if (l->logged == 0U) {
        l->window_start = now;
    }
    if (l->logged == LOG_LIMIT_LINES) {
        l->suppressed++;
        return;
    }
    l->logged++;
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    logline(l->level, "%s", line);
}
