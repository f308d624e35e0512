/*
 * Fuzz target "script": the --script loader of canopen-emu (emu/scripts/emu_script.c through script_read, with the
 * line reader of emu/control/emu_lines.c), checked against a reference reading of docs/emulator.md "Scripts".
 *
 * Input: the script file's bytes. The harness puts in front of them one or two comment lines of 0-4094 bytes
 * (the length is a hash of the input), so that the loader's 4096-byte reads end at varying places inside the
 * fuzzed text; the reference reads the same bytes, padding included.
 *
 * Invariants (a violation prints "==fuzz== INVARIANT VIOLATION" and aborts):
 *  - the file is accepted exactly when the reference accepts it: lines of at most 2047 bytes without a NUL byte,
 *    '@MS' / '@+MS' times of decimal digits followed by the end of the line or a blank, every time at most
 *    1,000,000,000 ms after the start (also as a sum of '@+' times);
 *  - an accepted file: no message; the lines that are neither blank nor comments come out in their order, with
 *    their text (after the time) unchanged and their time (absolute, relative to the previous line, or the
 *    previous line's) within the limit; script_next_at / script_take_due give each line exactly at its time;
 *  - a refused file: exactly one message, "canopen-emu: NAME:N: ..." with N the number of the first bad line and
 *    the reason of the reference; the lines before it, as loaded, are the reference's;
 *  - no crash, leak or undefined behaviour (ASan, UBSan, LeakSanitizer: script_free frees everything).
 */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fuzz_abort.h"
#include "control/emu_lines.h"
#include "scripts/emu_script.h"

/* The documented limit (docs/emulator.md: "at most 1,000,000,000 ms"), written here again so that a changed
 * constant in the code is caught rather than trusted. */
#define DOC_LIMIT_MS 1000000000ULL
#define DOC_LINE_MAX 2047U
#define NAME "fuzz.script"

typedef enum { R_ACCEPTED, R_TOO_LONG, R_NUL, R_BAD_TIME, R_BEYOND } reason_t;

typedef struct ref_line {
    unsigned long long at_ms;
    const char *text;
    size_t len;
} ref_line_t;

typedef struct ref {
    ref_line_t *lines;
    size_t n;
    reason_t reason;        /* R_ACCEPTED: accepted */
    unsigned long bad_line; /* the first bad line (from 1) */
} ref_t;

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void fail(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "\n==fuzz== INVARIANT VIOLATION [script]:\n==fuzz==   ");
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

static bool blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/* The documented reading of a script, independent of the loader's code. */
static void reference(const char *d, size_t n, ref_t *r)
{
    unsigned long long at = 0U;
    unsigned long lineno = 0U;
    size_t start = 0U;
    r->n = 0U;
    r->reason = R_ACCEPTED;
    for (size_t i = 0U; i <= n; i++) {
        if (i < n && d[i] != '\n') {
            continue;
        }
        if (i == n && start == n) {
            break; /* the file ends with a newline (or is empty): no last line */
        }
        lineno++;
        const char *l = d + start;
        const size_t len = i - start;
        start = i + 1U;
        if (len > DOC_LINE_MAX) {
            r->reason = R_TOO_LONG;
        } else if (memchr(l, '\0', len) != NULL) {
            r->reason = R_NUL;
        }
        if (r->reason != R_ACCEPTED) {
            r->bad_line = lineno;
            return;
        }
        size_t p = 0U;
        while (p < len && blank(l[p])) {
            p++;
        }
        if (p == len || l[p] == '#') {
            continue;
        }
        if (l[p] == '@') {
            size_t q = p + 1U;
            const bool relative = q < len && l[q] == '+';
            q += relative ? 1U : 0U;
            const size_t digits = q;
            bool huge = false;
            unsigned long long v = 0U;
            for (; q < len && l[q] >= '0' && l[q] <= '9'; q++) {
                if (!huge) {
                    v = v * 10U + (unsigned long long)(l[q] - '0');
                    huge = v > DOC_LIMIT_MS;
                }
            }
            if (q == digits || (q < len && !blank(l[q]))) {
                r->reason = R_BAD_TIME;
            } else if (huge || (relative ? at + v : v) > DOC_LIMIT_MS) {
                r->reason = R_BEYOND;
            }
            if (r->reason != R_ACCEPTED) {
                r->bad_line = lineno;
                return;
            }
            at = relative ? at + v : v;
            p = q;
        }
        r->lines[r->n].at_ms = at;
        r->lines[r->n].text = l + p;
        r->lines[r->n].len = len - p;
        r->n++;
    }
}

static const char *reason_text(reason_t r)
{
    switch (r) {
    case R_TOO_LONG:
        return "line longer than 2047 bytes";
    case R_NUL:
        return "a NUL byte in the line";
    case R_BAD_TIME:
        return "bad time";
    case R_BEYOND:
        return "time after the start beyond the limit";
    default:
        return "(accepted)";
    }
}

