/* The CiA 301 types beyond the three shipped devices' (24/40/48/56-bit integers, TIME_OF_DAY, UNICODE_STRING),
 * limits of REAL32, REAL64 and UNSIGNED64 rows, [DummyUsage], and PDO state sized by the caller for an OD with
 * more PDOs than CO_TPDO_MAX (what canopen-emu does for a device read from its EDS). */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "fake_port.h"
#include "unity.h"

#define N_TPDO (CO_TPDO_MAX + 2U)

typedef struct tpdo_comm {
    uint8_t n;
    uint32_t cob;
    uint8_t type;
} tpdo_comm_t;

typedef struct types_values {
    uint32_t device_type;
    uint8_t error_register;
    uint32_t sync_cob;
    uint8_t id_n;
    uint32_t vendor;
    uint8_t rpdo_n;
    uint32_t rpdo_cob;
    uint8_t rpdo_type;
    uint8_t rmap_n;
    uint32_t rmap[2];
    tpdo_comm_t tpdo[N_TPDO];
    uint8_t tmap_n[N_TPDO];
    uint32_t tmap[N_TPDO];
    uint8_t i24[3];
    uint8_t u48[6];
    uint8_t tod[6];
    float r32;
    uint64_t r64; /* the bits of a REAL64 (a double is 32 bits wide on AVR) */
    uint64_t u64;
    uint8_t text[12];
    uint8_t text_len[CO_OD_LEN_SIZE]; /* its length (co_od.h) */
    uint16_t word;
    float r32_narrow;
} types_values_t;

#define ROW(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((types_values_t *)0)->m), offsetof(types_values_t, m))
#define ROW_L(i, s, t, f, m, n)                                                                                    \
    CO_OD_ROW_LIMITED(i, s, t, f, sizeof(((types_values_t *)0)->m), offsetof(types_values_t, m), limits, n)
#define RW (CO_OD_READ | CO_OD_WRITE)
enum { LIM_I24, LIM_R32, LIM_R64, LIM_R32_NARROW, LIM_U64 };
static const co_od_limits_t limits[] = {
    [LIM_I24] = {{.i = -1000}, {.i = 1000}},
    [LIM_R32] = {{.r = 0.0}, {.r = 10.0}},
    [LIM_R64] = {{.r = -1e30}, {.r = 1.5}},
    /* limits no float can hold: a REAL32 value is compared as the double it is */
    [LIM_R32_NARROW] = {{.r = -1e-40}, {.r = 0.1}},
    [LIM_U64] = {{.u = 0x10U}, {.u = 0x8000000000000000ULL}},
};
#define TPDO_ROWS(k)                                                                                               \
    ROW(0x1800 + (k), 0, CO_T_UNSIGNED8, CO_OD_READ, tpdo[k].n),                                                   \
        ROW(0x1800 + (k), 1, CO_T_UNSIGNED32, RW | CO_OD_NODEID, tpdo[k].cob),                                     \
        ROW(0x1800 + (k), 2, CO_T_UNSIGNED8, RW, tpdo[k].type)
#define TMAP_ROWS(k)                                                                                               \
    ROW(0x1A00 + (k), 0, CO_T_UNSIGNED8, RW, tmap_n[k]), ROW(0x1A00 + (k), 1, CO_T_UNSIGNED32, RW, tmap[k])
