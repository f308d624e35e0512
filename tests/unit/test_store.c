/*
 * Store / restore parameters 0x1010 / 0x1011 (facts §8, vectors #39-#41), groups, node-ID-relative rows,
 * storage failures, damaged blobs and the stored blob's format (documented at the top of src/co_store.c).
 */
#include "fixture.h"

#include <string.h>

#define SAVE 0x65766173UL /* "save" */
#define LOAD 0x64616F6CUL /* "load" */
#define HDR 16U           /* "COS1" | signature | payload length | CRC-32 */

void setUp(void)
{
    fx_start(5U, 0U);
    fake_port_clear(&fx.port);
}
void tearDown(void) {}

/* ---- helpers ---------------------------------------------------------------------------------------- */

static void sdo_expect(const uint8_t req[8], const uint8_t resp[8])
{
    const co_frame_t *f = fx_sdo(req);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(resp, f->data, 8);
}

static void save(uint8_t sub) { TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1010, sub, SAVE, 4U)); }
static void restore(uint8_t sub) { TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1011, sub, LOAD, 4U)); }
static void wr(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(index, sub, v, size));
}

static void power_cycle(void)
{
    fake_port_clear(&fx.port);
    fx.n_events = 0U;
    fx_power_cycle();
}

static int find_event_of(co_event_kind_t kind, uint16_t index)
{
    for (uint32_t i = fx.n_events; i > 0U; i--) {
        if (fx.events[i - 1U].kind == kind && fx.events[i - 1U].index == index) {
            return (int)(i - 1U);
        }
    }
    return -1;
}

/* The NVM status reported by the last CO_EV_NVM_LOADED event of an area (0x1010 parameters, 0x7E5 LSS). */
static uint32_t nvm_loaded_event_of(uint16_t index)
{
    const int e = find_event_of(CO_EV_NVM_LOADED, index);
    TEST_ASSERT_TRUE_MESSAGE(e >= 0, "no CO_EV_NVM_LOADED event");
    return fx.events[e].value;
}

static uint32_t nvm_loaded_event(void) { return nvm_loaded_event_of(0x1010U); }

static int find_event(co_event_kind_t kind)
{
    for (uint32_t i = fx.n_events; i > 0U; i--) {
        if (fx.events[i - 1U].kind == kind) {
            return (int)(i - 1U);
        }
    }
    return -1;
}

static fake_nvm_area_t *params(void) { return &fx.port.nvm[CO_NVM_PARAMS]; }

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Plain CRC-32 (IEEE 802.3, reflected, init and final xor 0xFFFFFFFF), written independently of the core. */
static uint32_t crc32_ieee(const uint8_t *p, uint32_t n)
{
    uint32_t crc = 0xFFFFFFFFUL;
    for (uint32_t i = 0U; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++) {
            crc = (crc & 1U) != 0U ? (crc >> 1) ^ 0xEDB88320UL : crc >> 1;
        }
    }
    return crc ^ 0xFFFFFFFFUL;
}

/* Walks the stored records; returns the number of records, checks they are well formed and sorted. */
static uint32_t record_count(void)
{
    const uint8_t *b = params()->stored;
    const uint32_t end = le32(&b[8]);
    uint32_t n = 0U;
    uint32_t last_key = 0U;
    for (uint32_t pos = 0U; pos < end;) {
        TEST_ASSERT_TRUE_MESSAGE(pos + 4U <= end, "record header runs past the payload");
        const uint32_t key = ((uint32_t)b[HDR + pos] | ((uint32_t)b[HDR + pos + 1U] << 8)) << 8 | b[HDR + pos + 2U];
        TEST_ASSERT_TRUE_MESSAGE(n == 0U || key > last_key, "records not sorted by (index, sub)");
        last_key = key;
        pos += 4U + b[HDR + pos + 3U];
        TEST_ASSERT_TRUE_MESSAGE(pos <= end, "record value runs past the payload");
        n++;
    }
    return n;
}

/* Finds the stored record of (index, sub); returns a pointer to its 4-byte head, or NULL. */
static const uint8_t *find_record(uint16_t index, uint8_t sub)
{
    const uint8_t *b = params()->stored;
    if (params()->stored_len < HDR) {
        return NULL;
    }
    const uint32_t end = le32(&b[8]);
    (void)record_count();
    for (uint32_t pos = 0U; pos < end; pos += 4U + b[HDR + pos + 3U]) {
        const uint8_t *r = &b[HDR + pos];
        if (r[0] == (uint8_t)index && r[1] == (uint8_t)(index >> 8) && r[2] == sub) {
            return r;
        }
    }
    return NULL;
}

static void set_all_groups(void)
{
    wr(0x1017, 0, 300U, 2U);        /* 0x1000-0x1FFF */
    wr(0x2000, 0, 1000U, 2U);       /* 0x2000-0x5FFF */
    wr(0x6300, 1, 0xAABBCCDDUL, 4U); /* 0x6000-0x9FFF */
}

/* ---- facts §11 #39-#41 and the object itself ---------------------------------------------------------- */

static void v39_save_signature(void)
{
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65},
               (const uint8_t[8]){0x60, 0x10, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00});
    TEST_ASSERT_EQUAL_UINT32(1U, params()->commits);
    const int e = find_event(CO_EV_STORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_HEX16(0x1010, fx.events[e].index);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.events[e].sub);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.events[e].code);
}

