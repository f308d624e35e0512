/* The SPSC receive ring: order, full/empty, index wrap at 2^32, and a two-thread producer/consumer run. */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <sched.h>
#include <string.h>

#include "co_bm_ring.h"
#include "unity.h"

/* Field by field: co_frame_t has padding, which a struct copy need not preserve. */
static bool same_frame(const co_frame_t *a, const co_frame_t *b)
{
    return a->id == b->id && a->len == b->len && a->flags == b->flags && memcmp(a->data, b->data, sizeof a->data) == 0;
}

static co_bm_ring_t ring;

void setUp(void) { co_bm_ring_init(&ring); }
void tearDown(void) {}

static co_frame_t frame(uint32_t n)
{
    co_frame_t f = {0x180U + (n & 0x7FU), 8U, 0U, {0U}};
    memcpy(f.data, &n, sizeof n);
    f.data[7] = (uint8_t)~n;
    return f;
}

static void pops_in_push_order(void)
{
    co_frame_t f;
    TEST_ASSERT_FALSE(co_bm_ring_pop(&ring, &f));
    for (uint32_t n = 0U; n < 5U; n++) {
        const co_frame_t in = frame(n);
        TEST_ASSERT_TRUE(co_bm_ring_push(&ring, &in));
    }
    TEST_ASSERT_EQUAL_UINT32(5U, co_bm_ring_count(&ring));
    for (uint32_t n = 0U; n < 5U; n++) {
        const co_frame_t want = frame(n);
        TEST_ASSERT_TRUE(co_bm_ring_pop(&ring, &f));
        TEST_ASSERT_TRUE(same_frame(&want, &f));
    }
    TEST_ASSERT_FALSE(co_bm_ring_pop(&ring, &f));
    TEST_ASSERT_EQUAL_UINT32(0U, co_bm_ring_count(&ring));
}

static void full_ring_drops_and_counts(void)
{
    for (uint32_t n = 0U; n < CO_BM_RING_LEN; n++) {
        const co_frame_t in = frame(n);
        TEST_ASSERT_TRUE(co_bm_ring_push(&ring, &in));
    }
    const co_frame_t extra = frame(999U);
    TEST_ASSERT_FALSE(co_bm_ring_push(&ring, &extra));
    TEST_ASSERT_FALSE(co_bm_ring_push(&ring, &extra));
    TEST_ASSERT_EQUAL_UINT32(2U, ring.overruns);
    co_frame_t f;
    TEST_ASSERT_TRUE(co_bm_ring_pop(&ring, &f)); /* one slot free again: the next push fits */
    TEST_ASSERT_TRUE(co_bm_ring_push(&ring, &extra));
    for (uint32_t n = 1U; n < CO_BM_RING_LEN; n++) {
        const co_frame_t want = frame(n);
        TEST_ASSERT_TRUE(co_bm_ring_pop(&ring, &f));
        TEST_ASSERT_TRUE(same_frame(&want, &f));
    }
    TEST_ASSERT_TRUE(co_bm_ring_pop(&ring, &f));
    TEST_ASSERT_TRUE(same_frame(&extra, &f)); /* the dropped copies left no trace */
    TEST_ASSERT_FALSE(co_bm_ring_pop(&ring, &f));
}

static void indices_wrap_at_2_pow_32(void)
{
    ring.head = ring.tail = UINT32_MAX - 3U;
    co_frame_t f;
    for (uint32_t round = 0U; round < 3U; round++) {
        for (uint32_t n = 0U; n < CO_BM_RING_LEN; n++) {
            const co_frame_t in = frame(round * 100U + n);
            TEST_ASSERT_TRUE(co_bm_ring_push(&ring, &in));
        }
        const co_frame_t extra = frame(7777U);
        TEST_ASSERT_FALSE(co_bm_ring_push(&ring, &extra)); /* still full across the wrap */
        TEST_ASSERT_EQUAL_UINT32(CO_BM_RING_LEN, co_bm_ring_count(&ring));
        for (uint32_t n = 0U; n < CO_BM_RING_LEN; n++) {
            const co_frame_t want = frame(round * 100U + n);
            TEST_ASSERT_TRUE(co_bm_ring_pop(&ring, &f));
            TEST_ASSERT_TRUE(same_frame(&want, &f));
        }
        TEST_ASSERT_FALSE(co_bm_ring_pop(&ring, &f));
    }
    TEST_ASSERT_TRUE(ring.head < 1000U); /* it did wrap */
}

/* Two threads as interrupt and main loop: every frame arrives once, in order, intact. */
#define STRESS_FRAMES 200000U
static void *producer(void *arg)
{
    (void)arg;
    for (uint32_t n = 0U; n < STRESS_FRAMES; n++) {
        const co_frame_t in = frame(n);
        while (!co_bm_ring_push(&ring, &in)) {
            sched_yield(); /* a real ISR would drop; here the producer waits so the check is exact */
        }
    }
    return NULL;
}

static void concurrent_producer_and_consumer(void)
{
    pthread_t t;
    TEST_ASSERT_EQUAL_INT(0, pthread_create(&t, NULL, producer, NULL));
    uint32_t bad = 0U;
    for (uint32_t n = 0U; n < STRESS_FRAMES;) {
        co_frame_t f;
        if (!co_bm_ring_pop(&ring, &f)) {
            sched_yield();
            continue;
        }
        const co_frame_t want = frame(n);
        bad += same_frame(&want, &f) ? 0U : 1U;
        n++;
    }
    TEST_ASSERT_EQUAL_INT(0, pthread_join(t, NULL));
    TEST_ASSERT_EQUAL_UINT32(0U, bad);
    TEST_ASSERT_EQUAL_UINT32(0U, co_bm_ring_count(&ring));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(pops_in_push_order);
    RUN_TEST(full_ring_drops_and_counts);
    RUN_TEST(indices_wrap_at_2_pow_32);
    RUN_TEST(concurrent_producer_and_consumer);
    return UNITY_END();
}
