/* The control protocol's sessions: see emu_session.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_session.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "runtime/emu.h"
#include "control/emu_commands.h"
#include "control/emu_json.h"
#include "runtime/emu_output.h"

static const char *const kind_names[EVENT_KIND_COUNT] = {
    "nmt", "boot-up", "emcy", "sdo-abort", "store", "nvm", "lss", "heartbeat", "guarding", "interface", "fault",
    "message", "frame"};

const char *event_kind_name(event_kind_t kind) { return kind < EVENT_KIND_COUNT ? kind_names[kind] : "?"; }

int event_kind_of(const char *name)
{
    for (int k = 0; k < (int)EVENT_KIND_COUNT; k++) {
        if (strcmp(kind_names[k], name) == 0) {
            return k;
        }
    }
    return -1;
}

/* emu_session_t.write: to the transport, or held behind a streamed answer's line (which must stay whole). */
static void session_write_line(void *ctx, const char *line, size_t len)
{
    emu_session_t *s = (emu_session_t *)ctx;
    if (s->stream.step == NULL) {
        s->transport_write(s->transport_ctx, line, len);
    } else if (!s->overflow && !byte_buffer_append(&s->held, line, len, SESSION_HELD_MAX)) {
        s->overflow = true; /* events it does not read: the transport closes it */
    }
}

void session_init(emu_session_t *s, const char *name, void (*write)(void *ctx, const char *line, size_t len), void *ctx)
{
    memset(s, 0, sizeof *s);
    (void)snprintf(s->name, sizeof s->name, "%s", name);
    s->transport_write = write;
    s->transport_ctx = ctx;
    s->write = session_write_line;
    s->ctx = s;
    s->output_high = SESSION_OUTPUT_HIGH;
    line_reader_init(&s->lines);
}

void session_free(emu_session_t *s)
{
    byte_buffer_free(&s->in);
    byte_buffer_free(&s->held);
    s->lines_waiting = 0U;
    s->stream.step = NULL;
}

void session_printf(emu_session_t *s, const char *fmt, ...)
{
    char line[4096];
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(line, sizeof line - 1U, fmt, ap);
    va_end(ap);
    size_t len = n < 0 ? 0U : (size_t)n < sizeof line - 1U ? (size_t)n : sizeof line - 2U;
    line[len++] = '\n';
    s->write(s->ctx, line, len);
}

bool session_wants(const emu_session_t *s, event_kind_t kind, uint8_t node_id, const struct emu_bus *bus,
                   uint32_t cob_id)
{
    if ((s->events & ((uint32_t)1U << kind)) == 0U) {
        return false;
    }
    if (kind == EVENT_FRAME) {
        size_t k = 0U;
        while (k < s->n_frames && (cob_id & s->frames[k].mask) != s->frames[k].id) {
            k++;
        }
        if (k == s->n_frames) {
            return false;
        }
    }
    if (s->n_nodes == 0U || node_id == 0U) {
        return true; /* no node filter, or an event of no node (an interface's) */
    }
    for (size_t i = 0U; i < s->n_nodes; i++) {
        if (s->nodes[i].id == node_id && (s->nodes[i].bus == NULL || s->nodes[i].bus == bus)) {
            return true;
        }
    }
    return false;
}

/* Replies of a text command go to the session that sent it. */
static void text_sink(void *ctx, const char *text, size_t len)
{
    emu_session_t *s = (emu_session_t *)ctx;
    char line[4096];
    if (len > sizeof line - 1U) {
        len = sizeof line - 1U;
    }
    memcpy(line, text, len);
    line[len++] = '\n';
    s->write(s->ctx, line, len);
}

/* The refusal select_nodes_any_bus replies ("error: no interface 'vcan7'"), kept for the caller's own answer. */
typedef struct refusal {
    char *text;
    size_t size;
} refusal_t;

static void refusal_sink(void *ctx, const char *text, size_t len)
{
    refusal_t *r = (refusal_t *)ctx;
    if (strncmp(text, "error: ", 7U) == 0) {
        text += 7;
        len -= 7U;
    }
    (void)snprintf(r->text, r->size, "%.*s", (int)len, text);
}

bool session_node_filter(emu_t *emu, char *word, session_node_filter_t *out, char *err, size_t errlen)
{
    emu_node_t *found[1];
    refusal_t r = {err, errlen};
    err[0] = '\0';
    const bool on_bus = strchr(word, '@') != NULL;
    const reply_sink_t to = {refusal_sink, &r};
    const int n = select_nodes_any_bus(emu, word, found, 1U, &to);
    if (n <= 0 || strncmp(word, "all", 3U) == 0) {
        if (n > 0) {
            err[0] = '\0'; /* "all" is no filter */
        }
        return false;
    }
    out->id = co_node_id(&found[0]->dev.node);
    out->bus = on_bus ? found[0]->bus : NULL;
    return true;
}

