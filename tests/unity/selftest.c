/*
 * Self-test of the minimal Unity-compatible harness.
 *
 * - every assert kind is run once with passing arguments (must not fail,
 *   must print nothing);
 * - every assert kind is run with failing arguments inside a nested
 *   TEST_PROTECT(): it must set Unity.CurrentTestFailed, abort the function
 *   (longjmp) and print exactly the expected upstream-style line; the flag
 *   is then reset so the enclosing test keeps passing;
 * - a complete run (UnityBegin / UnityDefaultTestRun / UnityEnd) is captured
 *   and compared character by character, including the summary block.
 *
 * The program exits 0 only if the harness behaves correctly.
 * Output is captured through UnitySetOutputHook(), a harness extension, so
 * this file is only built with the bundled harness (not upstream Unity).
 */
#include "unity.h"

#include <string.h>

#ifndef UNITY_HARNESS_MINI
#error "selftest.c tests the bundled harness, not upstream Unity"
#endif

/*-------------------------------------------------------
 * Output capture
 *-------------------------------------------------------*/
static char spy_buf[2048];
static size_t spy_len;

static void spy_putc(int c)
{
    if (spy_len < sizeof spy_buf - 1u) {
        spy_buf[spy_len++] = (char)c;
    }
    spy_buf[spy_len] = '\0';
}

static void spy_start(void)
{
    spy_len = 0u;
    spy_buf[0] = '\0';
    (void)UnitySetOutputHook(spy_putc);
}

static void spy_stop(void)
{
    (void)UnitySetOutputHook(NULL);
}

/* Expected-text builder */
static char exp_buf[2048];
static size_t exp_len;

static void eb_reset(void)
{
    exp_len = 0u;
    exp_buf[0] = '\0';
}

static void eb_str(const char *s)
{
    while ((s != NULL) && (*s != '\0') && (exp_len < sizeof exp_buf - 1u)) {
        exp_buf[exp_len++] = *s++;
    }
    exp_buf[exp_len] = '\0';
}

static void eb_num(unsigned long v)
{
    char tmp[24];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while ((n > 0) && (exp_len < sizeof exp_buf - 1u)) {
        exp_buf[exp_len++] = tmp[--n];
    }
    exp_buf[exp_len] = '\0';
}

/* "<file>:<line>:<test>:<kind><tail>" */
static void eb_result_line(const char *file, int line, const char *test, const char *kind, const char *tail)
{
    eb_str(file);
    eb_str(":");
    eb_num((unsigned long)line);
    eb_str(":");
    eb_str(test);
    eb_str(":");
    eb_str(kind);
    eb_str(tail);
}

/*-------------------------------------------------------
 * setUp / tearDown (required by the harness, as upstream)
 *-------------------------------------------------------*/
static unsigned setup_calls;
static unsigned teardown_calls;

void setUp(void)
{
    setup_calls++;
}

void tearDown(void)
{
    teardown_calls++;
}

/*-------------------------------------------------------
 * Running one function under a nested TEST_PROTECT
 *-------------------------------------------------------*/
static volatile int g_line;        /* line of the assert in the case */
static volatile int g_after;       /* set if code after the assert ran */
static volatile int g_returned;    /* set if the case function returned */

typedef enum { EXPECT_PASS, EXPECT_FAIL, EXPECT_IGNORE } expect_t;

/* Set on any detected problem; main() also checks it, so a harness that is
 * too broken to count its own failures still yields a non-zero exit. */
static int selftest_bad;

static void report_mismatch(const char *what)
{
    selftest_bad = 1;
    spy_stop();
    UnityPrint("\n  selftest: ");
    UnityPrint(what);
    UnityPrint("\n    expected output: ");
    UnityPrint(exp_buf);
    UnityPrint("\n    captured output: ");
    UnityPrint(spy_buf);
    UNITY_OUTPUT_CHAR('\n');
}

/* Returns NULL if fn behaved as expected, else a description. */
static const char *run_case(UnityTestFunction fn, expect_t expect, const char *tail)
{
    jmp_buf saved;
    UNITY_COUNTER_TYPE failed;
    UNITY_COUNTER_TYPE ignored;

    memcpy(saved, Unity.AbortFrame, sizeof(jmp_buf));
    g_line = -1;
    g_after = 0;
    g_returned = 0;

    spy_start();
    if (TEST_PROTECT()) {
        fn();
        g_returned = 1;
    }
    spy_stop();
    memcpy(Unity.AbortFrame, saved, sizeof(jmp_buf));

    failed = Unity.CurrentTestFailed;
    ignored = Unity.CurrentTestIgnored;
    /* undo the effect of the nested failure on the enclosing test */
    Unity.CurrentTestFailed = 0u;
    Unity.CurrentTestIgnored = 0u;

    eb_reset();
    if (expect == EXPECT_PASS) {
        if (failed != 0u || ignored != 0u) {
            return "passing assert failed";
        }
        if (!g_returned) {
            return "passing assert aborted the test";
        }
        if (spy_len != 0u) {
            return "passing assert printed something";
        }
        return NULL;
    }

    eb_result_line(Unity.TestFile, g_line, Unity.CurrentTestName,
                   (expect == EXPECT_FAIL) ? "FAIL" : "IGNORE", tail);
    if (expect == EXPECT_FAIL && (failed != 1u || ignored != 0u)) {
        return "failing assert did not set CurrentTestFailed";
    }
    if (expect == EXPECT_IGNORE && (ignored != 1u || failed != 0u)) {
        return "ignore did not set CurrentTestIgnored";
    }
    if (g_after || g_returned) {
        return "test body continued after failing assert (no longjmp)";
    }
    if (strcmp(spy_buf, exp_buf) != 0) {
        return "output differs";
    }
    return NULL;
}

/* One line per case so that __LINE__ of g_line and of the assert agree. */
#define CASE(name, ...)                                                                            \
    static void name(void)                                                                         \
    {                                                                                              \
        g_line = __LINE__; __VA_ARGS__; g_after = 1;                                               \
    }

/*-------------------------------------------------------
 * Data
 *-------------------------------------------------------*/
