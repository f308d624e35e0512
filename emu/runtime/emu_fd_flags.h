/*
 * O_NONBLOCK on a descriptor this process shares with others (stdin on a terminal is the shell's too), put back
 * when the program ends: at any return from main or exit(), which includes the ends SIGINT and SIGTERM give it (the
 * main loop stops and main returns). A terminal left non-blocking made the shell's next read fail with EAGAIN.
 * SIGKILL or a crash leaves it set.
 */
#ifndef EMU_FD_FLAGS_H
#define EMU_FD_FLAGS_H

#include <stdbool.h>

/** Sets O_NONBLOCK on fd and remembers to clear it again at exit if it was clear. false if fcntl fails. */
bool fd_flags_set_nonblock(int fd);

/** Clears O_NONBLOCK again where fd_flags_set_nonblock set it (registered with atexit; may be called before). */
void fd_flags_restore(void);

#endif /* EMU_FD_FLAGS_H */
