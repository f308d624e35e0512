/*
 * The device framework's common commands (devices/device.c): how numbers are read (device_parse_int, used by every
 * command of every device and by canopen-emu's node-IDs) and what `set` writes: only values the object's data type
 * holds. A Bürkert and a PRO IONIZER node on a fake port, at time 0.
 */
#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "buerkert/buerkert.h"
#include "buerkert_fc_od.h"
#include "fake_port.h"
#include "pro_ionizer/pro_ionizer.h"
#include "pro_ionizer_od.h"
#include "sds_od.h"
#include "unity.h"

static fake_port_t port;
static co_time_us_t now;
static device_t dev;
static union {
    buerkert_fc_od_values_t buerkert;
    pro_ionizer_od_values_t pro_ionizer;
} values;
static union {
    uint64_t align_u;
    double align_d;
    void *align_p;
    uint8_t bytes[4096];
} model_mem;
static char last_line[512];

static void on_print(void *ctx, const device_t *d, const char *line)
{
    (void)ctx;
    (void)d;
    (void)snprintf(last_line, sizeof last_line, "%s", line);
}

static void start(const device_class_t *cls)
{
    now = 0U;
    fake_port_init(&port, &now);
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = 16U;
    cfg.port = &port.port;
    cfg.port_ctx = &port;
    cfg.print = on_print;
    TEST_ASSERT_TRUE(cls->model_size <= sizeof model_mem.bytes);
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&dev, cls, &values, model_mem.bytes, &cfg, now));
    (void)device_process(&dev, now);
}

/* `set ADDRESS VALUE` as canopen-emu passes it on (the node's word already taken off). */
static device_cmd_result_t set(const char *address, const char *value)
{
    const char *argv[] = {"set", address, value};
    last_line[0] = '\0';
    return device_command(&dev, 3, argv, now, NULL);
}

static bool parses(const char *text, long long *out)
{
    return device_parse_int(text, LLONG_MIN, LLONG_MAX, out);
}

void setUp(void) {}
void tearDown(void) {}

static void numbers_are_decimal_or_0x_hex_never_octal(void)
{
    long long v = 0;
    TEST_ASSERT_TRUE(parses("010", &v));
    TEST_ASSERT_EQUAL_INT64(10, v);
    TEST_ASSERT_TRUE(parses("08", &v)); /* an octal reading refuses it */
    TEST_ASSERT_EQUAL_INT64(8, v);
    TEST_ASSERT_TRUE(parses("0100", &v));
    TEST_ASSERT_EQUAL_INT64(100, v);
    TEST_ASSERT_TRUE(parses("0x10", &v));
    TEST_ASSERT_EQUAL_INT64(16, v);
    TEST_ASSERT_TRUE(parses("0X1f", &v));
    TEST_ASSERT_EQUAL_INT64(31, v);
    TEST_ASSERT_TRUE(parses("0x010", &v));
    TEST_ASSERT_EQUAL_INT64(16, v);
    TEST_ASSERT_TRUE(parses("-0x10", &v));
    TEST_ASSERT_EQUAL_INT64(-16, v);
    TEST_ASSERT_TRUE(parses("-007", &v));
    TEST_ASSERT_EQUAL_INT64(-7, v);
    TEST_ASSERT_TRUE(parses("+5", &v));
    TEST_ASSERT_EQUAL_INT64(5, v);
    TEST_ASSERT_TRUE(parses("0", &v));
    TEST_ASSERT_EQUAL_INT64(0, v);
}

static void anything_else_is_not_a_number(void)
{
    static const char *const bad[] = {"", "-", "+", "0x", "-0x", " 1", "1 ", "\t1", "1a", "0x1g", "0b1", "1.0", "1e3",
                                      "--1", "+-1", "0x-1", "08x", "twelve"};
    long long v = 1234;
    for (size_t i = 0U; i < sizeof bad / sizeof bad[0]; i++) {
        TEST_ASSERT_FALSE_MESSAGE(parses(bad[i], &v), bad[i]);
    }
    TEST_ASSERT_EQUAL_INT64(1234, v); /* untouched */
}

