/* PDOs: facts §5 and test vectors #45-#51; the mapping procedure and its aborts; change-of-state,
 * inhibit time, event timer and trigger of TPDOs; RPDO length errors, dummies, deadline monitoring. */
#include <string.h>

#include "fixture.h"

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

#define W(index, sub, v, size) TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32((index), (sub), (v), (size)))
#define W_ABORT(code, index, sub, v, size) TEST_ASSERT_EQUAL_HEX32((code), fx_sdo_write_u32((index), (sub), (v), (size)))

static void start(void)
{
    RX(0x000, 0x01, 0x05);
}

/* TPDO1 (0x185, maps 0x1001) with event timer 100 ms, via the CiA procedure (§5.3). */
static void configure_tpdo1_event_timer_100ms(void)
{
    W(0x1800, 1, 0x80000185UL, 4);
    W(0x1A00, 0, 0, 1);
    W(0x1A00, 1, 0x10010008UL, 4);
    W(0x1A00, 0, 1, 1);
    W(0x1800, 2, 255, 1);
    W(0x1800, 5, 100, 2);
    W(0x1800, 1, 0x00000185UL, 4);
}

static void v45_mapping_write_while_pdo_valid(void)
{
    W_ABORT(0x06010000UL, 0x1600, 0, 0, 1);
    W_ABORT(0x06010000UL, 0x1600, 1, 0x62000108UL, 4);
}

static void v46_restricted_cob_id(void)
{
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000705UL, 4);
    W(0x1400, 1, 0x80000205UL, 4);
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000705UL, 4); /* also while invalid */
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000605UL, 4);
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000585UL, 4);
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000040UL, 4);
    W_ABORT(0x06090030UL, 0x1400, 1, 0x20000205UL, 4); /* 29-bit frame */
    W_ABORT(0x06090030UL, 0x1400, 1, 0x00000A05UL, 4); /* bits 11..28 */
    W(0x1400, 1, 0x00000206UL, 4);                     /* another valid ID is fine while invalid */
}

static void v47_rpdo_ignored_in_pre_operational(void)
{
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    start();
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value); /* not applied later either */
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    TEST_ASSERT_EQUAL_HEX32(0x44332211UL, fx.values.x6300_value);
}

