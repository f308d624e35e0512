/* Large objects (issue 35, rule 5; co_hooks_t.large_read/large_write): a DOMAIN whose value the application keeps
 * moves by segmented and block transfer, with the CRC, in pieces of at most CO_SDO_BUF_SIZE bytes; the application
 * sees BEGIN, DATA in order, then END or ABORT, and refuses what it cannot take. Exact frames in and out. */
#include <stddef.h>
#include <string.h>

#include "fake_port.h"
#include "unity.h"

#if CO_CONFIG_LARGE_OBJECTS

typedef struct large_values {
    uint32_t device_type;
    uint8_t error_register;
    uint8_t image_len[CO_OD_LEN_SIZE]; /* a large row holds no value; its length bytes are unused */
    uint8_t log_len[CO_OD_LEN_SIZE];
} large_values_t;

#define V large_values_t
#define RO CO_OD_READ
#define RW (CO_OD_READ | CO_OD_WRITE)
static const co_od_entry_t entries[] = {
    CO_OD_ROW(0x1000, 0, CO_T_UNSIGNED32, RO, sizeof(uint32_t), offsetof(V, device_type)),
    CO_OD_ROW(0x1001, 0, CO_T_UNSIGNED8, RO, sizeof(uint8_t), offsetof(V, error_register)),
    CO_OD_ROW(0x1F50, 1, CO_T_DOMAIN, RW, 0U, offsetof(V, image_len)), /* program data: size 0, a large object */
    CO_OD_ROW(0x2100, 0, CO_T_DOMAIN, RO, 0U, offsetof(V, log_len)),
};
static const V defaults = {.device_type = 0x191UL};
static const co_od_t od = {.name = "large", .entries = entries, .count = (uint16_t)(sizeof entries / sizeof entries[0]),
                           .defaults = &defaults, .values_size = (uint32_t)sizeof(V), .signature = 0x1A5E0B1EUL};

/* The application's side: one value per object, and a download's bytes until its END. */
#define MAX_VALUE (1024U * 1024U) /* a mebibyte: the least */
static struct app {
    uint8_t value[2][MAX_VALUE];
    uint32_t len[2];
    uint8_t next[MAX_VALUE];
    uint32_t next_len;
    char steps[64]; /* B begin, D data, E end, A abort */
    uint32_t n_steps;
    uint32_t biggest_piece;
    uint32_t begin_size;
} app;

static int which(const co_od_entry_t *e) { return e->index == 0x1F50U ? 0 : 1; }

static void step(char c)
{
    if (app.n_steps + 1U < sizeof app.steps && (app.n_steps == 0U || c != 'D' || app.steps[app.n_steps - 1U] != 'D')) {
        app.steps[app.n_steps++] = c; /* a run of DATA counts once */
    }
}

static uint32_t large_read(void *ctx, co_node_t *node, const co_od_entry_t *e, uint32_t offset, uint8_t *buf, size_t len,
                           uint32_t *length)
{
    (void)ctx;
    (void)node;
    const int k = which(e);
    *length = app.len[k];
    if (offset + len > app.len[k]) {
        return CO_ABORT_NO_DATA;
    }
    if (len > 0U) { /* len 0: the length only (buf may be NULL) */
        app.biggest_piece = len > app.biggest_piece ? (uint32_t)len : app.biggest_piece;
        memcpy(buf, &app.value[k][offset], len);
    }
    return 0U;
}

static uint32_t large_write(void *ctx, co_node_t *node, const co_od_entry_t *e, co_large_step_t s, uint32_t at,
                            const uint8_t *data, size_t len)
{
    (void)ctx;
    (void)node;
    switch (s) {
    case CO_LARGE_BEGIN:
        step('B');
        app.begin_size = at;
        app.next_len = 0U;
        return at > MAX_VALUE ? CO_ABORT_LENGTH_HIGH : 0U;
    case CO_LARGE_DATA:
        step('D');
        TEST_ASSERT_EQUAL_UINT32(app.next_len, at); /* in order */
        app.biggest_piece = len > app.biggest_piece ? (uint32_t)len : app.biggest_piece;
        if (at + len > MAX_VALUE) {
            return CO_ABORT_OUT_OF_MEMORY;
        }
        memcpy(&app.next[at], data, len);
        app.next_len += (uint32_t)len;
        return 0U;
    case CO_LARGE_END:
        step('E');
        TEST_ASSERT_EQUAL_UINT32(app.next_len, at);
        memcpy(app.value[which(e)], app.next, at);
        app.len[which(e)] = at;
        return 0U;
    default:
        step('A');
        return 0U;
    }
}

