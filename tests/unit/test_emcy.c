/* EMCY producer: frame layout, error register 0x1001 (bit 0 with any error), error reset, history 0x1003,
 * COB-ID 0x1014, inhibit time 0x1015, Stopped queueing, Eltex format (facts §7, §11 #36-#38, #55, #56). */
#include "fixture.h"

#define MS ((co_time_us_t)1000U)

static const uint8_t m12345[5] = {0x01, 0x02, 0x03, 0x04, 0x05};

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

static uint8_t sdo_read_u8(uint16_t index, uint8_t sub)
{
    uint32_t v = 0xDEADBEEFUL;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(index, sub, &v));
    return (uint8_t)v;
}

static void raise_sends_frame_with_bit0_in_register(void)
{
    fx_run_until(4321U);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8110U, 0x10U, m12345));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* sent by co_node_process */
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x10, 0x81, 0x11, 0x01, 0x02, 0x03, 0x04, 0x05);
    TEST_ASSERT_EQUAL_UINT64(4321U, fx.port.sent_at[0]);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_EQUAL_HEX8(0x11, sdo_read_u8(0x1001, 0));
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8110U));
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8120U));
    bool seen = false;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        if (fx.events[i].kind == CO_EV_EMCY) {
            TEST_ASSERT_EQUAL_HEX32(0x8110U, fx.events[i].value);
            TEST_ASSERT_EQUAL_HEX32(0x11U, fx.events[i].code);
            seen = true;
        }
    }
    TEST_ASSERT_TRUE(seen);
}

static void bit0_set_even_without_other_bits(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x6100U, 0x00U, NULL));
    (void)fx_process();
    ASSERT_FRAME(0, 0x085U, 8, 0x00, 0x61, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.values.x1001_error_register);
}

static void register_is_union_and_reset_carries_what_remains(void)
{
    static const uint8_t ma[5] = {0xA1, 0xA2, 0xA3, 0xA4, 0xA5};
    static const uint8_t mb[5] = {0xB1, 0xB2, 0xB3, 0xB4, 0xB5};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x3100U, 0x04U, ma));
    (void)fx_process();
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8110U, 0x10U, mb));
    (void)fx_process();
    ASSERT_FRAME(0, 0x085U, 8, 0x00, 0x31, 0x05, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5);
    ASSERT_FRAME(1, 0x085U, 8, 0x10, 0x81, 0x15, 0xB1, 0xB2, 0xB3, 0xB4, 0xB5);
    TEST_ASSERT_EQUAL_HEX8(0x15, fx.values.x1001_error_register);
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x3100U, ma));
    (void)fx_process();
    ASSERT_FRAME(2, 0x085U, 8, 0x00, 0x00, 0x11, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x3100U));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x8110U, mb));
    (void)fx_process();
    ASSERT_FRAME(3, 0x085U, 8, 0x00, 0x00, 0x00, 0xB1, 0xB2, 0xB3, 0xB4, 0xB5);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_EQUAL_UINT32(4U, fx.port.n_sent);
}

static void reset_uses_msef_given_to_clear(void)
{
    static const uint8_t other_tail[5] = {0x01, 0x02, 0x09, 0x09, 0x09};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, m12345));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x5000U, other_tail)); /* matches on code + msef[0..1] */
    (void)fx_process();
    ASSERT_FRAME(1, 0x085U, 8, 0x00, 0x00, 0x00, 0x01, 0x02, 0x09, 0x09, 0x09);
}

static void each_clear_sends_its_own_reset(void)
{
    static const uint8_t m1[5] = {0x02, 0x0A, 0, 0, 0};
    static const uint8_t m2[5] = {0x02, 0x0B, 0, 0, 0};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8130U, 0x10U, m1));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8130U, 0x10U, m2)); /* same code, other msef: another error */
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x8130U, m1));
    (void)fx_process();
    ASSERT_FRAME(2, 0x085U, 8, 0x00, 0x00, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x8130U));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x8130U, m2));
    (void)fx_process();
    ASSERT_FRAME(3, 0x085U, 8, 0x00, 0x00, 0x00, 0x02, 0x0B, 0x00, 0x00, 0x00);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x8130U));
}

