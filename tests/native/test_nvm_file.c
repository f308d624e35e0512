/*
 * Background commits of the NVM files (ports/linux/nvm_file.c, nvm_writer.c; co_port.h CO_NVM_BACKGROUND): the
 * commit returns before the file is replaced (the requests held back by the writer's test hook), a load right after
 * sees the new blob, the kernel carries the jobs out with no thread in the process and the loop's poll takes their
 * completions, a commit someone waits for lands after the node's background ones, close waits for them, a newer
 * blob replaces a waiting one, many nodes' jobs all land, a full queue commits at once, failures are said at once or
 * by the next background commit, and without io_uring a background commit is a synchronous one. Files in this
 * test's own TMPDIR. Where this process cannot set up an io_uring (a seccomp filter), the tests that need one are
 * ignored, not passed.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <liburing.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/single_threaded.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "nvm_file.h"
#include "unity.h"

static char dir[256];
static unsigned dir_seq;

/* A fresh directory for each test. */
void setUp(void)
{
    const char *tmp = getenv("TMPDIR");
    (void)snprintf(dir, sizeof dir, "%s/nvm-%ld-%u", tmp != NULL ? tmp : "/tmp", (long)getpid(), dir_seq++);
    TEST_ASSERT_EQUAL_INT(0, mkdir(dir, 0755));
    nvm_writer_hold(false);
    nvm_writer_refuse(false);
}

void tearDown(void)
{
    nvm_writer_hold(false);
    nvm_writer_refuse(false);
    char cmd[300];
    (void)snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    TEST_ASSERT_EQUAL_INT(0, system(cmd));
}

static void open_node(nvm_file_t *n, const char *key)
{
    char err[256];
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, nvm_file_open(n, dir, key, err, sizeof err), err);
}

/* A blob of len bytes: tag, then its index. */
static void blob(uint8_t *b, size_t len, uint8_t tag)
{
    for (size_t i = 0U; i < len; i++) {
        b[i] = (uint8_t)(tag + i);
    }
}

static co_status_t commit(nvm_file_t *n, co_nvm_area_t area, uint8_t tag, uint32_t flags)
{
    uint8_t b[40];
    blob(b, sizeof b, tag);
    TEST_ASSERT_EQUAL_INT(CO_OK, nvm_file_write(n, area, 0U, b, sizeof b));
    return nvm_file_commit(n, area, (uint32_t)sizeof b | flags);
}

static const char *const suffix[3] = {"params", "lss", "device"};

/* The file of the area: -1 absent, else whether it holds the blob of tag. */
static int file_holds(const char *key, co_nvm_area_t area, uint8_t tag)
{
    char path[400];
    (void)snprintf(path, sizeof path, "%s/%s.%s", dir, key, suffix[area]);
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        TEST_ASSERT_EQUAL_INT(ENOENT, errno);
        return -1;
    }
    uint8_t got[64];
    const size_t len = fread(got, 1U, sizeof got, f);
    (void)fclose(f);
    uint8_t want[40];
    blob(want, sizeof want, tag);
    return len == sizeof want && memcmp(got, want, sizeof want) == 0 ? 1 : 0;
}

/* A load of the area (the core's first read is at offset 0) holds the blob of tag. */
static void load_holds(nvm_file_t *n, co_nvm_area_t area, uint8_t tag)
{
    uint8_t got[40];
    uint8_t want[40];
    blob(want, sizeof want, tag);
    TEST_ASSERT_EQUAL_INT(CO_OK, nvm_file_read(n, area, 0U, got, 8U));
    TEST_ASSERT_EQUAL_INT(CO_OK, nvm_file_read(n, area, 8U, got + 8, sizeof got - 8U));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, got, sizeof want);
}

/* Whether this process can set up an io_uring at all (the writer then must use one). */
static bool uring_here(void)
{
    struct io_uring r;
    if (io_uring_queue_init(4U, &r, 0U) != 0) {
        return false;
    }
    io_uring_queue_exit(&r);
    return true;
}

#define NEED_URING()                                                                                                  \
    do {                                                                                                              \
        if (!uring_here()) {                                                                                          \
            TEST_IGNORE_MESSAGE("no io_uring in this process: background commits are synchronous here");             \
        }                                                                                                             \
    } while (0)

static bool exists(const char *name)
{
    char path[400];
    (void)snprintf(path, sizeof path, "%s/%s", dir, name);
    struct stat st;
    return lstat(path, &st) == 0;
}

