/*
 * Text shown to a person: the log, the replies to commands, events' text lines (emu_output.c, emu_events.c). What
 * they show comes partly from others: values from any SDO client on the bus, names from EDS files, words from
 * control clients. None of it may reach a terminal as something the terminal acts on instead of showing it
 * (ESC[2J clears the screen, an OSC sequence sets the window title, CR overwrites the line).
 *
 * Kept as they are: printable ASCII (0x20..0x7E), UTF-8 sequences of printable characters (from U+00A0; shortest
 * form, no surrogates, at most U+10FFFF: RFC 3629) and, in a multi-line reply, the line breaks. Every other byte is
 * written as \xNN (two lower-case hex digits): the C0 controls (ESC, CR, BS, BEL, TAB; a line break in a log line
 * or an event, which would forge the next line), DEL, the C1 controls U+0080..U+009F (terminals that take 8-bit
 * controls read U+009B as CSI) and each byte of a sequence that is not UTF-8. A backslash stays as it is: these
 * escapes make a line safe to show, not reversible (the text `get` shows a string value as a C string, every byte
 * recoverable: devices/device.c).
 *
 * Inline in this header: the fuzz target of the control path (tests/fuzz/target_control.c) links emu_events.c but
 * replaces emu_output.c, and needs the escaping all the same.
 */
#ifndef TEXT_ESCAPE_H
#define TEXT_ESCAPE_H

#include <stddef.h>
#include <string.h>

typedef enum text_lines {
    TEXT_ONE_LINE, /* a line break is escaped too: a log line, an event */
    TEXT_LINES     /* line breaks kept: a multi-line reply (help) */
} text_lines_t;

/* The length of the UTF-8 sequence of one printable character at in[0..left), or 0: a C1 control (U+0080..U+009F),
 * an overlong form, a surrogate, a code point beyond U+10FFFF, a sequence cut short or a byte that starts none
 * (RFC 3629's table of well-formed sequences). */
static inline size_t text_printable_utf8(const unsigned char *in, size_t left)
{
    const unsigned char b = in[0];
    size_t n;
    unsigned char lo = 0x80U, hi = 0xBFU; /* the range of the second byte */
    if (b == 0xC2U) {
        n = 2U;
        lo = 0xA0U; /* C2 80..C2 9F are the C1 controls */
    } else if (b >= 0xC3U && b <= 0xDFU) {
        n = 2U;
    } else if (b == 0xE0U) {
        n = 3U;
        lo = 0xA0U;
    } else if (b == 0xEDU) {
        n = 3U;
        hi = 0x9FU;
    } else if (b >= 0xE1U && b <= 0xEFU) {
        n = 3U;
    } else if (b == 0xF0U) {
        n = 4U;
        lo = 0x90U;
    } else if (b >= 0xF1U && b <= 0xF3U) {
        n = 4U;
    } else if (b == 0xF4U) {
        n = 4U;
        hi = 0x8FU;
    } else {
        return 0U;
    }
    if (left < n || in[1] < lo || in[1] > hi) {
        return 0U;
    }
    for (size_t i = 2U; i < n; i++) {
        if (in[i] < 0x80U || in[i] > 0xBFU) {
            return 0U;
        }
    }
    return n;
}

/* in[0..len) escaped as above into out: at most cap bytes, no NUL added, cut before an escape or a character
 * that would not fit whole. Returns the bytes written. */
static inline size_t text_escape(char *out, size_t cap, const char *in, size_t len, text_lines_t lines)
{
    static const char hex[] = "0123456789abcdef";
    const unsigned char *u = (const unsigned char *)in;
    size_t w = 0U;
    for (size_t i = 0U; i < len;) {
        const unsigned char b = u[i];
        size_t keep = 0U;
        if ((b >= 0x20U && b < 0x7FU) || (b == '\n' && lines == TEXT_LINES)) {
            keep = 1U;
        } else if (b >= 0x80U) {
            keep = text_printable_utf8(u + i, len - i);
        }
        if (keep > 0U) {
            if (keep > cap - w) {
                break;
            }
            memcpy(out + w, in + i, keep);
            w += keep;
            i += keep;
            continue;
        }
        if (4U > cap - w) {
            break;
        }
        out[w++] = '\\';
        out[w++] = 'x';
        out[w++] = hex[b >> 4];
        out[w++] = hex[b & 0x0FU];
        i++;
    }
    return w;
}

#endif /* TEXT_ESCAPE_H */
