/**
 * @file eds_diag.c
 * @brief Diagnostics of the EDS reader: "FILE:LINE: warning|error: ..." lines, grouped by kind so that the cap of
 * EDS_MAX_DIAGNOSTICS lines never hides a different one behind many of one.
 */
#include "eds_internal.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/*
 * Repeated diagnostics are grouped by kind so that the cap of EDS_MAX_DIAGNOSTICS lines never hides a different
 * one behind a hundred of the same (a python-canopen export had a PDOMapping warning on every entry). A kind is the
 * message without what names its place: words with a digit, [sections] and 'quoted' values. The first KIND_FULL of
 * a kind are given in full (the second and third only while half the room is free, so that new kinds always find
 * some); the rest become one note after the last of them: "... and 126 more like this, lines ...".
 */
#define KIND_SLOTS 512U /* open addressing, a power of two */
#define KINDS_MAX 256U  /* kinds tracked; a file with more gets the rest counted in one note */
#define KIND_FULL 3U
#define KIND_LINES 8U   /* lines a note lists (then "..., LAST") */

typedef struct diag_kind {
    uint64_t hash;      /* 0: free slot */
    uint32_t count, rest;
    bool shown;         /* its first one is among the lines kept */
    uint32_t last_full_line;
    uint32_t lines[KIND_LINES];
    uint32_t last_line;
} diag_kind_t;

struct eds_diag_kinds {
    diag_kind_t slot[KIND_SLOTS];
    uint32_t n_kinds;
    uint32_t full;      /* lines kept in full */
    uint32_t hidden;    /* diagnostics neither kept nor in a note */
};

static uint64_t fnv(uint64_t h, unsigned char c)
{
    return (h ^ c) * 0x100000001B3ULL;
}

/* The kind of a message: its words but those naming a place or a value. */
static uint64_t kind_of(const char *what, const char *body)
{
    uint64_t h = 0xCBF29CE484222325ULL;
    for (const char *p = what; *p != '\0'; p++) {
        h = fnv(h, (unsigned char)*p);
    }
    const char *p = body;
    bool unclosed[2] = {false, false}; /* no ']' / no further quote: not searched for again (linear time) */
    while (*p != '\0') {
        const int quote = *p == '\'' ? 1 : 0;
        if ((*p == '[' || quote) && !unclosed[quote]) {
            const char *close = strchr(p + 1, quote ? '\'' : ']');
            if (close != NULL) {
                p = close + 1;
                h = fnv(h, '#');
                continue;
            }
            unclosed[quote] = true;
        }
        const char *word = p;
        bool digit = false;
        while (*p != '\0' && *p != ' ') {
            digit = digit || isdigit((unsigned char)*p);
            p++;
        }
        for (const char *c = word; !digit && c < p; c++) {
            h = fnv(h, (unsigned char)*c);
        }
        h = fnv(h, ' ');
        while (*p == ' ') {
            p++;
        }
    }
    return h != 0U ? h : 1U;
}

static diag_kind_t *find_kind(eds_file_t *f, uint64_t hash)
{
    if (f->kinds == NULL) {
        f->kinds = eds_alloc(f, sizeof *f->kinds);
        if (f->kinds == NULL) {
            return NULL;
        }
    }
    for (uint32_t i = (uint32_t)hash & (KIND_SLOTS - 1U);; i = (i + 1U) & (KIND_SLOTS - 1U)) {
        diag_kind_t *k = &f->kinds->slot[i];
        if (k->hash == hash) {
            return k;
        }
        if (k->hash == 0U) {
            if (f->kinds->n_kinds == KINDS_MAX) {
                return NULL;
            }
            f->kinds->n_kinds++;
            k->hash = hash;
            return k;
        }
    }
}

static void push_diagnostic(eds_file_t *f, const char *text)
{
    char **list = f->diagnostics;
    if ((f->n_diagnostics & (f->n_diagnostics - 1U)) == 0U) { /* grow at powers of two */
        size_t cap = f->n_diagnostics == 0U ? 8U : (size_t)f->n_diagnostics * 2U;
        list = realloc(f->diagnostics, cap * sizeof(char *));
        if (list == NULL) {
            return;
        }
        f->diagnostics = list;
    }
    char *copy = eds_strndup(f, text, strlen(text));
    if (copy != NULL) {
        list[f->n_diagnostics++] = copy;
    }
}

static void diag(eds_file_t *f, uint32_t line, const char *what, const char *fmt, va_list ap)
{
    char body[448];
    vsnprintf(body, sizeof body, fmt, ap);
    diag_kind_t *k = find_kind(f, kind_of(what, body));
    if (k == NULL || f->kinds == NULL) {
        if (f->kinds != NULL) {
            f->kinds->hidden++;
        }
        return;
    }
    k->count++;
    const uint32_t room = k->count == 1U ? EDS_MAX_DIAGNOSTICS : EDS_MAX_DIAGNOSTICS / 2U;
    if (k->count <= KIND_FULL && f->kinds->full < room) {
        char text[512];
        if (line > 0U) {
            snprintf(text, sizeof text, "%s:%lu: %s: %s", f->path, (unsigned long)line, what, body);
        } else {
            snprintf(text, sizeof text, "%s: %s: %s", f->path, what, body);
        }
        push_diagnostic(f, text);
        f->kinds->full++;
        k->shown = k->shown || k->count == 1U;
        k->last_full_line = line;
    } else if (!k->shown) {
        f->kinds->hidden++;
    } else {
        if (k->rest < KIND_LINES) {
            k->lines[k->rest] = line;
        }
        k->rest++;
        k->last_line = line;
    }
}

void eds_diagnostics_done(eds_file_t *f)
{
    if (f->kinds == NULL) {
        return;
    }
    for (uint32_t i = 0; i < KIND_SLOTS; i++) {
        const diag_kind_t *k = &f->kinds->slot[i];
        if (k->rest == 0U) {
            continue;
        }
        char text[512];
        int n = k->last_full_line > 0U
                    ? snprintf(text, sizeof text, "%s:%lu: note: ... and %lu more like this, line%s", f->path,
                               (unsigned long)k->last_full_line, (unsigned long)k->rest, k->rest > 1U ? "s" : "")
                    : snprintf(text, sizeof text, "%s: note: ... and %lu more like this, line%s", f->path,
                               (unsigned long)k->rest, k->rest > 1U ? "s" : "");
        for (uint32_t j = 0; j < k->rest && j < KIND_LINES && n > 0 && (size_t)n < sizeof text; j++) {
            n += snprintf(text + n, sizeof text - (size_t)n, "%s %lu", j > 0U ? "," : "", (unsigned long)k->lines[j]);
        }
        if (k->rest > KIND_LINES && n > 0 && (size_t)n < sizeof text) {
            snprintf(text + n, sizeof text - (size_t)n, ", ..., %lu", (unsigned long)k->last_line);
        }
        push_diagnostic(f, text);
    }
    if (f->kinds->hidden > 0U) {
        char text[512];
        snprintf(text, sizeof text, "%s: note: %lu more problems of other kinds not shown (at most %u lines are given)",
                 f->path, (unsigned long)f->kinds->hidden, EDS_MAX_DIAGNOSTICS);
        push_diagnostic(f, text);
    }
}

void eds_warn(eds_file_t *f, uint32_t line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    diag(f, line, "warning", fmt, ap);
    va_end(ap);
    f->warnings++;
}

void eds_error(eds_file_t *f, uint32_t line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    diag(f, line, "error", fmt, ap);
    va_end(ap);
    f->errors++;
}
