/*
 * Bürkert mass flow controller (devices/buerkert): the device model through the core, frames in and out,
 * simulated time. Behaviour and decisions: docs/devices/buerkert-behaviour.md. Node-ID 1 (the class
 * default) unless a test changes it: SDO 0x601/0x581, TPDO1 0x181, RPDO1 0x201, EMCY 0x081, HB 0x701.
 */
#include <stdio.h>
#include <string.h>

#include "buerkert/buerkert.h"
#include "buerkert_fc_od.h"
#include "fake_port.h"
#include "unity.h"

/* ---- fixture: one device instance on a fake port ------------------------------------------------------- */

static fake_port_t port;
static co_time_us_t now;
static device_t dev;
static buerkert_fc_od_values_t values;
static union {
    uint64_t align_u;
    double align_d;
    void *align_p;
    uint8_t bytes[2048];
} model_mem;
static char last_line[512];
static uint32_t n_lines;

static void on_print(void *ctx, const device_t *d, const char *line)
{
    (void)ctx;
    (void)d;
    (void)snprintf(last_line, sizeof last_line, "%s", line);
    n_lines++;
}

static co_time_us_t process(void) { return device_process(&dev, now); }

/* Powers a node on; serial: 0x1018:04 as canopen-emu gives every node its own (0: the OD default). */
static void start_with_serial(uint8_t node_id, uint32_t serial)
{
    now = 0U;
    fake_port_init(&port, &now);
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = node_id;
    cfg.serial = serial;
    cfg.port = &port.port;
    cfg.port_ctx = &port;
    cfg.print = on_print;
    TEST_ASSERT_TRUE(buerkert_class.model_size <= sizeof model_mem.bytes);
    TEST_ASSERT_EQUAL_INT(CO_OK, device_init(&dev, &buerkert_class, &values, model_mem.bytes, &cfg, now));
    (void)process();
}

static void start(uint8_t node_id) { start_with_serial(node_id, 0U); }

static void power_cycle(void)
{
    TEST_ASSERT_EQUAL_INT(CO_OK, device_power_cycle(&dev, now));
    (void)process();
}

/* Advances to t, calling device_process at every deadline on the way (as the emulator's loop does). */
static void run_until(co_time_us_t t)
{
    for (;;) {
        const co_time_us_t next = process();
        if (next > t) {
            break;
        }
        TEST_ASSERT_TRUE_MESSAGE(next >= now, "deadline in the past");
        if (next == now) {
            TEST_ASSERT_TRUE_MESSAGE(process() > now, "process() did not advance its deadline");
            continue;
        }
        now = next;
    }
    now = t;
    (void)process();
}
static void advance(co_time_us_t d) { run_until(now + d); }

static void rx_frame(uint32_t id, uint8_t len, const uint8_t *data, uint8_t flags)
{
    co_frame_t f = {id, len, flags, {0U}};
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    device_rx(&dev, &f, now);
    (void)process();
}
#define RX(id, ...)                                                                      \
    do {                                                                                 \
        const uint8_t d_[] = {__VA_ARGS__};                                              \
        rx_frame((id), (uint8_t)sizeof d_, d_, 0U);                                      \
    } while (0)
#define RX0(id) rx_frame((id), 0U, NULL, 0U)
#define RX_RTR(id) rx_frame((id), 0U, NULL, CO_FRAME_RTR)

#define ASSERT_FRAME(i, id_, len_, ...)                                                  \
    do {                                                                                 \
        const uint8_t expect_[] = {__VA_ARGS__};                                         \
        TEST_ASSERT_TRUE_MESSAGE((uint32_t)(i) < port.n_sent, "frame missing");          \
        TEST_ASSERT_EQUAL_HEX32((id_), port.sent[(i)].id);                               \
        TEST_ASSERT_EQUAL_UINT8((len_), port.sent[(i)].len);                             \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(expect_, port.sent[(i)].data, (len_));              \
    } while (0)

static uint32_t count(uint32_t id)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < port.n_sent; i++) {
        n += port.sent[i].id == id ? 1U : 0U;
    }
    return n;
}
static int last(uint32_t id)
{
    for (uint32_t i = port.n_sent; i > 0U; i--) {
        if (port.sent[i - 1U].id == id) {
            return (int)(i - 1U);
        }
    }
    return -1;
}
static void clear(void) { fake_port_clear(&port); }

/* Asserts that exactly one frame with this id was sent since the last clear() and that it has this data. */
#define EXPECT_ONE(id_, ...)                                                             \
    do {                                                                                 \
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(1U, count(id_), "expected exactly one frame");  \
        const uint8_t e_[] = {__VA_ARGS__};                                              \
        ASSERT_FRAME(last(id_), (id_), (uint8_t)sizeof e_, __VA_ARGS__);                 \
    } while (0)

static uint8_t node_id(void) { return co_node_id(&dev.node); }

/* One SDO request to the current node-ID; exactly one answer on 0x580+id. */
static const co_frame_t *sdo(const uint8_t req[8])
{
    const uint32_t before = port.n_sent;
    const uint8_t id = node_id();
    rx_frame(0x600U + id, 8U, req, 0U);
    TEST_ASSERT_TRUE_MESSAGE(port.n_sent > before, "no SDO response");
    const co_frame_t *f = &port.sent[before];
    TEST_ASSERT_EQUAL_HEX32(0x580U + id, f->id);
    TEST_ASSERT_EQUAL_UINT8(8U, f->len);
    return f;
}
#define SDO(...)                                                                         \
    do {                                                                                 \
        const uint8_t req_[8] = {__VA_ARGS__};                                           \
        (void)sdo(req_);                                                                 \
    } while (0)
