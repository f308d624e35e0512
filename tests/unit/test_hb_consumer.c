/* Heartbeat consumer 0x1016: monitoring starts with the first heartbeat, timeout -> EMCY 0x8130 with
 * msef {02, node-ID, 0, 0, 0}, the next heartbeat -> error reset, duplicate node-IDs refused
 * (facts §3.2, §11 #54). */
#include "fixture.h"

#define MS ((co_time_us_t)1000U)

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

static uint32_t last_idx(uint32_t id)
{
    const int i = fx_last(id);
    TEST_ASSERT_TRUE_MESSAGE(i >= 0, "no frame with this CAN-ID");
    return (uint32_t)i;
}

static uint32_t hb_timeouts(uint32_t node_id)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        if (fx.events[i].kind == CO_EV_HB_TIMEOUT && fx.events[i].value == node_id) {
            n++;
        }
    }
    return n;
}

static void consume(uint8_t sub, uint32_t v)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, sub, v, 4U));
    fake_port_clear(&fx.port);
}

static void v54_timeout_200ms_after_heartbeat_sends_emcy_8130(void)
{
    consume(1U, 0x000A00C8UL); /* node 10, 200 ms */
    const co_time_us_t t0 = 50U * MS + 7U;
    fx_run_until(t0);
    RX(0x70A, 0x05);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t0 + 200U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(0U, hb_timeouts(10U));
    fx_run_until(t0 + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t0 + 200U * MS, fx.port.sent_at[0]);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x0A028130UL, fx.values.x1003_errors[0]);
    TEST_ASSERT_EQUAL_UINT32(1U, hb_timeouts(10U));
    /* One report per timeout. */
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(1U, hb_timeouts(10U));
}

static void timeout_event_names_entry_and_node(void)
{
    consume(3U, 0x002200C8UL);
    RX(0x722, 0x7F);
    fx_advance(200U * MS);
    bool seen = false;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        if (fx.events[i].kind == CO_EV_HB_TIMEOUT) {
            TEST_ASSERT_EQUAL_HEX16(0x1016, fx.events[i].index);
            TEST_ASSERT_EQUAL_UINT8(3U, fx.events[i].sub);
            TEST_ASSERT_EQUAL_UINT32(0x22U, fx.events[i].value);
            seen = true;
        }
    }
    TEST_ASSERT_TRUE(seen);
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x22, 0x00, 0x00, 0x00);
}

static void next_heartbeat_sends_error_reset_and_restarts_monitoring(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x05);
    fx_advance(450U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    const co_time_us_t t1 = fx.now;
    RX(0x70A, 0x05);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    const uint32_t i = last_idx(0x085U);
    ASSERT_FRAME(i, 0x085U, 8, 0x00, 0x00, 0x00, 0x02, 0x0A, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t1, fx.port.sent_at[i]);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8130U));
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count); /* the reset is not logged */
    fx_run_until(t1 + 200U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    fx_run_until(t1 + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(3U, fx_count(0x085U));
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
}

static void each_heartbeat_restarts_consumer_time(void)
{
    consume(1U, 0x000A00C8UL);
    co_time_us_t t = 0U;
    for (uint32_t k = 0U; k < 7U; k++) {
        t = 10U * MS + k * 199U * MS;
        fx_run_until(t);
        RX(0x70A, 0x05);
    }
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t + 200U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void no_heartbeat_ever_means_no_timeout(void)
{
    consume(1U, 0x000A00C8UL);
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(0U, hb_timeouts(10U));
}

static void bootup_does_not_start_monitoring(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x00);
    fx_advance(10000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    const co_time_us_t t0 = fx.now;
    RX(0x70A, 0x7F); /* the first heartbeat starts it */
    fx_run_until(t0 + 200U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t0 + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

/* A boot-up from a monitored node means it restarted: monitoring waits for its first heartbeat again
 * (the "first heartbeat" rule applies to every start of the remote node, and co_hb_consumer.c says so). */
static void bootup_while_monitoring_waits_for_first_heartbeat_again(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x05);
    fx_advance(100U * MS);
    RX(0x70A, 0x00); /* the remote node rebooted */
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx_count(0x085U), "timeout reported for a node that only booted");
    const co_time_us_t t0 = fx.now;
    RX(0x70A, 0x7F);
    fx_run_until(t0 + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void wrong_dlc_is_not_a_heartbeat(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x05, 0x00);
    RX0(0x70A);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    /* ... and does not feed a running monitor either. */
    RX(0x70A, 0x05);
    const co_time_us_t t0 = fx.now;
    fx_run_until(t0 + 100U * MS);
    RX(0x70A, 0x05, 0x00);
    fx_run_until(t0 + 200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void unmonitored_node_heartbeat_is_ignored(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70B, 0x05);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void duplicate_node_id_refused_with_06040043(void)
{
    consume(1U, 0x000A00C8UL);
    const uint8_t req[8] = {0x23, 0x16, 0x10, 0x02, 0x64, 0x00, 0x0A, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x80, 0x16, 0x10, 0x02, 0x43, 0x00, 0x04, 0x06};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1016_consumer[1]);
    TEST_ASSERT_EQUAL_HEX32(0x06040043UL, fx_sdo_write_u32(0x1016, 4, 0x000A0001UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1016_consumer[3]);
}

static void same_node_id_allowed_when_unused_or_same_entry(void)
{
    consume(1U, 0x000A00C8UL);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 2, 0x000A0000UL, 4U)); /* time 0: unused */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 1, 0x000A0064UL, 4U)); /* the same entry */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 3, 0x000B0064UL, 4U)); /* another node */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 1, 0x00000000UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 2, 0x000A0064UL, 4U)); /* free again */
    TEST_ASSERT_EQUAL_HEX32(0x000A0064UL, fx.values.x1016_consumer[1]);
}

