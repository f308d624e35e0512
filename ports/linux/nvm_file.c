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

static void recover(nvm_file_t *n);

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
    recover(n);
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

static void tmp_path(const nvm_file_t *n, int area, char *tmp, size_t len)
{
    (void)snprintf(tmp, len, "%s.tmp", n->path[area]);
}

/* The committed blob goes to "<file>.tmp" (write + fsync); the rename that makes it the file comes with the
 * store's last commit (finish_store), which renames all the store's areas as one transaction. */
static co_status_t write_tmp(nvm_file_t *n, co_nvm_area_t area, uint32_t total_len)
{
    nvm_staging_t *s = &n->staging[area];
    if (!s->active || total_len > s->len) {
        return CO_ERR_IO; /* nothing staged, or a blob longer than what was written */
    }
    s->active = false;
    char tmp[PATH_MAX + 8];
    tmp_path(n, (int)area, tmp, sizeof tmp);
    /* A leftover of a killed store (or anything else by that name) goes first: O_EXCL then guarantees a
     * fresh file, and O_NOFOLLOW that a symbolic link planted there never redirects the write. */
    (void)unlink(tmp);
    n->pending[area] = false;
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        return CO_ERR_IO;
    }
    const bool ok = write_all(fd, s->buf, total_len) && fsync(fd) == 0;
    if (close(fd) != 0 || !ok) {
        (void)unlink(tmp);
        return CO_ERR_IO;
    }
    n->pending[area] = true;
    return CO_OK;
}

/* The store is abandoned: its temporary files go, every area keeps its file. */
static void discard_store(nvm_file_t *n)
{
    for (int a = 0; a < 3; a++) {
        if (n->pending[a]) {
            char tmp[PATH_MAX + 8];
            tmp_path(n, a, tmp, sizeof tmp);
            (void)unlink(tmp);
            n->pending[a] = false;
        }
    }
}

/* Journal "<key>.journal": "CONVJ1" | one byte per area (1 = its .tmp belongs to the transaction) | '\n'.
 * Written to "<key>.journal.tmp", fsynced and renamed: it exists whole or not at all. */
#define JOURNAL_LEN 10U

static bool rename_pending(nvm_file_t *n, int area)
{
    char tmp[PATH_MAX + 8];
    tmp_path(n, area, tmp, sizeof tmp);
    if (rename(tmp, n->path[area]) != 0) {
        return false;
    }
    n->pending[area] = false;
    drop_loaded(n, area); /* it holds the replaced file */
    return true;
}

static bool sync_dir(const nvm_file_t *n)
{
    return n->dir_fd < 0 || fsync(n->dir_fd) == 0; /* the renames themselves are durable */
}

/* A rename over anything but a regular file (a directory, a FIFO, a device someone put there) cannot give a
 * loadable area, and a rename onto a directory fails outright: checked before the store is decided, so that
 * a journal never names a rename that cannot be done. */
static bool replaceable(const nvm_file_t *n, int area)
{
    struct stat st;
    return lstat(n->path[area], &st) != 0 ? errno == ENOENT : S_ISREG(st.st_mode) || S_ISLNK(st.st_mode);
}

/* Makes the store's areas (committed to their .tmp) the files: 0 when durable, -1 when nothing changed. */
static int finish_store(nvm_file_t *n)
{
    int count = 0;
    for (int a = 0; a < 3; a++) {
        if (n->pending[a] && !replaceable(n, a)) {
            discard_store(n);
            return -1;
        }
        count += n->pending[a] ? 1 : 0;
    }
    if (count == 1) {
        for (int a = 0; a < 3; a++) {
            if (n->pending[a] && !rename_pending(n, a)) {
                discard_store(n);
                return -1;
            }
        }
        return sync_dir(n) ? 0 : -1;
    }
    /* Several areas (an Eltex 0x1010 save writes parameters, LSS configuration and device data): a crash
     * between two renames would load a mix. The journal names the temporary files first; once it exists the
     * transaction is decided, and nvm_file_open() finishes the renames a crash interrupted. */
    char jtmp[PATH_MAX + 16];
    (void)snprintf(jtmp, sizeof jtmp, "%s.tmp", n->journal);
    (void)unlink(jtmp);
    const int fd = open(jtmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        discard_store(n);
        return -1;
    }
    const uint8_t j[JOURNAL_LEN] = {'C', 'O', 'N', 'V', 'J', '1', (uint8_t)n->pending[0], (uint8_t)n->pending[1],
                                    (uint8_t)n->pending[2], '\n'};
    const bool ok = write_all(fd, j, sizeof j) && fsync(fd) == 0;
    if (close(fd) != 0 || !ok || rename(jtmp, n->journal) != 0 || !sync_dir(n)) {
        (void)unlink(jtmp);
        (void)unlink(n->journal);
        discard_store(n);
        return -1;
    }
    for (int a = 0; a < 3; a++) {
        if (n->pending[a] && !rename_pending(n, a)) {
            recover(n); /* decided: the journal finishes the renames (now, or at the next open) */
            return 0;
        }
    }
    (void)sync_dir(n);
    (void)unlink(n->journal);
    (void)sync_dir(n);
    return 0;
}

