/*
 * The socketcand protocol as canopen-emu's --socketcand server speaks it (docs/buses.md): cutting a client's bytes
 * into commands, reading a command, writing a frame. Pure: no I/O, no clock, no state beyond a reader's; the server
 * (emu_socketcand.c) does the rest, and the fuzz target "socketcand" drives this module alone.
 *
 * linux-can socketcand's framing: a command is everything from a '<' to the next '>', with or without line breaks
 * between commands. What the server takes, as python-can's socketcand interface (4.6.1) and socketcand's
 * doc/protocol.md use it:
 *   < open CHANNEL >           the bus of that name
 *   < rawmode >  < bcmmode >   frames of the bus are sent in rawmode only (the BCM's subscriptions are not served)
 *   < send ID DLC B0 B1 ... >  ID: 1..8 hex digits, 8 meaning a 29-bit identifier; DLC 0..8; one 1..2 digit hex
 *                              token per byte. With DLC > 0 and no byte: a remote frame (python-can writes one so)
 *   < sendrtr ID DLC >         a remote frame
 *   < echo >                   answered with itself
 * and it writes
 *   < hi >  < ok >  < echo >  < error WHY >
 *   < frame ID SEC.USEC DATA > ID as 3 or 8 hex digits (python-can tells the kinds by that), DATA the bytes as
 *                              two hex digits each without spaces, as socketcand writes them
 *   < rtr ID SEC.USEC DLC >    a remote frame (doc/protocol.md's form; python-can skips it with a warning)
 * CAN FD (fdsend, or a DLC above 8) is recognised and not carried: the caller counts it.
 */
#ifndef SOCKETCAND_PROTO_H
#define SOCKETCAND_PROTO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "co/co.h"

/** Bytes of one command from '<' to '>' at most: "< send 1FFFFFFF 8 ff ff ff ff ff ff ff ff >" has 42, a channel's
 *  name up to 79, and a CAN FD frame's send (to be counted as one, not refused) up to about 220. A longer one is
 *  refused as a whole. */
#define SOCKETCAND_COMMAND_MAX 256U
/** A run of bytes outside any command longer than this is refused (and so is a shorter one once it ends). */
#define SOCKETCAND_JUNK_MAX 128U
/** Bytes of a channel's name (with its NUL). */
#define SOCKETCAND_CHANNEL_MAX 80U
/** Bytes a formatted frame needs at most (with its NUL). */
#define SOCKETCAND_FRAME_TEXT_MAX 96U

/** Cuts a connection's bytes into commands. Zero-initialise it (or socketcand_reader_init). */
typedef struct socketcand_reader {
    char cmd[SOCKETCAND_COMMAND_MAX + 1U]; /* the command so far, from its '<' */
    size_t len;
    bool inside;     /* a '<' was taken, not its '>' yet */
    bool skipping;   /* an overlong command: its bytes are dropped up to its '>' */
    size_t junk;     /* bytes of the current run outside any command (not counting spaces) */
    bool started;    /* a byte other than white space came: the connection's first was judged */
} socketcand_reader_t;

typedef enum socketcand_item {
    SOCKETCAND_MORE,        /* every byte given was taken; no item complete */
    SOCKETCAND_COMMAND,     /* a command in r->cmd (r->len bytes, NUL-terminated, '<' to '>') */
    SOCKETCAND_OVERLONG,    /* a command longer than SOCKETCAND_COMMAND_MAX: refused, skipped to its '>' */
    SOCKETCAND_JUNK,        /* a run of bytes outside any command */
    SOCKETCAND_FOREIGN      /* the connection's first byte other than white space is not '<': not a socketcand client
                             * (an HTTP request, ...); the caller closes it with nothing done */
} socketcand_item_t;

void socketcand_reader_init(socketcand_reader_t *r);

/** Takes bytes of data[0..len) until an item is complete; *used: how many were taken (all of them with
 *  SOCKETCAND_MORE). Call again with the rest. */
socketcand_item_t socketcand_reader_take(socketcand_reader_t *r, const char *data, size_t len, size_t *used);

typedef enum socketcand_verb {
    SOCKETCAND_OPEN,
    SOCKETCAND_RAWMODE,
    SOCKETCAND_BCMMODE,
    SOCKETCAND_SEND,        /* frame: a data or remote frame to put on the bus */
    SOCKETCAND_ECHO,
    SOCKETCAND_FD,          /* a CAN FD frame: not carried */
    SOCKETCAND_UNSUPPORTED, /* a command of socketcand this server does not serve (BCM jobs, ISO-TP, ...) */
    SOCKETCAND_BAD          /* not a command: why says what is wrong */
} socketcand_verb_t;

typedef struct socketcand_command {
    socketcand_verb_t verb;
    char channel[SOCKETCAND_CHANNEL_MAX]; /* SOCKETCAND_OPEN */
    co_frame_t frame;                     /* SOCKETCAND_SEND: DLC 0..8, bytes past it zero, flags RTR and EFF only */
    const char *why;                      /* SOCKETCAND_BAD, SOCKETCAND_UNSUPPORTED: a constant without '<' or '>' */
} socketcand_command_t;

/** Reads one command (the text from '<' to '>', as the reader gives it). */
void socketcand_parse(const char *text, size_t len, socketcand_command_t *cmd);

/** Writes a frame of the bus as socketcand does (`< frame ... >`, `< rtr ... >`, `< error ... >` for an error frame)
 *  at time sec.usec (wall clock); returns its length (below SOCKETCAND_FRAME_TEXT_MAX), 0 if out is too small. */
size_t socketcand_format_frame(const co_frame_t *f, uint64_t sec, uint32_t usec, char *out, size_t len);

/** Whether the bytes begin with an HTTP request line's method and target ("POST /", "GET http:"): for the log's
 *  words about a foreign connection. */
bool socketcand_looks_like_http(const char *data, size_t len);

#endif /* SOCKETCAND_PROTO_H */
