/*
 * The device framework's common commands (devices/device.c): how numbers are read (device_parse_int, used by every
 * command of every device and by canopen-emu's node-IDs) and what `set` writes. A Bürkert and a PRO IONIZER node on
 * a fake port, at time 0.
 */
#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "buerkert/buerkert.h"
#include "buerkert_fc_od.h"
#include "fake_port.h"
#include "pro_ionizer/pro_ionizer.h"
#include "pro_ionizer_od.h"
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
    return device_command(&dev, 3, argv, now);
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
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, temperature, now));
    TEST_ASSERT_EQUAL_STRING_LEN("temperature 100 C", last_line, strlen("temperature 100 C"));
    temperature[1] = "090";
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, temperature, now));
    TEST_ASSERT_EQUAL_STRING_LEN("temperature 90 C", last_line, strlen("temperature 90 C"));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(numbers_are_decimal_or_0x_hex_never_octal);
    RUN_TEST(anything_else_is_not_a_number);
    RUN_TEST(overflow_is_refused_not_clamped);
    RUN_TEST(device_commands_read_leading_zeros_as_decimal);
    return UNITY_END();
}
