/* Multiplexed PDOs (CiA 301 MPDO): a SAM producer sending the object scanner list in turn, a DAM consumer and a
 * SAM consumer with the object dispatching list; frame layout address | index | sub-index | 4 data bytes. */
#include <stddef.h>
#include <string.h>

#include "fake_port.h"
#include "unity.h"

typedef struct mpdo_values {
    uint32_t device_type;
    uint8_t error_register;
    uint32_t sync_cob;
    uint8_t rpdo1_n;
    uint32_t rpdo1_cob;
    uint8_t rpdo1_type;
    uint8_t rpdo2_n;
    uint32_t rpdo2_cob;
    uint8_t rpdo2_type;
    uint8_t rmap1_n;
    uint32_t rmap1[1];
    uint8_t rmap2_n;
    uint32_t rmap2[1];
    uint8_t tpdo1_n;
    uint32_t tpdo1_cob;
    uint8_t tpdo1_type;
    uint16_t tpdo1_inhibit;
    uint16_t tpdo1_event;
    uint8_t tmap1_n;
    uint32_t tmap1[1];
    uint8_t scanner_n;
    uint32_t scanner[4];
    uint8_t dispatch_n;
    uint64_t dispatch[1];
    uint8_t x2000_n;
    uint16_t x2000_1;
    uint32_t x2000_2;
    uint8_t x2001;
    uint32_t x2002;
    uint8_t x2100_n;
    uint16_t x2100_1;
    uint32_t x2101;
} mpdo_values_t;

#define M(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((mpdo_values_t *)0)->m), offsetof(mpdo_values_t, m))
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)
static const co_od_entry_t entries[] = {
    M(0x1000, 0, CO_T_UNSIGNED32, RO, device_type),
    M(0x1001, 0, CO_T_UNSIGNED8, RO, error_register),
    M(0x1005, 0, CO_T_UNSIGNED32, RW, sync_cob),
    M(0x1400, 0, CO_T_UNSIGNED8, RO, rpdo1_n),
    M(0x1400, 1, CO_T_UNSIGNED32, RW, rpdo1_cob),
    M(0x1400, 2, CO_T_UNSIGNED8, RW, rpdo1_type),
    M(0x1401, 0, CO_T_UNSIGNED8, RO, rpdo2_n),
    M(0x1401, 1, CO_T_UNSIGNED32, RW, rpdo2_cob),
    M(0x1401, 2, CO_T_UNSIGNED8, RW, rpdo2_type),
    M(0x1600, 0, CO_T_UNSIGNED8, RW, rmap1_n),
    M(0x1600, 1, CO_T_UNSIGNED32, RW, rmap1[0]),
    M(0x1601, 0, CO_T_UNSIGNED8, RW, rmap2_n),
    M(0x1601, 1, CO_T_UNSIGNED32, RW, rmap2[0]),
    M(0x1800, 0, CO_T_UNSIGNED8, RO, tpdo1_n),
    M(0x1800, 1, CO_T_UNSIGNED32, RW, tpdo1_cob),
    M(0x1800, 2, CO_T_UNSIGNED8, RW, tpdo1_type),
    M(0x1800, 3, CO_T_UNSIGNED16, RW, tpdo1_inhibit),
    M(0x1800, 5, CO_T_UNSIGNED16, RW, tpdo1_event),
    M(0x1A00, 0, CO_T_UNSIGNED8, RW, tmap1_n),
    M(0x1A00, 1, CO_T_UNSIGNED32, RW, tmap1[0]),
    M(0x1FA0, 0, CO_T_UNSIGNED8, RW, scanner_n),
    M(0x1FA0, 1, CO_T_UNSIGNED32, RW, scanner[0]),
    M(0x1FA0, 2, CO_T_UNSIGNED32, RW, scanner[1]),
    M(0x1FA0, 3, CO_T_UNSIGNED32, RW, scanner[2]),
    M(0x1FA0, 4, CO_T_UNSIGNED32, RW, scanner[3]),
    M(0x1FD0, 0, CO_T_UNSIGNED8, RW, dispatch_n),
    M(0x1FD0, 1, CO_T_UNSIGNED64, RW, dispatch[0]),
    M(0x2000, 0, CO_T_UNSIGNED8, RO, x2000_n),
    M(0x2000, 1, CO_T_UNSIGNED16, RO | CO_OD_TPDO, x2000_1),
    M(0x2000, 2, CO_T_UNSIGNED32, RO | CO_OD_TPDO, x2000_2),
    M(0x2001, 0, CO_T_UNSIGNED8, RO | CO_OD_TPDO, x2001),
    M(0x2002, 0, CO_T_UNSIGNED32, RO, x2002), /* not mappable: skipped by the scanner */
    M(0x2100, 0, CO_T_UNSIGNED8, RO, x2100_n),
    M(0x2100, 1, CO_T_UNSIGNED16, RW | CO_OD_RPDO, x2100_1),
    M(0x2101, 0, CO_T_UNSIGNED32, RW | CO_OD_RPDO, x2101),
};

