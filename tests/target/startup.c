/*
 * Minimal Cortex-M startup for the target tests: vector table, .data copy, .bss clear, main(), exit
 * status through semihosting. Faults print their name and exit with status 99.
 */
#include <stdint.h>
#include <stdio.h>

#include "semihost.h"

extern uint32_t __data_load[], __data_start[], __data_end[], __bss_start[], __bss_end[], __stack_top[];
int main(void);

/* picolibc's stdio wants a stdout; nothing in the tests prints through it, but unity.c references it. */
static int stdout_put(char c, FILE *f)
{
    (void)f;
    co_target_putc((unsigned char)c);
    return (unsigned char)c;
}
static FILE stdout_file = FDEV_SETUP_STREAM(stdout_put, NULL, NULL, _FDEV_SETUP_WRITE);
FILE *const stdout = &stdout_file;

void co_target_reset(void) __attribute__((noreturn));
void co_target_reset(void)
{
    const uint32_t *src = __data_load;
    for (uint32_t *dst = __data_start; dst < __data_end;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = __bss_start; dst < __bss_end;) {
        *dst++ = 0U;
    }
    co_target_exit(main());
}

static void fault(const char *name)
{
    for (const char *p = name; *p != '\0'; p++) {
        co_target_putc(*p);
    }
    co_target_putc('\n');
    co_target_exit(99);
}

static void nmi(void) { fault("target: NMI"); }
static void hard_fault(void) { fault("target: HardFault"); }
static void other_fault(void) { fault("target: MemManage/BusFault/UsageFault"); }
static void unexpected(void) { fault("target: unexpected exception"); }

typedef void (*vector_t)(void);
__attribute__((section(".vectors"), used)) static const vector_t vectors[16] = {
    (vector_t)(uintptr_t)__stack_top, co_target_reset, nmi, hard_fault, other_fault, other_fault, other_fault,
    0, 0, 0, 0, unexpected, unexpected, 0, unexpected, unexpected};
