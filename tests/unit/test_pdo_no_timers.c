/* The core compiled with CO_CONFIG_PDO_TIMERS 0 (what cmake/profiles/eltex.h and a fitted configuration choose for
 * a dictionary without PDO timers): event-driven TPDOs go at each change at once, RPDOs apply, nothing waits for a
 * timer; a dictionary that has timer sub-indices is refused by co_node_init (their values would change nothing). */
#include <stddef.h>

#include "fake_port.h"
#include "test_od.h"
#include "unity.h"

#if CO_CONFIG_PDO_TIMERS
#error "this test is built against a core with CO_CONFIG_PDO_TIMERS 0 (tests/CMakeLists.txt)"
#endif

/* A dictionary with one RPDO and one TPDO and no timer sub-indices (0x1400:05, 0x1800:03/05). */
typedef struct lean_values {
    uint32_t device_type, identity[4], sdo_cob[2], rpdo_cob, rpdo_map, tpdo_cob, tpdo_map;
    uint16_t producer_hb;
    uint8_t error_register, identity_n, sdo_n, rpdo_n, rpdo_type, rpdo_map_n, tpdo_n, tpdo_type, tpdo_map_n;
    uint8_t output, input;
} lean_values_t;

#define V lean_values_t
#define E(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m))
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)

/* The lean dictionary in three parts, so that the variants below can put rows between them. */
#define LEAN_UP_TO_RPDO_COMM                                                                                           \
    E(0x1000, 0x00, CO_T_UNSIGNED32, RO, device_type),                                                                 \
    E(0x1001, 0x00, CO_T_UNSIGNED8, RO, error_register),                                                               \
    E(0x1017, 0x00, CO_T_UNSIGNED16, RW, producer_hb),                                                                 \
    E(0x1018, 0x00, CO_T_UNSIGNED8, RO, identity_n),                                                                   \
    E(0x1018, 0x01, CO_T_UNSIGNED32, RO, identity[0]),                                                                 \
    E(0x1018, 0x02, CO_T_UNSIGNED32, RO, identity[1]),                                                                 \
    E(0x1018, 0x03, CO_T_UNSIGNED32, RO, identity[2]),                                                                 \
    E(0x1018, 0x04, CO_T_UNSIGNED32, RO, identity[3]),                                                                 \
    E(0x1200, 0x00, CO_T_UNSIGNED8, RO, sdo_n),                                                                        \
    E(0x1200, 0x01, CO_T_UNSIGNED32, RO | CO_OD_NODEID, sdo_cob[0]),                                                   \
    E(0x1200, 0x02, CO_T_UNSIGNED32, RO | CO_OD_NODEID, sdo_cob[1]),                                                   \
    E(0x1400, 0x00, CO_T_UNSIGNED8, RO, rpdo_n),                                                                       \
    E(0x1400, 0x01, CO_T_UNSIGNED32, RW | CO_OD_NODEID, rpdo_cob),                                                     \
    E(0x1400, 0x02, CO_T_UNSIGNED8, RO, rpdo_type)
#define LEAN_UP_TO_TPDO_COMM                                                                                           \
    E(0x1600, 0x00, CO_T_UNSIGNED8, RO, rpdo_map_n),                                                                   \
    E(0x1600, 0x01, CO_T_UNSIGNED32, RO, rpdo_map),                                                                    \
    E(0x1800, 0x00, CO_T_UNSIGNED8, RO, tpdo_n),                                                                       \
    E(0x1800, 0x01, CO_T_UNSIGNED32, RW | CO_OD_NODEID, tpdo_cob),                                                     \
    E(0x1800, 0x02, CO_T_UNSIGNED8, RO, tpdo_type)
