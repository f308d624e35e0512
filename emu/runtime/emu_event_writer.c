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

void writer_bytes_cut(event_writer_t *w, const char *bytes, size_t n)
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

/* "00".."99": two decimal digits a division. */
static const char two_digits[200] = {
    '0', '0', '0', '1', '0', '2', '0', '3', '0', '4', '0', '5', '0', '6', '0', '7', '0', '8', '0', '9',
    '1', '0', '1', '1', '1', '2', '1', '3', '1', '4', '1', '5', '1', '6', '1', '7', '1', '8', '1', '9',
    '2', '0', '2', '1', '2', '2', '2', '3', '2', '4', '2', '5', '2', '6', '2', '7', '2', '8', '2', '9',
    '3', '0', '3', '1', '3', '2', '3', '3', '3', '4', '3', '5', '3', '6', '3', '7', '3', '8', '3', '9',
    '4', '0', '4', '1', '4', '2', '4', '3', '4', '4', '4', '5', '4', '6', '4', '7', '4', '8', '4', '9',
    '5', '0', '5', '1', '5', '2', '5', '3', '5', '4', '5', '5', '5', '6', '5', '7', '5', '8', '5', '9',
    '6', '0', '6', '1', '6', '2', '6', '3', '6', '4', '6', '5', '6', '6', '6', '7', '6', '8', '6', '9',
    '7', '0', '7', '1', '7', '2', '7', '3', '7', '4', '7', '5', '7', '6', '7', '7', '7', '8', '7', '9',
    '8', '0', '8', '1', '8', '2', '8', '3', '8', '4', '8', '5', '8', '6', '8', '7', '8', '8', '8', '9',
    '9', '0', '9', '1', '9', '2', '9', '3', '9', '4', '9', '5', '9', '6', '9', '7', '9', '8', '9', '9'};

void writer_uint(event_writer_t *w, uint64_t v)
{
    char digits[20]; /* 2^64 - 1 has 20 */
    size_t i = sizeof digits;
    while (v >= 100U) {
        const size_t pair = (size_t)(v % 100U) * 2U;
        v /= 100U;
        i -= 2U;
        digits[i] = two_digits[pair];
        digits[i + 1U] = two_digits[pair + 1U];
    }
    if (v >= 10U) {
        i -= 2U;
        digits[i] = two_digits[v * 2U];
        digits[i + 1U] = two_digits[v * 2U + 1U];
    } else {
        digits[--i] = (char)('0' + (char)v);
    }
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

/* "00".."FF": the two hex digits of each byte value, one load a byte. */
static const char hex_pairs[2U * 256U + 1U] =
    "000102030405060708090A0B0C0D0E0F"
    "101112131415161718191A1B1C1D1E1F"
    "202122232425262728292A2B2C2D2E2F"
    "303132333435363738393A3B3C3D3E3F"
    "404142434445464748494A4B4C4D4E4F"
    "505152535455565758595A5B5C5D5E5F"
    "606162636465666768696A6B6C6D6E6F"
    "707172737475767778797A7B7C7D7E7F"
    "808182838485868788898A8B8C8D8E8F"
    "909192939495969798999A9B9C9D9E9F"
    "A0A1A2A3A4A5A6A7A8A9AAABACADAEAF"
    "B0B1B2B3B4B5B6B7B8B9BABBBCBDBEBF"
    "C0C1C2C3C4C5C6C7C8C9CACBCCCDCECF"
    "D0D1D2D3D4D5D6D7D8D9DADBDCDDDEDF"
    "E0E1E2E3E4E5E6E7E8E9EAEBECEDEEEF"
    "F0F1F2F3F4F5F6F7F8F9FAFBFCFDFEFF";

void writer_hex_bytes(event_writer_t *w, const uint8_t *bytes, size_t n)
{
    if (w->full || n > (w->cap - w->len) / 2U) {
        w->full = true;
        return;
    }
    char *out = w->buf + w->len;
    for (size_t i = 0U; i < n; i++) {
        memcpy(out + 2U * i, &hex_pairs[2U * bytes[i]], 2U);
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

/* The bytes Jansson writes as they are: printable ASCII but '"' and '\\', and DEL (JSON_ENSURE_ASCII escapes only
 * code points from U+0080). A table: the test of each byte of a string is one load. */
static const bool json_plain_bytes[256] = {
    /* 0x00..0x1F: controls (and the NUL that ends a string) */
    [0x20] = 1, [0x21] = 1, /* 0x22 '"' */ [0x23] = 1, [0x24] = 1, [0x25] = 1, [0x26] = 1, [0x27] = 1,
    [0x28] = 1, [0x29] = 1, [0x2A] = 1, [0x2B] = 1, [0x2C] = 1, [0x2D] = 1, [0x2E] = 1, [0x2F] = 1,
    [0x30] = 1, [0x31] = 1, [0x32] = 1, [0x33] = 1, [0x34] = 1, [0x35] = 1, [0x36] = 1, [0x37] = 1,
    [0x38] = 1, [0x39] = 1, [0x3A] = 1, [0x3B] = 1, [0x3C] = 1, [0x3D] = 1, [0x3E] = 1, [0x3F] = 1,
    [0x40] = 1, [0x41] = 1, [0x42] = 1, [0x43] = 1, [0x44] = 1, [0x45] = 1, [0x46] = 1, [0x47] = 1,
    [0x48] = 1, [0x49] = 1, [0x4A] = 1, [0x4B] = 1, [0x4C] = 1, [0x4D] = 1, [0x4E] = 1, [0x4F] = 1,
    [0x50] = 1, [0x51] = 1, [0x52] = 1, [0x53] = 1, [0x54] = 1, [0x55] = 1, [0x56] = 1, [0x57] = 1,
    [0x58] = 1, [0x59] = 1, [0x5A] = 1, [0x5B] = 1, /* 0x5C '\\' */ [0x5D] = 1, [0x5E] = 1, [0x5F] = 1,
    [0x60] = 1, [0x61] = 1, [0x62] = 1, [0x63] = 1, [0x64] = 1, [0x65] = 1, [0x66] = 1, [0x67] = 1,
    [0x68] = 1, [0x69] = 1, [0x6A] = 1, [0x6B] = 1, [0x6C] = 1, [0x6D] = 1, [0x6E] = 1, [0x6F] = 1,
    [0x70] = 1, [0x71] = 1, [0x72] = 1, [0x73] = 1, [0x74] = 1, [0x75] = 1, [0x76] = 1, [0x77] = 1,
    [0x78] = 1, [0x79] = 1, [0x7A] = 1, [0x7B] = 1, [0x7C] = 1, [0x7D] = 1, [0x7E] = 1, [0x7F] = 1,
    /* 0x80..0xFF: non-ASCII, escaped as the code point they are part of */
};

static inline bool json_plain(unsigned char b) { return json_plain_bytes[b]; }

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
