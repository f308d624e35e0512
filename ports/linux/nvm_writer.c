/* The NVM files' writer thread and its queue: see nvm_writer.h. */
#define _GNU_SOURCE
#include "nvm_writer.h"

#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

typedef struct job {
    nvm_writer_client_t *client;
    int area;
    uint8_t *blob; /* kept for the slot's next job */
    size_t cap;
    size_t len;
} job_t;

/* The queue is a ring: jobs[head] is the oldest (the one being written, once the thread took it), count jobs from
 * there. A slot is reused only after its job is done, so the thread reads its blob without the lock. */
static struct {
    pthread_mutex_t lock;
    pthread_cond_t work; /* a job was queued, the hold lifted or the stop asked for */
    pthread_cond_t done; /* a job was done */
    pthread_t thread;
    bool started;
    bool stopping;       /* at exit: the thread finishes the queue and ends; later commits are synchronous */
    bool held;
    pid_t pid;           /* of the process that started the thread (a forked child has no writer) */
    job_t jobs[NVM_WRITER_QUEUE];
    unsigned head;
    unsigned count;
    nvm_writer_counts_t counts;
} w = {.lock = PTHREAD_MUTEX_INITIALIZER, .work = PTHREAD_COND_INITIALIZER, .done = PTHREAD_COND_INITIALIZER};

static void *writer_main(void *arg)
{
    (void)arg;
    (void)pthread_mutex_lock(&w.lock);
    for (;;) {
        while (!w.stopping && (w.count == 0U || w.held)) {
            (void)pthread_cond_wait(&w.work, &w.lock);
        }
        if (w.count == 0U) {
            break; /* stopping, and nothing left */
        }
        job_t *j = &w.jobs[w.head];
        nvm_writer_client_t *c = j->client;
        c->waiting_slot[j->area] = 0U; /* started: a newer blob of the area gets a job of its own */
        (void)pthread_mutex_unlock(&w.lock);
        const bool ok = c->write(c, j->area, j->blob, j->len);
        (void)pthread_mutex_lock(&w.lock);
        c->outstanding[j->area]--;
        if (!ok) {
            c->failed[j->area] = true;
        }
        j->client = NULL;
        w.head = (w.head + 1U) % NVM_WRITER_QUEUE;
        w.count--;
        w.counts.done++;
        (void)pthread_cond_broadcast(&w.done);
    }
    (void)pthread_mutex_unlock(&w.lock);
    return NULL;
}

/* At exit: every job left is written (the loop's thread no longer waits for them), then the thread ends. */
static void writer_stop(void)
{
    if (!w.started || w.pid != getpid()) {
        return;
    }
    (void)pthread_mutex_lock(&w.lock);
    w.stopping = true;
    (void)pthread_cond_signal(&w.work);
    (void)pthread_mutex_unlock(&w.lock);
    (void)pthread_join(w.thread, NULL);
    w.started = false;
    for (unsigned i = 0U; i < NVM_WRITER_QUEUE; i++) {
        free(w.jobs[i].blob);
        w.jobs[i].blob = NULL;
        w.jobs[i].cap = 0U;
    }
}

/* Under the lock. The thread gets no signal: SIGINT and SIGTERM must reach the loop's thread, whose wait they end. */
static bool start_writer(void)
{
    if (w.started) {
        return w.pid == getpid();
    }
    if (w.stopping) {
        return false;
    }
    static bool stop_registered = false;
    if (!stop_registered) {
        if (atexit(writer_stop) != 0) {
            return false;
        }
        stop_registered = true;
    }
    sigset_t all;
    sigset_t old;
    (void)sigfillset(&all);
    (void)pthread_sigmask(SIG_SETMASK, &all, &old);
    const int e = pthread_create(&w.thread, NULL, writer_main, NULL);
    (void)pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (e != 0) {
        return false;
    }
    w.started = true;
    w.pid = getpid();
    return true;
}

static bool copy_blob(job_t *j, const uint8_t *blob, size_t len)
{
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
    return true;
}

nvm_writer_result_t nvm_writer_submit(nvm_writer_client_t *c, int area, const uint8_t *blob, size_t len)
{
    nvm_writer_result_t r = NVM_WRITER_REFUSED;
    (void)pthread_mutex_lock(&w.lock);
    if (c->failed[area]) {
        c->failed[area] = false;
        r = NVM_WRITER_FAILED;
    } else if (c->waiting_slot[area] != 0U) {
        if (copy_blob(&w.jobs[c->waiting_slot[area] - 1U], blob, len)) {
            w.counts.replaced++;
            r = NVM_WRITER_QUEUED;
        }
    } else if (w.count < NVM_WRITER_QUEUE && start_writer()) {
        const unsigned slot = (w.head + w.count) % NVM_WRITER_QUEUE;
        job_t *j = &w.jobs[slot];
        if (copy_blob(j, blob, len)) {
            j->client = c;
            j->area = area;
            w.count++;
            c->outstanding[area]++;
            c->waiting_slot[area] = slot + 1U;
            (void)pthread_cond_signal(&w.work);
            r = NVM_WRITER_QUEUED;
        }
    }
    (void)pthread_mutex_unlock(&w.lock);
    return r;
}

static bool has_jobs(const nvm_writer_client_t *c)
{
    for (int a = 0; a < NVM_WRITER_AREAS; a++) {
        if (c->outstanding[a] != 0U) {
            return true;
        }
    }
    return false;
}

void nvm_writer_wait(nvm_writer_client_t *c)
{
    (void)pthread_mutex_lock(&w.lock);
    if (has_jobs(c) && w.held) {
        w.held = false;
        (void)pthread_cond_signal(&w.work);
    }
    while (has_jobs(c)) {
        (void)pthread_cond_wait(&w.done, &w.lock);
    }
    (void)pthread_mutex_unlock(&w.lock);
}

bool nvm_writer_pending(nvm_writer_client_t *c, int area)
{
    (void)pthread_mutex_lock(&w.lock);
    const bool pending = c->outstanding[area] != 0U;
    (void)pthread_mutex_unlock(&w.lock);
    return pending;
}

void nvm_writer_hold(bool held)
{
    (void)pthread_mutex_lock(&w.lock);
    w.held = held;
    (void)pthread_cond_signal(&w.work);
    (void)pthread_mutex_unlock(&w.lock);
}

nvm_writer_counts_t nvm_writer_counts(void)
{
    (void)pthread_mutex_lock(&w.lock);
    nvm_writer_counts_t c = w.counts;
    c.queued = w.count;
    (void)pthread_mutex_unlock(&w.lock);
    return c;
}
