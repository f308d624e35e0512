/* Control commands from stdin: see emu_control.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_control.h"

#include <errno.h>
#include <unistd.h>

#include "emu.h"
#include "emu_commands.h"
#include "emu_fd_flags.h"
#include "emu_output.h"

void control_start(emu_control_t *c)
{
    line_reader_init(&c->lines);
    if (c->enabled) {
        (void)fd_flags_set_nonblock(STDIN_FILENO); /* cleared again at exit */
        c->open = true;
    }
}

static void control_line(void *ctx, line_verdict_t verdict, char *text, unsigned long lineno)
{
    emu_t *emu = (emu_t *)ctx;
    if (emu->quit) {
        /* The lines after `quit` that came in the same read: the program is stopping, and whether they arrived in
         * that read or the next one is chance (a pipe may deliver both at once), so none of them runs. */
        return;
    }
    if (verdict == LINE_TOO_LONG) {
        reply("error: stdin line %lu is longer than %d bytes: ignored", lineno, COMMAND_LINE_MAX);
    } else if (verdict == LINE_HAS_NUL) {
        reply("error: stdin line %lu holds a NUL byte: ignored", lineno);
    } else {
        run_command(emu, text);
    }
}

void control_read(struct emu *emu)
{
    emu_control_t *c = &emu->control;
    char chunk[4096];
    const ssize_t r = read(STDIN_FILENO, chunk, sizeof chunk);
    if (r > 0) {
        line_reader_feed(&c->lines, chunk, (size_t)r, control_line, emu);
    } else if (r == 0 || (errno != EAGAIN && errno != EINTR)) {
        line_reader_finish(&c->lines, control_line, emu);
        c->open = false; /* end of input: keep running (stop with a signal or 'quit') */
    }
}
