/*
 * The udp_multicast datagram codec (ports/linux/udp_datagram.c) from the command line, for test_udp_datagram.py to
 * compare with python-can's own packing and unpacking:
 *   datagram_tool encode ID FLAGS DLC HEXDATA TIMESTAMP   prints the datagram in hex (FLAGS: r = RTR, x = 29-bit, - none)
 *   datagram_tool decode HEX                               prints "frame ID FLAGS DLC HEXDATA", "fd", "error" or
 *                                                          "malformed: WHY"
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "udp_datagram.h"

static size_t from_hex(const char *hex, uint8_t *out, size_t cap)
{
    size_t n = 0U;
    for (; hex[0] != '\0' && hex[1] != '\0' && n < cap; hex += 2) {
        char byte[3] = {hex[0], hex[1], '\0'};
        out[n++] = (uint8_t)strtoul(byte, NULL, 16);
    }
    return n;
}

int main(int argc, char **argv)
{
    if (argc == 7 && strcmp(argv[1], "encode") == 0) {
        co_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = (uint32_t)strtoul(argv[2], NULL, 0);
        f.flags = (uint8_t)((strchr(argv[3], 'r') != NULL ? CO_FRAME_RTR : 0U) |
                            (strchr(argv[3], 'x') != NULL ? CO_FRAME_EFF : 0U));
        f.len = (uint8_t)strtoul(argv[4], NULL, 0);
        (void)from_hex(argv[5], f.data, sizeof f.data);
        uint8_t out[256];
        const size_t n = udp_datagram_encode(&f, strtod(argv[6], NULL), out, sizeof out);
        for (size_t i = 0U; i < n; i++) {
            printf("%02x", out[i]);
        }
        printf("\n");
        return n > 0U ? 0 : 1;
    }
    if (argc == 3 && strcmp(argv[1], "decode") == 0) {
        static uint8_t in[2U * UDP_DATAGRAM_MAX];
        const size_t n = from_hex(argv[2], in, sizeof in);
        co_frame_t f;
        char why[160] = "";
        switch (udp_datagram_decode(in, n, &f, why, sizeof why)) {
        case UDP_DATAGRAM_FRAME:
            printf("frame 0x%X %s%s %u ", (unsigned)f.id, (f.flags & CO_FRAME_RTR) != 0U ? "r" : "",
                   (f.flags & CO_FRAME_EFF) != 0U ? "x" : "", f.len);
            for (unsigned i = 0U; (f.flags & CO_FRAME_RTR) == 0U && i < f.len; i++) {
                printf("%02x", f.data[i]);
            }
            printf("\n");
            break;
        case UDP_DATAGRAM_FD:
            printf("fd\n");
            break;
        case UDP_DATAGRAM_ERROR_FRAME:
            printf("error\n");
            break;
        default:
            printf("malformed: %s\n", why);
            break;
        }
        return 0;
    }
    fprintf(stderr, "usage: datagram_tool encode ID FLAGS DLC HEXDATA TIMESTAMP | decode HEX\n");
    return 2;
}
