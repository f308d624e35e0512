/*
 * Fuzz target "udp_datagram": the decoder of python-can's udp_multicast datagrams (ports/linux/udp_datagram.c, on
 * msgpack-c), as canopen-emu's udp_multicast buses read whatever arrives on their group (docs/buses.md).
 *
 * Input: one datagram's bytes (run_fuzz.cmake's -max_len 4096: the longest datagram read). Invariants (a violation prints
 * "==fuzz== INVARIANT VIOLATION [udp_datagram] ..." and aborts):
 *  - a frame decoded is one the nodes can take: DLC 0..8, an identifier below 0x800 (2^29 when extended), no flags
 *    but RTR and EFF, the bytes past the DLC (all of a remote frame's) zero;
 *  - it encodes again, and that datagram decodes to the same frame (the round trip python-can's peers make);
 *  - a malformed datagram says why;
 *  - no crash, leak or undefined behaviour, and no allocation beyond libFuzzer's limit: msgpack-c allocates a
 *    container's entries from its header, so a header claiming more entries than the datagram has bytes must never
 *    reach it (-malloc_limit_mb catches one that does).
 */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_abort.h"
#include "udp_datagram.h"

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void violation(const char *fmt, ...)
{
    fprintf(stderr, "==fuzz== INVARIANT VIOLATION [udp_datagram] ");
    va_list ap;
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    co_frame_t f;
    char why[160] = "";
    const udp_datagram_kind_t kind = udp_datagram_decode(data, size, &f, why, sizeof why);
    if (kind == UDP_DATAGRAM_MALFORMED && why[0] == '\0') {
        violation("a malformed datagram of %zu bytes without a reason", size);
    }
    if (kind != UDP_DATAGRAM_FRAME) {
        return 0;
    }
    const bool eff = (f.flags & CO_FRAME_EFF) != 0U;
    if (f.len > 8U || (f.flags & ~(CO_FRAME_RTR | CO_FRAME_EFF)) != 0U || f.id >= (eff ? 0x20000000U : 0x800U)) {
        violation("frame id 0x%X flags 0x%02X len %u", (unsigned)f.id, f.flags, f.len);
    }
    const unsigned first_zero = (f.flags & CO_FRAME_RTR) != 0U ? 0U : f.len;
    for (unsigned i = first_zero; i < 8U; i++) {
        if (f.data[i] != 0U) {
            violation("byte %u past the data of a frame of %u is 0x%02X", i, f.len, f.data[i]);
        }
    }
    uint8_t again[256];
    const size_t n = udp_datagram_encode(&f, 1.5, again, sizeof again);
    co_frame_t back;
    if (n == 0U || udp_datagram_decode(again, n, &back, why, sizeof why) != UDP_DATAGRAM_FRAME ||
        memcmp(&back, &f, sizeof f) != 0) {
        violation("frame id 0x%X len %u did not survive encoding (%zu bytes; %s)", (unsigned)f.id, f.len, n, why);
    }
    return 0;
}