static void clear_of_inactive_error_does_nothing(void)
{
    TEST_ASSERT_FALSE(co_emcy_clear(&fx.node, 0x5000U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, m12345));
    (void)fx_process();
    TEST_ASSERT_FALSE(co_emcy_clear(&fx.node, 0x5000U, NULL)); /* other msef[0..1] */
    TEST_ASSERT_FALSE(co_emcy_clear(&fx.node, 0x5001U, m12345));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.values.x1001_error_register);
}

static void raising_active_error_again_sends_nothing(void)
{
    static const uint8_t same_head[5] = {0x01, 0x02, 0x77, 0x77, 0x77};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x4210U, 0x08U, m12345));
    (void)fx_process();
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x4210U, 0x08U, m12345));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x4210U, 0x08U, same_head));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
}

static void active_list_full_refuses_raise(void)
{
    for (uint16_t k = 0U; k < CO_EMCY_ACTIVE_MAX; k++) {
        TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, (uint16_t)(0x5001U + k), 0x01U, NULL));
    }
    TEST_ASSERT_FALSE(co_emcy_raise(&fx.node, 0x5100U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(CO_EMCY_ACTIVE_MAX, fx.port.n_sent);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x5100U));
    /* Clearing one makes room again. */
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x5001U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5100U, 0x01U, NULL));
}

static void history_newest_first_with_msef_bytes(void)
{
    static const uint8_t m[5] = {0xAB, 0xCD, 0xEE, 0xEE, 0xEE};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x3100U, 0x04U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8110U, 0x10U, m12345));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0xFF00U, 0x80U, m));
    (void)fx_process();
    fake_port_clear(&fx.port);
    TEST_ASSERT_EQUAL_UINT8(3U, sdo_read_u8(0x1003, 0));
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1003, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0xCDABFF00UL, v);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1003, 2, &v));
    TEST_ASSERT_EQUAL_HEX32(0x02018110UL, v);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1003, 3, &v));
    TEST_ASSERT_EQUAL_HEX32(0x00003100UL, v);
    /* Exact upload frame of sub 1. */
    const uint8_t req[8] = {0x40, 0x03, 0x10, 0x01, 0, 0, 0, 0};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x43, 0x03, 0x10, 0x01, 0x00, 0xFF, 0xAB, 0xCD};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
}

static void history_stores_only_nonzero_codes(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x5000U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x6100U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x6100U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(4U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT8(2U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x6100U, fx.values.x1003_errors[0]);
    TEST_ASSERT_EQUAL_HEX32(0x5000U, fx.values.x1003_errors[1]);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1003_errors[2]);
}

/* 0x0000 means "no error / error reset" (facts §7.3): it never enters the history, even when an
 * application passes it to co_emcy_raise by mistake. */
static void code_zero_never_enters_history(void)
{
    (void)co_emcy_raise(&fx.node, 0x0000U, 0x01U, NULL);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1003_errors[0]);
}

static void history_drops_oldest_when_full(void)
{
    for (uint16_t k = 0U; k < 10U; k++) {
        const uint8_t m[5] = {(uint8_t)k, 0, 0, 0, 0};
        TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, (uint16_t)(0x5001U + k), 0x01U, m));
        TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, (uint16_t)(0x5001U + k), m));
        (void)fx_process();
    }
    TEST_ASSERT_EQUAL_UINT8(8U, fx.values.x1003_count);
    for (uint32_t sub = 1U; sub <= 8U; sub++) {
        const uint32_t k = 10U - sub; /* sub 1 = the 10th error (k = 9) ... sub 8 = the 3rd (k = 2) */
        TEST_ASSERT_EQUAL_HEX32((0x5001UL + k) | (k << 16), fx.values.x1003_errors[sub - 1U]);
    }
    fake_port_clear(&fx.port);
    TEST_ASSERT_EQUAL_UINT8(8U, sdo_read_u8(0x1003, 0));
    TEST_ASSERT_EQUAL_HEX32(0x06090011UL, fx_sdo_read_u32(0x1003, 9, &(uint32_t){0}));
}

