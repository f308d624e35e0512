/* Every timed service across the wrap of a 32-bit clock (CO_CONFIG_TIME32: co_time_us_t wraps every 2^32 µs), and
 * timers longer than a 32-bit deadline can hold ahead (life guarding up to 4.6 hours, the SYNC timeout up to 107
 * minutes). The node starts 2.5 s before 2^32 µs: with 64-bit time nothing wraps there and the same timings hold.
 * Times are compared relative to the start, in co_time_us_t arithmetic (which wraps as the clock does). */
#include "fixture.h"
#include "priv/co_priv.h"

#define MS ((co_time_us_t)1000U)
#define MINUTE ((co_time_us_t)60000000UL) /* (a 16-bit int would wrap 40U * 60000U) */
#define T0 ((co_time_us_t)(0xFFFFFFFFUL - 2500000UL + 1UL)) /* 2^32 µs - 2.5 s */

void setUp(void)
{
    fx_start_at(5U, 0U, T0);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

static co_time_us_t at(co_time_us_t offset) { return (co_time_us_t)(T0 + offset); }
static co_time_us_t since_start(co_time_us_t t) { return (co_time_us_t)(t - T0); }

/* Runs to the offset in steps of 10 minutes at most: the contract of 32-bit time (the node is called no later than
 * 35.8 minutes after a deadline it returned) also holds where it has nothing to do for a long time. */
static void run_to(co_time_us_t offset)
{
    const co_time_us_t step = 10U * MINUTE;
    while (offset - since_start(fx.now) > step) {
        fx_run_until(at(since_start(fx.now) + step));
    }
    fx_run_until(at(offset));
}

/* The time of the k-th recorded frame with this CAN-ID (0-based), relative to the start; fails when there is none. */
static co_time_us_t nth_at(uint32_t id, uint32_t k)
{
    for (uint32_t i = 0U; i < fx.port.n_sent; i++) {
        if (fx.port.sent[i].id == id && k-- == 0U) {
            return since_start(fx.port.sent_at[i]);
        }
    }
    TEST_FAIL_MESSAGE("no such frame");
    return 0U;
}

static void heartbeats_stay_on_their_grid_across_the_wrap(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 700U, 2U));
    fake_port_clear(&fx.port);
    run_to(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(7U, fx_count(0x705U)); /* 0.7 s .. 4.9 s, 2.1 and 2.8 s around the wrap */
    for (uint32_t k = 0U; k < 7U; k++) {
        TEST_ASSERT_EQUAL_UINT64((k + 1U) * 700U * MS, nth_at(0x705U, k));
    }
}

static void emcy_inhibit_time_runs_across_the_wrap(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1015, 0, 10000U, 2U)); /* 1 s */
    run_to(2000U * MS);
    fake_port_clear(&fx.port);
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL);
    run_to(2100U * MS);
    (void)co_emcy_raise(&fx.node, 0x5001U, 0x01U, NULL);
    run_to(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(2000U * MS, nth_at(0x085U, 0));
    TEST_ASSERT_EQUAL_UINT64(3000U * MS, nth_at(0x085U, 1)); /* the inhibit time ended after the wrap */
}

/* An inhibit time that ended long ago never holds a later EMCY back (a past time kept in a 32-bit clock would look
 * ahead again half a wrap later, 35.8 minutes): the node is called only at the deadlines it returns. */
static void an_old_inhibit_time_never_delays_an_emcy(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1015, 0, 10U, 2U)); /* 1 ms */
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL);
    run_to(50U * MINUTE); /* 50 minutes */
    fake_port_clear(&fx.port);
    (void)co_emcy_raise(&fx.node, 0x5001U, 0x01U, NULL);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(50U * MINUTE, nth_at(0x085U, 0));
}

static void tpdo_event_timer_and_inhibit_across_the_wrap(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 5, 500U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 1, 0x80000185UL, 4U)); /* the inhibit time: while invalid */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 3, 3000U, 2U));           /* 300 ms */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 1, 0x185UL, 4U));
    run_to(1000U * MS);
    fx_rx(0x000U, 2U, (const uint8_t[]){0x01, 0x05}); /* Operational: TPDO1 at once, then every 500 ms */
    fake_port_clear(&fx.port);
    run_to(2400U * MS);
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL); /* the error register changes at 2.4 s: sent at once */
    run_to(2500U * MS);
    (void)co_emcy_clear(&fx.node, 0x5000U, NULL); /* and back at 2.5 s: held by the inhibit time to 2.7 s */
    run_to(4000U * MS);
    const co_time_us_t expect[] = {1500U, 2000U, 2400U, 2700U, 3200U, 3700U};
    TEST_ASSERT_EQUAL_UINT32(6U, fx_count(0x185U));
    for (uint32_t k = 0U; k < 6U; k++) {
        TEST_ASSERT_EQUAL_UINT64(expect[k] * MS, nth_at(0x185U, k));
    }
}