/* subscribe KIND[,KIND...] [NODE...] | subscribe frame COB-ID[x][/MASK] | unsubscribe [KIND[,KIND...]] */
static void text_subscribe(emu_t *emu, emu_session_t *s, char *line)
{
    char *save = NULL;
    const char *verb = strtok_r(line, " \t\r", &save);
    const bool on = strcmp(verb, "subscribe") == 0;
    char *kinds = strtok_r(NULL, " \t\r", &save);
    uint32_t mask = 0U;
    if (kinds == NULL) {
        if (on) {
            session_printf(s, "error: usage: subscribe KIND[,KIND...] [NODE...] | subscribe frame COB-ID[x][/MASK]; "
                              "kinds: nmt boot-up emcy sdo-abort store nvm lss heartbeat guarding interface fault "
                              "message frame, or all");
            return;
        }
        mask = 0xFFFFFFFFUL;
    } else if (strcmp(kinds, "all") == 0) {
        mask = (((uint32_t)1U << EVENT_KIND_COUNT) - 1U) & ~((uint32_t)1U << EVENT_FRAME); /* frames need their own filter */
    } else {
        char *ksave = NULL;
        for (char *k = strtok_r(kinds, ",", &ksave); k != NULL; k = strtok_r(NULL, ",", &ksave)) {
            const int kind = event_kind_of(k);
            if (kind < 0) {
                session_printf(s, "error: unknown event kind '%s'", k);
                return;
            }
            mask |= (uint32_t)1U << (unsigned)kind;
        }
    }
    if (!on) {
        s->events &= ~mask;
        session_printf(s, "unsubscribed");
        return;
    }
    if ((mask & ((uint32_t)1U << EVENT_FRAME)) != 0U) {
        session_frame_filter_t frames[SESSION_FRAME_FILTERS];
        size_t n = 0U;
        bool ok = mask == ((uint32_t)1U << EVENT_FRAME);
        for (char *w = strtok_r(NULL, " \t\r", &save); ok && w != NULL; w = strtok_r(NULL, " \t\r", &save)) {
            ok = n < SESSION_FRAME_FILTERS && json_parse_frame_filter(w, &frames[n].id, &frames[n].mask);
            n++;
        }
        if (!ok || n == 0U) {
            session_printf(s, "error: usage: subscribe frame COB-ID[x][/MASK] ... (at most %d; 0x700/0x780: every "
                              "heartbeat; x: 29-bit frames)", SESSION_FRAME_FILTERS);
            return;
        }
        memcpy(s->frames, frames, sizeof frames[0] * n);
        s->n_frames = n;
    } else {
        size_t n = 0U;
        for (char *w = strtok_r(NULL, " \t\r", &save); w != NULL; w = strtok_r(NULL, " \t\r", &save)) {
            if (n == SESSION_NODE_FILTERS) {
                session_printf(s, "error: at most %d nodes per subscription", SESSION_NODE_FILTERS);
                return;
            }
            char err[256];
            if (!session_node_filter(emu, w, &s->nodes[n], err, sizeof err)) {
                if (err[0] != '\0') {
                    session_printf(s, "error: %s", err);
                } else {
                    session_printf(s, "error: no node %s", w);
                }
                return;
            }
            n++;
        }
        s->n_nodes = n;
    }
    s->events |= mask;
    s->events_json = false;
    session_printf(s, "subscribed");
}

void session_run_line(emu_t *emu, emu_session_t *s, char *line)
{
    const char *p = line;
    while (*p == ' ' || *p == '\t' || *p == '\r') {
        p++;
    }
    if (*p == '{') {
        json_run(emu, s, p);
        return;
    }
    if (strncmp(p, "subscribe", 9) == 0 || strncmp(p, "unsubscribe", 11) == 0) {
        const char c = p[strncmp(p, "subscribe", 9) == 0 ? 9 : 11];
        if (c == '\0' || c == ' ' || c == '\t' || c == '\r') {
            text_subscribe(emu, s, line);
            return;
        }
    }
    const reply_sink_t to = {text_sink, s};
    emu->command_restricted = s->restricted;
    (void)run_command(emu, line, &to);
    emu->command_restricted = false;
}
