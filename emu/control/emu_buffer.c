/* Bytes waiting for a reader: see emu_buffer.h. */
#define _GNU_SOURCE /* ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_buffer.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

bool byte_buffer_append(byte_buffer_t *b, const char *data, size_t n, size_t max)
{
    if (n > max || b->len > max - n) {
        return false;
    }
    if (b->len + n > b->cap) {
        size_t cap = b->cap == 0U ? 4096U : b->cap;
        while (cap < b->len + n) {
            cap *= 2U;
        }
        char *grown = realloc(b->data, cap);
        if (grown == NULL) {
            return false;
        }
        b->data = grown;
        b->cap = cap;
    }
    memcpy(b->data + b->len, data, n);
    b->len += n;
    return true;
}

void byte_buffer_consume(byte_buffer_t *b, size_t n)
{
    memmove(b->data, b->data + n, b->len - n);
    b->len -= n;
}

char *byte_buffer_take(byte_buffer_t *b, size_t *len)
{
    char *data = b->len > 0U ? b->data : NULL;
    *len = b->len;
    if (data == NULL) {
        free(b->data);
    }
    b->data = NULL;
    b->len = 0U;
    b->cap = 0U;
    return data;
}

void byte_buffer_free(byte_buffer_t *b)
{
    free(b->data);
    b->data = NULL;
    b->len = 0U;
    b->cap = 0U;
}

bool byte_buffer_send(byte_buffer_t *b, int fd)
{
    while (b->len > 0U) {
        const ssize_t w = send(fd, b->data, b->len, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (w < 0) {
            return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
        }
        byte_buffer_consume(b, (size_t)w);
    }
    return true;
}
