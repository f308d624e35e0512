/* NMT slave: commands, boot-up, resets, DLC handling, and the state x service matrix (facts §2, §11 #1-#9). */
#include "fixture.h"

void setUp(void) { fx_start(5U, 0U); }
void tearDown(void) {}

static uint8_t hb_state_after_period(void)
{
    /* 0x1017 = 100 ms; the next heartbeat carries the state. */
    const uint32_t before = fx.port.n_sent;
    fx_advance(100000U);
    TEST_ASSERT_TRUE(fx.port.n_sent > before);
    const int i = fx_last(0x705U);
    TEST_ASSERT_TRUE(i >= (int)before);
    return fx.port.sent[i].data[0];
}

static void v01_power_on_sends_bootup(void)
{
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_INITIALISING, fx.last_from);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, fx.last_to);
}

static void v02_v03_v04_commands_seen_in_heartbeat(void)
{
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 100U, 2U));
    TEST_ASSERT_EQUAL_HEX8(0x7F, hb_state_after_period());
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_HEX8(0x05, hb_state_after_period());
    RX(0x000, 0x02, 0x00); /* broadcast */
    TEST_ASSERT_EQUAL_HEX8(0x04, hb_state_after_period());
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_HEX8(0x7F, hb_state_after_period());
    RX(0x000, 0x02, 0x05);
    RX(0x000, 0x01, 0x05); /* Stopped -> Operational */
    TEST_ASSERT_EQUAL_HEX8(0x05, hb_state_after_period());
}

static void v05_other_node_ignored(void)
{
    fake_port_clear(&fx.port);
    RX(0x000, 0x01, 0x06);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void v06_v07_wrong_dlc_ignored(void)
{
    fake_port_clear(&fx.port);
    RX(0x000, 0x01);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    RX(0x000, 0x01, 0x05, 0x00);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    RX(0x000, 0x01, 0x05, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void long_frames_accepted_with_option(void)
{
    fx_start(5U, CO_OPT_NMT_ACCEPT_LONG);
    RX(0x000, 0x01, 0x05, 0, 0, 0, 0, 0, 0); /* the Eltex manuals draw 8-byte NMT frames */
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    RX(0x000, 0x02);                          /* DLC 1 stays ignored */
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
}

static void unknown_command_and_rtr_ignored(void)
{
    RX(0x000, 0x03, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    const co_frame_t rtr = {0x000U, 2U, CO_FRAME_RTR, {0x01U, 0x05U}};
    co_node_rx(&fx.node, &rtr, fx.now);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    const co_frame_t ext = {0x000U, 2U, CO_FRAME_EFF, {0x01U, 0x05U}};
    co_node_rx(&fx.node, &ext, fx.now);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
}

static void same_state_command_is_noop(void)
{
    const uint32_t changes = fx.nmt_changes;
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(changes, fx.nmt_changes);
}

static void v08_reset_communication(void)
{
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port);
    RX(0x000, 0x82, 0x05);
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.resets_app - 1U); /* only the power-on application reset */
    TEST_ASSERT_EQUAL_UINT32(2U, fx.resets_comm);
}

static void v09_reset_node_broadcast(void)
{
    fake_port_clear(&fx.port);
    RX(0x000, 0x81, 0x00);
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.resets_app);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.resets_comm);
}

static void reset_comm_reinitialises_only_the_communication_area(void)
{
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 300U, 2U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x2000, 0, 1000U, 2U));
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
}

static void resets_restore_stored_values_not_defaults(void)
{
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 300U, 2U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x2000, 0, 1000U, 2U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1010, 1, 0x65766173UL, 4U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 400U, 2U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x2000, 0, 2000U, 2U));
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(2000U, fx.values.x2000_cycle_ms);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
}

/* Facts §2.4: which services answer in which state. One row per state. */
typedef struct services_seen {
    bool sdo, heartbeat, guard, emcy, sync_consumed, tpdo, rpdo_applied, lss;
} services_seen_t;

