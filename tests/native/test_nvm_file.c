/*
 * Background commits of the NVM files (ports/linux/nvm_file.c, nvm_writer.c; co_port.h CO_NVM_BACKGROUND): the
 * commit returns before the file is written (the writer held by its test hook), a load right after sees the new
 * blob, a commit someone waits for lands after the node's background ones, close waits for them, a newer blob
 * replaces a waiting one, many nodes' jobs all land, a full queue commits at once, a failed background write is
 * said by the next one, the writer thread takes no signal. Files in this test's own TMPDIR.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
}

void tearDown(void)
{
    nvm_writer_hold(false);
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

static volatile sig_atomic_t usr1_seen;
static void on_usr1(int sig)
{
    (void)sig;
    usr1_seen = 1;
}

/* First (the writer starts at the first background commit of the process): a signal for the process never goes
 * to the writer thread, whatever the loop's thread blocks at the moment (the emulator's SIGINT/SIGTERM end its
 * wait). Here the main thread blocks SIGUSR1: it stays pending for the main thread instead of being taken. */
static void test_the_writer_thread_takes_no_signal(void)
{
    nvm_file_t n;
    open_node(&n, "sig");
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 1U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_usr1;
    TEST_ASSERT_EQUAL_INT(0, sigaction(SIGUSR1, &sa, NULL));
    sigset_t usr1;
    sigset_t old;
    sigemptyset(&usr1);
    sigaddset(&usr1, SIGUSR1);
    TEST_ASSERT_EQUAL_INT(0, pthread_sigmask(SIG_BLOCK, &usr1, &old));
    TEST_ASSERT_EQUAL_INT(0, kill(getpid(), SIGUSR1));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 2U, CO_NVM_BACKGROUND)); /* the writer runs meanwhile */
    nvm_file_flush(&n);
    const struct timespec wait = {0, 50000000L};
    (void)nanosleep(&wait, NULL);
    sigset_t pending;
    TEST_ASSERT_EQUAL_INT(0, sigpending(&pending));
    TEST_ASSERT_EQUAL_INT(0, usr1_seen);
    TEST_ASSERT_EQUAL_INT(1, sigismember(&pending, SIGUSR1));
    const struct timespec none = {0, 0};
    TEST_ASSERT_EQUAL_INT(SIGUSR1, sigtimedwait(&usr1, NULL, &none));
    TEST_ASSERT_EQUAL_INT(0, pthread_sigmask(SIG_SETMASK, &old, NULL));
    nvm_file_close(&n);
}

static void test_a_background_commit_returns_before_the_file_is_written_and_a_load_sees_it(void)
{
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

static void test_a_newer_blob_replaces_one_that_has_not_started(void)
{
    nvm_file_t n;
    open_node(&n, "newer");
    nvm_writer_hold(true);
    const nvm_writer_counts_t before = nvm_writer_counts();
    for (uint8_t tag = 50U; tag < 55U; tag++) {
        TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, tag, CO_NVM_BACKGROUND));
        load_holds(&n, CO_NVM_DEVICE, tag);
    }
    const nvm_writer_counts_t held = nvm_writer_counts();
    TEST_ASSERT_EQUAL_UINT(1U, held.queued);
    TEST_ASSERT_EQUAL_UINT32(4U, (uint32_t)(held.replaced - before.replaced));
    nvm_file_close(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("newer", CO_NVM_DEVICE, 54U));
    TEST_ASSERT_EQUAL_UINT32(1U, (uint32_t)(nvm_writer_counts().done - before.done)); /* one file written */
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

/* NVM_WRITER_QUEUE jobs waiting: the next background commit of another node is written before it returns. */
static void test_a_full_queue_commits_at_once(void)
{
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

/* The file cannot be replaced (a directory has its name): the background commit answers CO_OK, its failure is said
 * by the area's next background commit, and a load meanwhile sees the file as it is, not the lost blob. */
static void test_a_failed_background_write_is_said_by_the_next_one(void)
{
    nvm_file_t n;
    open_node(&n, "fail");
    char path[400];
    (void)snprintf(path, sizeof path, "%s/fail.device", dir);
    TEST_ASSERT_EQUAL_INT(0, mkdir(path, 0755));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 60U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    uint8_t b[8];
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, nvm_file_read(&n, CO_NVM_DEVICE, 0U, b, sizeof b)); /* the directory */
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, commit(&n, CO_NVM_DEVICE, 61U, CO_NVM_BACKGROUND));
    TEST_ASSERT_EQUAL_INT(0, rmdir(path));
    TEST_ASSERT_EQUAL_INT(CO_OK, commit(&n, CO_NVM_DEVICE, 62U, CO_NVM_BACKGROUND));
    nvm_file_flush(&n);
    TEST_ASSERT_EQUAL_INT(1, file_holds("fail", CO_NVM_DEVICE, 62U));
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
    RUN_TEST(test_the_writer_thread_takes_no_signal);
    RUN_TEST(test_a_background_commit_returns_before_the_file_is_written_and_a_load_sees_it);
    RUN_TEST(test_a_load_sees_the_file_once_the_background_commit_is_written);
    RUN_TEST(test_a_commit_someone_waits_for_lands_after_the_nodes_background_commits);
    RUN_TEST(test_close_waits_for_the_nodes_background_commits);
    RUN_TEST(test_a_newer_blob_replaces_one_that_has_not_started);
    RUN_TEST(test_many_nodes_background_commits_all_land);
    RUN_TEST(test_a_full_queue_commits_at_once);
    RUN_TEST(test_a_failed_background_write_is_said_by_the_next_one);
    RUN_TEST(test_a_background_commit_in_an_open_store_commits_at_once);
    return UNITY_END();
}