static void consumer_timeout_across_the_wrap(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 1, 0x000A012CUL, 4U)); /* node 10, 300 ms */
    run_to(2300U * MS);
    fx_rx(0x70AU, 1U, (const uint8_t[]){0x05});
    fake_port_clear(&fx.port);
    run_to(4000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(2600U * MS, nth_at(0x085U, 0));
}

static void life_guarding_across_the_wrap_and_for_40_minutes(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 100U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 3U, 1U));
    run_to(2400U * MS);
    fx_rx_rtr(0x705U);
    fake_port_clear(&fx.port);
    run_to(4000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(2700U * MS, nth_at(0x085U, 0));
    /* 60 s x 40 = 40 minutes: longer than a 32-bit deadline holds ahead (2^31 µs = 35.8 minutes) */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 60000U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 40U, 1U));
    fx_rx_rtr(0x705U); /* at 4 s: the error clears (error reset EMCY) */
    fake_port_clear(&fx.port);
    run_to(4000U * MS + 40U * MINUTE - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    run_to(4000U * MS + 40U * MINUTE);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

/* A call 18 minutes after the first step's deadline (within the 35.8 minutes 32-bit time allows): the steps it
 * missed are taken at once, the deadline returned is the timeout's, not a past one. */
static void a_late_call_takes_the_missed_steps_of_a_long_timer(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 60000U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 40U, 1U)); /* 40 minutes, steps of 16.7 */
    fx_rx_rtr(0x705U);
    fake_port_clear(&fx.port);
    fx.now = at(35U * MINUTE);
    TEST_ASSERT_EQUAL_UINT64(at(40U * MINUTE), fx_process());
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    fx.now = at(40U * MINUTE);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void sync_timeout_across_the_wrap_and_after_25_minutes(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1006, 0, 200000U, 4U)); /* 200 ms: timeout 300 ms */
    run_to(2400U * MS);
    fx_rx(0x080U, 0U, NULL);
    fake_port_clear(&fx.port);
    run_to(4000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(2700U * MS, nth_at(0x085U, 0));
    /* a period of 1000 s: the timeout comes 1500 s (25 minutes) after a SYNC */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1006, 0, 1000000000UL, 4U));
    fx_rx(0x080U, 0U, NULL); /* at 4 s: clears the timeout error */
    fake_port_clear(&fx.port);
    run_to(4000U * MS + 25U * MINUTE - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    run_to(4000U * MS + 25U * MINUTE);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

/* Division and remainder without a divide instruction (co_priv.h): a late timer's re-alignment, a long timer's start. */
static void remainder_without_division(void)
{
    static const uint32_t edge[] = {0U, 1U, 2U, 3U, 999U, 1000U, 65535000UL, 0x7FFFFFFFUL, 0x80000000UL, 0x80000001UL,
                                    0xFFFFFFFEUL, 0xFFFFFFFFUL};
    const unsigned n = (unsigned)(sizeof edge / sizeof edge[0]);
    for (unsigned i = 0U; i < n; i++) {
        for (unsigned j = 1U; j < n; j++) {
            uint32_t rem = 0U;
            TEST_ASSERT_EQUAL_UINT32(edge[i] / edge[j], co_div_u32(edge[i], edge[j], &rem));
            TEST_ASSERT_EQUAL_UINT32(edge[i] % edge[j], rem);
        }
    }
    uint32_t x = 1U;
    for (unsigned k = 0U; k < 2000U; k++) {
        x = (uint32_t)(x * 1664525UL + 1013904223UL);
        const uint32_t a = x;
        x = (uint32_t)(x * 1664525UL + 1013904223UL);
        const uint32_t b = (x >> (x & 31U)) | 1U;
        TEST_ASSERT_EQUAL_UINT32(a % b, co_rem_u32(a, b));
        TEST_ASSERT_EQUAL_UINT32(a / b, co_div_u32(a, b, NULL));
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(heartbeats_stay_on_their_grid_across_the_wrap);
    RUN_TEST(emcy_inhibit_time_runs_across_the_wrap);
    RUN_TEST(an_old_inhibit_time_never_delays_an_emcy);
    RUN_TEST(tpdo_event_timer_and_inhibit_across_the_wrap);
    RUN_TEST(consumer_timeout_across_the_wrap);
    RUN_TEST(life_guarding_across_the_wrap_and_for_40_minutes);
    RUN_TEST(a_late_call_takes_the_missed_steps_of_a_long_timer);
    RUN_TEST(sync_timeout_across_the_wrap_and_after_25_minutes);
    RUN_TEST(remainder_without_division);
    return UNITY_END();
}
