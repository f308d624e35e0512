/* Values have a length (docs/decisions.md): a DOMAIN, OCTET_STRING, UNICODE_STRING or VISIBLE_STRING uploads what
 * was written last, or its default, with that length, by expedited, segmented and block transfer; an empty one is a
 * size-0 upload; 0x1010 keeps the length. Exact frames in and out on a dictionary of this file's own. */
#include <stddef.h>
#include <string.h>

#include "fake_port.h"
#include "unity.h"

typedef struct lengths_values {
    uint32_t device_type;
    uint32_t store_all;
    uint8_t error_register;
    uint8_t store_n;
    uint8_t blob[64]; /* 0x2000 DOMAIN RW, default 01 02 A0 FF (tests/eds/files/all-types.eds's 0x4009) */
    uint8_t blob_len[CO_OD_LEN_SIZE];
    uint8_t octets[32]; /* 0x2001 OCTET_STRING RW, stored, default empty */
    uint8_t octets_len[CO_OD_LEN_SIZE];
    char text[24]; /* 0x2002 VISIBLE_STRING RW, stored, default "abc" */
    uint8_t text_len[CO_OD_LEN_SIZE];
    uint8_t empty[8]; /* 0x2003 DOMAIN RO, default empty */
    uint8_t empty_len[CO_OD_LEN_SIZE];
} lengths_values_t;

#define V lengths_values_t
#define ROW(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m))
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)
#define RWS (CO_OD_READ | CO_OD_WRITE | CO_OD_STORE)
static const co_od_entry_t entries[] = {
    ROW(0x1000, 0, CO_T_UNSIGNED32, RO, device_type),
    ROW(0x1001, 0, CO_T_UNSIGNED8, RO, error_register),
    ROW(0x1010, 0, CO_T_UNSIGNED8, RO, store_n),
    ROW(0x1010, 1, CO_T_UNSIGNED32, RW, store_all),
    ROW(0x2000, 0, CO_T_DOMAIN, RW, blob),
    ROW(0x2001, 0, CO_T_OCTET_STRING, RWS, octets),
    ROW(0x2002, 0, CO_T_VISIBLE_STRING, RWS, text),
    ROW(0x2003, 0, CO_T_DOMAIN, RO, empty),
};
static const V defaults = {.device_type = 0x191UL, .store_all = 1U, .store_n = 1U,
                           .blob = {0x01, 0x02, 0xA0, 0xFF}, .blob_len = {4U, 0U},
                           .text = "abc", .text_len = {3U, 0U}};
static const co_od_t od = {.name = "lengths", .entries = entries,
                           .count = (uint16_t)(sizeof entries / sizeof entries[0]), .defaults = &defaults,
                           .values_size = (uint32_t)sizeof(V), .signature = 0x1E9C7B5AUL};

static fake_port_t port;
static co_time_us_t now;
static co_node_t node;
static V values;

static void power_on(void)
{
    co_node_cfg_t cfg = fake_port_node_cfg(&port, &od, &values, 5U);
    cfg.options = CO_OPT_SDO_SEGMENTED | CO_OPT_SDO_BLOCK;
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&node, &cfg, now));
    fake_port_clear(&port);
}

void setUp(void)
{
    now = 0U;
    memset(&values, 0xEE, sizeof values); /* what the defaults must overwrite, lengths included */
    fake_port_init(&port, &now);
    power_on();
}
void tearDown(void) {}

static void request(const uint8_t req[8])
{
    co_frame_t f = {0x605U, 8U, 0U, {0U}};
    memcpy(f.data, req, 8U);
    co_node_rx(&node, &f, now);
    (void)co_node_process(&node, now);
}

#define REQ(...)                                                                                                \
    do {                                                                                                        \
        const uint8_t r_[8] = {__VA_ARGS__};                                                                    \
        request(r_);                                                                                            \
    } while (0)
