/*
 * Cuts a byte stream (stdin, a script file) into command lines. A line is what comes before a newline, at most
 * COMMAND_LINE_MAX bytes. A longer line is refused whole and the rest of it, up to its newline, is discarded: its
 * tail must never run as a command of its own (a long comment ending in "quit" quit the emulator). A line holding a
 * NUL byte is refused too, and only that line (C strings would cut it there and glue the rest to the next line).
 */
#ifndef EMU_LINES_H
#define EMU_LINES_H

#include <stdbool.h>
#include <stddef.h>

/** Longest command line, in bytes without its newline. */
#define COMMAND_LINE_MAX 2047

typedef enum line_verdict {
    LINE_OK = 0,
    LINE_TOO_LONG = 1,   /**< more than COMMAND_LINE_MAX bytes: text holds its first COMMAND_LINE_MAX */
    LINE_HAS_NUL = 2     /**< a NUL byte in it: text is cut at the first one */
} line_verdict_t;

/** Gets each line: its text (NUL-terminated, without the newline; the callee may change it), its number from 1. */
typedef void (*line_fn)(void *ctx, line_verdict_t verdict, char *text, unsigned long lineno);

typedef struct line_reader {
    char text[COMMAND_LINE_MAX + 1];
    size_t len;              /* bytes of the current line kept in text */
    bool too_long;           /* the current line went past COMMAND_LINE_MAX: the rest of it is being discarded */
    bool has_nul;
    unsigned long lineno;    /* lines completed so far */
} line_reader_t;

void line_reader_init(line_reader_t *r);

/** Takes n more bytes; calls fn for each line completed by a newline among them. */
void line_reader_feed(line_reader_t *r, const char *data, size_t n, line_fn fn, void *ctx);

/** The input has ended: a last line without its newline is a line too. */
void line_reader_finish(line_reader_t *r, line_fn fn, void *ctx);

#endif /* EMU_LINES_H */
