/* Additional SDO servers (CiA 301: server SDO parameters 0x1201..0x127F): each object is one more server with
 * its own COB-IDs and transfer state, valid only while both COB-IDs are, with the COB-ID rules of CiA 301. */
#include <stddef.h>
#include <string.h>

#include "fake_port.h"
#include "unity.h"

typedef struct channels_values {
    uint32_t device_type;
    uint8_t error_register;
    uint8_t store_n;
    uint32_t store_all;
    uint8_t s0_n;
    uint32_t s0_cob[2];
    uint8_t s1_n;
    uint32_t s1_cob[2];
    uint8_t s1_client;
    uint8_t s2_n;
    uint32_t s2_cob[2];
    uint32_t value;
    char text[20];
    uint8_t text_len[CO_OD_LEN_SIZE]; /* its length (co_od.h) */
} channels_values_t;

#define C(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((channels_values_t *)0)->m), offsetof(channels_values_t, m))
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)
#define RWS (CO_OD_READ | CO_OD_WRITE | CO_OD_STORE)
static const co_od_entry_t entries[] = {
    C(0x1000, 0, CO_T_UNSIGNED32, RO, device_type),
    C(0x1001, 0, CO_T_UNSIGNED8, RO, error_register),
    C(0x1010, 0, CO_T_UNSIGNED8, RO, store_n),
    C(0x1010, 1, CO_T_UNSIGNED32, RW, store_all),
    C(0x1200, 0, CO_T_UNSIGNED8, RO, s0_n),
    C(0x1200, 1, CO_T_UNSIGNED32, RO | CO_OD_NODEID, s0_cob[0]),
    C(0x1200, 2, CO_T_UNSIGNED32, RO | CO_OD_NODEID, s0_cob[1]),
    C(0x1201, 0, CO_T_UNSIGNED8, RO, s1_n),
    C(0x1201, 1, CO_T_UNSIGNED32, RWS, s1_cob[0]),
    C(0x1201, 2, CO_T_UNSIGNED32, RWS, s1_cob[1]),
    C(0x1201, 3, CO_T_UNSIGNED8, RWS, s1_client),
    C(0x1203, 0, CO_T_UNSIGNED8, RO, s2_n), /* 0x1202 left out: servers need not be contiguous */
    C(0x1203, 1, CO_T_UNSIGNED32, RWS, s2_cob[0]),
    C(0x1203, 2, CO_T_UNSIGNED32, RWS, s2_cob[1]),
    C(0x2000, 0, CO_T_UNSIGNED32, RW, value),
    C(0x2001, 0, CO_T_VISIBLE_STRING, RW, text),
};
static const channels_values_t defaults = {
    0x00000191UL, 0U, 1U, 1U, 2U, {0x600UL, 0x580UL}, 3U, {0x80000000UL, 0x80000000UL}, 0U,
    2U, {0x6C1UL, 0x6D1UL}, 0x11223344UL, "two servers", {11U, 0U}};
static const co_od_t od = {.name = "channels", .entries = entries,
                           .count = (uint16_t)(sizeof entries / sizeof entries[0]), .defaults = &defaults,
                           .values_size = (uint32_t)sizeof(channels_values_t), .signature = 0x5D0C4A11UL};

static fake_port_t port;
static co_time_us_t now;
static co_node_t node;
static channels_values_t values;
static co_sdo_server_t servers[2];

static void start(uint8_t capacity, uint32_t options)
{
    const co_node_cfg_t cfg = {.od = &od, .values = &values, .port = &port.port, .port_ctx = &port, .node_id = 5U,
                               .options = options, .sdo_servers = servers, .sdo_server_count = capacity};
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&node, &cfg, now));
    fake_port_clear(&port);
}

void setUp(void)
{
    now = 0U;
    memset(&values, 0, sizeof values);
    fake_port_init(&port, &now);
    start(2U, CO_OPT_SDO_SEGMENTED);
}
void tearDown(void) {}

static void request(uint32_t id, const uint8_t req[8])
{
    co_frame_t f = {id, 8U, 0U, {0U}};
    memcpy(f.data, req, 8U);
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
}

#define REQ(id, ...)                                                                                            \
    do {                                                                                                        \
        const uint8_t r_[8] = {__VA_ARGS__};                                                                    \
        request((id), r_);                                                                                      \
    } while (0)
#define LAST(id_, ...)                                                                                          \
    do {                                                                                                        \
        const uint8_t e_[8] = {__VA_ARGS__};                                                                    \
        TEST_ASSERT_TRUE_MESSAGE(port.n_sent > 0U, "no frame");                                                 \
        TEST_ASSERT_EQUAL_HEX32((id_), port.sent[port.n_sent - 1U].id);                                         \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, port.sent[port.n_sent - 1U].data, 8);                                  \
    } while (0)

