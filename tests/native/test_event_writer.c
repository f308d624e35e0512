/*
 * The event writer (emu/runtime/emu_event_writer.c) against Jansson, which wrote the events before it and still
 * writes every answer: a JSON string of any bytes (quotes, backslashes, every control, DEL, non-ASCII, bytes that are
 * not UTF-8, long ones) is byte for byte what json_dumps(JSON_COMPACT | JSON_ENSURE_ASCII) writes for jstr() of it,
 * over a list of hostile strings and a million random ones; numbers, booleans and hex as Jansson and printf write
 * them; a line that does not fit is cut and marked full.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "runtime/emu_event_writer.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

/* The control protocol's jstr() (emu/control/emu_json.c), the string the events had before the writer. */
static json_t *jstr(const char *text)
{
    json_t *j = json_string(text);
    if (j != NULL) {
        return j;
    }
    char clean[4096];
    size_t n = 0U;
    for (; text[n] != '\0' && n < sizeof clean - 1U; n++) {
        clean[n] = (unsigned char)text[n] < 0x80U ? text[n] : '?';
    }
    clean[n] = '\0';
    return json_string(clean);
}

static char line[64U * 1024U];

/* {"a":1,"k":TEXT} by Jansson and by the writer: the same bytes. */
static void same_as_jansson(const char *text)
{
    json_t *o = json_object();
    (void)json_object_set_new(o, "a", json_integer(1));
    (void)json_object_set_new(o, "k", jstr(text));
    char *expected = json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
    json_decref(o);
    TEST_ASSERT_NOT_NULL(expected);
    event_writer_t w;
    writer_init(&w, line, sizeof line);
    writer_text(&w, "{\"a\":1");
    writer_member_string(&w, EVENT_KEY("k"), text);
    writer_bytes(&w, "}", 1U);
    TEST_ASSERT_FALSE(w.full);
    if (w.len != strlen(expected) || memcmp(line, expected, w.len) != 0) {
        char message[512];
        (void)snprintf(message, sizeof message, "input of %zu bytes, first bytes %02X %02X %02X; Jansson %.100s, writer %.*s",
                       strlen(text), (unsigned char)text[0], text[0] != '\0' ? (unsigned char)text[1] : 0U,
                       text[0] != '\0' && text[1] != '\0' ? (unsigned char)text[2] : 0U, expected,
                       (int)(w.len < 100U ? w.len : 100U), line);
        free(expected);
        TEST_FAIL_MESSAGE(message);
    }
    free(expected);
}

static void a_string_is_written_as_jansson_writes_it(void)
{
    static const char *const hostile[] = {
        "", "plain", "say \"hi\"", "back\\slash", "\\\"", "/slash/", "tab\there", "line\nbreak", "cr\r", "\b\f",
        "\x01\x02\x1B[2J\x1F", "del\x7F", "caf\xC3\xA9", "\xC2\x80\xC2\x9F csi \xC2\x9B", "\xC2\xA0nbsp",
        "\xE2\x82\xAC euro", "\xE2\x80\xA8 line separator", "\xEF\xBF\xBF", "\xEF\xBB\xBF bom",
        "\xF0\x9F\x98\x80 emoji", "\xF4\x8F\xBF\xBF max", "\xF0\x90\x80\x80 first beyond BMP",
        /* not UTF-8: replaced by '?' byte by byte, as jstr() does */
        "\x80", "\xBF", "\xC0\x80 overlong NUL", "\xC1\xBF", "\xE0\x80\x80", "\xE0\x9F\xBF", "\xF0\x80\x80\x80",
        "\xF0\x8F\xBF\xBF", "\xED\xA0\x80 surrogate", "\xED\xBF\xBF", "\xF4\x90\x80\x80 beyond", "\xF5\x80\x80\x80",
        "\xFE", "\xFF\"quote\\", "\xC3", "cut \xE2\x82", "cut \xF0\x9F\x98", "\xC3\x28", "\xE2\x28\xA1",
        "valid \xC3\xA9 then not \xFF with \x01 and \"", "\xC3\xA9\xC3", "\t\xE9\n"};
    for (size_t i = 0U; i < sizeof hostile / sizeof hostile[0]; i++) {
        same_as_jansson(hostile[i]);
    }
    char one[2] = {0, 0};
    for (unsigned b = 1U; b < 256U; b++) {
        one[0] = (char)b;
        same_as_jansson(one);
    }
}