#define EXPECT_SDO(...) ASSERT_FRAME(last(0x580U + node_id()), 0x580U + node_id(), 8, __VA_ARGS__)

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Expedited write of size bytes; returns 0 or the abort code. */
static uint32_t sdo_write(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    const uint8_t req[8] = {(uint8_t)(0x23U | ((4U - size) << 2)), (uint8_t)index, (uint8_t)(index >> 8), sub,
                            (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    const co_frame_t *f = sdo(req);
    if (f->data[0] == 0x80U) {
        return le32(&f->data[4]);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60, f->data[0]);
    return 0U;
}
static uint32_t f32_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static float bits_f32(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
static uint32_t sdo_write_f32(uint16_t index, uint8_t sub, float f) { return sdo_write(index, sub, f32_bits(f), 4U); }

/* Expedited read; fails the test on an abort. */
static uint32_t sdo_read(uint16_t index, uint8_t sub)
{
    const uint8_t req[8] = {0x40, (uint8_t)index, (uint8_t)(index >> 8), sub, 0, 0, 0, 0};
    const co_frame_t *f = sdo(req);
    TEST_ASSERT_EQUAL_HEX8_MESSAGE(0x43, f->data[0] & 0xF3U, "expected an expedited upload response");
    const uint8_t n = (uint8_t)(4U - ((f->data[0] >> 2) & 3U));
    uint32_t v = 0U;
    for (uint8_t i = 0U; i < n; i++) {
        v |= (uint32_t)f->data[4U + i] << (8U * i);
    }
    return v;
}
static float sdo_read_f32(uint16_t index, uint8_t sub) { return bits_f32(sdo_read(index, sub)); }

/* A control command line, split at spaces. */
static device_cmd_result_t cmd(const char *line)
{
    char buf[128];
    const char *argv[8];
    int argc = 0;
    (void)snprintf(buf, sizeof buf, "%s", line);
    for (char *t = strtok(buf, " "); t != NULL && argc < 8; t = strtok(NULL, " ")) {
        argv[argc++] = t;
    }
    const device_cmd_result_t r = device_command(&dev, argc, argv, now, NULL);
    (void)process();
    return r;
}

static void nmt(uint8_t cs) { RX(0x000, cs, 0x00); }

static float flow(void) { return values.x2500_01; }

/* e^-x for x >= 0 (Taylor series after halving; the test links no libm). */
static double exp_neg(double x)
{
    int k = 0;
    while (x > 0.5) {
        x /= 2.0;
        k++;
    }
    double term = 1.0;
    double sum = 1.0;
    for (int i = 1; i < 20; i++) {
        term *= -x / i;
        sum += term;
    }
    while (k-- > 0) {
        sum *= sum;
    }
    return sum;
}

/* s * (1 - exp(-t/tau)) with tau = 200 ms: the expected first-order step response. */
static float step_response(float s, double t_ms) { return (float)(s * (1.0 - exp_neg(t_ms / 200.0))); }

void setUp(void)
{
    n_lines = 0U;
    start(0U);
}
void tearDown(void) {}

/* ---- process value: first-order response --------------------------------------------------------------- */

static void first_order_response_of_the_flow(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, flow());
    const co_time_us_t t0 = now;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 80.0f));
    TEST_ASSERT_EQUAL_FLOAT(80.0f, sdo_read_f32(0x2540U, 1U));
    run_until(t0 + 100000U);
    TEST_ASSERT_FLOAT_WITHIN(0.02f, step_response(80.0f, 100.0), flow());
    run_until(t0 + 200000U); /* 1 tau: 63.2 % */
    TEST_ASSERT_FLOAT_WITHIN(0.02f, step_response(80.0f, 200.0), flow());
    TEST_ASSERT_FLOAT_WITHIN(0.015f * 80.0f, 0.632f * 80.0f, flow());
    run_until(t0 + 1000000U); /* 5 tau: within 1 %, still approaching */
    TEST_ASSERT_FLOAT_WITHIN(0.01f * 80.0f, 80.0f, flow());
    TEST_ASSERT_TRUE(flow() < 80.0f);
    run_until(t0 + 3000000U);
    TEST_ASSERT_EQUAL_FLOAT(80.0f, flow());
    /* the SDO upload carries the REAL32 as it is in the OD */
    clear();
    SDO(0x40, 0x00, 0x25, 0x01, 0, 0, 0, 0);
    EXPECT_SDO(0x43, 0x00, 0x25, 0x01, 0x00, 0x00, 0xA0, 0x42); /* 80.0f = 0x42A00000 */
    /* a step down follows the same law */
    const co_time_us_t t1 = now;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 20.0f));
    run_until(t1 + 200000U);
    TEST_ASSERT_FLOAT_WITHIN(0.02f, 80.0f - step_response(60.0f, 200.0), flow());
}

static void setpoint_is_clamped_to_the_range_and_checked(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 150.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(150.0f, sdo_read_f32(0x2540U, 1U)); /* stored as written */
    TEST_ASSERT_EQUAL_FLOAT(100.0f, flow());                    /* the controller stops at full scale */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, -5.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, flow());
    TEST_ASSERT_EQUAL_HEX32(0x06090030U, sdo_write(0x2540U, 1U, 0x7FC00000U, 4U)); /* NaN */
    TEST_ASSERT_EQUAL_FLOAT(-5.0f, values.x2540_01);
    TEST_ASSERT_EQUAL_HEX32(0x08000021U, sdo_write_f32(0x2500U, 1U, 12.0f)); /* the measured value */
    /* the local command writes the same object */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("setpoint 42.5"));
    TEST_ASSERT_EQUAL_FLOAT(42.5f, values.x2540_01);
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(42.5f, flow());
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("setpoint abc"));
}

static void rpdo1_setpoint_moves_the_flow_only_in_operational(void)
{
    RX(0x201, 0x00, 0x00, 0x48, 0x42); /* 50.0 in Pre-operational: dropped */
    advance(1000000U);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, values.x2540_01);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, flow());
    nmt(0x01);
    const co_time_us_t t0 = now;
    RX(0x201, 0x00, 0x00, 0x48, 0x42);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, values.x2540_01);
    run_until(t0 + 200000U);
    TEST_ASSERT_FLOAT_WITHIN(0.02f, step_response(50.0f, 200.0), flow());
    run_until(t0 + 1000000U);
    TEST_ASSERT_FLOAT_WITHIN(0.5f, 50.0f, flow());
    RX(0x201, 0x00, 0x00, 0xC0, 0x7F); /* NaN: refused by the device, dropped */
    TEST_ASSERT_EQUAL_FLOAT(50.0f, values.x2540_01);
}

/* ---- PDO timing ----------------------------------------------------------------------------------------- */

