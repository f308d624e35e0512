/* SYNC producer (CiA 301 §7.2.5, 0x1005 bit 30 "gen"): the SYNC every 0x1006 µs on its grid, with a counter
 * 1..0x1019 that wraps to 1, in Pre-operational and Operational only; the producer consumes its own SYNC (its
 * synchronous TPDOs) and takes none from the bus; the rules of writing 0x1005 while producing. */
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

/* Makes the node a producer with this period (and counter overflow value): returns the time production started. */
static co_time_us_t produce(uint32_t period_us, uint8_t overflow)
{
    wr(0x1019, 0, overflow, 1U);
    wr(0x1006, 0, period_us, 4U);
    wr(0x1005, 0, 0x40000080UL, 4U);
    fake_port_clear(&fx.port);
    return fx.now;
}

static void a_producer_sends_the_sync_every_period(void)
{
    const co_time_us_t t0 = produce(10000U, 0U);
    fx_run_until(t0 + 10000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(t0 + 10000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME0(0, 0x080U);
    TEST_ASSERT_EQUAL_UINT64(t0 + 10000U, fx.port.sent_at[0]);
    fx_run_until(t0 + 50000U);
    TEST_ASSERT_EQUAL_UINT32(5U, fx_count(0x080U));
    for (uint32_t i = 0U; i < 5U; i++) {
        ASSERT_FRAME0(i, 0x080U);
        TEST_ASSERT_EQUAL_UINT64(t0 + (i + 1U) * 10000U, fx.port.sent_at[i]);
    }
    TEST_ASSERT_EQUAL_HEX8(0x00, fx.values.x1001_error_register); /* no timeout of its own SYNC */
}

static void a_late_call_keeps_the_grid(void)
{
    const co_time_us_t t0 = produce(10000U, 0U);
    fx.now = t0 + 34000U; /* three periods late: one SYNC now, the missed ones skipped */
    TEST_ASSERT_EQUAL_UINT64(t0 + 40000U, fx_process());
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x080U));
    fx_run_until(t0 + 40000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x080U));
    TEST_ASSERT_EQUAL_UINT64(t0 + 40000U, fx.port.sent_at[1]);
}

static void the_counter_runs_from_1_to_the_overflow_value_and_again_from_1(void)
{
    const co_time_us_t t0 = produce(1000U, 3U);
    fx_run_until(t0 + 5000U);
    TEST_ASSERT_EQUAL_UINT32(5U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x080U, 1, 0x01);
    ASSERT_FRAME(1, 0x080U, 1, 0x02);
    ASSERT_FRAME(2, 0x080U, 1, 0x03);
    ASSERT_FRAME(3, 0x080U, 1, 0x01);
    ASSERT_FRAME(4, 0x080U, 1, 0x02);
}

static void no_sync_in_stopped_and_a_new_start_after_it(void)
{
    const co_time_us_t t0 = produce(1000U, 240U);
    fx_run_until(t0 + 2000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x080U));
    RX(0x000, 0x02, 0x05); /* Stopped */
    fake_port_clear(&fx.port);
    fx_advance(10U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_count(0x080U));
    RX(0x000, 0x80, 0x05); /* Pre-operational: a full period, the counter from 1 */
    const co_time_us_t t1 = fx.now;
    fake_port_clear(&fx.port);
    fx_run_until(t1 + 1000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x080U, 1, 0x01);
    TEST_ASSERT_EQUAL_UINT64(t1 + 1000U, fx.port.sent_at[0]);
}

