/* Frame routing by COB-ID (co_node_rx_ids, CO_EV_RX_FILTER), and the processing pass that runs only what changed
 * (co_node_process's early return, co_node_settled, co_node_values_changed, co_od_changed). */
#include "fixture.h"

void setUp(void) { fx_start(5U, 0U); }
void tearDown(void) {}

static uint16_t ids[300];

static uint16_t rx_ids(void) { return co_node_rx_ids(&fx.node, ids, (uint16_t)(sizeof ids / sizeof ids[0])); }

static uint32_t filter_events(void)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        n += fx.events[i].kind == CO_EV_RX_FILTER ? 1U : 0U;
    }
    return n;
}

static void rx_ids_are_the_services_cob_ids_sorted(void)
{
    /* NMT, SYNC 0x080, TPDO1's remote request 0x185 (type 255, RTR allowed; TPDO2 is not valid), RPDO1 0x205 (RPDO2
     * is not valid), SDO 0x605, the guard request 0x705, LSS 0x7E5 */
    TEST_ASSERT_EQUAL_UINT16(7U, rx_ids());
    const uint16_t want[7] = {0x000U, 0x080U, 0x185U, 0x205U, 0x605U, 0x705U, 0x7E5U};
    TEST_ASSERT_EQUAL_HEX16_ARRAY(want, ids, 7);
    uint16_t few[2] = {0xFFFFU, 0xFFFFU};
    TEST_ASSERT_EQUAL_UINT16(7U, co_node_rx_ids(&fx.node, few, 1U)); /* the count, however few are written */
    TEST_ASSERT_EQUAL_HEX16(0x000U, few[0]);
    TEST_ASSERT_EQUAL_HEX16(0xFFFFU, few[1]);
}

static void every_other_frame_is_ignored_and_every_listed_one_taken(void)
{
    const uint16_t n = rx_ids();
    uint16_t k = 0U;
    for (uint32_t id = 0U; id <= 0x7FFU; id++) {
        const bool listed = k < n && ids[k] == id;
        k = (uint16_t)(k + (listed ? 1U : 0U));
        const co_frame_t data = {id, 8U, 0U, {0U}};
        const co_frame_t remote = {id, 0U, CO_FRAME_RTR, {0U}};
        const bool taken = co_node_rx(&fx.node, &data, fx.now) || co_node_rx(&fx.node, &remote, fx.now);
        if (taken != listed) {
            TEST_FAIL_MESSAGE(listed ? "a listed COB-ID was ignored" : "a COB-ID not listed was taken");
        }
        (void)fx_process();
    }
    const co_frame_t extended = {0x605U, 8U, CO_FRAME_EFF, {0x40U, 0x00U, 0x10U}};
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &extended, fx.now));
}

static void the_list_follows_the_configuration(void)
{
    fx.n_events = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1016, 2, 0x00070064UL, 4U)); /* monitor node 7, 100 ms */
    TEST_ASSERT_EQUAL_UINT32(1U, filter_events());
    TEST_ASSERT_EQUAL_UINT16(8U, rx_ids());
    TEST_ASSERT_EQUAL_HEX16(0x707U, ids[6]);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1005, 0, 0x00000090UL, 4U)); /* SYNC on 0x090 */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1400, 1, 0x80000205UL, 4U)); /* RPDO1 not valid */
    TEST_ASSERT_EQUAL_UINT32(3U, filter_events());
    const uint16_t want[7] = {0x000U, 0x090U, 0x185U, 0x605U, 0x705U, 0x707U, 0x7E5U};
    TEST_ASSERT_EQUAL_UINT16(7U, rx_ids());
    TEST_ASSERT_EQUAL_HEX16_ARRAY(want, ids, 7);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1400, 2, 254U, 1U)); /* no COB-ID changed: no event */
    TEST_ASSERT_EQUAL_UINT32(3U, filter_events());
    fx_rx_rtr(0x000U); /* a remote frame on an NMT COB-ID is no command */
    RX(0x000, 0x82, 0x05);  /* reset communication: the defaults again */
    TEST_ASSERT_EQUAL_UINT16(7U, rx_ids());
    TEST_ASSERT_EQUAL_HEX16(0x080U, ids[1]);
}

