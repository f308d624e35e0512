/* --script FILE: see emu_script.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "scripts/emu_script.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "control/emu_lines.h"

typedef struct script_loader {
    emu_script_t *script;
    const char *path;
    FILE *err;              /* where refusals go: stderr, or a test's stream */
    co_time_us_t at;        /* the previous line's time */
    size_t cap;
    bool failed;            /* a line was refused (reported): the rest of the file is not looked at */
} script_loader_t;

/* "@MS" or "@+MS" at p: MS whole milliseconds, decimal digits only, the result at most SCRIPT_TIME_MAX_MS.
 * strtod took "@inf" and "@1e300" (run at once) and "@nan" (never), and a time near 2^64 µs wrapped. */
static bool parse_time(char *p, char **end, unsigned long long previous_ms, unsigned long long *ms)
{
    const bool relative = p[1] == '+';
    char *digit = p + (relative ? 2 : 1);
    unsigned long long v = 0U;
    char *q = digit;
    for (; *q >= '0' && *q <= '9'; q++) {
        v = v > SCRIPT_TIME_MAX_MS ? v : v * 10U + (unsigned long long)(*q - '0'); /* stops growing once too large */
    }
    if (q == digit || (*q != '\0' && *q != ' ' && *q != '\t' && *q != '\r')) {
        return false;
    }
    *ms = (relative ? previous_ms : 0U) + v; /* both at most SCRIPT_TIME_MAX_MS + 9 digits' worth: no overflow */
    *end = q;
    return true;
}

static void script_line(void *ctx, line_verdict_t verdict, char *text, unsigned long lineno)
{
    script_loader_t *l = (script_loader_t *)ctx;
    if (l->failed) {
        return;
    }
    if (verdict != LINE_OK) {
        if (verdict == LINE_TOO_LONG) {
            fprintf(l->err, "canopen-emu: %s:%lu: line longer than %d bytes\n", l->path, lineno, COMMAND_LINE_MAX);
        } else {
            fprintf(l->err, "canopen-emu: %s:%lu: a NUL byte in the line\n", l->path, lineno);
        }
        l->failed = true;
        return;
    }
    char *p = text;
    while (*p == ' ' || *p == '\t' || *p == '\r') {
        p++;
    }
    if (*p == '\0' || *p == '#') {
        return;
    }
    if (*p == '@') {
        char *end = NULL;
        unsigned long long ms = 0U;
        if (!parse_time(p, &end, l->at / 1000U, &ms)) {
            fprintf(l->err, "canopen-emu: %s:%lu: bad time (use '@MS command' or '@+MS command', MS a whole number "
                    "of milliseconds)\n", l->path, lineno);
            l->failed = true;
            return;
        }
        if (ms > SCRIPT_TIME_MAX_MS) {
            fprintf(l->err, "canopen-emu: %s:%lu: time after the start beyond the limit of %llu ms (11.6 days)\n",
                    l->path, lineno, SCRIPT_TIME_MAX_MS);
            l->failed = true;
            return;
        }
        l->at = (co_time_us_t)ms * 1000U;
        p = end;
    }
    emu_script_t *s = l->script;
    if (s->len == l->cap) {
        const size_t cap = l->cap == 0U ? 32U : l->cap * 2U;
        script_line_t *grown = realloc(s->lines, cap * sizeof *grown);
        if (grown == NULL) {
            fprintf(l->err, "canopen-emu: out of memory reading %s\n", l->path);
            l->failed = true;
            return;
        }
        s->lines = grown;
        l->cap = cap;
    }
    char *copy = strdup(p);
    if (copy == NULL) {
        fprintf(l->err, "canopen-emu: out of memory reading %s\n", l->path);
        l->failed = true;
        return;
    }
    s->lines[s->len].at = l->at;
    s->lines[s->len].text = copy;
    s->len++;
}

bool script_load(emu_script_t *s, const char *path)
{
    const int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        fprintf(stderr, "canopen-emu: cannot read script %s: %s\n", path, strerror(errno));
        return false;
    }
    struct stat st;
    if (fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) { /* open() allows it, and reading it gave an empty script */
        fprintf(stderr, "canopen-emu: cannot read script %s: it is a directory\n", path);
        (void)close(fd);
        return false;
    }
    const bool ok = script_read(s, fd, path, stderr);
    (void)close(fd);
    return ok;
}

bool script_read(emu_script_t *s, int fd, const char *name, FILE *err)
{
    script_loader_t loader = {s, name, err, 0U, 0U, false};
    line_reader_t reader;
    line_reader_init(&reader);
    char chunk[4096];
    ssize_t got;
    while (!loader.failed && (got = read(fd, chunk, sizeof chunk)) != 0) {
        if (got < 0) {
            if (errno == EINTR) {
                continue;
            }
            fprintf(err, "canopen-emu: cannot read script %s: %s\n", name, strerror(errno));
            return false;
        }
        line_reader_feed(&reader, chunk, (size_t)got, script_line, &loader);
    }
    if (!loader.failed) {
        line_reader_finish(&reader, script_line, &loader);
    }
    return !loader.failed;
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
    for (size_t i = 0U; i < s->len; i++) {
        free(s->lines[i].text);
    }
    free(s->lines);
    s->lines = NULL;
    s->len = 0U;
    s->pos = 0U;
}
