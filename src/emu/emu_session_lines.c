/* A session's byte stream cut into lines: see emu_session.h (session_feed, session_finish). Apart from the
 * protocol (emu_session.c), as the transports' side of it: a line that cannot be a command is refused here, in
 * the framing it seems to have, and only the others are handed to session_run_line. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include <string.h>

#include "emu.h"
#include "emu_json.h"
#include "emu_session.h"

static void on_line(void *ctx, line_verdict_t verdict, char *text, unsigned long lineno)
{
    void **pair = (void **)ctx;
    emu_t *emu = (emu_t *)pair[0];
    emu_session_t *s = (emu_session_t *)pair[1];
    if (emu->quit) {
        return; /* the program is stopping: what came after `quit` in the same read does not run */
    }
    const bool json = verdict != LINE_OK ? text[strspn(text, " \t\r")] == '{' : false;
    if (verdict == LINE_TOO_LONG) {
        if (json) {
            json_error(s, "line %lu is longer than %d bytes: ignored", lineno, COMMAND_LINE_MAX);
        } else {
            session_printf(s, "error: %s line %lu is longer than %d bytes: ignored", s->name, lineno, COMMAND_LINE_MAX);
        }
    } else if (verdict == LINE_HAS_NUL) {
        if (json) {
            json_error(s, "line %lu holds a NUL byte: ignored", lineno);
        } else {
            session_printf(s, "error: %s line %lu holds a NUL byte: ignored", s->name, lineno);
        }
    } else {
        session_run_line(emu, s, text);
    }
}

void session_feed(emu_t *emu, emu_session_t *s, const char *data, size_t n)
{
    void *pair[2] = {emu, s};
    line_reader_feed(&s->lines, data, n, on_line, pair);
}

void session_finish(emu_t *emu, emu_session_t *s)
{
    void *pair[2] = {emu, s};
    line_reader_finish(&s->lines, on_line, pair);
}
