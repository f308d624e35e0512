/* The DCF writer (eds/eds_write.c) with current values as canopen-emu's export-dcf gives them (any bytes an SDO
 * master wrote): a value a line of a CiA 306 file cannot hold is refused with the entry named and nothing written
 * (a line break in a string wrote sections and keys of the writer's choosing); what a line can hold is written
 * whole and reads back as the same bytes. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eds.h"
#include "unity.h"

/* A device with a string of each kind, a number after them, and long values. */
static const char DEVICE[] =
    "[DeviceInfo]\nVendorName=v\nVendorNumber=1\nProductName=p\nProductNumber=1\nRevisionNumber=1\n"
    "NrOfRXPDO=0\nNrOfTXPDO=0\n"
    "[MandatoryObjects]\nSupportedObjects=3\n1=0x1000\n2=0x1001\n3=0x1018\n"
    "[1000]\nParameterName=t\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n"
    "[1001]\nParameterName=e\nDataType=0x0005\nAccessType=ro\nDefaultValue=0\n"
    "[1018]\nParameterName=id\nObjectType=0x9\nSubNumber=2\n"
    "[1018sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=1\n"
    "[1018sub1]\nParameterName=v\nDataType=0x0007\nAccessType=ro\nDefaultValue=1\n"
    "[ManufacturerObjects]\nSupportedObjects=5\n1=0x2005\n2=0x2006\n3=0x2007\n4=0x2008\n5=0x2009\n"
    "[2005]\nParameterName=label\nDataType=0x0009\nAccessType=rw\nDefaultValue=abc\n"
    "[2006]\nParameterName=count\nDataType=0x0005\nAccessType=rw\nDefaultValue=3\n"
    "[2007]\nParameterName=unicode\nDataType=0x000B\nAccessType=rw\nDefaultValue=uni\n"
    "[2008]\nParameterName=octets\nDataType=0x000A\nAccessType=rw\nDefaultValue=0102\n"
    "[2009]\nParameterName=long\nDataType=0x0009\nAccessType=rw\nDefaultValue=";

/* The current values the test gives, as canopen-emu does: the entry's bytes as the SDO server holds them. */
typedef struct current {
    uint16_t index;
    uint8_t bytes[64];
    size_t len;
} current_t;

static current_t currents[4];
static size_t n_currents;
static eds_file_t *device;
static char error[512];

static void set_current(uint16_t index, const void *bytes, size_t len)
{
    TEST_ASSERT_TRUE(n_currents < sizeof currents / sizeof currents[0] && len <= sizeof currents[0].bytes);
    currents[n_currents].index = index;
    memset(currents[n_currents].bytes, 0, sizeof currents[0].bytes); /* padded with NULs, as a row of a capacity */
    memcpy(currents[n_currents].bytes, bytes, len);
    currents[n_currents].len = sizeof currents[0].bytes;
    n_currents++;
}

static long current_value(void *ctx, const eds_entry_t *e, uint8_t *buf, size_t cap)
{
    (void)ctx;
    for (size_t i = 0; i < n_currents; i++) {
        if (currents[i].index == e->index && e->sub == 0U && currents[i].len <= cap) {
            memcpy(buf, currents[i].bytes, currents[i].len);
            return (long)currents[i].len;
        }
    }
    return -1;
}

/* Writes the device (a DCF with the current values, or an EDS): the return of eds_write, the text in *text. */
static int write_device(bool dcf, const char *file_name, char **text, size_t *len)
{
    FILE *out = open_memstream(text, len);
    TEST_ASSERT_NOT_NULL(out);
    eds_write_options_t o;
    memset(&o, 0, sizeof o);
    o.dcf = dcf;
    o.node_id = 5U;
    o.file_name = file_name;
    o.current = dcf ? current_value : NULL;
    o.error = error;
    o.error_cap = sizeof error;
    errno = 0;
    const int rc = eds_write(out, device, &o);
    const int saved = errno;
    fclose(out);
    errno = saved;
    return rc;
}

static void assert_refused(const char *entry, const char *why)
{
    char *text = NULL;
    size_t len = 0U;
    TEST_ASSERT_EQUAL_INT(-1, write_device(true, NULL, &text, &len));
    TEST_ASSERT_EQUAL_INT(EINVAL, errno);
    TEST_ASSERT_EQUAL_size_t(0U, len); /* nothing written, not a file cut short */
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(error, entry), error);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(error, why), error);
    free(text);
}

/* The DCF written with the current values, read again (no errors). */
static eds_file_t *written_and_read_back(bool dcf)
{
    char *text = NULL;
    size_t len = 0U;
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, write_device(dcf, "x.dcf", &text, &len), error);
    eds_file_t *back = eds_read_buffer("x.dcf", text, len);
    free(text);
    TEST_ASSERT_NOT_NULL(back);
    TEST_ASSERT_EQUAL_UINT32(0U, back->errors);
    return back;
}

static const eds_value_t *param_of(const eds_file_t *f, uint16_t index)
{
    const eds_entry_t *e = eds_find(f, index, 0U);
    TEST_ASSERT_NOT_NULL(e);
    TEST_ASSERT_EQUAL_INT(EDS_V_BYTES, e->param.kind);
    return &e->param;
}

