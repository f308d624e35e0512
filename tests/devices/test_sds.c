/*
 * Eltex SDS device model (devices/sds/sds.c, docs/devices/sds-behaviour.md): behaviour through the core with
 * a fake port and simulated time. Frames go in as they would on the bus; the assertions read frames out
 * (SDO responses, EMCY, TPDO, boot-up) with their timestamps.
 */
#include <string.h>

#include "fake_port.h"
#include "sds/sds.h"
#include "sds_od.h"
#include "unity.h"

#define MS 1000ULL
#define S_ 1000000ULL

typedef struct sds_fixture {
    device_t dev;
    sds_od_values_t values;
    union {
        uint64_t align;
        uint8_t bytes[2048];
    } model;
    fake_port_t port;
    co_time_us_t now;
    uint32_t lines;
    char last_line[512];
} sds_fixture_t;

static sds_fixture_t S;

static void capture(void *ctx, const device_t *dev, const char *line)
{
    (void)ctx;
    (void)dev;
    S.lines++;
    (void)strncpy(S.last_line, line, sizeof S.last_line - 1U);
}

static uint8_t node_id(void) { return co_node_id(&S.dev.node); }

static void process(void) { (void)device_process(&S.dev, S.now); }

/* Advances to t, calling device_process at every deadline on the way (as canopen-emu does). */
static void run_until(co_time_us_t t)
{
    for (;;) {
        const co_time_us_t next = device_process(&S.dev, S.now);
        if (next > t) {
            break;
        }
        TEST_ASSERT_TRUE_MESSAGE(next >= S.now, "deadline in the past");
        if (next == S.now) {
            TEST_ASSERT_TRUE_MESSAGE(device_process(&S.dev, S.now) > S.now, "process() did not advance");
            continue;
        }
        S.now = next;
    }
    S.now = t;
    process();
}

static void advance(co_time_us_t d) { run_until(S.now + d); }

/* Starts a fresh node (fresh NVM) at time 0. */
static void start_variant(uint8_t id, const char *variant)
{
    memset(&S, 0, sizeof S);
    fake_port_init(&S.port, &S.now);
    TEST_ASSERT_TRUE(sds_class.model_size <= sizeof S.model.bytes);
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = id;
    cfg.variant = variant;
    cfg.port = &S.port.port;
    cfg.port_ctx = &S.port;
    cfg.print = capture;
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&S.dev, &sds_class, &S.values, S.model.bytes, &cfg, S.now));
    process();
}

static void start(void) { start_variant(5U, NULL); }

static void power_cycle(void)
{
    TEST_ASSERT_EQUAL_INT(CO_OK, device_power_cycle(&S.dev, S.now));
    process();
}

static void rx(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    device_rx(&S.dev, &f, S.now);
    process();
}

#define RX(id, ...)                                                                                          \
    do {                                                                                                     \
        const uint8_t d_[] = {__VA_ARGS__};                                                                  \
        rx((id), (uint8_t)sizeof d_, d_);                                                                    \
    } while (0)

static void nmt(uint8_t cs) { RX(0x000U, cs, node_id()); }

static const co_frame_t *sdo(const uint8_t req[8])
{
    const uint32_t before = S.port.n_sent;
    const uint8_t id = node_id();
    rx(0x600U + id, 8U, req);
    for (uint32_t i = before; i < S.port.n_sent; i++) {
        if (S.port.sent[i].id == 0x580U + id) {
            return &S.port.sent[i];
        }
    }
    TEST_FAIL_MESSAGE("no SDO response");
    return NULL;
}

static uint32_t abort_of(const co_frame_t *f)
{
    return (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) | ((uint32_t)f->data[6] << 16) |
           ((uint32_t)f->data[7] << 24);
}

/* Expedited download of size 1, 2 or 4 bytes: 0 or the abort code. */
static uint32_t sdo_write(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    const uint8_t cmd = size == 1U ? 0x2FU : (size == 2U ? 0x2BU : 0x23U);
    const uint8_t req[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub, (uint8_t)v, (uint8_t)(v >> 8),
                            (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    const co_frame_t *f = sdo(req);
    if (f->data[0] == 0x80U) {
        return abort_of(f);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60U, f->data[0]);
    return 0U;
}

static uint32_t sdo_read_raw(uint16_t index, uint8_t sub, uint32_t *v, uint8_t *size)
{
    const uint8_t req[8] = {0x40U, (uint8_t)index, (uint8_t)(index >> 8), sub, 0U, 0U, 0U, 0U};
    const co_frame_t *f = sdo(req);
    if (f->data[0] == 0x80U) {
        return abort_of(f);
    }
    *size = (uint8_t)(4U - ((f->data[0] >> 2) & 3U));
    *v = abort_of(f);
    return 0U;
}

/* Reads a value that must be readable; sign-extends INTEGER16 answers. */
static int32_t rd(uint16_t index, uint8_t sub)
{
    uint32_t v = 0U;
    uint8_t size = 0U;
    const uint32_t r = sdo_read_raw(index, sub, &v, &size);
    TEST_ASSERT_EQUAL_HEX32_MESSAGE(0U, r, "SDO read aborted");
    if (size == 2U && (index == 0x6401U || (index == 0x2001U && sub != 1U && sub != 5U))) {
        return (int32_t)(int16_t)(uint16_t)v;
    }
    return (int32_t)v;
}

static uint32_t rd_abort(uint16_t index, uint8_t sub)
{
    uint32_t v;
    uint8_t size;
    return sdo_read_raw(index, sub, &v, &size);
}

static device_cmd_result_t cmd(const char *line)
{
    char buf[128];
    const char *argv[8];
    int argc = 0;
    (void)strncpy(buf, line, sizeof buf - 1U);
    buf[sizeof buf - 1U] = '\0';
    for (char *p = strtok(buf, " "); p != NULL && argc < 8; p = strtok(NULL, " ")) {
        argv[argc++] = p;
    }
    const device_cmd_result_t r = device_command(&S.dev, argc, argv, S.now, NULL);
    process();
    return r;
}

static uint32_t count_since(uint32_t id, uint32_t since)
{
    uint32_t n = 0U;
    for (uint32_t i = since; i < S.port.n_sent; i++) {
        n += S.port.sent[i].id == id ? 1U : 0U;
    }
    return n;
}

/* Index of the first frame with this id at or after `since`, or -1. */
static int find_since(uint32_t id, uint32_t since)
{
    for (uint32_t i = since; i < S.port.n_sent; i++) {
        if (S.port.sent[i].id == id) {
            return (int)i;
        }
    }
    return -1;
}

#define EXPECT_FRAME_SINCE(since, id_, ...)                                                                  \
    do {                                                                                                     \
        const uint8_t e_[] = {__VA_ARGS__};                                                                  \
        const int i_ = find_since((id_), (since));                                                           \
        TEST_ASSERT_TRUE_MESSAGE(i_ >= 0, "expected frame missing");                                         \
        TEST_ASSERT_EQUAL_UINT8(sizeof e_, S.port.sent[i_].len);                                             \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, S.port.sent[i_].data, sizeof e_);                                   \
    } while (0)

static uint32_t emcy_id(void) { return 0x080U + node_id(); }

static void release(void) { TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x6200U, 1U, 0x0FU, 1U)); }
static bool hv_bit(void) { return (rd(0x6000U, 1U) & 0x01) != 0; }

