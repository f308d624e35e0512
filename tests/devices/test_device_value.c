/*
 * Typed values (devices/device_value.c: device_get_value, device_set_value), the output argument of device_command,
 * and the command language's word splitting (devices/device_words.c), on a node of the test dictionary
 * (tests/support/test_od.c: UNSIGNED16 with limits, INTEGER16 -100..100, REAL32, VISIBLE_STRING, UNSIGNED64) as a
 * device class without a model, on a fake port at time 0.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "device.h"
#include "fake_port.h"
#include "test_od.h"
#include "unity.h"

static const device_class_t test_class = {.name = "test", .od = &test_od, .default_node_id = 5U};

static fake_port_t port;
static co_time_us_t now;
static device_t dev;
static test_od_values_t values;
static char cfg_line[512];   /* the last line through cfg.print */
static char out_lines[4][512]; /* the lines through a command's own output */
static unsigned out_count;

static void on_cfg_print(void *ctx, const device_t *d, const char *line)
{
    (void)ctx;
    (void)d;
    (void)snprintf(cfg_line, sizeof cfg_line, "%s", line);
}

static void on_out_print(void *ctx, const device_t *d, const char *line)
{
    TEST_ASSERT_EQUAL_PTR(&out_count, ctx);
    TEST_ASSERT_EQUAL_PTR(&dev, d);
    if (out_count < 4U) {
        (void)snprintf(out_lines[out_count], sizeof out_lines[0], "%s", line);
    }
    out_count++;
}

void setUp(void)
{
    now = 0U;
    cfg_line[0] = '\0';
    out_count = 0U;
    memset(out_lines, 0, sizeof out_lines);
    fake_port_init(&port, &now);
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.port = &port.port;
    cfg.port_ctx = &port;
    cfg.print = on_cfg_print;
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&dev, &test_class, &values, NULL, &cfg, now));
}

void tearDown(void) {}

static device_value_t integer(int64_t i)
{
    device_value_t v;
    memset(&v, 0, sizeof v);
    v.kind = DEVICE_VALUE_SIGNED;
    v.as.i = i;
    return v;
}

static device_value_t real(double r)
{
    device_value_t v;
    memset(&v, 0, sizeof v);
    v.kind = DEVICE_VALUE_REAL;
    v.as.r = r;
    return v;
}

static device_value_t text(const char *t)
{
    device_value_t v;
    memset(&v, 0, sizeof v);
    v.kind = DEVICE_VALUE_TEXT;
    v.bytes = (const uint8_t *)t;
    v.len = strlen(t);
    return v;
}

/* Sets and expects a refusal with exactly this reason, the object unchanged. */
static void refused(uint16_t index, uint8_t sub, device_value_t v, const char *reason)
{
    uint8_t before[32], after[32];
    size_t n_before = 0U, n_after = 0U;
    const bool exists = co_od_read(&dev.node, index, sub, before, sizeof before, &n_before, CO_ORIGIN_LOCAL) == 0U;
    char why[256] = "";
    TEST_ASSERT_FALSE_MESSAGE(device_set_value(&dev, index, sub, &v, now, why, sizeof why), reason);
    TEST_ASSERT_EQUAL_STRING(reason, why);
    if (exists) {
        TEST_ASSERT_EQUAL_UINT32(0U, co_od_read(&dev.node, index, sub, after, sizeof after, &n_after, CO_ORIGIN_LOCAL));
        TEST_ASSERT_EQUAL_size_t(n_before, n_after);
        TEST_ASSERT_EQUAL_MEMORY(before, after, n_after);
    }
}

static void written(uint16_t index, uint8_t sub, device_value_t v)
{
    char why[256] = "";
    TEST_ASSERT_TRUE_MESSAGE(device_set_value(&dev, index, sub, &v, now, why, sizeof why), why);
}