static services_seen_t probe_services(void)
{
    services_seen_t s;
    uint32_t n;
    /* SDO */
    n = fx.port.n_sent;
    RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    s.sdo = fx_count(0x585U) > 0U && fx.port.n_sent > n;
    /* Heartbeat (0x1017 set directly: the SDO may be silent) */
    fx.values.x1017_producer_hb = 10U;
    co_od_changed(&fx.node, 0x1017U, 0U); /* a new period starts now */
    fake_port_clear(&fx.port);
    RX(0x000, 0x7F, 0x7F); /* nothing: unknown command */
    fx_advance(10000U);
    s.heartbeat = fx_count(0x705U) == 1U;
    fx.values.x1017_producer_hb = 0U;
    co_od_changed(&fx.node, 0x1017U, 0U);
    /* Node guarding */
    fake_port_clear(&fx.port);
    fx_rx_rtr(0x705U);
    s.guard = fx_count(0x705U) == 1U;
    /* EMCY */
    fake_port_clear(&fx.port);
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL);
    (void)fx_process();
    s.emcy = fx_count(0x085U) == 1U;
    (void)co_emcy_clear(&fx.node, 0x5000U, NULL);
    /* SYNC: with 0x1019 = 0 a SYNC of DLC 1 raises EMCY 0x8240 when SYNC is consumed */
    fake_port_clear(&fx.port);
    RX(0x080, 0x01);
    (void)fx_process();
    s.sync_consumed = co_emcy_is_active(&fx.node, 0x8240U);
    RX0(0x080); /* a good SYNC clears it again where consumed */
    /* TPDO: entering Operational sends TPDO1 at once; elsewhere nothing on 0x185 */
    fake_port_clear(&fx.port);
    fx.values.x1001_error_register ^= 0x80U; /* a change of the mapped value */
    co_node_values_changed(&fx.node);
    (void)fx_process();
    s.tpdo = fx_count(0x185U) > 0U;
    /* RPDO */
    fx.values.x6300_value = 0U;
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    s.rpdo_applied = fx.values.x6300_value == 0x44332211UL;
    /* LSS: switch to configuration, inquire node-ID, back to waiting */
    fake_port_clear(&fx.port);
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x5E, 0, 0, 0, 0, 0, 0, 0);
    s.lss = fx_count(0x7E4U) == 1U;
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    return s;
}

static void state_service_matrix(void)
{
    services_seen_t s = probe_services(); /* Pre-operational */
    TEST_ASSERT_TRUE(s.sdo);
    TEST_ASSERT_TRUE(s.heartbeat);
    TEST_ASSERT_TRUE(s.guard);
    TEST_ASSERT_TRUE(s.emcy);
    TEST_ASSERT_TRUE(s.sync_consumed);
    TEST_ASSERT_FALSE(s.tpdo);
    TEST_ASSERT_FALSE(s.rpdo_applied);
    TEST_ASSERT_TRUE(s.lss);

    RX(0x000, 0x01, 0x05);
    s = probe_services(); /* Operational */
    TEST_ASSERT_TRUE(s.sdo);
    TEST_ASSERT_TRUE(s.heartbeat);
    TEST_ASSERT_TRUE(s.guard);
    TEST_ASSERT_TRUE(s.emcy);
    TEST_ASSERT_TRUE(s.sync_consumed);
    TEST_ASSERT_TRUE(s.tpdo);
    TEST_ASSERT_TRUE(s.rpdo_applied);
    TEST_ASSERT_TRUE(s.lss);

    RX(0x000, 0x02, 0x05);
    s = probe_services(); /* Stopped */
    TEST_ASSERT_FALSE(s.sdo);
    TEST_ASSERT_TRUE(s.heartbeat);
    TEST_ASSERT_TRUE(s.guard);
    TEST_ASSERT_FALSE(s.emcy);
    TEST_ASSERT_FALSE(s.sync_consumed);
    TEST_ASSERT_FALSE(s.tpdo);
    TEST_ASSERT_FALSE(s.rpdo_applied);
    TEST_ASSERT_TRUE(s.lss);
}

