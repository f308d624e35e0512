/* Heartbeat producer 0x1017: exact timing on an absolute grid, state byte, period changes
 * (facts §3.1, §11 #2-#4, #10). */
#include "fixture.h"

#define MS ((co_time_us_t)1000U)

void setUp(void) { fx_start(5U, 0U); }
void tearDown(void) {}

/* Index of the last recorded frame with this CAN-ID; fails the test when there is none. */
static uint32_t last_idx(uint32_t id)
{
    const int i = fx_last(id);
    TEST_ASSERT_TRUE_MESSAGE(i >= 0, "no frame with this CAN-ID");
    return (uint32_t)i;
}

/* Number of heartbeats (0x705 frames with a non-zero state, i.e. not the boot-up) recorded so far. */
static uint32_t heartbeats(void)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.port.n_sent; i++) {
        if (fx.port.sent[i].id == 0x705U && fx.port.sent[i].len == 1U && fx.port.sent[i].data[0] != 0U) {
            n++;
        }
    }
    return n;
}

/* Sets the heartbeat period by SDO at the current time and forgets the recorded frames. */
static void set_hb_ms(uint16_t ms)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, ms, 2U));
    fake_port_clear(&fx.port);
}

static void no_heartbeat_by_default(void)
{
    ASSERT_FRAME(0, 0x705U, 1, 0x00); /* boot-up only */
    fake_port_clear(&fx.port);
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, fx_process());
}

static void v10_sdo_write_1017_then_7F_every_1000ms(void)
{
    const co_time_us_t t0 = 12345U; /* the period starts at the write, not at a multiple of it */
    fx_run_until(t0);
    fake_port_clear(&fx.port);
    RX(0x605, 0x2B, 0x17, 0x10, 0x00, 0xE8, 0x03, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x585U, 8, 0x60, 0x17, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x1017_producer_hb);
    for (uint32_t k = 1U; k <= 5U; k++) {
        fx_run_until(t0 + k * 1000U * MS - 1U);
        TEST_ASSERT_EQUAL_UINT32(k - 1U, fx_count(0x705U));
        fx_run_until(t0 + k * 1000U * MS);
        TEST_ASSERT_EQUAL_UINT32(k, fx_count(0x705U));
        const uint32_t i = last_idx(0x705U);
        ASSERT_FRAME(i, 0x705U, 1, 0x7F);
        TEST_ASSERT_EQUAL_UINT64(t0 + k * 1000U * MS, fx.port.sent_at[i]);
    }
}