#define LEAN_REST                                                                                                      \
    E(0x1A00, 0x00, CO_T_UNSIGNED8, RO, tpdo_map_n),                                                                   \
    E(0x1A00, 0x01, CO_T_UNSIGNED32, RO, tpdo_map),                                                                    \
    E(0x2000, 0x00, CO_T_UNSIGNED8, RW | CO_OD_TPDO, input),                                                           \
    E(0x2001, 0x00, CO_T_UNSIGNED8, RW | CO_OD_RPDO, output)

static const co_od_entry_t lean_rows[] = {LEAN_UP_TO_RPDO_COMM, LEAN_UP_TO_TPDO_COMM, LEAN_REST};

/* Node-ID-relative COB-IDs without the ID (the generator's convention). */
static const lean_values_t lean_defaults = {
    .device_type = 0x191U, .identity = {0xABCU, 1U, 2U, 3U}, .sdo_cob = {0x600U, 0x580U}, .rpdo_cob = 0x200U,
    .rpdo_map = 0x20010008UL, .tpdo_cob = 0x180U, .tpdo_map = 0x20000008UL, .identity_n = 4U, .sdo_n = 2U,
    .rpdo_n = 2U, .rpdo_type = 255U, .rpdo_map_n = 1U, .tpdo_n = 2U, .tpdo_type = 255U, .tpdo_map_n = 1U,
};

static const co_od_t lean_od = {.name = "lean", .entries = lean_rows,
                                .count = (uint16_t)(sizeof lean_rows / sizeof lean_rows[0]), .defaults = &lean_defaults,
                                .values_size = (uint32_t)sizeof(lean_values_t), .signature = 0x1EA7U,
                                .defaults_size = (uint32_t)sizeof lean_defaults};

static co_time_us_t now;
static fake_port_t port;
static co_node_t node;
static lean_values_t values;

static co_node_cfg_t config(const co_od_t *od, void *vals) { return fake_port_node_cfg(&port, od, vals, 5U); }

void setUp(void)
{
    now = 1000U;
    fake_port_init(&port, &now);
    const co_node_cfg_t cfg = config(&lean_od, &values);
    TEST_ASSERT_EQUAL(CO_OK, co_node_init(&node, &cfg, now));
    fake_port_clear(&port);
}
void tearDown(void) {}

static uint32_t sent(uint32_t id)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < port.n_sent; i++) {
        n += port.sent[i].id == id ? 1U : 0U;
    }
    return n;
}

static co_node_t other; /* a node of another dictionary (one, for a small target's RAM) */

static void a_dictionary_with_timers_is_refused(void)
{
    static test_od_values_t other_values;
    const co_node_cfg_t cfg = config(&test_od, &other_values); /* 0x1400:05, 0x1800:03 and :05 */
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, co_node_init(&other, &cfg, now));
}

/* Variants of the lean dictionary with more communication sub-indices, their values after the lean ones. */
typedef struct extra_values {
    lean_values_t lean;
    uint16_t extra[5];
} extra_values_t;

#define X(i, s, n, k) CO_OD_RUN(i, s, n, CO_T_UNSIGNED16, RW, sizeof(uint16_t), offsetof(extra_values_t, extra[k]))

static co_status_t init_variant(const co_od_entry_t *rows, uint16_t count)
{
    static extra_values_t other_values;
    const co_od_t od = {.name = "variant", .entries = rows, .count = count, .defaults = &lean_defaults,
                        .values_size = (uint32_t)sizeof(extra_values_t), .signature = 0x1EA8U,
                        .defaults_size = (uint32_t)sizeof lean_defaults};
    const co_node_cfg_t cfg = config(&od, &other_values);
    return co_node_init(&other, &cfg, now);
}
#define INIT_VARIANT(rows) init_variant(rows, (uint16_t)(sizeof rows / sizeof rows[0]))

static void sub_indices_that_are_no_timers_are_taken(void)
{
    /* RPDO 3, 4 and 6 (sub 3 is a TPDO's inhibit time only), TPDO 4 and 6: none is a timer this core leaves out */
    static const co_od_entry_t rows[] = {LEAN_UP_TO_RPDO_COMM, X(0x1400, 3, 2, 0), X(0x1400, 6, 1, 2),
                                         LEAN_UP_TO_TPDO_COMM, X(0x1800, 4, 1, 3),  X(0x1800, 6, 1, 4), LEAN_REST};
    TEST_ASSERT_EQUAL(CO_OK, INIT_VARIANT(rows));
}

