/* How an event reaches the sessions: see emu_events_publish.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_events_publish.h"

#include <stdlib.h>
#include <string.h>

#include "runtime/emu_events.h"
#include "text_escape.h"

/* Room for an event's JSON line on the stack: a device name and a text of a few hundred bytes even if each of
 * their bytes is escaped (6 bytes: \u001B). A longer one is written into a block of its worst case. */
#define EVENT_JSON_ROOM 4096U
size_t events_sessions_wanting(const emu_t *emu, event_kind_t kind, uint8_t id, const emu_bus_t *bus,
                               uint32_t cob_id, emu_session_t **to)
{
    size_t n = 0U;
    for (size_t i = 0U; i < emu->n_sessions; i++) {
        if (session_wants(emu->sessions[i], kind, id, bus, cob_id)) {
            to[n++] = emu->sessions[i];
        }
    }
    return n;
}

static void write_json_event(event_writer_t *w, const event_t *ev)
{
    writer_bytes(w, "{\"event\":\"", 10U);
    writer_text(w, event_kind_name(ev->kind)); /* the protocol's names: nothing to escape */
    writer_bytes(w, "\"", 1U);
    writer_member_uint(w, EVENT_KEY("time_us"), ev->time_us);
    if (ev->bus != NULL) {
        writer_member_string(w, EVENT_KEY("bus"), ev->bus->can.name);
    }
    if (ev->node != NULL) {
        writer_member_uint(w, EVENT_KEY("node"), co_node_id(&ev->node->dev.node));
        writer_member_string(w, EVENT_KEY("device"), ev->node->dev.cls->name); /* an EDS file's name: any bytes */
    }
    if (ev->fields != NULL) {
        writer_bytes(w, ev->fields->buf, ev->fields->len);
    }
    if (ev->text != NULL && ev->text_plain) {
        writer_member_plain(w, EVENT_KEY("text"), ev->text, strlen(ev->text));
    } else if (ev->text != NULL) {
        writer_member_string(w, EVENT_KEY("text"), ev->text);
    }
    writer_bytes(w, "}\n", 2U);
}

/* The JSON line of an event larger than EVENT_JSON_ROOM: written into a block that holds its worst case (each byte
 * of its strings escaped). NULL when memory ran out. */
static char *write_json_event_large(const event_t *ev, size_t *len)
{
    size_t strings = strlen(ev->bus != NULL ? ev->bus->can.name : "") + strlen(ev->text != NULL ? ev->text : "") +
                     strlen(ev->node != NULL ? ev->node->dev.cls->name : "");
    const size_t cap = 256U + (ev->fields != NULL ? ev->fields->len : 0U) + 6U * strings;
    char *block = malloc(cap);
    if (block == NULL) {
        return NULL;
    }
    event_writer_t w;
    writer_init(&w, block, cap);
    write_json_event(&w, ev);
    if (w.full) {
        free(block);
        return NULL;
    }
    *len = w.len;
    return block;
}

/* The text line of an event: "event KIND SECONDS node ID@BUS (DEVICE): TEXT", or "event KIND SECONDS BUS: TEXT" for
 * one of no node. The device's name (an EDS file's) and the text (a model's message) are shown escaped, as the log
 * shows them (text_escape.h): one line, nothing a terminal acts on. Cut to size (line_size - 1 bytes), it still ends
 * with its newline. */
static size_t write_text_event(const event_t *ev, char *line, size_t line_size)
{
    char raw[1024];
    event_writer_t w;
    writer_init(&w, raw, sizeof raw - 1U); /* as snprintf into raw cut it */
    writer_text(&w, "event ");
    writer_text(&w, event_kind_name(ev->kind));
    writer_bytes(&w, " ", 1U);
    writer_seconds(&w, ev->time_us);
    if (ev->node != NULL) {
        writer_text(&w, " node ");
        writer_uint(&w, co_node_id(&ev->node->dev.node));
        writer_bytes(&w, "@", 1U);
        writer_text(&w, ev->bus->can.name);
        writer_text(&w, " (");
        writer_text(&w, ev->node->dev.cls->name);
        writer_text(&w, "): ");
    } else {
        writer_bytes(&w, " ", 1U);
        writer_text(&w, ev->bus != NULL ? ev->bus->can.name : "-");
        writer_text(&w, ": ");
    }
    writer_text(&w, ev->text != NULL ? ev->text : "");
    size_t len = text_escape(line, line_size - 1U, raw, w.len, TEXT_ONE_LINE);
    line[len++] = '\n';
    return len;
}