static void tpdo1_follows_the_flow_with_inhibit_and_event_timer(void)
{
    /* defaults of the manual: type 0xFE, inhibit 5000 x 100 us, event timer 1000 ms; mapping 0x2500:01 */
    TEST_ASSERT_EQUAL_HEX32(0xFEU, sdo_read(0x1800U, 2U));
    TEST_ASSERT_EQUAL_UINT32(5000U, sdo_read(0x1800U, 3U));
    TEST_ASSERT_EQUAL_UINT32(1000U, sdo_read(0x1800U, 5U));
    TEST_ASSERT_EQUAL_HEX32(0x25000120U, sdo_read(0x1A00U, 1U));
    clear();
    const co_time_us_t t0 = now;
    nmt(0x01);
    EXPECT_ONE(0x181U, 0x00, 0x00, 0x00, 0x00); /* entering Operational */
    advance(100000U);
    RX(0x201, 0x00, 0x00, 0x48, 0x42); /* set-point 50.0 at t0 + 100 ms */
    run_until(t0 + 5000000U);

    /* expected: 0 (start), 500 (inhibit ends; moving), 1000, 1500, 2000 (settles), 3000, 4000, 5000 (event timer) */
    static const uint32_t expect_ms[] = {0U, 500U, 1000U, 1500U, 2000U, 3000U, 4000U, 5000U};
    uint32_t n = 0U;
    co_time_us_t prev = 0U;
    float prev_v = -1.0f;
    for (uint32_t i = 0U; i < port.n_sent; i++) {
        if (port.sent[i].id != 0x181U) {
            continue;
        }
        TEST_ASSERT_TRUE_MESSAGE(n < sizeof expect_ms / sizeof expect_ms[0], "too many TPDOs");
        TEST_ASSERT_EQUAL_UINT8(4U, port.sent[i].len);
        const co_time_us_t t = port.sent_at[i];
        TEST_ASSERT_EQUAL_UINT64((uint64_t)t0 + expect_ms[n] * 1000ULL, t);
        if (n > 0U) {
            TEST_ASSERT_TRUE_MESSAGE(t - prev >= 500000U, "inhibit time violated");
            TEST_ASSERT_TRUE_MESSAGE(t - prev <= 1000000U, "event timer missed");
        }
        const float v = bits_f32(le32(port.sent[i].data));
        TEST_ASSERT_TRUE_MESSAGE(v >= prev_v, "flow went backwards");
        if (expect_ms[n] >= 500U && expect_ms[n] <= 1500U) {
            /* the value sampled at the transmission: (t - 100 ms) of response */
            TEST_ASSERT_FLOAT_WITHIN(0.02f, step_response(50.0f, (double)expect_ms[n] - 100.0), v);
            TEST_ASSERT_TRUE(v < 50.0f);
        }
        prev = t;
        prev_v = v;
        n++;
    }
    TEST_ASSERT_EQUAL_UINT32(8U, n);
    /* settled: the REAL32 50.0 = 0x42480000, little-endian */
    ASSERT_FRAME(last(0x181U), 0x181U, 4, 0x00, 0x00, 0x48, 0x42);
}

static void synchronous_tpdo_configured_by_sdo_goes_with_sync(void)
{
    clear();
    SDO(0x2F, 0x00, 0x18, 0x02, 0x01, 0, 0, 0); /* TPDO1 transmission type 1: every SYNC */
    EXPECT_SDO(0x60, 0x00, 0x18, 0x02, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 60.0f));
    nmt(0x01);
    advance(2500000U); /* no SYNC: nothing, not even from the event timer */
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x181U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 20.0f));
    advance(100000U);
    const float v1 = flow();
    TEST_ASSERT_TRUE(v1 > 20.0f && v1 < 60.0f); /* moving */
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(1U, count(0x181U));
    TEST_ASSERT_EQUAL_HEX32(f32_bits(v1), le32(port.sent[last(0x181U)].data));
    advance(300000U);
    TEST_ASSERT_EQUAL_UINT32(1U, count(0x181U)); /* nothing between SYNCs */
    const float v2 = flow();
    TEST_ASSERT_TRUE(v2 < v1);
    RX0(0x080);
    TEST_ASSERT_EQUAL_UINT32(2U, count(0x181U));
    TEST_ASSERT_EQUAL_HEX32(f32_bits(v2), le32(port.sent[last(0x181U)].data));
    ASSERT_FRAME(last(0x181U), 0x181U, 4, (uint8_t)f32_bits(v2), (uint8_t)(f32_bits(v2) >> 8),
                 (uint8_t)(f32_bits(v2) >> 16), (uint8_t)(f32_bits(v2) >> 24));
}

/* ---- 0x2001: address, baud rate, reset -------------------------------------------------------------- */

static void address_written_to_0x2001_takes_effect_at_the_reset_entry(void)
{
    clear();
    SDO(0x2F, 0x01, 0x20, 0x02, 0x0A, 0, 0, 0);
    EXPECT_SDO(0x60, 0x01, 0x20, 0x02, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0x0AU, sdo_read(0x2001U, 2U)); /* the address after the next reset */
    advance(600000U);
    TEST_ASSERT_EQUAL_UINT8(1U, node_id());                 /* not yet */
    TEST_ASSERT_TRUE(count(0x701U) >= 1U);
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x70AU));
    clear();
    SDO(0x2F, 0x01, 0x20, 0x04, 0x02, 0, 0, 0); /* 0x2001:04 = 2: device reset */
    /* the confirmation comes first, from the old node-ID; then the boot-up with the new one */
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    ASSERT_FRAME(0, 0x581U, 8, 0x60, 0x01, 0x20, 0x04, 0, 0, 0, 0);
    ASSERT_FRAME(1, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT8(0x0AU, node_id());
    TEST_ASSERT_EQUAL_UINT32(0U, sdo_read(0x2001U, 4U)); /* reads back 0 */
    TEST_ASSERT_EQUAL_UINT32(0x0AU, sdo_read(0x2001U, 2U));
    clear();
    RX(0x601, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0); /* the old SDO server is gone */
    TEST_ASSERT_EQUAL_UINT32(0U, port.n_sent);
    /* the address was saved: it survives a power cycle */
    clear();
    power_cycle();
    ASSERT_FRAME(0, 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT8(0x0AU, node_id());
}

static void address_takes_effect_at_nmt_reset_and_at_the_communication_reset_entry(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 30.0f));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 2U, 0x0BU, 1U));
    clear();
    RX(0x000, 0x82, 0x01); /* NMT reset communication */
    EXPECT_ONE(0x70BU, 0x00);
    TEST_ASSERT_EQUAL_UINT8(0x0BU, node_id());
    TEST_ASSERT_EQUAL_FLOAT(30.0f, values.x2540_01); /* 0x2000 area untouched by a communication reset */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 2U, 0x0CU, 1U));
    clear();
    SDO(0x2F, 0x01, 0x20, 0x04, 0x01, 0, 0, 0); /* 0x2001:04 = 1: communication reset */
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    ASSERT_FRAME(0, 0x58BU, 8, 0x60, 0x01, 0x20, 0x04, 0, 0, 0, 0);
    ASSERT_FRAME(1, 0x70CU, 1, 0x00);
    TEST_ASSERT_EQUAL_FLOAT(30.0f, values.x2540_01);
    /* NMT reset node: application reset, the set-point is 0.0 again and the flow decays */
    advance(2000000U);
    TEST_ASSERT_FLOAT_WITHIN(0.1f, 30.0f, flow());
    clear();
    RX(0x000, 0x81, 0x0C);
    EXPECT_ONE(0x70CU, 0x00);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, values.x2540_01);
    TEST_ASSERT_TRUE(flow() > 29.0f); /* physical flow does not jump */
    advance(200000U);
    TEST_ASSERT_FLOAT_WITHIN(0.1f, 30.0f - step_response(30.0f, 200.0), flow());
    /* out-of-range addresses */
    TEST_ASSERT_EQUAL_HEX32(0x06090032U, sdo_write(0x2001U, 2U, 0U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06090031U, sdo_write(0x2001U, 2U, 128U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06090031U, sdo_write(0x2001U, 4U, 3U, 1U));
}

static void baud_rate_written_to_0x2001_takes_effect_at_the_device_reset(void)
{
    TEST_ASSERT_EQUAL_UINT32(2U, sdo_read(0x2001U, 1U)); /* 500 kbit/s */
    TEST_ASSERT_EQUAL_HEX32(0x06090030U, sdo_write(0x2001U, 1U, 1U, 1U)); /* 800 kbit/s: not in Bürkert's table */
    TEST_ASSERT_EQUAL_HEX32(0x06090031U, sdo_write(0x2001U, 1U, 9U, 1U));
    const uint32_t calls = port.bit_rate_calls;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 1U, 5U, 1U)); /* 100 kbit/s */
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 1U));
    TEST_ASSERT_EQUAL_UINT32(calls, port.bit_rate_calls);
    nmt(0x82); /* communication reset: the bit rate stays */
    TEST_ASSERT_EQUAL_UINT32(calls, port.bit_rate_calls);
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 4U, 2U, 1U));
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(100U, port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 1U));
    /* saved: a power cycle starts at 100 kbit/s */
    port.bit_rate_kbit = 0U;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(100U, port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 1U));
}

