/* Deadline arithmetic and the transmit path: absolute deadlines (no drift over 10,000 periods with late
 * wake-ups), deadlines returned by co_node_process, busy ports and lost frames. */
#include "fixture.h"

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

/* A deterministic pseudo-random lateness in [0, max) µs. */
static uint32_t lcg = 12345U;
static co_time_us_t late(co_time_us_t max)
{
    lcg = lcg * 1103515245U + 12345U;
    return (co_time_us_t)((lcg >> 8) % max);
}

static void heartbeat_has_no_drift_over_10000_periods(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 10U, 2U)); /* 10 ms, written at t0 */
    const co_time_us_t t0 = fx.now;
    const uint32_t sent_before = fx.node.stats.tx_frames;
    co_time_us_t next = fx_process();
    for (uint32_t k = 1U; k <= 10000U; k++) {
        TEST_ASSERT_EQUAL_UINT64(t0 + (co_time_us_t)k * 10000U, next); /* always on the grid */
        fx.now = next + late(9000U);                                  /* wake up up to 9 ms late */
        next = fx_process();
    }
    TEST_ASSERT_EQUAL_UINT32(10000U, fx.node.stats.tx_frames - sent_before); /* one heartbeat per period */
    TEST_ASSERT_EQUAL_UINT64(t0 + 10001UL * 10000U, next);
}

static void heartbeat_skips_periods_missed_entirely(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 10U, 2U));
    const co_time_us_t t0 = fx.now;
    fake_port_clear(&fx.port);
    fx.now = t0 + 35000U; /* 3.5 periods late: one heartbeat, then back on the grid */
    const co_time_us_t next = fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U));
    TEST_ASSERT_EQUAL_UINT64(t0 + 40000U, next);
}

static void event_timer_tpdo_has_no_drift(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 5, 20U, 2U)); /* 20 ms */
    RX(0x000, 0x01, 0x05);
    const co_time_us_t t0 = fx.now;
    const uint32_t sent_before = fx.node.stats.tx_frames;
    co_time_us_t next = fx_process();
    for (uint32_t k = 1U; k <= 10000U; k++) {
        TEST_ASSERT_EQUAL_UINT64(t0 + (co_time_us_t)k * 20000U, next);
        fx.now = next + late(15000U);
        next = fx_process();
    }
    TEST_ASSERT_EQUAL_UINT32(10000U, fx.node.stats.tx_frames - sent_before); /* + the one at start */
}

static void process_reports_never_when_idle(void)
{
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, fx_process());
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 100U, 2U));
    TEST_ASSERT_EQUAL_UINT64(fx.now + 100000U, fx_process());
}

static void busy_port_frames_are_retried_in_order(void)
{
    fx.port.busy_count = 3U; /* send, flush in process, flush again after the second RX */
    RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    RX(0x605, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0); /* queued behind the first */
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.busy_count);
    fx.port.busy_count = 1U;
    const co_time_us_t next = fx_process();
    TEST_ASSERT_EQUAL_UINT64(fx.now + CO_TX_RETRY_US, next);
    fx.now = next;
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x585U, 8, 0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00);
    ASSERT_FRAME(1, 0x585U, 8, 0x43, 0x18, 0x10, 0x01, 0x4E, 0x02, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.node.stats.tx_dropped);
}

static void full_queue_and_io_errors_are_counted_and_reported(void)
{
    fx.port.busy_count = 1000U;
    for (uint32_t i = 0U; i < CO_TX_QUEUE_LEN + 2U; i++) {
        RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    }
    TEST_ASSERT_EQUAL_UINT32(2U, fx.node.stats.tx_dropped);
    TEST_ASSERT_EQUAL_INT(CO_EV_TX_DROPPED, fx.events[fx.n_events - 1U].kind);
    TEST_ASSERT_EQUAL_HEX32(0x585U, fx.events[fx.n_events - 1U].value);
    fx.port.busy_count = 0U;
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(CO_TX_QUEUE_LEN, fx.port.n_sent);
    fx.port.send_io_error = true;
    RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.node.stats.tx_dropped);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(heartbeat_has_no_drift_over_10000_periods);
    RUN_TEST(heartbeat_skips_periods_missed_entirely);
    RUN_TEST(event_timer_tpdo_has_no_drift);
    RUN_TEST(process_reports_never_when_idle);
    RUN_TEST(busy_port_frames_are_retried_in_order);
    RUN_TEST(full_queue_and_io_errors_are_counted_and_reported);
    return UNITY_END();
}
