/*
 * LSS slave (CiA 305): facts §9 and test vectors #57-#79, plus the project's decisions of §12
 * (autonomous reset communication of an unconfigured node, fastscan only when unconfigured, identify
 * remote slave answered, identify non-configured answered only when the node-ID is 0xFF).
 * Node-ID 5, identity of the test OD: vendor 0x24E, product 0x1234, revision 0x00010002, serial 0x00ABCDEF.
 */
#include "fixture.h"

#include <string.h>

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

/* One master frame on 0x7E5 (8 bytes); recorded frames are cleared first, so what follows is its answer. */
#define LSS_IN(...)                                                                      \
    do {                                                                                 \
        fake_port_clear(&fx.port);                                                       \
        RX(0x7E5U, __VA_ARGS__);                                                         \
    } while (0)
/* Exactly one frame was sent, on 0x7E4, 8 bytes, with this data. */
#define EXPECT_LSS(...)                                                                  \
    do {                                                                                 \
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(1U, fx.port.n_sent, "expected exactly one frame"); \
        ASSERT_FRAME(0, 0x7E4U, 8, __VA_ARGS__);                                         \
    } while (0)
#define EXPECT_NONE() TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx.port.n_sent, "expected no frame")

/* Sends cs + a little-endian u32 + three reserved zero bytes. */
static void lss_u32(uint8_t cs, uint32_t v)
{
    LSS_IN(cs, (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24), 0, 0, 0);
}