static void a_sync_cob_id_shared_with_an_rpdo_stays_sync(void)
{
    /* Before the table, SYNC was tested before the PDOs: a COB-ID both use is SYNC's. */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1400, 1, 0x80000205UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1400, 1, 0x00000080UL, 4U));
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port);
    RX0(0x080); /* a SYNC of DLC 0: no RPDO length error (which would be EMCY 0x8210) */
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8210U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    TEST_ASSERT_EQUAL_UINT16(6U, rx_ids()); /* one entry for 0x080 */
}

static void a_pass_with_nothing_new_returns_the_same_deadline_and_sends_nothing(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1017, 0, 100U, 2U));
    fake_port_clear(&fx.port);
    const co_time_us_t due = fx_process();
    TEST_ASSERT_EQUAL_UINT64(fx.now + 100000U, due);
    for (int i = 0; i < 5; i++) {
        fx.now += 10000U;
        TEST_ASSERT_EQUAL_UINT64(due, fx_process());
    }
    const co_frame_t other = {0x606U, 8U, 0U, {0x40U, 0x00U, 0x10U}};
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &other, fx.now));
    TEST_ASSERT_EQUAL_UINT64(due, fx_process());
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_advance(due - fx.now);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U)); /* the heartbeat at its deadline, not before */
    TEST_ASSERT_EQUAL_UINT64(due, fx.port.sent_at[0]);
}

/* co_node_settled: after an expedited SDO request answered inside co_node_rx the node is settled on the deadline its
 * pass last returned (a runner of many nodes then skips the pass); not after a request that left something for the
 * pass: a transfer begun, an answer queued, a deadline moved forward. Each settled case is checked the way a runner
 * relies on it: the pass finds nothing (no frame, the same deadline). */
static void an_sdo_request_answered_at_once_leaves_the_node_settled(void)
{
    co_time_us_t due = fx_process();
    TEST_ASSERT_TRUE(co_node_settled(&fx.node, due));
    TEST_ASSERT_FALSE(co_node_settled(&fx.node, due + 1U)); /* not the deadline the pass gave */
    const co_frame_t upload = {0x605U, 8U, 0U, {0x40U, 0x00U, 0x10U, 0x00U}};
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &upload, fx.now));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x585U)); /* answered */
    TEST_ASSERT_TRUE(co_node_settled(&fx.node, due));
    TEST_ASSERT_EQUAL_UINT64(due, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    /* 0x1017 = 100 ms: the heartbeat's deadline comes before the one the runner has */
    const co_frame_t hb = {0x605U, 8U, 0U, {0x2BU, 0x17U, 0x10U, 0x00U, 100U, 0x00U}};
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &hb, fx.now));
    TEST_ASSERT_FALSE(co_node_settled(&fx.node, due));
    due = fx_process();
    TEST_ASSERT_EQUAL_UINT64(fx.now + 100000U, due);
    /* the same value again 10 ms later: the heartbeat keeps its deadline, nothing new for the pass */
    fx.now += 10000U;
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &hb, fx.now));
    TEST_ASSERT_TRUE(co_node_settled(&fx.node, due));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x585U));
    TEST_ASSERT_EQUAL_UINT64(due, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    /* a refused request (no such object) is answered whole too */
    const co_frame_t missing = {0x605U, 8U, 0U, {0x40U, 0x34U, 0x12U, 0x00U}};
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &missing, fx.now));
    TEST_ASSERT_TRUE(co_node_settled(&fx.node, due));
    TEST_ASSERT_EQUAL_HEX8(0x80U, fx.port.sent[1].data[0]);
    /* the answer queued behind a busy port: the pass sends it */
    fx.port.busy_count = 1U;
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &upload, fx.now));
    TEST_ASSERT_FALSE(co_node_settled(&fx.node, due));
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x585U) - 1U);
    /* an NMT command that changes the state marks every service; one that keeps it changes nothing */
    due = fx_process();
    const co_frame_t preop = {0x000U, 2U, 0U, {0x80U, 0x05U}}, start = {0x000U, 2U, 0U, {0x01U, 0x05U}};
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &preop, fx.now));
    TEST_ASSERT_TRUE(co_node_settled(&fx.node, due));
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &start, fx.now));
    TEST_ASSERT_FALSE(co_node_settled(&fx.node, due));
}

