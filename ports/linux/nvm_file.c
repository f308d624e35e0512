/* NVM areas in files with atomic replacement: see nvm_file.h. */
#define _GNU_SOURCE
#include "nvm_file.h"
#include "nvm_file_store.h"

#include <errno.h>
#include <fcntl.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *const suffix[3] = {"params", "lss", "device"};

static int make_dirs(const char *dir)
{
    char path[PATH_MAX];
    if (dir[0] == '\0') {
        return ENOENT; /* "" names no directory (the loop below would start past its end) */
    }
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
    if (snprintf(n->journal, sizeof n->journal, "%s/%s.journal", dir, key) >= (int)sizeof n->journal) {
        (void)snprintf(err, errlen, "NVM path too long in %s", dir);
        return ENAMETOOLONG;
    }
    n->dir_fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    for (int a = 0; a < 3; a++) {
        n->writer.path[a] = n->path[a];
    }
    n->writer.dir_fd = n->dir_fd;
    nvm_store_recover(n);
    return 0;
}

/* The next read loads the file again. */
static void drop_loaded(nvm_file_t *n, int a)
{
    n->loaded[a].active = false;
}

/* The staging copy lives in memory, not in "<file>.tmp" as it did: the core writes a blob in hundreds of
 * small pieces (two per record), and each one a system call made a store take ~0.1 s in User-Mode Linux
 * and widened the moment in which a crash leaves a temporary file. The file is written once, at commit. */
/* Room for need bytes in b->buf (doubling from 256, at most NVM_FILE_MAX); false when too long or out of memory. */
static bool reserve(nvm_staging_t *b, size_t need)
{
    if (need <= b->cap) {
        return true;
    }
    size_t cap = b->cap != 0U ? b->cap : 256U;
    while (cap < need) {
        cap *= 2U;
    }
    uint8_t *p = cap <= NVM_FILE_MAX ? realloc(b->buf, cap) : NULL;
    if (p == NULL) {
        return false;
    }
    b->buf = p;
    b->cap = cap;
    return true;
}

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
    if (!reserve(s, end)) {
        return CO_ERR_IO;
    }
    if (end > s->len) {
        memset(s->buf + s->len, 0, end - s->len); /* bytes between earlier writes and this one read as 0 */
        s->len = end;
    }
    memcpy(s->buf + offset, data, len);
    return CO_OK;
}

static bool store_open(const nvm_file_t *n) { return n->pending[0] || n->pending[1] || n->pending[2]; }

/* Hands the staged blob to the writer (nvm_writer.h). CO_ERR_BUSY: not handed over (no io_uring, or the queue is
 * full), the staged blob is still there for a commit at once. The node's temporary files are the writer's until
 * nvm_file_flush() has waited for its jobs. */
static co_status_t commit_background(nvm_file_t *n, co_nvm_area_t area, uint32_t len)
{
    nvm_staging_t *s = &n->staging[area];
    if (!s->active || len > s->len) {
        return CO_ERR_IO; /* nothing staged, or a blob longer than what was written */
    }
    if (!reserve(&n->newest[area], len)) {
        return CO_ERR_BUSY;
    }
    const nvm_writer_result_t r = nvm_writer_submit(&n->writer, (int)area, s->buf, len);
    if (r == NVM_WRITER_REFUSED) {
        return CO_ERR_BUSY;
    }
    s->active = false;
    if (r == NVM_WRITER_FAILED) {
        return CO_ERR_IO; /* an earlier background write of the area failed, or this one could not start: its file is
                             the blob before it */
    }
    memcpy(n->newest[area].buf, s->buf, len);
    n->newest[area].len = len;
    return CO_OK;
}