static void a_server_whose_cob_ids_are_valid_answers_on_them(void)
{
    REQ(0x6C1, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0); /* 0x1203 is valid from its defaults */
    LAST(0x6D1, 0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    REQ(0x6C2, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0); /* 0x1201 is not valid: nobody answers */
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
}

static void configuring_a_server_by_sdo(void)
{
    REQ(0x605, 0x23, 0x01, 0x12, 0x02, 0xD2, 0x06, 0x00, 0x00); /* tx 0x6D2, still not valid: rx invalid */
    LAST(0x585, 0x60, 0x01, 0x12, 0x02, 0, 0, 0, 0);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC2, 0x06, 0x00, 0x00); /* rx 0x6C2: now both valid */
    LAST(0x585, 0x60, 0x01, 0x12, 0x01, 0, 0, 0, 0);
    REQ(0x6C2, 0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x6D2, 0x43, 0x00, 0x20, 0x00, 0x44, 0x33, 0x22, 0x11);
    /* CiA 301: a valid COB-ID's CAN-ID changes only through "not valid"; 29-bit and restricted IDs refused */
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC3, 0x06, 0x00, 0x00);
    LAST(0x585, 0x80, 0x01, 0x12, 0x01, 0x30, 0x00, 0x09, 0x06);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC2, 0x06, 0x00, 0x20);
    LAST(0x585, 0x80, 0x01, 0x12, 0x01, 0x30, 0x00, 0x09, 0x06);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC2, 0x06, 0x00, 0x80); /* not valid: the server stops */
    LAST(0x585, 0x60, 0x01, 0x12, 0x01, 0, 0, 0, 0);
    const uint32_t sent = port.n_sent;
    REQ(0x6C2, 0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(sent, port.n_sent);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0x10, 0x06, 0x00, 0x00); /* 0x610: another node's default SDO */
    LAST(0x585, 0x80, 0x01, 0x12, 0x01, 0x30, 0x00, 0x09, 0x06);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC3, 0x06, 0x00, 0x40); /* bit 30 "dynamic" is kept */
    LAST(0x585, 0x60, 0x01, 0x12, 0x01, 0, 0, 0, 0);
    REQ(0x6C3, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    LAST(0x6D2, 0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x00, 0x00);
    REQ(0x605, 0x23, 0x00, 0x12, 0x01, 0xC4, 0x06, 0x00, 0x00); /* the default server's COB-IDs are fixed */
    LAST(0x585, 0x80, 0x00, 0x12, 0x01, 0x02, 0x00, 0x01, 0x06);
}

/* Each server has its own transfer: a segmented download on one and requests on another do not disturb it. */
static void servers_keep_their_own_transfers(void)
{
    REQ(0x605, 0x21, 0x01, 0x20, 0x00, 9, 0, 0, 0);
    LAST(0x585, 0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x6C1, 0x21, 0x01, 0x20, 0x00, 3, 0, 0, 0);
    LAST(0x6D1, 0x60, 0x01, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x605, 0x00, 'd', 'e', 'f', 'a', 'u', 'l', 't');
    LAST(0x585, 0x20, 0, 0, 0, 0, 0, 0, 0);
    REQ(0x6C1, 0x09, 'x', 'y', 'z', 0, 0, 0, 0);
    LAST(0x6D1, 0x20, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("xyz", values.text);
    REQ(0x605, 0x1B, '-', '1', 0, 0, 0, 0, 0);
    LAST(0x585, 0x30, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("default-1", values.text);
    REQ(0x6C1, 0x21, 0x01, 0x20, 0x00, 3, 0, 0, 0);
    now += 1000000U;
    (void)co_node_process(&node, now); /* the timeout of that server alone */
    LAST(0x6D1, 0x80, 0x01, 0x20, 0x00, 0x00, 0x00, 0x04, 0x05);
}

static void stored_cob_ids_come_back_after_a_power_cycle_and_a_reset(void)
{
    REQ(0x605, 0x23, 0x01, 0x12, 0x02, 0xD2, 0x06, 0x00, 0x00);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC2, 0x06, 0x00, 0x00);
    REQ(0x605, 0x23, 0x10, 0x10, 0x01, 's', 'a', 'v', 'e');
    start(2U, CO_OPT_SDO_SEGMENTED); /* power cycle, same NVM */
    REQ(0x6C2, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    LAST(0x6D2, 0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x00, 0x00);
    REQ(0x605, 0x23, 0x01, 0x12, 0x01, 0xC2, 0x06, 0x00, 0x80);
    const co_frame_t reset = {0x000U, 2U, 0U, {0x82U, 0x05U}};
    co_node_rx(&node, &reset, now); /* communication reset: the stored value again */
    fake_port_clear(&port);
    REQ(0x6C2, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    LAST(0x6D2, 0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x00, 0x00);
}

static void too_few_servers_for_the_dictionary_is_refused(void)
{
    const co_node_cfg_t cfg = {.od = &od, .values = &values, .port = &port.port, .port_ctx = &port, .node_id = 5U,
                               .sdo_servers = servers, .sdo_server_count = 1U};
    TEST_ASSERT_EQUAL_INT(CO_ERR_RANGE, co_node_init(&node, &cfg, now));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_server_whose_cob_ids_are_valid_answers_on_them);
    RUN_TEST(configuring_a_server_by_sdo);
    RUN_TEST(servers_keep_their_own_transfers);
    RUN_TEST(stored_cob_ids_come_back_after_a_power_cycle_and_a_reset);
    RUN_TEST(too_few_servers_for_the_dictionary_is_refused);
    return UNITY_END();
}