static const UNITY_UINT8 mem_a[4] = {1, 2, 3, 4};
static const UNITY_UINT8 mem_b[4] = {1, 2, 4, 4};
static const UNITY_UINT8 mem_c[4] = {1, 2, 3, 4};
static const UNITY_UINT32 u32_a[3] = {1u, 2u, 3u};
static const UNITY_UINT32 u32_b[3] = {1u, 2u, 4000000000u};
static const int int_a[3] = {-1, 0, 1};
static const int int_b[3] = {-1, 0, 1};
static const int int_c[3] = {-1, -5, 1};
static const UNITY_INT16 i16_a[2] = {-300, 7};
static const UNITY_INT16 i16_b[2] = {-300, -7};
static const UNITY_UINT64 u64_a[2] = {UINT64_MAX, 1u};
static const UNITY_UINT64 u64_b[2] = {UINT64_MAX, 2u};
static int dummy_object;
static const char *const null_str = NULL;
static volatile float f_zero = 0.0f;

/*-------------------------------------------------------
 * Failing cases (each must fail with the given text)
 *-------------------------------------------------------*/
CASE(f_assert, TEST_ASSERT(0))
CASE(f_assert_msg, TEST_ASSERT_MESSAGE(1 == 2, "custom"))
CASE(f_true, TEST_ASSERT_TRUE(0))
CASE(f_true_msg, TEST_ASSERT_TRUE_MESSAGE(0, "t"))
CASE(f_false, TEST_ASSERT_FALSE(1))
CASE(f_false_msg, TEST_ASSERT_FALSE_MESSAGE(1, "f"))
CASE(f_null, TEST_ASSERT_NULL(&dummy_object))
CASE(f_null_msg, TEST_ASSERT_NULL_MESSAGE(&dummy_object, "n"))
CASE(f_not_null, TEST_ASSERT_NOT_NULL(null_str))
CASE(f_not_null_msg, TEST_ASSERT_NOT_NULL_MESSAGE(null_str, "nn"))
CASE(f_equal, TEST_ASSERT_EQUAL(5, 6))
CASE(f_equal_msg, TEST_ASSERT_EQUAL_MESSAGE(5, 6, "ctx"))
CASE(f_not_equal, TEST_ASSERT_NOT_EQUAL(5, 5))
CASE(f_not_equal_msg, TEST_ASSERT_NOT_EQUAL_MESSAGE(5, 5, "ne"))
CASE(f_int, TEST_ASSERT_EQUAL_INT(-5, 6))
CASE(f_int_msg, TEST_ASSERT_EQUAL_INT_MESSAGE(-5, 6, "m"))
CASE(f_int8, TEST_ASSERT_EQUAL_INT8(-1, 1))
CASE(f_int8_msg, TEST_ASSERT_EQUAL_INT8_MESSAGE(-128, 127, "m"))
CASE(f_int16, TEST_ASSERT_EQUAL_INT16(-300, 300))
CASE(f_int16_msg, TEST_ASSERT_EQUAL_INT16_MESSAGE(-300, 300, "m"))
CASE(f_int32, TEST_ASSERT_EQUAL_INT32(-70000, 70000))
CASE(f_int32_msg, TEST_ASSERT_EQUAL_INT32_MESSAGE(INT32_MIN, INT32_MAX, "m"))
CASE(f_int64, TEST_ASSERT_EQUAL_INT64(INT64_MIN, INT64_MAX))
CASE(f_int64_msg, TEST_ASSERT_EQUAL_INT64_MESSAGE(-1, 0, "m"))
CASE(f_uint, TEST_ASSERT_EQUAL_UINT(5u, 6u))
CASE(f_uint_msg, TEST_ASSERT_EQUAL_UINT_MESSAGE(5u, 6u, "m"))
CASE(f_uint8, TEST_ASSERT_EQUAL_UINT8(255u, 254u))
CASE(f_uint8_msg, TEST_ASSERT_EQUAL_UINT8_MESSAGE(255u, 254u, "m"))
CASE(f_uint16, TEST_ASSERT_EQUAL_UINT16(65535u, 0u))
CASE(f_uint16_msg, TEST_ASSERT_EQUAL_UINT16_MESSAGE(65535u, 0u, "m"))
CASE(f_uint32, TEST_ASSERT_EQUAL_UINT32(4294967295u, 0u))
CASE(f_uint32_msg, TEST_ASSERT_EQUAL_UINT32_MESSAGE(4294967295u, 0u, "m"))
CASE(f_uint64, TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, 0u))
CASE(f_uint64_msg, TEST_ASSERT_EQUAL_UINT64_MESSAGE(UINT64_MAX, 0u, "m"))
CASE(f_hex, TEST_ASSERT_EQUAL_HEX(0x1234u, 0x1235u))
CASE(f_hex_msg, TEST_ASSERT_EQUAL_HEX_MESSAGE(0x1234u, 0x1235u, "m"))
CASE(f_hex8, TEST_ASSERT_EQUAL_HEX8(0xABu, 0xACu))
CASE(f_hex8_msg, TEST_ASSERT_EQUAL_HEX8_MESSAGE(0x0Au, 0x0Bu, "m"))
CASE(f_hex16, TEST_ASSERT_EQUAL_HEX16(0xABu, 0xBEEFu))
CASE(f_hex16_msg, TEST_ASSERT_EQUAL_HEX16_MESSAGE(0xABu, 0xBEEFu, "m"))
CASE(f_hex32, TEST_ASSERT_EQUAL_HEX32(0xDEADBEEFu, 0u))
CASE(f_hex32_msg, TEST_ASSERT_EQUAL_HEX32_MESSAGE(0xDEADBEEFu, 0u, "m"))
CASE(f_hex64, TEST_ASSERT_EQUAL_HEX64(0x0123456789ABCDEFull, 0u))
CASE(f_hex64_msg, TEST_ASSERT_EQUAL_HEX64_MESSAGE(0x0123456789ABCDEFull, 0u, "m"))
CASE(f_string, TEST_ASSERT_EQUAL_STRING("abc", "abd"))
CASE(f_string_msg, TEST_ASSERT_EQUAL_STRING_MESSAGE("abc", "ab", "m"))
CASE(f_string_null, TEST_ASSERT_EQUAL_STRING(null_str, "x"))
CASE(f_string_esc, TEST_ASSERT_EQUAL_STRING("a\n", "b\x01"))
CASE(f_string_len, TEST_ASSERT_EQUAL_STRING_LEN("abcX", "abcY", 4))
CASE(f_string_len_msg, TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE("abcXZZ", "abcYZZ", 4, "m"))
CASE(f_memory, TEST_ASSERT_EQUAL_MEMORY(mem_a, mem_b, 4))
CASE(f_memory_msg, TEST_ASSERT_EQUAL_MEMORY_MESSAGE(mem_a, mem_b, 4, "m"))
CASE(f_memory_zero, TEST_ASSERT_EQUAL_MEMORY(mem_a, mem_b, 0))
CASE(f_memory_exp_null, TEST_ASSERT_EQUAL_MEMORY(NULL, mem_b, 4))
CASE(f_memory_act_null, TEST_ASSERT_EQUAL_MEMORY(mem_a, NULL, 4))
CASE(f_hex8_array, TEST_ASSERT_EQUAL_HEX8_ARRAY(mem_a, mem_b, 4))
CASE(f_hex8_array_msg, TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(mem_a, mem_b, 4, "m"))
CASE(f_uint8_array, TEST_ASSERT_EQUAL_UINT8_ARRAY(mem_a, mem_b, 4))
CASE(f_uint8_array_msg, TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(mem_a, mem_b, 4, "m"))
CASE(f_uint32_array, TEST_ASSERT_EQUAL_UINT32_ARRAY(u32_a, u32_b, 3))
CASE(f_uint32_array_msg, TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(u32_a, u32_b, 3, "m"))
CASE(f_uint32_array_zero, TEST_ASSERT_EQUAL_UINT32_ARRAY(u32_a, u32_b, 0))
CASE(f_int_array, TEST_ASSERT_EQUAL_INT_ARRAY(int_a, int_c, 3))
CASE(f_int16_array, TEST_ASSERT_EQUAL_INT16_ARRAY(i16_a, i16_b, 2))
CASE(f_uint64_array, TEST_ASSERT_EQUAL_UINT64_ARRAY(u64_a, u64_b, 2))
CASE(f_gt, TEST_ASSERT_GREATER_THAN(5, 3))
CASE(f_gt_eq, TEST_ASSERT_GREATER_THAN(5, 5))
CASE(f_gt_msg, TEST_ASSERT_GREATER_THAN_MESSAGE(5, 3, "m"))
CASE(f_gt_int, TEST_ASSERT_GREATER_THAN_INT(-1, -2))
CASE(f_gt_uint, TEST_ASSERT_GREATER_THAN_UINT(0xFFFFFFFFu, 1u))
CASE(f_gt_uint32, TEST_ASSERT_GREATER_THAN_UINT32(0xFFFFFFFFu, 1u))
CASE(f_gt_uint64, TEST_ASSERT_GREATER_THAN_UINT64(UINT64_MAX, 1u))
CASE(f_gt_int64, TEST_ASSERT_GREATER_THAN_INT64(0, -1))
CASE(f_ge, TEST_ASSERT_GREATER_OR_EQUAL(5, 4))
CASE(f_ge_msg, TEST_ASSERT_GREATER_OR_EQUAL_MESSAGE(5, 4, "m"))
CASE(f_ge_uint64, TEST_ASSERT_GREATER_OR_EQUAL_UINT64(UINT64_MAX, 0u))
CASE(f_lt, TEST_ASSERT_LESS_THAN(5, 5))
CASE(f_lt_msg, TEST_ASSERT_LESS_THAN_MESSAGE(5, 6, "m"))
CASE(f_lt_uint32, TEST_ASSERT_LESS_THAN_UINT32(1u, 0xFFFFFFFFu))
CASE(f_lt_int64, TEST_ASSERT_LESS_THAN_INT64(INT64_MIN, 0))
CASE(f_le, TEST_ASSERT_LESS_OR_EQUAL(5, 6))
CASE(f_le_msg, TEST_ASSERT_LESS_OR_EQUAL_MESSAGE(5, 6, "m"))
CASE(f_le_uint64, TEST_ASSERT_LESS_OR_EQUAL_UINT64(1u, UINT64_MAX))
CASE(f_le_uint, TEST_ASSERT_LESS_OR_EQUAL_UINT(1u, 2u))
CASE(f_uint_within, TEST_ASSERT_UINT_WITHIN(2u, 10u, 13u))
CASE(f_uint_within_msg, TEST_ASSERT_UINT_WITHIN_MESSAGE(2u, 13u, 10u, "m"))
CASE(f_uint32_within, TEST_ASSERT_UINT32_WITHIN(1u, 0u, 0xFFFFFFFFu))
CASE(f_uint64_within, TEST_ASSERT_UINT64_WITHIN(1u, 0u, UINT64_MAX))
CASE(f_int_within, TEST_ASSERT_INT_WITHIN(3, -10, -14))
CASE(f_int_within_msg, TEST_ASSERT_INT_WITHIN_MESSAGE(3, -10, -6, "m"))
CASE(f_int64_within, TEST_ASSERT_INT64_WITHIN(1, INT64_MIN, INT64_MAX))
CASE(f_float_within, TEST_ASSERT_FLOAT_WITHIN(0.1f, 1.0f, 1.2f))
CASE(f_float_within_msg, TEST_ASSERT_FLOAT_WITHIN_MESSAGE(0.1f, 1.0f, -1.2f, "m"))
CASE(f_float_nan, TEST_ASSERT_FLOAT_WITHIN(1.0f, 1.0f, f_zero / f_zero))
CASE(f_float_inf, TEST_ASSERT_FLOAT_WITHIN(1.0f, 1.0f, 1.0f / f_zero))
CASE(f_equal_float, TEST_ASSERT_EQUAL_FLOAT(1.5f, 1.6f))
CASE(f_equal_float_msg, TEST_ASSERT_EQUAL_FLOAT_MESSAGE(0.1f, 0.2f, "m"))
CASE(f_equal_float_small, TEST_ASSERT_EQUAL_FLOAT(1e-20f, 2e-20f))
CASE(f_equal_float_big, TEST_ASSERT_EQUAL_FLOAT(123456789.0f, 1.0f))
CASE(f_equal_float_zero, TEST_ASSERT_EQUAL_FLOAT(0.0f, 0.0001f))
CASE(f_double_within, TEST_ASSERT_DOUBLE_WITHIN(0.001, 1.0, 1.01))
CASE(f_double_within_msg, TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(0.001, 1.0, 1.01, "m"))
CASE(f_equal_double, TEST_ASSERT_EQUAL_DOUBLE(3.25, 3.5))
CASE(f_bits, TEST_ASSERT_BITS(0xF0u, 0xA0u, 0xB0u))
CASE(f_bits_msg, TEST_ASSERT_BITS_MESSAGE(0xF0u, 0xA0u, 0xB0u, "m"))
CASE(f_bit_high, TEST_ASSERT_BIT_HIGH(3, 0x00u))
CASE(f_bit_high_msg, TEST_ASSERT_BIT_HIGH_MESSAGE(3, 0x00u, "m"))
CASE(f_bit_low, TEST_ASSERT_BIT_LOW(0, 0x01u))
CASE(f_bit_low_msg, TEST_ASSERT_BIT_LOW_MESSAGE(31, 0x80000000u, "m"))
CASE(f_fail, TEST_FAIL())
CASE(f_fail_msg, TEST_FAIL_MESSAGE("boom"))
CASE(f_fail_msg_space, TEST_FAIL_MESSAGE(" leading space"))
CASE(i_ignore, TEST_IGNORE())
CASE(i_ignore_msg, TEST_IGNORE_MESSAGE("not yet"))

