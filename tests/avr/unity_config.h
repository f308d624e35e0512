/* Unity output on the AVR: USART0 (tests/avr/avr_rt.c). Included through UNITY_INCLUDE_CONFIG_H. */
#ifndef CO_AVR_UNITY_CONFIG_H
#define CO_AVR_UNITY_CONFIG_H
#define UNITY_OUTPUT_CHAR(a) co_avr_putc(a)
#define UNITY_OUTPUT_CHAR_HEADER_DECLARATION co_avr_putc(int)
#define UNITY_OUTPUT_FLUSH() co_avr_flush()
#define UNITY_OUTPUT_FLUSH_HEADER_DECLARATION co_avr_flush(void)
#endif
