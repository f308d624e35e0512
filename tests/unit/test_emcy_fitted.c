/* The core compiled with CO_CONFIG_EMCY_HISTORY 0 and CO_CONFIG_EMCY_INHIBIT 0 (what a fitted configuration chooses
 * for a dictionary without the pre-defined error field 0x1003 and the inhibit time 0x1015, the Bürkert's): errors
 * still set 0x1001 and go out as EMCY, at once one after the other, and nothing keeps a history; a dictionary that has
 * 0x1003 or 0x1015 is refused by co_node_init (a history that never fills, an inhibit time that changes nothing). */
#include <stddef.h>

#include "fake_port.h"
#include "unity.h"

#if CO_CONFIG_EMCY_HISTORY || CO_CONFIG_EMCY_INHIBIT
#error "this test is built against a core with CO_CONFIG_EMCY_HISTORY 0 and CO_CONFIG_EMCY_INHIBIT 0 (tests/CMakeLists.txt)"
#endif

/* A dictionary with EMCY (0x1001, 0x1014), without 0x1003 and 0x1015 (values for them: the refused variants). */
typedef struct plain_values {
    uint32_t device_type, identity[4], sdo_cob[2], emcy_cob, history[1];
    uint16_t producer_hb, inhibit;
    uint8_t error_register, identity_n, sdo_n, history_n;
} plain_values_t;

#define V plain_values_t
#define E(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m))
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)

#define PLAIN_UP_TO_1001                                                                                               \
    E(0x1000, 0x00, CO_T_UNSIGNED32, RO, device_type), E(0x1001, 0x00, CO_T_UNSIGNED8, RO, error_register)
#define PLAIN_1014 E(0x1014, 0x00, CO_T_UNSIGNED32, RW | CO_OD_NODEID, emcy_cob)
#define PLAIN_REST                                                                                                     \
    E(0x1017, 0x00, CO_T_UNSIGNED16, RW, producer_hb),                                                                 \
    E(0x1018, 0x00, CO_T_UNSIGNED8, RO, identity_n),                                                                   \
    E(0x1018, 0x01, CO_T_UNSIGNED32, RO, identity[0]),                                                                 \
    E(0x1018, 0x02, CO_T_UNSIGNED32, RO, identity[1]),                                                                 \
    E(0x1018, 0x03, CO_T_UNSIGNED32, RO, identity[2]),                                                                 \
    E(0x1018, 0x04, CO_T_UNSIGNED32, RO, identity[3]),                                                                 \
    E(0x1200, 0x00, CO_T_UNSIGNED8, RO, sdo_n),                                                                        \
    E(0x1200, 0x01, CO_T_UNSIGNED32, RO | CO_OD_NODEID, sdo_cob[0]),                                                   \
    E(0x1200, 0x02, CO_T_UNSIGNED32, RO | CO_OD_NODEID, sdo_cob[1])

static const co_od_entry_t plain_rows[] = {PLAIN_UP_TO_1001, PLAIN_1014, PLAIN_REST};

/* Node-ID-relative COB-IDs without the ID (the generator's convention). */
static const plain_values_t plain_defaults = {
    .device_type = 0x191U, .identity = {0xABCU, 1U, 2U, 3U}, .sdo_cob = {0x600U, 0x580U}, .emcy_cob = 0x80U,
    .identity_n = 4U, .sdo_n = 2U,
};

static const co_od_t plain_od = {.name = "plain", .entries = plain_rows,
                                 .count = (uint16_t)(sizeof plain_rows / sizeof plain_rows[0]),
                                 .defaults = &plain_defaults, .values_size = (uint32_t)sizeof(plain_values_t),
                                 .signature = 0x1EA9U, .defaults_size = (uint32_t)sizeof plain_defaults};

static co_time_us_t now;
static fake_port_t port;
static co_node_t node;
static plain_values_t values;

static co_node_cfg_t config(const co_od_t *od, void *vals) { return fake_port_node_cfg(&port, od, vals, 5U); }

void setUp(void)
{
    now = 1000U;
    fake_port_init(&port, &now);
    const co_node_cfg_t cfg = config(&plain_od, &values);
    TEST_ASSERT_EQUAL(CO_OK, co_node_init(&node, &cfg, now));
    (void)co_node_process(&node, now);
    fake_port_clear(&port);
}
void tearDown(void) {}

static co_node_t other; /* a node of another dictionary (one, for a small target's RAM) */

static co_status_t init_variant(const co_od_entry_t *rows, uint16_t count)
{
    static plain_values_t other_values;
    const co_od_t od = {.name = "variant", .entries = rows, .count = count, .defaults = &plain_defaults,
                        .values_size = (uint32_t)sizeof(plain_values_t), .signature = 0x1EAAU,
                        .defaults_size = (uint32_t)sizeof plain_defaults};
    const co_node_cfg_t cfg = config(&od, &other_values);
    return co_node_init(&other, &cfg, now);
}
#define INIT_VARIANT(rows) init_variant(rows, (uint16_t)(sizeof rows / sizeof rows[0]))

