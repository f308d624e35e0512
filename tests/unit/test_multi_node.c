/* Several nodes in one process: same device type sharing one const OD, and a different device type.
 * Nothing is shared between nodes but the const tables. */
#include <stddef.h>
#include <string.h>

#include "fake_port.h"
#include "test_od.h"
#include "unity.h"

/* Nodes of many_nodes_of_one_type: every node-ID. A RAM-constrained target build (tests/target/) may lower it. */
#ifndef TEST_MULTI_NODE_COUNT
#define TEST_MULTI_NODE_COUNT 127U
#endif
/* The node that answers the SDO request: 99, or the last node when there are fewer. */
#define TEST_MULTI_NODE_SDO_ID (TEST_MULTI_NODE_COUNT < 99U ? TEST_MULTI_NODE_COUNT : 99U)

/* A second, minimal device type: identity, heartbeat, one TPDO. */
typedef struct mini_values {
    uint32_t device_type;
    uint8_t error_register;
    uint16_t heartbeat;
    uint8_t id_n;
    uint32_t vendor;
    uint8_t tpdo_n;
    uint32_t tpdo_cob;
    uint8_t tpdo_type;
    uint8_t map_n;
    uint32_t map1;
    uint8_t input;
} mini_values_t;

#define M(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((mini_values_t *)0)->m), offsetof(mini_values_t, m))
static const co_od_entry_t mini_entries[] = {
    M(0x1000, 0, CO_T_UNSIGNED32, CO_OD_READ, device_type),
    M(0x1001, 0, CO_T_UNSIGNED8, CO_OD_READ, error_register),
    M(0x1017, 0, CO_T_UNSIGNED16, CO_OD_READ | CO_OD_WRITE, heartbeat),
    M(0x1018, 0, CO_T_UNSIGNED8, CO_OD_READ, id_n),
    M(0x1018, 1, CO_T_UNSIGNED32, CO_OD_READ, vendor),
    M(0x1800, 0, CO_T_UNSIGNED8, CO_OD_READ, tpdo_n),
    M(0x1800, 1, CO_T_UNSIGNED32, CO_OD_READ | CO_OD_NODEID, tpdo_cob),
    M(0x1800, 2, CO_T_UNSIGNED8, CO_OD_READ, tpdo_type),
    M(0x1A00, 0, CO_T_UNSIGNED8, CO_OD_READ, map_n),
    M(0x1A00, 1, CO_T_UNSIGNED32, CO_OD_READ, map1),
    M(0x6000, 0, CO_T_UNSIGNED8, CO_OD_READ | CO_OD_TPDO, input),
};
static const mini_values_t mini_defaults = {0x00000191UL, 0U, 50U, 1U, 0x39UL, 2U, 0x180UL, 255U, 1U, 0x60000008UL, 0U};
static const co_od_t mini_od = {.name = "mini", .entries = mini_entries,
                                .count = (uint16_t)(sizeof mini_entries / sizeof mini_entries[0]),
                                .defaults = &mini_defaults, .values_size = (uint32_t)sizeof(mini_values_t),
                                .signature = 0x12345678UL};

/* One bus: every node's port records into the same fake port; frames are delivered to all nodes. */
static fake_port_t bus;
static co_time_us_t now;
/* The three nodes of most tests, and every node of many_nodes_of_one_type (setUp starts the first three again). */
#define NODE_SLOTS (TEST_MULTI_NODE_COUNT > 3U ? TEST_MULTI_NODE_COUNT : 3U)
static co_node_t node[NODE_SLOTS];
static test_od_values_t values_a, values_b;
static mini_values_t values_c;

static void deliver(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f = {id, len, 0U, {0U}};
    memcpy(f.data, data, len);
    for (size_t i = 0U; i < 3U; i++) {
        co_node_rx(&node[i], &f, now);
        (void)co_node_process(&node[i], now);
    }
}

static void start_node(size_t i, const co_od_t *od, void *values, uint8_t id)
{
    const co_node_cfg_t cfg = {.od = od, .values = values, .port = &bus.port, .port_ctx = &bus, .node_id = id, .bit_timing = 4U};
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&node[i], &cfg, now));
}

void setUp(void)
{
    now = 0U;
    fake_port_init(&bus, &now);
    start_node(0U, &test_od, &values_a, 5U);
    start_node(1U, &test_od, &values_b, 6U);
    start_node(2U, &mini_od, &values_c, 7U);
}
void tearDown(void) {}

