/*
 * Fuzz target "socketcand": the protocol of canopen-emu's --socketcand server (emu/socketcand/socketcand_proto.c), as the
 * server takes whatever a TCP client sends: the bytes cut into items by the reader, in pieces whose sizes the input
 * chooses (a client's bytes arrive in any split), each command read, each frame it sends written back as the
 * server writes frames.
 *
 * Input: byte 0 chooses the piece size (1..256, 0: all at once); the rest is the connection's bytes. Invariants (a
 * violation prints "==fuzz== INVARIANT VIOLATION [socketcand] ..." and aborts):
 *  - the reader takes at least one byte of each piece until it is used, never more than it was given, and an item
 *    other than SOCKETCAND_MORE only once;
 *  - SOCKETCAND_FOREIGN comes at most once, and only for a connection whose first byte other than white space is not
 *    '<'; nothing is read as a command after it (the server closes the connection there);
 *  - a command is '<' ... '>' of at most SOCKETCAND_COMMAND_MAX bytes, NUL-terminated, with no other '>';
 *  - a command read as a frame has DLC 0..8, an identifier below 0x800 (2^29 with EFF), flags RTR and EFF only,
 *    the bytes past its DLC (all of a remote frame's) zero; a refusal says why, without '<' or '>' (it is written
 *    inside "< error ... >");
 *  - the frame written back fits, is "< frame ...>" or "< rtr ...>" with the identifier's 3 or 8 digits, and
 *    written as a send command it is read back as the same frame (what another client of the channel would send);
 *  - no crash, leak or undefined behaviour.
 */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_abort.h"
