/*
 * The bytes that wait for a reader who takes them later (a control client's socket, a web session's next
 * exchange): one malloc'd block that grows by doubling, up to a ceiling the caller gives. Past the ceiling nothing
 * is added and the caller is told, so that it can drop the reader instead of the emulator waiting for it.
 */
#ifndef EMU_BUFFER_H
#define EMU_BUFFER_H

#include <stdbool.h>
#include <stddef.h>

typedef struct byte_buffer {
    char *data;     /* NULL until the first byte */
    size_t len;
    size_t cap;
} byte_buffer_t;

/** Appends n bytes. false, with nothing appended, when the buffer would hold more than max bytes or memory ran
 *  out. */
bool byte_buffer_append(byte_buffer_t *b, const char *data, size_t n, size_t max);

/** Drops the first n bytes (n <= len): those a reader took. */
void byte_buffer_consume(byte_buffer_t *b, size_t n);

/** The block itself, for a reader that takes everything at once and frees it with free(); the buffer is empty
 *  afterwards. NULL when it is empty. */
char *byte_buffer_take(byte_buffer_t *b, size_t *len);

void byte_buffer_free(byte_buffer_t *b);

/** Sends what the buffer holds to the socket fd as far as it takes it without blocking (the bytes sent are
 *  consumed). false when the peer went away (EPIPE, ECONNRESET...); true otherwise, also when some bytes wait. */
bool byte_buffer_send(byte_buffer_t *b, int fd);

#endif /* EMU_BUFFER_H */