static const co_hooks_t hooks = {.large_read = large_read, .large_write = large_write};
static fake_port_t port;
static co_time_us_t now;
static co_node_t node;
static V values;

static void start(const co_hooks_t *h)
{
    co_node_cfg_t cfg = fake_port_node_cfg(&port, &od, &values, 5U);
    cfg.options = CO_OPT_SDO_SEGMENTED | CO_OPT_SDO_BLOCK;
    cfg.hooks = h;
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&node, &cfg, now));
    fake_port_clear(&port);
}

void setUp(void)
{
    now = 0U;
    memset(&app, 0, sizeof app);
    for (uint32_t i = 0U; i < MAX_VALUE; i++) {
        app.value[0][i] = (uint8_t)(i * 7U + 1U);
        app.value[1][i] = (uint8_t)(i ^ 0x5AU);
    }
    app.len[0] = 1000U;
    app.len[1] = 3U;
    fake_port_init(&port, &now);
    start(&hooks);
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
#define LAST(...)                                                                                               \
    do {                                                                                                        \
        const uint8_t e_[8] = {__VA_ARGS__};                                                                    \
        TEST_ASSERT_TRUE_MESSAGE(port.n_sent > 0U, "no frame");                                                 \
        TEST_ASSERT_EQUAL_HEX32(0x585U, port.sent[port.n_sent - 1U].id);                                        \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, port.sent[port.n_sent - 1U].data, 8);                                  \
    } while (0)

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

static const uint8_t *last_data(void) { return &port.sent[port.n_sent - 1U].data[0]; }

