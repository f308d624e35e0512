/**
 * @file nvm_writer.h
 * @brief One thread per process that carries out the background commits of the NVM files (nvm_file.h; co_port.h,
 *        CO_NVM_BACKGROUND), so that the fsyncs of the device models' own periodic saves never hold the loop.
 *
 * A client (one per node: nvm_file_t embeds one) hands over a copy of a blob with nvm_writer_submit(); the thread
 * calls the client's write function for each job, one at a time, in the order they were handed over. A blob of an
 * area whose previous job has not started yet replaces that job's blob in place (the older one would only be
 * overwritten), so a client has at most one waiting job per area and the order per area is kept. The queue holds
 * NVM_WRITER_QUEUE jobs; when it is full, submit says so and the caller commits at once itself. The thread is
 * started at the first submit, with every signal blocked (they stay the loop's), and stopped at exit (atexit) after
 * it has carried out every job left: nothing handed over is lost at a normal exit.
 *
 * Threads: submit, wait, pending and the test hooks are for one thread (the loop's); the write function runs in
 * the writer thread with no lock held. After nvm_writer_wait() returns, the client has no job and the writer does
 * not touch it until its next submit.
 */
#ifndef NVM_WRITER_H
#define NVM_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define NVM_WRITER_AREAS 3
/** Jobs the queue holds (waiting and the one being written). A full emulator (8 x 127 Bürkert nodes) hands over
 *  about 17 a second; one job of each area of 85 nodes fits, more than a stalled disk lets pile up in seconds. */
#define NVM_WRITER_QUEUE 256U

typedef struct nvm_writer_client nvm_writer_client_t;
struct nvm_writer_client {
    /** Makes blob (len bytes) the area's content, durably; true when done. Runs in the writer thread. Set before
     *  the first submit and left alone until the client's last job is done. */
    bool (*write)(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len);
    /* The writer's (under its lock; zeroed: no job). */
    unsigned outstanding[NVM_WRITER_AREAS];  /**< jobs of the area handed over and not finished */
    unsigned waiting_slot[NVM_WRITER_AREAS]; /**< 1 + queue index of the area's job not started yet; 0: none */
    bool failed[NVM_WRITER_AREAS];           /**< a job of the area failed, not yet reported by a submit */
};

typedef enum nvm_writer_result {
    NVM_WRITER_QUEUED,  /**< the thread will write the blob (a waiting blob of the area replaced, or a new job) */
    NVM_WRITER_REFUSED, /**< the queue is full (or no thread, no memory): commit at once, after nvm_writer_wait() */
    NVM_WRITER_FAILED   /**< an earlier job of the area failed; said once, and this blob was not handed over */
} nvm_writer_result_t;

/** Hands over a copy of blob for the area. */
nvm_writer_result_t nvm_writer_submit(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len);
/** Waits until every job of the client is done (written or failed). Lifts a test hold (nvm_writer_hold). */
void nvm_writer_wait(nvm_writer_client_t *c);
/** True while a job of the area is handed over and not done: its file may not hold the newest blob yet. */
bool nvm_writer_pending(nvm_writer_client_t *c, int area);

/** Tests: while held, the thread starts no job (a job it is writing is finished); nvm_writer_wait() and exit lift
 *  the hold, so that a held writer never stops a synchronous commit. */
void nvm_writer_hold(bool held);
/** Tests: jobs in the queue now, jobs written since the start (failed ones too), blobs that replaced a waiting one. */
typedef struct nvm_writer_counts {
    unsigned queued;
    unsigned long done;
    unsigned long replaced;
} nvm_writer_counts_t;
nvm_writer_counts_t nvm_writer_counts(void);

#endif