/* ---- error control on this device's OD ------------------------------------------------------------------- */

static void heartbeat_every_500_ms_by_default(void)
{
    /* setUp powered on at t = 0: boot-up first */
    TEST_ASSERT_TRUE(port.n_sent >= 1U);
    ASSERT_FRAME(0, 0x701U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(500U, sdo_read(0x1017U, 0U));
    clear();
    run_until(1600000U);
    TEST_ASSERT_EQUAL_UINT32(3U, count(0x701U));
    for (uint32_t i = 0U; i < port.n_sent; i++) {
        TEST_ASSERT_EQUAL_HEX32(0x701U, port.sent[i].id);
        TEST_ASSERT_EQUAL_UINT64(500000ULL * (i + 1U), port.sent_at[i]);
        ASSERT_FRAME(i, 0x701U, 1, 0x7F);
    }
    nmt(0x01);
    clear();
    run_until(2100000U);
    ASSERT_FRAME(last(0x701U), 0x701U, 1, 0x05);
}

static void node_guarding_when_the_master_configures_it(void)
{
    clear();
    RX_RTR(0x701); /* heartbeat on: guarding off */
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x701U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1017U, 0U, 0U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x100CU, 0U, 100U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x100DU, 0U, 3U, 1U));
    clear();
    RX_RTR(0x701);
    EXPECT_ONE(0x701U, 0x7F);
    clear();
    advance(100000U);
    RX_RTR(0x701);
    EXPECT_ONE(0x701U, 0xFF); /* toggle bit */
    clear();
    advance(299000U);
    TEST_ASSERT_EQUAL_UINT32(0U, port.n_sent);
    advance(1000U); /* 100 ms x 3 without a guard request: life-guarding event */
    EXPECT_ONE(0x081U, 0x30, 0x81, 0x11, 0x01, 0x00, 0x00, 0x00, 0x00);
    clear();
    RX_RTR(0x701);
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    ASSERT_FRAME(0, 0x701U, 1, 0x7F);
    ASSERT_FRAME(1, 0x081U, 8, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x00);
}

static void heartbeat_consumer_reports_a_lost_producer_by_emcy(void)
{
    TEST_ASSERT_EQUAL_UINT32(127U, sdo_read(0x1016U, 0U));
    clear();
    SDO(0x23, 0x16, 0x10, 0x01, 0xC8, 0x00, 0x0A, 0x00); /* node 0x0A, 200 ms */
    EXPECT_SDO(0x60, 0x16, 0x10, 0x01, 0, 0, 0, 0);
    RX(0x70A, 0x05);
    clear();
    advance(199000U);
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x081U));
    advance(1000U);
    EXPECT_ONE(0x081U, 0x30, 0x81, 0x11, 0x02, 0x0A, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0x11U, sdo_read(0x1001U, 0U));
    TEST_ASSERT_EQUAL_UINT32(0x00U, sdo_read(0x2004U, 1U)); /* a bus error is not a device (NE 107) state */
    clear();
    RX(0x70A, 0x05);
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x00, 0x02, 0x0A, 0x00, 0x00, 0x00);
}

/* ---- strings: segmented SDO, frame by frame --------------------------------------------------------------- */

