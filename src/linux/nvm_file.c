/* NVM areas in files with atomic replacement: see nvm_file.h. */
#define _GNU_SOURCE
#include "nvm_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *const suffix[3] = {"params", "lss", "device"};

static int make_dirs(const char *dir)
{
    char path[PATH_MAX];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path) {
        return ENAMETOOLONG;
    }
    for (char *p = path + 1; *p != '\0'; p++) {
        if (*p == '/') {
            *p = '\0';
            if (mkdir(path, 0755) < 0 && errno != EEXIST) {
                return errno;
            }
            *p = '/';
        }
    }
    if (mkdir(path, 0755) < 0 && errno != EEXIST) {
        return errno;
    }
    return 0;
}

int nvm_file_check_dir(const char *dir, char *err, size_t errlen)
{
    int e = make_dirs(dir);
    if (e == 0) {
        char probe[PATH_MAX];
        (void)snprintf(probe, sizeof probe, "%s/.canopen-emu-write-test.%ld", dir, (long)getpid());
        const int fd = open(probe, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd < 0) {
            e = errno;
        } else {
            (void)close(fd);
            (void)unlink(probe);
        }
    }
    if (e != 0) {
        (void)snprintf(err, errlen, "NVM directory %s is not writable (%s); choose another with --nvm-dir DIR", dir,
                       strerror(e));
    }
    return e;
}

/* Largest blob an area takes: the core's parameter blob is at most 16 + 64 KiB. */
#define NVM_FILE_MAX (1UL << 20)

int nvm_file_open(nvm_file_t *n, const char *dir, const char *key, char *err, size_t errlen)
{
    memset(n, 0, sizeof *n);
    /* Before anything can fail: nvm_file_close() after a failed open must not close descriptor 0. */
    for (int a = 0; a < 3; a++) {
        n->read_fd[a] = -1;
    }
    n->dir_fd = -1;
    const int e = nvm_file_check_dir(dir, err, errlen);
    if (e != 0) {
        return e;
    }
    for (int a = 0; a < 3; a++) {
        if (snprintf(n->path[a], sizeof n->path[a], "%s/%s.%s", dir, key, suffix[a]) >= (int)sizeof n->path[a]) {
            (void)snprintf(err, errlen, "NVM path too long in %s", dir);
            return ENAMETOOLONG;
        }
    }
    n->dir_fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    return 0;
}

static void close_reader(nvm_file_t *n, int a)
{
    if (n->read_fd[a] >= 0) {
        (void)close(n->read_fd[a]);
        n->read_fd[a] = -1;
    }
}

void nvm_file_close(nvm_file_t *n)
{
    for (int a = 0; a < 3; a++) {
        free(n->staging[a].buf); /* an unfinished write is never committed: it only ever lived in memory */
        memset(&n->staging[a], 0, sizeof n->staging[a]);
        close_reader(n, a);
    }
    if (n->dir_fd >= 0) {
        (void)close(n->dir_fd);
        n->dir_fd = -1;
    }
}

/* The staging copy lives in memory, not in "<file>.tmp" as it did: the core writes a blob in hundreds of
 * small pieces (two per record), and each one a system call made a store take ~0.1 s in User-Mode Linux
 * and widened the moment in which a crash leaves a temporary file. The file is written once, at commit. */
co_status_t nvm_file_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    nvm_staging_t *s = &n->staging[area];
    if (len > NVM_FILE_MAX || offset > NVM_FILE_MAX - len) {
        return CO_ERR_IO;
    }
    const size_t end = (size_t)offset + len;
    if (!s->active) {
        s->len = 0U; /* a new blob: nothing of the previous one is kept */
        s->active = true;
    }
    if (end > s->cap) {
        size_t cap = s->cap != 0U ? s->cap : 256U;
        while (cap < end) {
            cap *= 2U;
        }
        uint8_t *b = realloc(s->buf, cap);
        if (b == NULL) {
            return CO_ERR_IO;
        }
        s->buf = b;
        s->cap = cap;
    }
    if (end > s->len) {
        memset(s->buf + s->len, 0, end - s->len); /* bytes between earlier writes and this one read as 0 */
        s->len = end;
    }
    memcpy(s->buf + offset, data, len);
    return CO_OK;
}

static bool write_all(int fd, const uint8_t *p, size_t len)
{
    while (len > 0U) {
        const ssize_t w = write(fd, p, len);
        if (w < 0 && errno == EINTR) {
            continue;
        }
        if (w <= 0) {
            return false;
        }
        p += w;
        len -= (size_t)w;
    }
    return true;
}

co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U || !n->staging[area].active || total_len > n->staging[area].len) {
        return CO_ERR_IO; /* nothing staged, or a blob longer than what was written */
    }
    nvm_staging_t *s = &n->staging[area];
    s->active = false;
    char tmp[PATH_MAX + 8];
    (void)snprintf(tmp, sizeof tmp, "%s.tmp", n->path[area]);
    /* A leftover of a killed store (or anything else by that name) goes first: O_EXCL then guarantees a
     * fresh file, and O_NOFOLLOW that a symbolic link planted there never redirects the write. */
    (void)unlink(tmp);
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        return CO_ERR_IO;
    }
    const bool ok = write_all(fd, s->buf, total_len) && fsync(fd) == 0;
    if (close(fd) != 0 || !ok || rename(tmp, n->path[area]) != 0) {
        (void)unlink(tmp);
        return CO_ERR_IO;
    }
    close_reader(n, (int)area); /* it still reads the replaced file */
    if (n->dir_fd >= 0) {
        (void)fsync(n->dir_fd); /* the rename itself is durable */
    }
    return CO_OK;
}

co_status_t nvm_file_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    if (offset == 0U) {
        close_reader(n, (int)area); /* a new load: see the file as it is now, even if replaced by hand */
    }
    if (n->read_fd[area] < 0) {
        n->read_fd[area] = open(n->path[area], O_RDONLY | O_CLOEXEC);
        if (n->read_fd[area] < 0) {
            return CO_ERR_NO_DATA;
        }
    }
    const ssize_t r = pread(n->read_fd[area], data, len, (off_t)offset);
    return r == (ssize_t)len ? CO_OK : CO_ERR_NO_DATA;
}