/* The kernel creates, syncs and renames the temporary file once the requests are given (the hold lifted): none of
 * it is done when the commit returns. glibc still takes its single-threaded paths: a thread would cost every system
 * call of the loop (docs/decisions.md). */
static void test_the_kernel_does_a_background_commit_and_the_process_keeps_one_thread(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "kernel");
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 1U, CO_NVM_BACKGROUND));
    TEST_ASSERT_FALSE(exists("kernel.device.tmp"));
    TEST_ASSERT_EQUAL_INT(-1, file_holds("kernel", CO_NVM_DEVICE, 1U));
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("kernel", CO_NVM_DEVICE, 1U));
    TEST_ASSERT_FALSE(exists("kernel.device.tmp"));
    TEST_ASSERT_TRUE(__libc_single_threaded);
    nvm_file_close(&n);
}

/* Without waiting: the loop's poll (one a pass) takes the completions as the kernel posts them. */
static void test_the_loops_poll_takes_the_completions(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "poll");
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_LSS, 2U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_LSS, 3U, CO_NVM_BACKGROUND)); /* waits for the first */
    const struct timespec ms = {0, 1000000L};
    for (int i = 0; i < 10000 && nvm_writer_counts().queued != 0U; i++) {
        nvm_writer_poll();
        (void)nanosleep(&ms, NULL);
    }
    TEST_ASSERT_EQUAL_UINT(0U, nvm_writer_counts().queued);
    TEST_ASSERT_EQUAL_INT(1, file_holds("poll", CO_NVM_LSS, 3U));
    nvm_file_close(&n);
}

/* Where no io_uring can be set up: the commit is a synchronous one, on disk before it returns. */
static void test_without_io_uring_a_background_commit_is_synchronous(void)
{
    nvm_file_t n;
    open_node(&n, "sync");
    nvm_writer_refuse(true);
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 4U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(1, file_holds("sync", CO_NVM_DEVICE, 4U));
    TEST_ASSERT_FALSE(exists("sync.device.tmp"));
    TEST_ASSERT_EQUAL_UINT(0U, nvm_writer_counts().queued);
    load_holds(&n, CO_NVM_DEVICE, 4U);
    nvm_file_close(&n);
}

static void test_a_background_commit_returns_before_the_file_is_written_and_a_load_sees_it(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "bg");
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 10U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(-1, file_holds("bg", CO_NVM_DEVICE, 10U)); /* not written yet */
    TEST_ASSERT_EQUAL_UINT(1U, nvm_writer_counts().queued);
    load_holds(&n, CO_NVM_DEVICE, 10U); /* the newest blob, at once */
    nvm_writer_hold(false);
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("bg", CO_NVM_DEVICE, 10U));
    load_holds(&n, CO_NVM_DEVICE, 10U); /* now from the file */
    nvm_file_close(&n);
}

/* Once written, a load sees the file again as it is, even one replaced by hand (nvm_file.h). */
static void test_a_load_sees_the_file_once_the_background_commit_is_written(void)
{
    nvm_file_t n;
    open_node(&n, "later");
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 20U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    char path[400];
    (void)snprintf(path, sizeof path, "%s/later.device", dir);
    TEST_ASSERT_EQUAL_INT(0, unlink(path));
    uint8_t b[8];
    TEST_ASSERT_EQUAL_INT(CO_ERR_NO_DATA, nvm_file_read(&n, CO_NVM_DEVICE, 0U, b, sizeof b));
    nvm_file_close(&n);
}

/* A commit without the flag (an answer waits for it) of the same area: it must not be overwritten by the older
 * background blob written after it. Of another area: the node's background commits are on disk before it returns. */
static void test_a_commit_someone_waits_for_lands_after_the_nodes_background_commits(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "order");
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 30U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 31U, 0U));
    nvm_writer_hold(false);
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("order", CO_NVM_DEVICE, 31U));
    load_holds(&n, CO_NVM_DEVICE, 31U);

    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 32U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_PARAMS, 33U, 0U));
    TEST_ASSERT_EQUAL_INT(1, file_holds("order", CO_NVM_DEVICE, 32U)); /* before the parameters returned */
    TEST_ASSERT_EQUAL_INT(1, file_holds("order", CO_NVM_PARAMS, 33U));
    nvm_file_close(&n);
}

