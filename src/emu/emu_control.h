/*
 * Control commands from stdin (on a terminal, or with --control -): read without blocking when poll says so,
 * cut into lines, each run by the command language (emu_commands.h).
 */
#ifndef EMU_CONTROL_H
#define EMU_CONTROL_H

#include <stdbool.h>
#include <stddef.h>

#define CONTROL_BUFFER_SIZE 2048

struct emu;

typedef struct emu_control {
    bool enabled;           /* commands are read from stdin */
    bool open;              /* ... and it has not ended */
    char buf[CONTROL_BUFFER_SIZE];
    size_t fill;
} emu_control_t;

/** Makes stdin non-blocking and starts reading it (when enabled). */
void control_start(emu_control_t *c);

/** Reads what stdin has (poll said so) and runs each complete line on emu. */
void control_read(struct emu *emu);

#endif /* EMU_CONTROL_H */
