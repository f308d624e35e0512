/* Node guarding and life guarding, slave side: 0x100C/0x100D, toggle bit, EMCY 0x8130 msef {01 ..},
 * disabled while the heartbeat producer runs (facts §3.3, §11 #12-#17). */
#include "fixture.h"

#define MS ((co_time_us_t)1000U)

/* #12 precondition: HB = 0, guard time 100 ms, life time factor 3, Pre-operational. */
void setUp(void)
{
    fx_start(5U, 0U);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 100U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 3U, 1U));
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

static uint32_t last_idx(uint32_t id)
{
    const int i = fx_last(id);
    TEST_ASSERT_TRUE_MESSAGE(i >= 0, "no frame with this CAN-ID");
    return (uint32_t)i;
}

/* Sends a guard request and checks that exactly one guard reply with this byte came back at once. */
static void guard(uint8_t expect)
{
    const uint32_t before = fx_count(0x705U);
    fx_rx_rtr(0x705U);
    TEST_ASSERT_EQUAL_UINT32(before + 1U, fx_count(0x705U));
    const uint32_t i = last_idx(0x705U);
    ASSERT_FRAME(i, 0x705U, 1, expect);
    TEST_ASSERT_EQUAL_UINT64(fx.now, fx.port.sent_at[i]);
}

static uint32_t guard_timeouts(void)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        if (fx.events[i].kind == CO_EV_GUARD_TIMEOUT) {
            n++;
        }
    }
    return n;
}

static void v12_first_reply_after_reset_is_7F(void)
{
    guard(0x7F);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
}

static void v13_second_reply_toggles_to_FF(void)
{
    guard(0x7F);
    guard(0xFF);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
}

static void v14_operational_reply_05(void)
{
    guard(0x7F);
    guard(0xFF);
    RX(0x000, 0x01, 0x05);
    guard(0x05);
}

static void v15_stopped_reply_84(void)
{
    guard(0x7F);
    guard(0xFF);
    RX(0x000, 0x01, 0x05);
    guard(0x05);
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    fx_rx_rtr(0x705U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x705U, 1, 0x84);
}

static void toggle_sequence_7F_FF_05_84(void)
{
    fx_rx_rtr(0x705U);
    fx_rx_rtr(0x705U);
    RX(0x000, 0x01, 0x05);
    fx_rx_rtr(0x705U);
    RX(0x000, 0x02, 0x05);
    fx_rx_rtr(0x705U);
    fx_rx_rtr(0x705U);
    TEST_ASSERT_EQUAL_UINT32(5U, fx_count(0x705U));
    const uint8_t expect[5] = {0x7F, 0xFF, 0x05, 0x84, 0x04};
    uint32_t k = 0U;
    for (uint32_t i = 0U; i < fx.port.n_sent; i++) {
        if (fx.port.sent[i].id == 0x705U) {
            TEST_ASSERT_EQUAL_UINT8(1U, fx.port.sent[i].len);
            TEST_ASSERT_EQUAL_HEX8(expect[k], fx.port.sent[i].data[0]);
            k++;
        }
    }
}

static void v16_life_guarding_emcy_at_exactly_300ms_after_last_rtr(void)
{
    const co_time_us_t t0 = 1234U;
    fx_run_until(t0);
    guard(0x7F);
    fx_run_until(t0 + 300U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT32(0U, guard_timeouts());
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    fx_run_until(t0 + 300U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    const uint32_t i = last_idx(0x085U);
    ASSERT_FRAME(i, 0x085U, 8, 0x30, 0x81, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t0 + 300U * MS, fx.port.sent_at[i]);
    TEST_ASSERT_EQUAL_UINT32(1U, guard_timeouts());
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8130U));
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x00018130UL, fx.values.x1003_errors[0]);
    /* One event only, however long the silence lasts. */
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT32(1U, guard_timeouts());
}

static void next_rtr_clears_life_guarding_error(void)
{
    guard(0x7F);
    fx_advance(400U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    const co_time_us_t t1 = fx.now;
    guard(0xFF);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    const uint32_t i = last_idx(0x085U);
    ASSERT_FRAME(i, 0x085U, 8, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t1, fx.port.sent_at[i]);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8130U));
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count); /* the error reset is not logged */
    /* Life guarding runs again from this request. */
    fx_run_until(t1 + 300U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    fx_run_until(t1 + 300U * MS);
    TEST_ASSERT_EQUAL_UINT32(3U, fx_count(0x085U));
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x30, 0x81, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00);
}