/* Producer 0x22's 0x2000:01 (one sub-index) is this node's 0x2100:01. */
#define DISPATCH_2000_01 ((1ULL << 56) | (0x2100ULL << 40) | (0x01ULL << 32) | (0x2000ULL << 16) | (0x01ULL << 8) | 0x22U)

static const mpdo_values_t defaults = {
    .device_type = 0x00000191UL,
    .sync_cob = 0x80UL,
    .rpdo1_n = 2U, .rpdo1_cob = 0x205UL, .rpdo1_type = 255U,
    .rpdo2_n = 2U, .rpdo2_cob = 0x305UL, .rpdo2_type = 255U,
    .rmap1_n = 0xFFU, /* DAM consumer */
    .rmap2_n = 0xFEU, /* SAM consumer */
    .tpdo1_n = 5U, .tpdo1_cob = 0x185UL, .tpdo1_type = 254U, .tpdo1_inhibit = 0U, .tpdo1_event = 100U,
    .tmap1_n = 0xFEU, /* SAM producer */
    /* 0x2000:01 and :02 (block of 2), 0x2002 (not mappable), 0x3000 (missing), then 0x2001 */
    .scanner_n = 4U, .scanner = {0x02200001UL, 0x00200200UL, 0x00300000UL, 0x00200100UL},
    .dispatch_n = 1U, .dispatch = {DISPATCH_2000_01},
    .x2000_n = 2U, .x2000_1 = 0x1234U, .x2000_2 = 0xA1B2C3D4UL, .x2001 = 0x5AU, .x2002 = 7U,
    .x2100_n = 1U,
};
static const co_od_t od = {.name = "mpdo", .entries = entries, .count = (uint16_t)(sizeof entries / sizeof entries[0]),
                           .defaults = &defaults, .values_size = (uint32_t)sizeof(mpdo_values_t),
                           .signature = 0x3DB0A11CUL};

static fake_port_t port;
static co_time_us_t now;
static co_node_t node;
static mpdo_values_t values;

static void rx(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f = {id, len, 0U, {0U}};
    memcpy(f.data, data, len);
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
}
#define RX(id, ...)                                                                                             \
    do {                                                                                                        \
        const uint8_t d_[] = {__VA_ARGS__};                                                                     \
        rx((id), (uint8_t)sizeof d_, d_);                                                                       \
    } while (0)

static void sync(void)
{
    const co_frame_t f = {0x080U, 0U, 0U, {0U}};
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
}

static void run_until(co_time_us_t t)
{
    while (now < t) {
        const co_time_us_t next = co_node_process(&node, now);
        now = next < t ? next : t;
    }
    (void)co_node_process(&node, now);
}

/* Frames with this COB-ID, in order, into out; returns how many. */
static uint32_t frames_of(uint32_t id, const co_frame_t **out, uint32_t cap)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < port.n_sent && n < cap; i++) {
        if (port.sent[i].id == id) {
            out[n++] = &port.sent[i];
        }
    }
    return n;
}