static void user_string_segmented_download_and_upload(void)
{
    clear();
    SDO(0x21, 0x02, 0x20, 0x03, 20, 0, 0, 0); /* 0x2002:03 User Description, 20 bytes */
    EXPECT_SDO(0x60, 0x02, 0x20, 0x03, 0, 0, 0, 0);
    SDO(0x00, 'L', 'i', 'n', 'e', ' ', '3', ' ');
    EXPECT_SDO(0x20, 0, 0, 0, 0, 0, 0, 0);
    SDO(0x10, '/', ' ', 'b', 'a', 'y', ' ', '1');
    EXPECT_SDO(0x30, 0, 0, 0, 0, 0, 0, 0);
    SDO(0x03, '2', ' ', '/', ' ', 'N', '2', 0); /* 6 bytes, last */
    EXPECT_SDO(0x20, 0, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_STRING_LEN("Line 3 / bay 12 / N2", values.x2002_03, 20);
    TEST_ASSERT_EQUAL_UINT32(4U, port.n_sent); /* one answer per request, nothing else */

    clear();
    SDO(0x40, 0x02, 0x20, 0x03, 0, 0, 0, 0);
    EXPECT_SDO(0x41, 0x02, 0x20, 0x03, 20, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_SDO(0x00, 'L', 'i', 'n', 'e', ' ', '3', ' ');
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_SDO(0x10, '/', ' ', 'b', 'a', 'y', ' ', '1');
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_SDO(0x03, '2', ' ', '/', ' ', 'N', '2', 0);

    /* capacity 32: 33 bytes are refused at the initiate */
    clear();
    SDO(0x21, 0x02, 0x20, 0x01, 33, 0, 0, 0);
    EXPECT_SDO(0x80, 0x02, 0x20, 0x01, 0x12, 0x00, 0x07, 0x06);
    /* 0x2000:01 Device Name: read-only, 12 bytes by segmented upload */
    clear();
    SDO(0x40, 0x00, 0x20, 0x01, 0, 0, 0, 0);
    EXPECT_SDO(0x41, 0x00, 0x20, 0x01, 12, 0, 0, 0);
    SDO(0x60, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_SDO(0x00, 'B', 'u', 'e', 'r', 'k', 'e', 'r');
    SDO(0x70, 0, 0, 0, 0, 0, 0, 0);
    EXPECT_SDO(0x15, 't', ' ', 'M', 'F', 'C', 0, 0);
    clear();
    SDO(0x21, 0x00, 0x20, 0x01, 4, 0, 0, 0);
    EXPECT_SDO(0x80, 0x00, 0x20, 0x01, 0x02, 0x00, 0x01, 0x06);
    /* saved with 0x1010 ("save") the string survives a power cycle */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x1010U, 1U, 0x65766173U, 4U));
    memset(values.x2002_03, 0, sizeof values.x2002_03);
    power_cycle();
    TEST_ASSERT_EQUAL_STRING_LEN("Line 3 / bay 12 / N2", values.x2002_03, 20);
}

/* ---- LSS ----------------------------------------------------------------------------------------------- */

/* Manual §2.3 "Example of the configuration via LSS", steps 1-5, with the fields the manual leaves open
 * filled in: table 0 index 5 (100 kbit/s, Bürkert's table), delay 100 ms, node-ID 5; reserved bytes 0. */
static void lss_walkthrough_of_the_manual_frame_for_frame(void)
{
    clear();
    /* 1. Switch Mode Global, configuration: 0x7E5 8 0x04 0x01 reserved -> no response */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x7E4U));
    /* 2. Configure Bit Timing: 0x7E5 8 0x13 Table Index -> 0x7E4 8 0x13 ErrorCode ErrorExtension */
    RX(0x7E5, 0x13, 0x00, 0x05, 0, 0, 0, 0, 0);
    EXPECT_ONE(0x7E4U, 0x13, 0x00, 0x00, 0, 0, 0, 0, 0);
    /* 3. Activate Bit Timing: 0x7E5 8 0x15 Delay -> no response; switch after the delay */
    clear();
    RX(0x7E5, 0x15, 0x64, 0x00, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x7E4U));
    advance(100000U);
    TEST_ASSERT_EQUAL_UINT32(100U, port.bit_rate_kbit);
    advance(100000U); /* silent for another delay */
    /* 4. Configure node-ID: 0x7E5 8 0x11 NodeID -> 0x7E4 8 0x11 ErrorCode ErrorExtension */
    clear();
    RX(0x7E5, 0x11, 0x05, 0, 0, 0, 0, 0, 0);
    EXPECT_ONE(0x7E4U, 0x11, 0x00, 0x00, 0, 0, 0, 0, 0);
    /* 5. Switch Mode Global, operation: 0x7E5 8 0x04 0x00 reserved -> no response */
    clear();
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x7E4U));

    /* 0x2001 shows the new configuration; the node-ID becomes active at the next reset */
    TEST_ASSERT_EQUAL_UINT8(1U, node_id());
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 2U));
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 1U));
    clear();
    RX(0x000, 0x82, 0x01);
    EXPECT_ONE(0x705U, 0x00);
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    TEST_ASSERT_EQUAL_UINT32(5U, sdo_read(0x2001U, 2U));
}

static void lss_uses_the_bit_timing_table_and_node_id_range_of_the_manual(void)
{
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    static const uint8_t index_ok[] = {0U, 2U, 3U, 4U, 5U, 6U, 7U, 8U};
    for (size_t i = 0U; i < sizeof index_ok; i++) {
        clear();
        RX(0x7E5, 0x13, 0x00, index_ok[i], 0, 0, 0, 0, 0);
        EXPECT_ONE(0x7E4U, 0x13, 0x00, 0x00, 0, 0, 0, 0, 0);
    }
    clear();
    RX(0x7E5, 0x13, 0x00, 0x01, 0, 0, 0, 0, 0); /* 800 kbit/s: "baud rate is not supported" */
    EXPECT_ONE(0x7E4U, 0x13, 0x01, 0x00, 0, 0, 0, 0, 0);
    clear();
    RX(0x7E5, 0x13, 0x00, 0x09, 0, 0, 0, 0, 0);
    EXPECT_ONE(0x7E4U, 0x13, 0x01, 0x00, 0, 0, 0, 0, 0);
    static const uint8_t id_bad[] = {0x00U, 0x80U, 0xFFU}; /* "only values between 1 and 127" */
    for (size_t i = 0U; i < sizeof id_bad; i++) {
        clear();
        RX(0x7E5, 0x11, id_bad[i], 0, 0, 0, 0, 0, 0);
        EXPECT_ONE(0x7E4U, 0x11, 0x01, 0x00, 0, 0, 0, 0, 0);
    }
    clear();
    RX(0x7E5, 0x11, 0x7F, 0, 0, 0, 0, 0, 0);
    EXPECT_ONE(0x7E4U, 0x11, 0x00, 0x00, 0, 0, 0, 0, 0);
}