static void v40_wrong_signature(void)
{
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x01, 0x20, 0x00, 0x00, 0x08});
    /* "load" to 0x1010 and "save" to 0x1011 are wrong signatures too */
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx_sdo_write_u32(0x1010, 1, LOAD, 4U));
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx_sdo_write_u32(0x1011, 1, SAVE, 4U));
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx_sdo_write_u32(0x1010, 2, 0x65766174UL, 4U));
    TEST_ASSERT_EQUAL_UINT32(0U, params()->commits);
    TEST_ASSERT_EQUAL_UINT32(0U, params()->stored_len);
}

static void v41_load_signature(void)
{
    sdo_expect((const uint8_t[8]){0x23, 0x11, 0x10, 0x01, 0x6C, 0x6F, 0x61, 0x64},
               (const uint8_t[8]){0x60, 0x11, 0x10, 0x01, 0x00, 0x00, 0x00, 0x00});
    TEST_ASSERT_EQUAL_UINT32(1U, params()->commits);
    const int e = find_event(CO_EV_RESTORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_HEX16(0x1011, fx.events[e].index);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.events[e].code);
}

static void sub0_is_read_only(void)
{
    sdo_expect((const uint8_t[8]){0x2F, 0x10, 0x10, 0x00, 0x01, 0x00, 0x00, 0x00},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x00, 0x02, 0x00, 0x01, 0x06});
    sdo_expect((const uint8_t[8]){0x2F, 0x11, 0x10, 0x00, 0x01, 0x00, 0x00, 0x00},
               (const uint8_t[8]){0x80, 0x11, 0x10, 0x00, 0x02, 0x00, 0x01, 0x06});
    sdo_expect((const uint8_t[8]){0x40, 0x10, 0x10, 0x00, 0, 0, 0, 0},
               (const uint8_t[8]){0x4F, 0x10, 0x10, 0x00, 0x04, 0x00, 0x00, 0x00});
}

static void sub_not_existing(void)
{
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x05, 0x73, 0x61, 0x76, 0x65},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x05, 0x11, 0x00, 0x09, 0x06});
    sdo_expect((const uint8_t[8]){0x23, 0x11, 0x10, 0x05, 0x6C, 0x6F, 0x61, 0x64},
               (const uint8_t[8]){0x80, 0x11, 0x10, 0x05, 0x11, 0x00, 0x09, 0x06});
    TEST_ASSERT_EQUAL_UINT32(0U, params()->commits);
}

static void read_sub1_gives_1(void)
{
    sdo_expect((const uint8_t[8]){0x40, 0x10, 0x10, 0x01, 0, 0, 0, 0},
               (const uint8_t[8]){0x43, 0x10, 0x10, 0x01, 0x01, 0x00, 0x00, 0x00});
    sdo_expect((const uint8_t[8]){0x40, 0x11, 0x10, 0x01, 0, 0, 0, 0},
               (const uint8_t[8]){0x43, 0x11, 0x10, 0x01, 0x01, 0x00, 0x00, 0x00});
    /* writing the signature is an action: the value read stays 1 */
    save(1U);
    restore(1U);
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1010, 1, &v));
    TEST_ASSERT_EQUAL_UINT32(1U, v);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1011, 1, &v));
    TEST_ASSERT_EQUAL_UINT32(1U, v);
}

static void wrong_length_refused(void)
{
    /* "sa" with 2 bytes: the object is U32 */
    sdo_expect((const uint8_t[8]){0x2B, 0x10, 0x10, 0x01, 0x73, 0x61, 0x00, 0x00},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x01, 0x13, 0x00, 0x07, 0x06});
    TEST_ASSERT_EQUAL_UINT32(0U, params()->commits);
}

/* ---- saving and loading ---------------------------------------------------------------------------- */

static void saved_values_survive_power_cycle(void)
{
    set_all_groups();
    wr(0x2001, 0, (uint16_t)(int16_t)-50, 2U);
    wr(0x2002, 0, 42U, 1U);
    wr(0x2005, 0, 0x00636261UL, 3U); /* "abc" */
    save(1U);
    /* change everything after the save */
    wr(0x1017, 0, 400U, 2U);
    wr(0x2000, 0, 2000U, 2U);
    wr(0x6300, 1, 1U, 4U);
    wr(0x2001, 0, 7U, 2U);
    wr(0x2002, 0, 1U, 1U);
    wr(0x2005, 0, 0x007A7978UL, 3U);

    power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0xAABBCCDDUL, fx.values.x6300_value);
    TEST_ASSERT_EQUAL_INT16(-50, fx.values.x2001_offset);
    TEST_ASSERT_EQUAL_UINT8(42U, fx.values.x2002_address);
    TEST_ASSERT_EQUAL_MEMORY("abc\0\0\0\0\0\0\0", fx.values.x2005_description, 10);
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_LOADED, nvm_loaded_event());
    /* the loaded heartbeat period is in effect */
    fake_port_clear(&fx.port);
    fx_advance(300000U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x705U));
    ASSERT_FRAME(0, 0x705U, 1, 0x7F);
}

static void saved_values_return_at_nmt_reset(void)
{
    set_all_groups();
    save(1U);
    wr(0x1017, 0, 400U, 2U);
    wr(0x2000, 0, 2000U, 2U);
    wr(0x6300, 1, 1U, 4U);
    RX(0x000, 0x82, 0x05); /* communication area only */
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(2000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(1U, fx.values.x6300_value);
    wr(0x1017, 0, 400U, 2U);
    RX(0x000, 0x81, 0x05); /* everything */
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0xAABBCCDDUL, fx.values.x6300_value);
}