#define ASSERT_DATA(frame, ...)                                                                                 \
    do {                                                                                                        \
        const uint8_t e_[8] = {__VA_ARGS__};                                                                    \
        TEST_ASSERT_EQUAL_UINT8(8, (frame)->len);                                                               \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, (frame)->data, 8);                                                     \
    } while (0)

void setUp(void)
{
    now = 0U;
    memset(&values, 0, sizeof values);
    fake_port_init(&port, &now);
    const co_node_cfg_t cfg = {.od = &od, .values = &values, .port = &port.port, .port_ctx = &port, .node_id = 5U};
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&node, &cfg, now));
    fake_port_clear(&port);
    RX(0x000, 0x01, 0x05); /* Operational */
}
void tearDown(void) {}

static void sam_producer_sends_the_scanner_list_in_turn(void)
{
    run_until(350000U);
    const co_frame_t *f[8];
    TEST_ASSERT_EQUAL_UINT32(4U, frames_of(0x185U, f, 8U)); /* at 0 (entering Operational), 100, 200, 300 ms */
    ASSERT_DATA(f[0], 0x05, 0x00, 0x20, 0x01, 0x34, 0x12, 0x00, 0x00);
    ASSERT_DATA(f[1], 0x05, 0x00, 0x20, 0x02, 0xD4, 0xC3, 0xB2, 0xA1);
    ASSERT_DATA(f[2], 0x05, 0x01, 0x20, 0x00, 0x5A, 0x00, 0x00, 0x00); /* 0x2002 and 0x3000 skipped */
    ASSERT_DATA(f[3], 0x05, 0x00, 0x20, 0x01, 0x34, 0x12, 0x00, 0x00); /* the list wraps */
    TEST_ASSERT_EQUAL_UINT64(300000U, port.sent_at[f[3] - port.sent]);
    values.x2000_2 = 0x01020304UL;
    co_tpdo_trigger(&node, 0U); /* an application event sends the next object at once */
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(5U, frames_of(0x185U, f, 8U));
    ASSERT_DATA(f[4], 0x05, 0x00, 0x20, 0x02, 0x04, 0x03, 0x02, 0x01);
}

static void sam_producer_is_event_driven_only(void)
{
    RX(0x000, 0x80, 0x05);
    RX(0x605, 0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0x00, 0x80); /* invalid, then synchronous */
    RX(0x605, 0x2F, 0x00, 0x18, 0x02, 0x01, 0x00, 0x00, 0x00);
    RX(0x605, 0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0x00, 0x00);
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&port);
    sync();
    sync();
    const co_frame_t *f[4];
    TEST_ASSERT_EQUAL_UINT32(0U, frames_of(0x185U, f, 4U)); /* no MPDO on SYNC */
    RX(0x000, 0x80, 0x05);
    RX(0x605, 0x23, 0x00, 0x18, 0x01, 0x85, 0x01, 0x00, 0x80);
    RX(0x605, 0x2F, 0x00, 0x1A, 0x00, 0xFF, 0x00, 0x00, 0x00); /* DAM producer: a master's role, refused */
    TEST_ASSERT_EQUAL_UINT32(2U, frames_of(0x585U, f, 4U));
    ASSERT_DATA(f[1], 0x80, 0x00, 0x1A, 0x00, 0x42, 0x00, 0x04, 0x06);
}

