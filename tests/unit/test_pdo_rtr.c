/* Remote requests of TPDOs (CiA 301 §7.2.2): transmission types 252 (sampled at the SYNC, sent on RTR) and 253
 * (sampled and sent on RTR); an RTR asks an event-driven TPDO (254/255) for a transmission; no answer with COB-ID bit
 * 30 set (no RTR allowed), for synchronous types 0..240, outside Operational; co_node_rx_ids lists what is answered. */
#include "fixture.h"

#define MS ((co_time_us_t)1000U)

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

static void wr(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(index, sub, v, size));
}

/* TPDO2 (0x285: 0x6000:01 U8 + 0x6401:01 U16) with this transmission type and COB-ID, then Operational. */
static void tpdo2(uint8_t type, uint32_t cob_id)
{
    wr(0x1801, 2, type, 1U);
    wr(0x1801, 1, cob_id, 4U);
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port);
}

static bool rtr(uint32_t id)
{
    const co_frame_t f = {id, 3U, CO_FRAME_RTR, {0U}};
    const bool taken = co_node_rx(&fx.node, &f, fx.now);
    (void)fx_process();
    return taken;
}

static bool listed(uint16_t id)
{
    uint16_t ids[32];
    const uint16_t n = co_node_rx_ids(&fx.node, ids, 32U);
    for (uint16_t i = 0U; i < n && i < 32U; i++) {
        if (ids[i] == id) {
            return true;
        }
    }
    return false;
}

static void type_253_samples_and_sends_on_rtr_only(void)
{
    tpdo2(253U, 0x00000285UL);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* not event-driven: nothing on entering Operational */
    fx.values.x6000_inputs[0] = 0x11U;
    fx.values.x6401_analog[0] = 0x2233U;
    co_node_values_changed(&fx.node);
    fx_advance(10U * MS);
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* neither a change nor a SYNC sends it */
    fx_advance(1U * MS);
    TEST_ASSERT_TRUE(rtr(0x285U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x285U, 3, 0x11, 0x33, 0x22);
    TEST_ASSERT_EQUAL_UINT64(fx.now, fx.port.sent_at[0]);
    fx.values.x6000_inputs[0] = 0x44U;
    TEST_ASSERT_TRUE(rtr(0x285U));
    ASSERT_FRAME(1, 0x285U, 3, 0x44, 0x33, 0x22); /* sampled at the request */
}

static void type_252_sends_what_the_last_sync_sampled(void)
{
    tpdo2(252U, 0x00000285UL);
    fx.values.x6000_inputs[0] = 0x11U;
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent); /* the SYNC samples, sends nothing */
    fx.values.x6000_inputs[0] = 0x22U;
    TEST_ASSERT_TRUE(rtr(0x285U));
    TEST_ASSERT_TRUE(rtr(0x285U));
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x285U, 3, 0x11, 0x00, 0x00);
    ASSERT_FRAME(1, 0x285U, 3, 0x11, 0x00, 0x00);
    RX0(0x080);
    TEST_ASSERT_TRUE(rtr(0x285U));
    ASSERT_FRAME(2, 0x285U, 3, 0x22, 0x00, 0x00);
}

static void type_252_before_its_first_sync_samples_at_the_request(void)
{
    tpdo2(252U, 0x00000285UL);
    fx.values.x6000_inputs[0] = 0x5AU;
    TEST_ASSERT_TRUE(rtr(0x285U));
    ASSERT_FRAME(0, 0x285U, 3, 0x5A, 0x00, 0x00);
}

static void cob_id_bit_30_means_no_answer(void)
{
    tpdo2(253U, 0x40000285UL);
    TEST_ASSERT_FALSE(rtr(0x285U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_FALSE(listed(0x285U));
    wr(0x1801, 1, 0x00000285UL, 4U); /* RTR allowed now: the filter list changes with it */
    TEST_ASSERT_TRUE(listed(0x285U));
    fake_port_clear(&fx.port);
    TEST_ASSERT_TRUE(rtr(0x285U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x285U));
}

static void no_answer_outside_operational(void)
{
    tpdo2(253U, 0x00000285UL);
    RX(0x000, 0x80, 0x05);
    (void)rtr(0x285U);
    RX(0x000, 0x02, 0x05);
    (void)rtr(0x285U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x285U));
}

static void synchronous_types_do_not_answer(void)
{
    tpdo2(1U, 0x00000285UL);
    TEST_ASSERT_FALSE(rtr(0x285U));
    TEST_ASSERT_FALSE(listed(0x285U));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void an_rtr_is_an_event_of_an_event_driven_tpdo(void)
{
    /* TPDO1 (0x185, 0x1001), type 255, inhibit time 10 ms: sent on entering Operational, then on RTR after it */
    wr(0x1800, 1, 0x80000185UL, 4U);
    wr(0x1800, 3, 100U, 2U);
    wr(0x1800, 1, 0x00000185UL, 4U);
    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
    const co_time_us_t t0 = fx.port.sent_at[fx_last(0x185U)];
    TEST_ASSERT_TRUE(rtr(0x185U));
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U)); /* inside the inhibit time: waits */
    fx_run_until(t0 + 10U * MS);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x185U));
    TEST_ASSERT_EQUAL_UINT64(t0 + 10U * MS, fx.port.sent_at[fx_last(0x185U)]);
}

static void a_data_frame_on_the_tpdo_cob_id_is_not_taken(void)
{
    tpdo2(253U, 0x00000285UL);
    const co_frame_t data = {0x285U, 3U, 0U, {1U, 2U, 3U}};
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &data, fx.now));
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void the_types_are_taken_by_a_tpdo_only(void)
{
    wr(0x1800, 2, 252U, 1U);
    wr(0x1800, 2, 253U, 1U);
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1800, 2, 251U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1400, 2, 252U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1400, 2, 253U, 1U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(type_253_samples_and_sends_on_rtr_only);
    RUN_TEST(type_252_sends_what_the_last_sync_sampled);
    RUN_TEST(type_252_before_its_first_sync_samples_at_the_request);
    RUN_TEST(cob_id_bit_30_means_no_answer);
    RUN_TEST(no_answer_outside_operational);
    RUN_TEST(synchronous_types_do_not_answer);
    RUN_TEST(an_rtr_is_an_event_of_an_event_driven_tpdo);
    RUN_TEST(a_data_frame_on_the_tpdo_cob_id_is_not_taken);
    RUN_TEST(the_types_are_taken_by_a_tpdo_only);
    return UNITY_END();
}