static void period_100ms_exact_window(void)
{
    set_hb_ms(100U);
    fx_run_until(99999U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(100000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x705U, 1, 0x7F);
    TEST_ASSERT_EQUAL_UINT64(100000U, fx.port.sent_at[0]);
    fx_run_until(199999U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(200000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT64(200000U, fx.port.sent_at[1]);
}

static void process_returns_next_heartbeat_deadline(void)
{
    set_hb_ms(100U);
    TEST_ASSERT_EQUAL_UINT64(100000U, fx_process());
    fx.now = 100000U;
    TEST_ASSERT_EQUAL_UINT64(200000U, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
    /* Calling again at the same time sends nothing more. */
    TEST_ASSERT_EQUAL_UINT64(200000U, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
}

/* Heartbeats and frames counted by run_counting() before the recorded ones. */
static uint32_t hb_counted, frames_counted;

/* Runs until the time in steps of 5 s, counting and forgetting the frames of each step: a small target
 * (tests/avr/) records fewer frames than a long run sends. */
static void count_and_forget(void)
{
    hb_counted += heartbeats();
    frames_counted += fx.port.n_sent;
    fake_port_clear(&fx.port);
}

static void run_counting(co_time_us_t until)
{
    count_and_forget();
    while (fx.now + 5000U * MS < until) {
        fx_run_until(fx.now + 5000U * MS);
        count_and_forget();
    }
    fx_run_until(until);
}

static void thousandth_heartbeat_at_100s_despite_late_call(void)
{
    set_hb_ms(100U);
    fx_run_until(4900U * MS); /* heartbeats 1..49 */
    TEST_ASSERT_EQUAL_UINT32(49U, heartbeats());
    /* Heartbeat 50 is due at 5.000 s but the application calls 50 ms late. */
    fx.now = 5050U * MS;
    TEST_ASSERT_EQUAL_UINT64(5100U * MS, fx_process());
    TEST_ASSERT_EQUAL_UINT32(50U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(5050U * MS, fx.port.sent_at[last_idx(0x705U)]);
    fx_run_until(5100U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(50U, heartbeats());
    fx_run_until(5100U * MS); /* back on the grid */
    TEST_ASSERT_EQUAL_UINT32(51U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(5100U * MS, fx.port.sent_at[last_idx(0x705U)]);
    /* A second late call, 99.999 ms late. */
    fx_run_until(7000U * MS);
    fx.now = 7100U * MS + 99999U;
    TEST_ASSERT_EQUAL_UINT64(7200U * MS, fx_process());
    hb_counted = 0U;
    frames_counted = 0U;
    run_counting(100000U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(999U, hb_counted + heartbeats());
    fx_run_until(100000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1000U, hb_counted + heartbeats());
    const uint32_t i = last_idx(0x705U);
    ASSERT_FRAME(i, 0x705U, 1, 0x7F);
    TEST_ASSERT_EQUAL_UINT64(100000U * MS, fx.port.sent_at[i]);
    TEST_ASSERT_EQUAL_UINT32(1000U, frames_counted + fx.port.n_sent); /* nothing else was sent */
}

static void very_late_call_sends_one_and_stays_on_grid(void)
{
    set_hb_ms(100U);
    fx_run_until(200U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, heartbeats());
    fx.now = 530U * MS; /* 300, 400 and 500 ms missed */
    TEST_ASSERT_EQUAL_UINT64(600U * MS, fx_process());
    TEST_ASSERT_EQUAL_UINT32(3U, heartbeats()); /* no burst of catch-up frames */
    fx_run_until(600U * MS);
    TEST_ASSERT_EQUAL_UINT32(4U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(600U * MS, fx.port.sent_at[last_idx(0x705U)]);
}

/* Catch-up arithmetic is 32-bit (no 64-bit division on a Cortex-M0+): a call up to 2^32 µs late stays on the
 * grid; later than that (71 minutes without a call), a new grid starts at the call. (With 32-bit time a call may
 * be at most 2^31 µs late: nothing to test.) */
static void hours_late_call_starts_a_new_grid(void)
{
#if CO_CONFIG_TIME32
    TEST_PASS();
#else
    set_hb_ms(700U);
    fx_run_until(700U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
    fx.now = 700U * MS + 0xFFFFFFFFULL; /* 4294.967295 s late: grid point 6136 (700 ms * 6137) comes next */
    TEST_ASSERT_EQUAL_UINT64(700ULL * MS * 6137U, fx_process());
    TEST_ASSERT_EQUAL_UINT32(2U, heartbeats());
    fx.now = 700ULL * MS * 6137U + 0x100000000ULL + 123U; /* more than 2^32 µs late, off the grid */
    TEST_ASSERT_EQUAL_UINT64(fx.now + 700U * MS, fx_process());
    TEST_ASSERT_EQUAL_UINT32(3U, heartbeats());
    const co_time_us_t grid = fx.now;
    fx_run_until(grid + 700U * MS);
    TEST_ASSERT_EQUAL_UINT32(4U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(grid + 700U * MS, fx.port.sent_at[last_idx(0x705U)]);
#endif
}

static void rewrite_1017_restarts_period_from_write(void)
{
    set_hb_ms(100U);
    fx_run_until(250U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, heartbeats());
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 100U, 2U)); /* same value, at 250 ms */
    fx_run_until(350U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, heartbeats()); /* not at 300 ms */
    fx_run_until(350U * MS);
    TEST_ASSERT_EQUAL_UINT32(3U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(350U * MS, fx.port.sent_at[last_idx(0x705U)]);
    /* A new period at 420 ms: next at 420 + 50 ms, then every 50 ms. */
    fx_run_until(420U * MS);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 50U, 2U));
    fx_run_until(470U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(3U, heartbeats());
    fx_run_until(470U * MS);
    TEST_ASSERT_EQUAL_UINT32(4U, heartbeats());
    fx_run_until(520U * MS);
    TEST_ASSERT_EQUAL_UINT32(5U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(520U * MS, fx.port.sent_at[last_idx(0x705U)]);
}

static void write_sends_no_immediate_heartbeat(void)
{
    fx_run_until(777U);
    fake_port_clear(&fx.port);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 100U, 2U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent); /* the SDO response only */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x705U));
}

static void write_zero_stops_heartbeat(void)
{
    set_hb_ms(100U);
    fx_run_until(150U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 0U, 2U));
    fx_run_until(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, fx_process());
}

static void local_write_restarts_period(void)
{
    fx_run_until(3000U);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x1017, 0, 20U));
    fake_port_clear(&fx.port);
    fx_run_until(23000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, heartbeats());
    fx_run_until(23000U);
    TEST_ASSERT_EQUAL_UINT32(1U, heartbeats());
}

/* #2: Pre-op -> Operational; the heartbeats carry 05. */
static void v02_start_heartbeats_become_05(void)
{
    set_hb_ms(100U);
    fx_run_until(100U * MS);
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x7F);
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    fx_run_until(300U * MS);
    TEST_ASSERT_EQUAL_UINT32(3U, heartbeats());
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x05);
    ASSERT_FRAME(last_idx(0x705U) - 1U, 0x705U, 1, 0x05);
}

/* #3: Operational -> Stopped by broadcast; the heartbeats carry 04 and keep coming in Stopped. */
static void v03_broadcast_stop_heartbeats_become_04(void)
{
    set_hb_ms(100U);
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port); /* entering Operational sent TPDO1 */
    fx_run_until(100U * MS);
    ASSERT_FRAME(0, 0x705U, 1, 0x05);
    RX(0x000, 0x02, 0x00);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_STOPPED, co_node_state(&fx.node));
    fx_run_until(500U * MS);
    TEST_ASSERT_EQUAL_UINT32(5U, fx.port.n_sent);
    for (uint32_t i = 1U; i < 5U; i++) {
        ASSERT_FRAME(i, 0x705U, 1, 0x04);
        TEST_ASSERT_EQUAL_UINT64((i + 1U) * 100U * MS, fx.port.sent_at[i]);
    }
}

/* #4: Stopped -> Pre-operational; the heartbeats carry 7F. */
static void v04_enter_preop_heartbeats_become_7F(void)
{
    set_hb_ms(100U);
    RX(0x000, 0x02, 0x05);
    fx_run_until(100U * MS);
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x04);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    fx_run_until(200U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, heartbeats());
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x7F);
}

