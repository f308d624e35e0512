/* Control commands from stdin: see emu_control.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_control.h"

#include <errno.h>
#include <unistd.h>

#include "runtime/emu.h"
#include "runtime/emu_events.h"
#include "runtime/emu_fd_flags.h"
#include "runtime/emu_output.h"

static void write_stdout(void *ctx, const char *line, size_t len)
{
    (void)ctx;
    output_reply_line(line, len);
}

void control_start(struct emu *emu)
{
    emu_control_t *c = &emu->control;
    session_init(&c->session, "stdin", write_stdout, NULL);
    if (c->enabled) {
        (void)fd_flags_set_nonblock(STDIN_FILENO); /* cleared again at exit */
        c->open = true;
        events_add_session(emu, &c->session);
    }
}

void control_read(struct emu *emu)
{
    emu_control_t *c = &emu->control;
    char chunk[4096];
    const ssize_t r = read(STDIN_FILENO, chunk, sizeof chunk);
    if (r > 0) {
        session_feed(emu, &c->session, chunk, (size_t)r);
    } else if (r == 0 || (errno != EAGAIN && errno != EINTR)) {
        session_finish(emu, &c->session);
        c->open = false; /* end of input: keep running (stop with a signal or 'quit'); events still go to stdout */
    }
}
