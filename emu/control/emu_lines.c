/* Command lines from a byte stream: see emu_lines.h. */
#include "control/emu_lines.h"

#include <string.h>

void line_reader_init(line_reader_t *r) { memset(r, 0, sizeof *r); }

static void complete(line_reader_t *r, line_fn fn, void *ctx)
{
    r->text[r->len] = '\0';
    r->lineno++;
    const line_verdict_t verdict = r->too_long ? LINE_TOO_LONG : r->has_nul ? LINE_HAS_NUL : LINE_OK;
    r->len = 0U;
    r->too_long = false;
    r->has_nul = false;
    fn(ctx, verdict, r->text, r->lineno);
}

void line_reader_feed(line_reader_t *r, const char *data, size_t n, line_fn fn, void *ctx)
{
    for (size_t i = 0U; i < n; i++) {
        const char c = data[i];
        if (c == '\n') {
            complete(r, fn, ctx);
        } else if (r->too_long) {
            /* discarded: the line is refused whole */
        } else if (r->len == COMMAND_LINE_MAX) {
            r->too_long = true;
        } else {
            r->has_nul = r->has_nul || c == '\0';
            r->text[r->len++] = c;
        }
    }
}

void line_reader_finish(line_reader_t *r, line_fn fn, void *ctx)
{
    if (r->len > 0U || r->too_long) {
        complete(r, fn, ctx);
    }
}