static void rows_without_store_flag_never_stored(void)
{
    wr(0x2003, 0, 0x12345678UL, 4U);
    wr(0x2000, 0, 1000U, 2U);
    save(1U);
    TEST_ASSERT_NULL(find_record(0x2003, 0));
    TEST_ASSERT_NULL(find_record(0x2004, 0)); /* RW, not stored */
    TEST_ASSERT_NULL(find_record(0x1018, 1)); /* RO */
    TEST_ASSERT_NULL(find_record(0x1010, 1)); /* the store command itself */
    TEST_ASSERT_NOT_NULL(find_record(0x2000, 0));
    power_cycle();
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x2003_volatile);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    wr(0x2003, 0, 0x12345678UL, 4U);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x2003_volatile);
}

/* ---- groups ---------------------------------------------------------------------------------------- */

static void save_group_2_communication_only(void)
{
    set_all_groups();
    save(2U);
    TEST_ASSERT_NOT_NULL(find_record(0x1017, 0));
    TEST_ASSERT_NULL(find_record(0x2000, 0));
    TEST_ASSERT_NULL(find_record(0x6300, 1));
    TEST_ASSERT_NULL(find_record(0x2002, 0));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
}

static void save_group_3_application_only(void)
{
    set_all_groups();
    save(3U);
    TEST_ASSERT_NULL(find_record(0x1017, 0));
    TEST_ASSERT_NULL(find_record(0x2000, 0));
    TEST_ASSERT_NOT_NULL(find_record(0x6300, 1));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0xAABBCCDDUL, fx.values.x6300_value);
}

static void save_group_4_manufacturer_only(void)
{
    set_all_groups();
    save(4U);
    TEST_ASSERT_NULL(find_record(0x1017, 0));
    TEST_ASSERT_NOT_NULL(find_record(0x2000, 0));
    TEST_ASSERT_NOT_NULL(find_record(0x2005, 0));
    TEST_ASSERT_NULL(find_record(0x6300, 1));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
}

static void saving_a_group_keeps_other_groups(void)
{
    wr(0x2000, 0, 1000U, 2U);
    save(4U);
    wr(0x2000, 0, 2000U, 2U); /* not saved again: the stored 1000 must stay */
    wr(0x1017, 0, 300U, 2U);
    save(2U);
    wr(0x6300, 1, 7U, 4U);
    wr(0x1017, 0, 400U, 2U); /* not saved again */
    save(3U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_HEX32(7U, fx.values.x6300_value);
    /* saving a group again replaces only that group's values */
    wr(0x2000, 0, 3000U, 2U);
    save(4U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(3000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_HEX32(7U, fx.values.x6300_value);
}

/* ---- restore --------------------------------------------------------------------------------------- */

static void restore_takes_effect_at_next_reset(void)
{
    set_all_groups();
    save(1U);
    restore(1U);
    /* running values unchanged */
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0xAABBCCDDUL, fx.values.x6300_value);
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x2000, 0, &v));
    TEST_ASSERT_EQUAL_UINT32(1000U, v);
    /* reset node: the defaults return */
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
}

static void restore_then_power_cycle(void)
{
    set_all_groups();
    save(1U);
    restore(1U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    /* only the CO_OD_KEEP row 0x2002 (saved at its default 99) is left */
    TEST_ASSERT_EQUAL_UINT32(1U, record_count());
    TEST_ASSERT_NOT_NULL(find_record(0x2002, 0));
}

static void restore_keeps_keep_rows(void)
{
    wr(0x2002, 0, 42U, 1U);
    wr(0x2000, 0, 1000U, 2U);
    save(1U);
    restore(1U);
    TEST_ASSERT_EQUAL_UINT32(1U, record_count());
    TEST_ASSERT_NOT_NULL(find_record(0x2002, 0));
    wr(0x2002, 0, 7U, 1U);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT8(42U, fx.values.x2002_address);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(42U, fx.values.x2002_address);
    /* restore of its own group keeps it too */
    restore(4U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(42U, fx.values.x2002_address);
}

static void restore_keep_row_never_stored_gives_default(void)
{
    wr(0x2002, 0, 42U, 1U); /* not saved */
    restore(1U);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT8(99U, fx.values.x2002_address);
}

static void restore_group_2_only_communication(void)
{
    set_all_groups();
    save(1U);
    restore(2U);
    TEST_ASSERT_NULL(find_record(0x1017, 0));
    TEST_ASSERT_NOT_NULL(find_record(0x2000, 0));
    TEST_ASSERT_NOT_NULL(find_record(0x6300, 1));
    RX(0x000, 0x82, 0x05); /* reset communication is enough for group 2 */
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0xAABBCCDDUL, fx.values.x6300_value);
}

static void restore_groups_3_and_4(void)
{
    set_all_groups();
    save(1U);
    restore(3U);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, fx.values.x6300_value);
    restore(4U);
    RX(0x000, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
}

static void restore_does_not_touch_lss_configuration(void)
{
    /* Eltex: restore factory settings except node-ID and bit timing (those live in the LSS area) */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    const uint32_t lss_commits = fx.port.nvm[CO_NVM_LSS].commits;
    restore(1U);
    TEST_ASSERT_EQUAL_UINT32(lss_commits, fx.port.nvm[CO_NVM_LSS].commits);
    power_cycle();
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
}

/* ---- node-ID-relative rows --------------------------------------------------------------------------- */

static void node_id_relative_defaults_follow_new_node_id(void)
{
    wr(0x1017, 0, 300U, 2U);
    save(1U);
    TEST_ASSERT_NULL(find_record(0x1014, 0));
    TEST_ASSERT_NULL(find_record(0x1400, 1));
    TEST_ASSERT_NULL(find_record(0x1401, 1));
    TEST_ASSERT_NULL(find_record(0x1800, 1));
    TEST_ASSERT_NULL(find_record(0x1801, 1));
    TEST_ASSERT_NOT_NULL(find_record(0x1800, 2)); /* plain row of the same object */

    /* LSS: node-ID 0x0A, store, power cycle */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    ASSERT_FRAME(fx.port.n_sent - 1U, 0x7E4U, 8, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    power_cycle();
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    sdo_expect((const uint8_t[8]){0x40, 0x14, 0x10, 0x00, 0, 0, 0, 0},
               (const uint8_t[8]){0x43, 0x14, 0x10, 0x00, 0x8A, 0x00, 0x00, 0x00});
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1800, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x18AU, v);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1400, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x20AU, v);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1801, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x8000028AUL, v);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb); /* the saved parameters are loaded too */
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    /* EMCY goes out on the new COB-ID */
    fake_port_clear(&fx.port);
    (void)co_emcy_raise(&fx.node, 0x5000U, 0x01U, NULL);
    (void)fx_process();
    TEST_ASSERT_EQUAL_UINT32(1U, fx_count(0x08AU));
}