static void v48_tpdo_at_start_then_every_event_period(void)
{
    configure_tpdo1_event_timer_100ms();
    fake_port_clear(&fx.port);
    start();
    ASSERT_FRAME(0, 0x185U, 1, 0x00);
    fx_advance(99999U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT64(100000U, fx.port.sent_at[1]);
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(3U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT64(200000U, fx.port.sent_at[2]);
}

static void v49_short_rpdo(void)
{
    start();
    fake_port_clear(&fx.port);
    RX(0x205, 0xAA, 0xBB);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME((uint32_t)fx_last(0x085U), 0x085U, 8, 0x10, 0x82, 0x11, 0x04, 0, 0, 0, 0);
}

static void v50_long_rpdo(void)
{
    start();
    fake_port_clear(&fx.port);
    RX(0x205, 0x55, 0x66, 0x77, 0x88, 0x99);
    TEST_ASSERT_EQUAL_HEX32(0x88776655UL, fx.values.x6300_value);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME((uint32_t)fx_last(0x085U), 0x085U, 8, 0x20, 0x82, 0x11, 0x04, 0, 0, 0, 0);
}

static void v51_correct_rpdo_resets_the_error(void)
{
    start();
    RX(0x205, 0xAA, 0xBB);
    fake_port_clear(&fx.port);
    RX(0x205, 0x01, 0x02, 0x03, 0x04);
    TEST_ASSERT_EQUAL_HEX32(0x04030201UL, fx.values.x6300_value);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME((uint32_t)fx_last(0x085U), 0x085U, 8, 0x00, 0x00, 0x00, 0x04, 0, 0, 0, 0);
    RX(0x205, 0x01, 0x02, 0x03, 0x04); /* no second error reset */
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
}

static void mapping_procedure_and_its_aborts(void)
{
    W_ABORT(0x06010000UL, 0x1A00, 1, 0x60000108UL, 4); /* step 1 missing: PDO valid */
    W(0x1800, 1, 0x80000185UL, 4);
    W_ABORT(0x06010000UL, 0x1A00, 1, 0x60000108UL, 4); /* step 2 missing: sub 0 != 0 */
    W(0x1A00, 0, 0, 1);
    W_ABORT(0x06040041UL, 0x1A00, 1, 0x10000020UL, 4); /* 0x1000 is not mappable */
    W_ABORT(0x06040041UL, 0x1A00, 1, 0x62000108UL, 4); /* RPDO-only object in a TPDO */
    W_ABORT(0x06020000UL, 0x1A00, 1, 0x21000108UL, 4); /* no such object */
    W_ABORT(0x06040041UL, 0x1A00, 1, 0x60000110UL, 4); /* 16 bits of a U8 */
    W_ABORT(0x06040041UL, 0x1A00, 1, 0x60000104UL, 4); /* bit granularity not supported */
    W(0x1800, 1, 0x00000185UL, 4); /* valid with an empty mapping, as a file may give it: silent */
    W_ABORT(0x06010000UL, 0x1A00, 1, 0x60000108UL, 4); /* mapped only while invalid */
    W(0x1800, 1, 0x80000185UL, 4);
    W(0x1A00, 1, 0x60000108UL, 4);
    W(0x1A00, 2, 0x64010110UL, 4);
    W(0x1A00, 3, 0x63000120UL, 4);
    W(0x1A00, 4, 0x63000120UL, 4);
    W_ABORT(0x06040042UL, 0x1A00, 0, 4, 1); /* 11 bytes */
    W_ABORT(0x06040042UL, 0x1A00, 0, 9, 1); /* more entries than exist */
    W(0x1A00, 0, 3, 1);
    W_ABORT(0x06010000UL, 0x1A00, 3, 0x60000208UL, 4); /* sub 0 != 0 again */
    W(0x1800, 1, 0x00000185UL, 4);
    W_ABORT(0x06090030UL, 0x1800, 1, 0x00000186UL, 4); /* CAN-ID change while valid */
    fx.values.x6000_inputs[0] = 0xA5U;
    fx.values.x6401_analog[0] = 0x1234U;
    fx.values.x6300_value = 0xDEADBEEFUL;
    fake_port_clear(&fx.port);
    start();
    ASSERT_FRAME(0, 0x185U, 7, 0xA5, 0x34, 0x12, 0xEF, 0xBE, 0xAD, 0xDE);
}

/* Sub-indices inside a run (0x6000:01-02 and 0x6401:01-02 are one row each in test_od): each maps its own value. */
static void mapping_sub_indices_inside_a_run(void)
{
    W(0x1800, 1, 0x80000185UL, 4);
    W(0x1A00, 0, 0, 1);
    W(0x1A00, 1, 0x60000208UL, 4);
    W(0x1A00, 2, 0x64010210UL, 4);
    W(0x1A00, 3, 0x60000108UL, 4);
    W_ABORT(0x06040041UL, 0x1A00, 4, 0x60000308UL, 4); /* past the run's end: 0x6000 has no sub-index 3 */
    W_ABORT(0x06040041UL, 0x1A00, 4, 0x64010208UL, 4); /* 8 bits of a U16 inside the run */
    W(0x1A00, 0, 3, 1);
    W(0x1800, 1, 0x00000185UL, 4);
    fx.values.x6000_inputs[0] = 0x11U;
    fx.values.x6000_inputs[1] = 0x22U;
    fx.values.x6401_analog[0] = 0x3333U;
    fx.values.x6401_analog[1] = 0x5544U;
    fake_port_clear(&fx.port);
    start();
    ASSERT_FRAME(0, 0x185U, 4, 0x22, 0x44, 0x55, 0x11);
    /* a change of the second element alone is a change of state of this TPDO */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x6401, 2, 0x6677U));
    fake_port_clear(&fx.port);
    (void)fx_process();
    ASSERT_FRAME(0, 0x185U, 4, 0x22, 0x77, 0x66, 0x11);
}

