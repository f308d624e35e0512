/*
 * How every fuzz target ends on an invariant violation: the caller prints its own header line ("==fuzz==
 * INVARIANT VIOLATION [target] ..."), this prints the message and aborts, so libFuzzer saves the input as a
 * reproducer.
 */
#ifndef FUZZ_ABORT_H
#define FUZZ_ABORT_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 0)))
#endif
static inline void fz_vabort(const char *fmt, va_list ap)
{
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    fflush(stderr);
    abort();
}

#endif