#define FRAME(i, ...)                                                                                           \
    do {                                                                                                        \
        const uint8_t e_[8] = {__VA_ARGS__};                                                                    \
        TEST_ASSERT_TRUE_MESSAGE((i) < port.n_sent, "frame missing");                                          \
        TEST_ASSERT_EQUAL_HEX32(0x585U, port.sent[(i)].id);                                                     \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, port.sent[(i)].data, 8);                                               \
    } while (0)
#define LAST(...) FRAME(port.n_sent - 1U, __VA_ARGS__)

/* CRC-16/XMODEM, the CRC of CiA 301 block transfer. */
static uint16_t crc16(const uint8_t *data, size_t len)
{
    uint16_t crc = 0U;
    for (size_t i = 0U; i < len; i++) {
        crc = (uint16_t)(crc ^ (uint16_t)(data[i] << 8));
        for (unsigned b = 0U; b < 8U; b++) {
            crc = (uint16_t)((crc & 0x8000U) != 0U ? ((unsigned)crc << 1) ^ 0x1021U : (unsigned)crc << 1);
        }
    }
    return crc;
}

static const uint8_t twenty[20] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20};

/* Writes the 20 bytes above to 0x2000 by segmented download. */
static void download_twenty_segmented(void)
{
    REQ(0x21, 0x00, 0x20, 0x00, 20, 0, 0, 0);
    LAST(0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x00, 1, 2, 3, 4, 5, 6, 7);
    LAST(0x20, 0, 0, 0, 0, 0, 0, 0);
    REQ(0x10, 8, 9, 10, 11, 12, 13, 14);
    LAST(0x30, 0, 0, 0, 0, 0, 0, 0);
    REQ(0x03, 15, 16, 17, 18, 19, 20, 0); /* 1 unused byte, last */
    LAST(0x20, 0, 0, 0, 0, 0, 0, 0);
}

/* The case: 621#4009200000000000 answered with the 4 bytes of the EDS value, not 64. */
static void a_domain_uploads_its_default_with_its_length(void)
{
    REQ(0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x43, 0x00, 0x20, 0x00, 0x01, 0x02, 0xA0, 0xFF);
}

static void a_segmented_upload_returns_what_was_written_last(void)
{
    download_twenty_segmented();
    REQ(0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x41, 0x00, 0x20, 0x00, 20, 0, 0, 0);
    REQ(0x60, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x00, 1, 2, 3, 4, 5, 6, 7);
    REQ(0x70, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x10, 8, 9, 10, 11, 12, 13, 14);
    REQ(0x60, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x03, 15, 16, 17, 18, 19, 20, 0); /* 6 bytes, last */
    /* a shorter value after a longer one: 2 bytes by expedited download, 2 bytes back */
    REQ(0x2B, 0x00, 0x20, 0x00, 0xAB, 0xCD, 0, 0);
    LAST(0x60, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x4B, 0x00, 0x20, 0x00, 0xAB, 0xCD, 0, 0);
}

