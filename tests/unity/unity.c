/*
 * Minimal Unity-compatible unit test harness - implementation.
 * See unity.h and README.md.
 */
#include "unity.h"

#include <string.h>

struct UNITY_STORAGE_T Unity;

/*-------------------------------------------------------
 * Fixed strings (identical to upstream Unity's output)
 *-------------------------------------------------------*/
static const char UnityStrPass[] = "PASS";
static const char UnityStrFail[] = "FAIL";
static const char UnityStrIgnore[] = "IGNORE";
static const char UnityStrInfo[] = "INFO";
static const char UnityStrOk[] = "OK";
static const char UnityStrExpected[] = " Expected ";
static const char UnityStrWas[] = " Was ";
static const char UnityStrGt[] = " to be greater than ";
static const char UnityStrLt[] = " to be less than ";
static const char UnityStrOrEqual[] = "or equal to ";
static const char UnityStrElement[] = " Element ";
static const char UnityStrByte[] = " Byte ";
static const char UnityStrMemory[] = " Memory Mismatch.";
static const char UnityStrDelta[] = " Values Not Within Delta ";
static const char UnityStrPointless[] = " You Asked Me To Compare Nothing, Which Was Pointless.";
static const char UnityStrNullPointerForExpected[] = " Expected pointer to be NULL";
static const char UnityStrNullPointerForActual[] = " Actual pointer was NULL";
static const char UnityStrNull[] = "NULL";
static const char UnityStrSpacer[] = ". ";
static const char UnityStrBreaker[] = "-----------------------";
static const char UnityStrResultsTests[] = " Tests ";
static const char UnityStrResultsFailures[] = " Failures ";
static const char UnityStrResultsIgnored[] = " Ignored ";

#define UNITY_FAIL_AND_BAIL                                                                        \
    do {                                                                                           \
        Unity.CurrentTestFailed = 1u;                                                              \
        UNITY_OUTPUT_FLUSH();                                                                      \
        TEST_ABORT();                                                                              \
    } while (0)

#define UNITY_IGNORE_AND_BAIL                                                                      \
    do {                                                                                           \
        Unity.CurrentTestIgnored = 1u;                                                             \
        UNITY_OUTPUT_FLUSH();                                                                      \
        TEST_ABORT();                                                                              \
    } while (0)

/* Like upstream: once a test has failed or been ignored, any further
 * assertion (e.g. in tearDown) just aborts again. */
#define RETURN_IF_FAIL_OR_IGNORE                                                                   \
    do {                                                                                           \
        if ((Unity.CurrentTestFailed != 0u) || (Unity.CurrentTestIgnored != 0u)) {                 \
            TEST_ABORT();                                                                          \
        }                                                                                          \
    } while (0)

/*-------------------------------------------------------
 * Character output
 *-------------------------------------------------------*/
static UnityOutputHookFn UnityOutputHook = NULL;

UnityOutputHookFn UnitySetOutputHook(UnityOutputHookFn hook)
{
    UnityOutputHookFn previous = UnityOutputHook;
    UnityOutputHook = hook;
    return previous;
}

void UnityOutputCharDefault(int c)
{
    if (UnityOutputHook != NULL) {
        UnityOutputHook(c);
    } else {
        (void)putchar(c);
    }
}

/*-------------------------------------------------------
 * Printing
 *-------------------------------------------------------*/
static void UnityPrintChar(const char c)
{
    if ((c >= 32) && (c <= 126)) {
        UNITY_OUTPUT_CHAR(c);
    } else if (c == '\r') {
        UNITY_OUTPUT_CHAR('\\');
        UNITY_OUTPUT_CHAR('r');
    } else if (c == '\n') {
        UNITY_OUTPUT_CHAR('\\');
        UNITY_OUTPUT_CHAR('n');
    } else {
        UNITY_OUTPUT_CHAR('\\');
        UNITY_OUTPUT_CHAR('x');
        UnityPrintNumberHex((UNITY_UINT)(unsigned char)c, 2);
    }
}

void UnityPrint(const char *string)
{
    const char *p = string;
    if (p == NULL) {
        return;
    }
    while (*p != '\0') {
        UnityPrintChar(*p);
        p++;
    }
}

void UnityPrintLen(const char *string, const UNITY_UINT32 length)
{
    UNITY_UINT32 i;
    if (string == NULL) {
        return;
    }
    for (i = 0u; (i < length) && (string[i] != '\0'); i++) {
        UnityPrintChar(string[i]);
    }
}

