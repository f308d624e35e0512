/* NVM areas in files with atomic replacement: see nvm_file.h. */
#define _GNU_SOURCE
#include "nvm_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
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

int nvm_file_open(nvm_file_t *n, const char *dir, const char *key, char *err, size_t errlen)
{
    memset(n, 0, sizeof *n);
    const int e = nvm_file_check_dir(dir, err, errlen);
    if (e != 0) {
        return e;
    }
    for (int a = 0; a < 3; a++) {
        n->staging[a] = -1;
        if (snprintf(n->path[a], sizeof n->path[a], "%s/%s.%s", dir, key, suffix[a]) >= (int)sizeof n->path[a]) {
            (void)snprintf(err, errlen, "NVM path too long in %s", dir);
            return ENAMETOOLONG;
        }
    }
    n->dir_fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    return 0;
}

void nvm_file_close(nvm_file_t *n)
{
    for (int a = 0; a < 3; a++) {
        if (n->staging[a] >= 0) {
            char tmp[PATH_MAX + 8];
            (void)close(n->staging[a]);
            (void)snprintf(tmp, sizeof tmp, "%s.tmp", n->path[a]);
            (void)unlink(tmp); /* an unfinished write is never committed */
            n->staging[a] = -1;
        }
    }
    if (n->dir_fd >= 0) {
        (void)close(n->dir_fd);
        n->dir_fd = -1;
    }
}

co_status_t nvm_file_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    if (n->staging[area] < 0) {
        char tmp[PATH_MAX + 8];
        (void)snprintf(tmp, sizeof tmp, "%s.tmp", n->path[area]);
        n->staging[area] = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (n->staging[area] < 0) {
            return CO_ERR_IO;
        }
    }
    const ssize_t w = pwrite(n->staging[area], data, len, (off_t)offset);
    return w == (ssize_t)len ? CO_OK : CO_ERR_IO;
}

co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U || n->staging[area] < 0) {
        return CO_ERR_IO;
    }
    const int fd = n->staging[area];
    n->staging[area] = -1;
    char tmp[PATH_MAX + 8];
    (void)snprintf(tmp, sizeof tmp, "%s.tmp", n->path[area]);
    const bool ok = ftruncate(fd, (off_t)total_len) == 0 && fsync(fd) == 0;
    if (close(fd) != 0 || !ok || rename(tmp, n->path[area]) != 0) {
        (void)unlink(tmp);
        return CO_ERR_IO;
    }
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
    const int fd = open(n->path[area], O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return CO_ERR_NO_DATA;
    }
    const ssize_t r = pread(fd, data, len, (off_t)offset);
    (void)close(fd);
    return r == (ssize_t)len ? CO_OK : CO_ERR_NO_DATA;
}