static void save(void) { TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1010U, 1U, 0x65766173UL, 4U)); }
static void restore(void) { TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1011U, 1U, 0x64616F6CUL, 4U)); }

/* HV on and kept on by a refresh every 9 s until `until`. */
static void hv_on_until(co_time_us_t until)
{
    release();
    while (S.now + 9U * S_ < until) {
        advance(9U * S_);
        release();
    }
    run_until(until);
}

void setUp(void) { start(); }
void tearDown(void) {}

/* ---- HV release 0x6200:01 --------------------------------------------------------------------------- */

static void release_drops_at_exactly_10_s_and_values_decay(void)
{
    run_until(1050U * MS);
    const uint32_t since = S.port.n_sent;
    release(); /* t0 = 1.05 s */
    TEST_ASSERT_TRUE(hv_bit());
    run_until(7U * S_); /* settled after ~4.7 s */
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x2001U, 1U));
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x2001U, 5U));
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x6401U, 1U));
    TEST_ASSERT_EQUAL_INT32(50, rd(0x2001U, 0x0AU));
    run_until(11050U * MS - 1U);
    TEST_ASSERT_TRUE(hv_bit());
    run_until(11050U * MS);
    TEST_ASSERT_FALSE(hv_bit());
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2001U, 0x0AU));       /* duty cycle: at once */
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x2001U, 1U));      /* voltages: first order, from the next tick */
    run_until(11100U * MS);
    TEST_ASSERT_EQUAL_INT32(4912, rd(0x2001U, 1U));      /* 6000 * exp(-0.1 s / 0.5 s), Q8 arithmetic */
    TEST_ASSERT_EQUAL_INT32(4912, rd(0x2001U, 5U));
    const int32_t i1 = rd(0x2001U, 2U);
    TEST_ASSERT_TRUE(i1 > 0 && i1 < 20);
    run_until(17U * S_);
    static const uint8_t subs[] = {1U, 2U, 3U, 4U, 5U, 6U, 7U, 8U};
    for (size_t i = 0U; i < sizeof subs; i++) {
        TEST_ASSERT_EQUAL_INT32(0, rd(0x2001U, subs[i]));
    }
    for (uint8_t s = 1U; s <= 3U; s++) {
        TEST_ASSERT_EQUAL_INT32(0, rd(0x6401U, s));
    }
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6000U, 2U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6000U, 3U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6000U, 4U));
    TEST_ASSERT_EQUAL_INT32(0x00, rd(0x6000U, 1U));
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(emcy_id(), since)); /* a timeout is no error */
}

static void release_refreshed_every_9_s_stays_on_for_a_minute(void)
{
    const co_time_us_t t0 = S.now;
    release();
    for (int k = 1; k <= 7; k++) {
        run_until(t0 + (co_time_us_t)k * 9U * S_ - 1U);
        TEST_ASSERT_TRUE(hv_bit());
        run_until(t0 + (co_time_us_t)k * 9U * S_);
        release();
    }
    const co_time_us_t last = S.now; /* 63 s */
    run_until(last + 10U * S_ - 1U);
    TEST_ASSERT_TRUE(hv_bit());
    run_until(last + 10U * S_);
    TEST_ASSERT_FALSE(hv_bit());
}

static void release_zero_switches_off_at_once_other_values_refused(void)
{
    release();
    advance(6U * S_);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x6200U, 1U, 0x05U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x6200U, 1U, 0xFFU, 1U));
    TEST_ASSERT_TRUE(hv_bit());
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY, rd_abort(0x6200U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x6200U, 1U, 0x00U, 1U));
    TEST_ASSERT_FALSE(hv_bit());
    advance(3U * S_); /* still off: 0x00 is no release with a timeout */
    TEST_ASSERT_FALSE(hv_bit());
    TEST_ASSERT_TRUE(rd(0x2001U, 1U) < 6000);
}

