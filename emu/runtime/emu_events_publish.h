/*
 * How an event reaches the sessions that want it (emu_events.h): the sessions found by their subscriptions, its JSON
 * line and its text line each written once by the event writer (emu_event_writer.h), in the protocol's order of the
 * members (docs/control-protocol.md "Events"), and handed to each session. Private to emu_events.c and
 * emu_events_publish.c (the frames' events, whose path matters most, are written there).
 */
#ifndef EMU_EVENTS_PUBLISH_H
#define EMU_EVENTS_PUBLISH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "runtime/emu.h"
#include "runtime/emu_event_writer.h"

/** One event, as events_publish writes it. */
typedef struct event {
    event_kind_t kind;
    const emu_node_t *node;         /* NULL: an event of no node (an interface's, a frame received) */
    const emu_bus_t *bus;           /* NULL: of no bus */
    co_time_us_t time_us;           /* the emulator's clock (emu_since_start) */
    const char *text;               /* NULL: none */
    bool text_plain;                /* text needs no escaping in JSON (a frame's, writer_member_plain) */
    const event_writer_t *fields;   /* NULL, or the members of its kind (",\"from\":...", writer_member_*) */
} event_t;

/* Room for the fields of one event (the longest, a store's, is about 80 bytes). */
#define EVENT_FIELDS_ROOM 192U

/** The sessions of emu an event of kind about node id (0: none) on bus is for (session_wants; cob_id: a frame's
 *  identity), into to[] (room for MAX_SESSIONS); their number. */
size_t events_sessions_wanting(const emu_t *emu, event_kind_t kind, uint8_t id, const emu_bus_t *bus, uint32_t cob_id,
                               emu_session_t **to);

/** One event to the sessions to[0..n_to) (events_sessions_wanting): its JSON line written once for those that
 *  subscribed with JSON, its text line once for the others. */
void events_publish(const event_t *ev, emu_session_t *const *to, size_t n_to);

#endif /* EMU_EVENTS_PUBLISH_H */