#define X32 "XXXXXXXXXXXXXXXXXXXXXXXX"

static const struct {
    UnityTestFunction fn;
    expect_t expect;
    const char *tail;
} fail_cases[] = {
    {f_assert, EXPECT_FAIL, ": Expression Evaluated To FALSE"},
    {f_assert_msg, EXPECT_FAIL, ": custom"},
    {f_true, EXPECT_FAIL, ": Expected TRUE Was FALSE"},
    {f_true_msg, EXPECT_FAIL, ": t"},
    {f_false, EXPECT_FAIL, ": Expected FALSE Was TRUE"},
    {f_false_msg, EXPECT_FAIL, ": f"},
    {f_null, EXPECT_FAIL, ": Expected NULL"},
    {f_null_msg, EXPECT_FAIL, ": n"},
    {f_not_null, EXPECT_FAIL, ": Expected Non-NULL"},
    {f_not_null_msg, EXPECT_FAIL, ": nn"},
    {f_equal, EXPECT_FAIL, ": Expected 5 Was 6"},
    {f_equal_msg, EXPECT_FAIL, ": Expected 5 Was 6. ctx"},
    {f_not_equal, EXPECT_FAIL, ": Expected Not-Equal"},
    {f_not_equal_msg, EXPECT_FAIL, ": ne"},
    {f_int, EXPECT_FAIL, ": Expected -5 Was 6"},
    {f_int_msg, EXPECT_FAIL, ": Expected -5 Was 6. m"},
    {f_int8, EXPECT_FAIL, ": Expected -1 Was 1"},
    {f_int8_msg, EXPECT_FAIL, ": Expected -128 Was 127. m"},
    {f_int16, EXPECT_FAIL, ": Expected -300 Was 300"},
    {f_int16_msg, EXPECT_FAIL, ": Expected -300 Was 300. m"},
    {f_int32, EXPECT_FAIL, ": Expected -70000 Was 70000"},
    {f_int32_msg, EXPECT_FAIL, ": Expected -2147483648 Was 2147483647. m"},
    {f_int64, EXPECT_FAIL, ": Expected -9223372036854775808 Was 9223372036854775807"},
    {f_int64_msg, EXPECT_FAIL, ": Expected -1 Was 0. m"},
    {f_uint, EXPECT_FAIL, ": Expected 5 Was 6"},
    {f_uint_msg, EXPECT_FAIL, ": Expected 5 Was 6. m"},
    {f_uint8, EXPECT_FAIL, ": Expected 255 Was 254"},
    {f_uint8_msg, EXPECT_FAIL, ": Expected 255 Was 254. m"},
    {f_uint16, EXPECT_FAIL, ": Expected 65535 Was 0"},
    {f_uint16_msg, EXPECT_FAIL, ": Expected 65535 Was 0. m"},
    {f_uint32, EXPECT_FAIL, ": Expected 4294967295 Was 0"},
    {f_uint32_msg, EXPECT_FAIL, ": Expected 4294967295 Was 0. m"},
    {f_uint64, EXPECT_FAIL, ": Expected 18446744073709551615 Was 0"},
    {f_uint64_msg, EXPECT_FAIL, ": Expected 18446744073709551615 Was 0. m"},
    {f_hex, EXPECT_FAIL, ": Expected 0x00001234 Was 0x00001235"},
    {f_hex_msg, EXPECT_FAIL, ": Expected 0x00001234 Was 0x00001235. m"},
    {f_hex8, EXPECT_FAIL, ": Expected 0xAB Was 0xAC"},
    {f_hex8_msg, EXPECT_FAIL, ": Expected 0x0A Was 0x0B. m"},
    {f_hex16, EXPECT_FAIL, ": Expected 0x00AB Was 0xBEEF"},
    {f_hex16_msg, EXPECT_FAIL, ": Expected 0x00AB Was 0xBEEF. m"},
    {f_hex32, EXPECT_FAIL, ": Expected 0xDEADBEEF Was 0x00000000"},
    {f_hex32_msg, EXPECT_FAIL, ": Expected 0xDEADBEEF Was 0x00000000. m"},
    {f_hex64, EXPECT_FAIL, ": Expected 0x0123456789ABCDEF Was 0x0000000000000000"},
    {f_hex64_msg, EXPECT_FAIL, ": Expected 0x0123456789ABCDEF Was 0x0000000000000000. m"},
    {f_string, EXPECT_FAIL, ": Expected 'abc' Was 'abd'"},
    {f_string_msg, EXPECT_FAIL, ": Expected 'abc' Was 'ab'. m"},
    {f_string_null, EXPECT_FAIL, ": Expected NULL Was 'x'"},
    {f_string_esc, EXPECT_FAIL, ": Expected 'a\\n' Was 'b\\x01'"},
    {f_string_len, EXPECT_FAIL, ": Expected 'abcX' Was 'abcY'"},
    {f_string_len_msg, EXPECT_FAIL, ": Expected 'abcX' Was 'abcY'. m"},
    {f_memory, EXPECT_FAIL, ": Memory Mismatch. Byte 2 Expected 0x03 Was 0x04"},
    {f_memory_msg, EXPECT_FAIL, ": Memory Mismatch. Byte 2 Expected 0x03 Was 0x04. m"},
    {f_memory_zero, EXPECT_FAIL, ": You Asked Me To Compare Nothing, Which Was Pointless."},
    {f_memory_exp_null, EXPECT_FAIL, ": Expected pointer to be NULL"},
    {f_memory_act_null, EXPECT_FAIL, ": Actual pointer was NULL"},
    {f_hex8_array, EXPECT_FAIL, ": Element 2 Expected 0x03 Was 0x04"},
    {f_hex8_array_msg, EXPECT_FAIL, ": Element 2 Expected 0x03 Was 0x04. m"},
    {f_uint8_array, EXPECT_FAIL, ": Element 2 Expected 3 Was 4"},
    {f_uint8_array_msg, EXPECT_FAIL, ": Element 2 Expected 3 Was 4. m"},
    {f_uint32_array, EXPECT_FAIL, ": Element 2 Expected 3 Was 4000000000"},
    {f_uint32_array_msg, EXPECT_FAIL, ": Element 2 Expected 3 Was 4000000000. m"},
    {f_uint32_array_zero, EXPECT_FAIL, ": You Asked Me To Compare Nothing, Which Was Pointless."},
    {f_int_array, EXPECT_FAIL, ": Element 1 Expected 0 Was -5"},
    {f_int16_array, EXPECT_FAIL, ": Element 1 Expected 7 Was -7"},
    {f_uint64_array, EXPECT_FAIL, ": Element 1 Expected 1 Was 2"},
    {f_gt, EXPECT_FAIL, ": Expected 3 to be greater than 5"},
    {f_gt_eq, EXPECT_FAIL, ": Expected 5 to be greater than 5"},
    {f_gt_msg, EXPECT_FAIL, ": Expected 3 to be greater than 5. m"},
    {f_gt_int, EXPECT_FAIL, ": Expected -2 to be greater than -1"},
    {f_gt_uint, EXPECT_FAIL, ": Expected 1 to be greater than 4294967295"},
    {f_gt_uint32, EXPECT_FAIL, ": Expected 1 to be greater than 4294967295"},
    {f_gt_uint64, EXPECT_FAIL, ": Expected 1 to be greater than 18446744073709551615"},
    {f_gt_int64, EXPECT_FAIL, ": Expected -1 to be greater than 0"},
    {f_ge, EXPECT_FAIL, ": Expected 4 to be greater than or equal to 5"},
    {f_ge_msg, EXPECT_FAIL, ": Expected 4 to be greater than or equal to 5. m"},
    {f_ge_uint64, EXPECT_FAIL, ": Expected 0 to be greater than or equal to 18446744073709551615"},
    {f_lt, EXPECT_FAIL, ": Expected 5 to be less than 5"},
    {f_lt_msg, EXPECT_FAIL, ": Expected 6 to be less than 5. m"},
    {f_lt_uint32, EXPECT_FAIL, ": Expected 4294967295 to be less than 1"},
    {f_lt_int64, EXPECT_FAIL, ": Expected 0 to be less than -9223372036854775808"},
    {f_le, EXPECT_FAIL, ": Expected 6 to be less than or equal to 5"},
    {f_le_msg, EXPECT_FAIL, ": Expected 6 to be less than or equal to 5. m"},
    {f_le_uint64, EXPECT_FAIL, ": Expected 18446744073709551615 to be less than or equal to 1"},
    {f_le_uint, EXPECT_FAIL, ": Expected 2 to be less than or equal to 1"},
    {f_uint_within, EXPECT_FAIL, ": Values Not Within Delta 2 Expected 10 Was 13"},
    {f_uint_within_msg, EXPECT_FAIL, ": Values Not Within Delta 2 Expected 13 Was 10. m"},
    {f_uint32_within, EXPECT_FAIL, ": Values Not Within Delta 1 Expected 0 Was 4294967295"},
    {f_uint64_within, EXPECT_FAIL, ": Values Not Within Delta 1 Expected 0 Was 18446744073709551615"},
    {f_int_within, EXPECT_FAIL, ": Values Not Within Delta 3 Expected -10 Was -14"},
    {f_int_within_msg, EXPECT_FAIL, ": Values Not Within Delta 3 Expected -10 Was -6. m"},
    {f_int64_within, EXPECT_FAIL,
     ": Values Not Within Delta 1 Expected -9223372036854775808 Was 9223372036854775807"},
    {f_float_within, EXPECT_FAIL, ": Expected 1 Was 1.2"},
    {f_float_within_msg, EXPECT_FAIL, ": Expected 1 Was -1.2. m"},
    {f_float_nan, EXPECT_FAIL, ": Expected 1 Was nan"},
    {f_float_inf, EXPECT_FAIL, ": Expected 1 Was inf"},
    {f_equal_float, EXPECT_FAIL, ": Expected 1.5 Was 1.6"},
    {f_equal_float_msg, EXPECT_FAIL, ": Expected 0.1 Was 0.2. m"},
    {f_equal_float_small, EXPECT_FAIL, ": Expected 1e-20 Was 2e-20"},
    {f_equal_float_big, EXPECT_FAIL, ": Expected 1.234568e+08 Was 1"},
    {f_equal_float_zero, EXPECT_FAIL, ": Expected 0 Was 0.0001"},
    {f_double_within, EXPECT_FAIL, ": Expected 1 Was 1.01"},
    {f_double_within_msg, EXPECT_FAIL, ": Expected 1 Was 1.01. m"},
    {f_equal_double, EXPECT_FAIL, ": Expected 3.25 Was 3.5"},
    {f_bits, EXPECT_FAIL, ": Expected " X32 "1010XXXX Was " X32 "1011XXXX"},
    {f_bits_msg, EXPECT_FAIL, ": Expected " X32 "1010XXXX Was " X32 "1011XXXX. m"},
    {f_bit_high, EXPECT_FAIL, ": Expected " X32 "XXXX1XXX Was " X32 "XXXX0XXX"},
    {f_bit_high_msg, EXPECT_FAIL, ": Expected " X32 "XXXX1XXX Was " X32 "XXXX0XXX. m"},
    {f_bit_low, EXPECT_FAIL, ": Expected " X32 "XXXXXXX0 Was " X32 "XXXXXXX1"},
    {f_bit_low_msg, EXPECT_FAIL, ": Expected 0XXXXXXXXXXXXXXXXXXXXXXXXXXXXXXX Was 1XXXXXXXXXXXXXXXXXXXXXXXXXXXXXXX. m"},
    {f_fail, EXPECT_FAIL, ""},
    {f_fail_msg, EXPECT_FAIL, ": boom"},
    {f_fail_msg_space, EXPECT_FAIL, ": leading space"},
    {i_ignore, EXPECT_IGNORE, ""},
    {i_ignore_msg, EXPECT_IGNORE, ": not yet"},
};