static void a_block_upload_returns_what_a_block_download_wrote(void)
{
    REQ(0xC6, 0x00, 0x20, 0x00, 20, 0, 0, 0); /* client CRC, size 20 */
    LAST(0xA4, 0x00, 0x20, 0x00, 10, 0, 0, 0); /* 10 segments: the 64-byte SDO buffer */
    REQ(0x01, 1, 2, 3, 4, 5, 6, 7);
    REQ(0x02, 8, 9, 10, 11, 12, 13, 14);
    REQ(0x83, 15, 16, 17, 18, 19, 20, 0);
    LAST(0xA2, 3, 10, 0, 0, 0, 0, 0);
    const uint16_t crc = crc16(twenty, sizeof twenty);
    REQ(0xC5, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0); /* 1 unused byte */
    LAST(0xA1, 0, 0, 0, 0, 0, 0, 0);
    const uint32_t before = port.n_sent;
    REQ(0xA4, 0x00, 0x20, 0x00, 127, 0, 0, 0);
    LAST(0xC6, 0x00, 0x20, 0x00, 20, 0, 0, 0);
    REQ(0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(before + 4U, port.n_sent);
    LAST(0x83, 15, 16, 17, 18, 19, 20, 0);
    REQ(0xA2, 3, 127, 0, 0, 0, 0, 0);
    LAST(0xC5, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
}

/* An empty DOMAIN: a size-0 upload, segmented and block (one segment with 7 unused bytes). */
static void an_empty_domain_is_a_size_0_upload(void)
{
    REQ(0x40, 0x03, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x41, 0x03, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x60, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x0F, 0, 0, 0, 0, 0, 0, 0);
    REQ(0xA4, 0x03, 0x20, 0x00, 127, 0, 0, 0);
    LAST(0xC6, 0x03, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0xA3, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x81, 0, 0, 0, 0, 0, 0, 0);
    REQ(0xA2, 1, 127, 0, 0, 0, 0, 0);
    LAST(0xDD, 0, 0, 0, 0, 0, 0, 0); /* 7 unused bytes, CRC of nothing: 0 */
}

/* A local read gives the length too (what the emulator's views show). */
static void a_local_read_gives_the_length(void)
{
    uint8_t buf[64];
    size_t len = 99U;
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2000, 0, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(4U, len);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2001, 0, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(0U, len);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_write(&node, 0x2001, 0, twenty, 7U, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2001, 0, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(7U, len);
    /* written around co_od_write(): co_od_changed() takes the whole capacity (a VISIBLE_STRING to its NUL) */
    memcpy(values.text, "hello", 6U);
    co_od_changed(&node, 0x2002, 0);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2002, 0, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(5U, len);
    co_od_changed(&node, 0x2001, 0);
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x2001, 0, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(32U, len);
}

/* 0x1010 keeps the length: 5 octets saved come back as 5 after a power cycle, an empty string as empty. */
static void the_store_keeps_the_length(void)
{
    REQ(0x21, 0x01, 0x20, 0x00, 5, 0, 0, 0);
    REQ(0x05, 0xDE, 0xAD, 0x00, 0x00, 0xEF, 0, 0); /* 2 unused bytes, last: 5 octets, zeros among them */
    LAST(0x20, 0, 0, 0, 0, 0, 0, 0);
    REQ(0x2F, 0x02, 0x20, 0x00, 'Z', 0, 0, 0); /* "abc" becomes "Z" */
    LAST(0x60, 0x02, 0x20, 0x00, 0, 0, 0, 0);
    REQ(0x23, 0x10, 0x10, 0x01, 's', 'a', 'v', 'e');
    LAST(0x60, 0x10, 0x10, 0x01, 0, 0, 0, 0);
    memset(&values, 0xEE, sizeof values);
    power_on();
    REQ(0x40, 0x01, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x41, 0x01, 0x20, 0x00, 5, 0, 0, 0);
    REQ(0x60, 0, 0, 0, 0, 0, 0, 0);
    LAST(0x05, 0xDE, 0xAD, 0x00, 0x00, 0xEF, 0, 0);
    REQ(0x40, 0x02, 0x20, 0x00, 0, 0, 0, 0);
    LAST(0x4F, 0x02, 0x20, 0x00, 'Z', 0, 0, 0);
    REQ(0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0); /* not stored: its default again */
    LAST(0x43, 0x00, 0x20, 0x00, 0x01, 0x02, 0xA0, 0xFF);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_domain_uploads_its_default_with_its_length);
    RUN_TEST(a_segmented_upload_returns_what_was_written_last);
    RUN_TEST(a_block_upload_returns_what_a_block_download_wrote);
    RUN_TEST(an_empty_domain_is_a_size_0_upload);
    RUN_TEST(a_local_read_gives_the_length);
    RUN_TEST(the_store_keeps_the_length);
    return UNITY_END();
}