static const co_od_entry_t rows[] = {
    ROW(0x1000, 0, CO_T_UNSIGNED32, CO_OD_READ, device_type),
    ROW(0x1001, 0, CO_T_UNSIGNED8, CO_OD_READ, error_register),
    ROW(0x1005, 0, CO_T_UNSIGNED32, RW, sync_cob),
    ROW(0x1018, 0, CO_T_UNSIGNED8, CO_OD_READ, id_n),
    ROW(0x1018, 1, CO_T_UNSIGNED32, CO_OD_READ, vendor),
    ROW(0x1400, 0, CO_T_UNSIGNED8, CO_OD_READ, rpdo_n),
    ROW(0x1400, 1, CO_T_UNSIGNED32, RW | CO_OD_NODEID, rpdo_cob),
    ROW(0x1400, 2, CO_T_UNSIGNED8, RW, rpdo_type),
    ROW(0x1600, 0, CO_T_UNSIGNED8, RW, rmap_n),
    ROW(0x1600, 1, CO_T_UNSIGNED32, RW, rmap[0]),
    ROW(0x1600, 2, CO_T_UNSIGNED32, RW, rmap[1]),
    TPDO_ROWS(0), TPDO_ROWS(1), TPDO_ROWS(2), TPDO_ROWS(3), TPDO_ROWS(4), TPDO_ROWS(5),
    TMAP_ROWS(0), TMAP_ROWS(1), TMAP_ROWS(2), TMAP_ROWS(3), TMAP_ROWS(4), TMAP_ROWS(5),
    ROW_L(0x2000, 0, CO_T_INTEGER24, RW | CO_OD_TPDO, i24, LIM_I24),
    ROW(0x2001, 0, CO_T_UNSIGNED48, RW, u48),
    ROW(0x2002, 0, CO_T_TIME_OF_DAY, RW, tod),
    ROW_L(0x2003, 0, CO_T_REAL32, RW, r32, LIM_R32),
    ROW_L(0x2004, 0, CO_T_REAL64, RW, r64, LIM_R64),
    ROW_L(0x2005, 0, CO_T_UNSIGNED64, RW, u64, LIM_U64),
    ROW(0x2006, 0, CO_T_UNICODE_STRING, CO_OD_READ, text),
    ROW(0x2007, 0, CO_T_UNSIGNED16, RW | CO_OD_TPDO | CO_OD_RPDO, word),
    ROW_L(0x2008, 0, CO_T_REAL32, RW, r32_narrow, LIM_R32_NARROW),
};
typedef char six_tpdos_in_rows[N_TPDO == 6U ? 1 : -1]; /* TPDO_ROWS above are written out for 6 */

static types_values_t defaults;
static co_od_t od = {.name = "types", .entries = rows, .count = (uint16_t)(sizeof rows / sizeof rows[0]),
                     .defaults = &defaults, .values_size = (uint32_t)sizeof(types_values_t), .signature = 0x7E5700D1UL,
                     .dummy_usage = 1U << CO_T_UNSIGNED16, .limits = limits};

static fake_port_t port;
static co_time_us_t now;
static co_node_t node;
static types_values_t values;
static co_tpdo_t tpdo_state[N_TPDO];

static co_status_t start(bool own_arrays)
{
    now = 0U;
    fake_port_init(&port, &now);
    co_node_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.od = &od;
    cfg.values = &values;
    cfg.port = &port.port;
    cfg.port_ctx = &port;
    cfg.node_id = 5U;
    cfg.bit_timing = 4U;
    cfg.options = CO_OPT_SDO_SEGMENTED;
    if (!own_arrays) {
        cfg.tpdo = tpdo_state;
        cfg.tpdo_count = N_TPDO;
    }
    co_status_t s = co_node_init(&node, &cfg, now);
    fake_port_clear(&port);
    return s;
}

void setUp(void)
{
    memset(&defaults, 0, sizeof defaults);
    defaults.id_n = 1U;
    defaults.sync_cob = 0x80U;
    defaults.rpdo_n = 2U;
    defaults.rpdo_cob = 0x200U;
    defaults.rpdo_type = 255U;
    defaults.rmap_n = 2U;
    defaults.rmap[0] = 0x00060010UL; /* a dummy UNSIGNED16: allowed by dummy_usage */
    defaults.rmap[1] = 0x20070010UL;
    for (unsigned n = 0U; n < N_TPDO; n++) {
        defaults.tpdo[n].n = 2U;
        defaults.tpdo[n].cob = 0x180U + n; /* + node-ID: 0x185.. */
        defaults.tpdo[n].type = 1U;        /* every SYNC */
        defaults.tmap_n[n] = 1U;
        defaults.tmap[n] = n == N_TPDO - 1U ? 0x20000018UL : 0x20070010UL;
    }
    defaults.i24[0] = 0x18; /* -1000 = 0xFFFC18 */
    defaults.i24[1] = 0xFC;
    defaults.i24[2] = 0xFF;
    defaults.r32 = 2.5f;
    defaults.u64 = 0x20U;
    const uint8_t utf16[] = {'G', 0, 'r', 0, 0xFC, 0, 0xDF, 0, 'e', 0};
    memcpy(defaults.text, utf16, sizeof utf16);
    defaults.text_len[0] = (uint8_t)sizeof utf16;
    TEST_ASSERT_EQUAL_INT(CO_OK, start(false));
}
void tearDown(void) {}

