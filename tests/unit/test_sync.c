/* SYNC consumer and synchronous PDOs: 0x1005/0x1006/0x1019 rules, wrong DLC -> EMCY 0x8240, timeout
 * after 1.5 x 0x1006 -> EMCY 0x8100, TPDO types 0 and 1..240, SYNC start value, synchronous RPDOs
 * (facts §5.2, §6, §11 #42, #52, #53). EMCY bytes 3..7 of SYNC errors are not fixed (facts §7.1). */
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

/* Frame i is an EMCY on 0x085 with this error code and error register. */
static void assert_emcy(uint32_t i, uint16_t code, uint8_t reg)
{
    TEST_ASSERT_TRUE_MESSAGE(i < fx.port.n_sent, "frame missing");
    TEST_ASSERT_EQUAL_HEX32(0x085U, fx.port.sent[i].id);
    TEST_ASSERT_EQUAL_UINT8(8U, fx.port.sent[i].len);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)code, fx.port.sent[i].data[0]);
    TEST_ASSERT_EQUAL_HEX8((uint8_t)(code >> 8), fx.port.sent[i].data[1]);
    TEST_ASSERT_EQUAL_HEX8(reg, fx.port.sent[i].data[2]);
}

static void wr(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(index, sub, v, size));
}

static void start(void)
{
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    fake_port_clear(&fx.port);
}

/* TPDO1 (0x185, 0x1001 U8) with transmission type t, then Operational. */
static void tpdo1_type_and_start(uint8_t t)
{
    wr(0x1800, 2, t, 1U);
    start();
}

static void sync_at(co_time_us_t t)
{
    fx_run_until(t);
    RX0(0x080);
}

static void v52_type2_sent_after_2nd_and_4th_sync(void)
{
    tpdo1_type_and_start(2U);
    const uint32_t expect[4] = {0U, 1U, 1U, 2U};
    for (uint32_t k = 0U; k < 4U; k++) {
        sync_at((k + 1U) * 10U * MS);
        TEST_ASSERT_EQUAL_UINT32(expect[k], fx_count(0x185U));
    }
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x185U, 1, 0x00);
    ASSERT_FRAME(1, 0x185U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT64(20U * MS, fx.port.sent_at[0]);
    TEST_ASSERT_EQUAL_UINT64(40U * MS, fx.port.sent_at[1]);
    /* Nothing between SYNCs. */
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
}

static void type1_every_sync_type3_every_third(void)
{
    tpdo1_type_and_start(1U);
    for (uint32_t k = 1U; k <= 5U; k++) {
        sync_at(k * MS);
        TEST_ASSERT_EQUAL_UINT32(k, fx_count(0x185U));
    }
    fx_start(5U, 0U);
    tpdo1_type_and_start(3U);
    const uint32_t expect[9] = {0U, 0U, 1U, 1U, 1U, 2U, 2U, 2U, 3U};
    for (uint32_t k = 0U; k < 9U; k++) {
        sync_at(fx.now + MS);
        TEST_ASSERT_EQUAL_UINT32(expect[k], fx_count(0x185U));
    }
}

static void sync_tpdo_carries_value_sampled_at_sync(void)
{
    tpdo1_type_and_start(1U);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x08U, NULL)); /* 0x1001 = 0x09 */
    (void)fx_process();
    fake_port_clear(&fx.port);
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x185U, 1, 0x09);
}

/* 0x1019 = 5: the counter runs 1..5; start value 3, type 2 -> first at counter 3, then every 2nd SYNC. */
static void sync_start_value_first_at_matching_counter(void)
{
    wr(0x1019, 0, 5U, 1U);
    wr(0x1800, 1, 0x80000185UL, 4U);
    wr(0x1800, 6, 3U, 1U);
    wr(0x1800, 2, 2U, 1U);
    wr(0x1800, 1, 0x00000185UL, 4U);
    start();
    const uint8_t counter[9] = {1, 2, 3, 4, 5, 1, 2, 3, 4};
    const uint32_t expect[9] = {0U, 0U, 1U, 1U, 2U, 2U, 3U, 3U, 4U};
    for (uint32_t k = 0U; k < 9U; k++) {
        fx_run_until(fx.now + MS);
        RX(0x080, counter[k]);
        TEST_ASSERT_EQUAL_UINT32(expect[k], fx_count(0x185U));
    }
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U)); /* DLC 1 is right with 0x1019 > 0 */
}