static void dam_consumer_writes_the_object_it_is_sent(void)
{
    RX(0x205, 0x85, 0x01, 0x21, 0x00, 0x78, 0x56, 0x34, 0x12);
    TEST_ASSERT_EQUAL_HEX32(0x12345678UL, values.x2101);
    RX(0x205, 0x80, 0x01, 0x21, 0x00, 0x01, 0x00, 0x00, 0x00); /* to all nodes */
    TEST_ASSERT_EQUAL_HEX32(1UL, values.x2101);
    RX(0x205, 0x86, 0x01, 0x21, 0x00, 0x02, 0x00, 0x00, 0x00); /* to node 6 */
    RX(0x205, 0x22, 0x00, 0x20, 0x01, 0x03, 0x00, 0x00, 0x00); /* a SAM frame on the DAM RPDO (in the list) */
    TEST_ASSERT_EQUAL_HEX16(0x0000U, values.x2100_1);
    TEST_ASSERT_EQUAL_HEX32(1UL, values.x2101);
    fake_port_clear(&port);
    RX(0x205, 0x85, 0x02, 0x20, 0x00, 0x03, 0x00, 0x00, 0x00); /* 0x2002 cannot be mapped */
    RX(0x205, 0x85, 0x09, 0x30, 0x00, 0x03, 0x00, 0x00, 0x00); /* a second failure: no second EMCY */
    const co_frame_t *f[4];
    TEST_ASSERT_EQUAL_UINT32(1U, frames_of(0x085U, f, 4U));
    ASSERT_DATA(f[0], 0x30, 0x82, 0x11, 0x04, 0x00, 0x00, 0x00, 0x00); /* 0x8230 DAM-MPDO not processed */
    RX(0x205, 0x85, 0x01, 0x21, 0x00, 0x04, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX32(4UL, values.x2101);
    TEST_ASSERT_EQUAL_UINT32(2U, frames_of(0x085U, f, 4U));
    ASSERT_DATA(f[1], 0x00, 0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x00); /* error reset */
    RX(0x205, 0x85, 0x01, 0x21, 0x00, 0x05); /* shorter than 8 bytes: the RPDO length error */
    TEST_ASSERT_EQUAL_HEX32(4UL, values.x2101);
    TEST_ASSERT_EQUAL_UINT32(3U, frames_of(0x085U, f, 4U));
    ASSERT_DATA(f[2], 0x10, 0x82, 0x11, 0x04, 0x00, 0x00, 0x00, 0x00);
}

static void sam_consumer_follows_the_dispatching_list(void)
{
    RX(0x305, 0x22, 0x00, 0x20, 0x01, 0x34, 0x12, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX16(0x1234U, values.x2100_1);
    RX(0x305, 0x23, 0x00, 0x20, 0x01, 0x11, 0x11, 0x00, 0x00); /* another producer */
    RX(0x305, 0x22, 0x00, 0x20, 0x02, 0x22, 0x22, 0x00, 0x00); /* an object not in the list */
    RX(0x305, 0x85, 0x00, 0x21, 0x01, 0x33, 0x33, 0x00, 0x00); /* a DAM frame to this node on the SAM RPDO */
    TEST_ASSERT_EQUAL_HEX16(0x1234U, values.x2100_1);
    const co_frame_t *f[2];
    TEST_ASSERT_EQUAL_UINT32(0U, frames_of(0x085U, f, 2U)); /* ignored without an EMCY */
}

static void mapping_sub0_takes_the_mpdo_values(void)
{
    RX(0x000, 0x80, 0x05);
    RX(0x605, 0x23, 0x00, 0x14, 0x01, 0x05, 0x02, 0x00, 0x80); /* RPDO1 invalid */
    RX(0x605, 0x2F, 0x00, 0x16, 0x00, 0xFE, 0x00, 0x00, 0x00); /* DAM -> SAM consumer */
    TEST_ASSERT_EQUAL_HEX8(0x60, port.sent[port.n_sent - 1U].data[0]);
    RX(0x605, 0x23, 0x00, 0x14, 0x01, 0x05, 0x02, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x60, port.sent[port.n_sent - 1U].data[0]);
    RX(0x000, 0x01, 0x05);
    RX(0x205, 0x22, 0x00, 0x20, 0x01, 0x99, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX16(0x0099U, values.x2100_1);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(sam_producer_sends_the_scanner_list_in_turn);
    RUN_TEST(sam_producer_is_event_driven_only);
    RUN_TEST(dam_consumer_writes_the_object_it_is_sent);
    RUN_TEST(sam_consumer_follows_the_dispatching_list);
    RUN_TEST(mapping_sub0_takes_the_mpdo_values);
    return UNITY_END();
}
