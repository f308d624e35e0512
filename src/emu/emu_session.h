/*
 * The control protocol, independent of its transport (docs/control-protocol.md). A session is one party that
 * sends command lines: stdin, or one client of a control socket. Each line is either the command language of
 * people (emu_commands.h) or, when its first non-blank byte is '{', one JSON request (emu_json.h); the answer
 * comes in the same framing, to that session only. A session may subscribe to events (emu_events.h), which are
 * written to it as they happen, in the framing it subscribed with.
 */
#ifndef EMU_SESSION_H
#define EMU_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emu_lines.h"

struct emu;
struct emu_bus;

/** The kinds of event, and the names the protocol gives them. */
typedef enum event_kind {
    EVENT_NMT = 0,      /* "nmt": a node's NMT state changed */
    EVENT_BOOT_UP,      /* "boot-up": a node sent its boot-up */
    EVENT_EMCY,         /* "emcy": a node sent an EMCY */
    EVENT_SDO_ABORT,    /* "sdo-abort": a node sent an SDO abort */
    EVENT_STORE,        /* "store": a store or restore (0x1010, 0x1011, LSS store) ended */
    EVENT_NVM,          /* "nvm": stored data loaded, refused or found damaged */
    EVENT_LSS,          /* "lss": a pending node-ID or bit timing changed, a bit rate switched */
    EVENT_HEARTBEAT,    /* "heartbeat": a consumed heartbeat is missing */
    EVENT_GUARDING,     /* "guarding": life guarding timed out */
    EVENT_INTERFACE,    /* "interface": the interface's troubles and their end */
    EVENT_FAULT,        /* "fault": a protocol fault was injected or cleared */
    EVENT_MESSAGE,      /* "message": a device's own message outside a command */
    EVENT_FRAME,        /* "frame": a frame sent or received (only with a COB-ID filter) */
    EVENT_KIND_COUNT
} event_kind_t;

const char *event_kind_name(event_kind_t kind);

/** event_kind_t of a name, or -1. */
int event_kind_of(const char *name);

/** Node filters a subscription may have. */
#define SESSION_NODE_FILTERS 16
/** COB-ID filters of frame events a subscription may have (a trace of NMT, SDO and EMCY: three). */
#define SESSION_FRAME_FILTERS 4

/** The frame format in a filter and in the identifier session_wants is given: set for a 29-bit (extended) frame.
 *  Bit 31, as SocketCAN's CAN_EFF_FLAG: above every identifier. */
#define SESSION_FRAME_EFF ((uint32_t)0x80000000UL)

/** Frames whose identifier (with SESSION_FRAME_EFF for an extended one) & mask == id. */
typedef struct session_frame_filter {
    uint32_t id;
    uint32_t mask;
} session_frame_filter_t;

typedef struct session_node_filter {
    uint8_t id;
    const struct emu_bus *bus; /* NULL: any */
} session_node_filter_t;

typedef struct emu_session {
    /** Writes one whole line, newline included; must not block (a transport buffers or drops). */
    void (*write)(void *ctx, const char *line, size_t len);
    void *ctx;
    char name[64];              /* for the log: "stdin", "client 3 (unix)" */
    line_reader_t lines;
    uint32_t events;            /* bit per event_kind_t subscribed */
    bool events_json;           /* subscribed with JSON: events are JSON lines */
    session_node_filter_t nodes[SESSION_NODE_FILTERS];
    size_t n_nodes;             /* 0: events of every node */
    session_frame_filter_t frames[SESSION_FRAME_FILTERS]; /* frame events: those any of these filters takes */
    size_t n_frames;
    bool restricted;            /* a web session: commands that stop the emulator or write a file are refused
                                 * (command_restriction, emu_commands.h) */
} emu_session_t;

/** A session with no subscriptions, writing through write(ctx, ...). */
void session_init(emu_session_t *s, const char *name, void (*write)(void *ctx, const char *line, size_t len), void *ctx);

/** Feeds bytes the session sent; runs each complete line (lines after a `quit` are not run). A line longer than
 *  COMMAND_LINE_MAX or holding a NUL byte is refused (emu_session_lines.c). */
void session_feed(struct emu *emu, emu_session_t *s, const char *data, size_t n);

/** The session's input ended: a last line without newline runs too. */
void session_finish(struct emu *emu, emu_session_t *s);

/** Runs one line of the session (text or JSON) and answers it. */
void session_run_line(struct emu *emu, emu_session_t *s, char *line);

/** Whether an event of kind about node node_id (0: none) on bus is for s; for EVENT_FRAME, cob_id is the frame's
 *  identifier, with SESSION_FRAME_EFF for an extended frame, matched against the session's COB-ID filter. */
bool session_wants(const emu_session_t *s, event_kind_t kind, uint8_t node_id, const struct emu_bus *bus,
                   uint32_t cob_id);

/** The event filter a subscription's NODE word names: an ID (that ID on any bus) or ID@IFACE, not "all". false when
 *  it names none: err then says why ("" when no node has that ID). */
bool session_node_filter(struct emu *emu, char *word, session_node_filter_t *out, char *err, size_t errlen);

/** Writes a formatted text line (newline added) to the session. */
void session_printf(emu_session_t *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif /* EMU_SESSION_H */