static void release_by_rpdo1_only_in_operational(void)
{
    const uint32_t id = 0x200U + node_id();
    RX(id, 0x0FU); /* Pre-operational: RPDOs are not evaluated */
    TEST_ASSERT_FALSE(hv_bit());
    nmt(0x01U);
    const co_time_us_t t_op = S.now;
    const uint32_t since = S.port.n_sent;
    RX(id, 0x0FU);
    TEST_ASSERT_TRUE(hv_bit());
    /* no change-of-state TPDO (CO_OPT_TPDO_NO_COS): the status change goes out at the next grid point */
    run_until(t_op + 500U * MS - 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x180U + node_id(), since));
    run_until(t_op + 500U * MS);
    const int t = find_since(0x180U + node_id(), since);
    TEST_ASSERT_TRUE(t >= 0);
    TEST_ASSERT_EQUAL_UINT64(t_op + 500U * MS, S.port.sent_at[t]);
    TEST_ASSERT_EQUAL_HEX8(0x01U, S.port.sent[t].data[0]);
    const uint32_t before = S.port.n_sent;
    RX(id, 0x05U); /* refused by the device: dropped silently, HV stays on */
    TEST_ASSERT_EQUAL_UINT32(before, S.port.n_sent);
    TEST_ASSERT_TRUE(hv_bit());
    advance(9U * S_);
    RX(id, 0x0FU); /* refresh by RPDO */
    advance(9U * S_);
    TEST_ASSERT_TRUE(hv_bit());
    RX(id, 0x00U);
    TEST_ASSERT_FALSE(hv_bit());
}

/* ---- Values and their consistency ------------------------------------------------------------------ */

static void balance_moves_status_balance_and_both_voltages(void)
{
    hv_on_until(6U * S_);
    TEST_ASSERT_EQUAL_INT32(50, rd(0x6000U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 4U, 40U, 1U));
    hv_on_until(S.now + 6U * S_);
    TEST_ASSERT_EQUAL_INT32(4000, rd(0x2001U, 1U)); /* positive reduced: 6000 * 40 / 60 */
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x2001U, 5U));
    TEST_ASSERT_EQUAL_INT32(40, rd(0x6000U, 2U));
    TEST_ASSERT_EQUAL_INT32(5099, rd(0x6401U, 1U)); /* sqrt((4000^2 + 6000^2) / 2) */
    TEST_ASSERT_EQUAL_INT32(10, rd(0x2001U, 2U));   /* 5 uA/kV * (4000 - 2000) V */
    TEST_ASSERT_EQUAL_INT32(-20, rd(0x2001U, 6U));
    TEST_ASSERT_EQUAL_INT32(-10, rd(0x6401U, 3U));  /* 10 + 2 - 20 - 2: more negative ions */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 50")); /* 3750 pS: leakage 15 / -23 uA */
    TEST_ASSERT_EQUAL_INT32(15, rd(0x2001U, 3U));
    TEST_ASSERT_EQUAL_INT32(-23, rd(0x2001U, 7U));
    TEST_ASSERT_EQUAL_INT32(-18, rd(0x6401U, 3U)); /* DC = active + leakage of both polarities */
    TEST_ASSERT_EQUAL_INT32(50, rd(0x6000U, 4U));
    TEST_ASSERT_EQUAL_INT32(29, rd(0x6000U, 3U));  /* negative side (20 + 23) / 150 uA */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 4U, 60U, 1U));
    hv_on_until(S.now + 6U * S_);
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x2001U, 1U));
    TEST_ASSERT_EQUAL_INT32(4000, rd(0x2001U, 5U));
    TEST_ASSERT_EQUAL_INT32(60, rd(0x6000U, 2U));
    TEST_ASSERT_EQUAL_INT32(18, rd(0x6401U, 3U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 4U, 34U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 4U, 66U, 1U));
}

static void readings_are_consistent_with_load_and_pollution(void)
{
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("load 40"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 50"));
    hv_on_until(6U * S_);
    const int32_t vp = rd(0x2001U, 1U), iap = rd(0x2001U, 2U), ilp = rd(0x2001U, 3U), ipp = rd(0x2001U, 4U);
    const int32_t vn = rd(0x2001U, 5U), ian = rd(0x2001U, 6U), iln = rd(0x2001U, 7U), ipn = rd(0x2001U, 8U);
    TEST_ASSERT_EQUAL_INT32(6000, vp);
    TEST_ASSERT_EQUAL_INT32(6000, vn);
    TEST_ASSERT_EQUAL_INT32(20, iap);  /* emission only: the positive web draws negative ions */
    TEST_ASSERT_EQUAL_INT32(-60, ian); /* emission 20 + web 40 */
    TEST_ASSERT_EQUAL_INT32(23, ilp);  /* 6000 V * 3750 pS = 22.5 uA */
    TEST_ASSERT_EQUAL_INT32(-23, iln);
    TEST_ASSERT_EQUAL_INT32(0, ipp);
    TEST_ASSERT_EQUAL_INT32(-10, ipn); /* a quarter of the web current */
    TEST_ASSERT_EQUAL_INT32(6000, rd(0x6401U, 1U));
    TEST_ASSERT_EQUAL_INT32(45, rd(0x6401U, 2U));                    /* sqrt((20^2 + 60^2) / 2) */
    TEST_ASSERT_EQUAL_INT32(iap + ilp + ian + iln, rd(0x6401U, 3U)); /* DC = -40: the web's charge */
    TEST_ASSERT_EQUAL_INT32(-40, rd(0x6401U, 3U));
    TEST_ASSERT_EQUAL_INT32(55, rd(0x6000U, 3U)); /* (60 + 23) / 150 uA */
    TEST_ASSERT_EQUAL_INT32(50, rd(0x6000U, 4U));
    TEST_ASSERT_EQUAL_INT32(50, rd(0x6000U, 2U));
    TEST_ASSERT_EQUAL_INT32(15, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U));
    /* the pollution reading is relative to the factor: a factor of 100 makes the same bar 38 % dirty */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 2U, 100U, 1U));
    advance(200U * MS);
    TEST_ASSERT_EQUAL_INT32(38, rd(0x6000U, 4U)); /* 3750 pS / (100 * 100 pS) */
    /* TPDO sampling sees the same values as SDO */
    nmt(0x01U);
    const int t1 = find_since(0x185U, 0U), t2 = find_since(0x285U, 0U);
    TEST_ASSERT_TRUE(t1 >= 0 && t2 >= 0);
    const uint8_t tp1[5] = {0x01U, 50U, 55U, 38U, 15U};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(tp1, S.port.sent[t1].data, 5);
    const uint8_t tp2[6] = {0x70U, 0x17U, 45U, 0U, 0xD8U, 0xFFU};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(tp2, S.port.sent[t2].data, 6);
}