#include "socketcand/socketcand_proto.h"

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void violation(const char *fmt, ...)
{
    fprintf(stderr, "==fuzz== INVARIANT VIOLATION [socketcand] ");
    va_list ap;
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

static void check_frame(const co_frame_t *f)
{
    const bool eff = (f->flags & CO_FRAME_EFF) != 0U;
    if (f->len > 8U || (f->flags & ~(CO_FRAME_RTR | CO_FRAME_EFF)) != 0U || f->id >= (eff ? 0x20000000U : 0x800U)) {
        violation("frame id 0x%X flags 0x%02X len %u", (unsigned)f->id, f->flags, f->len);
    }
    const unsigned first_zero = (f->flags & CO_FRAME_RTR) != 0U ? 0U : f->len;
    for (unsigned i = first_zero; i < 8U; i++) {
        if (f->data[i] != 0U) {
            violation("byte %u past the data of a frame of %u is 0x%02X", i, f->len, f->data[i]);
        }
    }
    char text[SOCKETCAND_FRAME_TEXT_MAX];
    const size_t n = socketcand_format_frame(f, 1767225600U, 123456U, text, sizeof text);
    const char *kind = (f->flags & CO_FRAME_RTR) != 0U ? "< rtr " : "< frame ";
    if (n == 0U || n != strlen(text) || strncmp(text, kind, strlen(kind)) != 0 || text[n - 1U] != '>') {
        violation("frame id 0x%X written as '%s'", (unsigned)f->id, text);
    }
    const size_t digits = strcspn(text + strlen(kind), " ");
    if (digits != (eff ? 8U : 3U)) {
        violation("'%s': %zu digits of the identifier", text, digits);
    }
    /* the same frame as a client sends it */
    char send[SOCKETCAND_COMMAND_MAX];
    int len = snprintf(send, sizeof send, "< %s %0*X %u", (f->flags & CO_FRAME_RTR) != 0U ? "sendrtr" : "send",
                       eff ? 8 : 3, (unsigned)f->id, f->len);
    for (unsigned i = 0U; (f->flags & CO_FRAME_RTR) == 0U && i < f->len; i++) {
        len += snprintf(send + len, sizeof send - (size_t)len, " %x", f->data[i]);
    }
    len += snprintf(send + len, sizeof send - (size_t)len, " >");
    socketcand_command_t back;
    socketcand_parse(send, (size_t)len, &back);
    if (back.verb != SOCKETCAND_SEND || memcmp(&back.frame, f, sizeof *f) != 0) {
        violation("'%s' was not read back as the frame it came from", send);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0U) {
        return 0;
    }
    const size_t piece = data[0] == 0U ? size : (size_t)data[0];
    const char *bytes = (const char *)data + 1;
    const size_t total = size - 1U;
    /* the first byte other than white space, as the server's rule sees it */
    size_t first = 0U;
    while (first < total && (bytes[first] == ' ' || bytes[first] == '\t' || bytes[first] == '\r' ||
                             bytes[first] == '\n')) {
        first++;
    }
    socketcand_reader_t r;
    socketcand_reader_init(&r);
    bool foreign = false;
    for (size_t at = 0U; at < total && !foreign;) {
        const size_t end = total - at < piece ? total : at + piece;
        while (at < end && !foreign) {
            size_t used = 0U;
            const socketcand_item_t item = socketcand_reader_take(&r, bytes + at, end - at, &used);
            if (used > end - at || (used == 0U && item == SOCKETCAND_MORE)) {
                violation("took %zu of %zu bytes (item %d)", used, end - at, (int)item);
            }
            if (used == 0U && item != SOCKETCAND_JUNK) {
                violation("item %d without taking a byte", (int)item); /* only a junk run ends before a '<' */
            }
            at += used;
            switch (item) {
            case SOCKETCAND_FOREIGN:
                if (first >= total || bytes[first] == '<' || at != first + 1U) {
                    violation("foreign at byte %zu; the first byte other than white space is at %zu", at - 1U, first);
                }
                foreign = true;
                break;
            case SOCKETCAND_COMMAND: {
                if (r.len < 2U || r.len > SOCKETCAND_COMMAND_MAX || r.cmd[0] != '<' || r.cmd[r.len - 1U] != '>' ||
                    r.cmd[r.len] != '\0' || memchr(r.cmd, '>', r.len - 1U) != NULL) {
                    violation("a command of %zu bytes: '%.*s'", r.len, (int)r.len, r.cmd);
                }
                socketcand_command_t cmd;
                socketcand_parse(r.cmd, r.len, &cmd);
                if (cmd.verb == SOCKETCAND_SEND) {
                    check_frame(&cmd.frame);
                } else if (cmd.verb == SOCKETCAND_BAD || cmd.verb == SOCKETCAND_UNSUPPORTED) {
                    if (cmd.why == NULL || cmd.why[0] == '\0' || strpbrk(cmd.why, "<>") != NULL) {
                        violation("a refusal of '%s' without a reason fit for an error line", r.cmd);
                    }
                } else if (cmd.verb == SOCKETCAND_OPEN &&
                           (cmd.channel[0] == '\0' || strlen(cmd.channel) >= SOCKETCAND_CHANNEL_MAX)) {
                    violation("open of a channel named '%s'", cmd.channel);
                }
                break;
            }
            default:
                break;
            }
        }
    }
    /* a frame of any bits the bus could give is written within bounds */
    if (total >= 14U) {
        co_frame_t f;
        memcpy(&f.id, bytes, sizeof f.id);
        f.len = (uint8_t)bytes[4];
        f.flags = (uint8_t)bytes[5];
        memcpy(f.data, bytes + 6, sizeof f.data);
        char text[SOCKETCAND_FRAME_TEXT_MAX];
        const size_t n = socketcand_format_frame(&f, UINT64_MAX / 2U, UINT32_MAX, text, sizeof text);
        if (n == 0U || n >= sizeof text || strlen(text) != n) {
            violation("frame id 0x%X len %u flags 0x%02X not written within %zu bytes", (unsigned)f.id, f.len,
                      f.flags, sizeof text);
        }
    }
    return 0;
}