static void emcy_raised_in_stopped_is_sent_on_leaving_it(void)
{
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME(0, 0x085U, 8, 0x00, 0x50, 0x01, 0, 0, 0, 0, 0);
}

/* co_node_rx tells a runner with many nodes on one bus which frames concerned the node (it then processes
 * that node) and which it ignored (the node's last deadline still holds). */
static bool rx_concerns(uint32_t id, uint8_t len, uint8_t flags)
{
    co_frame_t f = {id, len, flags, {0x01U, 0x00U, 0x10U, 0x00U, 0U, 0U, 0U, 0U}};
    return co_node_rx(&fx.node, &f, fx.now);
}

static void rx_reports_whether_the_frame_concerned_the_node(void)
{
    /* Pre-operational, node 5 */
    TEST_ASSERT_TRUE(rx_concerns(0x605U, 8U, 0U));            /* its SDO request */
    TEST_ASSERT_FALSE(rx_concerns(0x606U, 8U, 0U));           /* another node's */
    TEST_ASSERT_FALSE(rx_concerns(0x585U, 8U, 0U));           /* an SDO response */
    TEST_ASSERT_TRUE(rx_concerns(0x080U, 0U, 0U));            /* SYNC */
    TEST_ASSERT_TRUE(rx_concerns(0x7E5U, 8U, 0U));            /* LSS */
    TEST_ASSERT_TRUE(rx_concerns(0x705U, 0U, CO_FRAME_RTR));  /* its node-guarding request */
    TEST_ASSERT_FALSE(rx_concerns(0x706U, 0U, CO_FRAME_RTR));
    TEST_ASSERT_FALSE(rx_concerns(0x000U, 0U, CO_FRAME_RTR)); /* an RTR on the NMT COB-ID */
    TEST_ASSERT_FALSE(rx_concerns(0x707U, 1U, 0U));           /* a heartbeat nobody consumes */
    TEST_ASSERT_FALSE(rx_concerns(0x605U, 8U, CO_FRAME_EFF)); /* 29-bit */
    TEST_ASSERT_FALSE(rx_concerns(0x605U, 8U, CO_FRAME_ERR)); /* error frame */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1016, 1, 0x00070100UL, 4U)); /* consume node 7, 256 ms */
    TEST_ASSERT_TRUE(rx_concerns(0x707U, 1U, 0U));
    /* Operational: its RPDO1 (0x205) counts, the disabled RPDO2 (0x305) does not */
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_TRUE(rx_concerns(0x205U, 4U, 0U));
    TEST_ASSERT_FALSE(rx_concerns(0x305U, 4U, 0U));
    /* Stopped: its frames still count (the services decide to stay silent), other nodes' do not */
    RX(0x000, 0x02, 0x05);
    const uint32_t sent = fx.port.n_sent;
    TEST_ASSERT_TRUE(rx_concerns(0x605U, 8U, 0U));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(sent, fx.port.n_sent); /* ... silent in Stopped */
    TEST_ASSERT_FALSE(rx_concerns(0x606U, 8U, 0U));
    TEST_ASSERT_TRUE(rx_concerns(0x7E5U, 8U, 0U));
    TEST_ASSERT_TRUE(rx_concerns(0x000U, 2U, 0U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v01_power_on_sends_bootup);
    RUN_TEST(v02_v03_v04_commands_seen_in_heartbeat);
    RUN_TEST(v05_other_node_ignored);
    RUN_TEST(v06_v07_wrong_dlc_ignored);
    RUN_TEST(long_frames_accepted_with_option);
    RUN_TEST(unknown_command_and_rtr_ignored);
    RUN_TEST(same_state_command_is_noop);
    RUN_TEST(v08_reset_communication);
    RUN_TEST(v09_reset_node_broadcast);
    RUN_TEST(reset_comm_reinitialises_only_the_communication_area);
    RUN_TEST(resets_restore_stored_values_not_defaults);
    RUN_TEST(state_service_matrix);
    RUN_TEST(emcy_raised_in_stopped_is_sent_on_leaving_it);
    RUN_TEST(rx_reports_whether_the_frame_concerned_the_node);
    return UNITY_END();
}