static void v36_write_zero_clears_history(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x6100U, 0x01U, NULL));
    (void)fx_process();
    fake_port_clear(&fx.port);
    const uint8_t req[8] = {0x2F, 0x03, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x60, 0x03, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1003_errors[0]);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x1003_errors[1]);
    TEST_ASSERT_EQUAL_HEX32(0x08000024UL, fx_sdo_read_u32(0x1003, 1, &(uint32_t){0}));
    /* The active errors are not touched. */
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.values.x1001_error_register);
    TEST_ASSERT_TRUE(co_emcy_is_active(&fx.node, 0x5000U));
    /* New errors are logged from sub 1 again. */
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x7000U, 0x01U, NULL));
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x7000U, fx.values.x1003_errors[0]);
}

static void v37_write_nonzero_count_refused(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    fake_port_clear(&fx.port);
    const uint8_t req[8] = {0x2F, 0x03, 0x10, 0x00, 0x01, 0x00, 0x00, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x80, 0x03, 0x10, 0x00, 0x30, 0x00, 0x09, 0x06};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0x5000U, fx.values.x1003_errors[0]);
}

static void v38_read_empty_history_sub1(void)
{
    const uint8_t req[8] = {0x40, 0x03, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x80, 0x03, 0x10, 0x01, 0x24, 0x00, 0x00, 0x08};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    TEST_ASSERT_EQUAL_UINT8(0U, sdo_read_u8(0x1003, 0));
}

static void read_sub_beyond_count_is_08000024(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x6100U, 0x01U, NULL));
    (void)fx_process();
    fake_port_clear(&fx.port);
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1003, 2, &v));
    TEST_ASSERT_EQUAL_HEX32(0x5000U, v);
    TEST_ASSERT_EQUAL_HEX32(0x08000024UL, fx_sdo_read_u32(0x1003, 3, &v));
    TEST_ASSERT_EQUAL_HEX32(0x08000024UL, fx_sdo_read_u32(0x1003, 8, &v));
    TEST_ASSERT_EQUAL_HEX32(0x06090011UL, fx_sdo_read_u32(0x1003, 9, &v));
}

static void history_entries_are_read_only(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    fake_port_clear(&fx.port);
    TEST_ASSERT_EQUAL_HEX32(0x06010002UL, fx_sdo_write_u32(0x1003, 1, 0U, 4U));
    TEST_ASSERT_EQUAL_HEX32(0x06010002UL, fx_sdo_write_u32(0x1001, 0, 0U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x5000U, fx.values.x1003_errors[0]);
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.values.x1001_error_register);
}

static void stopped_queues_until_leaving(void)
{
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, m12345));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x8110U, 0x10U, NULL));
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0x5000U, m12345));
    fx_advance(1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0x11, fx.values.x1001_error_register); /* the register is current */
    TEST_ASSERT_EQUAL_UINT8(2U, fx.values.x1003_count);
    const co_time_us_t t = fx.now;
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x00, 0x50, 0x01, 0x01, 0x02, 0x03, 0x04, 0x05);
    ASSERT_FRAME(1, 0x085U, 8, 0x10, 0x81, 0x11, 0x00, 0x00, 0x00, 0x00, 0x00);
    ASSERT_FRAME(2, 0x085U, 8, 0x00, 0x00, 0x11, 0x01, 0x02, 0x03, 0x04, 0x05);
    TEST_ASSERT_EQUAL_UINT64(t, fx.port.sent_at[2]);
}

static void stopped_queue_sent_on_start_too(void)
{
    RX(0x000, 0x02, 0x05);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    fake_port_clear(&fx.port);
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x00, 0x50, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00);
}

static void queue_overflow_drops_oldest_and_counts(void)
{
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    for (uint16_t k = 0U; k < 5U; k++) { /* 10 frames for a queue of 8 */
        TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, (uint16_t)(0x5001U + k), 0x01U, NULL));
        TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, (uint16_t)(0x5001U + k), NULL));
    }
    TEST_ASSERT_EQUAL_UINT32(10U - CO_EMCY_QUEUE_LEN, fx.node.emcy.lost);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(CO_EMCY_QUEUE_LEN, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x02, 0x50, 0x01, 0, 0, 0, 0, 0); /* 0x5001 raise + reset were dropped */
    ASSERT_FRAME(CO_EMCY_QUEUE_LEN - 1U, 0x085U, 8, 0x00, 0x00, 0x00, 0, 0, 0, 0, 0);
}