static uint32_t sdo_write(uint16_t index, uint8_t sub, const uint8_t *data, uint8_t len)
{
    co_frame_t f = {0x605U, 8U, 0U, {(uint8_t)(0x23U | ((4U - len) << 2)), (uint8_t)index, (uint8_t)(index >> 8), sub}};
    memcpy(&f.data[4], data, len);
    fake_port_clear(&port);
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    const co_frame_t *r = &port.sent[0];
    TEST_ASSERT_EQUAL_HEX32(0x585U, r->id);
    if (r->data[0] != 0x80U) {
        return 0U;
    }
    return (uint32_t)r->data[4] | ((uint32_t)r->data[5] << 8) | ((uint32_t)r->data[6] << 16) | ((uint32_t)r->data[7] << 24);
}

/* Expedited upload: the answer's data bytes (n = 4 - unused count). */
static uint8_t sdo_read(uint16_t index, uint8_t sub, uint8_t out[4])
{
    const co_frame_t f = {0x605U, 8U, 0U, {0x40U, (uint8_t)index, (uint8_t)(index >> 8), sub}};
    fake_port_clear(&port);
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(1U, port.n_sent);
    const co_frame_t *r = &port.sent[0];
    TEST_ASSERT_EQUAL_HEX8(0x43U, r->data[0] & 0xF3U);
    memcpy(out, &r->data[4], 4U);
    return (uint8_t)(4U - ((r->data[0] >> 2) & 3U));
}

/* The n wire bytes (little-endian, as co_od_write takes them) of the low n bytes of v, on any host byte order. */
static const uint8_t *wire(uint64_t v, size_t n, uint8_t out[8])
{
    for (size_t i = 0U; i < n; i++) {
        out[i] = (uint8_t)(v >> (8U * i));
    }
    return out;
}

/* The bits of a float, as an integer: wire() then gives its wire bytes. */
static uint32_t float_bits(float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    return bits;
}

static void integer24_keeps_its_three_bytes_and_limits(void)
{
    uint8_t out[4];
    TEST_ASSERT_EQUAL_UINT8(3U, sdo_read(0x2000, 0, out));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){0x18, 0xFC, 0xFF}), out, 3U);
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2000, 0, (uint8_t[]){0xE8, 0x03, 0x00}, 3U)); /* 1000 */
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){0xE8, 0x03, 0x00}), values.i24, 3U);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2000, 0, (uint8_t[]){0xE9, 0x03, 0x00}, 3U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2000, 0, (uint8_t[]){0x17, 0xFC, 0xFF}, 3U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_HIGH, sdo_write(0x2000, 0, (uint8_t[]){1, 0, 0, 0}, 4U));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){0xE8, 0x03, 0x00}), values.i24, 3U); /* refused: unchanged */
}

