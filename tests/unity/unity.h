/*
 * Minimal Unity-compatible unit test harness.
 *
 * Source-compatible subset of the public API of ThrowTheSwitch's Unity
 * test framework (https://github.com/ThrowTheSwitch/Unity).  Test files
 * written for upstream Unity compile unchanged against this header, and the
 * output follows upstream's format so Unity output parsers keep working.
 *
 * Strict C99; depends only on <stdio.h>, <string.h>, <setjmp.h>,
 * <stdint.h> and <stddef.h>.  See README.md for the differences to upstream.
 */
#ifndef UNITY_H
#define UNITY_H

#ifdef UNITY_INCLUDE_CONFIG_H
#include "unity_config.h"
#endif

#include <setjmp.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Lets code detect that this harness (and not upstream Unity) is in use. */
#define UNITY_HARNESS_MINI 1

/*-------------------------------------------------------
 * Types
 *-------------------------------------------------------*/
typedef uint8_t  UNITY_UINT8;
typedef uint16_t UNITY_UINT16;
typedef uint32_t UNITY_UINT32;
typedef uint64_t UNITY_UINT64;
typedef int8_t   UNITY_INT8;
typedef int16_t  UNITY_INT16;
typedef int32_t  UNITY_INT32;
typedef int64_t  UNITY_INT64;

/* 64-bit support is always built in (also on 32-bit targets). */
typedef UNITY_UINT64 UNITY_UINT;
typedef UNITY_INT64  UNITY_INT;
#ifndef UNITY_SUPPORT_64
#define UNITY_SUPPORT_64
#endif

typedef float  UNITY_FLOAT;
typedef double UNITY_DOUBLE;

#ifndef UNITY_LINE_TYPE
#define UNITY_LINE_TYPE UNITY_UINT32
#endif
#ifndef UNITY_COUNTER_TYPE
#define UNITY_COUNTER_TYPE UNITY_UINT32
#endif

#define UNITY_INTERNAL_PTR const void *

#ifndef UNITY_FLOAT_PRECISION
#define UNITY_FLOAT_PRECISION (0.00001f)
#endif
#ifndef UNITY_DOUBLE_PRECISION
#define UNITY_DOUBLE_PRECISION (1e-12)
#endif

/* Display styles: low nibble = size in bytes, high bits = number range. */
#define UNITY_DISPLAY_RANGE_INT  (0x10)
#define UNITY_DISPLAY_RANGE_UINT (0x20)
#define UNITY_DISPLAY_RANGE_HEX  (0x40)

typedef enum {
    UNITY_DISPLAY_STYLE_INT = (int)sizeof(int) + UNITY_DISPLAY_RANGE_INT,
    UNITY_DISPLAY_STYLE_INT8 = 1 + UNITY_DISPLAY_RANGE_INT,
    UNITY_DISPLAY_STYLE_INT16 = 2 + UNITY_DISPLAY_RANGE_INT,
    UNITY_DISPLAY_STYLE_INT32 = 4 + UNITY_DISPLAY_RANGE_INT,
    UNITY_DISPLAY_STYLE_INT64 = 8 + UNITY_DISPLAY_RANGE_INT,

    UNITY_DISPLAY_STYLE_UINT = (int)sizeof(unsigned int) + UNITY_DISPLAY_RANGE_UINT,
    UNITY_DISPLAY_STYLE_UINT8 = 1 + UNITY_DISPLAY_RANGE_UINT,
    UNITY_DISPLAY_STYLE_UINT16 = 2 + UNITY_DISPLAY_RANGE_UINT,
    UNITY_DISPLAY_STYLE_UINT32 = 4 + UNITY_DISPLAY_RANGE_UINT,
    UNITY_DISPLAY_STYLE_UINT64 = 8 + UNITY_DISPLAY_RANGE_UINT,
    UNITY_DISPLAY_STYLE_SIZE_T = (int)sizeof(size_t) + UNITY_DISPLAY_RANGE_UINT,

    UNITY_DISPLAY_STYLE_HEX8 = 1 + UNITY_DISPLAY_RANGE_HEX,
    UNITY_DISPLAY_STYLE_HEX16 = 2 + UNITY_DISPLAY_RANGE_HEX,
    UNITY_DISPLAY_STYLE_HEX32 = 4 + UNITY_DISPLAY_RANGE_HEX,
    UNITY_DISPLAY_STYLE_HEX64 = 8 + UNITY_DISPLAY_RANGE_HEX,
    UNITY_DISPLAY_STYLE_POINTER = (int)sizeof(void *) + UNITY_DISPLAY_RANGE_HEX,

    UNITY_DISPLAY_STYLE_UNKNOWN
} UNITY_DISPLAY_STYLE_T;

