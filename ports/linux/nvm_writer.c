/* The NVM files' background commits through io_uring: see nvm_writer.h. */
#define _GNU_SOURCE
#include "nvm_writer.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <liburing.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* A job's requests, in two links: the leftover temporary file's removal and the fresh one's creation; then, with the
 * new file's descriptor, the blob's write, its fsync, its rename over the file and the directory's fsync. The
 * submission ring holds every job's requests (at most four a link) even while a test holds them all back; the
 * completion ring (twice as large) all their results. A request's user data: its job's slot * STEPS + its step. */
enum { STEP_UNLINK, STEP_OPEN, STEP_WRITE, STEP_FSYNC, STEP_RENAME, STEP_DIR_FSYNC, STEPS };
#define RING_ENTRIES (4U * NVM_WRITER_QUEUE)

typedef struct job {
    nvm_writer_client_t *client; /* NULL: a free slot */
    int area;
    bool opening;   /* the first link (removal, creation) is in flight */
    int fd;         /* the temporary file, from its creation until the job is done; -1: none */
    unsigned left;  /* completions of the link in flight still to come */
    bool ok;        /* every completion so far succeeded */
    uint8_t *blob;  /* the blob, kept until the kernel wrote it (the buffer stays for the slot's next job) */
    size_t cap;
    size_t len;
    char tmp[PATH_MAX + 8]; /* "<file>.tmp": kept until the kernel is done with it */
} job_t;

typedef enum { RING_UNTRIED, RING_READY, RING_NONE } ring_state_t;

static struct {
    struct io_uring ring;
    ring_state_t state;
    pid_t pid;        /* of the process that set the ring up (a forked child commits at once) */
    bool held;
    bool refuse;
    bool unsubmitted; /* requests prepared and not yet given to the kernel */
    job_t job[NVM_WRITER_QUEUE];
    nvm_writer_counts_t counts;
} w;

unsigned nvm_writer_in_flight; /* slots in use */

static void reap(void);

static void submit_prepared(void)
{
    if (w.unsubmitted && !w.held && io_uring_submit(&w.ring) >= 0) {
        w.unsubmitted = false; /* else tried again at the next submit, poll or wait */
    }
}

/* At exit: every job handed over (and every blob waiting for one) is carried out before the process ends; the
 * kernel would cancel the requests not yet started when the ring goes. */
static void drain_at_exit(void)
{
    if (w.state != RING_READY || w.pid != getpid()) {
        return;
    }
    w.held = false;
    while (nvm_writer_in_flight > 0U) {
        submit_prepared();
        struct io_uring_cqe *cqe;
        const int e = io_uring_wait_cqe(&w.ring, &cqe);
        if (e < 0 && e != -EINTR) {
            break;
        }
        reap();
    }
    io_uring_queue_exit(&w.ring);
    w.state = RING_NONE;
    for (unsigned i = 0U; i < NVM_WRITER_QUEUE; i++) {
        free(w.job[i].blob);
        w.job[i].blob = NULL;
        w.job[i].cap = 0U;
    }
}

/* Set up at the first submit: a process that never commits in the background has no ring. Needs the unlink and
 * rename requests (Linux 5.11); anything less and background commits are synchronous. */
static bool ring_ready(void)
{
    if (w.state == RING_UNTRIED) {
        w.state = RING_NONE;
        /* The kernel's task work (a completion posted, a linked request issued) waits for the loop's own next system
         * call instead of interrupting it; the ring's flag says when some waits. Before Linux 5.19: interrupts. */
        if (io_uring_queue_init(RING_ENTRIES, &w.ring, IORING_SETUP_COOP_TASKRUN | IORING_SETUP_TASKRUN_FLAG) == 0 ||
            io_uring_queue_init(RING_ENTRIES, &w.ring, 0) == 0) {
            struct io_uring_probe *p = io_uring_get_probe_ring(&w.ring);
            const bool can = p != NULL && io_uring_opcode_supported(p, IORING_OP_FSYNC) &&
                             io_uring_opcode_supported(p, IORING_OP_RENAMEAT) &&
                             io_uring_opcode_supported(p, IORING_OP_UNLINKAT) &&
                             io_uring_opcode_supported(p, IORING_OP_OPENAT) &&
                             io_uring_opcode_supported(p, IORING_OP_WRITE);
            if (p != NULL) {
                io_uring_free_probe(p);
            }
            /* One worker of each kind, as one writer thread was: 1,016 nodes' saves done side by side would compete
             * with the loop for a small machine's cores. Older kernels (before 5.15) keep their default. */
            unsigned workers[2] = {1U, 1U};
            (void)io_uring_register_iowq_max_workers(&w.ring, workers);
            if (can && atexit(drain_at_exit) == 0) {
                w.state = RING_READY;
                w.pid = getpid();
            } else {
                io_uring_queue_exit(&w.ring);
            }
        }
    }
    return w.state == RING_READY && !w.refuse && w.pid == getpid();
}