static void check_lines(const emu_script_t *s, const ref_t *r, size_t n)
{
    for (size_t i = 0U; i < n; i++) {
        const script_line_t *l = &s->lines[i];
        const ref_line_t *e = &r->lines[i];
        if (l->at > DOC_LIMIT_MS * 1000U) {
            fail("line %zu of the script runs at %llu us, beyond the documented limit of %llu ms", i + 1U,
                 (unsigned long long)l->at, DOC_LIMIT_MS);
        }
        if (l->at != e->at_ms * 1000U) {
            fail("script line %zu ('%.40s') at %llu us, the reference says %llu ms", i + 1U, l->text,
                 (unsigned long long)l->at, e->at_ms);
        }
        if (strlen(l->text) != e->len || memcmp(l->text, e->text, e->len) != 0) {
            fail("script line %zu is '%.60s' (%zu bytes), the file has '%.60s' (%zu bytes)", i + 1U, l->text,
                 strlen(l->text), e->text, e->len);
        }
    }
}

/* Every line comes out once, in its order, exactly when its time has come (a line waits for the one before it). */
static void check_take(emu_script_t *s, const ref_t *r)
{
    static char line[COMMAND_LINE_MAX + 1];
    for (size_t i = 0U; i < r->n; i++) {
        const co_time_us_t at = r->lines[i].at_ms * 1000U;
        if (script_next_at(s) != at) {
            fail("script_next_at gives %llu us for line %zu, due at %llu us", (unsigned long long)script_next_at(s),
                 i + 1U, (unsigned long long)at);
        }
        if (at > 0U && script_take_due(s, at - 1U, line, sizeof line)) {
            fail("line %zu (due at %llu us) was taken 1 us early", i + 1U, (unsigned long long)at);
        }
        if (!script_take_due(s, at, line, sizeof line)) {
            fail("line %zu was not taken at its time %llu us", i + 1U, (unsigned long long)at);
        }
        if (strlen(line) != r->lines[i].len || memcmp(line, r->lines[i].text, r->lines[i].len) != 0) {
            fail("line %zu was taken as '%.60s', the file has '%.60s'", i + 1U, line, r->lines[i].text);
        }
    }
    if (script_next_at(s) != CO_NEVER || script_take_due(s, CO_NEVER, line, sizeof line)) {
        fail("a line is left after the script's %zu lines", r->n);
    }
}

static void check_message(const char *msg, size_t len, const ref_t *r, bool accepted)
{
    if (accepted) {
        if (len != 0U) {
            fail("an accepted script gave the message '%s'", msg);
        }
        return;
    }
    char prefix[64];
    (void)snprintf(prefix, sizeof prefix, "canopen-emu: " NAME ":%lu: ", r->bad_line);
    const size_t pl = strlen(prefix);
    if (len < pl || strncmp(msg, prefix, pl) != 0 || strncmp(msg + pl, reason_text(r->reason), strlen(reason_text(r->reason))) != 0) {
        fail("refused script (line %lu: %s) gave the message '%s'", r->bad_line, reason_text(r->reason), msg);
    }
    if (msg[len - 1U] != '\n' || memchr(msg, '\n', len - 1U) != NULL) {
        fail("the refusal is not exactly one line: '%s'", msg);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int fd = -1;
    if (fd < 0) {
        fd = memfd_create("fuzz-script", MFD_CLOEXEC); /* the script file; rewritten every run */
        if (fd < 0) {
            perror("memfd_create");
            abort();
        }
    }
    /* Padding: comment lines shifting the fuzzed bytes against the loader's 4096-byte reads. */
    uint32_t h = 2166136261U;
    for (size_t i = 0U; i < size; i++) {
        h = (h ^ data[i]) * 16777619U;
    }
    const size_t pad = h % 4095U;
    char *buf = malloc(pad + size + 1U);
    if (buf == NULL) {
        abort();
    }
    for (size_t done = 0U; done < pad;) {
        const size_t l = pad - done > 2048U ? 2048U : pad - done; /* a line and its newline: at most 2048 bytes */
        buf[done] = '#';
        memset(buf + done + 1U, ' ', l - 1U);
        buf[done + l - 1U] = '\n';
        done += l;
    }
    if (size > 0U) {
        memcpy(buf + pad, data, size);
    }
    const size_t n = pad + size;
    buf[n] = '\0'; /* only for messages: the reference works on lengths */
    if (ftruncate(fd, 0) != 0 || pwrite(fd, buf, n, 0) != (ssize_t)n || lseek(fd, 0, SEEK_SET) != 0) {
        perror("script file");
        abort();
    }

    ref_t r;
    r.lines = malloc((n + 1U) * sizeof *r.lines);
    if (r.lines == NULL) {
        abort();
    }
    reference(buf, n, &r);

    char *msg = NULL;
    size_t msg_len = 0U;
    FILE *err = open_memstream(&msg, &msg_len);
    if (err == NULL) {
        abort();
    }
    emu_script_t s;
    memset(&s, 0, sizeof s);
    const bool ok = script_read(&s, fd, NAME, err);
    (void)fclose(err);

    if (ok != (r.reason == R_ACCEPTED)) {
        fail("the loader %s the script, the reference %s it (%s at line %lu); message: '%s'", ok ? "accepted" : "refused",
             r.reason == R_ACCEPTED ? "accepts" : "refuses", reason_text(r.reason), r.reason == R_ACCEPTED ? 0UL : r.bad_line, msg);
    }
    check_message(msg, msg_len, &r, ok);
    if (s.len != r.n) {
        fail("%zu lines loaded, the reference has %zu", s.len, r.n);
    }
    check_lines(&s, &r, s.len);
    if (ok) {
        check_take(&s, &r);
    }
    script_free(&s);
    free(msg);
    free(r.lines);
    free(buf);
    return 0;
}