typedef enum {
    UNITY_EQUAL_TO = 0x1,
    UNITY_GREATER_THAN = 0x2,
    UNITY_GREATER_OR_EQUAL = 0x2 + UNITY_EQUAL_TO,
    UNITY_SMALLER_THAN = 0x4,
    UNITY_SMALLER_OR_EQUAL = 0x4 + UNITY_EQUAL_TO
} UNITY_COMPARISON_T;

typedef enum {
    UNITY_ARRAY_TO_VAL = 0,
    UNITY_ARRAY_TO_ARRAY
} UNITY_FLAGS_T;

/*-------------------------------------------------------
 * Global state
 *-------------------------------------------------------*/
struct UNITY_STORAGE_T {
    const char *TestFile;
    const char *CurrentTestName;
    UNITY_LINE_TYPE CurrentTestLineNumber;
    UNITY_COUNTER_TYPE NumberOfTests;
    UNITY_COUNTER_TYPE TestFailures;
    UNITY_COUNTER_TYPE TestIgnores;
    UNITY_COUNTER_TYPE CurrentTestFailed;
    UNITY_COUNTER_TYPE CurrentTestIgnored;
    jmp_buf AbortFrame;
};

extern struct UNITY_STORAGE_T Unity;

/*-------------------------------------------------------
 * Output hooks (same names and defaults as upstream, except that
 * UNITY_OUTPUT_FLUSH defaults to fflush(stdout)).
 *-------------------------------------------------------*/

/* Harness extension (not in upstream): runtime redirection of the default
 * UNITY_OUTPUT_CHAR.  NULL restores putchar().  Returns the previous hook.
 * Has no effect when UNITY_OUTPUT_CHAR is defined by the user. */
typedef void (*UnityOutputHookFn)(int c);
UnityOutputHookFn UnitySetOutputHook(UnityOutputHookFn hook);
void UnityOutputCharDefault(int c);

#ifdef UNITY_OUTPUT_CHAR_HEADER_DECLARATION
extern void UNITY_OUTPUT_CHAR_HEADER_DECLARATION;
#endif
#ifdef UNITY_OUTPUT_FLUSH_HEADER_DECLARATION
extern void UNITY_OUTPUT_FLUSH_HEADER_DECLARATION;
#endif

#ifndef UNITY_OUTPUT_CHAR
#define UNITY_OUTPUT_CHAR(a) UnityOutputCharDefault(a)
#endif
#ifndef UNITY_OUTPUT_FLUSH
#define UNITY_OUTPUT_FLUSH() (void)fflush(stdout)
#endif
#ifndef UNITY_OUTPUT_START
#define UNITY_OUTPUT_START()
#endif
#ifndef UNITY_OUTPUT_COMPLETE
#define UNITY_OUTPUT_COMPLETE()
#endif
#ifndef UNITY_PRINT_EOL
#define UNITY_PRINT_EOL() UNITY_OUTPUT_CHAR('\n')
#endif

/*-------------------------------------------------------
 * Test running
 *-------------------------------------------------------*/
typedef void (*UnityTestFunction)(void);

/* Must be defined by every test file (as in upstream). */
void setUp(void);
void tearDown(void);

void UnityBegin(const char *filename);
int UnityEnd(void);
void UnityDefaultTestRun(UnityTestFunction Func, const char *FuncName, const int FuncLineNum);
void UnityConcludeTest(void);

#define UNITY_BEGIN() UnityBegin(__FILE__)
#define UNITY_END() UnityEnd()

#ifndef RUN_TEST
#define RUN_TEST(func) UnityDefaultTestRun(func, #func, __LINE__)
#endif

#define TEST_PROTECT() (setjmp(Unity.AbortFrame) == 0)
#define TEST_ABORT() longjmp(Unity.AbortFrame, 1)

/*-------------------------------------------------------
 * Output and assertion functions (called through the macros below)
 *-------------------------------------------------------*/
void UnityPrint(const char *string);
void UnityPrintLen(const char *string, const UNITY_UINT32 length);
void UnityPrintNumber(const UNITY_INT number);
void UnityPrintNumberUnsigned(const UNITY_UINT number);
void UnityPrintNumberHex(const UNITY_UINT number, const char nibbles_to_print);
void UnityPrintNumberByStyle(const UNITY_INT number, const UNITY_DISPLAY_STYLE_T style);
void UnityPrintMask(const UNITY_UINT mask, const UNITY_UINT number);
void UnityPrintFloat(const UNITY_DOUBLE number);

