/* The emulator's log and replies: see emu_output.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_output.h"

#include <stdarg.h>
#include <stdio.h>

#include "../linux/socketcan.h"

static co_time_us_t output_start;
static int output_log_level;

void output_init(co_time_us_t start, int log_level)
{
    output_start = start;
    output_log_level = log_level;
}

void logline(int level, const char *fmt, ...)
{
    if (level > output_log_level) {
        return;
    }
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    const co_time_us_t t = socketcan_now_us() - output_start;
    fprintf(stderr, "[%8.3f] %s\n", (double)t / 1e6, text);
}

void reply(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vprintf(fmt, ap);
    va_end(ap);
    (void)putchar('\n');
    fflush(stdout);
}