static void to_configuration(void)
{
    LSS_IN(0x04, 0x01, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
}

static void to_waiting(void)
{
    LSS_IN(0x04, 0x00, 0, 0, 0, 0, 0, 0);
}

/* True when the slave is in configuration state: it then answers inquire node-ID (which it checks). */
static bool answers_inquire_node_id(uint8_t expect_id)
{
    LSS_IN(0x5E, 0, 0, 0, 0, 0, 0, 0);
    if (fx.port.n_sent == 0U) {
        return false;
    }
    EXPECT_LSS(0x5E, expect_id, 0, 0, 0, 0, 0, 0);
    return true;
}

/* Fastscan frame; true when the slave acknowledged it (exactly one 4F frame), false when it stayed silent. */
static bool fastscan(uint32_t id, uint8_t bit_checked, uint8_t sub, uint8_t next)
{
    LSS_IN(0x51, (uint8_t)id, (uint8_t)(id >> 8), (uint8_t)(id >> 16), (uint8_t)(id >> 24), bit_checked, sub, next);
    if (fx.port.n_sent == 0U) {
        return false;
    }
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    return true;
}

static int find_event(co_event_kind_t kind)
{
    for (uint32_t i = fx.n_events; i > 0U; i--) {
        if (fx.events[i - 1U].kind == kind) {
            return (int)(i - 1U);
        }
    }
    return -1;
}

/* ---- Facts §11 vectors #57-#79 --------------------------------------------------------------------- */

static void v57_inquire_node_id_ignored_in_waiting(void)
{
    LSS_IN(0x5E, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
}

static void v58_switch_global_to_configuration(void)
{
    LSS_IN(0x04, 0x01, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    /* now in configuration: inquire node-ID is answered */
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
}

static void v59_inquire_node_id(void)
{
    to_configuration();
    LSS_IN(0x5E, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5E, 0x05, 0, 0, 0, 0, 0, 0);
}

static void v60_inquire_vendor(void)
{
    to_configuration();
    LSS_IN(0x5A, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5A, 0x4E, 0x02, 0x00, 0x00, 0, 0, 0);
}

static void v61_inquire_serial(void)
{
    to_configuration();
    LSS_IN(0x5D, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5D, 0xEF, 0xCD, 0xAB, 0x00, 0, 0, 0);
}

static void v62_configure_node_id(void)
{
    to_configuration();
    fx.n_events = 0U;
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    /* pending only: the active node-ID is still 5 */
    TEST_ASSERT_EQUAL_HEX8(0x05, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_HEX8(0x0A, fx.node.lss.pending_node_id);
    const int e = find_event(CO_EV_LSS_NODE_ID);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_UINT32(0x0AU, fx.events[e].value);
}

static void v63_configure_node_id_out_of_range(void)
{
    to_configuration();
    LSS_IN(0x11, 0x80, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0x05, fx.node.lss.pending_node_id);
}

static void v64_configure_bit_timing(void)
{
    to_configuration();
    LSS_IN(0x13, 0x00, 0x04, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(4U, fx.node.lss.pending_bit_timing);
    LSS_IN(0x13, 0x00, 0x03, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(3U, fx.node.lss.pending_bit_timing);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.bit_rate_calls); /* pending only */
}

static void v65_configure_bit_timing_reserved_index(void)
{
    to_configuration();
    LSS_IN(0x13, 0x00, 0x05, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(4U, fx.node.lss.pending_bit_timing);
}

static void v66_configure_bit_timing_other_selector(void)
{
    to_configuration();
    LSS_IN(0x13, 0x01, 0x04, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
}

static void v67_activate_bit_timing(void)
{
    /* heartbeat every 50 ms from t = 0: due at 50, 100, 150, 200, 250 ms ... */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 50U, 2U));
    to_configuration();
    LSS_IN(0x13, 0x00, 0x03, 0, 0, 0, 0, 0); /* 250 kbit/s pending */
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    fx_run_until(20000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.bit_rate_calls);
    fx.n_events = 0U;
    const uint32_t suppressed = fx.node.stats.tx_suppressed;

    LSS_IN(0x15, 0x64, 0x00, 0, 0, 0, 0, 0); /* delay 100 ms, at t = 20 ms */
    EXPECT_NONE();
    fx_run_until(20000U + 99999U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.bit_rate_calls);
    fx_run_until(20000U + 100000U); /* switch exactly after the delay */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(250U, fx.port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT8(3U, fx.node.lss.active_bit_timing);
    const int e = find_event(CO_EV_LSS_ACTIVATE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_UINT32(250U, fx.events[e].value);

    /* still silent in the second delay: even an LSS request gets no answer */
    fx_run_until(170000U);
    RX(0x7E5U, 0x5E, 0, 0, 0, 0, 0, 0, 0);
    fx_run_until(20000U + 199999U);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx.port.n_sent, "a frame was sent during the silence");
    /* heartbeats due at 50, 100, 150, 200 ms and the 5E answer were suppressed */
    TEST_ASSERT_EQUAL_UINT32(suppressed + 5U, fx.node.stats.tx_suppressed);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.bit_rate_calls);

    /* after 2 x delay the node talks again: the next heartbeat on its grid at 250 ms */
    fx_run_until(249999U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_run_until(250000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x705U, 1, 0x7F);
    TEST_ASSERT_EQUAL_UINT64(250000U, fx.port.sent_at[0]);
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
}

static void v68_store_configuration(void)
{
    to_configuration();
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.nvm[CO_NVM_LSS].commits);
    TEST_ASSERT_EQUAL_UINT32(12U, fx.port.nvm[CO_NVM_LSS].stored_len);
}

static void v69_node_id_pending_until_reset_communication(void)
{
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    to_waiting();
    EXPECT_NONE(); /* a configured node does not reset by itself */
    TEST_ASSERT_EQUAL_HEX8(0x05, co_node_id(&fx.node));
    to_configuration();
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05)); /* still the old ID */
    to_waiting();
    /* SDO still on the old ID */
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_read_u32(0x1014, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x85U, v);

    fake_port_clear(&fx.port);
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    to_configuration();
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x0A));
    /* node-ID-relative objects follow the new ID; the old SDO channel is gone */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_read_u32(0x1014, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x8AU, v);
    fake_port_clear(&fx.port);
    RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
}

static void pending_node_id_adopted_by_reset_node(void)
{
    to_configuration();
    LSS_IN(0x11, 0x21, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    fake_port_clear(&fx.port);
    RX(0x000, 0x81, 0x00); /* reset node, broadcast */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x721U, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x21, co_node_id(&fx.node));
    /* not stored: a power cycle returns to the configured default */
    fake_port_clear(&fx.port);
    fx_power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
}

static void v70_switch_state_selective(void)
{
    LSS_IN(0x40, 0x4E, 0x02, 0x00, 0x00, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x41, 0x34, 0x12, 0x00, 0x00, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x42, 0x02, 0x00, 0x01, 0x00, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x43, 0xEF, 0xCD, 0xAB, 0x00, 0, 0, 0);
    EXPECT_LSS(0x44, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05)); /* in configuration */
}

static void v71_switch_state_selective_wrong_serial(void)
{
    LSS_IN(0x40, 0x4E, 0x02, 0x00, 0x00, 0, 0, 0);
    LSS_IN(0x41, 0x34, 0x12, 0x00, 0x00, 0, 0, 0);
    LSS_IN(0x42, 0x02, 0x00, 0x01, 0x00, 0, 0, 0);
    LSS_IN(0x43, 0xEF, 0xCD, 0xAB, 0x01, 0, 0, 0);
    EXPECT_NONE();
    TEST_ASSERT_FALSE(answers_inquire_node_id(0x05)); /* still waiting */
}

static void v72_identify_non_configured(void)
{
    fx_start(0xFFU, 0U);
    LSS_IN(0x4C, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x50, 0, 0, 0, 0, 0, 0, 0);
}