/* A rename over anything but a regular file or a link (a directory, a FIFO) cannot give a loadable area. */
static bool replaceable(const char *path)
{
    struct stat st;
    return lstat(path, &st) != 0 ? errno == ENOENT : S_ISREG(st.st_mode) || S_ISLNK(st.st_mode);
}

/* After the io_uring_prep_ call, which clears the flags. */
static void tag_request(struct io_uring_sqe *sqe, const job_t *j, unsigned step, unsigned char flags)
{
    io_uring_sqe_set_data64(sqe, (uint64_t)(j - w.job) * STEPS + step);
    io_uring_sqe_set_flags(sqe, flags);
    w.unsubmitted = true;
}

/* Room for every job's requests (RING_ENTRIES): never NULL. */
static struct io_uring_sqe *next_request(void) { return io_uring_get_sqe(&w.ring); }

/* Queues the removal of a leftover temporary file (a failure, ENOENT, does not stop the link) and the creation of a
 * fresh one (O_EXCL and O_NOFOLLOW as in nvm_file_store.c). Both lock the directory, and a rename in it may hold
 * the lock while it waits for the file system's journal: they are the kernel's to wait for, not the loop's. Needs a
 * free slot and no job of the area in flight; false when the blob cannot replace the file (a directory or FIFO has
 * its name) or no memory. */