/* ---- Errors and warnings -------------------------------------------------------------------------- */

static void pollution_warning_at_80_error_at_100_and_clearing(void)
{
    hv_on_until(6U * S_);
    uint32_t since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 79"));
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x85U, since));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 80"));
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x85U, since));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x23, 0x03, 0x05, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x05U, (uint8_t)rd(0x6000U, 1U)); /* HV + warning */
    TEST_ASSERT_EQUAL_HEX8(0x03U, (uint8_t)rd(0x1001U, 0U));
    TEST_ASSERT_EQUAL_HEX32(0x01052300UL, (uint32_t)rd(0x1003U, 1U));
    TEST_ASSERT_EQUAL_INT32(80, rd(0x6000U, 4U));

    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 100"));
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x85U, since));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x23, 0x03, 0x01, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x06U, (uint8_t)rd(0x6000U, 1U)); /* the pollution error switched HV off */

    /* the internal check: the bar is still dirty */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, sdo_write(0x2003U, 2U, 0x01U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, sdo_write(0x2003U, 1U, 0x03U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 10"));
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 2U, 0x01U, 1U));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x00, 0x03, 0x05, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x02U, (uint8_t)rd(0x6000U, 1U));
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 1U, 0x03U, 1U));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x00, 0x00, 0x01, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00U, (uint8_t)rd(0x6000U, 1U));
    TEST_ASSERT_EQUAL_HEX8(0x00U, (uint8_t)rd(0x1001U, 0U));
    /* HV comes back only with a new release */
    advance(1U * S_);
    TEST_ASSERT_FALSE(hv_bit());
    release();
    TEST_ASSERT_TRUE(hv_bit());
}

static void clearing_inactive_or_unknown_codes_is_refused(void)
{
    const uint32_t since = S.port.n_sent;
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, sdo_write(0x2003U, 2U, 0x01U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, sdo_write(0x2003U, 1U, 0x03U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x2003U, 1U, 0x20U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x2003U, 2U, 0x60U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2003U, 1U, 0x00U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2003U, 1U, 0x51U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2003U, 2U, 0x61U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY, rd_abort(0x2003U, 1U));
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x85U, since));
    /* the command refuses in the same way */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("clear-warning 1"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("error 0x30"));
}

static void injected_errors_switch_hv_off_and_block_the_release(void)
{
    hv_on_until(6U * S_);
    uint32_t since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 1"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x20, 0x23, 0x03, 0x01, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x02U, (uint8_t)rd(0x6000U, 1U));
    release(); /* accepted, but no HV while a blocking error is active */
    TEST_ASSERT_FALSE(hv_bit());
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 1U, 0x01U, 1U)); /* a momentary event: clearable at once */
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_FALSE(hv_bit());
    release();
    TEST_ASSERT_TRUE(hv_bit());
    /* a non-blocking error: HV stays on */
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 8"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x63, 0x01, 0x01, 0x08, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x03U, (uint8_t)rd(0x6000U, 1U));
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("clear-error 8"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x00, 0x00, 0x01, 0x08, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x01U, (uint8_t)rd(0x6000U, 1U));
}

static void supply_temperature_and_overload_conditions(void)
{
    uint32_t since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 21.5"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x31, 0x05, 0x05, 0x03, 0x00, 0x00, 0x00);
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 19.1"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x20, 0x31, 0x05, 0x01, 0x04, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_DEVICE_STATE, sdo_write(0x2003U, 1U, 0x04U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24"));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 1U, 0x04U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 2U, 0x03U, 1U));
    TEST_ASSERT_EQUAL_HEX8(0x00U, (uint8_t)rd(0x1001U, 0U));

    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 65"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x42, 0x09, 0x05, 0x04, 0x00, 0x00, 0x00);
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 70"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x10, 0x42, 0x09, 0x01, 0x06, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 30"));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 1U, 0x06U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2003U, 2U, 0x04U, 1U));

    /* a heavily charged web: capacity warning at 90 %, overload error at 100 % (HV off) */
    hv_on_until(S.now + 6U * S_);
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("load 115")); /* negative side: 20 + 115 + 2 = 137 uA = 91 % */
    TEST_ASSERT_EQUAL_INT32(91, rd(0x6000U, 3U));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x10, 0x23, 0x03, 0x05, 0x02, 0x00, 0x00, 0x00);
    TEST_ASSERT_TRUE(hv_bit());
    since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("load 130"));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x10, 0x23, 0x03, 0x01, 0x02, 0x00, 0x00, 0x00);
    TEST_ASSERT_FALSE(hv_bit());
}

