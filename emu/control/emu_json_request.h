/*
 * Shared by the modules of the control protocol's JSON framing (emu_json.c: reading requests, the session and node
 * commands; emu_json_od.c: the object dictionary commands): one request being answered, and how an answer is
 * written. Private to those modules (and emu_events.c, for hex_string); the protocol is docs/control-protocol.md.
 */
#ifndef EMU_JSON_REQUEST_H
#define EMU_JSON_REQUEST_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "runtime/emu.h"

/** The request being answered: its session, its parsed object, its "id" (or NULL) and "cmd". */
typedef struct request {
    emu_t *emu;
    emu_session_t *s;
    json_t *req;
    json_t *id;
    const char *cmd;
} request_t;

/** A JSON string of text; bytes that are not UTF-8 become '?' (never NULL for a reply that echoes input). */
json_t *jstr(const char *text);

/** Upper-case hex of len bytes (at most 256). */
json_t *hex_string(const uint8_t *b, size_t len);

/** {"id", "ok"}: the start of every response. */
json_t *response(json_t *id, bool ok);

/** Writes obj (taken) as one line to s. */
void send_response(emu_session_t *s, json_t *obj);

/** Answers the request with {"ok": false, "error": ...}. */
void fail(emu_session_t *s, json_t *id, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/** Every field of the request is "id", "cmd" or one of allowed (NULL-terminated); else answered with an error. */
bool only_fields(const request_t *q, const char *const *allowed);

/** The one node of "node", or NULL after an error answer. */
emu_node_t *one_node(const request_t *q);

/** "object" (and "sub") as index and sub, with text "0xIIII:SS"; false after an error answer. */
bool object_address(const request_t *q, uint16_t *index, uint8_t *sub, char *text, size_t size);

/* The object dictionary commands (emu_json_od.c). */
void cmd_get(const request_t *q);
void cmd_set(const request_t *q);
void cmd_objects(const request_t *q);

/* The tables clients make forms and texts from: fault kinds, abort texts (emu_json_tables.c). */
void cmd_tables(const request_t *q);

#endif /* EMU_JSON_REQUEST_H */