static void each_rtr_restarts_node_life_time(void)
{
    guard(0x7F);
    fx_run_until(250U * MS);
    guard(0xFF);
    fx_run_until(500U * MS);
    guard(0x7F);
    fx_run_until(800U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    fx_run_until(800U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT64(800U * MS, fx.port.sent_at[last_idx(0x085U)]);
}

static void no_life_guarding_before_first_rtr(void)
{
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(0U, guard_timeouts());
}

static void life_time_zero_replies_without_life_guarding(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 0U, 1U));
    fake_port_clear(&fx.port);
    guard(0x7F);
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 3U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 0U, 2U));
    fake_port_clear(&fx.port);
    guard(0xFF);
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
}

static void life_time_uses_current_guard_time_and_factor(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100C, 0, 250U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x100D, 0, 4U, 1U));
    fake_port_clear(&fx.port);
    guard(0x7F);
    fx_run_until(1000U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    fx_run_until(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void v17_heartbeat_on_disables_guarding(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 1000U, 2U));
    fake_port_clear(&fx.port);
    fx_rx_rtr(0x705U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    /* Only heartbeats follow: no guard reply, no life guarding. */
    fx_advance(3000U * MS);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(3U, fx_count(0x705U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
}

static void heartbeat_switched_on_stops_running_life_guarding(void)
{
    guard(0x7F);
    fx_run_until(100U * MS);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 1000U, 2U));
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT32(0U, guard_timeouts());
}

static void guarding_answers_again_when_heartbeat_off(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 1000U, 2U));
    fx_rx_rtr(0x705U);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 0U, 2U));
    fake_port_clear(&fx.port);
    guard(0x7F); /* the ignored request did not move the toggle */
    fx_run_until(fx.now + 300U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void reset_communication_restarts_toggle_and_stops_life_guarding(void)
{
    guard(0x7F);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1010, 1, 0x65766173UL, 4U)); /* keep 0x100C/0x100D */
    RX(0x000, 0x82, 0x05);
    fake_port_clear(&fx.port);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* life guarding waits for the first request again */
    guard(0x7F);
    guard(0xFF);
}

static void data_frame_on_guard_id_is_not_a_request(void)
{
    RX(0x705, 0x7F);
    RX0(0x705);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void rtr_for_other_node_is_ignored(void)
{
    fx_rx_rtr(0x706U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void life_guarding_emcy_in_stopped_is_sent_on_leaving_it(void)
{
    RX(0x000, 0x02, 0x05);
    guard(0x04);
    fx_advance(300U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, guard_timeouts());
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x30, 0x81, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v12_first_reply_after_reset_is_7F);
    RUN_TEST(v13_second_reply_toggles_to_FF);
    RUN_TEST(v14_operational_reply_05);
    RUN_TEST(v15_stopped_reply_84);
    RUN_TEST(toggle_sequence_7F_FF_05_84);
    RUN_TEST(v16_life_guarding_emcy_at_exactly_300ms_after_last_rtr);
    RUN_TEST(next_rtr_clears_life_guarding_error);
    RUN_TEST(each_rtr_restarts_node_life_time);
    RUN_TEST(no_life_guarding_before_first_rtr);
    RUN_TEST(life_time_zero_replies_without_life_guarding);
    RUN_TEST(life_time_uses_current_guard_time_and_factor);
    RUN_TEST(v17_heartbeat_on_disables_guarding);
    RUN_TEST(heartbeat_switched_on_stops_running_life_guarding);
    RUN_TEST(guarding_answers_again_when_heartbeat_off);
    RUN_TEST(reset_communication_restarts_toggle_and_stops_life_guarding);
    RUN_TEST(data_frame_on_guard_id_is_not_a_request);
    RUN_TEST(rtr_for_other_node_is_ignored);
    RUN_TEST(life_guarding_emcy_in_stopped_is_sent_on_leaving_it);
    return UNITY_END();
}
