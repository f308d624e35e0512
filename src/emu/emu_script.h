/*
 * --script FILE: control commands at given times (docs/emulator.md "Scripts"). The whole file is read and
 * checked before any node starts; the main loop runs each line when its time has come.
 */
#ifndef EMU_SCRIPT_H
#define EMU_SCRIPT_H

#include <stdbool.h>
#include <stddef.h>

#include "co/co.h"

#define SCRIPT_LINE_MAX 512

typedef struct script_line {
    co_time_us_t at;        /* since the program's start */
    char text[SCRIPT_LINE_MAX];
} script_line_t;

typedef struct emu_script {
    script_line_t *lines;   /* malloc'd */
    size_t len;
    size_t pos;             /* the next line to run */
} emu_script_t;

/** Reads the script at path; false (and a message on stderr) if it cannot be read or has a bad line. */
bool script_load(emu_script_t *s, const char *path);

/** When the next line is due (µs since the start), or CO_NEVER when none is left. */
co_time_us_t script_next_at(const emu_script_t *s);

/** The next line, if it is due at `elapsed` (µs since the start), copied to line (it is split there in place);
 *  false when none is due. */
bool script_take_due(emu_script_t *s, co_time_us_t elapsed, char *line, size_t size);

void script_free(emu_script_t *s);

#endif /* EMU_SCRIPT_H */