/*-------------------------------------------------------
 * Passing cases: every macro, plain and _MESSAGE, must pass silently
 *-------------------------------------------------------*/
static void all_passing_asserts(void)
{
    const char *msg = "should not be printed";
    TEST_ASSERT(1);
    TEST_ASSERT_MESSAGE(1, msg);
    TEST_ASSERT_TRUE(2 > 1);
    TEST_ASSERT_TRUE_MESSAGE(2 > 1, msg);
    TEST_ASSERT_FALSE(0);
    TEST_ASSERT_FALSE_MESSAGE(0, msg);
    TEST_ASSERT_NULL(null_str);
    TEST_ASSERT_NULL_MESSAGE(null_str, msg);
    TEST_ASSERT_NOT_NULL(&dummy_object);
    TEST_ASSERT_NOT_NULL_MESSAGE(&dummy_object, msg);
    TEST_ASSERT_EQUAL(7, 7);
    TEST_ASSERT_EQUAL_MESSAGE(7, 7, msg);
    TEST_ASSERT_NOT_EQUAL(7, 8);
    TEST_ASSERT_NOT_EQUAL_MESSAGE(7, 8, msg);

    TEST_ASSERT_EQUAL_INT(-7, -7);
    TEST_ASSERT_EQUAL_INT_MESSAGE(-7, -7, msg);
    TEST_ASSERT_EQUAL_INT8(-1, 0xFF); /* truncated to 8 bits like upstream */
    TEST_ASSERT_EQUAL_INT8_MESSAGE(-128, -128, msg);
    TEST_ASSERT_EQUAL_INT16(-300, -300);
    TEST_ASSERT_EQUAL_INT16_MESSAGE(-1, 0xFFFF, msg);
    TEST_ASSERT_EQUAL_INT32(INT32_MIN, INT32_MIN);
    TEST_ASSERT_EQUAL_INT32_MESSAGE(-1, -1, msg);
    TEST_ASSERT_EQUAL_INT64(INT64_MIN, INT64_MIN);
    TEST_ASSERT_EQUAL_INT64_MESSAGE(INT64_MAX, INT64_MAX, msg);
    TEST_ASSERT_EQUAL_UINT(7u, 7u);
    TEST_ASSERT_EQUAL_UINT_MESSAGE(7u, 7u, msg);
    TEST_ASSERT_EQUAL_UINT8(0x1FFu, 0xFFu); /* truncated to 8 bits */
    TEST_ASSERT_EQUAL_UINT8_MESSAGE(1u, 1u, msg);
    TEST_ASSERT_EQUAL_UINT16(0x1FFFFu, 0xFFFFu);
    TEST_ASSERT_EQUAL_UINT16_MESSAGE(1u, 1u, msg);
    TEST_ASSERT_EQUAL_UINT32(0xFFFFFFFFu, 0xFFFFFFFFu);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(1u, 1u, msg);
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, UINT64_MAX);
    TEST_ASSERT_EQUAL_UINT64_MESSAGE(1u, 1u, msg);
    TEST_ASSERT_EQUAL_size_t(sizeof(int), sizeof(int));
    TEST_ASSERT_EQUAL_HEX(0xCAFEu, 0xCAFEu);
    TEST_ASSERT_EQUAL_HEX_MESSAGE(0xCAFEu, 0xCAFEu, msg);
    TEST_ASSERT_EQUAL_HEX8(0x1ABu, 0xABu);
    TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xABu, 0xABu, msg);
    TEST_ASSERT_EQUAL_HEX16(0xBEEFu, 0xBEEFu);
    TEST_ASSERT_EQUAL_HEX16_MESSAGE(0xBEEFu, 0xBEEFu, msg);
    TEST_ASSERT_EQUAL_HEX32(0xDEADBEEFu, 0xDEADBEEFu);
    TEST_ASSERT_EQUAL_HEX32_MESSAGE(0xDEADBEEFu, 0xDEADBEEFu, msg);
    TEST_ASSERT_EQUAL_HEX64(0xFEDCBA9876543210ull, 0xFEDCBA9876543210ull);
    TEST_ASSERT_EQUAL_HEX64_MESSAGE(0xFEDCBA9876543210ull, 0xFEDCBA9876543210ull, msg);
    TEST_ASSERT_EQUAL_PTR(&dummy_object, &dummy_object);
    TEST_ASSERT_EQUAL_PTR_MESSAGE(NULL, null_str, msg);

    TEST_ASSERT_EQUAL_STRING("abc", "abc");
    TEST_ASSERT_EQUAL_STRING_MESSAGE(null_str, null_str, msg);
    TEST_ASSERT_EQUAL_STRING_LEN("abcX", "abcY", 3);
    TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE("ab", "ab", 10, msg);
    TEST_ASSERT_EQUAL_MEMORY(mem_a, mem_c, sizeof mem_a);
    TEST_ASSERT_EQUAL_MEMORY_MESSAGE(mem_a, mem_b, 2, msg);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(mem_a, mem_c, 4);
    TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(mem_a, mem_b, 2, msg);
    TEST_ASSERT_EQUAL_UINT8_ARRAY(mem_a, mem_c, 4);
    TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(mem_a, mem_b, 2, msg);
    TEST_ASSERT_EQUAL_UINT32_ARRAY(u32_a, u32_a, 3);
    TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(u32_a, u32_b, 2, msg);
    TEST_ASSERT_EQUAL_INT_ARRAY(int_a, int_b, 3);
    TEST_ASSERT_EQUAL_INT16_ARRAY(i16_a, i16_b, 1);
    TEST_ASSERT_EQUAL_UINT64_ARRAY(u64_a, u64_b, 1);

    TEST_ASSERT_GREATER_THAN(5, 6);
    TEST_ASSERT_GREATER_THAN_MESSAGE(-5, 0, msg);
    TEST_ASSERT_GREATER_THAN_INT(-2, -1);
    TEST_ASSERT_GREATER_THAN_INT_MESSAGE(-2, -1, msg);
    TEST_ASSERT_GREATER_THAN_UINT(1u, 0xFFFFFFFFu);
    TEST_ASSERT_GREATER_THAN_UINT_MESSAGE(1u, 2u, msg);
    TEST_ASSERT_GREATER_THAN_UINT32(1u, 0xFFFFFFFFu);
    TEST_ASSERT_GREATER_THAN_UINT32_MESSAGE(1u, 2u, msg);
    TEST_ASSERT_GREATER_THAN_UINT64(1u, UINT64_MAX);
    TEST_ASSERT_GREATER_THAN_UINT64_MESSAGE(1u, UINT64_MAX, msg);
    TEST_ASSERT_GREATER_THAN_INT64(INT64_MIN, INT64_MAX);
    TEST_ASSERT_GREATER_THAN_INT64_MESSAGE(-1, 0, msg);
    TEST_ASSERT_GREATER_OR_EQUAL(5, 5);
    TEST_ASSERT_GREATER_OR_EQUAL_MESSAGE(5, 6, msg);
    TEST_ASSERT_GREATER_OR_EQUAL_INT(-1, -1);
    TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(-1, 0, msg);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT(3u, 3u);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT_MESSAGE(3u, 4u, msg);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32(0xFFFFFFFFu, 0xFFFFFFFFu);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT32_MESSAGE(0u, 0u, msg);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64(UINT64_MAX, UINT64_MAX);
    TEST_ASSERT_GREATER_OR_EQUAL_UINT64_MESSAGE(0u, 1u, msg);
    TEST_ASSERT_GREATER_OR_EQUAL_INT64(INT64_MIN, INT64_MIN);
    TEST_ASSERT_GREATER_OR_EQUAL_INT64_MESSAGE(0, 1, msg);
    TEST_ASSERT_LESS_THAN(5, 4);
    TEST_ASSERT_LESS_THAN_MESSAGE(0, -5, msg);
    TEST_ASSERT_LESS_THAN_INT(-1, -2);
    TEST_ASSERT_LESS_THAN_INT_MESSAGE(-1, -2, msg);
    TEST_ASSERT_LESS_THAN_UINT(0xFFFFFFFFu, 1u);
    TEST_ASSERT_LESS_THAN_UINT_MESSAGE(2u, 1u, msg);
    TEST_ASSERT_LESS_THAN_UINT32(0xFFFFFFFFu, 1u);
    TEST_ASSERT_LESS_THAN_UINT32_MESSAGE(2u, 1u, msg);
    TEST_ASSERT_LESS_THAN_UINT64(UINT64_MAX, 1u);
    TEST_ASSERT_LESS_THAN_UINT64_MESSAGE(UINT64_MAX, 0u, msg);
    TEST_ASSERT_LESS_THAN_INT64(INT64_MAX, INT64_MIN);
    TEST_ASSERT_LESS_THAN_INT64_MESSAGE(0, -1, msg);
    TEST_ASSERT_LESS_OR_EQUAL(5, 5);
    TEST_ASSERT_LESS_OR_EQUAL_MESSAGE(5, 4, msg);
    TEST_ASSERT_LESS_OR_EQUAL_INT(-1, -1);
    TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(-1, -2, msg);
    TEST_ASSERT_LESS_OR_EQUAL_UINT(3u, 3u);
    TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(3u, 2u, msg);
    TEST_ASSERT_LESS_OR_EQUAL_UINT32(0xFFFFFFFFu, 0u);
    TEST_ASSERT_LESS_OR_EQUAL_UINT32_MESSAGE(0u, 0u, msg);
    TEST_ASSERT_LESS_OR_EQUAL_UINT64(UINT64_MAX, UINT64_MAX);
    TEST_ASSERT_LESS_OR_EQUAL_UINT64_MESSAGE(1u, 0u, msg);
    TEST_ASSERT_LESS_OR_EQUAL_INT64(INT64_MIN, INT64_MIN);
    TEST_ASSERT_LESS_OR_EQUAL_INT64_MESSAGE(1, 0, msg);

    TEST_ASSERT_UINT_WITHIN(2u, 10u, 12u);
    TEST_ASSERT_UINT_WITHIN_MESSAGE(2u, 12u, 10u, msg);
    TEST_ASSERT_UINT32_WITHIN(1u, 0xFFFFFFFFu, 0xFFFFFFFEu);
    TEST_ASSERT_UINT32_WITHIN_MESSAGE(1u, 0u, 1u, msg);
    TEST_ASSERT_UINT64_WITHIN(2u, UINT64_MAX, UINT64_MAX - 2u);
    TEST_ASSERT_UINT64_WITHIN_MESSAGE(UINT64_MAX, 0u, UINT64_MAX, msg);
    TEST_ASSERT_INT_WITHIN(3, -10, -13);
    TEST_ASSERT_INT_WITHIN_MESSAGE(3, -10, -7, msg);
    TEST_ASSERT_INT64_WITHIN(1, INT64_MIN, INT64_MIN + 1);
    TEST_ASSERT_INT64_WITHIN_MESSAGE(UINT64_MAX, INT64_MIN, INT64_MAX, msg);
    TEST_ASSERT_FLOAT_WITHIN(0.1f, 1.0f, 1.05f);
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE(0.1f, -1.0f, -1.05f, msg);
    TEST_ASSERT_FLOAT_WITHIN(1.0f, f_zero / f_zero, f_zero / f_zero); /* NaN == NaN like upstream */
    TEST_ASSERT_FLOAT_WITHIN(1.0f, 1.0f / f_zero, 1.0f / f_zero);    /* +inf == +inf */
    TEST_ASSERT_EQUAL_FLOAT(0.1f, 0.1f);
    TEST_ASSERT_EQUAL_FLOAT(100000.0f, 100000.5f); /* within relative precision */
    TEST_ASSERT_EQUAL_FLOAT_MESSAGE(-2.5f, -2.5f, msg);
    TEST_ASSERT_DOUBLE_WITHIN(0.001, 1.0, 1.0005);
    TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(0.001, 1.0, 0.9995, msg);
    TEST_ASSERT_EQUAL_DOUBLE(0.1, 0.1);

    TEST_ASSERT_BITS(0xF0u, 0xA5u, 0xAAu);
    TEST_ASSERT_BITS_MESSAGE(0x0Fu, 0x15u, 0x25u, msg);
    TEST_ASSERT_BITS_HIGH(0x81u, 0xFFu);
    TEST_ASSERT_BITS_LOW(0x81u, 0x7Eu);
    TEST_ASSERT_BIT_HIGH(7, 0x80u);
    TEST_ASSERT_BIT_HIGH_MESSAGE(31, 0x80000000u, msg);
    TEST_ASSERT_BIT_HIGH(63, 0x8000000000000000ull);
    TEST_ASSERT_BIT_LOW(7, 0x7Fu);
    TEST_ASSERT_BIT_LOW_MESSAGE(0, 0xFEu, msg);
}