void UnityPrintNumberUnsigned(const UNITY_UINT number)
{
    char buf[24];
    int n = 0;
    UNITY_UINT v = number;
    do {
        buf[n++] = (char)('0' + (int)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n > 0) {
        UNITY_OUTPUT_CHAR(buf[--n]);
    }
}

void UnityPrintNumber(const UNITY_INT number)
{
    UNITY_UINT magnitude = (UNITY_UINT)number;
    if (number < 0) {
        UNITY_OUTPUT_CHAR('-');
        magnitude = (UNITY_UINT)0u - magnitude;
    }
    UnityPrintNumberUnsigned(magnitude);
}

void UnityPrintNumberHex(const UNITY_UINT number, const char nibbles_to_print)
{
    int nibbles = (int)nibbles_to_print;
    if (nibbles > 16) {
        nibbles = 16;
    }
    while (nibbles > 0) {
        int nibble;
        nibbles--;
        nibble = (int)((number >> (4 * nibbles)) & 0x0Fu);
        UNITY_OUTPUT_CHAR((char)((nibble <= 9) ? ('0' + nibble) : ('A' - 10 + nibble)));
    }
}

static int UnityStyleSize(const UNITY_DISPLAY_STYLE_T style)
{
    return (int)style & 0x0F;
}

void UnityPrintNumberByStyle(const UNITY_INT number, const UNITY_DISPLAY_STYLE_T style)
{
    if (((int)style & UNITY_DISPLAY_RANGE_INT) != 0) {
        UnityPrintNumber(number);
    } else if (((int)style & UNITY_DISPLAY_RANGE_UINT) != 0) {
        UnityPrintNumberUnsigned((UNITY_UINT)number);
    } else {
        UNITY_OUTPUT_CHAR('0');
        UNITY_OUTPUT_CHAR('x');
        UnityPrintNumberHex((UNITY_UINT)number, (char)(UnityStyleSize(style) * 2));
    }
}

void UnityPrintMask(const UNITY_UINT mask, const UNITY_UINT number)
{
    /* 32 bit positions like upstream (UNITY_INT_WIDTH), 64 if the mask needs it */
    int width = ((mask >> 32) != 0u) ? 64 : 32;
    while (width > 0) {
        UNITY_UINT bit;
        width--;
        bit = (UNITY_UINT)1u << width;
        if ((mask & bit) != 0u) {
            UNITY_OUTPUT_CHAR(((number & bit) != 0u) ? '1' : '0');
        } else {
            UNITY_OUTPUT_CHAR('X');
        }
    }
}

static int UnityIsNan(const UNITY_DOUBLE x)
{
    return x != x;
}

static int UnityIsInf(const UNITY_DOUBLE x)
{
    return (x == x) && ((x - x) != (x - x));
}

/* Prints like upstream UnityPrintFloat: sig_digits significant digits,
 * trailing zeros removed, exponent form outside a sensible range. */
static void UnityPrintFloatDigits(const UNITY_DOUBLE input, const int sig_digits)
{
    UNITY_DOUBLE number = input;
    UNITY_INT32 min_scaled = 1;
    UNITY_INT32 max_scaled;
    int i;

    for (i = 1; i < sig_digits; i++) {
        min_scaled *= 10;
    }
    max_scaled = min_scaled * 10;

    if (number < 0.0) {
        UNITY_OUTPUT_CHAR('-');
        number = -number;
    }

    if (number == 0.0) {
        UnityPrint("0");
    } else if (UnityIsNan(number)) {
        UnityPrint("nan");
    } else if (UnityIsInf(number)) {
        UnityPrint("inf");
    } else {
        UNITY_INT32 n_int = 0;
        UNITY_INT32 n;
        int exponent = 0;
        int decimals;
        int digits;
        char buf[16];

        if (number < 1.0) {
            UNITY_DOUBLE factor = 1.0;
            while (number < (UNITY_DOUBLE)max_scaled / 1e10) {
                number *= 1e10;
                exponent -= 10;
            }
            while (number * factor < (UNITY_DOUBLE)min_scaled) {
                factor *= 10.0;
                exponent--;
            }
            number *= factor;
        } else if (number > (UNITY_DOUBLE)max_scaled) {
            UNITY_DOUBLE divisor = 1.0;
            while (number > (UNITY_DOUBLE)min_scaled * 1e10) {
                number /= 1e10;
                exponent += 10;
            }
            while (number / divisor > (UNITY_DOUBLE)max_scaled) {
                divisor *= 10.0;
                exponent++;
            }
            number /= divisor;
        } else {
            /* split off the integer part first to keep precision */
            UNITY_DOUBLE factor = 1.0;
            n_int = (UNITY_INT32)number;
            number -= (UNITY_DOUBLE)n_int;
            while (n_int < min_scaled) {
                n_int *= 10;
                factor *= 10.0;
                exponent--;
            }
            number *= factor;
        }

        /* round to nearest, ties to even */
        n = ((UNITY_INT32)(number + number) + 1) / 2;
        if (((n & 1) != 0) && (((UNITY_DOUBLE)n - number) == 0.5)) {
            n--;
        }
        n += n_int;

        if (n >= max_scaled) {
            n = min_scaled;
            exponent++;
        }

        /* place the decimal point */
        decimals = ((exponent <= 0) && (exponent >= -(sig_digits + 3))) ? -exponent : (sig_digits - 1);
        exponent += decimals;

        while ((decimals > 0) && ((n % 10) == 0)) {
            n /= 10;
            decimals--;
        }

        digits = 0;
        while ((n != 0) || (digits <= decimals)) {
            buf[digits++] = (char)('0' + (n % 10));
            n /= 10;
        }
        while (digits > 0) {
            if (digits == decimals) {
                UNITY_OUTPUT_CHAR('.');
            }
            UNITY_OUTPUT_CHAR(buf[--digits]);
        }

        if (exponent != 0) {
            UNITY_OUTPUT_CHAR('e');
            if (exponent < 0) {
                UNITY_OUTPUT_CHAR('-');
                exponent = -exponent;
            } else {
                UNITY_OUTPUT_CHAR('+');
            }
            digits = 0;
            while ((exponent != 0) || (digits < 2)) {
                buf[digits++] = (char)('0' + (exponent % 10));
                exponent /= 10;
            }
            while (digits > 0) {
                UNITY_OUTPUT_CHAR(buf[--digits]);
            }
        }
    }
}

void UnityPrintFloat(const UNITY_DOUBLE number)
{
    UnityPrintFloatDigits(number, 7);
}

/*-------------------------------------------------------
 * Result line helpers
 *-------------------------------------------------------*/
static void UnityTestResultsBegin(const char *file, const UNITY_LINE_TYPE line)
{
    UnityPrint(file);
    UNITY_OUTPUT_CHAR(':');
    UnityPrintNumber((UNITY_INT)line);
    UNITY_OUTPUT_CHAR(':');
    UnityPrint(Unity.CurrentTestName);
    UNITY_OUTPUT_CHAR(':');
}

static void UnityTestResultsFailBegin(const UNITY_LINE_TYPE line)
{
    UnityTestResultsBegin(Unity.TestFile, line);
    UnityPrint(UnityStrFail);
    UNITY_OUTPUT_CHAR(':');
}

static void UnityAddMsgIfSpecified(const char *msg)
{
    if (msg != NULL) {
        UnityPrint(UnityStrSpacer);
        UnityPrint(msg);
    }
}

static void UnityPrintPointlessAndBail(const char *msg, const UNITY_LINE_TYPE line)
{
    UnityTestResultsFailBegin(line);
    UnityPrint(UnityStrPointless);
    UnityAddMsgIfSpecified(msg);
    UNITY_FAIL_AND_BAIL;
}

static int UnityIsOneArrayNull(UNITY_INTERNAL_PTR expected, UNITY_INTERNAL_PTR actual,
                               const UNITY_LINE_TYPE line, const char *msg)
{
    if (expected == actual) {
        return 0;
    }
    if (expected == NULL) {
        UnityTestResultsFailBegin(line);
        UnityPrint(UnityStrNullPointerForExpected);
        UnityAddMsgIfSpecified(msg);
        return 1;
    }
    if (actual == NULL) {
        UnityTestResultsFailBegin(line);
        UnityPrint(UnityStrNullPointerForActual);
        UnityAddMsgIfSpecified(msg);
        return 1;
    }
    return 0;
}

/*-------------------------------------------------------
 * Control
 *-------------------------------------------------------*/
void UnityFail(const char *message, const UNITY_LINE_TYPE line)
{
    RETURN_IF_FAIL_OR_IGNORE;
    UnityTestResultsBegin(Unity.TestFile, line);
    UnityPrint(UnityStrFail);
    if (message != NULL) {
        UNITY_OUTPUT_CHAR(':');
        if (message[0] != ' ') {
            UNITY_OUTPUT_CHAR(' ');
        }
        UnityPrint(message);
    }
    UNITY_FAIL_AND_BAIL;
}

void UnityIgnore(const char *message, const UNITY_LINE_TYPE line)
{
    RETURN_IF_FAIL_OR_IGNORE;
    UnityTestResultsBegin(Unity.TestFile, line);
    UnityPrint(UnityStrIgnore);
    if (message != NULL) {
        UNITY_OUTPUT_CHAR(':');
        UNITY_OUTPUT_CHAR(' ');
        UnityPrint(message);
    }
    UNITY_IGNORE_AND_BAIL;
}

void UnityMessage(const char *message, const UNITY_LINE_TYPE line)
{
    UnityTestResultsBegin(Unity.TestFile, line);
    UnityPrint(UnityStrInfo);
    if (message != NULL) {
        UNITY_OUTPUT_CHAR(':');
        UNITY_OUTPUT_CHAR(' ');
        UnityPrint(message);
    }
    UNITY_PRINT_EOL();
}

/*-------------------------------------------------------
 * Assertions
 *-------------------------------------------------------*/
void UnityAssertEqualNumber(const UNITY_INT expected, const UNITY_INT actual, const char *msg,
                            const UNITY_LINE_TYPE lineNumber, const UNITY_DISPLAY_STYLE_T style)
{
    RETURN_IF_FAIL_OR_IGNORE;
    if (expected != actual) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrExpected);
        UnityPrintNumberByStyle(expected, style);
        UnityPrint(UnityStrWas);
        UnityPrintNumberByStyle(actual, style);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

void UnityAssertGreaterOrLessOrEqualNumber(const UNITY_INT threshold, const UNITY_INT actual,
                                           const UNITY_COMPARISON_T compare, const char *msg,
                                           const UNITY_LINE_TYPE lineNumber,
                                           const UNITY_DISPLAY_STYLE_T style)
{
    int failed = 0;
    const int cmp = (int)compare;
    RETURN_IF_FAIL_OR_IGNORE;

    if (threshold == actual) {
        failed = ((cmp & UNITY_EQUAL_TO) == 0);
    } else if (((int)style & UNITY_DISPLAY_RANGE_INT) != 0) {
        if ((actual > threshold) && ((cmp & UNITY_SMALLER_THAN) != 0)) {
            failed = 1;
        }
        if ((actual < threshold) && ((cmp & UNITY_GREATER_THAN) != 0)) {
            failed = 1;
        }
    } else {
        if (((UNITY_UINT)actual > (UNITY_UINT)threshold) && ((cmp & UNITY_SMALLER_THAN) != 0)) {
            failed = 1;
        }
        if (((UNITY_UINT)actual < (UNITY_UINT)threshold) && ((cmp & UNITY_GREATER_THAN) != 0)) {
            failed = 1;
        }
    }

    if (failed) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrExpected);
        UnityPrintNumberByStyle(actual, style);
        if ((cmp & UNITY_GREATER_THAN) != 0) {
            UnityPrint(UnityStrGt);
        }
        if ((cmp & UNITY_SMALLER_THAN) != 0) {
            UnityPrint(UnityStrLt);
        }
        if ((cmp & UNITY_EQUAL_TO) != 0) {
            UnityPrint(UnityStrOrEqual);
        }
        UnityPrintNumberByStyle(threshold, style);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

void UnityAssertNumbersWithin(const UNITY_UINT delta, const UNITY_INT expected, const UNITY_INT actual,
                              const char *msg, const UNITY_LINE_TYPE lineNumber,
                              const UNITY_DISPLAY_STYLE_T style)
{
    UNITY_UINT diff;
    int larger;
    RETURN_IF_FAIL_OR_IGNORE;

    if (((int)style & UNITY_DISPLAY_RANGE_INT) != 0) {
        larger = (actual > expected);
    } else {
        larger = ((UNITY_UINT)actual > (UNITY_UINT)expected);
    }
    if (larger) {
        diff = (UNITY_UINT)actual - (UNITY_UINT)expected;
    } else {
        diff = (UNITY_UINT)expected - (UNITY_UINT)actual;
    }

    if (diff > delta) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrDelta);
        UnityPrintNumberByStyle((UNITY_INT)delta, style);
        UnityPrint(UnityStrExpected);
        UnityPrintNumberByStyle(expected, style);
        UnityPrint(UnityStrWas);
        UnityPrintNumberByStyle(actual, style);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

void UnityAssertBits(const UNITY_INT mask, const UNITY_INT expected, const UNITY_INT actual,
                     const char *msg, const UNITY_LINE_TYPE lineNumber)
{
    RETURN_IF_FAIL_OR_IGNORE;
    if ((mask & expected) != (mask & actual)) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrExpected);
        UnityPrintMask((UNITY_UINT)mask, (UNITY_UINT)expected);
        UnityPrint(UnityStrWas);
        UnityPrintMask((UNITY_UINT)mask, (UNITY_UINT)actual);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

static void UnityPrintQuotedOrNull(const char *s, const UNITY_UINT32 length, const int use_length)
{
    if (s != NULL) {
        UNITY_OUTPUT_CHAR('\'');
        if (use_length) {
            UnityPrintLen(s, length);
        } else {
            UnityPrint(s);
        }
        UNITY_OUTPUT_CHAR('\'');
    } else {
        UnityPrint(UnityStrNull);
    }
}

static void UnityStringFailure(const char *expected, const char *actual, const UNITY_UINT32 length,
                               const int use_length, const char *msg, const UNITY_LINE_TYPE lineNumber)
{
    UnityTestResultsFailBegin(lineNumber);
    UnityPrint(UnityStrExpected);
    UnityPrintQuotedOrNull(expected, length, use_length);
    UnityPrint(UnityStrWas);
    UnityPrintQuotedOrNull(actual, length, use_length);
    UnityAddMsgIfSpecified(msg);
    UNITY_FAIL_AND_BAIL;
}

void UnityAssertEqualString(const char *expected, const char *actual, const char *msg,
                            const UNITY_LINE_TYPE lineNumber)
{
    int failed = 0;
    RETURN_IF_FAIL_OR_IGNORE;
    if ((expected != NULL) && (actual != NULL)) {
        failed = (strcmp(expected, actual) != 0);
    } else {
        failed = (expected != actual); /* both NULL passes */
    }
    if (failed) {
        UnityStringFailure(expected, actual, 0u, 0, msg, lineNumber);
    }
}

void UnityAssertEqualStringLen(const char *expected, const char *actual, const UNITY_UINT32 length,
                               const char *msg, const UNITY_LINE_TYPE lineNumber)
{
    int failed = 0;
    RETURN_IF_FAIL_OR_IGNORE;
    if ((expected != NULL) && (actual != NULL)) {
        UNITY_UINT32 i;
        for (i = 0u; (i < length) && ((expected[i] != '\0') || (actual[i] != '\0')); i++) {
            if (expected[i] != actual[i]) {
                failed = 1;
                break;
            }
        }
    } else {
        failed = (expected != actual);
    }
    if (failed) {
        UnityStringFailure(expected, actual, length, 1, msg, lineNumber);
    }
}

void UnityAssertEqualMemory(UNITY_INTERNAL_PTR expected, UNITY_INTERNAL_PTR actual,
                            const UNITY_UINT32 length, const UNITY_UINT32 num_elements,
                            const char *msg, const UNITY_LINE_TYPE lineNumber,
                            const UNITY_FLAGS_T flags)
{
    const unsigned char *ptr_exp = (const unsigned char *)expected;
    const unsigned char *ptr_act = (const unsigned char *)actual;
    UNITY_UINT32 element;

    RETURN_IF_FAIL_OR_IGNORE;
    if ((num_elements == 0u) || (length == 0u)) {
        UnityPrintPointlessAndBail(msg, lineNumber);
    }
    if (expected == actual) {
        return;
    }
    if (UnityIsOneArrayNull(expected, actual, lineNumber, msg)) {
        UNITY_FAIL_AND_BAIL;
    }

    for (element = 0u; element < num_elements; element++) {
        UNITY_UINT32 byte;
        for (byte = 0u; byte < length; byte++) {
            if (ptr_exp[byte] != ptr_act[byte]) {
                UnityTestResultsFailBegin(lineNumber);
                UnityPrint(UnityStrMemory);
                if (num_elements > 1u) {
                    UnityPrint(UnityStrElement);
                    UnityPrintNumberUnsigned(element);
                }
                UnityPrint(UnityStrByte);
                UnityPrintNumberUnsigned(byte);
                UnityPrint(UnityStrExpected);
                UnityPrintNumberByStyle((UNITY_INT)ptr_exp[byte], UNITY_DISPLAY_STYLE_HEX8);
                UnityPrint(UnityStrWas);
                UnityPrintNumberByStyle((UNITY_INT)ptr_act[byte], UNITY_DISPLAY_STYLE_HEX8);
                UnityAddMsgIfSpecified(msg);
                UNITY_FAIL_AND_BAIL;
            }
        }
        if (flags == UNITY_ARRAY_TO_ARRAY) {
            ptr_exp += length;
        }
        ptr_act += length;
    }
}

static UNITY_INT UnityReadElement(const unsigned char *p, const UNITY_DISPLAY_STYLE_T style)
{
    const int is_signed = (((int)style & UNITY_DISPLAY_RANGE_INT) != 0);
    switch (UnityStyleSize(style)) {
    case 1:
        if (is_signed) {
            UNITY_INT8 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        } else {
            UNITY_UINT8 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        }
    case 2:
        if (is_signed) {
            UNITY_INT16 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        } else {
            UNITY_UINT16 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        }
    case 4:
        if (is_signed) {
            UNITY_INT32 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        } else {
            UNITY_UINT32 v;
            memcpy(&v, p, sizeof v);
            return (UNITY_INT)v;
        }
    default: {
        UNITY_INT64 v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    }
}

void UnityAssertEqualIntArray(UNITY_INTERNAL_PTR expected, UNITY_INTERNAL_PTR actual,
                              const UNITY_UINT32 num_elements, const char *msg,
                              const UNITY_LINE_TYPE lineNumber, const UNITY_DISPLAY_STYLE_T style,
                              const UNITY_FLAGS_T flags)
{
    const unsigned char *ptr_exp = (const unsigned char *)expected;
    const unsigned char *ptr_act = (const unsigned char *)actual;
    const size_t size = (size_t)UnityStyleSize(style);
    UNITY_UINT32 element;

    RETURN_IF_FAIL_OR_IGNORE;
    if (num_elements == 0u) {
        UnityPrintPointlessAndBail(msg, lineNumber);
    }
    if (expected == actual) {
        return;
    }
    if (UnityIsOneArrayNull(expected, actual, lineNumber, msg)) {
        UNITY_FAIL_AND_BAIL;
    }

    for (element = 0u; element < num_elements; element++) {
        const UNITY_INT expect_val = UnityReadElement(ptr_exp, style);
        const UNITY_INT actual_val = UnityReadElement(ptr_act, style);
        if (expect_val != actual_val) {
            UnityTestResultsFailBegin(lineNumber);
            UnityPrint(UnityStrElement);
            UnityPrintNumberUnsigned(element);
            UnityPrint(UnityStrExpected);
            UnityPrintNumberByStyle(expect_val, style);
            UnityPrint(UnityStrWas);
            UnityPrintNumberByStyle(actual_val, style);
            UnityAddMsgIfSpecified(msg);
            UNITY_FAIL_AND_BAIL;
        }
        if (flags == UNITY_ARRAY_TO_ARRAY) {
            ptr_exp += size;
        }
        ptr_act += size;
    }
}

static int UnityDoublesWithin(UNITY_DOUBLE delta, const UNITY_DOUBLE expected, const UNITY_DOUBLE actual)
{
    UNITY_DOUBLE diff;
    if (UnityIsInf(expected) && UnityIsInf(actual) && ((expected < 0.0) == (actual < 0.0))) {
        return 1;
    }
    if (UnityIsNan(expected) && UnityIsNan(actual)) {
        return 1;
    }
    diff = actual - expected;
    if (diff < 0.0) {
        diff = -diff;
    }
    if (delta < 0.0) {
        delta = -delta;
    }
    return !(UnityIsNan(diff) || UnityIsInf(diff) || (diff > delta));
}

static int UnityFloatsWithin(UNITY_FLOAT delta, const UNITY_FLOAT expected, const UNITY_FLOAT actual)
{
    UNITY_FLOAT diff;
    if (UnityIsInf(expected) && UnityIsInf(actual) && ((expected < 0.0f) == (actual < 0.0f))) {
        return 1;
    }
    if (UnityIsNan(expected) && UnityIsNan(actual)) {
        return 1;
    }
    diff = actual - expected;
    if (diff < 0.0f) {
        diff = -diff;
    }
    if (delta < 0.0f) {
        delta = -delta;
    }
    return !(UnityIsNan(diff) || UnityIsInf(diff) || (diff > delta));
}

void UnityAssertFloatsWithin(const UNITY_FLOAT delta, const UNITY_FLOAT expected,
                             const UNITY_FLOAT actual, const char *msg,
                             const UNITY_LINE_TYPE lineNumber)
{
    RETURN_IF_FAIL_OR_IGNORE;
    if (!UnityFloatsWithin(delta, expected, actual)) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrExpected);
        UnityPrintFloatDigits((UNITY_DOUBLE)expected, 7);
        UnityPrint(UnityStrWas);
        UnityPrintFloatDigits((UNITY_DOUBLE)actual, 7);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

void UnityAssertDoublesWithin(const UNITY_DOUBLE delta, const UNITY_DOUBLE expected,
                              const UNITY_DOUBLE actual, const char *msg,
                              const UNITY_LINE_TYPE lineNumber)
{
    RETURN_IF_FAIL_OR_IGNORE;
    if (!UnityDoublesWithin(delta, expected, actual)) {
        UnityTestResultsFailBegin(lineNumber);
        UnityPrint(UnityStrExpected);
        UnityPrintFloatDigits(expected, 9);
        UnityPrint(UnityStrWas);
        UnityPrintFloatDigits(actual, 9);
        UnityAddMsgIfSpecified(msg);
        UNITY_FAIL_AND_BAIL;
    }
}

/*-------------------------------------------------------
 * Test running
 *-------------------------------------------------------*/
void UnityBegin(const char *filename)
{
    Unity.TestFile = filename;
    Unity.CurrentTestName = NULL;
    Unity.CurrentTestLineNumber = 0u;
    Unity.NumberOfTests = 0u;
    Unity.TestFailures = 0u;
    Unity.TestIgnores = 0u;
    Unity.CurrentTestFailed = 0u;
    Unity.CurrentTestIgnored = 0u;
    UNITY_OUTPUT_START();
}

void UnityConcludeTest(void)
{
    if (Unity.CurrentTestIgnored != 0u) {
        Unity.TestIgnores++;
    } else if (Unity.CurrentTestFailed == 0u) {
        UnityTestResultsBegin(Unity.TestFile, Unity.CurrentTestLineNumber);
        UnityPrint(UnityStrPass);
    } else {
        Unity.TestFailures++;
    }
    Unity.CurrentTestFailed = 0u;
    Unity.CurrentTestIgnored = 0u;
    UNITY_PRINT_EOL();
    UNITY_OUTPUT_FLUSH();
}

void UnityDefaultTestRun(UnityTestFunction Func, const char *FuncName, const int FuncLineNum)
{
    Unity.CurrentTestName = FuncName;
    Unity.CurrentTestLineNumber = (UNITY_LINE_TYPE)FuncLineNum;
    Unity.NumberOfTests++;
    if (TEST_PROTECT()) {
        setUp();
        Func();
    }
    if (TEST_PROTECT()) {
        tearDown();
    }
    UnityConcludeTest();
}

int UnityEnd(void)
{
    UNITY_PRINT_EOL();
    UnityPrint(UnityStrBreaker);
    UNITY_PRINT_EOL();
    UnityPrintNumberUnsigned((UNITY_UINT)Unity.NumberOfTests);
    UnityPrint(UnityStrResultsTests);
    UnityPrintNumberUnsigned((UNITY_UINT)Unity.TestFailures);
    UnityPrint(UnityStrResultsFailures);
    UnityPrintNumberUnsigned((UNITY_UINT)Unity.TestIgnores);
    UnityPrint(UnityStrResultsIgnored);
    UNITY_PRINT_EOL();
    if (Unity.TestFailures == 0u) {
        UnityPrint(UnityStrOk);
    } else {
        UnityPrint(UnityStrFail);
    }
    UNITY_PRINT_EOL();
    UNITY_OUTPUT_FLUSH();
    UNITY_OUTPUT_COMPLETE();
    return (int)Unity.TestFailures;
}