static void sync_start_value_waits_even_when_started_mid_cycle(void)
{
    wr(0x1019, 0, 10U, 1U);
    wr(0x1800, 1, 0x80000185UL, 4U);
    wr(0x1800, 6, 2U, 1U);
    wr(0x1800, 2, 1U, 1U);
    wr(0x1800, 1, 0x00000185UL, 4U);
    start();
    const uint8_t counter[5] = {7, 8, 9, 10, 1};
    for (uint32_t k = 0U; k < 5U; k++) {
        RX(0x080, counter[k]);
    }
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    RX(0x080, 2);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    RX(0x080, 3);
    RX(0x080, 4);
    TEST_ASSERT_EQUAL_UINT32(3U, fx_count(0x185U)); /* type 1: every SYNC from then on */
}

static void sync_start_value_only_writable_while_pdo_invalid(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1800, 6, 3U, 1U));
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.tpdo_comm[0].sync_start);
}

static void v53_wrong_dlc_raises_8240(void)
{
    RX(0x080, 0x01); /* 0x1019 = 0: a SYNC has no data */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    assert_emcy(0, 0x8240U, 0x11);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8240U));
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_EQUAL_HEX16(0x8240U, (uint16_t)fx.values.x1003_errors[0]);
}

static void wrong_dlc_sync_is_not_processed(void)
{
    tpdo1_type_and_start(1U);
    RX(0x080, 0x01);
    RX(0x080, 0x01, 0x02);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U)); /* one report per episode */
    assert_emcy(0, 0x8240U, 0x11);
    RX0(0x080); /* right again: processed, and the error is reset */
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    assert_emcy(last_idx(0x085U), 0x0000U, 0x00);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8240U));
}

static void wrong_dlc_with_counter_configured(void)
{
    wr(0x1019, 0, 5U, 1U);
    tpdo1_type_and_start(1U);
    RX0(0x080);
    RX(0x080, 0x01, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    assert_emcy(0, 0x8240U, 0x11);
    RX(0x080, 0x01);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    assert_emcy(last_idx(0x085U), 0x0000U, 0x00);
}

static void wrong_dlc_sync_does_not_restart_timeout(void)
{
    wr(0x1006, 0, 10000U, 4U);
    sync_at(1000U);
    fx_run_until(11000U);
    RX(0x080, 0x01); /* not a valid SYNC: the timeout still runs from 1 ms */
    fx_run_until(16000U - 1U);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8100U));
    fx_run_until(16000U);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8100U));
    assert_emcy(last_idx(0x085U), 0x8100U, 0x11);
}

static void v42_overflow_value_1_refused(void)
{
    const uint8_t req[8] = {0x2F, 0x19, 0x10, 0x00, 0x01, 0x00, 0x00, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x80, 0x19, 0x10, 0x00, 0x30, 0x00, 0x09, 0x06};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1019_sync_overflow);
}

static void overflow_value_range(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1019, 0, 241U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1019, 0, 255U, 1U));
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1019_sync_overflow);
    wr(0x1019, 0, 2U, 1U);
    TEST_ASSERT_EQUAL_UINT8(2U, fx.values.x1019_sync_overflow);
    wr(0x1019, 0, 240U, 1U);
    TEST_ASSERT_EQUAL_UINT8(240U, fx.values.x1019_sync_overflow);
    wr(0x1019, 0, 0U, 1U);
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1019_sync_overflow);
}

static void overflow_value_locked_while_period_set(void)
{
    wr(0x1006, 0, 10000U, 4U);
    TEST_ASSERT_EQUAL_HEX32(0x08000022UL, fx_sdo_write_u32(0x1019, 0, 5U, 1U));
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1019_sync_overflow);
    wr(0x1006, 0, 0U, 4U);
    wr(0x1019, 0, 5U, 1U);
    TEST_ASSERT_EQUAL_UINT8(5U, fx.values.x1019_sync_overflow);
}