static void communication_parameter_rules(void)
{
    W_ABORT(0x06090030UL, 0x1800, 2, 241, 1);
    W_ABORT(0x06090030UL, 0x1800, 2, 251, 1);
    W_ABORT(0x06090030UL, 0x1400, 2, 250, 1);
    W_ABORT(0x06090030UL, 0x1400, 2, 252, 1); /* RTR-only: TPDOs only (test_pdo_rtr) */
    W_ABORT(0x06090030UL, 0x1400, 2, 253, 1);
    W(0x1800, 2, 240, 1);
    W(0x1800, 2, 0, 1);
    W(0x1800, 2, 254, 1);
    W_ABORT(0x06090030UL, 0x1800, 3, 10, 2); /* inhibit time only while invalid */
    W_ABORT(0x06090030UL, 0x1800, 6, 2, 1);  /* SYNC start value only while invalid */
    W(0x1800, 5, 250, 2);                     /* event timer any time */
    W(0x1800, 1, 0xC0000185UL, 4);
    W(0x1800, 3, 10, 2);
    W(0x1800, 6, 2, 1);
    W(0x1800, 1, 0x40000185UL, 4); /* bit 30 (no RTR) is allowed for a TPDO */
}

static void tpdos_only_in_operational(void)
{
    configure_tpdo1_event_timer_100ms();
    fake_port_clear(&fx.port);
    fx_advance(1000000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    start();
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    fx_advance(1000000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    RX(0x000, 0x80, 0x05);
    fx_advance(1000000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
}

static void change_of_state_sent_without_application_call(void)
{
    start();
    ASSERT_FRAME(0, 0x185U, 1, 0x00);
    fx_advance(5000000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U)); /* no change, no event timer: silent */
    (void)co_emcy_raise(&fx.node, 0x3000U, 0x04U, NULL); /* 0x1001 becomes 0x05 */
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    ASSERT_FRAME((uint32_t)fx_last(0x185U), 0x185U, 1, 0x05);
}

static void option_no_cos_sends_only_on_trigger_and_timer(void)
{
    fx_start(5U, CO_OPT_TPDO_NO_COS);
    start();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U)); /* entering Operational still sends once */
    fx.values.x1001_error_register = 0x42U;
    co_node_values_changed(&fx.node);
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U)); /* a change alone sends nothing */
    co_tpdo_trigger(&fx.node, 0U);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    ASSERT_FRAME((uint32_t)fx_last(0x185U), 0x185U, 1, 0x42);
}

static void inhibit_time_spaces_transmissions(void)
{
    W(0x1800, 1, 0x80000185UL, 4);
    W(0x1800, 3, 100, 2); /* 10 ms */
    W(0x1800, 1, 0x00000185UL, 4);
    start(); /* t = 0: first transmission */
    fx.values.x1001_error_register = 1U;
    co_node_values_changed(&fx.node);
    fx_advance(1000U);
    fx.values.x1001_error_register = 2U;
    co_node_values_changed(&fx.node);
    fx_advance(1000U);
    fx.values.x1001_error_register = 3U;
    co_node_values_changed(&fx.node);
    fx_advance(7999U); /* t = 9.999 ms */
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    ASSERT_FRAME((uint32_t)fx_last(0x185U), 0x185U, 1, 0x03); /* the latest value */
    TEST_ASSERT_EQUAL_UINT64(10000U, fx.port.sent_at[fx_last(0x185U)]);
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
}

static void event_timer_expiring_during_inhibit_waits_for_it(void)
{
    /* found by fuzzing: the deadline returned was the expired timer, in the past: a caller would spin */
    W(0x1800, 1, 0x80000185UL, 4);
    W(0x1800, 3, 1000, 2); /* inhibit 100 ms */
    W(0x1800, 5, 20, 2);   /* event timer 20 ms */
    W(0x1800, 1, 0x00000185UL, 4);
    start(); /* sent at t0 */
    const co_time_us_t t0 = fx.now;
    fx_advance(99999U); /* fx_run_until fails on a deadline that does not advance */
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT64(t0 + 100000U, fx.port.sent_at[fx_last(0x185U)]);
    TEST_ASSERT_TRUE(fx_process() > fx.now);
}