/*-------------------------------------------------------
 * Full-run check (UnityBegin .. UnityEnd), done from main before the real
 * run so that nested RUN_TEST state does not interfere.
 *-------------------------------------------------------*/
static int meta_fail_line;
static int meta_ignore_line;
static int meta_info_line;

static void meta_pass(void)
{
    TEST_ASSERT_EQUAL_INT(1, 1);
}

static void meta_pass_early(void)
{
    TEST_PASS();
    TEST_FAIL_MESSAGE("not reached"); /* TEST_PASS must abort as passed */
}

static void meta_fail(void)
{
    meta_fail_line = __LINE__; TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xAB, 0xAC, "hexmsg");
    g_after = 1;
}

static void meta_ignore(void)
{
    meta_ignore_line = __LINE__; TEST_IGNORE_MESSAGE("later");
}

static void meta_info(void)
{
    meta_info_line = __LINE__; TEST_MESSAGE("hello");
}

static const char *meta_error;
static char meta_expected[1024];
static char meta_captured[1024];

static void meta_record(const char *error)
{
    if (meta_error == NULL && error != NULL) {
        meta_error = error;
        memcpy(meta_expected, exp_buf, sizeof meta_expected - 1u);
        memcpy(meta_captured, spy_buf, sizeof meta_captured - 1u);
    }
}