static void no_period_no_sync(void)
{
    const co_time_us_t t0 = produce(0U, 0U);
    fx_run_until(t0 + 1000U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    wr(0x1006, 0, 2000U, 4U); /* a period: production starts now */
    const co_time_us_t t1 = fx.now;
    fake_port_clear(&fx.port);
    fx_run_until(t1 + 4000U);
    TEST_ASSERT_EQUAL_UINT32(2U, fx_count(0x080U));
    TEST_ASSERT_EQUAL_UINT64(t1 + 2000U, fx.port.sent_at[0]);
    wr(0x1006, 0, 0U, 4U);
    fake_port_clear(&fx.port);
    fx_advance(100U * MS);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

/* TPDO1 (0x185, 0x1001) synchronous every 2nd SYNC, TPDO2 (0x285) every SYNC: each right after the SYNC that sends
 * it, in Operational. */
static void the_producer_consumes_its_own_sync(void)
{
    wr(0x1800, 2, 2U, 1U);
    wr(0x1801, 2, 1U, 1U);
    wr(0x1801, 1, 0x00000285UL, 4U);
    RX(0x000, 0x01, 0x05);
    const co_time_us_t t0 = produce(1000U, 0U);
    fx_run_until(t0 + 4000U);
    TEST_ASSERT_EQUAL_UINT32(4U + 2U + 4U, fx.port.n_sent);
    ASSERT_FRAME0(0, 0x080U);
    ASSERT_FRAME(1, 0x285U, 3, 0x00, 0x00, 0x00);
    ASSERT_FRAME0(2, 0x080U);
    ASSERT_FRAME(3, 0x185U, 1, 0x00);
    ASSERT_FRAME(4, 0x285U, 3, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT64(t0 + 2000U, fx.port.sent_at[3]);
}

static void the_producer_takes_no_sync_from_the_bus(void)
{
    wr(0x1800, 2, 1U, 1U);
    RX(0x000, 0x01, 0x05);
    (void)produce(0U, 0U);
    RX0(0x080);
    RX(0x080, 0x01); /* not even as a SYNC of the wrong length (EMCY 0x8240) */
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    uint16_t ids[16];
    const uint16_t n = co_node_rx_ids(&fx.node, ids, 16U);
    for (uint16_t i = 0U; i < n && i < 16U; i++) {
        TEST_ASSERT_NOT_EQUAL(0x080U, ids[i]);
    }
    wr(0x1005, 0, 0x00000080UL, 4U); /* a consumer again */
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x185U));
}

static void the_cob_id_rules_while_producing(void)
{
    wr(0x1005, 0, 0x40000081UL, 4U); /* not producing yet: gen and another CAN-ID at once */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x40000082UL, 4U)); /* CAN-ID while gen */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x60000081UL, 4U)); /* 29-bit */
    TEST_ASSERT_EQUAL_HEX32(0x06090030UL, fx_sdo_write_u32(0x1005, 0, 0x40000701UL, 4U)); /* restricted */
    TEST_ASSERT_EQUAL_HEX32(0x40000081UL, fx.values.x1005_cob_id_sync);
    wr(0x1005, 0, 0x40000081UL, 4U); /* the same: fine */
    wr(0x1005, 0, 0x00000081UL, 4U); /* gen off first */
    wr(0x1005, 0, 0x40000082UL, 4U); /* then another CAN-ID with gen */
    TEST_ASSERT_EQUAL_HEX32(0x40000082UL, fx.values.x1005_cob_id_sync);
    wr(0x1006, 0, 1000U, 4U);
    fake_port_clear(&fx.port);
    fx_advance(1000U);
    ASSERT_FRAME0(0, 0x082U);
    /* 0x1019 may change only while 0x1006 is 0 (CiA 301), producing or not */
    TEST_ASSERT_EQUAL_HEX32(0x08000022UL, fx_sdo_write_u32(0x1019, 0, 4U, 1U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_producer_sends_the_sync_every_period);
    RUN_TEST(a_late_call_keeps_the_grid);
    RUN_TEST(the_counter_runs_from_1_to_the_overflow_value_and_again_from_1);
    RUN_TEST(no_sync_in_stopped_and_a_new_start_after_it);
    RUN_TEST(no_period_no_sync);
    RUN_TEST(the_producer_consumes_its_own_sync);
    RUN_TEST(the_producer_takes_no_sync_from_the_bus);
    RUN_TEST(the_cob_id_rules_while_producing);
    return UNITY_END();
}