co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    nvm_file_t *n = (nvm_file_t *)ctx;
    if ((unsigned)area > 2U) {
        return CO_ERR_ARG;
    }
    if (total_len == CO_NVM_DISCARD) {
        n->staging[area].active = false;
        discard_store(n);
        return CO_OK;
    }
    if (write_tmp(n, area, total_len & ~CO_NVM_MORE) != CO_OK) {
        discard_store(n); /* all or none: the areas committed before it in this store go too */
        return CO_ERR_IO;
    }
    if ((total_len & CO_NVM_MORE) != 0U) {
        return CO_OK; /* more areas of this store follow: durable with the last one */
    }
    return finish_store(n) == 0 ? CO_OK : CO_ERR_IO;
}

/* At open: a journal means a transaction was decided but maybe not carried out: rename the temporary files it
 * names that are still there (those already renamed are gone). Without a journal, temporary files are
 * leftovers of an undecided store: removed, never loaded (a removal a crash undoes is simply done again).
 * The directory is synced only when a journal was carried out: two fsyncs per node at every start made the
 * emulator's last nodes boot seconds late on a loaded machine's disk (127 nodes: 254 fsyncs). */
static void recover(nvm_file_t *n)
{
    uint8_t j[JOURNAL_LEN];
    bool listed[3] = {false, false, false};
    int fd = open(n->journal, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    struct stat st;
    if (fd >= 0 && (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))) {
        (void)close(fd); /* not a journal of ours (a directory or FIFO by that name): nothing was decided */
        fd = -1;
    }
    const bool journal = fd >= 0;
    if (journal) {
        const ssize_t r = read(fd, j, sizeof j);
        (void)close(fd);
        if (r == (ssize_t)JOURNAL_LEN && memcmp(j, "CONVJ1", 6U) == 0 && j[9] == '\n') {
            for (int a = 0; a < 3; a++) {
                listed[a] = j[6 + a] == 1U;
            }
        }
    }
    for (int a = 0; a < 3; a++) {
        char tmp[PATH_MAX + 8];
        tmp_path(n, a, tmp, sizeof tmp);
        if (listed[a]) {
            (void)rename(tmp, n->path[a]); /* ENOENT: renamed before the crash */
        }
        /* Not listed: a leftover of an undecided store. Listed but still there: the rename failed (a directory has
         * the area's name), and with the journal gone below nothing would ever use it. */
        (void)unlink(tmp);
    }
    /* The journal's own temporary file: a store that stopped before its journal existed decided nothing. It stayed
     * until the next store of several areas. */
    char jtmp[PATH_MAX + 16];
    (void)snprintf(jtmp, sizeof jtmp, "%s.tmp", n->journal);
    (void)unlink(jtmp);
    if (journal) {
        sync_dir(n); /* the renames are durable before the journal that decided them goes */
    }
    /* The journal once carried out, or whatever else has its name (a FIFO, a link: never followed, decides
     * nothing); a directory stays (unlink cannot remove it, and it may hold someone's files). */
    (void)unlink(n->journal);
    if (journal) {
        sync_dir(n);
    }
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

void nvm_file_close(nvm_file_t *n)
{
    discard_store(n); /* a store without its last commit was never confirmed */
    for (int a = 0; a < 3; a++) {
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