static void identify_non_configured_silent_when_configured(void)
{
    LSS_IN(0x4C, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    to_configuration();
    LSS_IN(0x4C, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
}

static void identify_remote(uint32_t vendor, uint32_t product, uint32_t rev_lo, uint32_t rev_hi, uint32_t ser_lo,
                            uint32_t ser_hi)
{
    lss_u32(0x46, vendor);
    EXPECT_NONE();
    lss_u32(0x47, product);
    EXPECT_NONE();
    lss_u32(0x48, rev_lo);
    EXPECT_NONE();
    lss_u32(0x49, rev_hi);
    EXPECT_NONE();
    lss_u32(0x4A, ser_lo);
    EXPECT_NONE();
    lss_u32(0x4B, ser_hi);
}

static void v73_identify_remote_slave(void)
{
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    /* exact bounds are inclusive */
    identify_remote(0x24EU, 0x1234U, 0x00010002UL, 0x00010002UL, 0x00ABCDEFUL, 0x00ABCDEFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    /* answered in configuration state too */
    to_configuration();
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
}

static void identify_remote_slave_mismatch_is_silent(void)
{
    identify_remote(0x24FU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL); /* vendor */
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1235U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL); /* product */
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1234U, 0x00010003UL, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL); /* revision below range */
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1234U, 0U, 0x00010001UL, 0U, 0xFFFFFFFFUL); /* revision above range */
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0x00ABCDF0UL, 0xFFFFFFFFUL); /* serial below range */
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0x00ABCDEEUL); /* serial above range */
    EXPECT_NONE();
    /* out of order: 0x48 skipped */
    lss_u32(0x46, 0x24EU);
    lss_u32(0x47, 0x1234U);
    lss_u32(0x49, 0xFFFFFFFFUL);
    lss_u32(0x4A, 0U);
    lss_u32(0x4B, 0xFFFFFFFFUL);
    EXPECT_NONE();
    /* without 0x46 */
    lss_u32(0x47, 0x1234U);
    lss_u32(0x48, 0U);
    lss_u32(0x49, 0xFFFFFFFFUL);
    lss_u32(0x4A, 0U);
    lss_u32(0x4B, 0xFFFFFFFFUL);
    EXPECT_NONE();
    /* a full good sequence still works afterwards */
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    /* a mismatch, the rest of its sequence (silent), then a good one started at once */
    lss_u32(0x46, 0x24EU);
    lss_u32(0x47, 0x1235U);
    lss_u32(0x48, 0U);
    EXPECT_NONE();
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
}

static void v74_fastscan_reset(void)
{
    fx_start(0xFFU, 0U);
    LSS_IN(0x51, 0x00, 0x00, 0x00, 0x00, 0x80, 0x00, 0x00);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
}

static void v75_fastscan_confirm_all_four(void)
{
    fx_start(0xFFU, 0U);
    LSS_IN(0x51, 0x00, 0x00, 0x00, 0x00, 0x80, 0x00, 0x00);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x51, 0x4E, 0x02, 0x00, 0x00, 0x00, 0x00, 0x01);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_FALSE(answers_inquire_node_id(0xFF)); /* not yet in configuration */
    LSS_IN(0x51, 0x34, 0x12, 0x00, 0x00, 0x00, 0x01, 0x02);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x51, 0x02, 0x00, 0x01, 0x00, 0x00, 0x02, 0x03);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_FALSE(answers_inquire_node_id(0xFF));
    LSS_IN(0x51, 0xEF, 0xCD, 0xAB, 0x00, 0x00, 0x03, 0x00);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x5E, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5E, 0xFF, 0, 0, 0, 0, 0, 0);
}

static void v76_configured_unconfigured_node_boots_by_itself(void)
{
    v75_fastscan_confirm_all_four();
    const uint32_t resets = fx.resets_comm;
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
    LSS_IN(0x04, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(resets + 1U, fx.resets_comm);
    /* the services run on the new ID, with node-ID-relative objects filled in */
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_read_u32(0x1014, 0, &v));
    TEST_ASSERT_EQUAL_HEX32(0x8AU, v);
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_read_u32(0x1800, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x18AU, v);
    fake_port_clear(&fx.port);
    RX(0x000, 0x01, 0x0A);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    /* and it is in LSS waiting state now */
    TEST_ASSERT_FALSE(answers_inquire_node_id(0x0A));
}

