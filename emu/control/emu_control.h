/*
 * Control commands from stdin (on a terminal, or with --control -): read without blocking when poll says so, and
 * run as the lines of a control session (emu_session.h: the command language, or JSON requests), answered on
 * stdout. A line that is too long or holds a NUL byte is refused with a reply, and only that line.
 */
#ifndef EMU_CONTROL_H
#define EMU_CONTROL_H

#include <stdbool.h>
#include <stddef.h>

#include "control/emu_session.h"

struct emu;

typedef struct emu_control {
    bool enabled;           /* commands are read from stdin */
    bool open;              /* ... and it has not ended */
    emu_session_t session;
} emu_control_t;

/** Makes stdin non-blocking (until the program ends: emu_fd_flags.h) and starts reading it (when enabled). */
void control_start(struct emu *emu);

/** Reads what stdin has (poll said so) and runs each complete line on emu; at its end, the last line too. */
void control_read(struct emu *emu);

#endif /* EMU_CONTROL_H */
