/* See avr_rt.h. */
#include "avr_rt.h"

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>

/* Before main: the transmitter on (1 Mbit/s at 16 MHz; simavr does not care about the rate). */
__attribute__((used, naked, section(".init8"))) static void usart_on(void)
{
    UBRR0 = 0U;
    UCSR0B = (uint8_t)(1U << TXEN0);
}

void co_avr_putc(int c)
{
    while ((UCSR0A & (1U << UDRE0)) == 0U) {
    }
    UDR0 = (uint8_t)c;
}

/* simavr prints a line when it receives its '\n'; the last one waits until the transmitter is empty. */
void co_avr_flush(void)
{
    while ((UCSR0A & (1U << UDRE0)) == 0U) {
    }
}

/* The stack grows down from the end of SRAM towards the data: a test whose data leaves too little room would
 * overwrite them silently. So the free SRAM is painted before main, and the paint left at the end tells how
 * much of it the stack never reached (printed for tools/avr-tests, which fails a test below its minimum). */
#define CO_AVR_PAINT 0xC5U
extern uint8_t __heap_start;

__attribute__((used, naked, section(".init5"))) static void paint(void)
{
    for (uint8_t *p = &__heap_start; p < (uint8_t *)SP - 32U; p++) {
        *p = CO_AVR_PAINT;
    }
}

__attribute__((noinline)) static void print_stack_margin(void)
{
    unsigned margin = 0U;
    for (const uint8_t *p = &__heap_start; *p == CO_AVR_PAINT && p < (const uint8_t *)SP; p++) {
        margin++;
    }
    char digits[6];
    unsigned n = 0U;
    do {
        digits[n++] = (char)('0' + margin % 10U);
        margin /= 10U;
    } while (margin > 0U);
    for (const char *s = "avr-stack-margin: "; *s != '\0'; s++) {
        co_avr_putc(*s);
    }
    while (n > 0U) {
        co_avr_putc(digits[--n]);
    }
    co_avr_putc('\n');
}

/* After main returns (avr-libc's exit runs .fini9 down to .fini0): simavr ends the run at a sleep with
 * interrupts off, instead of the endless loop avr-libc would enter. */
__attribute__((used, naked, section(".fini1"))) static void stop(void)
{
    print_stack_margin();
    co_avr_flush();
    cli();
    sleep_cpu();
}