static void resets_forget_momentary_faults_and_report_persisting_ones_again(void)
{
    hv_on_until(6U * S_);
    uint32_t since = S.port.n_sent;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 120"));
    /* both thresholds crossed in one step: the warning first, then the error (E8, D18) */
    TEST_ASSERT_EQUAL_UINT32(2U, count_since(0x85U, since));
    const int w = find_since(0x85U, since);
    EXPECT_FRAME_SINCE((uint32_t)w, 0x85U, 0x00, 0x23, 0x03, 0x05, 0x01, 0x00, 0x00, 0x00);
    EXPECT_FRAME_SINCE((uint32_t)w + 1U, 0x85U, 0x00, 0x23, 0x03, 0x01, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 7"));
    TEST_ASSERT_EQUAL_HEX8(0x06U, (uint8_t)rd(0x6000U, 1U));
    /* reset communication: the core forgets its errors, the device reports all of its active ones again */
    since = S.port.n_sent;
    nmt(0x82U);
    TEST_ASSERT_EQUAL_INT(find_since(0x705U, since) + 1, find_since(0x85U, since)); /* after the boot-up */
    TEST_ASSERT_EQUAL_UINT32(3U, count_since(0x85U, since)); /* 2 errors + 1 warning */
    /* reset node: the momentary generator fault is gone, the pollution persists (judged at full HV: the
     * measured voltages have long decayed, so only the internal check can tell, E10) */
    advance(6U * S_);
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6000U, 4U));
    since = S.port.n_sent;
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT32(2U, count_since(0x85U, since));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x23, 0x03, 0x01, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x06U, (uint8_t)rd(0x6000U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, sdo_write(0x2003U, 1U, 0x07U, 1U));
}

static void power_cycle_keeps_the_inputs_and_restarts_the_bar(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 0U, 2U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("pollution 50"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("load 40"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 21.5")); /* warning 0x03: caused by the environment */
    hv_on_until(6U * S_);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 8")); /* parameter memory error: not caused by it */
    TEST_ASSERT_EQUAL_HEX8(0x07U, (uint8_t)rd(0x6000U, 1U));
    release(); /* a release that would run until 16 s */
    const uint32_t since = S.port.n_sent;
    power_cycle();
    /* the running state restarts: no release, HV off, voltages 0, error 0x08 forgotten ... */
    TEST_ASSERT_EQUAL_HEX8(0x04U, (uint8_t)rd(0x6000U, 1U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2001U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, sdo_write(0x2003U, 1U, 0x08U, 1U));
    /* ... the supply is still 21.5 V: the warning is raised again, after the boot-up */
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x85U, since));
    TEST_ASSERT_TRUE(find_since(0x705U, since) < find_since(0x85U, since));
    EXPECT_FRAME_SINCE(since, 0x85U, 0x00, 0x31, 0x05, 0x05, 0x03, 0x00, 0x00, 0x00);
    advance(12U * S_);
    TEST_ASSERT_FALSE(hv_bit());
    /* the pollution and the web are still there: the same readings as before the power cycle */
    hv_on_until(S.now + 6U * S_);
    TEST_ASSERT_EQUAL_INT32(50, rd(0x6000U, 4U));
    TEST_ASSERT_EQUAL_INT32(-60, rd(0x2001U, 6U));
    TEST_ASSERT_EQUAL_INT32(-40, rd(0x6401U, 3U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("model"));
    TEST_ASSERT_NOT_NULL(strstr(S.last_line, "pollution 50 %"));
}

/* ---- Variants --------------------------------------------------------------------------------------- */

static void variant_n_working_distance_10_to_15(void)
{
    start_variant(5U, "N");
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 8U, 16U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 8U, 9U, 1U));
    TEST_ASSERT_EQUAL_INT32(15, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 8U, 10U, 1U));
    TEST_ASSERT_EQUAL_INT32(10, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY, rd_abort(0x2002U, 8U));
    hv_on_until(6U * S_);
    TEST_ASSERT_EQUAL_INT32(5000, rd(0x2001U, 1U)); /* 3000 V + 200 V/cm * 10 cm */
    /* RPDO-refused style check through the command line: the same range applies locally */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:08 20"));
}

static void variant_e_working_distance_15_to_30(void)
{
    start_variant(5U, "E");
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 8U, 16U, 1U));
    TEST_ASSERT_EQUAL_INT32(16, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 8U, 14U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 8U, 31U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 8U, 30U, 1U));
    hv_on_until(6U * S_);
    TEST_ASSERT_EQUAL_INT32(9000, rd(0x2001U, 1U));
    TEST_ASSERT_EQUAL_INT32(9000, rd(0x2001U, 5U));
}

/* D4: the parameters an SDS/E saved, loaded by an SDS/N: the working distance 25 is out of the N's range, which
 * a write of it would be refused for (0x06090031), so the stored parameters are refused as a whole and reported
 * (CO_NVM_REFUSED): the N starts from its defaults, not with a clamped or foreign value. The same file on the E
 * again loads as saved. */
static void variant_change_with_the_same_nvm_refuses_the_stored_distance(void)
{
    start_variant(5U, "E");
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 8U, 25U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 9U, 44U, 1U));
    save();
    device_cfg_t cfg = S.dev.cfg; /* the same port and NVM, now as an SDS/N */
    cfg.variant = "N";
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&S.dev, &sds_class, &S.values, S.model.bytes, &cfg, S.now));
    process();
    TEST_ASSERT_EQUAL_INT(CO_NVM_REFUSED, S.dev.node.nvm_status);
    TEST_ASSERT_EQUAL_INT32(15, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U)); /* the N's default, not the E's stored 44 */
    cfg.variant = "E";
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&S.dev, &sds_class, &S.values, S.model.bytes, &cfg, S.now));
    process();
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, S.dev.node.nvm_status);
    TEST_ASSERT_EQUAL_INT32(25, rd(0x6000U, 5U));
    TEST_ASSERT_EQUAL_INT32(44, rd(0x2001U, 9U));
}

static void variant_pulse_frequency_defaults_48_and_40(void)
{
    start_variant(5U, "N");
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U));
    start_variant(5U, NULL);
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U)); /* N is the default variant */
    start_variant(5U, "E");
    TEST_ASSERT_EQUAL_INT32(40, rd(0x2001U, 9U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_WRITE_ONLY, rd_abort(0x2002U, 9U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 9U, 29U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 9U, 51U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 9U, 45U, 1U));
    TEST_ASSERT_EQUAL_INT32(45, rd(0x2001U, 9U));
    power_cycle(); /* not saved: the variant default returns */
    TEST_ASSERT_EQUAL_INT32(40, rd(0x2001U, 9U));
    /* a stored value wins over the variant default, also when it equals the EDS (SDS/N) default */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 9U, 48U, 1U));
    save();
    power_cycle();
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U));
    nmt(0x81U);
    TEST_ASSERT_EQUAL_INT32(48, rd(0x2001U, 9U));
    /* restore defaults: the variant's default again */
    restore();
    nmt(0x81U);
    TEST_ASSERT_EQUAL_INT32(40, rd(0x2001U, 9U));
}