static void overflow_is_refused_not_clamped(void)
{
    long long v = 0;
    TEST_ASSERT_TRUE(parses("9223372036854775807", &v));
    TEST_ASSERT_EQUAL_INT64(LLONG_MAX, v);
    TEST_ASSERT_TRUE(parses("-9223372036854775808", &v));
    TEST_ASSERT_EQUAL_INT64(LLONG_MIN, v);
    TEST_ASSERT_FALSE(parses("9223372036854775808", &v));
    TEST_ASSERT_FALSE(parses("-9223372036854775809", &v));
    TEST_ASSERT_FALSE(parses("99999999999999999999", &v));
    TEST_ASSERT_FALSE(parses("0x10000000000000000", &v));
    TEST_ASSERT_FALSE(device_parse_int("128", 1, 127, &v));
    TEST_ASSERT_FALSE(device_parse_int("0", 1, 127, &v));
    TEST_ASSERT_TRUE(device_parse_int("0127", 1, 127, &v));
    TEST_ASSERT_EQUAL_INT64(127, v);
}

static void device_commands_read_leading_zeros_as_decimal(void)
{
    start(&buerkert_class);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "0100"));
    TEST_ASSERT_EQUAL_UINT16(100U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "0x0100"));
    TEST_ASSERT_EQUAL_UINT16(256U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, set("0x1017", "0100 "));
    TEST_ASSERT_EQUAL_UINT16(256U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    /* a device's own command: the Bürkert temperature input, 0..150 */
    const char *temperature[] = {"temperature", "0100"};
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, temperature, now, NULL));
    TEST_ASSERT_EQUAL_STRING_LEN("temperature 100 C", last_line, strlen("temperature 100 C"));
    temperature[1] = "090";
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, temperature, now, NULL));
    TEST_ASSERT_EQUAL_STRING_LEN("temperature 90 C", last_line, strlen("temperature 90 C"));
}

/* The reply names the object's range, and the object keeps its value. */
static void assert_refused(const char *address, const char *value, const char *range, uint32_t kept,
                           uint32_t (*read)(void))
{
    TEST_ASSERT_EQUAL_INT_MESSAGE(DEVICE_CMD_ERROR, set(address, value), value);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(last_line, "out of range"), last_line);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(last_line, range), last_line);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(kept, read(), value);
}

static uint32_t heartbeat_time(void) { return co_od_get_u16(&dev.node, 0x1017U, 0U); }
static uint32_t life_time_factor(void) { return co_od_get_u8(&dev.node, 0x100DU, 0U); }
static uint32_t operation_time(void) { return co_od_get_u32(&dev.node, 0x2004U, 4U); }
static uint32_t supply_voltage_bits(void) { return co_od_get_u32(&dev.node, 0x2004U, 3U); }

static void set_refuses_values_outside_the_unsigned_types_with_their_range(void)
{
    start(&buerkert_class);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "500"));
    assert_refused("0x1017", "70000", "0x1017:00 (UNSIGNED16) holds 0..65535", 500U, heartbeat_time); /* was 4464 */
    assert_refused("0x1017", "65536", "0..65535", 500U, heartbeat_time);
    assert_refused("0x1017", "0x10000", "0..65535", 500U, heartbeat_time);
    assert_refused("0x1017", "-1", "0..65535", 500U, heartbeat_time); /* was 65535 */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "65535"));
    TEST_ASSERT_EQUAL_UINT16(65535U, heartbeat_time());
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "-0"));
    TEST_ASSERT_EQUAL_UINT16(0U, heartbeat_time());

    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x100D", "255"));
    assert_refused("0x100D", "256", "0x100D:00 (UNSIGNED8) holds 0..255", 255U, life_time_factor);

    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x2004:04", "4294967295"));
    assert_refused("0x2004:04", "4294967296", "(UNSIGNED32) holds 0..4294967295", 4294967295U, operation_time);
    assert_refused("0x2004:04", "-4294967295", "0..4294967295", 4294967295U, operation_time); /* was 1 */

    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x2004:03", "24.5"));
    const uint32_t bits = supply_voltage_bits();
    assert_refused("0x2004:03", "1e39", "(REAL32)", bits, supply_voltage_bits); /* was +inf */
}

