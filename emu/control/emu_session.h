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

#include "co/co.h"
#include "control/emu_buffer.h"
#include "control/emu_lines.h"

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

/** Bytes of request lines a session may have waiting to run (a web exchange's whole body and its newline fit); a
 *  transport reads no more from its client while they fill this. */
#define SESSION_INPUT_MAX (16U * 1024U + 1U)
/** A session whose transport holds this many bytes unread runs nothing more, and its streamed answer pauses,
 *  until the reader takes some: a client that does not read costs no work, and a large answer never piles up. */
#define SESSION_OUTPUT_HIGH (64U * 1024U)
/** Bytes of events a session may have held while its streamed answer is being written (as CLIENT_OUTPUT_MAX). */
#define SESSION_HELD_MAX (1024U * 1024U)

struct emu_session;

/** An answer written piece by piece (emu_session_work.c): `objects` of a device with thousands of entries is
 *  megabytes. Its line is written as the reader takes it, its output_high at most waiting; events that come
 *  meanwhile are held and follow the answer's line. */
typedef struct session_stream {
    /** Writes the next piece (session_stream_write); false once the answer's line is complete. */
    bool (*step)(struct emu *emu, struct emu_session *s);
    void *node;         /* the step's own state: objects' node, entry, sub-index and whether with values */
    uint16_t entry;
    uint8_t sub;
    bool values;
    unsigned long count;    /* pieces (rows) written so far */
} session_stream_t;

typedef struct emu_session {
    /** Writes one whole line, newline included; never blocks. Events and every answer go through it: to the
     *  transport, or held while a stream is being written (ctx is the session itself). */
    void (*write)(void *ctx, const char *line, size_t len);
    void *ctx;
    /** The transport's writer and its context, as session_init was given them (a transport buffers or drops). */
    void (*transport_write)(void *ctx, const char *line, size_t len);
    void *transport_ctx;
    /** The transport's output waiting unread, for the session to pause at SESSION_OUTPUT_HIGH; NULL: a transport
     *  that takes every line at once (stdin's), which gets no streamed answers either. */
    const byte_buffer_t *unread;
    size_t output_high;         /* unread bytes at which the session pauses (SESSION_OUTPUT_HIGH unless its
                                 * transport says otherwise: a web session's reader takes everything at once) */
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
    /* A line server's (a control socket client's) guards, emu_session_lines.c: */
    bool refuse_http;           /* a first line that is an HTTP request line ends the session, nothing of it runs */
    const char *token;          /* non-NULL: the first line must be hello with this token, or the session ends */
    bool authenticated;         /* the token was given */
    unsigned long lines_seen;   /* lines the session sent, refused ones too */
    /* Set by the session, acted on by its transport (which closes it): */
    const char *hang_up;        /* why the session must end (a static text for the log), NULL: it goes on */
    bool overflow;              /* more than SESSION_HELD_MAX of events waited behind a streamed answer */
    /* Work waiting (emu_session_work.c): */
    byte_buffer_t in;           /* bytes received and not yet run: whole lines, then at most a partial one */
    size_t lines_waiting;       /* newlines in `in` */
    session_stream_t stream;    /* step non-NULL: an answer is being written */
    byte_buffer_t held;         /* events written while the stream runs */
} emu_session_t;

/** A session with no subscriptions, writing through write(ctx, ...). */
void session_init(emu_session_t *s, const char *name, void (*write)(void *ctx, const char *line, size_t len), void *ctx);

/** Frees what the session holds (its waiting input, a stream's held events); the transport frees the rest. */
void session_free(emu_session_t *s);

/* ---- Work waiting, and the pass's budget for it (emu_session_work.c) ------------------------------------------ */

/** Work of all sessions together in one pass of the main loop, at most (beyond the first unit): node deadlines
 *  and frames come between. */
#define SESSION_PASS_BUDGET_US 2000U

/** Bytes the session can still take as input (SESSION_INPUT_MAX less what waits). */
size_t session_input_room(const emu_session_t *s);

/** Queues bytes a client sent (at most session_input_room); they run in sessions_work, a line at a time. */
void session_input(struct emu *emu, emu_session_t *s, const char *data, size_t n);

/** Whether work waits for the session (a line to run, a stream to continue), whatever its output. */
bool session_busy(const emu_session_t *s);

/** Runs waiting work of every session of emu, round-robin, one unit at a time (a line, or a piece of a stream),
 *  until none is left that may run (a session whose reader lags at its output_high waits) or stop_at has
 *  passed (the clock is read after each unit; the first unit always runs). Returns whether work that may run is
 *  left: the loop then does not sleep. */
bool sessions_work(struct emu *emu, co_time_us_t stop_at);

/** Runs waiting work of s alone, at most max_units units (lines, pieces of a stream), while it may run: what a
 *  web exchange answers at once (emu_web_sessions.c); the rest waits for sessions_work. */
void session_work_units(struct emu *emu, emu_session_t *s, unsigned max_units);

/** Starts a streamed answer: step will be called until it returns false. false when the session cannot stream
 *  (unread NULL): the caller answers at once. */
bool session_stream_start(emu_session_t *s, const session_stream_t *stream);

/** A piece of the streamed answer's line, to the transport. */
void session_stream_write(emu_session_t *s, const char *data, size_t n);

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