static void real_and_unsigned64_limits_are_checked(void)
{
    uint8_t b[8];
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003, 0, wire(float_bits(10.0f), 4U, b), 4U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2003, 0, wire(float_bits(10.5f), 4U, b), 4U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2003, 0, wire(float_bits(-0.5f), 4U, b), 4U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x2003, 0, (uint8_t[]){0x00, 0x00, 0xC0, 0x7F}, 4U)); /* NaN */
    TEST_ASSERT_TRUE(values.r32 == 10.0f);
    /* REAL64 and UNSIGNED64 through the local API (8 bytes do not fit an expedited transfer) */
    const uint64_t d_ok = 0x3FF8000000000000ULL, d_high = 0x3FF8000000000001ULL; /* 1.5, the next double */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&node, 0x2004, 0, wire(d_ok, 8U, b), 8U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_write(&node, 0x2004, 0, wire(d_high, 8U, b), 8U, CO_ORIGIN_SDO));
    const uint8_t top[8] = {0, 0, 0, 0, 0, 0, 0, 0x80}, over[8] = {1, 0, 0, 0, 0, 0, 0, 0x80}, under[8] = {0x0F};
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&node, 0x2005, 0, top, 8U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_write(&node, 0x2005, 0, over, 8U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, co_od_write(&node, 0x2005, 0, under, 8U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX64(0x8000000000000000ULL, values.u64);
}

/* The answer of a floating-point comparison with the row's limits: what the core's integer comparison must give. */
static uint32_t real_limits_reference(double v, const co_od_limits_t *l)
{
    if (v != v) {
        return CO_ABORT_INVALID_VALUE;
    }
    return v > l->high.r ? CO_ABORT_VALUE_HIGH : (v < l->low.r ? CO_ABORT_VALUE_LOW : CO_ABORT_NONE);
}

static uint32_t next_random(uint32_t *state)
{
    *state = (uint32_t)(*state * 1664525UL + 1013904223UL);
    return *state;
}

/* Every class of float (zeros, subnormals, normals, infinities, NaNs) at and around limits a float cannot hold, and
 * random bit patterns: the same answer as a floating-point comparison (the core compares without floating point). */
static void real_limits_agree_with_a_floating_point_comparison(void)
{
    static const uint32_t special[] = {0x00000000UL, 0x80000000UL, 0x00000001UL, 0x80000001UL, 0x000116C2UL,
                                       0x800116C2UL, 0x800116C1UL, 0x800116C3UL, 0x007FFFFFUL, 0x807FFFFFUL,
                                       0x00800000UL, 0x3DCCCCCCUL, 0x3DCCCCCDUL, 0x3DCCCCCBUL, 0x7F800000UL,
                                       0xFF800000UL, 0x7FC00000UL, 0xFFC00001UL, 0x7F800001UL, 0x3F800000UL};
    uint32_t state = 12345U;
    for (unsigned i = 0U; i < 20000U; i++) {
        const uint32_t bits = i < sizeof special / sizeof special[0] ? special[i] : next_random(&state);
        float f;
        memcpy(&f, &bits, sizeof f);
        const uint32_t expected = real_limits_reference((double)f, &limits[LIM_R32_NARROW]);
        uint8_t b[8];
        const uint32_t got = co_od_write(&node, 0x2008, 0, wire(bits, 4U, b), 4U, CO_ORIGIN_SDO);
        if (got != expected) {
            char what[64];
            snprintf(what, sizeof what, "REAL32 bits 0x%08lX", (unsigned long)bits);
            TEST_ASSERT_EQUAL_HEX32_MESSAGE(expected, got, what);
        }
    }
    if (sizeof(double) != 8U) {
        return; /* REAL64 values need a 64-bit double to be compared with (not on AVR) */
    }
    static const uint64_t special64[] = {0x3FF8000000000000ULL, 0x3FF8000000000001ULL, 0x3FF7FFFFFFFFFFFFULL,
                                         0xFE27E41B4D2A8C5AULL, 0xFFF0000000000000ULL, 0x7FF0000000000001ULL,
                                         0x8000000000000000ULL, 0x0000000000000001ULL};
    for (unsigned i = 0U; i < 20000U; i++) {
        const uint64_t bits = i < sizeof special64 / sizeof special64[0]
                                  ? special64[i]
                                  : ((uint64_t)next_random(&state) << 32) | next_random(&state);
        double d;
        memcpy(&d, &bits, sizeof d);
        const uint32_t expected = real_limits_reference(d, &limits[LIM_R64]);
        uint8_t b[8];
        const uint32_t got = co_od_write(&node, 0x2004, 0, wire(bits, 8U, b), 8U, CO_ORIGIN_SDO);
        if (got != expected) {
            char what[64];
            snprintf(what, sizeof what, "REAL64 bits 0x%016llX", (unsigned long long)bits);
            TEST_ASSERT_EQUAL_HEX32_MESSAGE(expected, got, what);
        }
    }
}

static void six_byte_and_unicode_rows(void)
{
    const uint8_t tod[6] = {0x10, 0x20, 0x30, 0x04, 0x50, 0x60};
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&node, 0x2002, 0, tod, 6U, CO_ORIGIN_SDO));
    uint8_t buf[16];
    size_t len = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2002, 0, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(6U, len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(tod, buf, 6U);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2006, 0, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(10U, len); /* a string: the length of its value (its default), not its capacity */
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){'G', 0, 'r', 0, 0xFC, 0, 0xDF, 0}), buf, 8U);
    TEST_ASSERT_EQUAL_UINT16(0U, co_od_type_size(CO_T_UNICODE_STRING));
    TEST_ASSERT_EQUAL_UINT16(7U, co_od_type_size(CO_T_UNSIGNED56));
    TEST_ASSERT_EQUAL_UINT16(5U, co_od_type_size(CO_T_INTEGER40));
}

