/* Object dictionary: lookup, the read and write paths, local access, node-ID-relative defaults. */
#include <string.h>

#include "fixture.h"
#include "priv/co_priv.h"

/* The compact layout (ctest unit-mcu) is what a firmware's flash is counted with: 10 bytes a row on every target. */
#if CO_CONFIG_OD_COMPACT
typedef char compact_row_is_10_bytes[sizeof(co_od_entry_t) == 10U ? 1 : -1];
#endif

void setUp(void) { fx_start(5U, 0U); }
void tearDown(void) {}

static void lookup(void)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(&test_od, 0x1018, 0x03, &one);
    TEST_ASSERT_NOT_NULL(e);
    TEST_ASSERT_EQUAL_HEX16(0x1018, e->index);
    TEST_ASSERT_EQUAL_HEX8(0x03, e->sub);
    TEST_ASSERT_NULL(co_od_find(&test_od, 0x1018, 0x05, &one));
    TEST_ASSERT_NULL(co_od_find(&test_od, 0x0FFF, 0x00, &one));
    TEST_ASSERT_NULL(co_od_find(&test_od, 0xFFFF, 0xFF, &one));
    TEST_ASSERT_NULL(co_od_find(&test_od, 0x1400, 0x03, &one)); /* a gap: 0x1400 has 0, 1, 2 and 5 */
    TEST_ASSERT_NULL(co_od_find(&test_od, 0x1400, 0x06, &one));
    TEST_ASSERT_TRUE(co_od_has_index(&test_od, 0x1018));
    TEST_ASSERT_FALSE(co_od_has_index(&test_od, 0x2100));
    /* every sub-index of every row is found, as itself: a row's first sub-index in the table, the others of a run
     * as a copy with their own sub-index and offset; nothing past a run's end */
    unsigned subs = 0U;
    for (uint16_t i = 0U; i < test_od.count; i++) {
        const co_od_entry_t *row = &test_od.entries[i];
        for (uint8_t k = 0U; k < co_od_entry_subs(row); k++, subs++) {
            e = co_od_find(&test_od, row->index, (uint8_t)(row->sub + k), &one);
            TEST_ASSERT_EQUAL_PTR(k == 0U ? row : &one, e);
            TEST_ASSERT_EQUAL_HEX16(row->index, e->index);
            TEST_ASSERT_EQUAL_HEX8(row->sub + k, e->sub);
            TEST_ASSERT_EQUAL_UINT32(row->offset + (uint32_t)k * row->size, e->offset);
            TEST_ASSERT_EQUAL_UINT16(row->size, e->size);
            TEST_ASSERT_EQUAL_HEX8(row->flags, e->flags);
            TEST_ASSERT_EQUAL_PTR(co_od_entry_limits(&test_od, row), co_od_entry_limits(&test_od, e));
            TEST_ASSERT_EQUAL_UINT8(k == 0U ? co_od_entry_subs(row) : 1U, co_od_entry_subs(e));
        }
        const bool next_is_adjacent = i + 1U < test_od.count && test_od.entries[i + 1U].index == row->index &&
                                      test_od.entries[i + 1U].sub == row->sub + co_od_entry_subs(row);
        if (!next_is_adjacent && row->sub + co_od_entry_subs(row) <= 0xFFU) {
            TEST_ASSERT_NULL(co_od_find(&test_od, row->index, (uint8_t)(row->sub + co_od_entry_subs(row)), &one));
        }
    }
    TEST_ASSERT_EQUAL_UINT(118U, subs); /* the sub-indices test_od.c lists */
    TEST_ASSERT_TRUE(test_od.count < subs); /* runs: 0x1003:01-08 and the others are one row each */
    TEST_ASSERT_EQUAL_UINT8(8U, co_od_sub_count(&test_od, 0x1003));
    TEST_ASSERT_EQUAL_UINT8(4U, co_od_sub_count(&test_od, 0x1016));
    TEST_ASSERT_EQUAL_UINT8(3U, co_od_sub_count(&test_od, 0x1400));
}

/* Three ways to the same rows: the rows alone (test_od), an object table built from them, and that table hashed
 * (default layout): every index and sub-index gets the same answer. */