void UnityFail(const char *message, const UNITY_LINE_TYPE line);
void UnityIgnore(const char *message, const UNITY_LINE_TYPE line);
void UnityMessage(const char *message, const UNITY_LINE_TYPE line);

void UnityAssertEqualNumber(const UNITY_INT expected, const UNITY_INT actual, const char *msg,
                            const UNITY_LINE_TYPE lineNumber, const UNITY_DISPLAY_STYLE_T style);
void UnityAssertGreaterOrLessOrEqualNumber(const UNITY_INT threshold, const UNITY_INT actual,
                                           const UNITY_COMPARISON_T compare, const char *msg,
                                           const UNITY_LINE_TYPE lineNumber,
                                           const UNITY_DISPLAY_STYLE_T style);
void UnityAssertNumbersWithin(const UNITY_UINT delta, const UNITY_INT expected, const UNITY_INT actual,
                              const char *msg, const UNITY_LINE_TYPE lineNumber,
                              const UNITY_DISPLAY_STYLE_T style);
void UnityAssertBits(const UNITY_INT mask, const UNITY_INT expected, const UNITY_INT actual,
                     const char *msg, const UNITY_LINE_TYPE lineNumber);
void UnityAssertEqualString(const char *expected, const char *actual, const char *msg,
                            const UNITY_LINE_TYPE lineNumber);
void UnityAssertEqualStringLen(const char *expected, const char *actual, const UNITY_UINT32 length,
                               const char *msg, const UNITY_LINE_TYPE lineNumber);
void UnityAssertEqualMemory(UNITY_INTERNAL_PTR expected, UNITY_INTERNAL_PTR actual,
                            const UNITY_UINT32 length, const UNITY_UINT32 num_elements,
                            const char *msg, const UNITY_LINE_TYPE lineNumber,
                            const UNITY_FLAGS_T flags);
void UnityAssertEqualIntArray(UNITY_INTERNAL_PTR expected, UNITY_INTERNAL_PTR actual,
                              const UNITY_UINT32 num_elements, const char *msg,
                              const UNITY_LINE_TYPE lineNumber, const UNITY_DISPLAY_STYLE_T style,
                              const UNITY_FLAGS_T flags);
void UnityAssertFloatsWithin(const UNITY_FLOAT delta, const UNITY_FLOAT expected,
                             const UNITY_FLOAT actual, const char *msg,
                             const UNITY_LINE_TYPE lineNumber);
void UnityAssertDoublesWithin(const UNITY_DOUBLE delta, const UNITY_DOUBLE expected,
                              const UNITY_DOUBLE actual, const char *msg,
                              const UNITY_LINE_TYPE lineNumber);

/*-------------------------------------------------------
 * Internal assertion macros (same names as upstream's unity_internals.h)
 *-------------------------------------------------------*/
#define UNITY_PTR_TO_INT(p) ((UNITY_INT)(uintptr_t)(p))

#define UNITY_TEST_FAIL(line, message) UnityFail((message), (UNITY_LINE_TYPE)(line))
#define UNITY_TEST_IGNORE(line, message) UnityIgnore((message), (UNITY_LINE_TYPE)(line))
#define UNITY_TEST_ASSERT(condition, line, message)                                                \
    do {                                                                                           \
        if (condition) {                                                                           \
        } else {                                                                                   \
            UNITY_TEST_FAIL((line), (message));                                                    \
        }                                                                                          \
    } while (0)

#define UNITY_EQ_(e, a, T, line, msg, style)                                                       \
    UnityAssertEqualNumber((UNITY_INT)(T)(e), (UNITY_INT)(T)(a), (msg), (UNITY_LINE_TYPE)(line),   \
                           (style))
#define UNITY_CMP_(t, a, T, cmp, line, msg, style)                                                 \
    UnityAssertGreaterOrLessOrEqualNumber((UNITY_INT)(T)(t), (UNITY_INT)(T)(a), (cmp), (msg),      \
                                          (UNITY_LINE_TYPE)(line), (style))
#define UNITY_WITHIN_(d, e, a, DT, T, line, msg, style)                                            \
    UnityAssertNumbersWithin((UNITY_UINT)(DT)(d), (UNITY_INT)(T)(e), (UNITY_INT)(T)(a), (msg),     \
                             (UNITY_LINE_TYPE)(line), (style))
#define UNITY_ARRAY_(e, a, n, line, msg, style)                                                    \
    UnityAssertEqualIntArray((UNITY_INTERNAL_PTR)(e), (UNITY_INTERNAL_PTR)(a), (UNITY_UINT32)(n),  \
                             (msg), (UNITY_LINE_TYPE)(line), (style), UNITY_ARRAY_TO_ARRAY)

