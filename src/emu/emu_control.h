/*
 * Control commands from stdin (on a terminal, or with --control -): read without blocking when poll says so,
 * cut into lines (emu_lines.h), each run by the command language (emu_commands.h). A line that is too long or holds
 * a NUL byte is refused with a reply, and only that line.
 */
#ifndef EMU_CONTROL_H
#define EMU_CONTROL_H

#include <stdbool.h>
#include <stddef.h>

#include "emu_lines.h"

struct emu;

typedef struct emu_control {
    bool enabled;           /* commands are read from stdin */
    bool open;              /* ... and it has not ended */
    line_reader_t lines;
} emu_control_t;

/** Makes stdin non-blocking (until the program ends: emu_fd_flags.h) and starts reading it (when enabled). */
void control_start(emu_control_t *c);

/** Reads what stdin has (poll said so) and runs each complete line on emu; at its end, the last line too. */
void control_read(struct emu *emu);

#endif /* EMU_CONTROL_H */