static void queue_overflow_keeps_the_newest_in_order(void)
{
    RX(0x000, 0x02, 0x05);
    fake_port_clear(&fx.port);
    const uint32_t reports = 2U * (CO_EMCY_QUEUE_LEN - 1U); /* 14 for a queue of 8: the slots wrap, some twice */
    for (uint16_t k = 0U; k < reports / 2U; k++) {
        TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, (uint16_t)(0x5001U + k), 0x01U, NULL));
        TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, (uint16_t)(0x5001U + k), NULL));
    }
    TEST_ASSERT_EQUAL_UINT32(reports - CO_EMCY_QUEUE_LEN, fx.node.emcy.lost);
    RX(0x000, 0x80, 0x05);
    TEST_ASSERT_EQUAL_UINT32(CO_EMCY_QUEUE_LEN, fx.port.n_sent);
    for (uint32_t i = 0U; i < CO_EMCY_QUEUE_LEN; i++) { /* the last reports, raise and reset alternating */
        const uint32_t report = reports - CO_EMCY_QUEUE_LEN + i;
        const uint16_t code = (report % 2U) == 0U ? (uint16_t)(0x5001U + report / 2U) : 0U;
        TEST_ASSERT_EQUAL_HEX16(code, (uint16_t)(fx.port.sent[i].data[0] | (fx.port.sent[i].data[1] << 8)));
    }
}

static void inhibit_time_in_100us_units(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1015, 0, 50U, 2U)); /* 5 ms */
    const co_time_us_t t0 = 10U * MS;
    fx_run_until(t0);
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5001U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5002U, 0x01U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5003U, 0x01U, NULL));
    TEST_ASSERT_EQUAL_UINT64(t0 + 5000U, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x01, 0x50, 0x01, 0, 0, 0, 0, 0);
    fx_run_until(t0 + 4999U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(t0 + 5000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(1, 0x085U, 8, 0x02, 0x50, 0x01, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT64(t0 + 5000U, fx.port.sent_at[1]);
    fx_run_until(t0 + 9999U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    fx_run_until(t0 + 10000U);
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    ASSERT_FRAME(2, 0x085U, 8, 0x03, 0x50, 0x01, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT64(t0 + 10000U, fx.port.sent_at[2]);
}

static void inhibit_time_counts_from_last_emcy(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1015, 0, 1U, 2U)); /* 100 µs */
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5001U, 0x01U, NULL));
    (void)fx_process();
    const co_time_us_t t0 = fx.now;
    fx_run_until(t0 + 30U);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5002U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(t0 + 99U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    fx_run_until(t0 + 100U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    /* After a quiet gap longer than the inhibit time the next EMCY goes at once. */
    fx_run_until(t0 + 1000U);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5003U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(3U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT64(t0 + 1000U, fx.port.sent_at[2]);
}

static void cob_id_bit31_disables_emcy(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x80000085UL, 4U));
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    fx_advance(100U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.values.x1001_error_register); /* the error is still recorded */
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x00000085UL, 4U));
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x6100U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x085U));
    ASSERT_FRAME(last_idx(0x085U), 0x085U, 8, 0x00, 0x61, 0x01, 0, 0, 0, 0, 0);
}

static void can_id_change_only_while_invalid(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x85U, fx.values.x1014_cob_id_emcy);
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1014, 0, 0x00000086UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0x85U, fx.values.x1014_cob_id_emcy);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x00000085UL, 4U)); /* same ID: fine */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x80000085UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x800000A0UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x000000A0UL, 4U));
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x0A0U, 8, 0x00, 0x50, 0x01, 0, 0, 0, 0, 0);
}

static void restricted_and_malformed_cob_ids_refused(void)
{
    static const uint32_t bad[] = {0x000UL, 0x07FUL, 0x101UL, 0x180UL, 0x581UL, 0x5FFUL, 0x601UL,
                                   0x67FUL, 0x6E0UL, 0x6FFUL, 0x701UL, 0x705UL, 0x7FFUL};
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x80000085UL, 4U));
    for (uint32_t i = 0U; i < sizeof bad / sizeof bad[0]; i++) {
        TEST_ASSERT_EQUAL_HEX32_MESSAGE(0x06090030UL, fx_sdo_write_u32(0x1014, 0, bad[i], 4U), "restricted ID");
    }
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1014, 0, 0x20000085UL, 4U)); /* 29-bit */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1014, 0, 0x00000885UL, 4U)); /* bits 11..28 */
    TEST_ASSERT_EQUAL_HEX32(0x80000085UL, fx.values.x1014_cob_id_emcy);
    /* Exact abort frame for 0x705 (facts §1). */
    const uint8_t req[8] = {0x23, 0x14, 0x10, 0x00, 0x05, 0x07, 0x00, 0x00};
    const co_frame_t *f = fx_sdo(req);
    const uint8_t expect[8] = {0x80, 0x14, 0x10, 0x00, 0x30, 0x00, 0x09, 0x06};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, f->data, 8);
    /* Boundaries that are allowed. */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x00000100UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x80000100UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1014, 0, 0x00000700UL, 4U));
}