static void set_gives_signed_types_their_negative_half(void)
{
    /* No device has a signed object that `set` may change: 0x6401:03 (DC current discharging, INTEGER16) is a
     * measurement, which the Eltex model refuses to have set (E6), after the range check. */
    start(&pro_ionizer_class);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, set("0x6401:03", "32768")); /* was -32768, then refused by the model */
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(last_line, "0x6401:03 (INTEGER16) holds -32768..32767"), last_line);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, set("0x6401:03", "-32769"));
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(last_line, "-32768..32767"), last_line);
    static const char *const in_range[] = {"-32768", "-1", "32767"};
    for (size_t i = 0U; i < sizeof in_range / sizeof in_range[0]; i++) {
        TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, set("0x6401:03", in_range[i]));
        TEST_ASSERT_NULL_MESSAGE(strstr(last_line, "out of range"), last_line); /* the model's refusal */
    }
}

static void a_value_that_wrapped_into_the_eltex_heartbeat_rule_is_refused(void)
{
    start(&pro_ionizer_class);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, set("0x1017", "1000"));
    assert_refused("0x1017", "65636", "0..65535", 1000U, heartbeat_time); /* cut to 16 bits it was 100, allowed */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, set("0x1017", "50"));      /* the rule itself: 0 or 100..60000 */
    TEST_ASSERT_EQUAL_UINT16(1000U, heartbeat_time());
}

/* The generated object table gives every look-up the answer the rows alone give (the search without it): the same
 * row, or for a sub-index inside a run the same narrowed copy; its generated hash (default layout) the object the
 * table's search gives. */
static void check_object_table(const co_od_t *od)
{
    co_od_t rows_only = *od;
    rows_only.objects = NULL;
    rows_only.n_objects = 0U;
    TEST_ASSERT_NOT_NULL(od->objects);
    for (uint16_t k = 0U; k < od->n_objects; k++) {
        const co_od_object_t *o = &od->objects[k];
        TEST_ASSERT_TRUE(k == 0U || o[-1].index < o->index);
        TEST_ASSERT_EQUAL_HEX16(o->index, od->entries[o->first].index);
        TEST_ASSERT_TRUE(o->first == 0U || od->entries[o->first - 1U].index != o->index);
    }
#if !CO_CONFIG_OD_COMPACT
    TEST_ASSERT_NOT_NULL(od->object_slots); /* od's look-ups below go through its hash, the rows_only's through none */
#endif
    static const uint8_t probe_subs[] = {0U, 1U, 2U, 3U, 7U, 0x7FU, 0xFEU, 0xFFU};
    for (uint32_t index = 0U; index <= 0xFFFFU; index++) {
        const bool present = co_od_has_index(&rows_only, (uint16_t)index);
        TEST_ASSERT_EQUAL(present, co_od_has_index(od, (uint16_t)index));
        for (uint32_t i = 0U; i < (present ? 256U : sizeof probe_subs); i++) {
            const uint8_t sub = present ? (uint8_t)i : probe_subs[i];
            co_od_entry_t one_a;
            co_od_entry_t one_b;
            const co_od_entry_t *a = co_od_find(od, (uint16_t)index, sub, &one_a);
            const co_od_entry_t *b = co_od_find(&rows_only, (uint16_t)index, sub, &one_b);
            const bool same = (a == NULL && b == NULL) ||
                              (a != NULL && b != NULL && a->index == b->index && a->sub == b->sub && a->sub == sub &&
                               a->offset == b->offset && a->size == b->size && a->type == b->type &&
                               a->flags == b->flags && (a == b || (a == &one_a && b == &one_b)));
            if (!same) {
                char msg[64];
                (void)snprintf(msg, sizeof msg, "%s 0x%04X:%02X", od->name, (unsigned)index, (unsigned)sub);
                TEST_FAIL_MESSAGE(msg);
            }
        }
    }
}

static void object_tables_find_what_the_rows_hold(void)
{
    check_object_table(&pro_ionizer_od);
    check_object_table(&sds_od);
    check_object_table(&buerkert_fc_od);
}

/* device_settled, as canopen-emu asks it after each frame a node took: an SDO upload answered at once leaves nothing
 * for device_process (it would return the same deadline and send nothing); an SDO write of one of the model's
 * objects (0x2000 and up) touches the model, whose step must run. */
