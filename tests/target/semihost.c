/* ARM semihosting calls (bkpt 0xAB on M-profile): SYS_WRITE0 for text, SYS_EXIT_EXTENDED for the status. */
#include "semihost.h"

#include <stdint.h>

enum { SYS_WRITE0 = 0x04, SYS_EXIT_EXTENDED = 0x20 };
#define ADP_STOPPED_APPLICATION_EXIT 0x20026UL

static int32_t semihost_call(int32_t op, const void *arg)
{
    register int32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static char line[128];
static unsigned line_len;

void co_target_flush(void)
{
    if (line_len > 0U) {
        line[line_len] = '\0';
        (void)semihost_call(SYS_WRITE0, line);
        line_len = 0U;
    }
}

void co_target_putc(int c)
{
    line[line_len++] = (char)c;
    if (c == '\n' || line_len == sizeof line - 1U) {
        co_target_flush();
    }
}

void co_target_exit(int status)
{
    co_target_flush();
    const uint32_t block[2] = {ADP_STOPPED_APPLICATION_EXIT, (uint32_t)status};
    for (;;) {
        (void)semihost_call(SYS_EXIT_EXTENDED, block);
    }
}