static void an_object_table_and_its_hash_find_what_the_rows_hold(void)
{
    static co_od_object_t objects[64];
    co_od_t by_object = test_od;
    by_object.n_objects = 0U;
    for (uint16_t i = 0U; i < test_od.count; i++) {
        if (i == 0U || test_od.entries[i - 1U].index != test_od.entries[i].index) {
            TEST_ASSERT_TRUE(by_object.n_objects < 64U);
            objects[by_object.n_objects].index = test_od.entries[i].index;
            objects[by_object.n_objects++].first = i;
        }
    }
    by_object.objects = objects;
    co_od_t hashed = by_object;
#if !CO_CONFIG_OD_COMPACT
    static uint16_t slots[128];
    const uint8_t bits = co_od_object_slot_bits(by_object.n_objects);
    TEST_ASSERT_TRUE((1U << bits) >= 2U * by_object.n_objects && (1U << bits) < 4U * by_object.n_objects);
    TEST_ASSERT_TRUE((1U << bits) <= 128U);
    TEST_ASSERT_FALSE(co_od_object_slots_fill(objects, by_object.n_objects, slots, (uint8_t)(bits - 1U)));
    TEST_ASSERT_FALSE(co_od_object_slots_fill(objects, by_object.n_objects, slots, 18U));
    TEST_ASSERT_TRUE(co_od_object_slots_fill(objects, by_object.n_objects, slots, bits));
    unsigned used = 0U;
    for (unsigned k = 0U; k < (1U << bits); k++) {
        used += slots[k] != 0U ? 1U : 0U;
    }
    TEST_ASSERT_EQUAL_UINT(by_object.n_objects, used);
    hashed.object_slots = slots;
    hashed.object_slot_bits = bits;
#endif
    static const uint8_t subs[] = {0U, 1U, 2U, 3U, 4U, 5U, 8U, 9U, 0x7FU, 0xFEU, 0xFFU};
    for (uint32_t index = 0U; index <= 0xFFFFU; index++) {
        for (size_t i = 0U; i < sizeof subs; i++) {
            co_od_entry_t one_a;
            co_od_entry_t one_b;
            co_od_entry_t one_c;
            const co_od_entry_t *a = co_od_find(&test_od, (uint16_t)index, subs[i], &one_a);
            const co_od_entry_t *b = co_od_find(&by_object, (uint16_t)index, subs[i], &one_b);
            const co_od_entry_t *c = co_od_find(&hashed, (uint16_t)index, subs[i], &one_c);
            TEST_ASSERT_TRUE(a == NULL ? b == NULL && c == NULL
                                       : b != NULL && c != NULL && a->index == b->index && a->index == c->index &&
                                             a->sub == subs[i] && b->sub == subs[i] && c->sub == subs[i] &&
                                             a->offset == b->offset && a->offset == c->offset);
        }
        TEST_ASSERT_EQUAL(co_od_has_index(&test_od, (uint16_t)index), co_od_has_index(&hashed, (uint16_t)index));
    }
#if !CO_CONFIG_OD_COMPACT
    /* A table of the caller's with no empty slot: a look-up of an index it lacks ends (NULL), never loops. */
    for (unsigned k = 0U; k < 4U; k++) {
        slots[k] = (uint16_t)(k + 1U);
    }
    hashed.object_slot_bits = 2U;
    hashed.n_objects = 4U;
    TEST_ASSERT_NULL(co_od_find(&hashed, 0x6000U, 0U, &(co_od_entry_t){0}));
    TEST_ASSERT_NOT_NULL(co_od_find(&hashed, objects[2].index, 0U, &(co_od_entry_t){0}));
#endif
}

/* A value inside a run is its own: writes and reads of 0x1016:03 touch its 4 bytes of the array, no other. */
static void a_run_holds_one_value_per_sub_index(void)
{
    const test_od_values_t *v = &fx.values;
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x1016, 3, "\x64\x00\x07\x00", 4U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(0x00070064UL, v->x1016_consumer[2]);
    TEST_ASSERT_EQUAL_HEX32(0U, v->x1016_consumer[1]);
    TEST_ASSERT_EQUAL_HEX32(0U, v->x1016_consumer[3]);
    TEST_ASSERT_EQUAL_HEX32(0x00ABCDEFUL, co_od_get_u32(&fx.node, 0x1018, 4));
    TEST_ASSERT_EQUAL_HEX32(0x00001234UL, co_od_get_u32(&fx.node, 0x1018, 2));
    TEST_ASSERT_EQUAL_PTR(&v->x1003_errors[6], co_od_value(&fx.node, 0x1003, 7));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, co_od_write(&fx.node, 0x1016, 5, "\x00\x00\x00\x00", 4U, CO_ORIGIN_SDO));
    /* node-ID-relative defaults of a run: each sub-index gets the node-ID added once */
    TEST_ASSERT_EQUAL_HEX32(0x605UL, v->x1200_cob[0]);
    TEST_ASSERT_EQUAL_HEX32(0x585UL, v->x1200_cob[1]);
}