static void lss_stored_node_id_survives_a_restart_and_0x2001_02_follows(void)
{
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x07, 0, 0, 0, 0, 0, 0);
    clear();
    RX(0x7E5, 0x17, 0, 0, 0, 0, 0, 0, 0); /* Store Configuration */
    EXPECT_ONE(0x7E4U, 0x17, 0x00, 0x00, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(7U, sdo_read(0x2001U, 2U));
    clear();
    power_cycle();
    ASSERT_FRAME(0, 0x707U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(7U, sdo_read(0x2001U, 2U));
    /* a later 0x2001:02 write is newer than the LSS store: it wins at the next power-on */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 2U, 9U, 1U));
    clear();
    power_cycle();
    ASSERT_FRAME(0, 0x709U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(9U, sdo_read(0x2001U, 2U));
    /* and a later LSS store wins over that */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0C, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x17, 0, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    clear();
    power_cycle();
    ASSERT_FRAME(0, 0x70CU, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(12U, sdo_read(0x2001U, 2U));
    /* an LSS node-ID without Store Configuration is lost at a power cycle (CiA 305) */
    RX(0x7E5, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x11, 0x0D, 0, 0, 0, 0, 0, 0);
    RX(0x7E5, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(13U, sdo_read(0x2001U, 2U));
    clear();
    power_cycle();
    ASSERT_FRAME(0, 0x70CU, 1, 0x00);
}

/* ---- faults and NAMUR status ----------------------------------------------------------------------------- */

static void faults_set_namur_bits_and_send_emcy(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 50.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, flow());
    TEST_ASSERT_EQUAL_UINT32(0x00U, sdo_read(0x2004U, 1U));

    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("flow-fault on"));
    EXPECT_ONE(0x081U, 0x10, 0x50, 0x01, 0x00, 0x00, 0x05, 0x00, 0x00); /* 0x5010, ER 0x01, status 0x05 */
    TEST_ASSERT_EQUAL_UINT32(0x05U, sdo_read(0x2004U, 1U));                /* NAMUR state 5 = error */
    TEST_ASSERT_EQUAL_UINT32(0x01U, sdo_read(0x1001U, 0U));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, sdo_read_f32(0x2500U, 1U)); /* no measurement */
    advance(1000000U);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, flow());
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("flow-fault off"));
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0x00U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_TRUE(flow() < 1.0f); /* the valve was closed: the flow comes back with the time constant */
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, flow());

    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 20.5"));
    EXPECT_ONE(0x081U, 0x20, 0x31, 0x05, 0x00, 0x00, 0x03, 0x00, 0x00); /* under-voltage, ER voltage */
    TEST_ASSERT_EQUAL_UINT32(0x03U, sdo_read(0x2004U, 1U));               /* out of specification */
    TEST_ASSERT_EQUAL_FLOAT(20.5f, sdo_read_f32(0x2004U, 3U));
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 80"));
    EXPECT_ONE(0x081U, 0x10, 0x42, 0x0D, 0x00, 0x00, 0x03, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(80U, sdo_read(0x2004U, 2U));
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24"));
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x09, 0x00, 0x00, 0x03, 0x00, 0x00); /* temperature remains */
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 27"));
    EXPECT_ONE(0x081U, 0x10, 0x31, 0x0D, 0x00, 0x00, 0x03, 0x00, 0x00); /* over-voltage */
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("valve-fault on"));
    EXPECT_ONE(0x081U, 0x20, 0x50, 0x0D, 0x00, 0x00, 0x05, 0x00, 0x00); /* error wins over out of spec. */
    TEST_ASSERT_EQUAL_UINT32(0x05U, sdo_read(0x2004U, 1U));
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("valve-fault off"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 25"));
    TEST_ASSERT_EQUAL_UINT32(3U, count(0x081U));
    ASSERT_FRAME(last(0x081U), 0x081U, 8, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0x00U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_UINT32(0x00U, sdo_read(0x1001U, 0U));
}

static void stuck_valve_freezes_the_flow_and_is_raised_again_after_a_reset(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 50.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("valve-fault on"));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 10.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, flow());
    clear();
    nmt(0x82); /* the communication reset clears the core's error list; the fault persists */
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    ASSERT_FRAME(0, 0x701U, 1, 0x00);
    ASSERT_FRAME(1, 0x081U, 8, 0x20, 0x50, 0x01, 0x00, 0x00, 0x05, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0x01U, sdo_read(0x1001U, 0U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("valve-fault off"));
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(10.0f, flow());
}

static void error_commands_and_namur_mode(void)
{
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 0xFF01 2"));
    EXPECT_ONE(0x081U, 0x01, 0xFF, 0x81, 0x00, 0x00, 0x02, 0x00, 0x00); /* maintenance required */
    TEST_ASSERT_EQUAL_UINT32(0x02U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 0x6100"));
    TEST_ASSERT_EQUAL_UINT32(0x05U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("error 0x5010")); /* built-in: use flow-fault */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("clear-error 0x1234"));
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("clear-error 0x6100"));
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x81, 0x00, 0x00, 0x02, 0x00, 0x00);
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("clear-error 0xFF01"));
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00);

    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("mode hand"));
    TEST_ASSERT_EQUAL_UINT32(0x10U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x08000021U, sdo_write_f32(0x2540U, 1U, 40.0f)); /* local control */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("setpoint 40"));
    TEST_ASSERT_EQUAL_FLOAT(40.0f, values.x2540_01);
    nmt(0x01);
    RX(0x201, 0x00, 0x00, 0x48, 0x42); /* RPDO refused in hand mode */
    TEST_ASSERT_EQUAL_FLOAT(40.0f, values.x2540_01);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("mode flashing"));
    TEST_ASSERT_EQUAL_UINT32(0x20U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("mode auto"));
    RX(0x201, 0x00, 0x00, 0x48, 0x42);
    TEST_ASSERT_EQUAL_FLOAT(50.0f, values.x2540_01);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("mode manual"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_UNKNOWN, cmd("frobnicate"));
    n_lines = 0U;
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("status"));
    TEST_ASSERT_TRUE(n_lines >= 3U);
}

/* 0x2004:04-08 are stored by the write itself (no save step): the answer is given only once the .device blob is
 * durable; a failed store answers 0x06060000 and the value stays as before, also after a power cycle. */