/*-------------------------------------------------------
 * Public API: test control
 *-------------------------------------------------------*/
#define TEST_FAIL_MESSAGE(message) UNITY_TEST_FAIL(__LINE__, (message))
#define TEST_FAIL() UNITY_TEST_FAIL(__LINE__, NULL)
#define TEST_IGNORE_MESSAGE(message) UNITY_TEST_IGNORE(__LINE__, (message))
#define TEST_IGNORE() UNITY_TEST_IGNORE(__LINE__, NULL)
#define TEST_MESSAGE(message) UnityMessage((message), __LINE__)
#define TEST_PASS() TEST_ABORT()
#define TEST_PASS_MESSAGE(message)                                                                 \
    do {                                                                                           \
        UnityMessage((message), __LINE__);                                                         \
        TEST_ABORT();                                                                              \
    } while (0)

/*-------------------------------------------------------
 * Public API: boolean / pointer
 *-------------------------------------------------------*/
#define TEST_ASSERT(condition) UNITY_TEST_ASSERT((condition), __LINE__, " Expression Evaluated To FALSE")
#define TEST_ASSERT_MESSAGE(condition, message) UNITY_TEST_ASSERT((condition), __LINE__, (message))
#define TEST_ASSERT_TRUE(condition) UNITY_TEST_ASSERT((condition), __LINE__, " Expected TRUE Was FALSE")
#define TEST_ASSERT_TRUE_MESSAGE(condition, message) UNITY_TEST_ASSERT((condition), __LINE__, (message))
#define TEST_ASSERT_UNLESS(condition) UNITY_TEST_ASSERT(!(condition), __LINE__, " Expression Evaluated To TRUE")
#define TEST_ASSERT_UNLESS_MESSAGE(condition, message) UNITY_TEST_ASSERT(!(condition), __LINE__, (message))
#define TEST_ASSERT_FALSE(condition) UNITY_TEST_ASSERT(!(condition), __LINE__, " Expected FALSE Was TRUE")
#define TEST_ASSERT_FALSE_MESSAGE(condition, message) UNITY_TEST_ASSERT(!(condition), __LINE__, (message))
#define TEST_ASSERT_NULL(pointer) UNITY_TEST_ASSERT(((pointer) == NULL), __LINE__, " Expected NULL")
#define TEST_ASSERT_NULL_MESSAGE(pointer, message) UNITY_TEST_ASSERT(((pointer) == NULL), __LINE__, (message))
#define TEST_ASSERT_NOT_NULL(pointer) UNITY_TEST_ASSERT(((pointer) != NULL), __LINE__, " Expected Non-NULL")
#define TEST_ASSERT_NOT_NULL_MESSAGE(pointer, message) UNITY_TEST_ASSERT(((pointer) != NULL), __LINE__, (message))
#define TEST_ASSERT_NOT_EQUAL(expected, actual) UNITY_TEST_ASSERT(((expected) != (actual)), __LINE__, " Expected Not-Equal")
#define TEST_ASSERT_NOT_EQUAL_MESSAGE(expected, actual, message) UNITY_TEST_ASSERT(((expected) != (actual)), __LINE__, (message))

/*-------------------------------------------------------
 * Public API: integer equality
 *-------------------------------------------------------*/
#define TEST_ASSERT_EQUAL_INT_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_EQUAL_INT8_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT8, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_EQUAL_INT16_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT16, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_EQUAL_INT32_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT32, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_EQUAL_INT64_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT64, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_EQUAL_UINT_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_INT, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_EQUAL_UINT8_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT8, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_EQUAL_UINT16_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT16, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_EQUAL_UINT32_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT32, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_EQUAL_UINT64_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT64, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_EQUAL_size_t_MESSAGE(e, a, m) UNITY_EQ_(e, a, size_t, __LINE__, (m), UNITY_DISPLAY_STYLE_SIZE_T)
#define TEST_ASSERT_EQUAL_HEX_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT32, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX32)
#define TEST_ASSERT_EQUAL_HEX8_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT8, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX8)
#define TEST_ASSERT_EQUAL_HEX16_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT16, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX16)
#define TEST_ASSERT_EQUAL_HEX32_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT32, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX32)
#define TEST_ASSERT_EQUAL_HEX64_MESSAGE(e, a, m) UNITY_EQ_(e, a, UNITY_UINT64, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX64)
#define TEST_ASSERT_EQUAL_PTR_MESSAGE(e, a, m)                                                     \
    UnityAssertEqualNumber(UNITY_PTR_TO_INT(e), UNITY_PTR_TO_INT(a), (m), (UNITY_LINE_TYPE)__LINE__, \
                           UNITY_DISPLAY_STYLE_POINTER)
