/* Control commands from stdin: see emu_control.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_control.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <unistd.h>

#include "emu.h"
#include "emu_commands.h"

void control_start(emu_control_t *c)
{
    if (c->enabled) {
        (void)fcntl(STDIN_FILENO, F_SETFL, fcntl(STDIN_FILENO, F_GETFL) | O_NONBLOCK);
        c->open = true;
    }
}

void control_read(struct emu *emu)
{
    emu_control_t *c = &emu->control;
    const ssize_t r = read(STDIN_FILENO, c->buf + c->fill, sizeof c->buf - c->fill - 1U);
    if (r <= 0) {
        if (r == 0 || (errno != EAGAIN && errno != EINTR)) {
            c->open = false; /* end of input: keep running (stop with a signal or 'quit') */
        }
        return;
    }
    c->fill += (size_t)r;
    c->buf[c->fill] = '\0';
    char *start = c->buf;
    char *nl;
    while ((nl = strchr(start, '\n')) != NULL) {
        *nl = '\0';
        run_command(emu, start);
        start = nl + 1;
    }
    c->fill = strlen(start);
    memmove(c->buf, start, c->fill);
    if (c->fill >= sizeof c->buf - 1U) {
        c->fill = 0U; /* an overlong line is dropped */
    }
}