static void node_id_relative_row_changed_is_stored_as_value(void)
{
    wr(0x1014, 0, 0x80000085UL, 4U); /* EMCY disabled: no longer the relative default */
    save(1U);
    const uint8_t *r = find_record(0x1014, 0);
    TEST_ASSERT_NOT_NULL(r);
    const uint8_t expect[8] = {0x14, 0x10, 0x00, 0x04, 0x85, 0x00, 0x00, 0x80};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(expect, r, 8);
    power_cycle();
    TEST_ASSERT_EQUAL_HEX32(0x80000085UL, fx.values.x1014_cob_id_emcy);
    /* back at the default and saved again: the record is gone */
    wr(0x1014, 0, 0x85U, 4U);
    save(1U);
    TEST_ASSERT_NULL(find_record(0x1014, 0));
}

/* A save while the node-ID is unconfigured (a local 0x1010 write; SDO needs a node-ID) must not store the bare
 * defaults of node-ID-relative rows: TPDO1's 0x180 is a restricted COB-ID, which refused the whole file at the next
 * load (found by tests/fuzz/target_nvm_file.c). They follow the node-ID the node gets, as after any save. */
static void save_while_unconfigured_keeps_relative_rows_relative(void)
{
    fx_start(0xFFU, 0U);
    const uint8_t hb[2] = {0x2C, 0x01}; /* 300 ms, in wire bytes as co_od_write takes them */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x1017, 0, hb, 2U, CO_ORIGIN_LOCAL));
    const uint8_t sig[4] = {'s', 'a', 'v', 'e'};
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&fx.node, 0x1010, 1, sig, 4U, CO_ORIGIN_SDO));
    TEST_ASSERT_NULL(find_record(0x1800, 1));
    TEST_ASSERT_NULL(find_record(0x1014, 0));
    power_cycle(); /* still unconfigured */
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    /* LSS: node-ID 0x0A, store, power cycle */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    power_cycle();
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT16(300U, fx.values.x1017_producer_hb);
    uint32_t v = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_read_u32(0x1800, 1, &v));
    TEST_ASSERT_EQUAL_HEX32(0x18AU, v);
}

/* ---- storage failures ----------------------------------------------------------------------------- */

static void store_failure(bool fail_write)
{
    wr(0x2000, 0, 1000U, 2U);
    save(1U);
    const uint32_t commits = params()->commits;
    wr(0x2000, 0, 2000U, 2U);
    fx.port.nvm_fail_write = fail_write;
    fx.port.nvm_fail_commit = !fail_write;
    fx.n_events = 0U;
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x01, 0x00, 0x00, 0x06, 0x06});
    const int e = find_event(CO_EV_STORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, fx.events[e].code);
    sdo_expect((const uint8_t[8]){0x23, 0x11, 0x10, 0x01, 0x6C, 0x6F, 0x61, 0x64},
               (const uint8_t[8]){0x80, 0x11, 0x10, 0x01, 0x00, 0x00, 0x06, 0x06});
    TEST_ASSERT_EQUAL_UINT32(commits, params()->commits);
    fx.port.nvm_fail_write = false;
    fx.port.nvm_fail_commit = false;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
}

/* ---- one store, one answer: the device's areas and the core's become durable together (co_port.h) ---- */

static fake_nvm_area_t *device_area(void) { return &fx.port.nvm[CO_NVM_DEVICE]; }

static void save_stages_device_areas_first_and_commits_params_last(void)
{
    fx.store_device_area = true;
    save(1U);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.store_hooks);
    TEST_ASSERT_EQUAL_HEX16(0x1010U, fx.store_index);
    TEST_ASSERT_EQUAL_UINT8(1U, fx.store_sub);
    TEST_ASSERT_EQUAL_STRING("2+0.", fx.port.nvm_log); /* device area with CO_NVM_MORE, then the last commit */
    TEST_ASSERT_EQUAL_UINT32(4U, device_area()->stored_len);
    TEST_ASSERT_EQUAL_MEMORY("DEV1", device_area()->stored, 4U);
    TEST_ASSERT_EQUAL_UINT32(1U, params()->commits);
    restore(1U);
    TEST_ASSERT_EQUAL_HEX16(0x1011U, fx.store_index);
    TEST_ASSERT_EQUAL_STRING("2+0.2+0.", fx.port.nvm_log);
}