#define TEST_ASSERT_EQUAL_MESSAGE(e, a, m) TEST_ASSERT_EQUAL_INT_MESSAGE(e, a, m)

#define TEST_ASSERT_EQUAL_INT(e, a) TEST_ASSERT_EQUAL_INT_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_INT8(e, a) TEST_ASSERT_EQUAL_INT8_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_INT16(e, a) TEST_ASSERT_EQUAL_INT16_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_INT32(e, a) TEST_ASSERT_EQUAL_INT32_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_INT64(e, a) TEST_ASSERT_EQUAL_INT64_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_UINT(e, a) TEST_ASSERT_EQUAL_UINT_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_UINT8(e, a) TEST_ASSERT_EQUAL_UINT8_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_UINT16(e, a) TEST_ASSERT_EQUAL_UINT16_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_UINT32(e, a) TEST_ASSERT_EQUAL_UINT32_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_UINT64(e, a) TEST_ASSERT_EQUAL_UINT64_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_size_t(e, a) TEST_ASSERT_EQUAL_size_t_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_HEX(e, a) TEST_ASSERT_EQUAL_HEX_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_HEX8(e, a) TEST_ASSERT_EQUAL_HEX8_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_HEX16(e, a) TEST_ASSERT_EQUAL_HEX16_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_HEX32(e, a) TEST_ASSERT_EQUAL_HEX32_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_HEX64(e, a) TEST_ASSERT_EQUAL_HEX64_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_PTR(e, a) TEST_ASSERT_EQUAL_PTR_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL(e, a) TEST_ASSERT_EQUAL_INT_MESSAGE(e, a, NULL)

/*-------------------------------------------------------
 * Public API: ordering (threshold first, actual second)
 *-------------------------------------------------------*/
#define TEST_ASSERT_GREATER_THAN_INT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_GREATER_THAN_INT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT8, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_GREATER_THAN_INT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT16, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_GREATER_THAN_INT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT32, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_GREATER_THAN_INT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT64, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_GREATER_THAN_UINT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_GREATER_THAN_UINT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT8, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_GREATER_THAN_UINT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT16, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_GREATER_THAN_UINT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT32, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_GREATER_THAN_UINT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT64, UNITY_GREATER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_GREATER_THAN_MESSAGE(t, a, m) TEST_ASSERT_GREATER_THAN_INT_MESSAGE(t, a, m)

#define TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT8, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT16, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT32, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT64, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT8, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT16, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT32, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT64, UNITY_GREATER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_GREATER_OR_EQUAL_MESSAGE(t, a, m) TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(t, a, m)

#define TEST_ASSERT_LESS_THAN_INT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_LESS_THAN_INT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT8, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_LESS_THAN_INT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT16, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_LESS_THAN_INT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT32, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_LESS_THAN_INT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT64, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_LESS_THAN_UINT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_LESS_THAN_UINT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT8, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_LESS_THAN_UINT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT16, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_LESS_THAN_UINT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT32, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_LESS_THAN_UINT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT64, UNITY_SMALLER_THAN, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_LESS_THAN_MESSAGE(t, a, m) TEST_ASSERT_LESS_THAN_INT_MESSAGE(t, a, m)

#define TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_LESS_OR_EQUAL_INT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT8, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_LESS_OR_EQUAL_INT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT16, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_LESS_OR_EQUAL_INT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT32, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_LESS_OR_EQUAL_INT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT64, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_INT, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT8_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT8, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT16_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT16, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT32_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT32, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT64_MESSAGE(t, a, m) UNITY_CMP_(t, a, UNITY_UINT64, UNITY_SMALLER_OR_EQUAL, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_LESS_OR_EQUAL_MESSAGE(t, a, m) TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(t, a, m)

#define TEST_ASSERT_GREATER_THAN(t, a) TEST_ASSERT_GREATER_THAN_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_INT(t, a) TEST_ASSERT_GREATER_THAN_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_INT8(t, a) TEST_ASSERT_GREATER_THAN_INT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_INT16(t, a) TEST_ASSERT_GREATER_THAN_INT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_INT32(t, a) TEST_ASSERT_GREATER_THAN_INT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_INT64(t, a) TEST_ASSERT_GREATER_THAN_INT64_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT(t, a) TEST_ASSERT_GREATER_THAN_UINT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT8(t, a) TEST_ASSERT_GREATER_THAN_UINT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT16(t, a) TEST_ASSERT_GREATER_THAN_UINT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT32(t, a) TEST_ASSERT_GREATER_THAN_UINT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_THAN_UINT64(t, a) TEST_ASSERT_GREATER_THAN_UINT64_MESSAGE(t, a, NULL)