static void run_meta_checks(void)
{
    int rc;

    /* 1: mixed run -> FAIL summary, return value = failures */
    setup_calls = 0u;
    teardown_calls = 0u;
    g_after = 0;
    spy_start();
    UnityBegin("meta.c");
    UnityDefaultTestRun(meta_pass, "meta_pass", 11);
    UnityDefaultTestRun(meta_fail, "meta_fail", 12);
    UnityDefaultTestRun(meta_ignore, "meta_ignore", 13);
    UnityDefaultTestRun(meta_pass_early, "meta_pass_early", 14);
    UnityDefaultTestRun(meta_info, "meta_info", 15);
    rc = UnityEnd();
    spy_stop();

    eb_reset();
    eb_result_line("meta.c", 11, "meta_pass", "PASS", "\n");
    eb_result_line("meta.c", meta_fail_line, "meta_fail", "FAIL", ": Expected 0xAB Was 0xAC. hexmsg\n");
    eb_result_line("meta.c", meta_ignore_line, "meta_ignore", "IGNORE", ": later\n");
    eb_result_line("meta.c", 14, "meta_pass_early", "PASS", "\n");
    eb_result_line("meta.c", meta_info_line, "meta_info", "INFO", ": hello\n");
    eb_result_line("meta.c", 15, "meta_info", "PASS", "\n");
    eb_str("\n-----------------------\n5 Tests 1 Failures 1 Ignored \nFAIL\n");
    meta_record(strcmp(spy_buf, exp_buf) != 0 ? "mixed run: output differs" : NULL);
    meta_record(rc != 1 ? "mixed run: UnityEnd() did not return 1" : NULL);
    meta_record(g_after ? "mixed run: failing test continued after assert" : NULL);
    meta_record((setup_calls != 5u || teardown_calls != 5u) ? "mixed run: setUp/tearDown not called for every test"
                                                            : NULL);

    /* 2: all passing -> OK summary, return 0 */
    spy_start();
    UnityBegin("ok.c");
    UnityDefaultTestRun(meta_pass, "meta_pass", 3);
    rc = UnityEnd();
    spy_stop();
    eb_reset();
    eb_str("ok.c:3:meta_pass:PASS\n\n-----------------------\n1 Tests 0 Failures 0 Ignored \nOK\n");
    meta_record(strcmp(spy_buf, exp_buf) != 0 ? "passing run: output differs" : NULL);
    meta_record(rc != 0 ? "passing run: UnityEnd() did not return 0" : NULL);
}