/* ---- Cyclic TPDOs --------------------------------------------------------------------------------- */

static void tpdo1_tpdo2_every_transfer_time_only_in_operational(void)
{
    advance(2U * S_);
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x185U, 0U) + count_since(0x285U, 0U));
    run_until(2345U * MS);
    const co_time_us_t t_op = S.now;
    const uint32_t since = S.port.n_sent;
    nmt(0x01U);
    run_until(t_op + 5U * S_);
    /* at entry (the core) and then every 500 ms on the grid */
    TEST_ASSERT_EQUAL_UINT32(11U, count_since(0x185U, since));
    TEST_ASSERT_EQUAL_UINT32(11U, count_since(0x285U, since));
    uint32_t k = 0U;
    for (uint32_t i = since; i < S.port.n_sent; i++) {
        if (S.port.sent[i].id == 0x185U) {
            TEST_ASSERT_EQUAL_UINT64(t_op + k * 500U * MS, S.port.sent_at[i]);
            const uint8_t tp1[5] = {0x00U, 0U, 0U, 0U, 15U}; /* HV off: status 0, balance/capacity/pollution 0 */
            TEST_ASSERT_EQUAL_HEX8_ARRAY(tp1, S.port.sent[i].data, 5);
            k++;
        }
        if (S.port.sent[i].id == 0x285U) {
            TEST_ASSERT_EQUAL_UINT8(6U, S.port.sent[i].len);
        }
    }
    /* a new period starts at the write */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 1U, 200U, 2U));
    const co_time_us_t tw = S.now;
    const uint32_t since2 = S.port.n_sent;
    run_until(tw + 1U * S_);
    TEST_ASSERT_EQUAL_UINT32(5U, count_since(0x185U, since2));
    TEST_ASSERT_EQUAL_UINT64(tw + 200U * MS, S.port.sent_at[find_since(0x185U, since2)]);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 1U, 99U, 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 1U, 60001U, 2U));
    /* Stopped and Pre-operational: none */
    nmt(0x02U);
    const uint32_t since3 = S.port.n_sent;
    advance(3U * S_);
    nmt(0x80U);
    advance(3U * S_);
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x185U, since3) + count_since(0x285U, since3));
}

static void tpdo_grid_does_not_drift_with_late_calls(void)
{
    const co_time_us_t t_op = S.now;
    const uint32_t since = S.port.n_sent;
    nmt(0x01U);
    /* a runner that only wakes every 70 ms: each transmission is late, the grid is not */
    for (co_time_us_t t = t_op + 70U * MS; t <= t_op + 10U * S_; t += 70U * MS) {
        S.now = t;
        process();
    }
    uint32_t k = 0U;
    for (uint32_t i = since; i < S.port.n_sent; i++) {
        if (S.port.sent[i].id == 0x285U) {
            const co_time_us_t grid = t_op + k * 500U * MS;
            TEST_ASSERT_TRUE(S.port.sent_at[i] >= grid);
            TEST_ASSERT_TRUE(S.port.sent_at[i] < grid + 70U * MS);
            k++;
        }
    }
    TEST_ASSERT_EQUAL_UINT32(20U, k); /* at entry, then grid points 0.5 s ... 9.5 s */
}

static void steady_hv_sends_only_the_cyclic_tpdos_with_consistent_values(void)
{
    nmt(0x01U);
    hv_on_until(8U * S_);
    release(); /* valid until 18 s */
    const uint32_t since = S.port.n_sent;
    const co_time_us_t t = S.now;
    run_until(t + 5U * S_); /* grid points 8.5 s ... 13 s, nothing in between */
    TEST_ASSERT_EQUAL_UINT32(10U, count_since(0x185U, since));
    TEST_ASSERT_EQUAL_UINT32(10U, count_since(0x285U, since));
    const int i1 = find_since(0x185U, since), i2 = find_since(0x285U, since);
    const uint8_t tp1[5] = {0x01U, 50U, 15U, 5U, 15U};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(tp1, S.port.sent[i1].data, 5);
    const uint8_t tp2[6] = {0x70U, 0x17U, 20U, 0U, 0U, 0U}; /* 6000 V, 20 uA, DC 0 */
    TEST_ASSERT_EQUAL_HEX8_ARRAY(tp2, S.port.sent[i2].data, 6);
    TEST_ASSERT_EQUAL_INT32(rd(0x6000U, 3U), S.port.sent[i1].data[2]);
}

/* ---- Counters ------------------------------------------------------------------------------------- */