/* fail_hook: the device's own area cannot be staged; else the store's last commit fails. */
static void failed_store_leaves_every_area_old(bool fail_hook)
{
    wr(0x2000, 0, 1000U, 2U);
    save(1U); /* parameters stored, no device area yet */
    wr(0x2000, 0, 2000U, 2U);
    fx.store_device_area = true;
    fx.store_fail = fail_hook;
    fx.port.nvm_fail_commit = !fail_hook;
    fx.port.nvm_log[0] = '\0';
    fx.n_events = 0U;
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x01, 0x00, 0x00, 0x06, 0x06});
    /* a failed hook: the store is discarded before the core stages its area; a failed last commit: all goes */
    TEST_ASSERT_EQUAL_STRING(fail_hook ? "2+0x" : "2+0.", fx.port.nvm_log);
    TEST_ASSERT_EQUAL_UINT32(0U, device_area()->stored_len);
    TEST_ASSERT_EQUAL_UINT32(0U, device_area()->commits);
    TEST_ASSERT_EQUAL_UINT32(1U, params()->commits);
    const int e = find_event(CO_EV_STORE);
    TEST_ASSERT_TRUE(e >= 0);
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, fx.events[e].code);
    fx.store_fail = false;
    fx.port.nvm_fail_commit = false;
    fx.store_device_area = false;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
}

static void failed_device_area_fails_the_store(void) { failed_store_leaves_every_area_old(true); }
static void failed_last_commit_drops_the_device_area(void) { failed_store_leaves_every_area_old(false); }

/* ---- stored values pass the checks of a write (issue 12, D12) ---------------------------------------------- */

#define DEFAULTS ((const test_od_values_t *)test_od.defaults)

/* Overwrites the value of a stored record (same length) and makes the blob's CRC right again: a blob no CRC
 * check can tell from one the node wrote, holding a value a write would be refused for. */
static void patch_record(uint16_t index, uint8_t sub, uint32_t value)
{
    uint8_t *r = (uint8_t *)find_record(index, sub);
    TEST_ASSERT_NOT_NULL_MESSAGE(r, "no such stored record");
    for (uint8_t i = 0U; i < r[3]; i++) {
        r[4U + i] = (uint8_t)(value >> (8U * i));
    }
    uint8_t *b = params()->stored;
    const uint32_t crc = crc32_ieee(&b[HDR], le32(&b[8]));
    for (uint8_t i = 0U; i < 4U; i++) {
        b[12U + i] = (uint8_t)(crc >> (8U * i));
    }
}

static void refused_record(uint16_t index, uint8_t sub, uint32_t value, uint32_t abort_code)
{
    wr(0x2000, 0, 1000U, 2U);
    wr(0x1017, 0, 300U, 2U);
    wr(0x1800, 2, 1U, 1U);
    save(1U);
    patch_record(index, sub, value);
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_REFUSED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_REFUSED, nvm_loaded_event());
    const int e = find_event(CO_EV_NVM_REFUSED);
    TEST_ASSERT_TRUE_MESSAGE(e >= 0, "no CO_EV_NVM_REFUSED event");
    TEST_ASSERT_EQUAL_HEX16(index, fx.events[e].index);
    TEST_ASSERT_EQUAL_HEX8(sub, fx.events[e].sub);
    TEST_ASSERT_EQUAL_HEX32(abort_code, fx.events[e].code);
    /* the whole blob is refused: every stored value is back at its default, in both areas */
    TEST_ASSERT_EQUAL_UINT16(DEFAULTS->x2000_cycle_ms, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_UINT16(DEFAULTS->x1017_producer_hb, fx.values.x1017_producer_hb);
    TEST_ASSERT_EQUAL_UINT8(DEFAULTS->tpdo_comm[0].type, fx.values.tpdo_comm[0].type);
    /* ... also after a reset communication, which loads the communication area again */
    fx_rx(0x000U, 2U, (const uint8_t[]){0x82, 0x05});
    TEST_ASSERT_EQUAL_UINT16(DEFAULTS->x1017_producer_hb, fx.values.x1017_producer_hb);
    /* a new save of valid values loads again */
    wr(0x1017, 0, 400U, 2U);
    save(1U);
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT16(400U, fx.values.x1017_producer_hb);
}

static void stored_value_above_its_limit_is_refused(void) { refused_record(0x2000, 0, 60001U, 0x06090031UL); }
static void stored_reserved_transmission_type_is_refused(void) { refused_record(0x1800, 2, 245U, 0x06090030UL); }

/* A TPDO whose COB-ID was changed by the CiA 301 procedure (invalid, new ID, valid again) is stored valid with its
 * new COB-ID and inhibit time: loading it is not a change of a valid PDO, so it loads whole. */
static void stored_valid_pdo_with_new_cob_id_loads(void)
{
    wr(0x1800, 1, 0x80000185UL, 4U);
    wr(0x1800, 1, 0x800001A5UL, 4U);
    wr(0x1800, 3, 50U, 2U);
    wr(0x1800, 1, 0x000001A5UL, 4U);
    save(1U);
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_HEX32(0x000001A5UL, fx.values.tpdo_comm[0].cob_id);
    TEST_ASSERT_EQUAL_UINT16(50U, fx.values.tpdo_comm[0].inhibit);
}

static void store_write_failure(void) { store_failure(true); }
static void store_commit_failure(void) { store_failure(false); }