/*-------------------------------------------------------
 * The real tests
 *-------------------------------------------------------*/
static void test_full_run_output_and_counters(void)
{
    if (meta_error != NULL) {
        selftest_bad = 1;
        UnityPrint("\n    expected output: ");
        UnityPrint(meta_expected);
        UnityPrint("\n    captured output: ");
        UnityPrint(meta_captured);
        UNITY_OUTPUT_CHAR('\n');
        TEST_FAIL_MESSAGE(meta_error);
    }
}

static void test_passing_asserts_pass_silently(void)
{
    const char *err = run_case(all_passing_asserts, EXPECT_PASS, NULL);
    if (err != NULL) {
        report_mismatch(err);
        TEST_FAIL_MESSAGE(err);
    }
    /* and once more directly, so a wrong pass/fail decision shows up here too */
    all_passing_asserts();
}

static void test_each_failing_assert_fails_with_upstream_text(void)
{
    size_t i;
    for (i = 0u; i < sizeof fail_cases / sizeof fail_cases[0]; i++) {
        const char *err = run_case(fail_cases[i].fn, fail_cases[i].expect, fail_cases[i].tail);
        if (err != NULL) {
            UnityPrint("\n  case #");
            UnityPrintNumberUnsigned((UNITY_UINT)i);
            report_mismatch(err);
            TEST_FAIL_MESSAGE(err);
        }
    }
}