static void counters_advance_and_survive_a_power_cycle(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 0U, 2U)); /* quiet bus for the long run */
    hv_on_until(150U * S_);
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x6200U, 1U, 0x00U, 1U)); /* HV for exactly 150 s */
    run_until(90U * 60U * S_ + 30U * S_);                           /* 1 h 30 min 30 s */
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 1U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 2U));
    TEST_ASSERT_EQUAL_INT32(1, rd(0x2000U, 3U));
    TEST_ASSERT_EQUAL_INT32(30, rd(0x2000U, 4U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 7U));
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2000U, 8U));
    TEST_ASSERT_TRUE(S.port.nvm[CO_NVM_DEVICE].commits >= 90U); /* at least every emulated minute */
    power_cycle(); /* the 25 s since the last save (node 5: 5 s past each minute) are lost, as on a real device */
    TEST_ASSERT_EQUAL_INT32(1, rd(0x2000U, 3U));
    TEST_ASSERT_EQUAL_INT32(30, rd(0x2000U, 4U));
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2000U, 8U));
    advance(55U * S_ - 1U); /* counting on from the stored 1 h 30 min 5 s */
    TEST_ASSERT_EQUAL_INT32(30, rd(0x2000U, 4U));
    advance(1U);
    TEST_ASSERT_EQUAL_INT32(31, rd(0x2000U, 4U));
    TEST_ASSERT_EQUAL_INT32(31, rd(0x2000U, 4U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_READ_ONLY, sdo_write(0x2000U, 4U, 0U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2000:04 5"));
}

static void a_30_day_gap_is_caught_up_at_once(void)
{
    /* found by fuzzing: every missed 100 ms tick was simulated (26 million for 30 days) */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 0U, 2U));
    release(); /* HV on, released for 10 s */
    advance(2U * S_);
    TEST_ASSERT_TRUE(hv_bit());
    S.now += 30ULL * 24U * 3600U * S_; /* the host slept: one call covers the gap */
    (void)device_process(&S.dev, S.now);
    TEST_ASSERT_FALSE(hv_bit());                    /* the release timed out inside the gap */
    TEST_ASSERT_EQUAL_INT32(30, rd(0x2000U, 2U));   /* operating days */
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 6U));    /* HV days: only the 10 s */
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 7U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6401U, 1U));    /* the voltage has settled at 0 */
}

static void counters_years_days_from_stored_seconds(void)
{
    /* the device's own blob (docs: "SDSM" | 2 | flags | 0 0 | op s | HV s | CRC-32 of bytes 0..15) */
    uint8_t b[20];
    memset(b, 0, sizeof b);
    memcpy(b, "SDSM", 4U);
    b[4] = 2U;
    const uint32_t op = (565U * 1440U + 2U * 60U + 3U) * 60U - 1U; /* 1 y 200 d 2 h 2 min 59 s */
    const uint32_t hv = 59U * 60U + 59U;
    for (unsigned i = 0U; i < 4U; i++) {
        b[8 + i] = (uint8_t)(op >> (8U * i));
        b[12 + i] = (uint8_t)(hv >> (8U * i));
    }
    uint32_t crc = 0xFFFFFFFFUL;
    for (unsigned i = 0U; i < 16U; i++) {
        crc ^= b[i];
        for (unsigned k = 0U; k < 8U; k++) {
            crc = (crc >> 1) ^ (0xEDB88320UL & (0U - (crc & 1U)));
        }
    }
    crc = ~crc;
    for (unsigned i = 0U; i < 4U; i++) {
        b[16 + i] = (uint8_t)(crc >> (8U * i));
    }
    memcpy(S.port.nvm[CO_NVM_DEVICE].stored, b, sizeof b);
    S.port.nvm[CO_NVM_DEVICE].stored_len = sizeof b;
    power_cycle();
    TEST_ASSERT_EQUAL_INT32(1, rd(0x2000U, 1U));
    TEST_ASSERT_EQUAL_INT32(200, rd(0x2000U, 2U));
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2000U, 3U));
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2000U, 4U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 7U));
    TEST_ASSERT_EQUAL_INT32(59, rd(0x2000U, 8U));
    advance(1U * S_);
    TEST_ASSERT_EQUAL_INT32(3, rd(0x2000U, 4U));
    release();
    advance(1U * S_);
    TEST_ASSERT_EQUAL_INT32(1, rd(0x2000U, 7U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 8U));
    /* a damaged blob counts as nothing stored */
    S.port.nvm[CO_NVM_DEVICE].stored[9] ^= 0x01U;
    power_cycle();
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 1U));
    TEST_ASSERT_EQUAL_INT32(0, rd(0x2000U, 4U));
}

/* ---- Node-ID, bit timing, storage -------------------------------------------------------------------- */

static void node_id_from_2002_06_only_after_save_and_reset(void)
{
    TEST_ASSERT_EQUAL_INT32(5, rd(0x2002U, 6U)); /* reads the active node-ID */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 6U, 10U, 1U));
    TEST_ASSERT_EQUAL_INT32(10, rd(0x2002U, 6U));
    uint32_t since = S.port.n_sent;
    nmt(0x81U); /* written, not saved: no effect */
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x705U, since));
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    TEST_ASSERT_EQUAL_INT32(5, rd(0x2002U, 6U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 6U, 10U, 1U));
    nmt(0x82U);
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    TEST_ASSERT_EQUAL_INT32(5, rd(0x2002U, 6U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 6U, 10U, 1U));
    save();
    TEST_ASSERT_EQUAL_UINT8(5U, node_id()); /* saving alone changes nothing */
    advance(1U * S_);
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    since = S.port.n_sent;
    nmt(0x82U); /* any NMT reset applies it (0x81 in the LSS test) */
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x70AU, since));
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x705U, since));
    TEST_ASSERT_EQUAL_INT32(10, rd(0x2002U, 6U)); /* SDO on 0x60A now */
    since = S.port.n_sent;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x70AU, since));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x2002U, 6U, 0U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 6U, 128U, 1U));
    /* 0x1011 restores the rest but keeps the node-ID (and bit timing) */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 2U, 50U, 1U));
    save();
    restore();
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    TEST_ASSERT_EQUAL_INT32(75, rd(0x2002U, 2U));
}

