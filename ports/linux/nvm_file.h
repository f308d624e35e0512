/**
 * @file nvm_file.h
 * @brief The port's non-volatile memory as files: one file per area of one node, replaced atomically.
 *
 * Writes go to a staging copy in memory; commit writes it to "<file>.tmp" (a fresh file: a leftover of a
 * killed process is removed first, a symbolic link there is never followed) and fsyncs it. The last commit of a
 * store (co_port.h: without CO_NVM_MORE) then renames the store's temporary files over the files and fsyncs the
 * directory, as one transaction, before it returns: one area is one rename; several (an Eltex 0x1010 save
 * writes parameters, LSS configuration and device data) are first named in "<key>.journal", which
 * nvm_file_open() uses to finish renames a crash interrupted. So a commit that answers CO_OK is durable, one
 * that fails (full disk, I/O error, a directory or FIFO where a file must be) leaves every area of the store
 * as it was, and after a crash or SIGKILL at any moment every area is its old blob or its new one, the areas of
 * one store all old or all new; a "<file>.tmp" outside a journal is removed. CO_NVM_DISCARD drops a store.
 * A read at offset 0 (every load starts there) reads the whole file into memory, and the core's many small
 * reads of one load (two per record) are served from there: one open and one read per load, not a system call
 * per record (in User-Mode Linux each is a round trip to the host: a node's parameter load took 150-350 ms
 * and a CI run's last nodes booted after 10 s). Every load sees the file as it is then, even one replaced
 * by hand.
 *
 * A commit with CO_NVM_BACKGROUND (co_port.h: a model's own save no answer waits for) returns before the blob is
 * durable: it hands a copy to the process's io_uring (nvm_writer.h), and the kernel's workers do the same steps as a
 * store of that one area ("<file>.tmp" created fresh, written, fsynced, renamed over the file, the directory
 * fsynced), in order, a failed step cancelling the rest; so the loop waits for no disk and the process stays
 * single-threaded, and after a crash or power loss the area is its old blob or the new one. Until the rename is done,
 * a load of the area sees that blob (the newest handed over), not the file. Order per node is kept: a commit without
 * the flag (a 0x1010 or LSS store, an answer waiting for it), a discard and nvm_file_close() first wait for the
 * node's background commits; one job per area is in flight, and a newer blob replaces one waiting for it. A
 * background commit whose file cannot be replaced (a directory or FIFO has its name) answers CO_ERR_IO at once; a
 * failure the kernel finds later (creation, write, fsync, rename) leaves the file as it was and is answered CO_ERR_IO
 * by the area's next background commit (that blob is not kept: the model saves again later); a commit without the
 * flag of the area forgets it. Where no io_uring can be set up (an old kernel, a seccomp filter, User-Mode Linux),
 * with NVM_WRITER_QUEUE jobs in flight, and while a store of several areas is open, a background commit commits at
 * once, as a port without the flag does. At a normal exit every commit handed over is carried out; a SIGKILL or a
 * crash loses the ones not yet done (each area is then its old blob or a newer one, never a mix).
 * Files: <dir>/<key>.params, .lss, .device.
 */
#ifndef NVM_FILE_H
#define NVM_FILE_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "co/co.h"
#include "nvm_writer.h"

/** A blob in memory: one being written (staging) or one loaded from its file (loaded). */
typedef struct nvm_staging {
    uint8_t *buf;  /**< malloc'd, kept for the next store or load */
    size_t cap;    /**< bytes allocated */
    size_t len;    /**< staging: highest offset + length written since the last commit; loaded: the file's size */
    bool active;   /**< staging: a write happened since the last commit; loaded: the file was read */
} nvm_staging_t;

typedef struct nvm_file {
    char path[3][PATH_MAX];
    char journal[PATH_MAX];  /**< <dir>/<key>.journal: the areas of a multi-area transaction */
    nvm_staging_t staging[3];
    bool pending[3];         /**< committed to <file>.tmp with CO_NVM_MORE: waits for the store's last commit */
    nvm_staging_t loaded[3]; /**< the file as read by the load in progress (active: it was read) */
    nvm_staging_t newest[3]; /**< the blob of the area's last background commit: loads see it until it is written */
    int dir_fd;
    nvm_writer_client_t writer; /**< the node's background commits (nvm_writer.h) */
} nvm_file_t;

/** Prepares the files of one node (key e.g. "pro-ionizer-99") in dir, creating dir if needed.
 *  Returns 0 or an errno value with a message for the user in err. */
int nvm_file_open(nvm_file_t *n, const char *dir, const char *key, char *err, size_t errlen);
/** Waits for the node's background commits, then frees its buffers; a store without its last commit is dropped (it
 *  was never confirmed). */
void nvm_file_close(nvm_file_t *n);
/** Waits until the node's background commits are done (on disk, or failed: the next one says so). */
void nvm_file_flush(nvm_file_t *n);

/** Checks that dir exists or can be created and that files can be written there. */
int nvm_file_check_dir(const char *dir, char *err, size_t errlen);

co_status_t nvm_file_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len);
co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len);
co_status_t nvm_file_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len);

#endif