static void default_cob_id_follows_node_id(void)
{
    fx_start(0x20U, 0U);
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    ASSERT_FRAME(0, 0x0A0U, 8, 0x00, 0x50, 0x01, 0, 0, 0, 0, 0);
}

static void reset_communication_clears_active_errors(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL));
    (void)fx_process();
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&fx.node, 0x5000U));
    TEST_ASSERT_EQUAL_UINT8(0U, fx.values.x1003_count);
}

/* #55: an Eltex warning 0x12 active: Type 0x05 (warning), Code 0x12. The CiA code chosen here is 0xFF00
 * (device specific) with the manufacturer bit 7 of the register. */
static void v55_eltex_warning_frame(void)
{
    static const uint8_t warn[5] = {0x05, 0x12, 0x00, 0x00, 0x00};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0xFF00U, 0x80U, warn));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x085U, 8, 0x00, 0xFF, 0x81, 0x05, 0x12, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX32(0x1205FF00UL, fx.values.x1003_errors[0]);
}

/* #56: after #55 the warning is deleted (the device model does it on 0x2003:02 = 0x12): confirmation. */
static void v56_eltex_confirmation_after_deletion(void)
{
    static const uint8_t warn[5] = {0x05, 0x12, 0x00, 0x00, 0x00};
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0xFF00U, 0x80U, warn));
    (void)fx_process();
    TEST_ASSERT_TRUE(co_emcy_clear(&fx.node, 0xFF00U, warn));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(1, 0x085U, 8, 0x00, 0x00, 0x00, 0x05, 0x12, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.values.x1003_count);
}

static void emcy_sent_in_preop_and_operational(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5001U, 0x01U, NULL));
    (void)fx_process();
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_TRUE(co_emcy_raise(&fx.node, 0x5002U, 0x01U, NULL));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x085U));
}

/* A history whose table lacks a sub-index (0x1003:01, :03..05; no :02): a sub-index the table lacks moves nothing,
 * the one above it keeps its value (the count still counts the present sub-indices), and clearing zeroes the count
 * and the errors up to that count. */
typedef struct gap_values {
    uint32_t device_type;
    uint8_t error_register;
    uint8_t count;
    uint32_t errors[4]; /* :01, :03, :04, :05 */
    uint8_t id_n;
    uint32_t vendor;
} gap_values_t;

#define G(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((gap_values_t *)0)->m), offsetof(gap_values_t, m))
static const co_od_entry_t gap_entries[] = {
    G(0x1000, 0, CO_T_UNSIGNED32, CO_OD_READ, device_type),
    G(0x1001, 0, CO_T_UNSIGNED8, CO_OD_READ, error_register),
    G(0x1003, 0, CO_T_UNSIGNED8, CO_OD_READ | CO_OD_WRITE, count),
    G(0x1003, 1, CO_T_UNSIGNED32, CO_OD_READ, errors[0]),
    CO_OD_RUN(0x1003, 3, 3, CO_T_UNSIGNED32, CO_OD_READ, sizeof(uint32_t), offsetof(gap_values_t, errors[1])),
    G(0x1018, 0, CO_T_UNSIGNED8, CO_OD_READ, id_n),
    G(0x1018, 1, CO_T_UNSIGNED32, CO_OD_READ, vendor),
};
static const gap_values_t gap_defaults = {0x191UL, 0U, 0U, {0x11UL, 0x33UL, 0x44UL, 0x55UL}, 1U, 0x39UL};
static const co_od_t gap_od = {.name = "gap", .entries = gap_entries,
                               .count = (uint16_t)(sizeof gap_entries / sizeof gap_entries[0]), .defaults = &gap_defaults,
                               .values_size = (uint32_t)sizeof(gap_values_t), .signature = 0x6A90UL};