static void timeout_at_1_5_periods_then_cleared_by_next_sync(void)
{
    wr(0x1006, 0, 10000U, 4U); /* 10 ms */
    fake_port_clear(&fx.port);
    const co_time_us_t t0 = 1000U;
    sync_at(t0);
    fx_run_until(t0 + 15000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t0 + 15000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    assert_emcy(0, 0x8100U, 0x11);
    TEST_ASSERT_EQUAL_UINT64(t0 + 15000U, fx.port.sent_at[0]);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent); /* reported once */
    const co_time_us_t t1 = fx.now;
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    assert_emcy(1, 0x0000U, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t1, fx.port.sent_at[1]);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8100U));
    /* Monitoring goes on from this SYNC. */
    fx_run_until(t1 + 15000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    fx_run_until(t1 + 15000U);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    assert_emcy(2, 0x8100U, 0x11);
}

static void process_returns_sync_timeout_deadline(void)
{
    wr(0x1006, 0, 2000U, 4U);
    fx_run_until(500U);
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT64(500U + 3000U, fx_process());
}

static void no_timeout_before_first_sync(void)
{
    wr(0x1006, 0, 10000U, 4U);
    fake_port_clear(&fx.port);
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void regular_syncs_never_time_out(void)
{
    wr(0x1006, 0, 10000U, 4U);
    fake_port_clear(&fx.port);
    for (uint32_t k = 1U; k <= 100U; k++) {
        sync_at(k * 14999U); /* just inside 1.5 periods every time */
    }
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void period_zero_stops_timeout_monitoring(void)
{
    wr(0x1006, 0, 10000U, 4U);
    sync_at(1000U);
    wr(0x1006, 0, 0U, 4U);
    fake_port_clear(&fx.port);
    fx_advance(5000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

/* The SYNC consumer is off in Stopped (facts §2.4). SYNCs that kept coming while the node was stopped
 * are no reason for a timeout when it comes back: monitoring must not count the Stopped time. */
static void no_spurious_timeout_after_stopped_while_syncs_continue(void)
{
    wr(0x1006, 0, 10000U, 4U);
    fake_port_clear(&fx.port);
    for (uint32_t k = 1U; k <= 100U; k++) {
        sync_at(k * 10U * MS);
        if (k == 10U) {
            RX(0x000, 0x02, 0x05); /* Stopped at 100 ms */
        }
        if (k == 50U) {
            RX(0x000, 0x80, 0x05); /* Pre-operational again at 500 ms; SYNCs never stopped */
        }
    }
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx_count(0x085U), "SYNC timeout EMCY although SYNCs never stopped");
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8100U));
    /* Monitoring still works afterwards. */
    fx_run_until(1000U * MS + 15000U);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8100U));
}

static void sync_cob_id_rules(void)
{
    /* bit 30 (produce): test_sync_producer */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x20000080UL, 4U)); /* 29-bit */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x00000880UL, 4U)); /* bits 11..28 */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x00000001UL, 4U)); /* restricted */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x00000705UL, 4U)); /* restricted */
    TEST_ASSERT_EQUAL_HEX32(0x80U, fx.values.x1005_cob_id_sync);
}

static void sync_cob_id_change_moves_the_consumer(void)
{
    wr(0x1005, 0, 0x00000081UL, 4U);
    tpdo1_type_and_start(1U);
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    RX0(0x081);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
}

static void sync_in_preop_consumed_but_no_pdos(void)
{
    wr(0x1800, 2, 1U, 1U);
    wr(0x1006, 0, 10000U, 4U);
    fake_port_clear(&fx.port);
    sync_at(1000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(16000U); /* the timeout monitoring runs in Pre-operational */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    assert_emcy(0, 0x8100U, 0x11);
}

static void sync_in_stopped_ignored(void)
{
    wr(0x1800, 2, 1U, 1U);
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    RX(0x080, 0x01);
    RX0(0x080);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8240U));
}