static void type_sizes(void)
{
    TEST_ASSERT_EQUAL_UINT16(1U, co_od_type_size(CO_T_BOOLEAN));
    TEST_ASSERT_EQUAL_UINT16(1U, co_od_type_size(CO_T_INTEGER8));
    TEST_ASSERT_EQUAL_UINT16(2U, co_od_type_size(CO_T_UNSIGNED16));
    TEST_ASSERT_EQUAL_UINT16(4U, co_od_type_size(CO_T_REAL32));
    TEST_ASSERT_EQUAL_UINT16(8U, co_od_type_size(CO_T_UNSIGNED64));
    TEST_ASSERT_EQUAL_UINT16(0U, co_od_type_size(CO_T_VISIBLE_STRING));
}

static void local_access_bypasses_access_rights_not_sizes(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x6401, 1, 1234U)); /* RO for SDO */
    TEST_ASSERT_EQUAL_UINT16(1234U, fx.values.x6401_analog[0]);
    TEST_ASSERT_EQUAL_UINT16(1234U, co_od_get_u16(&fx.node, 0x6401, 1));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_HIGH, co_od_set_u32(&fx.node, 0x6401, 1, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_LOW, co_od_set_u8(&fx.node, 0x6401, 1, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_OBJECT, co_od_set_u8(&fx.node, 0x2100, 0, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, co_od_set_u8(&fx.node, 0x6401, 9, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x2000, 0, 5U)); /* limits are for SDO/RPDO */
    TEST_ASSERT_EQUAL_UINT16(0U, co_od_get_u16(&fx.node, 0x2000, 1)); /* missing: 0 */
    TEST_ASSERT_EQUAL_UINT32(0U, co_od_get_u32(&fx.node, 0x2000, 0)); /* other size: 0 */
    TEST_ASSERT_EQUAL_HEX32(0x000F0191UL, co_od_get_u32(&fx.node, 0x1000, 0));
    TEST_ASSERT_EQUAL_PTR(&fx.values.x2003_volatile, co_od_value(&fx.node, 0x2003, 0));
    TEST_ASSERT_NULL(co_od_value(&fx.node, 0x2003, 1));
}

static void read_path(void)
{
    uint8_t buf[32];
    size_t len = 99U;
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&fx.node, 0x1000, 0, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(4U, len);
    const uint8_t le[4] = {0x91, 0x01, 0x0F, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(le, buf, 4);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY, co_od_read(&fx.node, 0x6200, 1, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&fx.node, 0x6200, 1, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&fx.node, 0x1009, 0, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(24U, len);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_HIGH, co_od_read(&fx.node, 0x1009, 0, buf, 10U, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_HIGH, co_od_read(&fx.node, 0x1000, 0, buf, 3U, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&fx.node, 0x2006, 0, buf, sizeof buf, &len, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(8U, len);
    const uint8_t u64[8] = {8, 7, 6, 5, 4, 3, 2, 1};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(u64, buf, 8);
}

static void write_path_order(void)
{
    uint32_t hooks = fx.write_hooks;
    /* the device hook only sees writes the core accepted */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, co_od_write(&fx.node, 0x1000, 0, "\0\0\0\0", 4U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, co_od_write(&fx.node, 0x2000, 0, "\1\0", 2U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_LOW, co_od_write(&fx.node, 0x2000, 0, "\1", 1U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, co_od_write(&fx.node, 0x1019, 0, "\xF1", 1U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(hooks, fx.write_hooks);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x2000, 0, "\x10\x27", 2U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT32(hooks + 1U, fx.write_hooks);
    TEST_ASSERT_EQUAL_UINT16(10000U, fx.values.x2000_cycle_ms);
    /* a refused write changes nothing */
    fx.refuse_code = CO_ABORT_DEVICE_STATE;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, co_od_write(&fx.node, 0x2000, 0, "\x20\x4E", 2U, CO_ORIGIN_SDO));
    TEST_ASSERT_EQUAL_UINT16(10000U, fx.values.x2000_cycle_ms);
}

/* Inclusive limits of an unsigned and a signed row, at and just past each bound (also with 32-bit pairs: unit-mcu). */
static void limits_at_their_bounds(void)
{
    co_od_entry_t one;
    const co_od_entry_t *u16 = co_od_find(&test_od, 0x2000, 0, &one); /* 100..60000 */
    const co_od_entry_t *i16 = co_od_find(&test_od, 0x2001, 0, &one); /* -100..100 */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, co_od_check_limits(&test_od, u16, (const uint8_t *)"\x63\x00", 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, u16, (const uint8_t *)"\x64\x00", 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, u16, (const uint8_t *)"\x60\xEA", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_check_limits(&test_od, u16, (const uint8_t *)"\x61\xEA", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_check_limits(&test_od, u16, (const uint8_t *)"\xFF\xFF", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, co_od_check_limits(&test_od, i16, (const uint8_t *)"\x9B\xFF", 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, i16, (const uint8_t *)"\x9C\xFF", 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, i16, (const uint8_t *)"\xFF\xFF", 2U)); /* -1 */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, i16, (const uint8_t *)"\x64\x00", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_check_limits(&test_od, i16, (const uint8_t *)"\x65\x00", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, co_od_check_limits(&test_od, i16, (const uint8_t *)"\x00\x80", 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, co_od_check_limits(&test_od, i16, (const uint8_t *)"\xFF\x7F", 2U));
    /* a row without limits */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_check_limits(&test_od, co_od_find(&test_od, 0x1017, 0, &one), (const uint8_t *)"\xFF\xFF", 2U));
}

static void strings_shorter_than_capacity_are_zero_padded(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x2005, 0, "abcdefghijkl", 12U, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x2005, 0, "xy", 2U, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_STRING("xy", fx.values.x2005_description);
    for (size_t i = 2U; i < sizeof fx.values.x2005_description; i++) {
        TEST_ASSERT_EQUAL_HEX8(0, fx.values.x2005_description[i]);
    }
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_LENGTH_HIGH,
                            co_od_write(&fx.node, 0x2005, 0, "123456789012345678901", 21U, CO_ORIGIN_LOCAL));
}

static void node_id_relative_defaults(void)
{
    TEST_ASSERT_EQUAL_HEX32(0x185U, fx.values.tpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_HEX32(0x205U, fx.values.rpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_HEX32(0x85U, fx.values.x1014_cob_id_emcy);
    TEST_ASSERT_EQUAL_HEX32(0x605U, fx.values.x1200_cob[0]);
    TEST_ASSERT_EQUAL_HEX32(0x80000285UL, fx.values.tpdo_comm[1].cob_id);
    fx_start(0x42U, 0U);
    TEST_ASSERT_EQUAL_HEX32(0x1C2U, fx.values.tpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_HEX32(0xC2U, fx.values.x1014_cob_id_emcy);
}

static void init_rejects_bad_configuration(void)
{
    co_node_t n;
    co_node_cfg_t cfg = fx.cfg;
    cfg.node_id = 0U;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
    cfg.node_id = 128U;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
    cfg.node_id = 5U;
    cfg.values = NULL;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, NULL, 0U));
    cfg = fx.cfg;
    co_port_t no_send = fx.port.port;
    no_send.send = NULL;
    cfg.port = &no_send;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
#if !CO_CONFIG_OD_COMPACT
    /* an object hash of a size no look-up can use (1..17 bits), the same table with a usable one taken */
    static uint16_t slots[4];
    co_od_t od = test_od;
    od.object_slots = slots;
    cfg = fx.cfg;
    cfg.od = &od;
    od.object_slot_bits = 0U;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
    od.object_slot_bits = 18U;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, co_node_init(&n, &cfg, 0U));
    od.object_slot_bits = 2U; /* every slot empty: no object table, so look-ups search the rows */
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&n, &cfg, 0U));
#endif
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(lookup);
    RUN_TEST(a_run_holds_one_value_per_sub_index);
    RUN_TEST(an_object_table_and_its_hash_find_what_the_rows_hold);
    RUN_TEST(type_sizes);
    RUN_TEST(limits_at_their_bounds);
    RUN_TEST(local_access_bypasses_access_rights_not_sizes);
    RUN_TEST(read_path);
    RUN_TEST(write_path_order);
    RUN_TEST(strings_shorter_than_capacity_are_zero_padded);
    RUN_TEST(node_id_relative_defaults);
    RUN_TEST(init_rejects_bad_configuration);
    return UNITY_END();
}