static void history_with_a_sub_index_the_table_lacks(void)
{
    static co_node_t gap_node;
    static gap_values_t v;
    const co_node_cfg_t cfg = {.od = &gap_od, .values = &v, .port = &fx.port.port, .port_ctx = &fx.port, .node_id = 9U};
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&gap_node, &cfg, 0U));
    static const uint32_t after[5][5] = {
        /* count, :01, :03, :04, :05 after raising 0x5001, 0x5002, ... */
        {1U, 0x5001UL, 0x33UL, 0x44UL, 0x55UL},
        {2U, 0x5002UL, 0x33UL, 0x44UL, 0x55UL}, /* :01's error is lost: :02 is missing */
        {3U, 0x5003UL, 0x33UL, 0x44UL, 0x55UL}, /* :03 is not written: the one below is missing */
        {4U, 0x5004UL, 0x33UL, 0x33UL, 0x55UL}, /* :04 takes what :03 held */
        {4U, 0x5005UL, 0x33UL, 0x33UL, 0x55UL}, /* 4 present sub-indices: the count stays */
    };
    for (unsigned k = 0U; k < 5U; k++) {
        TEST_ASSERT_TRUE(co_emcy_raise(&gap_node, (uint16_t)(0x5001U + k), 0x80U, NULL));
        TEST_ASSERT_EQUAL_UINT8(after[k][0], v.count);
        for (unsigned j = 0U; j < 4U; j++) {
            TEST_ASSERT_EQUAL_HEX32(after[k][j + 1U], v.errors[j]);
        }
    }
    const uint8_t zero = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&gap_node, 0x1003U, 0U, &zero, 1U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT8(0U, v.count);
    TEST_ASSERT_EQUAL_HEX32(0U, v.errors[0]);
    TEST_ASSERT_EQUAL_HEX32(0U, v.errors[1]);
    TEST_ASSERT_EQUAL_HEX32(0U, v.errors[2]);
    TEST_ASSERT_EQUAL_HEX32(0x55UL, v.errors[3]); /* :05, past the count of present sub-indices */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(raise_sends_frame_with_bit0_in_register);
    RUN_TEST(bit0_set_even_without_other_bits);
    RUN_TEST(register_is_union_and_reset_carries_what_remains);
    RUN_TEST(reset_uses_msef_given_to_clear);
    RUN_TEST(each_clear_sends_its_own_reset);
    RUN_TEST(clear_of_inactive_error_does_nothing);
    RUN_TEST(raising_active_error_again_sends_nothing);
    RUN_TEST(active_list_full_refuses_raise);
    RUN_TEST(history_newest_first_with_msef_bytes);
    RUN_TEST(history_stores_only_nonzero_codes);
    RUN_TEST(code_zero_never_enters_history);
    RUN_TEST(history_drops_oldest_when_full);
    RUN_TEST(history_with_a_sub_index_the_table_lacks);
    RUN_TEST(v36_write_zero_clears_history);
    RUN_TEST(v37_write_nonzero_count_refused);
    RUN_TEST(v38_read_empty_history_sub1);
    RUN_TEST(read_sub_beyond_count_is_08000024);
    RUN_TEST(history_entries_are_read_only);
    RUN_TEST(stopped_queues_until_leaving);
    RUN_TEST(stopped_queue_sent_on_start_too);
    RUN_TEST(queue_overflow_drops_oldest_and_counts);
    RUN_TEST(queue_overflow_keeps_the_newest_in_order);
    RUN_TEST(inhibit_time_in_100us_units);
    RUN_TEST(inhibit_time_counts_from_last_emcy);
    RUN_TEST(cob_id_bit31_disables_emcy);
    RUN_TEST(can_id_change_only_while_invalid);
    RUN_TEST(restricted_and_malformed_cob_ids_refused);
    RUN_TEST(default_cob_id_follows_node_id);
    RUN_TEST(reset_communication_clears_active_errors);
    RUN_TEST(v55_eltex_warning_frame);
    RUN_TEST(v56_eltex_confirmation_after_deletion);
    RUN_TEST(emcy_sent_in_preop_and_operational);
    return UNITY_END();
}
