/* The NVM files' transactions: see nvm_file_store.h and nvm_file.h. */
#define _GNU_SOURCE
#include "nvm_file_store.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

/* blob in a fresh file tmp, fsynced; false (and no file) when that fails. */
static bool write_synced(const char *tmp, const uint8_t *blob, size_t len)
{
    /* A leftover of a killed store (or anything else by that name) goes first: O_EXCL then guarantees a
     * fresh file, and O_NOFOLLOW that a symbolic link planted there never redirects the write. */
    (void)unlink(tmp);
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        return false;
    }
    const bool ok = write_all(fd, blob, len) && fsync(fd) == 0;
    if (close(fd) != 0 || !ok) {
        (void)unlink(tmp);
        return false;
    }
    return true;
}

co_status_t nvm_store_write_tmp(nvm_file_t *n, co_nvm_area_t area, uint32_t total_len)
{
    nvm_staging_t *s = &n->staging[area];
    if (!s->active || total_len > s->len) {
        return CO_ERR_IO; /* nothing staged, or a blob longer than what was written */
    }
    s->active = false;
    char tmp[PATH_MAX + 8];
    tmp_path(n, (int)area, tmp, sizeof tmp);
    n->pending[area] = write_synced(tmp, s->buf, total_len);
    return n->pending[area] ? CO_OK : CO_ERR_IO;
}

void nvm_store_discard(nvm_file_t *n)
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
    n->loaded[area].active = false; /* it holds the replaced file: the next read loads the file again */
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
int nvm_store_finish(nvm_file_t *n)
{
    int count = 0;
    for (int a = 0; a < 3; a++) {
        if (n->pending[a] && !replaceable(n, a)) {
            nvm_store_discard(n);
            return -1;
        }
        count += n->pending[a] ? 1 : 0;
    }
    if (count == 1) {
        for (int a = 0; a < 3; a++) {
            if (n->pending[a] && !rename_pending(n, a)) {
                nvm_store_discard(n);
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
        nvm_store_discard(n);
        return -1;
    }
    const uint8_t j[JOURNAL_LEN] = {'C', 'O', 'N', 'V', 'J', '1', (uint8_t)n->pending[0], (uint8_t)n->pending[1],
                                    (uint8_t)n->pending[2], '\n'};
    const bool ok = write_all(fd, j, sizeof j) && fsync(fd) == 0;
    if (close(fd) != 0 || !ok || rename(jtmp, n->journal) != 0 || !sync_dir(n)) {
        (void)unlink(jtmp);
        (void)unlink(n->journal);
        nvm_store_discard(n);
        return -1;
    }
    for (int a = 0; a < 3; a++) {
        if (n->pending[a] && !rename_pending(n, a)) {
            nvm_store_recover(n); /* decided: the journal finishes the renames (now, or at the next open) */
            return 0;
        }
    }
    (void)sync_dir(n);
    (void)unlink(n->journal);
    (void)sync_dir(n);
    return 0;
}

/* At open: a journal means a transaction was decided but maybe not carried out: rename the temporary files it
 * names that are still there (those already renamed are gone). Without a journal, temporary files are
 * leftovers of an undecided store: removed, never loaded (a removal a crash undoes is simply done again).
 * The directory is synced only when a journal was carried out: two fsyncs per node at every start made the
 * emulator's last nodes boot seconds late on a loaded machine's disk (127 nodes: 254 fsyncs). */
void nvm_store_recover(nvm_file_t *n)
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