CASE(f_ptr, TEST_ASSERT_EQUAL_PTR((void *)(uintptr_t)0x10u, (void *)(uintptr_t)0xABCu))

static void test_ptr_failure_uses_pointer_width(void)
{
    const char *tail = (sizeof(void *) == 8u) ? ": Expected 0x0000000000000010 Was 0x0000000000000ABC"
                                              : ": Expected 0x00000010 Was 0x00000ABC";
    const char *err = run_case(f_ptr, EXPECT_FAIL, tail);
    if (err != NULL) {
        report_mismatch(err);
        TEST_FAIL_MESSAGE(err);
    }
}

static void test_counters_untouched_by_nested_failures(void)
{
    /* the nested failures above must not have been counted as real ones */
    TEST_ASSERT_EQUAL_UINT32(0u, Unity.TestFailures);
    TEST_ASSERT_EQUAL_UINT32(0u, Unity.TestIgnores);
    TEST_ASSERT_EQUAL_STRING("test_counters_untouched_by_nested_failures", Unity.CurrentTestName);
}

int main(void)
{
    run_meta_checks();

    UNITY_BEGIN();
    RUN_TEST(test_full_run_output_and_counters);
    RUN_TEST(test_passing_asserts_pass_silently);
    RUN_TEST(test_each_failing_assert_fails_with_upstream_text);
    RUN_TEST(test_ptr_failure_uses_pointer_width);
    RUN_TEST(test_counters_untouched_by_nested_failures);
    return (UNITY_END() != 0 || selftest_bad || meta_error != NULL) ? 1 : 0;
}