static void each_node_boots_with_its_own_id(void)
{
    TEST_ASSERT_EQUAL_UINT32(3U, bus.n_sent);
    TEST_ASSERT_EQUAL_HEX32(0x705U, bus.sent[0].id);
    TEST_ASSERT_EQUAL_HEX32(0x706U, bus.sent[1].id);
    TEST_ASSERT_EQUAL_HEX32(0x707U, bus.sent[2].id);
    TEST_ASSERT_EQUAL_HEX32(0x185U, values_a.tpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_HEX32(0x186U, values_b.tpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_HEX32(0x187U, values_c.tpdo_cob);
}

static void values_are_per_node(void)
{
    const uint8_t w[8] = {0x2B, 0x00, 0x20, 0x00, 0xE8, 0x03, 0, 0};
    deliver(0x605U, 8U, w);
    TEST_ASSERT_EQUAL_UINT16(1000U, values_a.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_UINT16(500U, values_b.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0x585U, bus.sent[bus.n_sent - 1U].id);
    TEST_ASSERT_EQUAL_UINT32(4U, bus.n_sent); /* only node 5 answered */
}

static void nmt_addressed_and_broadcast(void)
{
    const uint8_t start6[2] = {0x01, 0x06};
    deliver(0x000U, 2U, start6);
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&node[0]));
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_OPERATIONAL, co_node_state(&node[1]));
    TEST_ASSERT_EQUAL_HEX8(CO_NMT_PRE_OPERATIONAL, co_node_state(&node[2]));
    const uint8_t stop_all[2] = {0x02, 0x00};
    deliver(0x000U, 2U, stop_all);
    for (size_t i = 0U; i < 3U; i++) {
        TEST_ASSERT_EQUAL_HEX8(CO_NMT_STOPPED, co_node_state(&node[i]));
    }
}

static void timers_are_per_node(void)
{
    /* node 7 (mini) has a 50 ms heartbeat by default; the others none */
    bus.n_sent = 0U;
    for (now = 0U; now <= 200000U; now += 1000U) {
        for (size_t i = 0U; i < 3U; i++) {
            (void)co_node_process(&node[i], now);
        }
    }
    TEST_ASSERT_EQUAL_UINT32(4U, bus.n_sent);
    for (uint32_t i = 0U; i < bus.n_sent; i++) {
        TEST_ASSERT_EQUAL_HEX32(0x707U, bus.sent[i].id);
        TEST_ASSERT_EQUAL_UINT64(50000U * (i + 1U), bus.sent_at[i]);
    }
}

static void emcy_of_one_node_stays_there(void)
{
    (void)co_emcy_raise(&node[1], 0x5000U, 0x01U, NULL);
    TEST_ASSERT_EQUAL_HEX8(0x01, values_b.x1001_error_register);
    TEST_ASSERT_EQUAL_HEX8(0x00, values_a.x1001_error_register);
    TEST_ASSERT_FALSE(co_emcy_is_active(&node[0], 0x5000U));
    TEST_ASSERT_TRUE(co_emcy_is_active(&node[1], 0x5000U));
}

static void many_nodes_of_one_type(void)
{
    co_node_t *nodes = node;
    static test_od_values_t vals[TEST_MULTI_NODE_COUNT];
    bus.n_sent = 0U;
    for (uint8_t i = 0U; i < TEST_MULTI_NODE_COUNT; i++) {
        const co_node_cfg_t cfg = {.od = &test_od, .values = &vals[i], .port = &bus.port, .port_ctx = &bus, .node_id = (uint8_t)(i + 1U), .bit_timing = 4U};
        TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&nodes[i], &cfg, now));
    }
    TEST_ASSERT_EQUAL_UINT32(TEST_MULTI_NODE_COUNT, bus.n_sent);
    const co_frame_t read = {0x600U + TEST_MULTI_NODE_SDO_ID, 8U, 0U, {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0}};
    for (uint8_t i = 0U; i < TEST_MULTI_NODE_COUNT; i++) {
        co_node_rx(&nodes[i], &read, now);
    }
    TEST_ASSERT_EQUAL_UINT32(TEST_MULTI_NODE_COUNT + 1U, bus.n_sent);
    TEST_ASSERT_EQUAL_HEX32(0x580U + TEST_MULTI_NODE_SDO_ID, bus.sent[TEST_MULTI_NODE_COUNT].id);
}

/* A device without 0x100C/0x100D (heartbeat only, like the Eltex devices) does not answer a guard request even
 * with its heartbeat off; a device with them does. */
static void guard_request_answered_only_by_a_device_with_node_guarding(void)
{
    values_c.heartbeat = 0U; /* mini: no 0x100C/0x100D */
    bus.n_sent = 0U;
    const co_frame_t rtr7 = {0x707U, 0U, CO_FRAME_RTR, {0U}};
    co_node_rx(&node[2], &rtr7, now);
    (void)co_node_process(&node[2], now);
    TEST_ASSERT_EQUAL_UINT32(0U, bus.n_sent);
    const co_frame_t rtr5 = {0x705U, 0U, CO_FRAME_RTR, {0U}};
    co_node_rx(&node[0], &rtr5, now); /* the test OD has them, heartbeat off by default */
    (void)co_node_process(&node[0], now);
    TEST_ASSERT_EQUAL_UINT32(1U, bus.n_sent);
    TEST_ASSERT_EQUAL_HEX32(0x705U, bus.sent[0].id);
    TEST_ASSERT_EQUAL_HEX8(0x7F, bus.sent[0].data[0]);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(each_node_boots_with_its_own_id);
    RUN_TEST(values_are_per_node);
    RUN_TEST(nmt_addressed_and_broadcast);
    RUN_TEST(timers_are_per_node);
    RUN_TEST(emcy_of_one_node_stays_there);
    RUN_TEST(many_nodes_of_one_type);
    RUN_TEST(guard_request_answered_only_by_a_device_with_node_guarding);
    return UNITY_END();
}