co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    if (total_len != CO_NVM_DISCARD && (total_len & (CO_NVM_BACKGROUND | CO_NVM_MORE)) == CO_NVM_BACKGROUND &&
        !store_open(n)) {
        const co_status_t st = commit_background(n, area, total_len & ~CO_NVM_FLAGS);
        if (st != CO_ERR_BUSY) {
            return st;
        }
    }
    nvm_file_flush(n); /* the node's background commits are older: on disk first */
    n->writer.failed[area] = false; /* this commit's own result says what the area holds (nvm_writer.h: no job now) */
    if (total_len == CO_NVM_DISCARD) {
        n->staging[area].active = false;
        nvm_store_discard(n);
        return CO_OK;
    }
    if (nvm_store_write_tmp(n, area, total_len & ~CO_NVM_FLAGS) != CO_OK) {
        nvm_store_discard(n); /* all or none: the areas committed before it in this store go too */
        return CO_ERR_IO;
    }
    if ((total_len & CO_NVM_MORE) != 0U) {
        return CO_OK; /* more areas of this store follow: durable with the last one */
    }
    return nvm_store_finish(n) == 0 ? CO_OK : CO_ERR_IO;
}

/* Reads the whole file of an area into loaded[area] (at most NVM_FILE_MAX bytes: a longer file is a damaged
 * one, and reads past what was read fail as for a short file). */
static co_status_t load_file(nvm_file_t *n, int area)
{
    nvm_staging_t *l = &n->loaded[area];
    /* O_NONBLOCK: a FIFO put there must not stop the emulator in open() (it waited for a writer for ever). */
    const int fd = open(n->path[area], O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        return errno == ENOENT ? CO_ERR_NO_DATA : CO_ERR_IO;
    }
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        (void)close(fd);
        return CO_ERR_IO; /* a directory, FIFO or device is there: a damaged area, not "nothing stored" */
    }
    l->len = 0U;
    for (;;) {
        if (l->len == l->cap && !reserve(l, l->cap + 1U)) {
            break; /* too long (or no memory): what was read is all a load sees */
        }
        const ssize_t r = read(fd, l->buf + l->len, l->cap - l->len);
        if (r < 0 && errno == EINTR) {
            continue;
        }
        if (r < 0) {
            (void)close(fd);
            return CO_ERR_IO;
        }
        if (r == 0) {
            break;
        }
        l->len += (size_t)r;
    }
    (void)close(fd);
    l->active = true;
    return CO_OK;
}

co_status_t nvm_file_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    if (offset == 0U) {
        drop_loaded(n, (int)area); /* a new load: see the file as it is now, even if replaced by hand */
        const nvm_staging_t *b = &n->newest[area];
        if (nvm_writer_pending(&n->writer, (int)area)) { /* ... or the blob a background commit will make it */
            if (!reserve(&n->loaded[area], b->len)) {
                return CO_ERR_IO;
            }
            memcpy(n->loaded[area].buf, b->buf, b->len);
            n->loaded[area].len = b->len;
            n->loaded[area].active = true;
        }
    }
    if (!n->loaded[area].active) {
        const co_status_t st = load_file(n, (int)area);
        if (st != CO_OK) {
            return st;
        }
    }
    const nvm_staging_t *l = &n->loaded[area];
    /* The file is there but too short (even empty): a damaged blob, not "nothing stored" (co_port.h). */
    if (len > l->len || offset > l->len - len) {
        return CO_ERR_IO;
    }
    memcpy(data, l->buf + offset, len);
    return CO_OK;
}

void nvm_file_flush(nvm_file_t *n) { nvm_writer_wait(&n->writer); }

void nvm_file_close(nvm_file_t *n)
{
    nvm_file_flush(n); /* handed over, so as good as confirmed: on disk before the node goes */
    nvm_store_discard(n); /* a store without its last commit was never confirmed */
    for (int a = 0; a < 3; a++) {
        free(n->newest[a].buf);
        memset(&n->newest[a], 0, sizeof n->newest[a]);
        free(n->staging[a].buf); /* an unfinished write is never committed: it only ever lived in memory */
        memset(&n->staging[a], 0, sizeof n->staging[a]);
        free(n->loaded[a].buf);
        memset(&n->loaded[a], 0, sizeof n->loaded[a]);
    }
    if (n->dir_fd >= 0) {
        (void)close(n->dir_fd);
        n->dir_fd = -1;
    }
}