static void test_close_waits_for_the_nodes_background_commits(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "close");
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 40U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_LSS, 41U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(-1, file_holds("close", CO_NVM_DEVICE, 40U));
    nvm_file_close(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("close", CO_NVM_DEVICE, 40U));
    TEST_ASSERT_EQUAL_INT(1, file_holds("close", CO_NVM_LSS, 41U));
}

/* One job per area is in flight; the blobs after it wait, the newest replacing the one before. */
static void test_a_newer_blob_replaces_one_that_has_not_started(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "newer");
    nvm_writer_hold(true);
    const nvm_writer_counts_t before = nvm_writer_counts();
    for (uint8_t tag = 50U; tag < 55U; tag++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, tag, CO_NVM_BACKGROUND));
        load_holds(&n, CO_NVM_DEVICE, tag);
    }
    /* 50 in flight, 51 waiting for it, replaced by 52, 53 and 54 */
    const nvm_writer_counts_t held = nvm_writer_counts();
    TEST_ASSERT_EQUAL_UINT(1U, held.queued);
    TEST_ASSERT_EQUAL_UINT32(3U, (uint32_t)(held.replaced - before.replaced));
    nvm_file_close(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("newer", CO_NVM_DEVICE, 54U));
    TEST_ASSERT_EQUAL_UINT32(2U, (uint32_t)(nvm_writer_counts().done - before.done)); /* two files written */
}

#define MANY 60

static void test_many_nodes_background_commits_all_land(void)
{
    nvm_file_t *n = calloc(MANY, sizeof *n);
    TEST_ASSERT_NOT_NULL(n);
    char key[32];
    for (int i = 0; i < MANY; i++) {
        (void)snprintf(key, sizeof key, "node-%d", i);
        open_node(&n[i], key);
    }
    for (int round = 0; round < 3; round++) {
        for (int i = 0; i < MANY; i++) {
            TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[i], CO_NVM_DEVICE, (uint8_t)(i + round), CO_NVM_BACKGROUND));
            TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[i], CO_NVM_LSS, (uint8_t)(100 + i + round), CO_NVM_BACKGROUND));
        }
    }
    for (int i = 0; i < MANY; i++) {
        load_holds(&n[i], CO_NVM_DEVICE, (uint8_t)(i + 2));
        nvm_file_close(&n[i]);
        (void)snprintf(key, sizeof key, "node-%d", i);
        TEST_ASSERT_EQUAL_INT(1, file_holds(key, CO_NVM_DEVICE, (uint8_t)(i + 2)));
        TEST_ASSERT_EQUAL_INT(1, file_holds(key, CO_NVM_LSS, (uint8_t)(100 + i + 2)));
    }
    free(n);
}

/* NVM_WRITER_QUEUE jobs in flight: the next background commit of another node is written before it returns. */
static void test_a_full_queue_commits_at_once(void)
{
    NEED_URING();
    const int nodes = (int)(NVM_WRITER_QUEUE / 2U) + 1;
    nvm_file_t *n = calloc((size_t)nodes, sizeof *n);
    TEST_ASSERT_NOT_NULL(n);
    char key[32];
    for (int i = 0; i < nodes; i++) {
        (void)snprintf(key, sizeof key, "full-%d", i);
        open_node(&n[i], key);
    }
    nvm_writer_hold(true);
    for (int i = 0; i + 1 < nodes; i++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[i], CO_NVM_DEVICE, (uint8_t)i, CO_NVM_BACKGROUND));
        TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[i], CO_NVM_LSS, (uint8_t)(i + 1), CO_NVM_BACKGROUND));
    }
    TEST_ASSERT_EQUAL_UINT(NVM_WRITER_QUEUE, nvm_writer_counts().queued);
    TEST_ASSERT_EQUAL_INT(-1, file_holds("full-0", CO_NVM_DEVICE, 0U));
    const int last = nodes - 1;
    (void)snprintf(key, sizeof key, "full-%d", last);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[last], CO_NVM_DEVICE, 200U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(1, file_holds(key, CO_NVM_DEVICE, 200U)); /* at once */
    TEST_ASSERT_EQUAL_UINT(NVM_WRITER_QUEUE, nvm_writer_counts().queued); /* the others still wait */
    /* A waiting blob of an area is still replaced in a full queue. */
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n[0], CO_NVM_DEVICE, 201U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(-1, file_holds("full-0", CO_NVM_DEVICE, 201U));
    for (int i = 0; i < nodes; i++) {
        nvm_file_close(&n[i]);
    }
    TEST_ASSERT_EQUAL_INT(1, file_holds("full-0", CO_NVM_DEVICE, 201U));
    TEST_ASSERT_EQUAL_INT(1, file_holds("full-1", CO_NVM_LSS, 2U));
    free(n);
}