static void integers_of_any_kind_go_in_within_the_type_and_its_limits(void)
{
    written(0x1017U, 0U, integer(1000));
    TEST_ASSERT_EQUAL_UINT16(1000U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    written(0x1017U, 0U, text("0x2A"));
    TEST_ASSERT_EQUAL_UINT16(42U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    written(0x1017U, 0U, real(250.0)); /* a whole REAL is a number like any other */
    TEST_ASSERT_EQUAL_UINT16(250U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    written(0x1017U, 0U, text("1e3"));
    TEST_ASSERT_EQUAL_UINT16(1000U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    device_value_t yes;
    memset(&yes, 0, sizeof yes);
    yes.kind = DEVICE_VALUE_BOOLEAN;
    yes.as.b = true;
    written(0x1017U, 0U, yes);
    TEST_ASSERT_EQUAL_UINT16(1U, co_od_get_u16(&dev.node, 0x1017U, 0U));
    written(0x2001U, 0U, integer(-100));
    TEST_ASSERT_EQUAL_INT16(-100, (int16_t)co_od_get_u16(&dev.node, 0x2001U, 0U));
    written(0x2006U, 0U, text("18446744073709551615")); /* every UNSIGNED64, as a word */
    uint8_t buf[8];
    device_value_t got;
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2006U, 0U, now, buf, sizeof buf, &got));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_UNSIGNED, got.kind);
    TEST_ASSERT_TRUE(got.as.u == UINT64_MAX);
}

static void a_value_the_type_cannot_hold_is_refused_with_the_reason(void)
{
    written(0x1017U, 0U, integer(1000));
    refused(0x1017U, 0U, integer(70000), "70000 is out of range: 0x1017:00 (UNSIGNED16) holds 0..65535");
    refused(0x1017U, 0U, integer(-1), "-1 is out of range: 0x1017:00 (UNSIGNED16) holds 0..65535");
    refused(0x1017U, 0U, real(2.5), "2.5 is not a whole number");
    refused(0x1017U, 0U, real(NAN), "nan is not a whole number");
    refused(0x1017U, 0U, text("abc"), "'abc' is not a number");
    refused(0x1017U, 0U, text("2.5"), "2.5 is not a whole number"); /* the words of a JSON 2.5 */
    refused(0x1017U, 0U, text("12 "), "'12 ' is not a number");
    refused(0x2001U, 0U, integer(-32769), "-32769 is out of range: 0x2001:00 (INTEGER16) holds -32768..32767");
    /* within the type but outside the EDS limits (-100..100), which bind an SDO client, not the device */
    written(0x2001U, 0U, integer(101));
    TEST_ASSERT_EQUAL_INT16(101, (int16_t)co_od_get_u16(&dev.node, 0x2001U, 0U));
    refused(0x2004U, 0U, real(1e39), "1e+39 is out of range: 0x2004:00 (REAL32) holds -3.4e38..3.4e38");
    refused(0x2005U, 0U, integer(7), "0x2005:00 is a VISIBLE_STRING: give it text");
    refused(0x2005U, 0U, text("twenty-one characters"), "0x2005:00 holds at most 20 characters");
    refused(0x3000U, 0U, integer(1), "no object 0x3000:00");
}

static void reals_and_text_go_in_as_their_types(void)
{
    written(0x2004U, 0U, real(1.5));
    written(0x2005U, 0U, text("pump 7"));
    uint8_t buf[64];
    device_value_t v;
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2004U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_REAL, v.kind);
    TEST_ASSERT_EQUAL_UINT8(CO_T_REAL32, v.type);
    TEST_ASSERT_TRUE(v.as.r == 1.5);
    written(0x2004U, 0U, text("-0.25"));
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2004U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_TRUE(v.as.r == -0.25);
    written(0x2004U, 0U, integer(3));
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2004U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_TRUE(v.as.r == 3.0);
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2005U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_TEXT, v.kind);
    TEST_ASSERT_EQUAL_size_t(6U, v.len); /* up to the first NUL of the 20-byte object */
    TEST_ASSERT_EQUAL_MEMORY("pump 7", v.bytes, 6U);
}