static void v77_unconfigured_node_runs_lss_only(void)
{
    fx_start(0xFFU, 0U);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx.port.n_sent, "no boot-up for an unconfigured node");
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
    RX(0x000, 0x01, 0x00);
    TEST_ASSERT_NOT_EQUAL(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    RX(0x000, 0x82, 0x00);
    RX(0x67F, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    RX(0x6FF, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    /* no heartbeat either, even with a period set */
    fx.values.x1017_producer_hb = 10U;
    fx_advance(1000000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_NOT_EQUAL(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    /* but LSS answers */
    to_configuration();
    TEST_ASSERT_TRUE(answers_inquire_node_id(0xFF));
}

static void v78_fastscan_ignored_by_configured_node(void)
{
    LSS_IN(0x51, 0x00, 0x00, 0x00, 0x00, 0x80, 0x00, 0x00);
    EXPECT_NONE();
    LSS_IN(0x51, 0x4E, 0x02, 0x00, 0x00, 0x00, 0x00, 0x01);
    EXPECT_NONE();
}

static void v79_wrong_dlc_ignored(void)
{
    to_configuration();
    fake_port_clear(&fx.port);
    RX(0x7E5U, 0x5E, 0x00); /* DLC 2 */
    EXPECT_NONE();
    static const uint8_t d[8] = {0x5E, 0, 0, 0, 0, 0, 0, 0};
    for (uint8_t len = 0U; len < 8U; len++) {
        fx_rx(0x7E5U, len, d);
    }
    EXPECT_NONE();
    /* DLC 8 is answered (the node really is in configuration) */
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
    /* a short switch-state frame does not change the state either */
    fx_rx(0x7E5U, 2U, (const uint8_t[]){0x04, 0x00});
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
}

/* ---- Further behaviour ---------------------------------------------------------------------------- */

static void inquire_product_and_revision(void)
{
    to_configuration();
    LSS_IN(0x5B, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5B, 0x34, 0x12, 0x00, 0x00, 0, 0, 0);
    LSS_IN(0x5C, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5C, 0x02, 0x00, 0x01, 0x00, 0, 0, 0);
}

static void switch_global_back_to_waiting_and_bad_mode(void)
{
    to_configuration();
    LSS_IN(0x04, 0x02, 0, 0, 0, 0, 0, 0); /* other modes are ignored */
    EXPECT_NONE();
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
    to_waiting();
    EXPECT_NONE();
    TEST_ASSERT_FALSE(answers_inquire_node_id(0x05));
    LSS_IN(0x04, 0x02, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_FALSE(answers_inquire_node_id(0x05));
}

static void selective_out_of_order_gives_no_answer(void)
{
    /* 40 42 41 43 */
    lss_u32(0x40, 0x24EU);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_NONE();
    /* without 40 */
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_NONE();
    /* 41 repeated */
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_NONE();
    TEST_ASSERT_FALSE(answers_inquire_node_id(0x05));
    /* a good sequence afterwards works */
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_LSS(0x44, 0, 0, 0, 0, 0, 0, 0);
}

static void selective_wrong_vendor_product_revision(void)
{
    const uint32_t good[4] = {0x24EU, 0x1234U, 0x00010002UL, 0x00ABCDEFUL};
    for (uint8_t wrong = 0U; wrong < 4U; wrong++) {
        for (uint8_t i = 0U; i < 4U; i++) {
            lss_u32((uint8_t)(0x40U + i), i == wrong ? good[i] ^ 0x100U : good[i]);
        }
        EXPECT_NONE();
        TEST_ASSERT_FALSE(answers_inquire_node_id(0x05));
    }
}

/* A wrong number ends its sequence; a new one started at 0x40 at any point is taken. */
static void selective_wrong_number_then_a_new_sequence(void)
{
    lss_u32(0x40, 0x24FU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_NONE();
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1235U);
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_LSS(0x44, 0, 0, 0, 0, 0, 0, 0);
}

static void selective_ignored_in_configuration(void)
{
    to_configuration();
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_NONE();
}

static void configuration_services_ignored_in_waiting(void)
{
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x13, 0x00, 0x03, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x15, 0x0A, 0x00, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_NONE();
    for (uint8_t cs = 0x5AU; cs <= 0x5EU; cs++) {
        LSS_IN(cs, 0, 0, 0, 0, 0, 0, 0);
        EXPECT_NONE();
    }
    TEST_ASSERT_EQUAL_HEX8(0x05, fx.node.lss.pending_node_id);
    TEST_ASSERT_EQUAL_UINT8(4U, fx.node.lss.pending_bit_timing);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.nvm[CO_NVM_LSS].commits);
    fx_advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.bit_rate_calls);
    /* not even a silence: a heartbeat goes out normally */
    TEST_ASSERT_EQUAL_UINT32(0U, fx_sdo_write_u32(0x1017, 0, 10U, 2U));
    fake_port_clear(&fx.port);
    fx_advance(10000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U));
    /* a later NMT reset keeps the ID */
    fake_port_clear(&fx.port);
    RX(0x000, 0x82, 0x05);
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
}

static void lss_works_in_stopped_and_operational(void)
{
    RX(0x000, 0x02, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_STOPPED, co_node_state(&fx.node));
    to_configuration();
    LSS_IN(0x5E, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5E, 0x05, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x11, 0x0B, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    to_waiting();
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_LSS(0x44, 0, 0, 0, 0, 0, 0, 0);

    RX(0x000, 0x01, 0x05);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&fx.node));
    LSS_IN(0x5A, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x5A, 0x4E, 0x02, 0x00, 0x00, 0, 0, 0);
    LSS_IN(0x13, 0x00, 0x02, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    to_waiting();
    identify_remote(0x24EU, 0x1234U, 0U, 0xFFFFFFFFUL, 0U, 0xFFFFFFFFUL);
    EXPECT_LSS(0x4F, 0, 0, 0, 0, 0, 0, 0);
}

static void configure_node_id_range(void)
{
    to_configuration();
    LSS_IN(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x11, 0xFE, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0x05, fx.node.lss.pending_node_id);
    LSS_IN(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0x01, fx.node.lss.pending_node_id);
    LSS_IN(0x11, 0x7F, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0x7F, fx.node.lss.pending_node_id);
}

static void configure_node_id_ff_unconfigures_after_reset(void)
{
    to_configuration();
    LSS_IN(0x11, 0xFF, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0xFF, fx.node.lss.pending_node_id);
    to_waiting();
    EXPECT_NONE();
    TEST_ASSERT_EQUAL_HEX8(0x05, co_node_id(&fx.node));
    fake_port_clear(&fx.port);
    RX(0x000, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, fx.port.n_sent, "no boot-up once unconfigured");
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
    RX(0x605, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    EXPECT_NONE();
    LSS_IN(0x4C, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x50, 0, 0, 0, 0, 0, 0, 0);
}

static void configure_node_id_ff_refused_with_option(void)
{
    fx_start(5U, CO_OPT_LSS_NO_UNCONFIGURE);
    fake_port_clear(&fx.port);
    to_configuration();
    LSS_IN(0x11, 0xFF, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX8(0x05, fx.node.lss.pending_node_id);
    LSS_IN(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x01, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x11, 0x7F, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
}

static void bit_timing_default_table(void)
{
    /* CiA 305 v3: 0..8 except the reserved 5; 9 (auto detection) is not supported by the emulator */
    static const uint8_t err[12] = {0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1};
    to_configuration();
    for (uint8_t i = 0U; i < 12U; i++) {
        LSS_IN(0x13, 0x00, i, 0, 0, 0, 0, 0);
        EXPECT_LSS(0x13, err[i], 0, 0, 0, 0, 0, 0);
    }
    LSS_IN(0x13, 0x00, 0xFF, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x13, 0x80, 0x00, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(8U, fx.node.lss.pending_bit_timing); /* the last accepted */
}

static const uint16_t buerkert_like[CO_LSS_BIT_TIMING_COUNT] = {1000U, 0U, 500U, 250U, 125U, 100U, 50U, 20U, 10U, 0U};

static void bit_timing_device_table(void)
{
    fx.cfg.bit_rates_kbit = buerkert_like;
    fx_power_cycle();
    fake_port_clear(&fx.port);
    to_configuration();
    LSS_IN(0x13, 0x00, 0x05, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x13, 0x00, 0x01, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x13, 0x00, 0x09, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT8(5U, fx.node.lss.pending_bit_timing);
    LSS_IN(0x15, 0x0A, 0x00, 0, 0, 0, 0, 0); /* 10 ms */
    fx_advance(10000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(100U, fx.port.bit_rate_kbit);
    fx_advance(10000U);
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x05));
}

static void store_configuration_survives_power_cycle(void)
{
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x13, 0x00, 0x03, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x13, 0x00, 0, 0, 0, 0, 0, 0);
    fx.n_events = 0U;
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    const int e = find_event(CO_EV_STORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.events[e].code);
    /* storing does not activate anything */
    TEST_ASSERT_EQUAL_HEX8(0x05, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.bit_rate_calls);

    fake_port_clear(&fx.port);
    fx_power_cycle();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(250U, fx.port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT8(3U, fx.node.lss.active_bit_timing);
    to_configuration();
    TEST_ASSERT_TRUE(answers_inquire_node_id(0x0A));
    /* a second power cycle still boots as 0x0A */
    fake_port_clear(&fx.port);
    fx_power_cycle();
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
}

static void stored_unconfigured_node_id_survives_power_cycle(void)
{
    to_configuration();
    LSS_IN(0x11, 0xFF, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    fake_port_clear(&fx.port);
    fx_power_cycle();
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
}

static void store_configuration_not_supported(void)
{
    fx.port.port.nvm_write = NULL;
    fx.port.port.nvm_commit = NULL;
    fx.port.port.nvm_read = NULL;
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.nvm[CO_NVM_LSS].commits);
}

static void store_configuration_media_error(void)
{
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    fx.port.nvm_fail_commit = true;
    fx.n_events = 0U;
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x02, 0, 0, 0, 0, 0, 0);
    const int e = find_event(CO_EV_STORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_UINT32(2U, fx.events[e].code);
    fx.port.nvm_fail_commit = false;
    fx.port.nvm_fail_write = true;
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x02, 0, 0, 0, 0, 0, 0);
    fx.port.nvm_fail_write = false;
    /* nothing was stored: the node boots with its configured ID */
    fake_port_clear(&fx.port);
    fx_power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
}

/* LSS store configuration is one store with the device's own data of it (co_node.h on_store): the hook sees
 * 0x7E5/0x17, its area goes first with CO_NVM_MORE, and a failure anywhere answers error 2 with nothing kept. */
static void store_configuration_includes_the_device_area(void)
{
    to_configuration();
    fx.store_device_area = true;
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX16(0x7E5U, fx.store_index);
    TEST_ASSERT_EQUAL_HEX8(0x17U, fx.store_sub);
    TEST_ASSERT_EQUAL_STRING("2+1.", fx.port.nvm_log);
    TEST_ASSERT_EQUAL_UINT32(4U, fx.port.nvm[CO_NVM_DEVICE].stored_len);

    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    fx.store_fail = true;
    fx.port.nvm_log[0] = '\0';
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x02, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("2+1x", fx.port.nvm_log);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.nvm[CO_NVM_LSS].commits);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.nvm[CO_NVM_DEVICE].commits);
    /* the node-ID of the failed store was not kept */
    fx.store_fail = false;
    fake_port_clear(&fx.port);
    fx_power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
}

static void damaged_lss_blob_ignored(void)
{
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    fx.port.nvm[CO_NVM_LSS].stored[4] ^= 0x01U; /* node-ID byte: CRC no longer matches */
    fake_port_clear(&fx.port);
    fx_power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
}

static void fastscan_full_scan_finds_identity(void)
{
    /* The master's algorithm of python-canopen (LssMaster.fast_scan): bit by bit from bit 31. */
    fx_start(0xFFU, 0U);
    uint32_t id[4] = {0U, 0U, 0U, 0U};
    uint8_t sub = 0U;
    uint8_t next = 0U;
    TEST_ASSERT_TRUE(fastscan(0U, 0x80U, 0U, 0U));
    while (sub < 4U) {
        for (int bit = 31; bit >= 0; bit--) {
            if (!fastscan(id[sub], (uint8_t)bit, sub, next)) {
                id[sub] |= (uint32_t)1U << (uint32_t)bit;
            }
        }
        next = (uint8_t)((sub + 1U) & 3U);
        TEST_ASSERT_TRUE_MESSAGE(fastscan(id[sub], 0U, sub, next), "confirmation not acknowledged");
        sub++;
    }
    TEST_ASSERT_EQUAL_HEX32(0x0000024EUL, id[0]);
    TEST_ASSERT_EQUAL_HEX32(0x00001234UL, id[1]);
    TEST_ASSERT_EQUAL_HEX32(0x00010002UL, id[2]);
    TEST_ASSERT_EQUAL_HEX32(0x00ABCDEFUL, id[3]);
    TEST_ASSERT_TRUE(answers_inquire_node_id(0xFF)); /* in configuration */
    /* once in configuration, fastscan is not answered */
    TEST_ASSERT_FALSE(fastscan(0U, 0x80U, 0U, 0U));
}

static void fastscan_invalid_frames_ignored(void)
{
    fx_start(0xFFU, 0U);
    TEST_ASSERT_TRUE(fastscan(0U, 0x80U, 0U, 0U));
    TEST_ASSERT_FALSE(fastscan(0x24EU, 32U, 0U, 0U));   /* BitChecked 32..0x7F */
    TEST_ASSERT_FALSE(fastscan(0x24EU, 0x7FU, 0U, 0U));
    TEST_ASSERT_FALSE(fastscan(0x24EU, 0x81U, 0U, 0U)); /* > 0x80 */
    TEST_ASSERT_FALSE(fastscan(0x24EU, 0U, 4U, 0U));    /* LSSSub > 3 */
    TEST_ASSERT_FALSE(fastscan(0x24EU, 0U, 0U, 4U));    /* LSSNext > 3 */
    TEST_ASSERT_FALSE(fastscan(0x1234U, 0U, 1U, 2U));   /* not the slave's position (0) */
    TEST_ASSERT_FALSE(fastscan(0x24FU, 0U, 0U, 1U));    /* mismatch */
    TEST_ASSERT_FALSE(fastscan(0x0000034EU, 8U, 0U, 0U)); /* bits 31..8 differ */
    TEST_ASSERT_TRUE(fastscan(0x000002FFU, 8U, 0U, 0U));  /* bits 7..0 not compared */
    /* none of those moved the position: the good sequence still works */
    TEST_ASSERT_TRUE(fastscan(0x24EU, 0U, 0U, 1U));
    TEST_ASSERT_TRUE(fastscan(0x1234U, 0U, 1U, 2U));
    TEST_ASSERT_TRUE(fastscan(0x00010002UL, 0U, 2U, 3U));
    TEST_ASSERT_TRUE(fastscan(0x00ABCDEFUL, 0U, 3U, 0U));
    TEST_ASSERT_TRUE(answers_inquire_node_id(0xFF));
}

static void fastscan_reset_restarts_position(void)
{
    fx_start(0xFFU, 0U);
    TEST_ASSERT_TRUE(fastscan(0U, 0x80U, 0U, 0U));
    TEST_ASSERT_TRUE(fastscan(0x24EU, 0U, 0U, 1U));
    TEST_ASSERT_TRUE(fastscan(0U, 0x80U, 0U, 0U));      /* back to LSSSub 0 */
    TEST_ASSERT_FALSE(fastscan(0x1234U, 0U, 1U, 2U));
    TEST_ASSERT_TRUE(fastscan(0x24EU, 0U, 0U, 1U));
    TEST_ASSERT_TRUE(fastscan(0x1234U, 0U, 1U, 2U));
}

static void unconfigured_switch_to_waiting_without_id_stays_silent(void)
{
    fx_start(0xFFU, 0U);
    to_configuration();
    to_waiting();
    EXPECT_NONE();
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
    /* configuring 0xFF again changes nothing either */
    to_configuration();
    LSS_IN(0x11, 0xFF, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    to_waiting();
    EXPECT_NONE();
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
}

static void unconfigured_node_id_lost_without_store(void)
{
    fx_start(0xFFU, 0U);
    to_configuration();
    LSS_IN(0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    to_waiting();
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    fake_port_clear(&fx.port);
    fx_power_cycle();
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0xFF, co_node_id(&fx.node));
}

static void unconfigured_node_configured_by_selective_and_stored(void)
{
    fx_start(0xFFU, 0U);
    lss_u32(0x40, 0x24EU);
    lss_u32(0x41, 0x1234U);
    lss_u32(0x42, 0x00010002UL);
    lss_u32(0x43, 0x00ABCDEFUL);
    EXPECT_LSS(0x44, 0, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x11, 0x20, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x11, 0x00, 0, 0, 0, 0, 0, 0);
    LSS_IN(0x17, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_LSS(0x17, 0x00, 0, 0, 0, 0, 0, 0);
    to_waiting();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x720U, 1, 0x00);
    fake_port_clear(&fx.port);
    fx_power_cycle();
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x720U, 1, 0x00);
}

static void lss_frames_with_rtr_or_extended_id_ignored(void)
{
    to_configuration();
    fake_port_clear(&fx.port);
    const co_frame_t rtr = {0x7E5U, 8U, CO_FRAME_RTR, {0x5E, 0, 0, 0, 0, 0, 0, 0}};
    co_node_rx(&fx.node, &rtr, fx.now);
    const co_frame_t ext = {0x7E5U, 8U, CO_FRAME_EFF, {0x5E, 0, 0, 0, 0, 0, 0, 0}};
    co_node_rx(&fx.node, &ext, fx.now);
    (void)fx_process();
    EXPECT_NONE();
}

static void api_pending_bit_timing_and_store(void)
{
    TEST_ASSERT_FALSE(co_lss_set_pending_bit_timing(&fx.node, 5U));  /* not in the CiA 305 table */
    TEST_ASSERT_FALSE(co_lss_set_pending_bit_timing(&fx.node, 10U));
    TEST_ASSERT_TRUE(co_lss_set_pending_bit_timing(&fx.node, 3U));
    TEST_ASSERT_TRUE(co_lss_set_pending_node_id(&fx.node, 0x0BU));
    TEST_ASSERT_EQUAL_INT(CO_OK, co_lss_store(&fx.node));
    TEST_ASSERT_EQUAL_HEX8(5U, co_node_id(&fx.node)); /* pending until the next reset */
    fx_power_cycle();
    TEST_ASSERT_EQUAL_HEX8(0x0BU, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_UINT8(3U, fx.node.lss.active_bit_timing);
    TEST_ASSERT_EQUAL_UINT32(250U, fx.port.bit_rate_kbit); /* applied through the port at power-on */
    TEST_ASSERT_TRUE(co_lss_set_pending_bit_timing(&fx.node, 6U));
    const uint32_t calls = fx.port.bit_rate_calls;
    TEST_ASSERT_EQUAL_INT(CO_OK, co_lss_apply_bit_timing(&fx.node));
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, fx.port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(50U, fx.port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT8(6U, fx.node.lss.active_bit_timing);
    co_port_t no_nvm = fx.port.port;
    no_nvm.nvm_write = NULL;
    fx.node.port = &no_nvm;
    TEST_ASSERT_EQUAL_INT(CO_ERR_IO, co_lss_store(&fx.node));
    fx.node.port = &fx.port.port;
}

static void stored_bit_timing_out_of_range_is_not_used(void)
{
    /* found by fuzzing: a CRC-valid LSS blob with bit timing 200 indexed past the rate table */
    uint8_t b[12] = {'C', 'O', 'L', '1', 0x0A, 200U, 0, 0, 0, 0, 0, 0};
    const uint32_t crc = co_crc32(0U, b, 8U);
    b[8] = (uint8_t)crc;
    b[9] = (uint8_t)(crc >> 8);
    b[10] = (uint8_t)(crc >> 16);
    b[11] = (uint8_t)(crc >> 24);
    memcpy(fx.port.nvm[CO_NVM_LSS].stored, b, sizeof b);
    fx.port.nvm[CO_NVM_LSS].stored_len = sizeof b;
    const uint32_t calls = fx.port.bit_rate_calls;
    fx_power_cycle();
    TEST_ASSERT_EQUAL_HEX8(5U, co_node_id(&fx.node)); /* the blob is not ours: the configured ID */
    TEST_ASSERT_EQUAL_UINT8(4U, fx.node.lss.active_bit_timing);
    TEST_ASSERT_EQUAL_UINT32(calls, fx.port.bit_rate_calls);
}

static void queued_frames_wait_for_the_end_of_the_silence(void)
{
    /* found by fuzzing: a frame waiting for a busy port went out during the bit-rate switch silence */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x13, 0x00, 0x03, 0, 0, 0, 0, 0);
    fake_port_clear(&fx.port);
    fx.port.busy_count = 2U;
    RX(0x7E5, 0x5E, 0, 0, 0, 0, 0, 0, 0); /* answer queued: the port is busy */
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    RX(0x7E5, 0x15, 0x64, 0x00, 0, 0, 0, 0, 0); /* activate: switch at +100 ms, silent until +200 ms */
    const co_time_us_t t0 = fx.now;
    fx_advance(199999U);
    TEST_ASSERT_EQUAL_UINT32(0U, fx.port.n_sent);
    fx_advance(1U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    TEST_ASSERT_EQUAL_UINT64(t0 + 200000U, fx.port.sent_at[0]);
    ASSERT_FRAME(0, 0x7E4U, 8, 0x5E, 0x05, 0, 0, 0, 0, 0, 0);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v57_inquire_node_id_ignored_in_waiting);
    RUN_TEST(v58_switch_global_to_configuration);
    RUN_TEST(v59_inquire_node_id);
    RUN_TEST(v60_inquire_vendor);
    RUN_TEST(v61_inquire_serial);
    RUN_TEST(v62_configure_node_id);
    RUN_TEST(v63_configure_node_id_out_of_range);
    RUN_TEST(v64_configure_bit_timing);
    RUN_TEST(v65_configure_bit_timing_reserved_index);
    RUN_TEST(v66_configure_bit_timing_other_selector);
    RUN_TEST(v67_activate_bit_timing);
    RUN_TEST(v68_store_configuration);
    RUN_TEST(v69_node_id_pending_until_reset_communication);
    RUN_TEST(pending_node_id_adopted_by_reset_node);
    RUN_TEST(v70_switch_state_selective);
    RUN_TEST(v71_switch_state_selective_wrong_serial);
    RUN_TEST(v72_identify_non_configured);
    RUN_TEST(v73_identify_remote_slave);
    RUN_TEST(v74_fastscan_reset);
    RUN_TEST(v75_fastscan_confirm_all_four);
    RUN_TEST(v76_configured_unconfigured_node_boots_by_itself);
    RUN_TEST(v77_unconfigured_node_runs_lss_only);
    RUN_TEST(v78_fastscan_ignored_by_configured_node);
    RUN_TEST(v79_wrong_dlc_ignored);
    RUN_TEST(identify_non_configured_silent_when_configured);
    RUN_TEST(identify_remote_slave_mismatch_is_silent);
    RUN_TEST(inquire_product_and_revision);
    RUN_TEST(switch_global_back_to_waiting_and_bad_mode);
    RUN_TEST(selective_out_of_order_gives_no_answer);
    RUN_TEST(selective_wrong_vendor_product_revision);
    RUN_TEST(selective_wrong_number_then_a_new_sequence);
    RUN_TEST(selective_ignored_in_configuration);
    RUN_TEST(configuration_services_ignored_in_waiting);
    RUN_TEST(lss_works_in_stopped_and_operational);
    RUN_TEST(configure_node_id_range);
    RUN_TEST(configure_node_id_ff_unconfigures_after_reset);
    RUN_TEST(configure_node_id_ff_refused_with_option);
    RUN_TEST(bit_timing_default_table);
    RUN_TEST(bit_timing_device_table);
    RUN_TEST(store_configuration_survives_power_cycle);
    RUN_TEST(stored_unconfigured_node_id_survives_power_cycle);
    RUN_TEST(store_configuration_not_supported);
    RUN_TEST(store_configuration_media_error);
    RUN_TEST(damaged_lss_blob_ignored);
    RUN_TEST(fastscan_full_scan_finds_identity);
    RUN_TEST(fastscan_invalid_frames_ignored);
    RUN_TEST(fastscan_reset_restarts_position);
    RUN_TEST(unconfigured_switch_to_waiting_without_id_stays_silent);
    RUN_TEST(unconfigured_node_id_lost_without_store);
    RUN_TEST(unconfigured_node_configured_by_selective_and_stored);
    RUN_TEST(lss_frames_with_rtr_or_extended_id_ignored);
    RUN_TEST(api_pending_bit_timing_and_store);
    RUN_TEST(stored_bit_timing_out_of_range_is_not_used);
    RUN_TEST(queued_frames_wait_for_the_end_of_the_silence);
    RUN_TEST(store_configuration_includes_the_device_area);
    return UNITY_END();
}
