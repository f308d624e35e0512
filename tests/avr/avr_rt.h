/*
 * Output and end of the unit tests on an AVR under simavr: characters go out through USART0 (simavr prints
 * each line it receives), and the program ends by sleeping with interrupts off (simavr then exits).
 */
#ifndef CO_AVR_RT_H
#define CO_AVR_RT_H

void co_avr_putc(int c);
void co_avr_flush(void);

#endif