#define TEST_ASSERT_GREATER_OR_EQUAL(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT8(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT16(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT32(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_INT64(t, a) TEST_ASSERT_GREATER_OR_EQUAL_INT64_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT(t, a) TEST_ASSERT_GREATER_OR_EQUAL_UINT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT8(t, a) TEST_ASSERT_GREATER_OR_EQUAL_UINT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT16(t, a) TEST_ASSERT_GREATER_OR_EQUAL_UINT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT32(t, a) TEST_ASSERT_GREATER_OR_EQUAL_UINT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_GREATER_OR_EQUAL_UINT64(t, a) TEST_ASSERT_GREATER_OR_EQUAL_UINT64_MESSAGE(t, a, NULL)

#define TEST_ASSERT_LESS_THAN(t, a) TEST_ASSERT_LESS_THAN_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_INT(t, a) TEST_ASSERT_LESS_THAN_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_INT8(t, a) TEST_ASSERT_LESS_THAN_INT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_INT16(t, a) TEST_ASSERT_LESS_THAN_INT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_INT32(t, a) TEST_ASSERT_LESS_THAN_INT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_INT64(t, a) TEST_ASSERT_LESS_THAN_INT64_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_UINT(t, a) TEST_ASSERT_LESS_THAN_UINT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_UINT8(t, a) TEST_ASSERT_LESS_THAN_UINT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_UINT16(t, a) TEST_ASSERT_LESS_THAN_UINT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_UINT32(t, a) TEST_ASSERT_LESS_THAN_UINT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_THAN_UINT64(t, a) TEST_ASSERT_LESS_THAN_UINT64_MESSAGE(t, a, NULL)

#define TEST_ASSERT_LESS_OR_EQUAL(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT8(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT16(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT32(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_INT64(t, a) TEST_ASSERT_LESS_OR_EQUAL_INT64_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT(t, a) TEST_ASSERT_LESS_OR_EQUAL_UINT_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT8(t, a) TEST_ASSERT_LESS_OR_EQUAL_UINT8_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT16(t, a) TEST_ASSERT_LESS_OR_EQUAL_UINT16_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT32(t, a) TEST_ASSERT_LESS_OR_EQUAL_UINT32_MESSAGE(t, a, NULL)
#define TEST_ASSERT_LESS_OR_EQUAL_UINT64(t, a) TEST_ASSERT_LESS_OR_EQUAL_UINT64_MESSAGE(t, a, NULL)

/*-------------------------------------------------------
 * Public API: integer ranges (delta, expected, actual)
 *-------------------------------------------------------*/
#define TEST_ASSERT_INT_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT, UNITY_INT, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_INT8_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT8, UNITY_INT8, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_INT16_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT16, UNITY_INT16, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_INT32_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT32, UNITY_INT32, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_INT64_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT64, UNITY_INT64, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_UINT_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT, UNITY_INT, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_UINT8_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT8, UNITY_UINT8, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_UINT16_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT16, UNITY_UINT16, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_UINT32_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT32, UNITY_UINT32, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_UINT64_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT64, UNITY_UINT64, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_HEX8_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT8, UNITY_UINT8, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX8)
#define TEST_ASSERT_HEX16_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT16, UNITY_UINT16, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX16)
#define TEST_ASSERT_HEX32_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT32, UNITY_UINT32, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX32)
#define TEST_ASSERT_HEX64_WITHIN_MESSAGE(d, e, a, m) UNITY_WITHIN_(d, e, a, UNITY_UINT64, UNITY_UINT64, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX64)

#define TEST_ASSERT_INT_WITHIN(d, e, a) TEST_ASSERT_INT_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_INT8_WITHIN(d, e, a) TEST_ASSERT_INT8_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_INT16_WITHIN(d, e, a) TEST_ASSERT_INT16_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_INT32_WITHIN(d, e, a) TEST_ASSERT_INT32_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_INT64_WITHIN(d, e, a) TEST_ASSERT_INT64_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_UINT_WITHIN(d, e, a) TEST_ASSERT_UINT_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_UINT8_WITHIN(d, e, a) TEST_ASSERT_UINT8_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_UINT16_WITHIN(d, e, a) TEST_ASSERT_UINT16_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_UINT32_WITHIN(d, e, a) TEST_ASSERT_UINT32_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_UINT64_WITHIN(d, e, a) TEST_ASSERT_UINT64_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_HEX8_WITHIN(d, e, a) TEST_ASSERT_HEX8_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_HEX16_WITHIN(d, e, a) TEST_ASSERT_HEX16_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_HEX32_WITHIN(d, e, a) TEST_ASSERT_HEX32_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_HEX64_WITHIN(d, e, a) TEST_ASSERT_HEX64_WITHIN_MESSAGE(d, e, a, NULL)