static void a_segmented_transfer_begun_leaves_work_for_the_pass(void)
{
    fx_start(5U, CO_OPT_SDO_SEGMENTED);
    const co_time_us_t due = fx_process();
    const co_frame_t name = {0x605U, 8U, 0U, {0x40U, 0x09U, 0x10U, 0x00U}}; /* 0x1009: longer than 4 bytes */
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &name, fx.now));
    TEST_ASSERT_EQUAL_HEX8(0x41U, fx.port.sent[0].data[0]); /* segmented upload initiated */
    TEST_ASSERT_FALSE(co_node_settled(&fx.node, due));
    TEST_ASSERT_EQUAL_UINT64(fx.now + CO_SDO_TIMEOUT_US, fx_process()); /* the transfer's timeout */
}

static void a_value_written_around_the_api_is_seen_only_when_told(void)
{
    RX(0x000, 0x01, 0x05); /* TPDO1 (0x1001, change of state) goes out once on entering Operational */
    fake_port_clear(&fx.port);
    fx.values.x1001_error_register = 0x21U; /* written directly, as a device model does */
    fx_advance(1000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U)); /* the core was not told */
    co_node_values_changed(&fx.node);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    ASSERT_FRAME((uint32_t)fx_last(0x185U), 0x185U, 1, 0x21);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u8(&fx.node, 0x1001U, 0U, 0x22U)); /* through the API: seen */
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    ASSERT_FRAME((uint32_t)fx_last(0x185U), 0x185U, 1, 0x22);
}

static void a_communication_parameter_written_around_the_api_takes_effect_when_told(void)
{
    fake_port_clear(&fx.port);
    fx.values.x1017_producer_hb = 20U; /* through co_od_value's pointer or the values struct */
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x705U));
    co_od_changed(&fx.node, 0x1017U, 0U); /* a new period starts now */
    const co_time_us_t start = fx.now;
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(5U, fx_count(0x705U));
    TEST_ASSERT_EQUAL_UINT64(start + 20000U, fx.port.sent_at[0]);
    co_od_changed(&fx.node, 0x7777U, 9U); /* no such object: nothing */
    fx.values.x1005_cob_id_sync = 0x91UL;
    co_od_changed(&fx.node, 0x1005U, 0U);
    TEST_ASSERT_EQUAL_UINT16(7U, rx_ids());
    TEST_ASSERT_EQUAL_HEX16(0x091U, ids[1]);
}

static void a_timer_restarted_by_a_frame_keeps_its_deadline(void)
{
    /* RPDO1 with an event timer of 50 ms: each RPDO restarts the reception monitoring without a processing pass of
     * the PDOs. The deadline returned may be the earlier one (a pass then finds nothing due and returns the new one):
     * it is never later than the monitoring's. */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1400, 5, 50U, 2U));
    RX(0x000, 0x01, 0x05);
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    TEST_ASSERT_EQUAL_UINT64(fx.now + 50000U, fx_process());
    fx_advance(30000U);
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    const co_time_us_t restarted = fx.now;
    TEST_ASSERT_TRUE(fx_process() <= restarted + 50000U);
    fx_advance(20000U);
    TEST_ASSERT_EQUAL_UINT64(restarted + 50000U, fx_process()); /* after the early pass: the true deadline */
    fx_advance(29999U);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8250U));
    fx_advance(1U);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8250U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(rx_ids_are_the_services_cob_ids_sorted);
    RUN_TEST(every_other_frame_is_ignored_and_every_listed_one_taken);
    RUN_TEST(the_list_follows_the_configuration);
    RUN_TEST(a_sync_cob_id_shared_with_an_rpdo_stays_sync);
    RUN_TEST(a_pass_with_nothing_new_returns_the_same_deadline_and_sends_nothing);
    RUN_TEST(an_sdo_request_answered_at_once_leaves_the_node_settled);
    RUN_TEST(a_segmented_transfer_begun_leaves_work_for_the_pass);
    RUN_TEST(a_value_written_around_the_api_is_seen_only_when_told);
    RUN_TEST(a_communication_parameter_written_around_the_api_takes_effect_when_told);
    RUN_TEST(a_timer_restarted_by_a_frame_keeps_its_deadline);
    return UNITY_END();
}