static void stored_write_answers_only_what_was_stored(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2004U, 5U, 120U, 2U));
    port.nvm_fail_area_mask = 1U << CO_NVM_DEVICE;
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, sdo_write(0x2004U, 5U, 130U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, sdo_write_f32(0x2004U, 7U, 30.0f));
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, sdo_write(0x2004U, 4U, 3600U, 4U));
    TEST_ASSERT_EQUAL_UINT32(120U, sdo_read(0x2004U, 5U));
    port.nvm_fail_area_mask = 0U;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(120U, sdo_read(0x2004U, 5U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2004U, 5U, 130U, 2U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(130U, sdo_read(0x2004U, 5U));
}

/* 0x2001:01/02 are stored in the LSS area by the write itself: a failed store refuses the write (0x06060000) and
 * changes nothing, neither the value read back nor what the next reset or power cycle uses (the refused baud
 * rate and address stayed pending; found by tests/fuzz/target_nvm_file.c with a directory in place of .lss). */
static void failed_store_of_address_or_baud_rate_changes_nothing(void)
{
    TEST_ASSERT_EQUAL_UINT32(2U, sdo_read(0x2001U, 1U)); /* 500 kbit/s */
    port.nvm_fail_area_mask = 1U << CO_NVM_LSS;
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, sdo_write(0x2001U, 1U, 5U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0x06060000UL, sdo_write(0x2001U, 2U, 0x20U, 1U));
    TEST_ASSERT_EQUAL_UINT32(2U, sdo_read(0x2001U, 1U));
    TEST_ASSERT_EQUAL_UINT32(1U, sdo_read(0x2001U, 2U));
    TEST_ASSERT_EQUAL_UINT8(2U, dev.node.lss.pending_bit_timing);
    TEST_ASSERT_EQUAL_UINT8(1U, dev.node.lss.pending_node_id);
    port.nvm_fail_area_mask = 0U;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2001U, 4U, 2U, 1U)); /* device reset */
    advance(10000U);
    TEST_ASSERT_EQUAL_UINT8(1U, node_id());
    TEST_ASSERT_EQUAL_UINT8(2U, dev.node.lss.active_bit_timing);
    TEST_ASSERT_EQUAL_UINT32(2U, sdo_read(0x2001U, 1U));
}

static void power_cycle_keeps_the_supply_voltage_and_restarts_the_controller(void)
{
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 50.0f));
    advance(3000000U);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 20.5")); /* out of specification: EMCY 0x3120 */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("valve-fault on"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("error 0xFF01 2"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("mode hand"));
    TEST_ASSERT_EQUAL_UINT32(0x15U, sdo_read(0x2004U, 1U));
    clear();
    power_cycle();
    /* the supply is still 20.5 V: after the boot-up the device reports it again */
    TEST_ASSERT_EQUAL_UINT32(2U, port.n_sent);
    ASSERT_FRAME(0, 0x701U, 1, 0x00);
    ASSERT_FRAME(1, 0x081U, 8, 0x20, 0x31, 0x05, 0x00, 0x00, 0x03, 0x00, 0x00);
    TEST_ASSERT_EQUAL_FLOAT(20.5f, sdo_read_f32(0x2004U, 3U));
    /* the running state restarted: no stuck valve, no injected error, auto mode, flow 0 */
    TEST_ASSERT_EQUAL_UINT32(0x03U, sdo_read(0x2004U, 1U));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, flow());
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2540U, 1U, 30.0f)); /* auto mode: the bus set-point acts */
    advance(3000000U);
    TEST_ASSERT_EQUAL_FLOAT(30.0f, flow()); /* the valve moves again */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("clear-error 0xFF01"));
    clear();
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24"));
    EXPECT_ONE(0x081U, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00);
}

/* ---- 0x2004: measurements, min/max, operating time ----------------------------------------------------- */

