/*
 * --script FILE: control commands at given times (docs/emulator.md "Scripts"). The whole file is read and
 * checked before any node starts; the main loop runs each line when its time has come.
 */
#ifndef EMU_SCRIPT_H
#define EMU_SCRIPT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "co/co.h"

/** The latest time a script line may have, in ms after the start (about 11.6 days). A bound far below what
 *  overflows: a time just below 2^64 µs wrapped the loop's deadline (100 % CPU while idle). */
#define SCRIPT_TIME_MAX_MS 1000000000ULL

/** The script lines the main loop runs in one pass at most (the rest of those due in the next passes). */
#define SCRIPT_LINES_PER_PASS 64U

typedef struct script_line {
    co_time_us_t at;        /* since the program's start */
    char *text;             /* malloc'd */
} script_line_t;

typedef struct emu_script {
    script_line_t *lines;   /* malloc'd */
    size_t len;
    size_t pos;             /* the next line to run */
} emu_script_t;

/** Reads the script at path; false (and a message on stderr naming the line) if it cannot be read, is a directory,
 *  or has a bad line: a bad time, a line longer than COMMAND_LINE_MAX bytes, a NUL byte. */
bool script_load(emu_script_t *s, const char *path);

/** script_load's reading and checking of an open file (fd is read to its end, not closed), with name in the
 *  messages and the messages on err: the seam of the fuzz target tests/fuzz/target_script.c. */
bool script_read(emu_script_t *s, int fd, const char *name, FILE *err);

/** When the next line is due (µs since the start), or CO_NEVER when none is left (inline: asked at every pass). */
static inline co_time_us_t script_next_at(const emu_script_t *s)
{
    return s->pos < s->len ? s->lines[s->pos].at : CO_NEVER;
}

/** The next line, if it is due at `elapsed` (µs since the start), copied to line (it is split there in place);
 *  false when none is due. */
bool script_take_due(emu_script_t *s, co_time_us_t elapsed, char *line, size_t size);

void script_free(emu_script_t *s);

#endif /* EMU_SCRIPT_H */