/* TPDO2 (0x285: 0x6000:01 U8 + 0x6401:01 U16) with type 0. */
static void type0_sent_at_sync_only_after_change_or_trigger(void)
{
    wr(0x1801, 2, 0U, 1U);
    wr(0x1801, 1, 0x00000285UL, 4U);
    start();
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x285U)); /* not event-driven: nothing on entering Operational */
    sync_at(1U * MS);
    const uint32_t n = fx_count(0x285U);
    sync_at(2U * MS);
    sync_at(3U * MS);
    TEST_ASSERT_EQUAL_UINT32(n, fx_count(0x285U)); /* unchanged: nothing */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u8(&fx.node, 0x6000, 1, 0x11));
    fx_advance(10U * MS);
    TEST_ASSERT_EQUAL_UINT32(n, fx_count(0x285U)); /* a change alone does not send */
    sync_at(20U * MS);
    TEST_ASSERT_EQUAL_UINT32(n + 1U, fx_count(0x285U));
    ASSERT_FRAME(last_idx(0x285U), 0x285U, 3, 0x11, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(20U * MS, fx.port.sent_at[last_idx(0x285U)]);
    sync_at(21U * MS);
    TEST_ASSERT_EQUAL_UINT32(n + 1U, fx_count(0x285U));
    co_tpdo_trigger(&fx.node, 1U);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(n + 1U, fx_count(0x285U)); /* waits for the SYNC */
    sync_at(22U * MS);
    TEST_ASSERT_EQUAL_UINT32(n + 2U, fx_count(0x285U));
    ASSERT_FRAME(last_idx(0x285U), 0x285U, 3, 0x11, 0x00, 0x00);
    sync_at(23U * MS);
    TEST_ASSERT_EQUAL_UINT32(n + 2U, fx_count(0x285U));
}

static void sync_rpdo_applied_at_next_sync(void)
{
    wr(0x1400, 2, 0U, 1U);
    start();
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    fx_advance(5U * MS);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    RX0(0x080);
    TEST_ASSERT_EQUAL_HEX32(0x44332211UL, fx.values.x6300_value);
    /* Applied once: a later SYNC without a new RPDO changes nothing. */
    fx.values.x6300_value = 0U;
    RX0(0x080);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
}

static void sync_rpdo_type_n_applied_at_next_sync_with_latest_data(void)
{
    wr(0x1400, 2, 240U, 1U);
    start();
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    RX(0x205, 0x55, 0x66, 0x77, 0x88);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    RX0(0x080);
    TEST_ASSERT_EQUAL_HEX32(0x88776655UL, fx.values.x6300_value);
}

static void event_driven_rpdo_applied_at_once(void)
{
    start();
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    TEST_ASSERT_EQUAL_HEX32(0x44332211UL, fx.values.x6300_value);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v52_type2_sent_after_2nd_and_4th_sync);
    RUN_TEST(type1_every_sync_type3_every_third);
    RUN_TEST(sync_tpdo_carries_value_sampled_at_sync);
    RUN_TEST(sync_start_value_first_at_matching_counter);
    RUN_TEST(sync_start_value_waits_even_when_started_mid_cycle);
    RUN_TEST(sync_start_value_only_writable_while_pdo_invalid);
    RUN_TEST(v53_wrong_dlc_raises_8240);
    RUN_TEST(wrong_dlc_sync_is_not_processed);
    RUN_TEST(wrong_dlc_with_counter_configured);
    RUN_TEST(wrong_dlc_sync_does_not_restart_timeout);
    RUN_TEST(v42_overflow_value_1_refused);
    RUN_TEST(overflow_value_range);
    RUN_TEST(overflow_value_locked_while_period_set);
    RUN_TEST(timeout_at_1_5_periods_then_cleared_by_next_sync);
    RUN_TEST(process_returns_sync_timeout_deadline);
    RUN_TEST(no_timeout_before_first_sync);
    RUN_TEST(regular_syncs_never_time_out);
    RUN_TEST(period_zero_stops_timeout_monitoring);
    RUN_TEST(no_spurious_timeout_after_stopped_while_syncs_continue);
    RUN_TEST(sync_cob_id_rules);
    RUN_TEST(sync_cob_id_change_moves_the_consumer);
    RUN_TEST(sync_in_preop_consumed_but_no_pdos);
    RUN_TEST(sync_in_stopped_ignored);
    RUN_TEST(type0_sent_at_sync_only_after_change_or_trigger);
    RUN_TEST(sync_rpdo_applied_at_next_sync);
    RUN_TEST(sync_rpdo_type_n_applied_at_next_sync_with_latest_data);
    RUN_TEST(event_driven_rpdo_applied_at_once);
    return UNITY_END();
}