static void two_nodes_time_out_independently(void)
{
    consume(1U, 0x000A00C8UL); /* node 10, 200 ms */
    consume(2U, 0x000B012CUL); /* node 11, 300 ms */
    RX(0x70A, 0x05);
    RX(0x70B, 0x05);
    fx_run_until(200U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
    fx_run_until(300U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(300U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(1, 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x0B, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(300U * MS, fx.port.sent_at[1]);
    TEST_ASSERT_EQUAL_UINT8(2U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x0B028130UL, fx.values.x1003_errors[0]);
    TEST_ASSERT_EQUAL_HEX32(0x0A028130UL, fx.values.x1003_errors[1]);
    /* Node 10 is back: error reset with the register of what remains (node 11 still missing). */
    RX(0x70A, 0x05);
    ASSERT_FRAME(2, 0x085U, 8, 0x00, 0x00, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8130U));
    RX(0x70B, 0x05);
    ASSERT_FRAME(3, 0x085U, 8, 0x00, 0x00, 0x00, 0x02, 0x0B, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8130U));
}

static void process_returns_consumer_deadline(void)
{
    consume(1U, 0x000A00C8UL);
    fx_run_until(1000U);
    RX(0x70A, 0x05);
    TEST_ASSERT_EQUAL_UINT64(1000U + 200U * MS, fx_process());
}

static void rewriting_entry_restarts_waiting_for_first_heartbeat(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x05);
    fx_advance(100U * MS);
    consume(1U, 0x000A00C8UL);
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void disabling_timed_out_entry_clears_its_error(void)
{
    consume(1U, 0x000A00C8UL);
    RX(0x70A, 0x05);
    fx_advance(200U * MS);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    fake_port_clear(&fx.port);
    RX(0x605, 0x23, 0x16, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00); /* 0x1016:01 = 0 */
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME((uint32_t)fx_last(0x585U), 0x585U, 8, 0x60, 0x16, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00);
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x00, 0x00, 0x00, 0x02, 0x0A, 0x00, 0x00, 0x00);
    fake_port_clear(&fx.port);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    RX(0x70A, 0x05);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* no longer monitored */
}

static void reset_communication_forgets_monitoring(void)
{
    consume(1U, 0x000A00C8UL);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1010, 1, 0x65766173UL, 4U)); /* keep 0x1016 */
    RX(0x70A, 0x05);
    fx_advance(100U * MS);
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_HEX32(0x000A00C8UL, fx.values.x1016_consumer[0]);
    fake_port_clear(&fx.port);
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

/* Only the last entry in use, for node 127 (the last bit of the monitored set); then the same entry moved to
 * node 9: the heartbeat of 127 is then ignored and that of 9 monitored. rx/process skip unused entries. */
static void last_entry_and_highest_node_id_are_monitored(void)
{
    consume(4U, 0x007F0064UL); /* entry 4: node 127, 100 ms */
    RX(0x77F, 0x05);
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &(co_frame_t){0x77FU, 1U, 0U, {0x05U}}, fx.now));
    fx_advance(100U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, hb_timeouts(127U));
    ASSERT_FRAME(0, 0x085U, 8, 0x30, 0x81, 0x11, 0x02, 0x7F, 0x00, 0x00, 0x00);
    RX(0x77F, 0x05); /* 127 is back: error reset */
    fake_port_clear(&fx.port);
    consume(4U, 0x00090064UL); /* entry 4: node 9 */
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &(co_frame_t){0x77FU, 1U, 0U, {0x05U}}, fx.now));
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &(co_frame_t){0x709U, 1U, 0U, {0x05U}}, fx.now));
    fx_advance(100U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, hb_timeouts(127U));
    TEST_ASSERT_EQUAL_UINT32(1U, hb_timeouts(9U));
    RX(0x709, 0x05); /* 9 is back: error reset */
    fake_port_clear(&fx.port);
    consume(4U, 0U); /* unused again: nothing is monitored */
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &(co_frame_t){0x709U, 1U, 0U, {0x05U}}, fx.now));
    TEST_ASSERT_EQUAL_UINT8(0U, fx.node.hbc.used);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v54_timeout_200ms_after_heartbeat_sends_emcy_8130);
    RUN_TEST(timeout_event_names_entry_and_node);
    RUN_TEST(next_heartbeat_sends_error_reset_and_restarts_monitoring);
    RUN_TEST(each_heartbeat_restarts_consumer_time);
    RUN_TEST(no_heartbeat_ever_means_no_timeout);
    RUN_TEST(bootup_does_not_start_monitoring);
    RUN_TEST(bootup_while_monitoring_waits_for_first_heartbeat_again);
    RUN_TEST(wrong_dlc_is_not_a_heartbeat);
    RUN_TEST(unmonitored_node_heartbeat_is_ignored);
    RUN_TEST(duplicate_node_id_refused_with_06040043);
    RUN_TEST(same_node_id_allowed_when_unused_or_same_entry);
    RUN_TEST(two_nodes_time_out_independently);
    RUN_TEST(process_returns_consumer_deadline);
    RUN_TEST(rewriting_entry_restarts_waiting_for_first_heartbeat);
    RUN_TEST(disabling_timed_out_entry_clears_its_error);
    RUN_TEST(reset_communication_forgets_monitoring);
    RUN_TEST(last_entry_and_highest_node_id_are_monitored);
    return UNITY_END();
}