static void a_long_string_is_written_whole_and_one_not_utf8_cut_as_jstr_cuts_it(void)
{
    static char text[10000];
    for (size_t n = 4090U; n < 4100U; n++) {
        memset(text, 'x', n);
        text[n] = '\0';
        same_as_jansson(text); /* valid: whole */
        text[0] = '\xFF';
        same_as_jansson(text); /* not UTF-8: its first 4,095 bytes */
        text[0] = '\x01';
        text[n - 1U] = '\xFF';
        same_as_jansson(text); /* its invalid byte at the end, cut off: still written as not UTF-8 */
    }
    for (size_t i = 0U; i + 3U < sizeof text; i += 3U) {
        memcpy(text + i, "\xE2\x82\xAC", 3U);
    }
    text[sizeof text - 1U - (sizeof text - 1U) % 3U] = '\0';
    same_as_jansson(text);
}

/* xorshift64*: random strings the same in every run. */
static uint64_t random_state = 0x9E3779B97F4A7C15ULL;
static uint32_t random_u32(void)
{
    random_state ^= random_state >> 12;
    random_state ^= random_state << 25;
    random_state ^= random_state >> 27;
    return (uint32_t)((random_state * 0x2545F4914F6CDD1DULL) >> 32);
}

static void random_strings_are_written_as_jansson_writes_them(void)
{
    /* Mostly the bytes that matter (the ends of the ranges RFC 3629 draws, controls, quotes), some of any value. */
    static const unsigned char interesting[] = {'a', ' ', '"', '\\', '/', 0x01, 0x1F, 0x7F, 0x80, 0x8F, 0x90, 0x9F,
                                                0xA0, 0xBF, 0xC0, 0xC1, 0xC2, 0xDF, 0xE0, 0xED, 0xEF, 0xF0, 0xF4,
                                                0xF5, 0xFF, '\n', '\t'};
    char text[64];
    for (unsigned run = 0U; run < 1000000U; run++) {
        const uint32_t r = random_u32();
        const size_t len = r % 24U;
        for (size_t i = 0U; i < len; i++) {
            const uint32_t q = random_u32();
            unsigned char b = (q & 3U) == 0U ? (unsigned char)(q >> 8) : interesting[(q >> 8) % sizeof interesting];
            text[i] = (char)(b == 0U ? 'z' : b);
        }
        text[len] = '\0';
        same_as_jansson(text);
    }
}

/* The number as Jansson writes it in an object, and the writer's member. */
static void number_as_jansson(uint64_t v)
{
    json_t *o = json_object();
    (void)json_object_set_new(o, "a", json_integer(1));
    (void)json_object_set_new(o, "n", json_integer((json_int_t)v));
    char *expected = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    event_writer_t w;
    writer_init(&w, line, sizeof line);
    writer_text(&w, "{\"a\":1");
    writer_member_uint(&w, EVENT_KEY("n"), v);
    writer_bytes(&w, "}", 1U);
    TEST_ASSERT_EQUAL_size_t(strlen(expected), w.len);
    TEST_ASSERT_EQUAL_STRING_LEN(expected, line, w.len);
    free(expected);
}

