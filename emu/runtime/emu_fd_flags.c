/* O_NONBLOCK put back at exit: see emu_fd_flags.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_fd_flags.h"

#include <fcntl.h>
#include <stdlib.h>

/* stdin, stdout, stderr: the only descriptors the program shares. */
#define MAX_CHANGED 3

static int changed[MAX_CHANGED];
static int n_changed;
static bool registered;

bool fd_flags_set_nonblock(int fd)
{
    const int flags = fcntl(fd, F_GETFL);
    if (flags < 0) {
        return false;
    }
    if ((flags & O_NONBLOCK) != 0) {
        return true; /* someone else's choice: left as it is at exit */
    }
    if (n_changed == MAX_CHANGED || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) {
        return false;
    }
    changed[n_changed++] = fd;
    if (!registered) {
        registered = atexit(fd_flags_restore) == 0;
    }
    return true;
}

void fd_flags_restore(void)
{
    /* Only the bit: other flags of a shared description may have been changed since by its other users. */
    for (int i = 0; i < n_changed; i++) {
        const int flags = fcntl(changed[i], F_GETFL);
        if (flags >= 0) {
            (void)fcntl(changed[i], F_SETFL, flags & ~O_NONBLOCK);
        }
    }
    n_changed = 0;
}
