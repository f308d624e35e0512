/* --script FILE: see emu_script.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_script.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool script_load(emu_script_t *s, const char *path)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "canopen-emu: cannot read script %s: %s\n", path, strerror(errno));
        return false;
    }
    char line[SCRIPT_LINE_MAX];
    co_time_us_t at = 0U;
    size_t cap = 0U;
    unsigned lineno = 0U;
    while (fgets(line, sizeof line, f) != NULL) {
        lineno++;
        char *p = line;
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        if (*p == '\0' || *p == '\n' || *p == '#') {
            continue;
        }
        if (*p == '@') {
            char *end = NULL;
            const bool relative = p[1] == '+';
            const double ms = strtod(p + (relative ? 2 : 1), &end);
            if (end == p + 1 || ms < 0.0 || (*end != ' ' && *end != '\t' && *end != '\n' && *end != '\0')) {
                fprintf(stderr, "canopen-emu: %s:%u: bad time (use '@MS command' or '@+MS command')\n", path, lineno);
                fclose(f);
                return false;
            }
            at = (relative ? at : 0U) + (co_time_us_t)(ms * 1000.0);
            p = end;
        }
        if (s->len == cap) {
            cap = cap == 0U ? 32U : cap * 2U;
            script_line_t *grown = realloc(s->lines, cap * sizeof *grown);
            if (grown == NULL) {
                fclose(f);
                return false;
            }
            s->lines = grown;
        }
        s->lines[s->len].at = at;
        (void)snprintf(s->lines[s->len].text, SCRIPT_LINE_MAX, "%s", p);
        s->len++;
    }
    fclose(f);
    return true;
}

co_time_us_t script_next_at(const emu_script_t *s)
{
    return s->pos < s->len ? s->lines[s->pos].at : CO_NEVER;
}

bool script_take_due(emu_script_t *s, co_time_us_t elapsed, char *line, size_t size)
{
    if (s->pos >= s->len || elapsed < s->lines[s->pos].at) {
        return false;
    }
    (void)snprintf(line, size, "%s", s->lines[s->pos++].text);
    return true;
}

void script_free(emu_script_t *s)
{
    free(s->lines);
    s->lines = NULL;
    s->len = 0U;
    s->pos = 0U;
}