static void min_max_tracking_persists(void)
{
    TEST_ASSERT_EQUAL_UINT32(25U, sdo_read(0x2004U, 2U));
    TEST_ASSERT_EQUAL_FLOAT(24.0f, sdo_read_f32(0x2004U, 3U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 40"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 10"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 30"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 26.0"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 22.5"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24.2"));
    clear();
    SDO(0x40, 0x04, 0x20, 0x05, 0, 0, 0, 0);
    EXPECT_SDO(0x4B, 0x04, 0x20, 0x05, 40, 0x00, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(10U, sdo_read(0x2004U, 6U));
    TEST_ASSERT_EQUAL_FLOAT(26.0f, sdo_read_f32(0x2004U, 7U));
    TEST_ASSERT_EQUAL_FLOAT(22.5f, sdo_read_f32(0x2004U, 8U));
    TEST_ASSERT_EQUAL_UINT32(0U, count(0x081U)); /* all inside the specification */
    TEST_ASSERT_EQUAL_UINT32(port.nvm[CO_NVM_DEVICE].commits, port.nvm[CO_NVM_DEVICE].background_commits); /* extremes */
    /* kept in the device's NVM area: a power cycle keeps them (and the environment: 30 C, 24.2 V) */
    TEST_ASSERT_TRUE(port.nvm[CO_NVM_DEVICE].stored_len > 0U);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(30U, sdo_read(0x2004U, 2U));
    TEST_ASSERT_EQUAL_FLOAT(24.2f, sdo_read_f32(0x2004U, 3U));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("temperature 25"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_OK, cmd("supply 24.0"));
    TEST_ASSERT_EQUAL_UINT32(40U, sdo_read(0x2004U, 5U));
    TEST_ASSERT_EQUAL_UINT32(10U, sdo_read(0x2004U, 6U));
    TEST_ASSERT_EQUAL_FLOAT(26.0f, sdo_read_f32(0x2004U, 7U));
    TEST_ASSERT_EQUAL_FLOAT(22.5f, sdo_read_f32(0x2004U, 8U));
    /* an NMT reset node re-initialises 0x2000-0x9FFF: the drag indicators come back from the model */
    nmt(0x81);
    TEST_ASSERT_EQUAL_UINT32(40U, sdo_read(0x2004U, 5U));
    /* a write resets an indicator; it then includes the present measurement again */
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2004U, 5U, 0U, 2U));
    TEST_ASSERT_EQUAL_UINT32(25U, sdo_read(0x2004U, 5U));
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write_f32(0x2004U, 8U, 99.0f));
    TEST_ASSERT_EQUAL_FLOAT(24.0f, sdo_read_f32(0x2004U, 8U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(25U, sdo_read(0x2004U, 5U));
    TEST_ASSERT_EQUAL_FLOAT(24.0f, sdo_read_f32(0x2004U, 8U));
    TEST_ASSERT_EQUAL_HEX32(0x06090030U, sdo_write(0x2004U, 7U, 0x7FC00000U, 4U)); /* NaN */
}

static void operating_time_counts_and_is_saved_every_minute(void)
{
    run_until(61500000U);
    clear();
    SDO(0x40, 0x04, 0x20, 0x04, 0, 0, 0, 0);
    EXPECT_SDO(0x43, 0x04, 0x20, 0x04, 61, 0x00, 0x00, 0x00);
    /* saved every minute at the node's phase, node-ID 1: 1 s past the minute (device_save_phase_us) */
    const uint32_t commits = port.nvm[CO_NVM_DEVICE].commits;
    TEST_ASSERT_TRUE(commits >= 2U); /* saved at 1 s and 61 s */
    /* no answer waits for them: the port may write them later (co_port.h), off an emulator's loop */
    TEST_ASSERT_EQUAL_UINT32(commits, port.nvm[CO_NVM_DEVICE].background_commits);
    run_until(121000000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(commits, port.nvm[CO_NVM_DEVICE].commits); /* nothing new to save before 121 s */
    run_until(121000000U);
    TEST_ASSERT_EQUAL_UINT32(commits + 1U, port.nvm[CO_NVM_DEVICE].commits);
    run_until(180000000U);
    power_cycle(); /* the 59 s since 121 s were not saved */
    TEST_ASSERT_EQUAL_UINT32(121U, sdo_read(0x2004U, 4U));
    advance(5000000U);
    TEST_ASSERT_EQUAL_UINT32(126U, sdo_read(0x2004U, 4U));
    const uint32_t background = port.nvm[CO_NVM_DEVICE].background_commits;
    TEST_ASSERT_EQUAL_HEX32(0U, sdo_write(0x2004U, 4U, 1000U, 4U)); /* a write sets the counter and saves it */
    TEST_ASSERT_EQUAL_UINT32(background, port.nvm[CO_NVM_DEVICE].background_commits); /* durable before the answer */
    TEST_ASSERT_EQUAL_UINT32(1000U, sdo_read(0x2004U, 4U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(1000U, sdo_read(0x2004U, 4U));
    /* a damaged blob is ignored: the counter starts at 0 */
    port.nvm[CO_NVM_DEVICE].stored[9] ^= 0x55U;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(0U, sdo_read(0x2004U, 4U));
}

/* Decision 30 (docs/devices/buerkert-flow-controller.md): 0x2000:07 is the serial number of 0x1018:04, also when the
 * emulator gives the node its own (a master read 0x00000001 from 0x2000:07 next to 0x13 in 0x1018:04). */
static void serial_number_of_0x2000_07_is_that_of_0x1018_04(void)
{
    start_with_serial(18U, 0x13U);
    TEST_ASSERT_EQUAL_HEX32(0x13U, sdo_read(0x1018U, 4U));
    TEST_ASSERT_EQUAL_HEX32(0x13U, sdo_read(0x2000U, 7U));
    TEST_ASSERT_EQUAL_HEX32(sdo_read(0x1018U, 2U), sdo_read(0x2000U, 8U));
    RX(0x000U, 0x81U, 18U); /* after a reset application (0x2000 re-initialised) as well */
    TEST_ASSERT_EQUAL_HEX32(0x13U, sdo_read(0x2000U, 7U));
    power_cycle();
    TEST_ASSERT_EQUAL_HEX32(0x13U, sdo_read(0x2000U, 7U));
}

/* Decision 26: TPDO sub-index 4 is reserved by CiA 301 (not implemented: 0x06090011), whatever the manual's
 * "Compatibility Entry" row says; decision 53: the mapping entries have distinct names. */
static void tpdo_sub_index_4_is_reserved_and_mapping_entries_have_distinct_names(void)
{
    start(5U);
    for (uint16_t n = 0U; n < 4U; n++) {
        const uint8_t req[8] = {0x40, 0x00, (uint8_t)(0x18U + (n >> 8)), 4, 0, 0, 0, 0};
        uint8_t r[8];
        memcpy(r, req, sizeof r);
        r[1] = (uint8_t)n;
        const co_frame_t *f = sdo(r);
        TEST_ASSERT_EQUAL_HEX8(0x80, f->data[0]);
        TEST_ASSERT_EQUAL_HEX32(0x06090011UL, le32(&f->data[4]));
        TEST_ASSERT_EQUAL_HEX32(0x00000005UL, sdo_read((uint16_t)(0x1800U + n), 0U)); /* highest sub-index: 5 */
    }
    const co_od_t *od = buerkert_class.od;
    char expect[32];
    unsigned checked = 0U;
    for (uint16_t i = 0U; i < od->count; i++) {
        for (uint8_t k = 0U; k < co_od_entry_subs(&od->entries[i]); k++) { /* the mapping entries are a run */
            co_od_entry_t one;
            const co_od_entry_t *e = co_od_entry_at(&od->entries[i], k, &one);
            if (((e->index >= 0x1600U && e->index <= 0x1603U) || (e->index >= 0x1A00U && e->index <= 0x1A03U)) &&
                e->sub > 0U) {
                snprintf(expect, sizeof expect, "PDO Mapping Entry %u", (unsigned)e->sub);
                TEST_ASSERT_EQUAL_STRING(expect, device_object_name(&buerkert_class, e));
                checked++;
            }
        }
    }
    TEST_ASSERT_EQUAL_UINT(8U * 8U, checked);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(tpdo_sub_index_4_is_reserved_and_mapping_entries_have_distinct_names);
    RUN_TEST(serial_number_of_0x2000_07_is_that_of_0x1018_04);
    RUN_TEST(first_order_response_of_the_flow);
    RUN_TEST(stored_write_answers_only_what_was_stored);
    RUN_TEST(setpoint_is_clamped_to_the_range_and_checked);
    RUN_TEST(rpdo1_setpoint_moves_the_flow_only_in_operational);
    RUN_TEST(tpdo1_follows_the_flow_with_inhibit_and_event_timer);
    RUN_TEST(synchronous_tpdo_configured_by_sdo_goes_with_sync);
    RUN_TEST(address_written_to_0x2001_takes_effect_at_the_reset_entry);
    RUN_TEST(address_takes_effect_at_nmt_reset_and_at_the_communication_reset_entry);
    RUN_TEST(baud_rate_written_to_0x2001_takes_effect_at_the_device_reset);
    RUN_TEST(heartbeat_every_500_ms_by_default);
    RUN_TEST(node_guarding_when_the_master_configures_it);
    RUN_TEST(heartbeat_consumer_reports_a_lost_producer_by_emcy);
    RUN_TEST(user_string_segmented_download_and_upload);
    RUN_TEST(lss_walkthrough_of_the_manual_frame_for_frame);
    RUN_TEST(lss_uses_the_bit_timing_table_and_node_id_range_of_the_manual);
    RUN_TEST(lss_stored_node_id_survives_a_restart_and_0x2001_02_follows);
    RUN_TEST(faults_set_namur_bits_and_send_emcy);
    RUN_TEST(stuck_valve_freezes_the_flow_and_is_raised_again_after_a_reset);
    RUN_TEST(error_commands_and_namur_mode);
    RUN_TEST(failed_store_of_address_or_baud_rate_changes_nothing);
    RUN_TEST(power_cycle_keeps_the_supply_voltage_and_restarts_the_controller);
    RUN_TEST(min_max_tracking_persists);
    RUN_TEST(operating_time_counts_and_is_saved_every_minute);
    return UNITY_END();
}