static void port_without_storage(void)
{
    fx.port.port.nvm_write = NULL;
    fx.port.port.nvm_commit = NULL;
    fx.port.port.nvm_read = NULL;
    sdo_expect((const uint8_t[8]){0x23, 0x10, 0x10, 0x01, 0x73, 0x61, 0x76, 0x65},
               (const uint8_t[8]){0x80, 0x10, 0x10, 0x01, 0x00, 0x00, 0x06, 0x06});
    sdo_expect((const uint8_t[8]){0x23, 0x11, 0x10, 0x01, 0x6C, 0x6F, 0x61, 0x64},
               (const uint8_t[8]){0x80, 0x11, 0x10, 0x01, 0x00, 0x00, 0x06, 0x06});
    /* the signature is still checked first */
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx_sdo_write_u32(0x1010, 1, 0U, 4U));
    wr(0x2000, 0, 1000U, 2U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_INT(CO_NVM_NONE, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_NONE, nvm_loaded_event());
}

static void port_with_read_only_storage(void)
{
    wr(0x2000, 0, 1000U, 2U);
    save(1U);
    fx.port.port.nvm_write = NULL;
    fx.port.port.nvm_commit = NULL;
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, fx_sdo_write_u32(0x1010, 1, SAVE, 4U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms); /* still loaded */
}

/* ---- damaged blobs ---------------------------------------------------------------------------------- */

static void save_2000(void)
{
    wr(0x2000, 0, 1000U, 2U);
    save(1U);
    TEST_ASSERT_TRUE(params()->stored_len > HDR);
}

static void expect_defaults_with_status(co_nvm_status_t st)
{
    power_cycle();
    ASSERT_FRAME(0, 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT16(500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_INT(st, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)st, nvm_loaded_event());
}

static void nothing_stored_is_none(void)
{
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_NONE, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_NONE, nvm_loaded_event());
    /* also right after fx_start */
    fx_start(5U, 0U);
    TEST_ASSERT_EQUAL_INT(CO_NVM_NONE, fx.node.nvm_status);
}

static void good_blob_is_loaded(void)
{
    save_2000();
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(1000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_LOADED, nvm_loaded_event());
}

static void flipped_payload_byte_is_corrupt(void)
{
    save_2000();
    const uint8_t *r = find_record(0x2000, 0);
    TEST_ASSERT_NOT_NULL(r);
    params()->stored[(size_t)(r - params()->stored) + 4U] ^= 0x01U; /* value low byte: 1000 -> 1001 */
    expect_defaults_with_status(CO_NVM_CORRUPT);
    /* every byte of the payload is protected */
    fx_start(5U, 0U);
    save_2000();
    params()->stored[params()->stored_len - 1U] ^= 0x80U;
    expect_defaults_with_status(CO_NVM_CORRUPT);
}

static void damaged_header_is_corrupt(void)
{
    save_2000();
    params()->stored[0] = 'X'; /* magic */
    expect_defaults_with_status(CO_NVM_CORRUPT);
    fx_start(5U, 0U);
    save_2000();
    params()->stored[12] ^= 0x01U; /* CRC */
    expect_defaults_with_status(CO_NVM_CORRUPT);
    fx_start(5U, 0U);
    save_2000();
    params()->stored[8] ^= 0x04U; /* payload length */
    expect_defaults_with_status(CO_NVM_CORRUPT);
}

static void truncated_blob_is_corrupt(void)
{
    save_2000();
    params()->stored_len -= 1U;
    expect_defaults_with_status(CO_NVM_CORRUPT);
    params()->stored_len = HDR; /* header only, payload missing */
    expect_defaults_with_status(CO_NVM_CORRUPT);
}

static void truncated_header_is_corrupt(void)
{
    /* co_node.h: CORRUPT = "a blob was there but its header, length or CRC is wrong"; NONE = nothing stored */
    save_2000();
    params()->stored_len = 10U;
    expect_defaults_with_status(CO_NVM_CORRUPT);
}

static void foreign_signature(void)
{
    save_2000();
    params()->stored[4] ^= 0xFFU; /* the signature is outside the CRC */
    expect_defaults_with_status(CO_NVM_FOREIGN);
    /* a foreign blob with a bad CRC counts as corrupt */
    params()->stored[HDR + 5U] ^= 0x01U;
    expect_defaults_with_status(CO_NVM_CORRUPT);
}

static void save_over_damaged_blob_recovers(void)
{
    wr(0x1017, 0, 300U, 2U);
    save_2000();
    params()->stored[HDR] ^= 0x01U;
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_CORRUPT, fx.node.nvm_status);
    wr(0x2000, 0, 1500U, 2U);
    save(4U); /* the damaged blob counts as empty: only group 4 ends up stored */
    power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT16(1500U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_UINT16(0U, fx.values.x1017_producer_hb);
}

/* ---- blob format (top of src/co_store.c) ------------------------------------------------------------ */

