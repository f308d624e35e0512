/* Unity output on the target: semihosting (tests/target/semihost.c). Included through
 * UNITY_INCLUDE_CONFIG_H by unity.c and every test of the target build. */
#ifndef CO_TARGET_UNITY_CONFIG_H
#define CO_TARGET_UNITY_CONFIG_H
#define UNITY_OUTPUT_CHAR(a) co_target_putc(a)
#define UNITY_OUTPUT_CHAR_HEADER_DECLARATION co_target_putc(int)
#define UNITY_OUTPUT_FLUSH() co_target_flush()
#define UNITY_OUTPUT_FLUSH_HEADER_DECLARATION co_target_flush(void)
#endif
