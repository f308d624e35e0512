/*
 * The writer of the event lines (emu_events.c): text appended to a buffer the caller owns (no allocation, no
 * formatting call), JSON members among it. Events have a fixed shape, and one is written for every frame a
 * subscriber takes, so they are not built as a Jansson tree (docs/decisions.md, "Events written by code of our own").
 *
 * The JSON is byte for byte what Jansson's json_dumps(JSON_COMPACT | JSON_ENSURE_ASCII) writes for the same object
 * (tests/native/test_event_writer.c compares them): a string as the control protocol's jstr() makes it
 * (emu/control/emu_json.c): valid UTF-8 is kept, written as ASCII (\uXXXX with upper-case hex digits, a surrogate pair
 * beyond U+FFFF; \" \\ \b \f \n \r \t; the other C0 controls as \u00XX; DEL as it is); a string that is not UTF-8
 * (RFC 3629: no overlong form, no surrogate, nothing beyond U+10FFFF) has each byte from 0x80 replaced by '?' and is
 * cut to its first 4,095 bytes.
 *
 * What does not fit is cut off (a text as snprintf cuts it) and the writer is then `full`: a JSON line that is full is
 * not whole and must not be sent.
 */
#ifndef EMU_EVENT_WRITER_H
#define EMU_EVENT_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct event_writer {
    char *buf;
    size_t cap;
    size_t len;
    bool full;  /* something did not fit: buf[0..len) is not the line that was asked for */
} event_writer_t;

/** An empty line in buf[0..cap). */
void writer_init(event_writer_t *w, char *buf, size_t cap);

/** n bytes as they are. */
void writer_bytes(event_writer_t *w, const char *bytes, size_t n);

/** A NUL-terminated text as it is. */
void writer_text(event_writer_t *w, const char *text);

/** v in decimal. */
void writer_uint(event_writer_t *w, uint64_t v);

/** v in upper-case hex, at least min_digits digits (leading zeros), at most 16. */
void writer_hex_uint(event_writer_t *w, uint64_t v, unsigned min_digits);

/** Two upper-case hex digits a byte. */
void writer_hex_bytes(event_writer_t *w, const uint8_t *bytes, size_t n);

/** A time in µs as seconds with 6 decimals ("12.000345"), as printf's "%.6f" writes us / 1e6. */
void writer_seconds(event_writer_t *w, uint64_t us);

/** A JSON string, quotes included, of text as the header says. */
void writer_json_string(event_writer_t *w, const char *text);

/** A JSON object's member after the first: ,"key":value. key is the program's own (written as it is: no byte that
 *  needs escaping). */
void writer_member_string(event_writer_t *w, const char *key, const char *value);
void writer_member_uint(event_writer_t *w, const char *key, uint64_t value);
void writer_member_bool(event_writer_t *w, const char *key, bool value);
/** Bytes as a string of two upper-case hex digits a byte (as the control protocol's hex_string). */
void writer_member_hex(event_writer_t *w, const char *key, const uint8_t *bytes, size_t n);

#endif /* EMU_EVENT_WRITER_H */
