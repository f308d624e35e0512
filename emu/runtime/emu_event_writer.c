/* The writer of the event lines: see emu_event_writer.h. */
#include "runtime/emu_event_writer.h"

#include <string.h>

/* What jstr() keeps of a string that is not UTF-8 (its buffer of 4,096 bytes less the NUL). */
#define NOT_UTF8_KEPT 4095U

static const char hex_digits[16] = {'0', '1', '2', '3', '4', '5', '6', '7', '8', '9', 'A', 'B', 'C', 'D', 'E', 'F'};

void writer_init(event_writer_t *w, char *buf, size_t cap)
{
    w->buf = buf;
    w->cap = cap;
    w->len = 0U;
    w->full = false;
}

void writer_bytes(event_writer_t *w, const char *bytes, size_t n)
{
    if (w->full) {
        return; /* nothing after a cut */
    }
    if (n > w->cap - w->len) {
        n = w->cap - w->len; /* what fits, as snprintf cuts a text */
        w->full = true;
    }
    memcpy(w->buf + w->len, bytes, n);
    w->len += n;
}

static void writer_byte(event_writer_t *w, char c)
{
    if (w->full || w->len == w->cap) {
        w->full = true;
        return;
    }
    w->buf[w->len++] = c;
}

void writer_text(event_writer_t *w, const char *text) { writer_bytes(w, text, strlen(text)); }

void writer_uint(event_writer_t *w, uint64_t v)
{
    char digits[20]; /* 2^64 - 1 has 20 */
    size_t i = sizeof digits;
    do {
        digits[--i] = (char)('0' + (char)(v % 10U));
        v /= 10U;
    } while (v != 0U);
    writer_bytes(w, digits + i, sizeof digits - i);
}

void writer_hex_uint(event_writer_t *w, uint64_t v, unsigned min_digits)
{
    char digits[16];
    size_t i = sizeof digits;
    do {
        digits[--i] = hex_digits[v & 0x0FU];
        v >>= 4;
    } while (v != 0U || (i > 0U && sizeof digits - i < min_digits));
    writer_bytes(w, digits + i, sizeof digits - i);
}

void writer_hex_bytes(event_writer_t *w, const uint8_t *bytes, size_t n)
{
    if (w->full || n > (w->cap - w->len) / 2U) {
        w->full = true;
        return;
    }
    char *out = w->buf + w->len;
    for (size_t i = 0U; i < n; i++) {
        out[2U * i] = hex_digits[bytes[i] >> 4];
        out[2U * i + 1U] = hex_digits[bytes[i] & 0x0FU];
    }
    w->len += 2U * n;
}

void writer_seconds(event_writer_t *w, uint64_t us)
{
    writer_uint(w, us / 1000000U);
    uint32_t fraction = (uint32_t)(us % 1000000U);
    char digits[7];
    digits[0] = '.';
    for (size_t i = 6U; i > 0U; i--) {
        digits[i] = (char)('0' + (char)(fraction % 10U));
        fraction /= 10U;
    }
    writer_bytes(w, digits, sizeof digits);
}

/* ---- JSON strings, as Jansson writes them ------------------------------------------------------------------- */

/* A byte Jansson writes as it is: printable ASCII but '"' and '\\', and DEL (JSON_ENSURE_ASCII escapes only code
 * points from U+0080). */
static inline bool json_plain(unsigned char b) { return (unsigned char)(b - 0x20U) < 0x60U && b != '"' && b != '\\'; }

/* \uXXXX of one UTF-16 unit. */
static void write_u_escape(event_writer_t *w, uint32_t unit)
{
    const char seq[6] = {'\\', 'u', hex_digits[(unit >> 12) & 0x0FU], hex_digits[(unit >> 8) & 0x0FU],
                         hex_digits[(unit >> 4) & 0x0FU], hex_digits[unit & 0x0FU]};
    writer_bytes(w, seq, sizeof seq);
}

/* An ASCII byte that is not json_plain: a short escape where JSON has one, \u00XX otherwise. */
static void write_ascii_escape(event_writer_t *w, unsigned char b)
{
    char short_form;
    switch (b) {
    case '"': short_form = '"'; break;
    case '\\': short_form = '\\'; break;
    case '\b': short_form = 'b'; break;
    case '\f': short_form = 'f'; break;
    case '\n': short_form = 'n'; break;
    case '\r': short_form = 'r'; break;
    case '\t': short_form = 't'; break;
    default: write_u_escape(w, b); return;
    }
    const char seq[2] = {'\\', short_form};
    writer_bytes(w, seq, sizeof seq);
}