static void no_extra_heartbeat_on_state_change(void)
{
    set_hb_ms(100U);
    fx_run_until(50U * MS);
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x705U));
    fx_run_until(100U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x705U));
    fx_run_until(100U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U));
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x05);
    fx_run_until(150U * MS);
    RX(0x000, 0x02, 0x05);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U));
    fx_run_until(200U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x705U));
    ASSERT_FRAME(last_idx(0x705U), 0x705U, 1, 0x7F);
    TEST_ASSERT_EQUAL_UINT64(200U * MS, fx.port.sent_at[last_idx(0x705U)]); /* the grid was not shifted */
}

static void heartbeat_uses_node_id(void)
{
    fx_start(0x7FU, 0U);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x1017, 0, 10U));
    fake_port_clear(&fx.port);
    fx_run_until(10U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x77FU, 1, 0x7F);
}

static void reset_communication_restarts_heartbeat_from_bootup(void)
{
    set_hb_ms(100U);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1010, 1, 0x65766173UL, 4U)); /* store 0x1017 = 100 */
    fx_run_until(1234567U);
    fake_port_clear(&fx.port);
    RX(0x000, 0x82, 0x05);
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(1234567U + 100U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(1234567U + 100U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(1, 0x705U, 1, 0x7F);
}

static void reset_communication_without_stored_period_stops_heartbeat(void)
{
    set_hb_ms(100U);
    fx_run_until(150U * MS);
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    fake_port_clear(&fx.port);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(no_heartbeat_by_default);
    RUN_TEST(v10_sdo_write_1017_then_7F_every_1000ms);
    RUN_TEST(period_100ms_exact_window);
    RUN_TEST(process_returns_next_heartbeat_deadline);
    RUN_TEST(thousandth_heartbeat_at_100s_despite_late_call);
    RUN_TEST(very_late_call_sends_one_and_stays_on_grid);
    RUN_TEST(hours_late_call_starts_a_new_grid);
    RUN_TEST(rewrite_1017_restarts_period_from_write);
    RUN_TEST(write_sends_no_immediate_heartbeat);
    RUN_TEST(write_zero_stops_heartbeat);
    RUN_TEST(local_write_restarts_period);
    RUN_TEST(v02_start_heartbeats_become_05);
    RUN_TEST(v03_broadcast_stop_heartbeats_become_04);
    RUN_TEST(v04_enter_preop_heartbeats_become_7F);
    RUN_TEST(no_extra_heartbeat_on_state_change);
    RUN_TEST(heartbeat_uses_node_id);
    RUN_TEST(reset_communication_restarts_heartbeat_from_bootup);
    RUN_TEST(reset_communication_without_stored_period_stops_heartbeat);
    return UNITY_END();
}