/*-------------------------------------------------------
 * Public API: floating point
 *-------------------------------------------------------*/
#define TEST_ASSERT_FLOAT_WITHIN_MESSAGE(d, e, a, m)                                               \
    UnityAssertFloatsWithin((UNITY_FLOAT)(d), (UNITY_FLOAT)(e), (UNITY_FLOAT)(a), (m),             \
                            (UNITY_LINE_TYPE)__LINE__)
#define TEST_ASSERT_EQUAL_FLOAT_MESSAGE(e, a, m)                                                   \
    TEST_ASSERT_FLOAT_WITHIN_MESSAGE((UNITY_FLOAT)(e) * (UNITY_FLOAT)UNITY_FLOAT_PRECISION, e, a, m)
#define TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(d, e, a, m)                                              \
    UnityAssertDoublesWithin((UNITY_DOUBLE)(d), (UNITY_DOUBLE)(e), (UNITY_DOUBLE)(a), (m),         \
                             (UNITY_LINE_TYPE)__LINE__)
#define TEST_ASSERT_EQUAL_DOUBLE_MESSAGE(e, a, m)                                                  \
    TEST_ASSERT_DOUBLE_WITHIN_MESSAGE((UNITY_DOUBLE)(e) * (UNITY_DOUBLE)UNITY_DOUBLE_PRECISION, e, a, m)

#define TEST_ASSERT_FLOAT_WITHIN(d, e, a) TEST_ASSERT_FLOAT_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_EQUAL_FLOAT(e, a) TEST_ASSERT_EQUAL_FLOAT_MESSAGE(e, a, NULL)
#define TEST_ASSERT_DOUBLE_WITHIN(d, e, a) TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(d, e, a, NULL)
#define TEST_ASSERT_EQUAL_DOUBLE(e, a) TEST_ASSERT_EQUAL_DOUBLE_MESSAGE(e, a, NULL)

/*-------------------------------------------------------
 * Public API: bits
 *-------------------------------------------------------*/
#define TEST_ASSERT_BITS_MESSAGE(mask, e, a, m)                                                    \
    UnityAssertBits((UNITY_INT)(mask), (UNITY_INT)(e), (UNITY_INT)(a), (m), (UNITY_LINE_TYPE)__LINE__)
#define TEST_ASSERT_BITS_HIGH_MESSAGE(mask, a, m) TEST_ASSERT_BITS_MESSAGE(mask, (UNITY_UINT)(-1), a, m)
#define TEST_ASSERT_BITS_LOW_MESSAGE(mask, a, m) TEST_ASSERT_BITS_MESSAGE(mask, (UNITY_UINT)(0), a, m)
#define TEST_ASSERT_BIT_HIGH_MESSAGE(bit, a, m)                                                    \
    TEST_ASSERT_BITS_MESSAGE(((UNITY_UINT)1 << (bit)), (UNITY_UINT)(-1), a, m)
#define TEST_ASSERT_BIT_LOW_MESSAGE(bit, a, m)                                                     \
    TEST_ASSERT_BITS_MESSAGE(((UNITY_UINT)1 << (bit)), (UNITY_UINT)(0), a, m)

#define TEST_ASSERT_BITS(mask, e, a) TEST_ASSERT_BITS_MESSAGE(mask, e, a, NULL)
#define TEST_ASSERT_BITS_HIGH(mask, a) TEST_ASSERT_BITS_HIGH_MESSAGE(mask, a, NULL)
#define TEST_ASSERT_BITS_LOW(mask, a) TEST_ASSERT_BITS_LOW_MESSAGE(mask, a, NULL)
#define TEST_ASSERT_BIT_HIGH(bit, a) TEST_ASSERT_BIT_HIGH_MESSAGE(bit, a, NULL)
#define TEST_ASSERT_BIT_LOW(bit, a) TEST_ASSERT_BIT_LOW_MESSAGE(bit, a, NULL)

/*-------------------------------------------------------
 * Public API: strings, memory, arrays
 *-------------------------------------------------------*/
#define TEST_ASSERT_EQUAL_STRING_MESSAGE(e, a, m)                                                  \
    UnityAssertEqualString((const char *)(e), (const char *)(a), (m), (UNITY_LINE_TYPE)__LINE__)
