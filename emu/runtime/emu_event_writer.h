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
#include <string.h>

typedef struct event_writer {
    char *buf;
    size_t cap;
    size_t len;
    bool full;  /* something did not fit: buf[0..len) is not the line that was asked for */
} event_writer_t;

/** An empty line in buf[0..cap). */
void writer_init(event_writer_t *w, char *buf, size_t cap);

/** writer_bytes when the bytes do not fit, or the writer is full: what fits of them. */
void writer_bytes_cut(event_writer_t *w, const char *bytes, size_t n);

/** n bytes as they are. Inline: most pieces are a few bytes of constant length, copied without a call. */
static inline void writer_bytes(event_writer_t *w, const char *bytes, size_t n)
{
    if (!w->full && n <= w->cap - w->len) {
        memcpy(w->buf + w->len, bytes, n);
        w->len += n;
    } else {
        writer_bytes_cut(w, bytes, n);
    }
}

/** A NUL-terminated text as it is. */
static inline void writer_text(event_writer_t *w, const char *text) { writer_bytes(w, text, strlen(text)); }

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

/* ---- Members of a JSON object, after its first ---------------------------------------------------------------- */

/** The key argument of the writer_member_* functions: ,"key": and its length, of a string literal (the program's
 *  own keys: no byte that needs escaping). */
#define EVENT_KEY(key) ",\"" key "\":", (sizeof ",\"" key "\":" - 1U)

static inline void writer_member_string(event_writer_t *w, const char *key, size_t key_len, const char *value)
{
    writer_bytes(w, key, key_len);
    writer_json_string(w, value);
}

/** A string the program wrote itself of bytes that need no escaping (printable ASCII but '"' and '\\'): hex digits,
 *  a name of its own tables. */
static inline void writer_member_plain(event_writer_t *w, const char *key, size_t key_len, const char *value,
                                       size_t value_len)
{
    writer_bytes(w, key, key_len);
    writer_bytes(w, "\"", 1U);
    writer_bytes(w, value, value_len);
    writer_bytes(w, "\"", 1U);
}

static inline void writer_member_uint(event_writer_t *w, const char *key, size_t key_len, uint64_t value)
{
    writer_bytes(w, key, key_len);
    writer_uint(w, value);
}

static inline void writer_member_bool(event_writer_t *w, const char *key, size_t key_len, bool value)
{
    writer_bytes(w, key, key_len);
    if (value) {
        writer_bytes(w, "true", 4U);
    } else {
        writer_bytes(w, "false", 5U);
    }
}

/** Bytes as a string of two upper-case hex digits a byte (as the control protocol's hex_string). */
static inline void writer_member_hex(event_writer_t *w, const char *key, size_t key_len, const uint8_t *bytes,
                                     size_t n)
{
    writer_bytes(w, key, key_len);
    writer_bytes(w, "\"", 1U);
    writer_hex_bytes(w, bytes, n);
    writer_bytes(w, "\"", 1U);
}

#endif /* EMU_EVENT_WRITER_H */