static void values_are_read_by_their_types(void)
{
    uint8_t buf[64];
    device_value_t v;
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x1008U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_TEXT, v.kind); /* "ES61", not the number 825643845 */
    TEST_ASSERT_EQUAL_size_t(4U, v.len);
    TEST_ASSERT_EQUAL_MEMORY("ES61", v.bytes, 4U);
    written(0x2001U, 0U, integer(-7));
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x2001U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_SIGNED, v.kind);
    TEST_ASSERT_TRUE(v.as.i == -7);
    TEST_ASSERT_EQUAL_UINT32(0U, device_get_value(&dev, 0x1018U, 1U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_INT(DEVICE_VALUE_UNSIGNED, v.kind);
    TEST_ASSERT_TRUE(v.as.u == 0x24EU);
    TEST_ASSERT_EQUAL_UINT32(CO_ABORT_NO_OBJECT, device_get_value(&dev, 0x3000U, 0U, now, buf, sizeof buf, &v));
    TEST_ASSERT_EQUAL_UINT32(CO_ABORT_NO_SUBINDEX, device_get_value(&dev, 0x1018U, 9U, now, buf, sizeof buf, &v));
}

static void a_command_replies_to_its_own_output_and_the_node_keeps_its_print(void)
{
    const device_output_t out = {on_out_print, &out_count};
    const char *const get[] = {"get", "0x1017"};
    written(0x1017U, 0U, integer(1000));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, get, now, &out));
    TEST_ASSERT_EQUAL_UINT(1U, out_count);
    TEST_ASSERT_EQUAL_STRING("0x1017:00 = 1000 (0x3E8)", out_lines[0]);
    TEST_ASSERT_EQUAL_STRING("", cfg_line); /* nothing through cfg.print */
    TEST_ASSERT_NULL(dev.replies);          /* set for the call only */
    const char *const set[] = {"set", "0x1017", "70000"};
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, device_command(&dev, 3, set, now, &out));
    TEST_ASSERT_EQUAL_STRING("error: 70000 is out of range: 0x1017:00 (UNSIGNED16) holds 0..65535", out_lines[1]);
    /* no output given: the replies go where the node's other lines go */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, device_command(&dev, 2, get, now, NULL));
    TEST_ASSERT_EQUAL_STRING("0x1017:00 = 1000 (0x3E8)", cfg_line);
    TEST_ASSERT_EQUAL_UINT(2U, out_count);
    device_printf(&dev, "a message of the model");
    TEST_ASSERT_EQUAL_STRING("a message of the model", cfg_line);
}

static void a_line_splits_into_words_quotes_and_a_comment(void)
{
    char line[] = "  set 16\t0x2005 \"two words\" # the rest is a comment";
    char *argv[8];
    TEST_ASSERT_EQUAL_INT(4, device_split_words(line, argv, 8));
    TEST_ASSERT_EQUAL_STRING("set", argv[0]);
    TEST_ASSERT_EQUAL_STRING("16", argv[1]);
    TEST_ASSERT_EQUAL_STRING("0x2005", argv[2]);
    TEST_ASSERT_EQUAL_STRING("two words", argv[3]);
    char many[] = "a b c d";
    TEST_ASSERT_EQUAL_INT(-1, device_split_words(many, argv, 3));
    char blank[] = " \t\r\n";
    TEST_ASSERT_EQUAL_INT(0, device_split_words(blank, argv, 3));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(integers_of_any_kind_go_in_within_the_type_and_its_limits);
    RUN_TEST(a_value_the_type_cannot_hold_is_refused_with_the_reason);
    RUN_TEST(reals_and_text_go_in_as_their_types);
    RUN_TEST(values_are_read_by_their_types);
    RUN_TEST(a_command_replies_to_its_own_output_and_the_node_keeps_its_print);
    RUN_TEST(a_line_splits_into_words_quotes_and_a_comment);
    return UNITY_END();
}