static void numbers_booleans_and_hex_are_written_as_jansson_and_printf_write_them(void)
{
    static const uint64_t numbers[] = {0U, 1U, 9U, 10U, 99U, 100U, 255U, 0x7E5U, 65535U, 0x7FFFFFFFU, 0x80000000U,
                                       0xFFFFFFFFU, 1000000U, 1234567890123ULL, 0x7FFFFFFFFFFFFFFFULL};
    for (size_t i = 0U; i < sizeof numbers / sizeof numbers[0]; i++) {
        number_as_jansson(numbers[i]);
    }
    for (unsigned run = 0U; run < 20000U; run++) {
        number_as_jansson(((uint64_t)random_u32() << 31) ^ random_u32());
    }
    event_writer_t w;
    writer_init(&w, line, sizeof line);
    writer_member_bool(&w, EVENT_KEY("rtr"), true);
    writer_member_bool(&w, EVENT_KEY("ok"), false);
    static const uint8_t bytes[] = {0x00, 0x01, 0x7F, 0x80, 0xA5, 0xFF, 0x0F, 0xF0};
    writer_member_hex(&w, EVENT_KEY("data"), bytes, sizeof bytes);
    writer_member_hex(&w, EVENT_KEY("none"), bytes, 0U);
    writer_member_plain(&w, EVENT_KEY("text"), "rx 181#01", 9U);
    const char *expected_members = ",\"rtr\":true,\"ok\":false,\"data\":\"00017F80A5FF0FF0\",\"none\":\"\",\"text\":\"rx 181#01\"";
    TEST_ASSERT_EQUAL_size_t(strlen(expected_members), w.len);
    TEST_ASSERT_EQUAL_STRING_LEN(expected_members, line, w.len);
    char expected[64];
    for (unsigned run = 0U; run < 20000U; run++) {
        const uint32_t id = random_u32() >> (random_u32() % 32U);
        const unsigned digits = run % 2U == 0U ? 3U : 8U;
        writer_init(&w, line, sizeof line);
        writer_hex_uint(&w, id, digits);
        (void)snprintf(expected, sizeof expected, "%0*X", (int)digits, (unsigned)id);
        TEST_ASSERT_EQUAL_STRING_LEN(expected, line, strlen(expected));
        TEST_ASSERT_EQUAL_size_t(strlen(expected), w.len);
        const uint64_t us = ((uint64_t)random_u32() << (random_u32() % 20U)) + random_u32() % 2U;
        writer_init(&w, line, sizeof line);
        writer_seconds(&w, us);
        (void)snprintf(expected, sizeof expected, "%.6f", (double)us / 1e6);
        TEST_ASSERT_EQUAL_STRING_LEN(expected, line, strlen(expected));
        TEST_ASSERT_EQUAL_size_t(strlen(expected), w.len);
    }
}

static void what_does_not_fit_is_cut_and_the_writer_full(void)
{
    char small[8];
    event_writer_t w;
    writer_init(&w, small, sizeof small);
    writer_text(&w, "event ");
    TEST_ASSERT_FALSE(w.full);
    writer_text(&w, "frame");
    TEST_ASSERT_TRUE(w.full);
    TEST_ASSERT_EQUAL_size_t(8U, w.len);
    TEST_ASSERT_EQUAL_STRING_LEN("event fr", small, 8U); /* as snprintf cuts */
    writer_uint(&w, 5U);
    TEST_ASSERT_EQUAL_size_t(8U, w.len);
    writer_init(&w, small, sizeof small);
    writer_json_string(&w, "\x01\x02");    /* "\u0001\u0002": 14 bytes */
    TEST_ASSERT_TRUE(w.full);
    writer_init(&w, small, sizeof small);
    writer_json_string(&w, "\xE9\x01\x01"); /* not UTF-8: "?\u0001..." does not fit either */
    TEST_ASSERT_TRUE(w.full);
    writer_init(&w, small, sizeof small);
    writer_json_string(&w, "\xC3\xA9\xC3\xA9\xFF"); /* "\u00E9\u00E9... does not fit; "?????" does */
    TEST_ASSERT_FALSE(w.full);
    TEST_ASSERT_EQUAL_STRING_LEN("\"?????\"", small, w.len);
    writer_init(&w, small, sizeof small);
    writer_hex_bytes(&w, (const uint8_t *)"abcde", 5U);
    TEST_ASSERT_TRUE(w.full);
    TEST_ASSERT_EQUAL_size_t(0U, w.len);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_string_is_written_as_jansson_writes_it);
    RUN_TEST(a_long_string_is_written_whole_and_one_not_utf8_cut_as_jstr_cuts_it);
    RUN_TEST(random_strings_are_written_as_jansson_writes_them);
    RUN_TEST(numbers_booleans_and_hex_are_written_as_jansson_and_printf_write_them);
    RUN_TEST(what_does_not_fit_is_cut_and_the_writer_full);
    return UNITY_END();
}