#define TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE(e, a, len, m)                                         \
    UnityAssertEqualStringLen((const char *)(e), (const char *)(a), (UNITY_UINT32)(len), (m),      \
                              (UNITY_LINE_TYPE)__LINE__)
#define TEST_ASSERT_EQUAL_MEMORY_MESSAGE(e, a, len, m)                                             \
    UnityAssertEqualMemory((UNITY_INTERNAL_PTR)(e), (UNITY_INTERNAL_PTR)(a), (UNITY_UINT32)(len), 1u, \
                           (m), (UNITY_LINE_TYPE)__LINE__, UNITY_ARRAY_TO_ARRAY)
#define TEST_ASSERT_EQUAL_MEMORY_ARRAY_MESSAGE(e, a, len, n, m)                                    \
    UnityAssertEqualMemory((UNITY_INTERNAL_PTR)(e), (UNITY_INTERNAL_PTR)(a), (UNITY_UINT32)(len),  \
                           (UNITY_UINT32)(n), (m), (UNITY_LINE_TYPE)__LINE__, UNITY_ARRAY_TO_ARRAY)

#define TEST_ASSERT_EQUAL_STRING(e, a) TEST_ASSERT_EQUAL_STRING_MESSAGE(e, a, NULL)
#define TEST_ASSERT_EQUAL_STRING_LEN(e, a, len) TEST_ASSERT_EQUAL_STRING_LEN_MESSAGE(e, a, len, NULL)
#define TEST_ASSERT_EQUAL_MEMORY(e, a, len) TEST_ASSERT_EQUAL_MEMORY_MESSAGE(e, a, len, NULL)
#define TEST_ASSERT_EQUAL_MEMORY_ARRAY(e, a, len, n) TEST_ASSERT_EQUAL_MEMORY_ARRAY_MESSAGE(e, a, len, n, NULL)

#define TEST_ASSERT_EQUAL_INT_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_INT)
#define TEST_ASSERT_EQUAL_INT8_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_INT8)
#define TEST_ASSERT_EQUAL_INT16_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_INT16)
#define TEST_ASSERT_EQUAL_INT32_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_INT32)
#define TEST_ASSERT_EQUAL_INT64_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_INT64)
#define TEST_ASSERT_EQUAL_UINT_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT)
#define TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT8)
#define TEST_ASSERT_EQUAL_UINT16_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT16)
#define TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT32)
#define TEST_ASSERT_EQUAL_UINT64_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_UINT64)
#define TEST_ASSERT_EQUAL_HEX_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX32)
#define TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX8)
#define TEST_ASSERT_EQUAL_HEX16_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX16)
#define TEST_ASSERT_EQUAL_HEX32_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX32)
#define TEST_ASSERT_EQUAL_HEX64_ARRAY_MESSAGE(e, a, n, m) UNITY_ARRAY_(e, a, n, __LINE__, (m), UNITY_DISPLAY_STYLE_HEX64)

#define TEST_ASSERT_EQUAL_INT_ARRAY(e, a, n) TEST_ASSERT_EQUAL_INT_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_INT8_ARRAY(e, a, n) TEST_ASSERT_EQUAL_INT8_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_INT16_ARRAY(e, a, n) TEST_ASSERT_EQUAL_INT16_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_INT32_ARRAY(e, a, n) TEST_ASSERT_EQUAL_INT32_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_INT64_ARRAY(e, a, n) TEST_ASSERT_EQUAL_INT64_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_UINT_ARRAY(e, a, n) TEST_ASSERT_EQUAL_UINT_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_UINT8_ARRAY(e, a, n) TEST_ASSERT_EQUAL_UINT8_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_UINT16_ARRAY(e, a, n) TEST_ASSERT_EQUAL_UINT16_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_UINT32_ARRAY(e, a, n) TEST_ASSERT_EQUAL_UINT32_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_UINT64_ARRAY(e, a, n) TEST_ASSERT_EQUAL_UINT64_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_HEX_ARRAY(e, a, n) TEST_ASSERT_EQUAL_HEX_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_HEX8_ARRAY(e, a, n) TEST_ASSERT_EQUAL_HEX8_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_HEX16_ARRAY(e, a, n) TEST_ASSERT_EQUAL_HEX16_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_HEX32_ARRAY(e, a, n) TEST_ASSERT_EQUAL_HEX32_ARRAY_MESSAGE(e, a, n, NULL)
#define TEST_ASSERT_EQUAL_HEX64_ARRAY(e, a, n) TEST_ASSERT_EQUAL_HEX64_ARRAY_MESSAGE(e, a, n, NULL)

#ifdef __cplusplus
}
#endif

#endif /* UNITY_H */