/* 1000 bytes, 15 times the SDO buffer, by a segmented upload: 143 segments, each read as it goes (7 bytes). */
static void a_segmented_upload_reads_the_object_piece_by_piece(void)
{
    REQ(0x40, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    LAST(0x41, 0x50, 0x1F, 0x01, 0xE8, 0x03, 0, 0);
    uint8_t got[1000];
    uint32_t n = 0U;
    for (uint8_t toggle = 0U; n < 1000U; toggle ^= 0x10U) {
        REQ((uint8_t)(0x60U | toggle), 0, 0, 0, 0, 0, 0, 0);
        const uint8_t *d = last_data();
        TEST_ASSERT_EQUAL_HEX8(toggle, d[0] & 0x10U);
        const uint32_t k = 7U - ((d[0] >> 1) & 7U);
        memcpy(&got[n], &d[1], k);
        n += k;
        TEST_ASSERT_EQUAL(n == 1000U, (d[0] & 1U) != 0U);
    }
    TEST_ASSERT_EQUAL_HEX8_ARRAY(app.value[0], got, 1000U);
    TEST_ASSERT_TRUE(app.biggest_piece <= CO_SDO_BUF_SIZE);
}

/* 200 bytes by a segmented download: handed over in pieces of at most the buffer, in order, then END. */
static void a_segmented_download_hands_the_value_over_in_pieces(void)
{
    uint8_t image[200];
    for (unsigned i = 0U; i < sizeof image; i++) {
        image[i] = (uint8_t)(0xC0U ^ i);
    }
    REQ(0x21, 0x50, 0x1F, 0x01, 200, 0, 0, 0);
    LAST(0x60, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    uint8_t toggle = 0U;
    const unsigned total = (unsigned)sizeof image;
    for (unsigned at = 0U; at < total; at += 7U, toggle ^= 0x10U) {
        const unsigned k = total - at < 7U ? total - at : 7U;
        uint8_t seg[8] = {(uint8_t)(toggle | ((7U - k) << 1) | (at + k == total ? 1U : 0U))};
        memcpy(&seg[1], &image[at], k);
        request(seg);
        LAST((uint8_t)(0x20U | toggle), 0, 0, 0, 0, 0, 0, 0);
    }
    TEST_ASSERT_EQUAL_STRING("BDE", app.steps);
    TEST_ASSERT_EQUAL_UINT32(200U, app.begin_size);
    TEST_ASSERT_EQUAL_UINT32(200U, app.len[0]);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(image, app.value[0], sizeof image);
    TEST_ASSERT_TRUE(app.biggest_piece <= CO_SDO_BUF_SIZE);
}

/* Sends n bytes as block download segments of one block from sequence number 1 (the last with the c bit). */
static void send_block(const uint8_t *data, unsigned n)
{
    for (unsigned at = 0U, seq = 1U; at < n; at += 7U, seq++) {
        uint8_t seg[8] = {(uint8_t)(seq | (at + 7U >= n ? 0x80U : 0U))};
        memcpy(&seg[1], &data[at], n - at < 7U ? n - at : 7U);
        request(seg);
    }
}

/* 700 bytes by a block download with the CRC: whole blocks of 127 segments offered, the CRC taken as the pieces go. */
static void a_block_download_with_crc_of_a_large_object(void)
{
    uint8_t image[700];
    for (unsigned i = 0U; i < sizeof image; i++) {
        image[i] = (uint8_t)(i * 13U);
    }
    REQ(0xC6, 0x50, 0x1F, 0x01, 0xBC, 0x02, 0, 0); /* CRC, size 700 */
    LAST(0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0);
    send_block(image, sizeof image); /* 100 segments: the last full */
    LAST(0xA2, 100, 127, 0, 0, 0, 0, 0);
    const uint16_t crc = crc16(image, sizeof image);
    REQ(0xC1, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    LAST(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("BDE", app.steps);
    TEST_ASSERT_EQUAL_UINT32(700U, app.len[0]);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(image, app.value[0], sizeof image);
    TEST_ASSERT_TRUE(app.biggest_piece <= CO_SDO_BUF_SIZE);
}

/* A wrong CRC: 0x05040004, ABORT to the application, the old value stays. */
static void a_bad_crc_drops_the_download(void)
{
    uint8_t image[100] = {1, 2, 3};
    REQ(0xC6, 0x50, 0x1F, 0x01, 100, 0, 0, 0);
    send_block(image, sizeof image); /* 15 segments, 5 unused bytes */
    LAST(0xA2, 15, 127, 0, 0, 0, 0, 0);
    const uint16_t crc = (uint16_t)(crc16(image, sizeof image) ^ 1U);
    REQ(0xD5, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    LAST(0x80, 0x50, 0x1F, 0x01, 0x04, 0x00, 0x04, 0x05);
    TEST_ASSERT_EQUAL_STRING("BDA", app.steps);
    TEST_ASSERT_EQUAL_UINT32(1000U, app.len[0]);
}

/* 1000 bytes by a block upload with the CRC: 143 segments in two blocks, the CRC of the whole at the end. */
static void a_block_upload_with_crc_of_a_large_object(void)
{
    REQ(0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0);
    LAST(0xC6, 0x50, 0x1F, 0x01, 0xE8, 0x03, 0, 0);
    REQ(0xA3, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(1U + 127U, port.n_sent); /* a whole block at once: the port takes every frame */
    const uint32_t first = 1U;
    TEST_ASSERT_EQUAL_HEX8(0x01, port.sent[first].data[0]);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(&app.value[0][0], &port.sent[first].data[1], 7U);
    TEST_ASSERT_EQUAL_HEX8(127, last_data()[0]);
    REQ(0xA2, 127, 127, 0, 0, 0, 0, 0);
    LAST(0x90, app.value[0][994], app.value[0][995], app.value[0][996], app.value[0][997], app.value[0][998],
         app.value[0][999], 0); /* segment 16 of the second block, the last (c bit, 0x80 | 16), 6 bytes */
    REQ(0xA2, 16, 127, 0, 0, 0, 0, 0);
    const uint16_t crc = crc16(app.value[0], 1000U);
    LAST(0xC5, (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0); /* 1 unused byte */
    REQ(0xA1, 0, 0, 0, 0, 0, 0, 0);
}

/* 1 MiB by a segmented download, back by a block upload with the CRC; another 1 MiB by a block download with the
 * CRC, back by a segmented upload. The frames are checked by their contents (their number: 150,000 each way). */
static void a_mebibyte_each_way(void)
{
    static uint8_t image[MAX_VALUE];
    for (uint32_t i = 0U; i < MAX_VALUE; i++) {
        image[i] = (uint8_t)((i * 2654435761U) >> 24);
    }
    REQ(0x21, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x10, 0x00);
    uint8_t toggle = 0U;
    for (uint32_t at = 0U; at < MAX_VALUE; at += 7U, toggle ^= 0x10U) {
        const uint32_t k = MAX_VALUE - at < 7U ? MAX_VALUE - at : 7U;
        uint8_t seg[8] = {(uint8_t)(toggle | ((7U - k) << 1) | (at + k == MAX_VALUE ? 1U : 0U))};
        memcpy(&seg[1], &image[at], k);
        fake_port_clear(&port);
        request(seg);
        LAST((uint8_t)(0x20U | toggle), 0, 0, 0, 0, 0, 0, 0);
    }
    TEST_ASSERT_EQUAL_STRING("BDE", app.steps);
    TEST_ASSERT_EQUAL_UINT32(MAX_VALUE, app.len[0]);
    TEST_ASSERT_EQUAL_MEMORY(image, app.value[0], MAX_VALUE);
    /* block upload, 127 segments a block, each block confirmed whole */
    REQ(0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0);
    LAST(0xC6, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x10, 0x00);
    static uint8_t got[MAX_VALUE];
    uint32_t n = 0U;
    uint8_t cmd[8] = {0xA3, 0, 0, 0, 0, 0, 0, 0};
    for (;;) {
        fake_port_clear(&port);
        request(cmd);
        uint8_t seq = 0U;
        bool last = false;
        for (uint32_t i = 0U; i < port.n_sent && !last; i++) {
            const uint8_t *d = port.sent[i].data;
            TEST_ASSERT_EQUAL_UINT8(seq + 1U, d[0] & 0x7FU);
            seq = (uint8_t)(d[0] & 0x7FU);
            last = (d[0] & 0x80U) != 0U;
            const uint32_t k = MAX_VALUE - n < 7U ? MAX_VALUE - n : 7U;
            memcpy(&got[n], &d[1], k);
            n += k;
        }
        const uint8_t ack[8] = {0xA2, seq, 127, 0, 0, 0, 0, 0};
        memcpy(cmd, ack, sizeof cmd);
        if (last) {
            break;
        }
    }
    fake_port_clear(&port);
    request(cmd);
    const uint16_t crc = crc16(image, MAX_VALUE);
    const uint8_t unused = (uint8_t)((7U - MAX_VALUE % 7U) % 7U);
    LAST((uint8_t)(0xC1U | (unused << 2)), (uint8_t)crc, (uint8_t)(crc >> 8), 0, 0, 0, 0, 0);
    REQ(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(MAX_VALUE, n);
    TEST_ASSERT_EQUAL_MEMORY(image, got, MAX_VALUE);
    /* block download of the image reversed, with the CRC, then a segmented upload of it */
    for (uint32_t i = 0U; i < MAX_VALUE / 2U; i++) {
        const uint8_t b = image[i];
        image[i] = image[MAX_VALUE - 1U - i];
        image[MAX_VALUE - 1U - i] = b;
    }
    memset(app.steps, 0, sizeof app.steps);
    app.n_steps = 0U;
    REQ(0xC6, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x10, 0x00);
    LAST(0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0);
    for (uint32_t at = 0U; at < MAX_VALUE;) {
        fake_port_clear(&port);
        uint8_t seq = 0U;
        for (; seq < 127U && at < MAX_VALUE; at += 7U) {
            seq++;
            uint8_t seg[8] = {(uint8_t)(seq | (at + 7U >= MAX_VALUE ? 0x80U : 0U))};
            memcpy(&seg[1], &image[at], MAX_VALUE - at < 7U ? MAX_VALUE - at : 7U);
            request(seg);
        }
        LAST(0xA2, seq, 127, 0, 0, 0, 0, 0);
    }
    const uint16_t crc2 = crc16(image, MAX_VALUE);
    REQ((uint8_t)(0xC1U | (unused << 2)), (uint8_t)crc2, (uint8_t)(crc2 >> 8), 0, 0, 0, 0, 0);
    LAST(0xA1, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("BDE", app.steps);
    TEST_ASSERT_EQUAL_MEMORY(image, app.value[0], MAX_VALUE);
    REQ(0x40, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    LAST(0x41, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x10, 0x00);
    n = 0U;
    for (uint8_t t = 0U; n < MAX_VALUE; t ^= 0x10U) {
        fake_port_clear(&port);
        REQ((uint8_t)(0x60U | t), 0, 0, 0, 0, 0, 0, 0);
        const uint8_t *d = last_data();
        const uint32_t k = 7U - ((d[0] >> 1) & 7U);
        memcpy(&got[n], &d[1], k);
        n += k;
    }
    TEST_ASSERT_EQUAL_MEMORY(image, got, MAX_VALUE);
    TEST_ASSERT_TRUE(app.biggest_piece <= CO_SDO_BUF_SIZE);
}

/* What the application refuses, and every way a download ends early: ABORT, the old value kept. */
static void refusals_and_early_ends(void)
{
    REQ(0x21, 0x50, 0x1F, 0x01, 0x01, 0x00, 0x10, 0x00); /* 1 MiB + 1: more than it takes */
    LAST(0x80, 0x50, 0x1F, 0x01, 0x12, 0x00, 0x07, 0x06);
    REQ(0x20, 0x50, 0x1F, 0x01, 0, 0, 0, 0); /* size not indicated, then a client abort */
    LAST(0x60, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    REQ(0x00, 1, 2, 3, 4, 5, 6, 7);
    REQ(0x80, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("BBA", app.steps); /* nothing handed over yet: 7 bytes are in the buffer */
    REQ(0xC2, 0x50, 0x1F, 0x01, 200, 0, 0, 0); /* block, no CRC; then the 1 s timeout */
    uint8_t data[140] = {0};
    send_block(data, sizeof data); /* 20 segments: 140 bytes, two pieces handed over */
    now += CO_SDO_TIMEOUT_US;
    (void)co_node_process(&node, now);
    LAST(0x80, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x04, 0x05);
    TEST_ASSERT_EQUAL_STRING("BBABDA", app.steps);
    REQ(0x21, 0x50, 0x1F, 0x01, 10, 0, 0, 0); /* a new request ends the download in progress */
    REQ(0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("BBABDABA", app.steps);
    REQ(0x21, 0x00, 0x21, 0x00, 10, 0, 0, 0); /* read-only */
    LAST(0x80, 0x00, 0x21, 0x00, 0x02, 0x00, 0x01, 0x06);
    TEST_ASSERT_EQUAL_UINT32(1000U, app.len[0]);
}

/* A small large object goes by expedited transfer, read and written whole through the same calls. */
static void a_short_value_goes_expedited(void)
{
    REQ(0x40, 0x00, 0x21, 0x00, 0, 0, 0, 0);
    LAST(0x47, 0x00, 0x21, 0x00, 0x5A, 0x5B, 0x58, 0);
    REQ(0x2B, 0x50, 0x1F, 0x01, 0xAA, 0xBB, 0, 0);
    LAST(0x60, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING("BDE", app.steps);
    REQ(0x40, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    LAST(0x4B, 0x50, 0x1F, 0x01, 0xAA, 0xBB, 0, 0);
    uint8_t buf[8];
    size_t len = 0U;
    app.len[0] = 0U; /* empty: a size-0 upload */
    TEST_ASSERT_EQUAL_HEX32(0U, co_od_read(&node, 0x1F50, 1, buf, sizeof buf, &len, CO_ORIGIN_LOCAL));
    TEST_ASSERT_EQUAL_UINT32(0U, len);
    REQ(0x40, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    LAST(0x41, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
}

/* Without the application's calls a large object is not accessible. */
static void without_hooks_it_is_refused(void)
{
    start(NULL);
    REQ(0x40, 0x50, 0x1F, 0x01, 0, 0, 0, 0);
    LAST(0x80, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x01, 0x06);
    REQ(0x21, 0x50, 0x1F, 0x01, 10, 0, 0, 0);
    LAST(0x80, 0x50, 0x1F, 0x01, 0x00, 0x00, 0x01, 0x06);
}
#endif

int main(void)
{
    UNITY_BEGIN();
#if CO_CONFIG_LARGE_OBJECTS
    RUN_TEST(a_segmented_upload_reads_the_object_piece_by_piece);
    RUN_TEST(a_segmented_download_hands_the_value_over_in_pieces);
    RUN_TEST(a_block_download_with_crc_of_a_large_object);
    RUN_TEST(a_bad_crc_drops_the_download);
    RUN_TEST(a_block_upload_with_crc_of_a_large_object);
    RUN_TEST(a_mebibyte_each_way);
    RUN_TEST(refusals_and_early_ends);
    RUN_TEST(a_short_value_goes_expedited);
    RUN_TEST(without_hooks_it_is_refused);
#endif
    return UNITY_END();
}
