/* The socketcand protocol's commands and frames: see socketcand_proto.h. */
#include "socketcand/socketcand_proto.h"

#include <stdio.h>
#include <string.h>

static bool is_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n';
}

void socketcand_reader_init(socketcand_reader_t *r)
{
    memset(r, 0, sizeof *r);
}

socketcand_item_t socketcand_reader_take(socketcand_reader_t *r, const char *data, size_t len, size_t *used)
{
    size_t i = 0U;
    while (i < len) {
        const char ch = data[i];
        if (r->inside) {
            i++;
            if (r->skipping) {
                if (ch == '>') {
                    r->inside = false;
                    r->skipping = false;
                }
                continue;
            }
            if (r->len == SOCKETCAND_COMMAND_MAX) {
                /* no room for this byte: the command is refused now, the rest of it dropped as it comes */
                r->inside = ch != '>';
                r->skipping = r->inside;
                r->len = 0U;
                *used = i;
                return SOCKETCAND_OVERLONG;
            }
            r->cmd[r->len++] = ch;
            if (ch == '>') {
                r->cmd[r->len] = '\0';
                r->inside = false;
                *used = i;
                return SOCKETCAND_COMMAND;
            }
            continue;
        }
        if (ch == '<') {
            if (r->junk > 0U) {
                r->junk = 0U; /* the run before it ends here; the '<' is taken with the next call */
                *used = i;
                return SOCKETCAND_JUNK;
            }
            r->started = true;
            r->inside = true;
            r->cmd[0] = '<';
            r->len = 1U;
            i++;
            continue;
        }
        i++;
        if (is_space(ch)) {
            if (r->junk > 0U) {
                r->junk = 0U;
                *used = i;
                return SOCKETCAND_JUNK;
            }
            continue;
        }
        if (!r->started) {
            r->started = true;
            *used = i;
            return SOCKETCAND_FOREIGN;
        }
        if (++r->junk == SOCKETCAND_JUNK_MAX) {
            r->junk = 0U;
            *used = i;
            return SOCKETCAND_JUNK;
        }
    }
    *used = i;
    return SOCKETCAND_MORE;
}

/* ---- Commands ------------------------------------------------------------------------------------------- */

#define MAX_TOKENS 68U /* fdsend ID FLAGS LEN and 64 bytes (a CAN FD frame is recognised whole), one more */

typedef struct token {
    const char *p;
    size_t len;
} token_t;

static bool token_is(const token_t *t, const char *word)
{
    return t->len == strlen(word) && memcmp(t->p, word, t->len) == 0;
}

/* A hex number of 1..max_digits digits; false for anything else. */
static bool parse_hex(const token_t *t, size_t max_digits, uint32_t *value)
{
    if (t->len == 0U || t->len > max_digits) {
        return false;
    }
    uint32_t v = 0U;
    for (size_t i = 0U; i < t->len; i++) {
        const char ch = t->p[i];
        uint32_t d;
        if (ch >= '0' && ch <= '9') {
            d = (uint32_t)(ch - '0');
        } else if (ch >= 'a' && ch <= 'f') {
            d = (uint32_t)(ch - 'a') + 10U;
        } else if (ch >= 'A' && ch <= 'F') {
            d = (uint32_t)(ch - 'A') + 10U;
        } else {
            return false;
        }
        v = (v << 4) | d;
    }
    *value = v;
    return true;
}

static void bad(socketcand_command_t *cmd, const char *why)
{
    cmd->verb = SOCKETCAND_BAD;
    cmd->why = why;
}

/* ID DLC [BYTES]: the frame of send (rtr: sendrtr, which has no bytes). */
static void parse_frame(const token_t *t, size_t n, bool rtr, socketcand_command_t *cmd)
{
    uint32_t id, dlc;
    if (n < 3U) {
        bad(cmd, rtr ? "sendrtr takes ID DLC" : "send takes ID DLC and the bytes");
        return;
    }
    if (!parse_hex(&t[1], 8U, &id)) {
        bad(cmd, "the ID is 1 to 8 hex digits (8 for a 29-bit identifier)");
        return;
    }
    const bool eff = t[1].len == 8U; /* socketcand's rule, and python-can writes 3 or 8 digits */
    if (id > (eff ? 0x1FFFFFFFU : 0x7FFU)) {
        bad(cmd, eff ? "a 29-bit ID is at most 1FFFFFFF" : "an 11-bit ID is at most 7FF (8 digits for 29 bits)");
        return;
    }
    if (!parse_hex(&t[2], 2U, &dlc)) {
        bad(cmd, "the DLC is 0 to 8");
        return;
    }
    if (dlc > 8U) {
        if (dlc <= 64U && !rtr && n - 3U <= dlc) {
            cmd->verb = SOCKETCAND_FD; /* python-can writes an FD frame's length so */
        } else {
            bad(cmd, "the DLC is 0 to 8");
        }
        return;
    }
    const size_t bytes = n - 3U;
    /* python-can writes a remote frame as send with its DLC and no byte */
    const bool remote = rtr || (bytes == 0U && dlc > 0U);
    if (rtr ? bytes != 0U : (!remote && bytes != dlc)) {
        bad(cmd, rtr ? "sendrtr takes ID DLC and no bytes" : "send has as many bytes as its DLC says");
        return;
    }
    memset(&cmd->frame, 0, sizeof cmd->frame);
    for (size_t i = 0U; i < bytes; i++) {
        uint32_t b;
        if (!parse_hex(&t[3U + i], 2U, &b)) {
            bad(cmd, "a byte is 1 or 2 hex digits");
            return;
        }
        cmd->frame.data[i] = (uint8_t)b;
    }
    cmd->frame.id = id;
    cmd->frame.len = (uint8_t)dlc;
    cmd->frame.flags = (uint8_t)((eff ? CO_FRAME_EFF : 0U) | (remote ? CO_FRAME_RTR : 0U));
    cmd->verb = SOCKETCAND_SEND;
}