static void lss_store_and_2002_06_stay_consistent_newest_wins(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 6U, 10U, 1U));
    save();
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    /* LSS: configuration state, configure node-ID 20, store, back to waiting */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x11, 20, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x17, 0, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    uint32_t since = S.port.n_sent;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(20U, node_id()); /* the LSS store is newer than the saved 0x2002:06 */
    TEST_ASSERT_EQUAL_UINT32(1U, count_since(0x714U, since));
    TEST_ASSERT_EQUAL_INT32(20, rd(0x2002U, 6U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(20U, node_id());
    /* a later save of 0x2002:06 wins again */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 6U, 30U, 1U));
    save();
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT8(30U, node_id());
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(30U, node_id());
    /* LSS configure without store: active after the reset (CiA 305), gone after a power cycle */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x11, 40, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT8(40U, node_id());
    TEST_ASSERT_EQUAL_INT32(40, rd(0x2002U, 6U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(30U, node_id());
}

static void bit_timing_from_2002_07_after_save_and_reset(void)
{
    TEST_ASSERT_EQUAL_INT32(4, rd(0x2002U, 7U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x2002U, 7U, 5U, 1U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x2002U, 7U, 9U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 7U, 2U, 1U));
    const uint32_t calls = S.port.bit_rate_calls;
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT32(calls, S.port.bit_rate_calls); /* not saved */
    TEST_ASSERT_EQUAL_INT32(4, rd(0x2002U, 7U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2002U, 7U, 2U, 1U));
    save();
    nmt(0x81U);
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, S.port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(500U, S.port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2002U, 7U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(500U, S.port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_INT32(2, rd(0x2002U, 7U));
}

static void heartbeat_time_rules(void)
{
    TEST_ASSERT_EQUAL_INT32(5000, rd(0x1017U, 0U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x1017U, 0U, 1U, 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_LOW, sdo_write(0x1017U, 0U, 99U, 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x1017U, 0U, 150U, 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, sdo_write(0x1017U, 0U, 1001U, 2U));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, sdo_write(0x1017U, 0U, 60100U, 2U));
    TEST_ASSERT_EQUAL_INT32(5000, rd(0x1017U, 0U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 60000U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 100U, 2U));
    const uint32_t since = S.port.n_sent;
    advance(1U * S_);
    TEST_ASSERT_EQUAL_UINT32(10U, count_since(0x705U, since));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 0U, 2U));
    const uint32_t since2 = S.port.n_sent;
    advance(2U * S_);
    TEST_ASSERT_EQUAL_UINT32(0U, count_since(0x705U, since2));
}

/* ---- Commands ----------------------------------------------------------------------------------------- */

static void control_commands(void)
{
    TEST_ASSERT_NOT_NULL(sds_class.commands_help);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("pollution"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("pollution abc"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("supply 12,5"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("temperature 200"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_UNKNOWN, cmd("no-such-command"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("conductance 7400"));
    hv_on_until(6U * S_);
    TEST_ASSERT_EQUAL_INT32(99, rd(0x6000U, 4U)); /* 7400 pS = 98.7 % of factor 75 */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("conductance 7500"));
    TEST_ASSERT_EQUAL_INT32(100, rd(0x6000U, 4U)); /* at once; the error switches HV off */
    TEST_ASSERT_EQUAL_HEX8(0x06U, (uint8_t)rd(0x6000U, 1U));
    advance(6U * S_);
    TEST_ASSERT_EQUAL_INT32(0, rd(0x6000U, 4U)); /* no HV, no measurement */
    const uint32_t before = S.lines;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("faults"));
    TEST_ASSERT_EQUAL_UINT32(before + 13U, S.lines);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("model"));
    TEST_ASSERT_NOT_NULL(strstr(S.last_line, "pollution"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("air 10"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("set 0x6200:01 0x00"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x6200:01 7"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x6000:04 90"));
    /* local writes obey the EDS limits and the rules of the SDO path (E2, E5, E6) */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:02 0"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:04 66"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:07 9"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:07 5"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x1017 5001"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("set 0x2002:04 65"));
    TEST_ASSERT_EQUAL_INT32(75, rd(0x2002U, 2U));
    TEST_ASSERT_EQUAL_INT32(4, rd(0x2002U, 7U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(release_drops_at_exactly_10_s_and_values_decay);
    RUN_TEST(a_30_day_gap_is_caught_up_at_once);
    RUN_TEST(release_refreshed_every_9_s_stays_on_for_a_minute);
    RUN_TEST(release_zero_switches_off_at_once_other_values_refused);
    RUN_TEST(release_by_rpdo1_only_in_operational);
    RUN_TEST(balance_moves_status_balance_and_both_voltages);
    RUN_TEST(readings_are_consistent_with_load_and_pollution);
    RUN_TEST(pollution_warning_at_80_error_at_100_and_clearing);
    RUN_TEST(clearing_inactive_or_unknown_codes_is_refused);
    RUN_TEST(injected_errors_switch_hv_off_and_block_the_release);
    RUN_TEST(supply_temperature_and_overload_conditions);
    RUN_TEST(resets_forget_momentary_faults_and_report_persisting_ones_again);
    RUN_TEST(power_cycle_keeps_the_inputs_and_restarts_the_bar);
    RUN_TEST(variant_n_working_distance_10_to_15);
    RUN_TEST(variant_e_working_distance_15_to_30);
    RUN_TEST(variant_change_with_the_same_nvm_refuses_the_stored_distance);
    RUN_TEST(variant_pulse_frequency_defaults_48_and_40);
    RUN_TEST(tpdo1_tpdo2_every_transfer_time_only_in_operational);
    RUN_TEST(tpdo_grid_does_not_drift_with_late_calls);
    RUN_TEST(steady_hv_sends_only_the_cyclic_tpdos_with_consistent_values);
    RUN_TEST(counters_advance_and_survive_a_power_cycle);
    RUN_TEST(counters_years_days_from_stored_seconds);
    RUN_TEST(node_id_from_2002_06_only_after_save_and_reset);
    RUN_TEST(lss_store_and_2002_06_stay_consistent_newest_wins);
    RUN_TEST(bit_timing_from_2002_07_after_save_and_reset);
    RUN_TEST(heartbeat_time_rules);
    RUN_TEST(control_commands);
    return UNITY_END();
}