static void blob_format(void)
{
    /* the reference CRC itself */
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926UL, crc32_ieee((const uint8_t *)"123456789", 9U));

    wr(0x2000, 0, 1000U, 2U);
    wr(0x1017, 0, 300U, 2U);
    wr(0x6300, 1, 0x11223344UL, 4U);
    save(1U);
    const uint8_t *b = params()->stored;
    const uint32_t payload = le32(&b[8]);
    TEST_ASSERT_EQUAL_MEMORY("COS1", b, 4);
    TEST_ASSERT_EQUAL_HEX32(test_od.signature, le32(&b[4]));
    TEST_ASSERT_EQUAL_UINT32(params()->stored_len - HDR, payload);
    TEST_ASSERT_EQUAL_HEX32(crc32_ieee(&b[HDR], payload), le32(&b[12]));

    const uint8_t r2000[6] = {0x00, 0x20, 0x00, 0x02, 0xE8, 0x03};
    TEST_ASSERT_NOT_NULL(find_record(0x2000, 0));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r2000, find_record(0x2000, 0), 6);
    const uint8_t r1017[6] = {0x17, 0x10, 0x00, 0x02, 0x2C, 0x01};
    TEST_ASSERT_NOT_NULL(find_record(0x1017, 0));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r1017, find_record(0x1017, 0), 6);
    const uint8_t r6300[8] = {0x00, 0x63, 0x01, 0x04, 0x44, 0x33, 0x22, 0x11};
    TEST_ASSERT_NOT_NULL(find_record(0x6300, 1));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r6300, find_record(0x6300, 1), 8);
    const uint8_t r2002[5] = {0x02, 0x20, 0x00, 0x01, 99};
    TEST_ASSERT_NOT_NULL(find_record(0x2002, 0));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r2002, find_record(0x2002, 0), 5);
    /* strings: their length up to the first NUL */
    const uint8_t r2005[13] = {0x05, 0x20, 0x00, 0x09, 't', 'e', 's', 't', ' ', 'n', 'o', 'd', 'e'};
    TEST_ASSERT_NOT_NULL(find_record(0x2005, 0));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r2005, find_record(0x2005, 0), 13);
    /* one record per stored sub-index of the test OD that is not at a node-ID-relative default: every sub-index of
     * a run (0x1016:01-04 is one row) has its own record */
    const uint8_t r1016_4[8] = {0x16, 0x10, 0x04, 0x04, 0x00, 0x00, 0x00, 0x00};
    TEST_ASSERT_NOT_NULL(find_record(0x1016, 4));
    TEST_ASSERT_EQUAL_HEX8_ARRAY(r1016_4, find_record(0x1016, 4), 8);
    TEST_ASSERT_NOT_NULL(find_record(0x1A01, 8));
    uint32_t expected = 0U;
    for (uint16_t i = 0U; i < test_od.count; i++) {
        const co_od_entry_t *e = &test_od.entries[i];
        if ((e->flags & CO_OD_STORE) != 0U && (e->flags & CO_OD_NODEID) == 0U) {
            expected += co_od_entry_subs(e);
        }
    }
    TEST_ASSERT_EQUAL_UINT32(expected, record_count());
}

static void lss_blob_format(void)
{
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x13, 0x00, 0x03, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    const fake_nvm_area_t *a = &fx.port.nvm[CO_NVM_LSS];
    TEST_ASSERT_EQUAL_UINT32(12U, a->stored_len);
    const uint8_t head[8] = {'C', 'O', 'L', '1', 0x0A, 0x03, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(head, a->stored, 8);
    TEST_ASSERT_EQUAL_HEX32(crc32_ieee(a->stored, 8U), le32(&a->stored[8]));
    /* the LSS area does not disturb the parameter area */
    TEST_ASSERT_EQUAL_UINT32(0U, params()->stored_len);
}

/* The LSS area is checked like the parameters: a damaged blob is reported once at power-on (CO_EV_NVM_LOADED,
 * index 0x7E5) and the configured node-ID and bit timing are used. */
static void damaged_lss_blob_is_reported_and_ignored(void)
{
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_NONE, nvm_loaded_event_of(0x7E5U));
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0A, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0x00, 0, 0, 0, 0, 0, 0);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_LOADED, nvm_loaded_event_of(0x7E5U));
    TEST_ASSERT_EQUAL_HEX8(0x0A, co_node_id(&fx.node));
    fake_nvm_area_t *a = &fx.port.nvm[CO_NVM_LSS];
    uint8_t good[12];
    memcpy(good, a->stored, sizeof good);
    static const struct {
        uint32_t len;  /* stored length after the damage */
        int flip;      /* byte to flip, -1 none */
    } damage[] = {{12U, 4}, {12U, 9}, {12U, 0}, {11U, -1}, {4U, -1}, {0U, -1}};
    for (size_t i = 0U; i < sizeof damage / sizeof damage[0]; i++) {
        memcpy(a->stored, good, sizeof good);
        a->stored_len = damage[i].len;
        a->empty_blob = damage[i].len == 0U;
        if (damage[i].flip >= 0) {
            a->stored[damage[i].flip] ^= 0x01U;
        }
        power_cycle();
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(CO_NVM_CORRUPT, nvm_loaded_event_of(0x7E5U), "damage not reported");
        TEST_ASSERT_EQUAL_HEX8(0x05, co_node_id(&fx.node)); /* the configured node-ID */
        ASSERT_FRAME(0, 0x705U, 1, 0x00);
    }
    /* A valid CRC over values this node never writes: node-ID 0; bit timing 5, which the CiA 305 table of the test
     * node lacks (an LSS configure bit timing of it is refused); "unconfigured" where LSS may not unconfigure. The
     * last of each pair is the same blob with a value it does write, which loads. */
    static const struct {
        uint8_t id;
        uint8_t bit_timing;
        uint32_t options;
        co_nvm_status_t status;
    } forged[] = {{0x00, 0x00, 0U, CO_NVM_CORRUPT},
                  {0x05, 0x05, 0U, CO_NVM_CORRUPT},
                  {0x05, 0x04, 0U, CO_NVM_LOADED},
                  {0xFF, 0x00, CO_OPT_LSS_NO_UNCONFIGURE, CO_NVM_CORRUPT},
                  {0xFF, 0x00, 0U, CO_NVM_LOADED}};
    for (size_t i = 0U; i < sizeof forged / sizeof forged[0]; i++) {
        fx_start(5U, forged[i].options);
        uint8_t *b = fx.port.nvm[CO_NVM_LSS].stored;
        const uint8_t head[8] = {'C', 'O', 'L', '1', forged[i].id, forged[i].bit_timing, 0x00, 0x00};
        memcpy(b, head, sizeof head);
        const uint32_t crc = crc32_ieee(b, 8U);
        for (unsigned k = 0U; k < 4U; k++) {
            b[8U + k] = (uint8_t)(crc >> (8U * k));
        }
        fx.port.nvm[CO_NVM_LSS].stored_len = 12U;
        power_cycle();
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(forged[i].status, nvm_loaded_event_of(0x7E5U), "forged LSS blob");
        TEST_ASSERT_EQUAL_HEX8(forged[i].status == CO_NVM_LOADED ? forged[i].id : 0x05, co_node_id(&fx.node));
    }
}