static void dummy_entries_follow_dummy_usage(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1400, 1, (uint8_t[]){0x05, 0x02, 0, 0x80}, 4U)); /* invalidate */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1600, 0, (uint8_t[]){0}, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1600, 1, (uint8_t[]){0x10, 0, 0x06, 0}, 4U)); /* dummy U16: allowed */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, sdo_write(0x1600, 1, (uint8_t[]){0x08, 0, 0x05, 0}, 4U)); /* U8: not */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, sdo_write(0x1600, 1, (uint8_t[]){0x20, 0, 0x07, 0}, 4U));
    /* a dummy is as long as its type (issue 15: 8 bits of a 16- or 32-bit dummy were taken) */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, sdo_write(0x1600, 1, (uint8_t[]){0x08, 0, 0x06, 0}, 4U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NOT_MAPPABLE, sdo_write(0x1600, 1, (uint8_t[]){0x20, 0, 0x06, 0}, 4U));
    /* the RPDO with its allowed dummy works: bytes 0-1 skipped, 2-3 into 0x2007 */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1600, 0, (uint8_t[]){2}, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1400, 1, (uint8_t[]){0x05, 0x02, 0, 0}, 4U));
    const co_frame_t start_op = {0x000U, 2U, 0U, {0x01, 0x05}};
    co_node_rx(&node, &start_op, now);
    const co_frame_t pdo = {0x205U, 4U, 0U, {0xAA, 0xBB, 0x34, 0x12}};
    co_node_rx(&node, &pdo, now);
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_HEX16(0x1234U, values.word);
}

static void more_tpdos_than_co_tpdo_max_with_caller_arrays(void)
{
    TEST_ASSERT_EQUAL_INT(CO_ERR_RANGE, start(true)); /* the node's own arrays hold CO_TPDO_MAX */
    TEST_ASSERT_EQUAL_INT(CO_OK, start(false));
    TEST_ASSERT_EQUAL_UINT16(N_TPDO, node.n_tpdo);
    values.word = 0x0102U;
    const co_frame_t start_op = {0x000U, 2U, 0U, {0x01, 0x05}}, sync = {0x080U, 0U, 0U, {0}};
    co_node_rx(&node, &start_op, now);
    co_node_rx(&node, &sync, now);
    (void)co_node_process(&node, now);
    TEST_ASSERT_EQUAL_UINT32(N_TPDO, port.n_sent);
    for (unsigned n = 0U; n + 1U < N_TPDO; n++) {
        TEST_ASSERT_EQUAL_HEX32(0x185U + n, port.sent[n].id);
        TEST_ASSERT_EQUAL_UINT8(2U, port.sent[n].len);
        TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){0x02, 0x01}), port.sent[n].data, 2U);
    }
    const co_frame_t *last = &port.sent[N_TPDO - 1U]; /* the 6th TPDO: the INTEGER24 */
    TEST_ASSERT_EQUAL_HEX32(0x185U + N_TPDO - 1U, last->id);
    TEST_ASSERT_EQUAL_UINT8(3U, last->len);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(((uint8_t[]){0x18, 0xFC, 0xFF}), last->data, 3U);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(integer24_keeps_its_three_bytes_and_limits);
    RUN_TEST(real_and_unsigned64_limits_are_checked);
    RUN_TEST(real_limits_agree_with_a_floating_point_comparison);
    RUN_TEST(six_byte_and_unicode_rows);
    RUN_TEST(dummy_entries_follow_dummy_usage);
    RUN_TEST(more_tpdos_than_co_tpdo_max_with_caller_arrays);
    return UNITY_END();
}