static bool start_job(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len)
{
    unsigned slot = 0U;
    while (w.job[slot].client != NULL) {
        slot++;
    }
    job_t *j = &w.job[slot];
    if (snprintf(j->tmp, sizeof j->tmp, "%s.tmp", c->path[area]) >= (int)sizeof j->tmp ||
        !replaceable(c->path[area])) {
        return false;
    }
    if (len > j->cap) {
        uint8_t *p = realloc(j->blob, len);
        if (p == NULL) {
            return false;
        }
        j->blob = p;
        j->cap = len;
    }
    if (len > 0U) {
        memcpy(j->blob, blob, len);
    }
    j->len = len;
    struct io_uring_sqe *sqe = next_request();
    io_uring_prep_unlinkat(sqe, AT_FDCWD, j->tmp, 0);
    tag_request(sqe, j, STEP_UNLINK, IOSQE_IO_HARDLINK);
    sqe = next_request();
    io_uring_prep_openat(sqe, AT_FDCWD, j->tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    tag_request(sqe, j, STEP_OPEN, 0U);
    j->client = c;
    j->area = area;
    j->opening = true;
    j->fd = -1;
    j->left = 2U;
    j->ok = true;
    c->job[area] = slot + 1U;
    nvm_writer_in_flight++;
    submit_prepared();
    return true;
}

static void finish_job(job_t *j);

/* The temporary file exists: queues write -> fsync -> rename -> directory fsync, a failed one (a short write too)
 * cancelling the rest. Even the write is the kernel's: it starts a journal handle (the file's times), which waits
 * while the file system commits other files' fsyncs. */
static void opened(job_t *j)
{
    const nvm_writer_client_t *c = j->client;
    j->opening = false;
    if (!j->ok) {
        finish_job(j);
        return;
    }
    struct io_uring_sqe *sqe = next_request();
    io_uring_prep_write(sqe, j->fd, j->blob, (unsigned)j->len, 0U);
    tag_request(sqe, j, STEP_WRITE, IOSQE_IO_LINK);
    sqe = next_request();
    io_uring_prep_fsync(sqe, j->fd, 0U);
    tag_request(sqe, j, STEP_FSYNC, IOSQE_IO_LINK);
    sqe = next_request();
    io_uring_prep_renameat(sqe, AT_FDCWD, j->tmp, AT_FDCWD, c->path[j->area], 0U);
    tag_request(sqe, j, STEP_RENAME, c->dir_fd >= 0 ? IOSQE_IO_LINK : 0U);
    j->left = 3U;
    if (c->dir_fd >= 0) {
        sqe = next_request();
        io_uring_prep_fsync(sqe, c->dir_fd, 0U);
        tag_request(sqe, j, STEP_DIR_FSYNC, 0U);
        j->left = 4U;
    }
    submit_prepared();
}

/* The job's last completion: its file is the new blob (ok), or the old one. The area's waiting blob starts next. */
static void finish_job(job_t *j)
{
    nvm_writer_client_t *c = j->client;
    const int area = j->area;
    if (j->fd >= 0) {
        (void)close(j->fd);
        j->fd = -1;
    }
    if (!j->ok) {
        (void)unlink(j->tmp); /* still there unless the rename was done (then nothing of ours has the name) */
        c->failed[area] = true;
    }
    j->client = NULL;
    c->job[area] = 0U;
    nvm_writer_in_flight--;
    w.counts.done++;
    nvm_writer_blob_t *b = &c->waiting[area];
    if (b->waiting) {
        b->waiting = false;
        if (!start_job(c, area, b->buf, b->len)) {
            c->failed[area] = true;
            w.counts.done++;
        }
    }
}

static void reap(void)
{
    struct io_uring_cqe *cqe;
    /* __io_uring_peek_cqe only reads the ring (io_uring_peek_cqe may enter the kernel when it is empty). */
    while (__io_uring_peek_cqe(&w.ring, &cqe, NULL) == 0 && cqe != NULL) {
        const uint64_t data = io_uring_cqe_get_data64(cqe);
        const int res = cqe->res;
        io_uring_cqe_seen(&w.ring, cqe);
        job_t *j = &w.job[data / STEPS];
        const uint64_t step = data % STEPS;
        if (step == STEP_OPEN && res >= 0) {
            j->fd = res;
        }
        j->ok = j->ok && (res >= 0 || step == STEP_UNLINK) && /* no leftover to remove: the usual case */
                (step != STEP_WRITE || (size_t)res == j->len); /* short: the kernel cancelled the rest too */
        if (--j->left == 0U) {
            if (j->opening) {
                opened(j);
            } else {
                finish_job(j);
            }
        }
    }
}

void nvm_writer_take_completions(void)
{
    submit_prepared();
    /* The kernel's flag word, read as liburing's IO_URING_READ_ONCE does, by the builtin: the macro casts to
     * _Atomic, which clang refuses in C99 (-Wc11-extensions). */
    if ((__atomic_load_n(w.ring.sq.kflags, __ATOMIC_RELAXED) & IORING_SQ_TASKRUN) != 0U) {
        (void)io_uring_get_events(&w.ring);
    }
    reap();
}

static bool keep_waiting(nvm_writer_blob_t *b, const uint8_t *blob, size_t len)
{
    if (len > b->cap) {
        uint8_t *p = realloc(b->buf, len);
        if (p == NULL) {
            return false;
        }
        b->buf = p;
        b->cap = len;
    }
    if (len > 0U) {
        memcpy(b->buf, blob, len);
    }
    b->len = len;
    if (b->waiting) {
        w.counts.replaced++;
    }
    b->waiting = true;
    return true;
}

nvm_writer_result_t nvm_writer_submit(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len)
{
    if (!ring_ready()) {
        return NVM_WRITER_REFUSED;
    }
    nvm_writer_poll();
    if (c->failed[area]) {
        c->failed[area] = false;
        return NVM_WRITER_FAILED;
    }
    if (c->job[area] != 0U) {
        return keep_waiting(&c->waiting[area], blob, len) ? NVM_WRITER_QUEUED : NVM_WRITER_REFUSED;
    }
    if (nvm_writer_in_flight >= NVM_WRITER_QUEUE) {
        return NVM_WRITER_REFUSED;
    }
    return start_job(c, area, blob, len) ? NVM_WRITER_QUEUED : NVM_WRITER_FAILED;
}

static bool has_jobs(const nvm_writer_client_t *c)
{
    for (int a = 0; a < NVM_WRITER_AREAS; a++) {
        if (c->job[a] != 0U) {
            return true; /* a waiting blob always has a job in flight before it */
        }
    }
    return false;
}

void nvm_writer_wait(nvm_writer_client_t *c)
{
    if (has_jobs(c)) {
        w.held = false;
        while (has_jobs(c)) {
            submit_prepared();
            struct io_uring_cqe *cqe;
            const int e = io_uring_wait_cqe(&w.ring, &cqe);
            if (e < 0 && e != -EINTR && e != -EAGAIN) {
                break; /* the ring is broken: nothing more will complete */
            }
            reap();
        }
    }
    for (int a = 0; a < NVM_WRITER_AREAS; a++) {
        free(c->waiting[a].buf);
        memset(&c->waiting[a], 0, sizeof c->waiting[a]);
    }
}

bool nvm_writer_pending(nvm_writer_client_t *c, int area)
{
    nvm_writer_poll();
    return c->job[area] != 0U;
}

void nvm_writer_hold(bool held)
{
    w.held = held;
    if (w.state == RING_READY) {
        submit_prepared();
    }
}

void nvm_writer_refuse(bool refuse) { w.refuse = refuse; }

nvm_writer_counts_t nvm_writer_counts(void)
{
    nvm_writer_counts_t c = w.counts;
    c.queued = nvm_writer_in_flight;
    return c;
}