void socketcand_parse(const char *text, size_t len, socketcand_command_t *cmd)
{
    memset(cmd, 0, sizeof *cmd);
    if (len < 2U || text[0] != '<' || text[len - 1U] != '>') {
        bad(cmd, "a command is written < ... >");
        return;
    }
    token_t t[MAX_TOKENS];
    size_t n = 0U;
    for (size_t i = 1U; i + 1U < len;) {
        if (is_space(text[i])) {
            i++;
            continue;
        }
        const size_t start = i;
        while (i + 1U < len && !is_space(text[i])) {
            if ((unsigned char)text[i] < 0x21U || (unsigned char)text[i] > 0x7EU) {
                bad(cmd, "a command is printable ASCII");
                return;
            }
            i++;
        }
        if (n == MAX_TOKENS) {
            bad(cmd, "too many fields");
            return;
        }
        t[n].p = text + start;
        t[n].len = i - start;
        n++;
    }
    if (n == 0U) {
        bad(cmd, "empty command");
        return;
    }
    static const char *const unsupported[] = {"add", "update", "delete", "filter", "muxfilter", "subscribe",
                                              "unsubscribe", "controlmode", "statistics", "isotpmode", "isotpconf",
                                              "sendpdu"};
    if (token_is(&t[0], "open")) {
        if (n != 2U || t[1].len >= SOCKETCAND_CHANNEL_MAX) {
            bad(cmd, "open takes a channel name");
            return;
        }
        memcpy(cmd->channel, t[1].p, t[1].len);
        cmd->channel[t[1].len] = '\0';
        cmd->verb = SOCKETCAND_OPEN;
    } else if (token_is(&t[0], "rawmode") || token_is(&t[0], "bcmmode") || token_is(&t[0], "echo")) {
        if (n != 1U) {
            bad(cmd, "this command takes no arguments");
            return;
        }
        cmd->verb = token_is(&t[0], "rawmode") ? SOCKETCAND_RAWMODE
                    : token_is(&t[0], "bcmmode") ? SOCKETCAND_BCMMODE : SOCKETCAND_ECHO;
    } else if (token_is(&t[0], "send")) {
        parse_frame(t, n, false, cmd);
    } else if (token_is(&t[0], "sendrtr")) {
        parse_frame(t, n, true, cmd);
    } else if (token_is(&t[0], "fdsend")) {
        cmd->verb = SOCKETCAND_FD;
    } else {
        for (size_t i = 0U; i < sizeof unsupported / sizeof unsupported[0]; i++) {
            if (token_is(&t[0], unsupported[i])) {
                cmd->verb = SOCKETCAND_UNSUPPORTED;
                cmd->why = "not served here: open, rawmode, send, sendrtr and echo are";
                return;
            }
        }
        bad(cmd, "unknown command");
    }
}

/* ---- Frames --------------------------------------------------------------------------------------------- */

size_t socketcand_format_frame(const co_frame_t *f, uint64_t sec, uint32_t usec, char *out, size_t len)
{
    const bool eff = (f->flags & CO_FRAME_EFF) != 0U;
    const int digits = eff ? 8 : 3; /* python-can takes any other count than 3 for a 29-bit identifier */
    const unsigned id = (unsigned)(f->id & (eff ? 0x1FFFFFFFU : 0x7FFU));
    const unsigned long long s = (unsigned long long)sec;
    const unsigned us = (unsigned)(usec % 1000000U);
    const unsigned dlc = f->len <= 8U ? f->len : 8U;
    int n;
    if ((f->flags & CO_FRAME_ERR) != 0U) {
        n = snprintf(out, len, "< error %03X %llu.%06u >", (unsigned)(f->id & 0x1FFFFFFFU), s, us);
    } else if ((f->flags & CO_FRAME_RTR) != 0U) {
        n = snprintf(out, len, "< rtr %0*X %llu.%06u %u >", digits, id, s, us, dlc);
    } else {
        char hex[17];
        for (unsigned i = 0U; i < dlc; i++) {
            static const char digit[] = "0123456789ABCDEF";
            hex[2U * i] = digit[f->data[i] >> 4];
            hex[2U * i + 1U] = digit[f->data[i] & 0x0FU];
        }
        hex[2U * dlc] = '\0';
        /* an empty frame keeps both spaces: python-can reads the data as the third field */
        n = snprintf(out, len, "< frame %0*X %llu.%06u %s >", digits, id, s, us, hex);
    }
    return n > 0 && (size_t)n < len ? (size_t)n : 0U;
}

bool socketcand_looks_like_http(const char *data, size_t len)
{
    size_t i = 0U;
    while (i < len && data[i] >= 'A' && data[i] <= 'Z') {
        i++;
    }
    return i >= 3U && i + 1U < len && data[i] == ' ' && (data[i + 1U] == '/' || data[i + 1U] == 'h' ||
                                                           data[i + 1U] == '*');
}