/* An empty parameter blob (an empty file) is a damaged one, not "nothing stored". */
static void empty_parameter_blob_is_damaged(void)
{
    params()->stored_len = 0U;
    params()->empty_blob = true;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_CORRUPT, nvm_loaded_event());
    TEST_ASSERT_EQUAL_INT(CO_NVM_CORRUPT, fx.node.nvm_status);
    params()->empty_blob = false;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(CO_NVM_NONE, nvm_loaded_event());
}

/* A value the application wrote past the object's limits (a local write checks none) would be refused at the next
 * load: the save fails as a whole (0x08000020) instead of being confirmed and then lost to defaults. Found by the
 * long run of fuzz_nvm_file (an SDS whose 0x2002:07 had been set to 9 locally). */
static void a_value_its_load_would_refuse_fails_the_save(void)
{
    wr(0x2000, 0, 2000U, 2U);
    save(1U);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x2000U, 0U, 50U)); /* below the limit 100 */
    fx.n_events = 0U;
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx_sdo_write_u32(0x1010, 1, SAVE, 4U));
    const int refused = find_event_of(CO_EV_NVM_REFUSED, 0x2000U);
    TEST_ASSERT_TRUE(refused >= 0);
    TEST_ASSERT_EQUAL_UINT32(1U, fx.events[refused].value); /* at a save */
    TEST_ASSERT_EQUAL_HEX32(0x06090032UL, fx.events[refused].code);
    TEST_ASSERT_EQUAL_HEX32(0x08000020UL, fx.events[find_event_of(CO_EV_STORE, 0x1010U)].code);
    power_cycle(); /* the save before it holds */
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT16(2000U, fx.values.x2000_cycle_ms);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_set_u16(&fx.node, 0x2000U, 0U, 150U)); /* in range again: saved */
    save(1U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT16(150U, fx.values.x2000_cycle_ms);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(v39_save_signature);
    RUN_TEST(v40_wrong_signature);
    RUN_TEST(v41_load_signature);
    RUN_TEST(sub0_is_read_only);
    RUN_TEST(sub_not_existing);
    RUN_TEST(read_sub1_gives_1);
    RUN_TEST(wrong_length_refused);
    RUN_TEST(saved_values_survive_power_cycle);
    RUN_TEST(saved_values_return_at_nmt_reset);
    RUN_TEST(rows_without_store_flag_never_stored);
    RUN_TEST(save_group_2_communication_only);
    RUN_TEST(save_group_3_application_only);
    RUN_TEST(save_group_4_manufacturer_only);
    RUN_TEST(saving_a_group_keeps_other_groups);
    RUN_TEST(restore_takes_effect_at_next_reset);
    RUN_TEST(restore_then_power_cycle);
    RUN_TEST(restore_keeps_keep_rows);
    RUN_TEST(restore_keep_row_never_stored_gives_default);
    RUN_TEST(restore_group_2_only_communication);
    RUN_TEST(restore_groups_3_and_4);
    RUN_TEST(restore_does_not_touch_lss_configuration);
    RUN_TEST(node_id_relative_defaults_follow_new_node_id);
    RUN_TEST(node_id_relative_row_changed_is_stored_as_value);
    RUN_TEST(save_while_unconfigured_keeps_relative_rows_relative);
    RUN_TEST(store_write_failure);
    RUN_TEST(store_commit_failure);
    RUN_TEST(port_without_storage);
    RUN_TEST(port_with_read_only_storage);
    RUN_TEST(nothing_stored_is_none);
    RUN_TEST(good_blob_is_loaded);
    RUN_TEST(flipped_payload_byte_is_corrupt);
    RUN_TEST(damaged_header_is_corrupt);
    RUN_TEST(truncated_blob_is_corrupt);
    RUN_TEST(truncated_header_is_corrupt);
    RUN_TEST(foreign_signature);
    RUN_TEST(save_over_damaged_blob_recovers);
    RUN_TEST(blob_format);
    RUN_TEST(lss_blob_format);
    RUN_TEST(damaged_lss_blob_is_reported_and_ignored);
    RUN_TEST(empty_parameter_blob_is_damaged);
    RUN_TEST(save_stages_device_areas_first_and_commits_params_last);
    RUN_TEST(stored_value_above_its_limit_is_refused);
    RUN_TEST(stored_reserved_transmission_type_is_refused);
    RUN_TEST(stored_valid_pdo_with_new_cob_id_loads);
    RUN_TEST(failed_device_area_fails_the_store);
    RUN_TEST(failed_last_commit_drops_the_device_area);
    RUN_TEST(a_value_its_load_would_refuse_fails_the_save);
    return UNITY_END();
}
