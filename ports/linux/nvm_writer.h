/**
 * @file nvm_writer.h
 * @brief The background commits of the NVM files (nvm_file.h; co_port.h, CO_NVM_BACKGROUND) through one io_uring
 *        per process, so that the fsyncs of the device models' own periodic saves never hold the loop, with no
 *        thread in the process.
 *
 * A client (one per node: nvm_file_t embeds one) hands over a blob of an area with nvm_writer_submit(), which copies
 * it and gives the kernel two links of requests: the removal of a leftover "<file>.tmp" and the creation of a fresh one
 * (O_EXCL, O_NOFOLLOW, as nvm_file_store.c does); once that is done, the blob's write to it, its fsync, its rename
 * over the file and the directory's fsync. The kernel carries them out in its own workers, in that order, and a
 * failed one (a short write too) cancels the rest: after a crash or a power loss the file is its old blob or the new
 * one. The loop itself touches no file of a job but to close it: on a journalling file system busy with other
 * files' fsyncs, a creation, a write (the file's times) or a rename can wait for the journal, tens of ms. Completions
 * are taken without a system call (a look at the completion ring) by nvm_writer_poll() (the loop calls it once a
 * pass: one load of a counter when nothing is in flight), by every submit and by nvm_writer_pending();
 * nvm_writer_wait() waits for them in the kernel. The kernel runs one worker of each kind for them, as one writer
 * thread would, and its task work (posting a completion, issuing a linked request) waits for the loop's own next
 * system call instead of interrupting it (IORING_SETUP_COOP_TASKRUN; when the ring's flag says task work waits, the
 * poll enters the kernel once).
 *
 * One job per area is in flight (its temporary file has one name): a blob of an area whose job is in flight waits
 * in the client, and a newer blob replaces a waiting one (the older would only be overwritten); it is written when
 * the job in flight completes. NVM_WRITER_QUEUE jobs are in flight at most; when they are, submit says so and the
 * caller commits at once itself. Where no io_uring can be set up (no kernel support, a seccomp filter, the
 * User-Mode Linux kernel of the vcan tests) every submit says so: background commits are then synchronous. At a
 * normal exit (atexit) every job handed over is carried out before the process ends.
 *
 * One thread (the loop's) calls everything here. After nvm_writer_wait() returns, the client has no job and no
 * waiting blob, and the writer does not touch it until its next submit.
 */
#ifndef NVM_WRITER_H
#define NVM_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define NVM_WRITER_AREAS 3
/** Jobs in flight at most. A full emulator (8 x 127 Bürkert nodes) hands over about 17 a second, each done in a few
 *  ms on a sound disk; this many is more than a stalled disk lets pile up in seconds. */
#define NVM_WRITER_QUEUE 128U

/** A blob of an area waiting for the area's job in flight. */
typedef struct nvm_writer_blob {
    uint8_t *buf; /**< malloc'd; freed by nvm_writer_wait() */
    size_t cap;
    size_t len;
    bool waiting;
} nvm_writer_blob_t;

typedef struct nvm_writer_client {
    /** Set before the first submit and left alone until the client's last job is done: the file of each area, and
     *  the directory that holds them (fsynced after a rename; -1: not synced). */
    const char *path[NVM_WRITER_AREAS];
    int dir_fd;
    /* The writer's (zeroed: nothing in flight). */
    unsigned job[NVM_WRITER_AREAS];              /**< 1 + the slot of the area's job in flight; 0: none */
    nvm_writer_blob_t waiting[NVM_WRITER_AREAS]; /**< the area's next blob */
    bool failed[NVM_WRITER_AREAS];               /**< a job of the area failed, not yet said by a submit */
} nvm_writer_client_t;

typedef enum nvm_writer_result {
    NVM_WRITER_QUEUED,  /**< the blob will be written (a job of its own, or waiting for the area's job in flight) */
    NVM_WRITER_REFUSED, /**< no io_uring, NVM_WRITER_QUEUE jobs in flight, no memory: commit at once, after a wait */
    NVM_WRITER_FAILED   /**< an earlier job of the area failed (said once), or this blob cannot replace the file (a
                             directory or FIFO has its name): not handed over */
} nvm_writer_result_t;

/** Hands over blob (copied before it returns) for the area. */
nvm_writer_result_t nvm_writer_submit(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len);
/** Waits until every job of the client is done (on disk, or failed) and none waits. Lifts a test hold. */
void nvm_writer_wait(nvm_writer_client_t *c);
/** True while a blob of the area is handed over and not on disk: its file may not hold the newest blob yet. */
bool nvm_writer_pending(nvm_writer_client_t *c, int area);
/** Jobs in flight now: the writer's, read by nvm_writer_poll() without a call. */
extern unsigned nvm_writer_in_flight;
/** Takes the completions there are, without a system call (and gives the kernel requests a failed submit left). */
void nvm_writer_take_completions(void);
/** The loop's, once a pass: nothing but a load of a counter when no job is in flight. */
static inline void nvm_writer_poll(void)
{
    if (nvm_writer_in_flight != 0U) {
        nvm_writer_take_completions();
    }
}

/** Tests: while held, the jobs' requests are prepared but not given to the kernel (nothing of them is done);
 *  nvm_writer_wait() and exit lift the hold, so that a held writer never stops a synchronous commit. */
void nvm_writer_hold(bool held);
/** Tests: from now on every submit says NVM_WRITER_REFUSED, as where no io_uring can be set up. */
void nvm_writer_refuse(bool refuse);
/** Tests: jobs in flight now, jobs done since the start (failed ones too), blobs that replaced a waiting one. */
typedef struct nvm_writer_counts {
    unsigned queued;
    unsigned long done;
    unsigned long replaced;
} nvm_writer_counts_t;
nvm_writer_counts_t nvm_writer_counts(void);

#endif
