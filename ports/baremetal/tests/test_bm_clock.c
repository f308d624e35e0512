/* The clock: 64-bit µs from wrapping counters of several widths and frequencies, exactly, no drift. */
#include "co_bm_clock.h"
#include "unity.h"

typedef struct counter {
    uint64_t ticks; /* true elapsed ticks */
    uint32_t mask;
} counter_t;

static uint32_t read_counter(void *ctx)
{
    const counter_t *c = (const counter_t *)ctx;
    return (uint32_t)c->ticks & c->mask;
}

void setUp(void) {}
void tearDown(void) {}

static uint32_t lcg = 1U;
static uint32_t rnd(uint32_t max)
{
    lcg = lcg * 1103515245U + 12345U;
    return (lcg >> 4) % max;
}

/* Advances the counter by random steps (each below one period) for `steps` calls; checks every reading
 * against the exact conversion of the true tick count. */
static void run(uint32_t hz, uint8_t bits, uint64_t start_ticks, uint32_t steps)
{
    counter_t c = {start_ticks, bits >= 32U ? UINT32_MAX : (uint32_t)((1UL << bits) - 1UL)};
    co_bm_clock_t clk;
    co_bm_clock_init(&clk, read_counter, &c, hz, bits, 0U);
    const uint64_t t0 = c.ticks;
    uint32_t wraps = 0U;
    for (uint32_t i = 0U; i < steps; i++) {
        const uint64_t before = c.ticks;
        c.ticks += rnd(c.mask) + (i % 7U == 0U ? 0U : 1U); /* sometimes no tick at all */
        wraps += (uint32_t)((c.ticks >> bits) != (before >> bits));
        const uint64_t elapsed = c.ticks - t0;
        const uint64_t want = elapsed / hz * 1000000U + (elapsed % hz) * 1000000U / hz;
        const co_time_us_t now = co_bm_clock_now(&clk);
        if (now != want) {
            TEST_ASSERT_EQUAL_UINT64(want, now);
        }
    }
    TEST_ASSERT_TRUE_MESSAGE(wraps > 10U, "the counter should have wrapped many times");
}

static void timer_16bit_1mhz(void) { run(1000000U, 16U, 0xFFF0U, 100000U); }
static void timer_24bit_systick_72mhz(void) { run(72000000U, 24U, 0U, 100000U); }
static void timer_32bit_170mhz(void) { run(170000000U, 32U, 0xFFFFFF00UL, 20000U); }
static void rtc_32768hz_16bit(void) { run(32768U, 16U, 0U, 100000U); }
static void ms_tick_32bit_wraps_after_49_days(void) { run(1000U, 32U, 0xFFFFFFF0UL, 20000U); }

static void exact_over_a_long_run_without_drift(void)
{
    /* 32768 Hz: one tick is 30.517578125 µs; after exactly 2^15 ticks it must be exactly 1 s. */
    counter_t c = {0U, 0xFFFFU};
    co_bm_clock_t clk;
    co_bm_clock_init(&clk, read_counter, &c, 32768U, 16U, 5000U);
    for (uint32_t s = 1U; s <= 3600U; s++) {
        for (uint32_t k = 0U; k < 8U; k++) {
            c.ticks += 4096U;
            (void)co_bm_clock_now(&clk);
        }
        TEST_ASSERT_EQUAL_UINT64(5000U + (uint64_t)s * 1000000U, clk.us);
    }
}

static void ticks_until_deadline(void)
{
    counter_t c = {0U, UINT32_MAX};
    co_bm_clock_t clk;
    co_bm_clock_init(&clk, read_counter, &c, 32768U, 32U, 0U);
    TEST_ASSERT_EQUAL_UINT32(0U, co_bm_clock_ticks_until(&clk, 1000U, 1000U, 0xFFFFU));
    TEST_ASSERT_EQUAL_UINT32(0U, co_bm_clock_ticks_until(&clk, 1000U, 10U, 0xFFFFU));
    TEST_ASSERT_EQUAL_UINT32(1U, co_bm_clock_ticks_until(&clk, 0U, 1U, 0xFFFFU));        /* rounded up */
    TEST_ASSERT_EQUAL_UINT32(32768U, co_bm_clock_ticks_until(&clk, 0U, 1000000U, 0xFFFFU));
    TEST_ASSERT_EQUAL_UINT32(0xFFFFU, co_bm_clock_ticks_until(&clk, 0U, 10000000U, 0xFFFFU)); /* capped */
    TEST_ASSERT_EQUAL_UINT32(0xFFFFU, co_bm_clock_ticks_until(&clk, 0U, CO_NEVER, 0xFFFFU));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(timer_16bit_1mhz);
    RUN_TEST(timer_24bit_systick_72mhz);
    RUN_TEST(timer_32bit_170mhz);
    RUN_TEST(rtc_32768hz_16bit);
    RUN_TEST(ms_tick_32bit_wraps_after_49_days);
    RUN_TEST(exact_over_a_long_run_without_drift);
    RUN_TEST(ticks_until_deadline);
    return UNITY_END();
}