static void a_dictionary_with_an_error_history_is_refused(void)
{
    static const co_od_entry_t rows[] = {PLAIN_UP_TO_1001, E(0x1003, 0x00, CO_T_UNSIGNED8, RW, history_n),
                                         E(0x1003, 0x01, CO_T_UNSIGNED32, RO, history[0]), PLAIN_1014, PLAIN_REST};
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(rows));
}

static void a_dictionary_with_an_inhibit_time_is_refused(void)
{
    static const co_od_entry_t rows[] = {PLAIN_UP_TO_1001, PLAIN_1014, E(0x1015, 0x00, CO_T_UNSIGNED16, RW, inhibit),
                                         PLAIN_REST};
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(rows));
}

static void the_plain_dictionary_is_taken_again(void)
{
    /* the refusals above are for 0x1003 and 0x1015 alone: the same rows without them are taken */
    static const co_od_entry_t rows[] = {PLAIN_UP_TO_1001, PLAIN_1014, PLAIN_REST};
    TEST_ASSERT_EQUAL(CO_OK, INIT_VARIANT(rows));
}

static uint8_t error_register(void)
{
    uint8_t reg = 0xEEU;
    size_t len = 0U;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NONE, co_od_read(&node, 0x1001U, 0U, &reg, sizeof reg, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL(1U, len);
    return reg;
}

static void check_emcy(uint32_t k, const uint8_t expected[8])
{
    TEST_ASSERT_TRUE(k < port.n_sent);
    TEST_ASSERT_EQUAL_HEX32(0x85U, port.sent[k].id);
    TEST_ASSERT_EQUAL(8U, port.sent[k].len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expected, port.sent[k].data, 8U);
}

static void errors_still_set_the_register_and_go_out_as_emcy(void)
{
    const uint8_t msef[5] = {1U, 2U, 3U, 4U, 5U};
    TEST_ASSERT_TRUE(co_emcy_raise(&node, 0x5030U, 0x04U, msef));
    (void)co_node_process(&node, now);
    const uint8_t raised[8] = {0x30U, 0x50U, 0x05U, 1U, 2U, 3U, 4U, 5U}; /* generic bit 0 with the voltage bit 2 */
    TEST_ASSERT_EQUAL(1U, port.n_sent);
    check_emcy(0U, raised);
    TEST_ASSERT_EQUAL_HEX8(0x05U, error_register());

    TEST_ASSERT_TRUE(co_emcy_clear(&node, 0x5030U, msef));
    (void)co_node_process(&node, now);
    const uint8_t cleared[8] = {0x00U, 0x00U, 0x00U, 1U, 2U, 3U, 4U, 5U}; /* the error reset, nothing left */
    TEST_ASSERT_EQUAL(2U, port.n_sent);
    check_emcy(1U, cleared);
    TEST_ASSERT_EQUAL_HEX8(0x00U, error_register());
}

static void emcys_go_out_back_to_back(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&node, 0x5030U, 0x04U, NULL));
    TEST_ASSERT_TRUE(co_emcy_raise(&node, 0x8130U, 0x10U, NULL));
    TEST_ASSERT_TRUE(co_emcy_clear(&node, 0x5030U, NULL));
    TEST_ASSERT_EQUAL(CO_NEVER, co_node_process(&node, now)); /* nothing left to wait for */
    const uint8_t first[8] = {0x30U, 0x50U, 0x05U, 0U, 0U, 0U, 0U, 0U};
    const uint8_t second[8] = {0x30U, 0x81U, 0x15U, 0U, 0U, 0U, 0U, 0U};
    const uint8_t reset[8] = {0x00U, 0x00U, 0x11U, 0U, 0U, 0U, 0U, 0U}; /* 0x8130 remains */
    TEST_ASSERT_EQUAL(3U, port.n_sent);
    check_emcy(0U, first);
    check_emcy(1U, second);
    check_emcy(2U, reset);
    TEST_ASSERT_EQUAL(now, port.sent_at[2]);
}

static void there_is_no_history_to_read(void)
{
    TEST_ASSERT_TRUE(co_emcy_raise(&node, 0x8130U, 0x10U, NULL));
    uint8_t buf[4];
    size_t len = 0U;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, co_od_read(&node, 0x1003U, 0U, buf, sizeof buf, &len, CO_ORIGIN_SDO));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_dictionary_with_an_error_history_is_refused);
    RUN_TEST(a_dictionary_with_an_inhibit_time_is_refused);
    RUN_TEST(the_plain_dictionary_is_taken_again);
    RUN_TEST(emcys_go_out_back_to_back);
    RUN_TEST(errors_still_set_the_register_and_go_out_as_emcy);
    RUN_TEST(there_is_no_history_to_read);
    return UNITY_END();
}