static void a_timer_sub_index_alone_or_inside_a_run_is_refused(void)
{
    static const co_od_entry_t rpdo_event[] = {LEAN_UP_TO_RPDO_COMM, X(0x1400, 5, 1, 0), LEAN_UP_TO_TPDO_COMM,
                                               LEAN_REST};
    static const co_od_entry_t rpdo_run[] = {LEAN_UP_TO_RPDO_COMM, X(0x1400, 3, 3, 0), LEAN_UP_TO_TPDO_COMM,
                                             LEAN_REST};
    static const co_od_entry_t tpdo_inhibit[] = {LEAN_UP_TO_RPDO_COMM, LEAN_UP_TO_TPDO_COMM, X(0x1800, 3, 1, 0),
                                                 LEAN_REST};
    static const co_od_entry_t tpdo_run[] = {LEAN_UP_TO_RPDO_COMM, LEAN_UP_TO_TPDO_COMM, X(0x1800, 4, 3, 0), LEAN_REST};
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(rpdo_event));
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(rpdo_run)); /* 3..5 */
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(tpdo_inhibit));
    TEST_ASSERT_EQUAL(CO_ERR_RANGE, INIT_VARIANT(tpdo_run)); /* 4..6 */
}

static void event_driven_tpdo_goes_at_each_change_at_once(void)
{
    const co_frame_t start = {0x000U, 2U, 0U, {0x01U, 5U}};
    TEST_ASSERT_TRUE(co_node_rx(&node, &start, now));
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_node_process(&node, now)); /* no heartbeat, no timer: nothing due */
    TEST_ASSERT_EQUAL_UINT32(1U, sent(0x185U)); /* entering Operational: sent once */
    for (uint8_t v = 1U; v <= 3U; v++) {
        now += 10U; /* far below any inhibit time a dictionary could give */
        TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&node, 0x2000U, 0U, &v, 1U, CO_ORIGIN_LOCAL));
        TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_node_process(&node, now));
        TEST_ASSERT_EQUAL_UINT32(1U + v, sent(0x185U));
        TEST_ASSERT_EQUAL_HEX8(v, port.sent[port.n_sent - 1U].data[0]);
    }
    now += 1000000000U; /* a long silence: no event timer sends anything */
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_node_process(&node, now));
    TEST_ASSERT_EQUAL_UINT32(4U, sent(0x185U));
}

static void rpdo_applies_and_nothing_monitors_it(void)
{
    const co_frame_t start = {0x000U, 2U, 0U, {0x01U, 5U}};
    TEST_ASSERT_TRUE(co_node_rx(&node, &start, now));
    (void)co_node_process(&node, now);
    const co_frame_t rpdo = {0x205U, 1U, 0U, {0x5AU}};
    TEST_ASSERT_TRUE(co_node_rx(&node, &rpdo, now));
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_node_process(&node, now));
    TEST_ASSERT_EQUAL_HEX8(0x5AU, values.output);
    now += 1000000000U;
    TEST_ASSERT_EQUAL_UINT64(CO_NEVER, co_node_process(&node, now));
    TEST_ASSERT_EQUAL_UINT32(0U, sent(0x085U)); /* no EMCY 0x8250: there is no deadline to miss */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_dictionary_with_timers_is_refused);
    RUN_TEST(sub_indices_that_are_no_timers_are_taken);
    RUN_TEST(a_timer_sub_index_alone_or_inside_a_run_is_refused);
    RUN_TEST(event_driven_tpdo_goes_at_each_change_at_once);
    RUN_TEST(rpdo_applies_and_nothing_monitors_it);
    return UNITY_END();
}
