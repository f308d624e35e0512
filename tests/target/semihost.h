/*
 * ARM semihosting for the target tests (Cortex-M under QEMU: -semihosting-config enable=on,target=native).
 * Only what the Unity harness needs: characters out, and the exit status back to the host.
 */
#ifndef CO_TARGET_SEMIHOST_H
#define CO_TARGET_SEMIHOST_H

/* Buffers one character; a full line (or a full buffer) goes out with one SYS_WRITE0 call. */
void co_target_putc(int c);
/* Writes out what is buffered. */
void co_target_flush(void);
/* Flushes, then ends the program: QEMU exits with this status (SYS_EXIT_EXTENDED). Never returns. */
void co_target_exit(int status) __attribute__((noreturn));

#endif
