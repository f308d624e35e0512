/* The words of the command language: see device_words.h. */
#include "device_words.h"

#include <limits.h>
#include <string.h>

/* -1 when there are more than max words: the rest was once ignored and the command then met as "unknown", which
 * hid the reason. */
int device_split_words(char *line, char **argv, int max)
{
    int argc = 0;
    char *p = line;
    while (*p != '\0') {
        while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
            p++;
        }
        if (*p == '\0' || *p == '#') {
            break;
        }
        if (argc == max) {
            return -1;
        }
        if (*p == '"') {
            argv[argc++] = ++p;
            while (*p != '\0' && *p != '"') {
                p++;
            }
        } else {
            argv[argc++] = p;
            while (*p != '\0' && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n') {
                p++;
            }
        }
        if (*p != '\0') {
            *p++ = '\0';
        }
    }
    return argc;
}

/* [+|-] then decimal digits or 0x and hex digits, nothing else: strtoll's base 0 read a leading zero as octal
 * ("010" was 8, "08" no number), skipped leading blanks and clamped an overflow without a word. */
bool device_parse_magnitude(const char *text, bool *negative, unsigned long long *magnitude)
{
    const char *p = text;
    *negative = *p == '-';
    if (*p == '-' || *p == '+') {
        p++;
    }
    unsigned base = 10U;
    if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        base = 16U;
        p += 2;
    }
    if (*p == '\0') {
        return false;
    }
    unsigned long long v = 0U;
    for (; *p != '\0'; p++) {
        const char c = *p;
        const unsigned d = (c >= '0' && c <= '9') ? (unsigned)(c - '0')
                           : (c >= 'a' && c <= 'f') ? (unsigned)(c - 'a' + 10)
                           : (c >= 'A' && c <= 'F') ? (unsigned)(c - 'A' + 10) : 16U;
        if (d >= base || v > (ULLONG_MAX - d) / base) {
            return false;
        }
        v = v * base + d;
    }
    *magnitude = v;
    return true;
}

bool device_parse_int(const char *text, long long lo, long long hi, long long *out)
{
    bool negative;
    unsigned long long magnitude;
    if (text == NULL || !device_parse_magnitude(text, &negative, &magnitude)) {
        return false;
    }
    const unsigned long long most_negative = (unsigned long long)LLONG_MAX + 1U;
    long long v;
    if (negative) {
        if (magnitude > most_negative) {
            return false;
        }
        v = magnitude == most_negative ? LLONG_MIN : -(long long)magnitude;
    } else {
        if (magnitude > (unsigned long long)LLONG_MAX) {
            return false;
        }
        v = (long long)magnitude;
    }
    if (v < lo || v > hi) {
        return false;
    }
    *out = v;
    return true;
}

/* One hex field of an address: optional 0x, hex digits only. */
static bool parse_hex(const char *text, size_t n, unsigned long max, unsigned long *out)
{
    if (n > 2U && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        text += 2;
        n -= 2U;
    }
    if (n == 0U || n > 4U) {
        return false;
    }
    unsigned long v = 0U;
    for (size_t i = 0U; i < n; i++) {
        const char c = text[i];
        const int d = (c >= '0' && c <= '9') ? c - '0' : (c >= 'a' && c <= 'f') ? c - 'a' + 10 : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
        if (d < 0) {
            return false;
        }
        v = v * 16U + (unsigned long)d;
    }
    if (v > max) {
        return false;
    }
    *out = v;
    return true;
}

bool device_parse_address(const char *text, uint16_t *index, uint8_t *sub)
{
    const char *colon = strchr(text, ':');
    const size_t ilen = colon != NULL ? (size_t)(colon - text) : strlen(text);
    unsigned long i, s = 0U;
    if (!parse_hex(text, ilen, 0xFFFFU, &i) || (colon != NULL && !parse_hex(colon + 1, strlen(colon + 1), 0xFFU, &s))) {
        return false;
    }
    *index = (uint16_t)i;
    *sub = (uint8_t)s;
    return true;
}

/* The first " / " in [p, end), or end. */
static const char *next_alternative(const char *p, const char *end)
{
    for (; p + 3 <= end; p++) {
        if (p[0] == ' ' && p[1] == '/' && p[2] == ' ') {
            return p;
        }
    }
    return end;
}

bool device_help_usage(const char *help, const char *word, const char **args, size_t *args_len)
{
    const size_t word_len = strlen(word);
    if (help == NULL || word_len == 0U) {
        return false;
    }
    const char *line = help;
    while (*line != '\0') {
        const char *end = strchr(line, '\n');
        if (end == NULL) {
            end = line + strlen(line);
        }
        if (end - line > 2 && line[0] == ' ' && line[1] == ' ' && line[2] != ' ') {
            const char *usage = line + 2;
            const char *stop = usage; /* the usage column ends at two blanks in a row */
            while (stop < end && !(stop[0] == ' ' && stop + 1 < end && stop[1] == ' ')) {
                stop++;
            }
            for (const char *alt = usage; alt < stop;) {
                const char *alt_end = next_alternative(alt, stop);
                if ((size_t)(alt_end - alt) >= word_len && strncmp(alt, word, word_len) == 0 &&
                    (alt + word_len == alt_end || alt[word_len] == ' ')) {
                    const char *a = alt + word_len;
                    while (a < alt_end && *a == ' ') {
                        a++;
                    }
                    *args = a;
                    *args_len = (size_t)(alt_end - a);
                    return true;
                }
                alt = alt_end == stop ? stop : alt_end + 3;
            }
        }
        line = *end == '\n' ? end + 1 : end;
    }
    return false;
}

