/*
 * The command language of canopen-emu (docs/emulator.md "Command language"): one command line from stdin or a
 * script, run on the nodes it names; replies go to stdout (emu_output.h).
 */
#ifndef EMU_COMMANDS_H
#define EMU_COMMANDS_H

#include "emu.h"

/** Most words a command line may have (the longest command, emcy, has 8). */
#define MAX_ARGS 16

/** Runs one command line (without its newline; it is split in place). `quit` sets emu->quit. */
void run_command(emu_t *emu, char *line);

#endif /* EMU_COMMANDS_H */