static void trigger_sends_unchanged_data(void)
{
    start();
    co_tpdo_trigger(&fx.node, 0U);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    co_tpdo_trigger(&fx.node, 7U); /* no such TPDO: ignored */
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
}

static void invalid_tpdo_sends_nothing(void)
{
    W(0x1800, 1, 0x80000185UL, 4);
    start();
    fx.values.x1001_error_register = 7U;
    co_tpdo_trigger(&fx.node, 0U);
    fx_advance(1000000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x285U)); /* TPDO2 is invalid by default */
}

static void rpdo_with_dummy_entry_and_real32(void)
{
    W(0x1601, 0, 0, 1);
    W(0x1601, 1, 0x00050008UL, 4); /* dummy U8 */
    W(0x1601, 2, 0x62000108UL, 4);
    W(0x1601, 3, 0x20040020UL, 4); /* REAL32 set-point */
    W(0x1601, 0, 3, 1);
    W(0x1401, 1, 0x00000305UL, 4);
    start();
    RX(0x305, 0xFF, 0x0A, 0x00, 0x00, 0x48, 0x42); /* 50.0f */
    TEST_ASSERT_EQUAL_HEX8(0x0A, fx.values.x6200_output);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, fx.values.x2004_setpoint);
}

static void rpdo_goes_through_the_write_hook(void)
{
    start();
    const uint32_t hooks = fx.write_hooks;
    fx.refuse_code = CO_ABORT_VALUE_HIGH;
    RX(0x205, 0x11, 0x22, 0x33, 0x44);
    TEST_ASSERT_EQUAL_UINT32(hooks + 1U, fx.write_hooks);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value); /* refused: dropped silently */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x585U));
}

static void rpdo_deadline_monitoring(void)
{
    W(0x1400, 5, 50, 2); /* 50 ms */
    start();
    fake_port_clear(&fx.port);
    fx_advance(200000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U)); /* starts with the first RPDO */
    RX(0x205, 1, 2, 3, 4);
    const co_time_us_t rpdo_at = fx.now;
    fx_advance(49999U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x085U));
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME((uint32_t)fx_last(0x085U), 0x085U, 8, 0x50, 0x82, 0x11, 0x04, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT64(rpdo_at + 50000U, fx.port.sent_at[fx_last(0x085U)]);
    RX(0x205, 1, 2, 3, 4);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    ASSERT_FRAME((uint32_t)fx_last(0x085U), 0x085U, 8, 0x00, 0x00, 0x00, 0x04, 0, 0, 0, 0);
}

static void write_hook_sees_pdo_origin(void)
{
    /* an RPDO may only write RPDO-mappable rows, even through co_od_write */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, co_od_write(&fx.node, 0x2003, 0, "\1\2\3\4", 4U, CO_ORIGIN_RPDO));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v45_mapping_write_while_pdo_valid);
    RUN_TEST(v46_restricted_cob_id);
    RUN_TEST(v47_rpdo_ignored_in_pre_operational);
    RUN_TEST(v48_tpdo_at_start_then_every_event_period);
    RUN_TEST(v49_short_rpdo);
    RUN_TEST(v50_long_rpdo);
    RUN_TEST(v51_correct_rpdo_resets_the_error);
    RUN_TEST(mapping_procedure_and_its_aborts);
    RUN_TEST(mapping_sub_indices_inside_a_run);
    RUN_TEST(communication_parameter_rules);
    RUN_TEST(tpdos_only_in_operational);
    RUN_TEST(change_of_state_sent_without_application_call);
    RUN_TEST(option_no_cos_sends_only_on_trigger_and_timer);
    RUN_TEST(inhibit_time_spaces_transmissions);
    RUN_TEST(event_timer_expiring_during_inhibit_waits_for_it);
    RUN_TEST(trigger_sends_unchanged_data);
    RUN_TEST(invalid_tpdo_sends_nothing);
    RUN_TEST(rpdo_with_dummy_entry_and_real32);
    RUN_TEST(rpdo_goes_through_the_write_hook);
    RUN_TEST(rpdo_deadline_monitoring);
    RUN_TEST(write_hook_sees_pdo_origin);
    return UNITY_END();
}