/* The file cannot be replaced (a directory has its name): found before the commit returns, it answers CO_ERR_IO,
 * and a load sees the file as it is, not the lost blob. */
static void test_a_background_commit_that_cannot_start_fails_at_once(void)
{
    nvm_file_t n;
    open_node(&n, "fail");
    char path[400];
    (void)snprintf(path, sizeof path, "%s/fail.device", dir);
    TEST_ASSERT_EQUAL_INT(0, mkdir(path, 0755));
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, commit(&n, CO_NVM_DEVICE, 60U, CO_NVM_BACKGROUND));
    TEST_ASSERT_FALSE(exists("fail.device.tmp"));
    uint8_t b[8];
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, nvm_file_read(&n, CO_NVM_DEVICE, 0U, b, sizeof b)); /* the directory */
    TEST_ASSERT_EQUAL_INT(0, rmdir(path));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 62U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("fail", CO_NVM_DEVICE, 62U));
    nvm_file_close(&n);
}

/* The kernel's rename fails (a directory took the file's name after the commit returned): the file is as it was,
 * the temporary file is gone, and the area's next background commit says it, once. */
static void test_a_failed_background_write_is_said_by_the_next_one(void)
{
    NEED_URING();
    nvm_file_t n;
    open_node(&n, "late");
    char path[400];
    (void)snprintf(path, sizeof path, "%s/late.device", dir);
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 63U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(0, mkdir(path, 0755));
    nvm_file_flush(&n);
    TEST_ASSERT_FALSE(exists("late.device.tmp"));
    uint8_t b[8];
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, nvm_file_read(&n, CO_NVM_DEVICE, 0U, b, sizeof b)); /* the directory */
    TEST_ASSERT_EQUAL_INT(0, rmdir(path));
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, commit(&n, CO_NVM_DEVICE, 64U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 65U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("late", CO_NVM_DEVICE, 65U));
    nvm_file_close(&n);
}

/* Between a CO_NVM_MORE commit and the store's last one (the core never does this): committed at once, as by a port
 * without the flag, which ends the store. Nothing is left at a temporary name. */
static void test_a_background_commit_in_an_open_store_commits_at_once(void)
{
    nvm_file_t n;
    open_node(&n, "store");
    nvm_writer_hold(true);
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_LSS, 70U, CO_NVM_MORE));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 71U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(1, file_holds("store", CO_NVM_LSS, 70U));
    TEST_ASSERT_EQUAL_INT(1, file_holds("store", CO_NVM_DEVICE, 71U));
    TEST_ASSERT_EQUAL_UINT(0U, nvm_writer_counts().queued);
    char path[400];
    (void)snprintf(path, sizeof path, "%s/store.device.tmp", dir);
    struct stat st;
    TEST_ASSERT_NOT_EQUAL(0, lstat(path, &st));
    nvm_file_close(&n);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_the_kernel_does_a_background_commit_and_the_process_keeps_one_thread);
    RUN_TEST(test_the_loops_poll_takes_the_completions);
    RUN_TEST(test_without_io_uring_a_background_commit_is_synchronous);
    RUN_TEST(test_a_background_commit_returns_before_the_file_is_written_and_a_load_sees_it);
    RUN_TEST(test_a_load_sees_the_file_once_the_background_commit_is_written);
    RUN_TEST(test_a_commit_someone_waits_for_lands_after_the_nodes_background_commits);
    RUN_TEST(test_close_waits_for_the_nodes_background_commits);
    RUN_TEST(test_a_newer_blob_replaces_one_that_has_not_started);
    RUN_TEST(test_many_nodes_background_commits_all_land);
    RUN_TEST(test_a_full_queue_commits_at_once);
    RUN_TEST(test_a_background_commit_that_cannot_start_fails_at_once);
    RUN_TEST(test_a_failed_background_write_is_said_by_the_next_one);
    RUN_TEST(test_a_background_commit_in_an_open_store_commits_at_once);
    return UNITY_END();
}