static void a_request_answered_whole_leaves_the_device_settled_unless_it_touched_the_model(void)
{
    start(&buerkert_class);
    const co_time_us_t due = device_process(&dev, now);
    fake_port_clear(&port);
    const co_frame_t upload = {0x610U, 8U, 0U, {0x40U, 0x18U, 0x10U, 0x01U}};
    TEST_ASSERT_TRUE(device_rx(&dev, &upload, now));
    TEST_ASSERT_TRUE(device_settled(&dev));
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    TEST_ASSERT_EQUAL_UINT64(due, device_process(&dev, now));
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    const co_frame_t name = {0x610U, 8U, 0U, {0x27U, 0x02U, 0x20U, 0x01U, 'A', 'B', 'C'}}; /* 0x2002:01 = "ABC" */
    TEST_ASSERT_TRUE(device_rx(&dev, &name, now));
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0x60U, port.sent[1].data[0]);
    TEST_ASSERT_FALSE(device_settled(&dev));
}

/* What the core's pass did that may concern the model (here an SDO transfer timing out: its event touches the model)
 * gets the model's step in the same device_process, not at the deadline that call returns, which a runner sleeps
 * until; a frame that then touches nothing is settled, one that writes the model's objects is not. */
static void the_model_follows_what_the_core_pass_did_at_once(void)
{
    start(&buerkert_class);
    fake_port_clear(&port);
    const co_frame_t upload = {0x610U, 8U, 0U, {0x40U, 0x08U, 0x10U, 0x00U}}; /* 0x1008, 12 bytes: segmented */
    TEST_ASSERT_TRUE(device_rx(&dev, &upload, now));
    (void)device_process(&dev, now);
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    TEST_ASSERT_EQUAL_HEX8(0x41U, port.sent[0].data[0]);
    TEST_ASSERT_FALSE(dev.touched);
    now += CO_SDO_TIMEOUT_US;
    (void)device_process(&dev, now);
    TEST_ASSERT_EQUAL_UINT32(3U, port.n_sent); /* its heartbeat (1 s), then the abort */
    TEST_ASSERT_EQUAL_HEX32(0x710U, port.sent[1].id);
    TEST_ASSERT_EQUAL_HEX32(0x590U, port.sent[2].id);
    TEST_ASSERT_EQUAL_HEX8(0x80U, port.sent[2].data[0]);
    const uint8_t *code = &port.sent[2].data[4];
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_TIMEOUT, (uint32_t)code[0] | (uint32_t)code[1] << 8 | (uint32_t)code[2] << 16 |
                                                  (uint32_t)code[3] << 24);
    TEST_ASSERT_FALSE(dev.touched); /* the timeout's event touched it; its step ran in the same call */
    const co_frame_t identity = {0x610U, 8U, 0U, {0x40U, 0x18U, 0x10U, 0x01U}};
    TEST_ASSERT_TRUE(device_rx(&dev, &identity, now));
    TEST_ASSERT_TRUE(device_settled(&dev));
    const co_frame_t name = {0x610U, 8U, 0U, {0x27U, 0x02U, 0x20U, 0x01U, 'A', 'B', 'C'}}; /* 0x2002:01 = "ABC" */
    TEST_ASSERT_TRUE(device_rx(&dev, &name, now));
    TEST_ASSERT_FALSE(device_settled(&dev));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(object_tables_find_what_the_rows_hold);
    RUN_TEST(numbers_are_decimal_or_0x_hex_never_octal);
    RUN_TEST(anything_else_is_not_a_number);
    RUN_TEST(overflow_is_refused_not_clamped);
    RUN_TEST(device_commands_read_leading_zeros_as_decimal);
    RUN_TEST(set_refuses_values_outside_the_unsigned_types_with_their_range);
    RUN_TEST(set_gives_signed_types_their_negative_half);
    RUN_TEST(a_value_that_wrapped_into_the_eltex_heartbeat_rule_is_refused);
    RUN_TEST(a_request_answered_whole_leaves_the_device_settled_unless_it_touched_the_model);
    RUN_TEST(the_model_follows_what_the_core_pass_did_at_once);
    return UNITY_END();
}