void events_publish(const event_t *ev, emu_session_t *const *to, size_t n_to)
{
    char json_room[EVENT_JSON_ROOM];
    const char *json_line = NULL;
    char *json_block = NULL;
    size_t json_len = 0U;
    bool json_failed = false;
    char text_line[1024];
    size_t text_len = 0U;
    for (size_t i = 0U; i < n_to; i++) {
        emu_session_t *s = to[i];
        if (s->events_json) {
            if (json_line == NULL && !json_failed) {
                event_writer_t w;
                writer_init(&w, json_room, sizeof json_room);
                write_json_event(&w, ev);
                if (!w.full) {
                    json_line = json_room;
                    json_len = w.len;
                } else {
                    json_block = write_json_event_large(ev, &json_len);
                    json_line = json_block;
                    json_failed = json_block == NULL;
                }
            }
            if (json_line != NULL) {
                s->write(s->ctx, json_line, json_len);
            }
        } else {
            if (text_len == 0U) {
                text_len = write_text_event(ev, text_line, sizeof text_line);
            }
            s->write(s->ctx, text_line, text_len);
        }
    }
    free(json_block);
}

/* Out of line: its buffers would otherwise make every frame pay for a stack frame nobody uses. */
__attribute__((noinline)) void events_frame_publish(emu_t *emu, emu_bus_t *bus, const emu_node_t *from,
                                                    const co_frame_t *f, co_time_us_t at)
{
    /* The format is part of the frame's identity (session_wants): an extended 0x181 is no TPDO1 of node 1. */
    const bool eff = (f->flags & CO_FRAME_EFF) != 0U;
    const bool rtr = (f->flags & CO_FRAME_RTR) != 0U;
    const uint32_t identity = f->id | (eff ? SESSION_FRAME_EFF : 0U);
    emu_session_t *to[MAX_SESSIONS];
    const size_t n_to = events_sessions_wanting(emu, EVENT_FRAME, from != NULL ? co_node_id(&from->dev.node) : 0U, bus,
                                         identity, to);
    if (n_to == 0U) {
        return; /* nothing is written for a frame nobody's filter takes */
    }
    const char *dir = from != NULL ? "tx" : "rx";
    const size_t len = f->len < 8U ? f->len : 8U;
    /* candump's form: 3 hex digits for an 11-bit identifier, 8 for a 29-bit one, whatever its value */
    char text[48];
    event_writer_t t;
    writer_init(&t, text, sizeof text);
    writer_bytes(&t, dir, 2U);
    writer_bytes(&t, " ", 1U);
    writer_hex_uint(&t, f->id, eff ? 8U : 3U);
    writer_bytes(&t, "#", 1U);
    const size_t data_at = t.len;
    writer_hex_bytes(&t, f->data, len);
    if (rtr) {
        writer_bytes(&t, "R", 1U);
    }
    writer_bytes(&t, "", 1U); /* its NUL */
    char room[EVENT_FIELDS_ROOM];
    event_writer_t fields;
    writer_init(&fields, room, sizeof room);
    writer_member_plain(&fields, EVENT_KEY("dir"), dir, 2U);
    writer_member_uint(&fields, EVENT_KEY("id"), f->id);
    writer_member_plain(&fields, EVENT_KEY("data"), text + data_at, 2U * len); /* the text's hex digits */
    if (rtr) {
        writer_member_bool(&fields, EVENT_KEY("rtr"), true);
    }
    if (eff) {
        writer_member_bool(&fields, EVENT_KEY("eff"), true);
    }
    const event_t ev = {EVENT_FRAME, from, bus, emu_since_start(emu, at), text, true, &fields};
    events_publish(&ev, to, n_to);
}