/* The length of the UTF-8 sequence at s (NUL-terminated) and its code point; 0 when it is none (RFC 3629, as
 * Jansson's utf8_check_full: a byte that starts none, a continuation missing, an overlong form, a surrogate, a code
 * point beyond U+10FFFF). */
static size_t utf8_decode(const unsigned char *s, uint32_t *code_point)
{
    const unsigned char b = s[0];
    size_t n;
    uint32_t v;
    if (b >= 0xC2U && b <= 0xDFU) {
        n = 2U;
        v = b & 0x1FU;
    } else if (b >= 0xE0U && b <= 0xEFU) {
        n = 3U;
        v = b & 0x0FU;
    } else if (b >= 0xF0U && b <= 0xF4U) {
        n = 4U;
        v = b & 0x07U;
    } else {
        return 0U; /* a continuation byte, 0xC0/0xC1 (overlong ASCII), 0xF5 and up */
    }
    for (size_t i = 1U; i < n; i++) {
        if ((s[i] & 0xC0U) != 0x80U) {
            return 0U; /* the NUL at the end too: a sequence cut short */
        }
        v = (v << 6) | (s[i] & 0x3FU);
    }
    if (v > 0x10FFFFU || (v >= 0xD800U && v <= 0xDFFFU) || (n == 3U && v < 0x800U) || (n == 4U && v < 0x10000U)) {
        return 0U;
    }
    *code_point = v;
    return n;
}

/* jstr()'s string for a text that is not UTF-8: its first NOT_UTF8_KEPT bytes, each from 0x80 as '?'. */
static void write_not_utf8(event_writer_t *w, const unsigned char *text)
{
    writer_byte(w, '"');
    for (size_t i = 0U; text[i] != '\0' && i < NOT_UTF8_KEPT; i++) {
        const unsigned char b = text[i];
        if (json_plain(b)) {
            writer_byte(w, (char)b);
        } else if (b >= 0x80U) {
            writer_byte(w, '?');
        } else {
            write_ascii_escape(w, b);
        }
    }
    writer_byte(w, '"');
}

void writer_json_string(event_writer_t *w, const char *text)
{
    const size_t start = w->len;
    const bool was_full = w->full;
    const unsigned char *p = (const unsigned char *)text;
    writer_byte(w, '"');
    for (;;) {
        const unsigned char *run = p;
        while (json_plain(*p)) {
            p++;
        }
        writer_bytes(w, (const char *)run, (size_t)(p - run));
        if (*p == '\0') {
            break;
        }
        if (*p < 0x80U) {
            write_ascii_escape(w, *p);
            p++;
            continue;
        }
        uint32_t cp = 0U;
        const size_t n = utf8_decode(p, &cp);
        if (n == 0U) {
            w->len = start; /* written again, as jstr() makes such a string */
            w->full = was_full;
            write_not_utf8(w, (const unsigned char *)text);
            return;
        }
        if (cp < 0x10000U) {
            write_u_escape(w, cp);
        } else {
            cp -= 0x10000U; /* a UTF-16 surrogate pair */
            write_u_escape(w, 0xD800U | (cp >> 10));
            write_u_escape(w, 0xDC00U | (cp & 0x3FFU));
        }
        p += n;
    }
    writer_byte(w, '"');
}

/* ---- Members ------------------------------------------------------------------------------------------------ */

static void write_key(event_writer_t *w, const char *key)
{
    writer_bytes(w, ",\"", 2U);
    writer_text(w, key);
    writer_bytes(w, "\":", 2U);
}

void writer_member_string(event_writer_t *w, const char *key, const char *value)
{
    write_key(w, key);
    writer_json_string(w, value);
}

void writer_member_uint(event_writer_t *w, const char *key, uint64_t value)
{
    write_key(w, key);
    writer_uint(w, value);
}

void writer_member_bool(event_writer_t *w, const char *key, bool value)
{
    write_key(w, key);
    if (value) {
        writer_bytes(w, "true", 4U);
    } else {
        writer_bytes(w, "false", 5U);
    }
}

void writer_member_hex(event_writer_t *w, const char *key, const uint8_t *bytes, size_t n)
{
    write_key(w, key);
    writer_byte(w, '"');
    writer_hex_bytes(w, bytes, n);
    writer_byte(w, '"');
}