void setUp(void)
{
    /* 0x2009's default: 2000 characters, longer than any fixed buffer of the writer */
    static char text[sizeof DEVICE + 2002];
    memcpy(text, DEVICE, sizeof DEVICE - 1U);
    memset(text + sizeof DEVICE - 1U, 'x', 2000U);
    memcpy(text + sizeof DEVICE - 1U + 2000U, "\n", 2U);
    device = eds_read_buffer("device.eds", text, strlen(text));
    TEST_ASSERT_NOT_NULL(device);
    TEST_ASSERT_EQUAL_UINT32(0U, device->errors);
    n_currents = 0U;
    error[0] = '\0';
}

void tearDown(void)
{
    eds_free(device);
}

static void a_line_break_in_a_visible_string_is_refused_and_nothing_written(void)
{
    static const char injected[] = "x\n[2006]\nParameterValue=7";
    set_current(0x2005U, injected, strlen(injected));
    assert_refused("0x2005:00", "a line break");
    n_currents = 0U;
    set_current(0x2005U, "x\r[2006]", 8U); /* a lone CR ends a line too */
    assert_refused("0x2005:00", "a line break");
}

static void a_unicode_string_that_is_not_a_line_of_text_is_refused(void)
{
    static const uint8_t line_break[] = {'a', 0, '\n', 0, 'b', 0};
    set_current(0x2007U, line_break, sizeof line_break);
    assert_refused("0x2007:00", "a line break");
    n_currents = 0U;
    static const uint8_t lone_surrogate[] = {'a', 0, 0x00, 0xD8, 'b', 0};
    set_current(0x2007U, lone_surrogate, sizeof lone_surrogate);
    assert_refused("0x2007:00", "unpaired UTF-16 surrogate");
}

static void bytes_that_are_not_utf8_are_refused(void)
{
    set_current(0x2005U, "caf\xE9", 4U); /* Latin-1: the reader would take the whole file as Latin-1 */
    assert_refused("0x2005:00", "not UTF-8");
}

static void strings_a_line_can_hold_are_written_and_read_back_as_the_same_bytes(void)
{
    static const char visible[] = "Gr\xC3\xBC\xC3\x9F" "e \x1B[1m; [2006] = 7";
    static const uint8_t unicode[] = {0xE4, 0, 'b', 0, 0x3D, 0xD8, 0x00, 0xDE}; /* "äb😀" */
    static const uint8_t octets[] = {'\n', '\r', 0, '[', 0xFF};
    set_current(0x2005U, visible, strlen(visible));
    set_current(0x2007U, unicode, sizeof unicode);
    set_current(0x2008U, octets, sizeof octets);
    eds_file_t *back = written_and_read_back(true);
    const eds_value_t *v = param_of(back, 0x2005U);
    TEST_ASSERT_EQUAL_size_t(strlen(visible), v->len);
    TEST_ASSERT_EQUAL_MEMORY(visible, v->bytes, v->len);
    v = param_of(back, 0x2007U);
    TEST_ASSERT_EQUAL_size_t(sizeof unicode, v->len); /* the U+0000 padding ends it, as a NUL ends a string */
    TEST_ASSERT_EQUAL_MEMORY(unicode, v->bytes, v->len);
    v = param_of(back, 0x2008U);
    TEST_ASSERT_EQUAL_size_t(64U, v->len); /* OCTET_STRING: hexadecimal digits, every byte kept */
    TEST_ASSERT_EQUAL_MEMORY(octets, v->bytes, sizeof octets);
    const eds_entry_t *count = eds_find(back, 0x2006U, 0U);
    TEST_ASSERT_NOT_NULL(count);
    TEST_ASSERT_EQUAL_UINT(3U, (unsigned)count->param.u);
    eds_free(back);
}

static void long_values_are_written_whole(void)
{
    for (int dcf = 0; dcf < 2; dcf++) {
        eds_file_t *back = written_and_read_back(dcf != 0);
        const eds_entry_t *e = eds_find(back, 0x2009U, 0U);
        TEST_ASSERT_NOT_NULL(e);
        TEST_ASSERT_EQUAL_size_t(2000U, e->def.len);
        if (dcf != 0) {
            TEST_ASSERT_EQUAL_size_t(2000U, e->param.len);
        }
        eds_free(back);
    }
}

static void a_file_name_with_a_line_break_is_refused(void)
{
    char *text = NULL;
    size_t len = 0U;
    TEST_ASSERT_EQUAL_INT(-1, write_device(false, "x\n[2006]\nParameterValue=7", &text, &len));
    TEST_ASSERT_EQUAL_size_t(0U, len);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(error, "file name has a line break"), error);
    free(text);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_line_break_in_a_visible_string_is_refused_and_nothing_written);
    RUN_TEST(a_unicode_string_that_is_not_a_line_of_text_is_refused);
    RUN_TEST(bytes_that_are_not_utf8_are_refused);
    RUN_TEST(strings_a_line_can_hold_are_written_and_read_back_as_the_same_bytes);
    RUN_TEST(long_values_are_written_whole);
    RUN_TEST(a_file_name_with_a_line_break_is_refused);
    return UNITY_END();
}
