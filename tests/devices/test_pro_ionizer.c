/*
 * PRO IONIZER device model: behaviour through the core with simulated time (docs/devices/pro-ionizer-behaviour.md).
 * Frames go in through device_rx and come out of a fake port; NVM areas live in the fake port, so a power
 * cycle keeps them. Times are absolute µs from power-on at 0.
 */
#include <stdio.h>
#include <string.h>

#include "fake_port.h"
#include "pro_ionizer/pro_ionizer.h"
#include "pro_ionizer_od.h"
#include "unity.h"

/* ---- fixture ------------------------------------------------------------------------------------------ */

static fake_port_t port;
static co_time_us_t now;
static device_t dev;
static pro_ionizer_od_values_t values;
static union {
    uint64_t u;
    void *p;
    long double d;
    unsigned char b[1024];
} model;
static char lines[64][160];
static unsigned n_lines;

static void print_cb(void *ctx, const device_t *d, const char *line)
{
    (void)ctx;
    (void)d;
    if (n_lines < sizeof lines / sizeof lines[0]) {
        (void)snprintf(lines[n_lines++], sizeof lines[0], "%s", line);
    }
}

static bool logged(const char *text)
{
    for (unsigned i = 0U; i < n_lines; i++) {
        if (strstr(lines[i], text) != NULL) {
            return true;
        }
    }
    return false;
}

static co_status_t boot(uint8_t id, const char *variant)
{
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = id;
    cfg.variant = variant;
    cfg.port = &port.port;
    cfg.port_ctx = &port;
    cfg.print = print_cb;
    TEST_ASSERT_TRUE(pro_ionizer_class.model_size <= sizeof model.b);
    const co_status_t st = device_init(&dev, &pro_ionizer_class, &values, model.b, &cfg, now);
    if (st == CO_OK) {
        (void)device_process(&dev, now);
    }
    return st;
}

/* Fresh device (empty NVM) with node-ID id, at time 0. */
static void start(uint8_t id, const char *variant)
{
    now = 0U;
    n_lines = 0U;
    memset(&model, 0, sizeof model);
    fake_port_init(&port, &now);
    TEST_ASSERT_EQUAL_INT(CO_OK, boot(id, variant));
}

static void process(void) { (void)device_process(&dev, now); }

/* Advances to t, calling device_process at every deadline on the way (as the emulator's loop does). */
static void run_until(co_time_us_t t)
{
    for (;;) {
        co_time_us_t next = device_process(&dev, now);
        if (next > t) {
            break;
        }
        TEST_ASSERT_TRUE_MESSAGE(next >= now, "deadline in the past");
        if (next == now) {
            next = device_process(&dev, now);
            TEST_ASSERT_TRUE_MESSAGE(next > now, "process() did not advance its deadline");
            if (next > t) {
                break;
            }
        }
        now = next;
    }
    now = t;
    process();
}

static void advance_ms(uint32_t ms) { run_until(now + (co_time_us_t)ms * 1000U); }

static void rx(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    device_rx(&dev, &f, now);
    process();
}

#define RX(id, ...)                                                                                           \
    do {                                                                                                      \
        const uint8_t d_[] = {__VA_ARGS__};                                                                   \
        rx((id), (uint8_t)sizeof d_, d_);                                                                     \
    } while (0)

static uint8_t node_id(void) { return co_node_id(&dev.node); }

/* Sends an SDO request and returns the server's answer (exactly one). */
static const co_frame_t *sdo(const uint8_t req[8])
{
    const uint32_t before = port.n_sent;
    const uint32_t id = 0x580U + node_id();
    rx(0x600U + node_id(), 8U, req);
    const co_frame_t *answer = NULL;
    for (uint32_t i = before; i < port.n_sent; i++) {
        if (port.sent[i].id == id) {
            TEST_ASSERT_NULL_MESSAGE(answer, "more than one SDO answer");
            answer = &port.sent[i];
        }
    }
    TEST_ASSERT_NOT_NULL_MESSAGE(answer, "no SDO answer");
    TEST_ASSERT_EQUAL_UINT8(8U, answer->len);
    return answer;
}

#define SDO_EXPECT(req0, req1, req2, req3, req4, req5, req6, req7, ...)                                      \
    do {                                                                                                      \
        const uint8_t q_[8] = {req0, req1, req2, req3, req4, req5, req6, req7};                               \
        const uint8_t e_[8] = {__VA_ARGS__};                                                                  \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(e_, sdo(q_)->data, 8);                                                   \
    } while (0)

static uint32_t abort_of(const co_frame_t *f)
{
    return (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) | ((uint32_t)f->data[6] << 16) |
           ((uint32_t)f->data[7] << 24);
}

/* Expedited write of size bytes; 0 or the abort code. */
static uint32_t wr(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    const uint8_t req[8] = {(uint8_t)(0x23U | ((4U - size) << 2)), (uint8_t)index, (uint8_t)(index >> 8), sub,
                            (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    const co_frame_t *f = sdo(req);
    if (f->data[0] == 0x80U) {
        return abort_of(f);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60U, f->data[0]);
    return 0U;
}

static void wr_ok(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    TEST_ASSERT_EQUAL_HEX32(0U, wr(index, sub, v, size));
}

/* Expedited read: the value (asserts success). */
static uint32_t rd(uint16_t index, uint8_t sub)
{
    const uint8_t req[8] = {0x40U, (uint8_t)index, (uint8_t)(index >> 8), sub, 0U, 0U, 0U, 0U};
    const co_frame_t *f = sdo(req);
    TEST_ASSERT_NOT_EQUAL_MESSAGE(0x80U, f->data[0], "read aborted");
    return abort_of(f);
}

static uint32_t rd_abort(uint16_t index, uint8_t sub)
{
    const uint8_t req[8] = {0x40U, (uint8_t)index, (uint8_t)(index >> 8), sub, 0U, 0U, 0U, 0U};
    const co_frame_t *f = sdo(req);
    TEST_ASSERT_EQUAL_HEX8(0x80U, f->data[0]);
    return abort_of(f);
}

static void save(void) { wr_ok(0x1010U, 1U, 0x65766173UL, 4U); }   /* "save" */
static void restore(void) { wr_ok(0x1011U, 1U, 0x64616F6CUL, 4U); } /* "load" */

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
    process();
    return r;
}

static void cmd_ok(const char *line) { TEST_ASSERT_EQUAL_INT_MESSAGE(DEVICE_CMD_OK, cmd(line), line); }

static void power_cycle(void)
{
    n_lines = 0U;
    cmd_ok("power-cycle");
}

static uint32_t count_id(uint32_t id, uint32_t from)
{
    uint32_t n = 0U;
    for (uint32_t i = from; i < port.n_sent; i++) {
        n += port.sent[i].id == id ? 1U : 0U;
    }
    return n;
}

static int find_id(uint32_t id, uint32_t from)
{
    for (uint32_t i = from; i < port.n_sent; i++) {
        if (port.sent[i].id == id) {
            return (int)i;
        }
    }
    return -1;
}

#define ASSERT_FRAME_AT(i, id_, len_, ...)                                                                    \
    do {                                                                                                      \
        const uint8_t x_[] = {__VA_ARGS__};                                                                   \
        TEST_ASSERT_TRUE_MESSAGE((i) >= 0 && (uint32_t)(i) < port.n_sent, "frame missing");                 \
        TEST_ASSERT_EQUAL_HEX32((id_), port.sent[(i)].id);                                                    \
        TEST_ASSERT_EQUAL_UINT8((len_), port.sent[(i)].len);                                                  \
        TEST_ASSERT_EQUAL_HEX8_ARRAY(x_, port.sent[(i)].data, (len_));                                        \
    } while (0)

/* Releases the HV through the bus (enables bit 2 of 0x2002:02 first). */
static void bus_release(uint8_t value)
{
    wr_ok(0x2002U, 0x02U, 0x06U, 1U);
    wr_ok(0x6200U, 0x01U, value, 1U);
}

static uint8_t status(void) { return (uint8_t)rd(0x6000U, 0x01U); }
static uint16_t volts(void) { return (uint16_t)rd(0x6401U, 0x01U); }

void setUp(void) { start(5U, NULL); }
void tearDown(void) {}

/* ---- HV release ------------------------------------------------------------------------------------------ */

static void bus_release_is_ignored_until_canopen_release_is_enabled(void)
{
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x2002U, 0x02U)); /* default: HMI only */
    SDO_EXPECT(0x22, 0x00, 0x62, 0x01, 0x0F, 0x00, 0x00, 0x00, 0x60, 0x00, 0x62, 0x01, 0x00, 0x00, 0x00, 0x00);
    advance_ms(500U);
    TEST_ASSERT_TRUE(logged("ignored: release via CANopen is off"));
    TEST_ASSERT_EQUAL_HEX8(0x00U, status()); /* bit 5 (software release) and bit 0 stay 0 */
    TEST_ASSERT_EQUAL_UINT16(0U, volts());
    /* values other than 0x00/0x0A/0x0F are refused even then */
    SDO_EXPECT(0x22, 0x00, 0x62, 0x01, 0x05, 0x00, 0x00, 0x00, 0x80, 0x00, 0x62, 0x01, 0x30, 0x00, 0x09, 0x06);

    wr_ok(0x2002U, 0x02U, 0x06U, 1U); /* HMI + CANopen */
    SDO_EXPECT(0x22, 0x00, 0x62, 0x01, 0x0F, 0x00, 0x00, 0x00, 0x60, 0x00, 0x62, 0x01, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status()); /* HV on, discharge active, software release */
    advance_ms(3000U);
    TEST_ASSERT_EQUAL_UINT16(5000U, volts());
    SDO_EXPECT(0x22, 0x00, 0x62, 0x01, 0x00, 0x00, 0x00, 0x00, 0x60, 0x00, 0x62, 0x01, 0x00, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    advance_ms(3000U);
    TEST_ASSERT_EQUAL_UINT16(0U, volts());
}

static void rpdo_release_and_invalid_rpdo_value_ignored(void)
{
    wr_ok(0x2002U, 0x02U, 0x04U, 1U); /* CANopen only */
    RX(0x000U, 0x01, 0x05);
    RX(0x205U, 0x05); /* not a release value: dropped */
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    RX(0x205U, 0x0F);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    RX(0x205U, 0x07);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    RX(0x205U, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
}

static void release_0x0a_starts_reference_point_in_mode_6(void)
{
    cmd_ok("load 1 2000");
    wr_ok(0x2002U, 0x08U, 2000U, 2U); /* set-point 2000 V */
    wr_ok(0x2002U, 0x2DU, 6U, 1U);    /* reference point on request via the bus */
    wr_ok(0x2002U, 0x11U, 2U, 1U);    /* calibrate connection 1 at the next reference point */
    run_until(1000000U);
    bus_release(0x0F); /* a plain release: no reference point in mode 6 */
    advance_ms(1900U);
    TEST_ASSERT_UINT16_WITHIN(5U, 2000U, volts()); /* 2000 x (1 - e^-6.3) = 1996 V: never above the set-point */
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x2002U, 0x11U));
    TEST_ASSERT_FALSE(logged("reference point started"));

    run_until(3000000U);
    wr_ok(0x6200U, 0x01U, 0x0AU, 1U); /* release + reference point: Umax for 1 s */
    TEST_ASSERT_TRUE(logged("reference point started"));
    run_until(3900000U);
    TEST_ASSERT_TRUE(volts() > 4800U); /* 2000 + 3000 x (1 - e^-3) = 4851 V */
    run_until(4000000U);
    TEST_ASSERT_TRUE(logged("reference point measured"));
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2002U, 0x11U));    /* calibrated: monitoring on */
    TEST_ASSERT_EQUAL_UINT32(2000U, rd(0x2002U, 0x15U)); /* nominal power = load at Umax */
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    run_until(7000000U);
    TEST_ASSERT_EQUAL_UINT16(2000U, volts()); /* back at the set-point */
}

static void release_timeout_drops_release_exactly_and_refresh_restarts_it(void)
{
    wr_ok(0x2002U, 0x04U, 1000U, 2U);
    run_until(2000000U);
    bus_release(0x0F); /* at t = 2.000 s */
    run_until(2999999U);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    run_until(3000000U);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    TEST_ASSERT_TRUE(logged("release timeout"));

    run_until(5000000U);
    wr_ok(0x6200U, 0x01U, 0x0FU, 1U);
    run_until(5600000U);
    wr_ok(0x6200U, 0x01U, 0x0FU, 1U); /* refresh: the timer restarts */
    run_until(6599999U);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    run_until(6600000U);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());

    /* the timeout does not apply to a keypad release */
    cmd_ok("keypad release on");
    advance_ms(5000U);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
}

static void release_timeout_below_500_ms_reads_zero(void)
{
    SDO_EXPECT(0x2B, 0x02, 0x20, 0x04, 0x2C, 0x01, 0x00, 0x00, 0x60, 0x02, 0x20, 0x04, 0x00, 0x00, 0x00, 0x00);
    SDO_EXPECT(0x40, 0x02, 0x20, 0x04, 0x00, 0x00, 0x00, 0x00, 0x4B, 0x02, 0x20, 0x04, 0x00, 0x00, 0x00, 0x00);
    wr_ok(0x2002U, 0x04U, 499U, 2U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2002U, 0x04U));
    wr_ok(0x2002U, 0x04U, 500U, 2U);
    TEST_ASSERT_EQUAL_UINT32(500U, rd(0x2002U, 0x04U));
    /* saved right after the write, the coerced value is what is stored */
    wr_ok(0x2002U, 0x04U, 300U, 2U);
    save();
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2002U, 0x04U));
    TEST_ASSERT_EQUAL_UINT16(0U, values.x2002_04);
}

static void autostart_sets_release_at_power_on_only_when_saved(void)
{
    wr_ok(0x2002U, 0x02U, 0x03U, 1U); /* autostart + HMI, not saved */
    power_cycle();
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    wr_ok(0x2002U, 0x02U, 0x03U, 1U);
    save();
    power_cycle();
    TEST_ASSERT_TRUE(logged("autostart"));
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    advance_ms(3000U);
    TEST_ASSERT_EQUAL_UINT16(5000U, volts());
}

static void hardware_release_input_is_needed_when_bit_4_is_set(void)
{
    wr_ok(0x2002U, 0x02U, 0x14U, 1U); /* CANopen + hardware release */
    wr_ok(0x6200U, 0x01U, 0x0FU, 1U);
    TEST_ASSERT_EQUAL_HEX8(0x20U, status()); /* software release only: HV stays off */
    cmd_ok("hw-release on");
    TEST_ASSERT_EQUAL_HEX8(0x71U, status()); /* + hardware release, HV on, discharge active */
    cmd_ok("hw-release off");
    TEST_ASSERT_EQUAL_HEX8(0x20U, status());
    wr_ok(0x2002U, 0x02U, 0x04U, 1U); /* without bit 4 the input is shown but not needed */
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    cmd_ok("hw-release on");
    TEST_ASSERT_EQUAL_HEX8(0x71U, status());
}

static void keypad_release_needs_hmi_bit_and_no_keyboard_lock(void)
{
    cmd_ok("keypad release on"); /* default 0x2002:02 = 2 (HMI) */
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
    cmd_ok("keypad release off");
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    wr_ok(0x2002U, 0x0FU, 1U, 1U); /* keyboard lock */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("keypad release on"));
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    wr_ok(0x2002U, 0x0FU, 0U, 1U);
    wr_ok(0x2002U, 0x02U, 0x04U, 1U); /* CANopen only */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("keypad release on"));
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
}

/* ---- Process values ----------------------------------------------------------------------------------------- */

static void voltage_settles_at_setpoint_times_percent_and_falls_to_zero(void)
{
    cmd_ok("load 1 2500");
    wr_ok(0x2002U, 0x08U, 4000U, 2U);
    wr_ok(0x2002U, 0x0BU, 50U, 1U); /* target 2000 V */
    run_until(1000000U);
    cmd_ok("keypad release on"); /* on the 100 ms grid: the first step is at 1.1 s */
    run_until(1300000U);           /* 3 steps = 1 time constant: 2000 x (1 - e^-1) = 1264 V */
    TEST_ASSERT_UINT16_WITHIN(13U, 1264U, volts());
    run_until(2500000U); /* 5 time constants: within 1 % */
    TEST_ASSERT_UINT16_WITHIN(20U, 2000U, volts());
    run_until(4000000U); /* 10 time constants: settled to the volt */
    TEST_ASSERT_EQUAL_UINT16(2000U, volts());
    run_until(6000000U); /* the integer filter reaches the target exactly after ~14 time constants */
    /* 2500 mW at 5000 V -> at 2000 V: P = 2500 x 0.16 = 400 mW, I = P / U = 200 uA */
    TEST_ASSERT_EQUAL_UINT32(200U, rd(0x6401U, 0x02U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6401U, 0x03U)); /* ion balance 100 %: no DC current */
    TEST_ASSERT_EQUAL_UINT32(4U, rd(0x6401U, 0x04U)); /* 0.4 W */
    TEST_ASSERT_EQUAL_UINT32(400U, rd(0x2001U, 0x06U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x07U));
    TEST_ASSERT_EQUAL_UINT32(2000U, rd(0x2001U, 0x01U));
    TEST_ASSERT_EQUAL_UINT32(2000U, rd(0x2001U, 0x02U));
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x6000U, 0x02U)); /* 0.4 W of 20 W */
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x6000U, 0x03U)); /* connected */
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6000U, 0x04U)); /* nothing connected */
    TEST_ASSERT_EQUAL_UINT32(0x0001U, rd(0x2001U, 0x05U));
    wr_ok(0x2002U, 0x0DU, 60U, 1U); /* ion balance 60 %: positive half-wave reduced, DC current negative */
    advance_ms(200U);
    TEST_ASSERT_EQUAL_UINT32(1800U, rd(0x2001U, 0x01U));
    TEST_ASSERT_EQUAL_UINT32(2000U, rd(0x2001U, 0x02U));
    TEST_ASSERT_EQUAL_INT16(-40, (int16_t)rd(0x6401U, 0x03U));
    cmd_ok("keypad release off");
    advance_ms(3000U);
    TEST_ASSERT_EQUAL_UINT16(0U, volts());
    advance_ms(2000U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6401U, 0x02U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6401U, 0x04U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x06U));
}

static void power_limit_reduces_voltage_and_warns(void)
{
    cmd_ok("load 1 8000");
    cmd_ok("load 2 8000");
    cmd_ok("load 3 8000");
    cmd_ok("load 4 8000"); /* 32 W at 5000 V > 20 W */
    const uint32_t first = port.n_sent;
    cmd_ok("keypad release on");
    advance_ms(6000U);
    /* U = 5000 x sqrt(20 / 32) = 3953 V */
    TEST_ASSERT_UINT16_WITHIN(1U, 3953U, volts());
    TEST_ASSERT_EQUAL_HEX32(0x0101U, rd(0x2001U, 0x05U)); /* active, voltage limiter */
    TEST_ASSERT_EQUAL_UINT32(100U, rd(0x6000U, 0x02U));
    TEST_ASSERT_EQUAL_HEX8(0x35U, status()); /* warning bit */
    const int e = find_id(0x85U, first);
    ASSERT_FRAME_AT(e, 0x85U, 8, 0x10, 0x23, 0x03, 0x05, 0x04, 0x00, 0x00, 0x00);
    /* each connection: 5 W > 4 W overload: status 3; the overload warning only with 0x2002:2E = 1 */
    TEST_ASSERT_EQUAL_UINT32(3U, rd(0x6000U, 0x03U));
    TEST_ASSERT_EQUAL_UINT32(1U, count_id(0x85U, first));
    wr_ok(0x2002U, 0x2EU, 1U, 1U);
    TEST_ASSERT_EQUAL_UINT32(5U, count_id(0x85U, first));
}

static void short_circuit_switches_hv_off_until_cleared(void)
{
    cmd_ok("keypad release on");
    advance_ms(1000U);
    const uint32_t first = port.n_sent;
    cmd_ok("load 2 short");
    const int e = find_id(0x85U, first);
    ASSERT_FRAME_AT(e, 0x85U, 8, 0x20, 0x23, 0x03, 0x01, 0x0C, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x02U, status()); /* HV off, release deleted, error */
    TEST_ASSERT_EQUAL_UINT32(4U, rd(0x6000U, 0x04U));
    cmd_ok("load 2 0");
    wr_ok(0x2003U, 0x01U, 12U, 1U); /* cause gone with the HV: can be cleared */
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6000U, 0x04U));
}

/* ---- TPDO cycle ---------------------------------------------------------------------------------------------- */

static void tpdos_every_transfer_time_in_operational_only(void)
{
    run_until(1000000U);
    advance_ms(2000U);
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x185U, 0U) + count_id(0x285U, 0U) + count_id(0x385U, 0U));
    const uint32_t first = port.n_sent;
    RX(0x000U, 0x01, 0x05); /* Operational at t = 3 s */
    run_until(5000000U);
    /* the core sends each once on entering Operational; then every 500 ms on the grid from t = 3 s */
    for (uint32_t id = 0x185U; id <= 0x385U; id += 0x100U) {
        TEST_ASSERT_EQUAL_UINT32(5U, count_id(id, first));
        uint32_t k = 0U;
        for (uint32_t i = first; i < port.n_sent; i++) {
            if (port.sent[i].id == id) {
                TEST_ASSERT_EQUAL_UINT64(3000000U + 500000U * k, port.sent_at[i]);
                k++;
            }
        }
    }
    const int t1 = find_id(0x185U, first);
    ASSERT_FRAME_AT(t1, 0x185U, 6, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00); /* status, capacity, connections */
    ASSERT_FRAME_AT(find_id(0x285U, first), 0x285U, 8, 0, 0, 0, 0, 0, 0, 0, 0);
    ASSERT_FRAME_AT(find_id(0x385U, first), 0x385U, 8, 0, 0, 0, 0, 0, 0, 0, 0);

    wr_ok(0x2002U, 0x01U, 200U, 2U); /* t = 5.0 s: a new grid starts at the write (E12) */
    const uint32_t second = port.n_sent;
    run_until(6300000U);
    uint32_t k = 0U;
    for (uint32_t i = second; i < port.n_sent; i++) {
        if (port.sent[i].id == 0x285U) {
            TEST_ASSERT_EQUAL_UINT64(5200000U + 200000U * k, port.sent_at[i]);
            k++;
        }
    }
    TEST_ASSERT_EQUAL_UINT32(6U, k); /* 5.2 5.4 5.6 5.8 6.0 6.2 */

    RX(0x000U, 0x80, 0x05); /* Pre-operational: none */
    const uint32_t third = port.n_sent;
    advance_ms(2000U);
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x185U, third) + count_id(0x285U, third) + count_id(0x385U, third));
}

static void tpdo_cycle_stays_on_its_grid_after_a_late_call(void)
{
    run_until(1000000U);
    RX(0x000U, 0x01, 0x05); /* grid: 1.5, 2.0, 2.5, ... */
    run_until(1500000U);
    const uint32_t first = port.n_sent;
    now = 2730000U; /* the emulator woke up late: 2.0 and 2.5 are skipped, one frame now */
    process();
    TEST_ASSERT_EQUAL_UINT32(1U, count_id(0x285U, first));
    TEST_ASSERT_EQUAL_UINT64(2730000U, port.sent_at[find_id(0x285U, first)]);
    const uint32_t second = port.n_sent;
    run_until(3600000U);
    TEST_ASSERT_EQUAL_UINT32(2U, count_id(0x285U, second));
    TEST_ASSERT_EQUAL_UINT64(3000000U, port.sent_at[find_id(0x285U, second)]);
}

static void tpdo_carries_the_mapped_values(void)
{
    wr_ok(0x2002U, 0x02U, 0x04U, 1U);
    cmd_ok("load 1 3500");
    const uint32_t op = port.n_sent;
    RX(0x000U, 0x01, 0x05);
    RX(0x205U, 0x0F);
    advance_ms(5000U);
    /* only cyclic frames while the voltage rises every 100 ms and the status changes (no change-of-state
     * transmissions, CO_OPT_TPDO_NO_COS): the one at entry + 10 grid points */
    TEST_ASSERT_EQUAL_UINT32(11U, count_id(0x185U, op));
    TEST_ASSERT_EQUAL_UINT32(11U, count_id(0x285U, op));
    TEST_ASSERT_EQUAL_UINT32(11U, count_id(0x385U, op));
    const uint32_t first = port.n_sent;
    advance_ms(500U);
    /* 5000 V, 700 uA, 0 uA DC, 3.5 W */
    ASSERT_FRAME_AT(find_id(0x285U, first), 0x285U, 8, 0x88, 0x13, 0xBC, 0x02, 0x00, 0x00, 0x23, 0x00);
    /* HV on + discharge + software release, capacity 17 %, connection 1 connected */
    ASSERT_FRAME_AT(find_id(0x185U, first), 0x185U, 6, 0x31, 0x11, 0x01, 0x00, 0x00, 0x00);
}

/* ---- Counters ------------------------------------------------------------------------------------------------- */

static void counters_advance_and_survive_power_cycle(void)
{
    wr_ok(0x1017U, 0x00U, 0U, 2U); /* no heartbeat: keeps the frame record small over hours */
    save();
    cmd_ok("keypad release on");
    run_until(30U * 60000000ULL); /* HV on for 30 minutes */
    cmd_ok("keypad release off");
    /* written once at the 0x1010 save (flags) and then once per emulated minute at node 5's phase, 5 s past it
     * (device_save_phase_us): the last of them at 60 min 5 s */
    run_until(60U * 60000000ULL + 5000000U - 1U);
    TEST_ASSERT_EQUAL_UINT32(1U + 60U, port.nvm[CO_NVM_DEVICE].commits);
    run_until(60U * 60000000ULL + 5000000U);
    TEST_ASSERT_EQUAL_UINT32(1U + 61U, port.nvm[CO_NVM_DEVICE].commits);
    /* the 0x1010 save's own (part of a store someone waits for) is not in the background; the minutes' are */
    TEST_ASSERT_EQUAL_UINT32(61U, port.nvm[CO_NVM_DEVICE].background_commits);
    run_until(61U * 60000000ULL + 1000000U);
    TEST_ASSERT_EQUAL_UINT32(1U + 61U, port.nvm[CO_NVM_DEVICE].commits);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x01U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x02U));
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2000U, 0x03U));
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2000U, 0x04U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x0BU));
    TEST_ASSERT_EQUAL_UINT32(30U, rd(0x2000U, 0x0CU));
    power_cycle(); /* the 56 s since the save at 60 min 5 s are lost: 1 h 0 min */
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2000U, 0x03U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x04U));
    TEST_ASSERT_EQUAL_UINT32(30U, rd(0x2000U, 0x0CU));
    /* a late call (25 h at once, landing off the 100 ms grid) still counts everything: 1 day 2 hours 0 minutes */
    now += 25ULL * 3600U * 1000000U + 50000U;
    process();
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2000U, 0x02U));
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x2000U, 0x03U));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x04U));
    TEST_ASSERT_EQUAL_UINT32(30U, rd(0x2000U, 0x0CU));
    /* the 100 ms measurement grid (from power-on) is kept across the jump */
    run_until(now + 50000U); /* back on the grid */
    cmd_ok("keypad release on");
    run_until(now + 260000U); /* 2 measurement steps: 5000 x (1 - e^-(2/3)) = 2433 V */
    TEST_ASSERT_UINT16_WITHIN(25U, 2433U, volts());
}

static void damaged_counter_memory_restarts_at_zero(void)
{
    run_until(2U * 60000000ULL + 1U);
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x2000U, 0x04U));
    port.nvm[CO_NVM_DEVICE].stored[5] ^= 0x01U; /* one bit flipped */
    power_cycle();
    TEST_ASSERT_TRUE(logged("counter memory damaged"));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2000U, 0x04U));
}

/* ---- Node-ID, bit timing, storage ----------------------------------------------------------------------------- */

static void node_id_takes_effect_only_after_save_and_reset(void)
{
    wr_ok(0x2002U, 0x06U, 10U, 1U);
    uint32_t first = port.n_sent;
    RX(0x000U, 0x81, 0x05); /* reset node without save: stays 5 */
    ASSERT_FRAME_AT(find_id(0x705U, first), 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x70AU, first));
    TEST_ASSERT_EQUAL_UINT32(5U, rd(0x2002U, 0x06U));

    wr_ok(0x2002U, 0x06U, 10U, 1U);
    save();
    TEST_ASSERT_EQUAL_UINT8(5U, node_id()); /* saving alone changes nothing */
    advance_ms(1000U);
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    first = port.n_sent;
    RX(0x000U, 0x82, 0x05); /* reset communication is "the NMT command" too (E1): boot-up on the new node-ID */
    ASSERT_FRAME_AT(find_id(0x70AU, first), 0x70AU, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x705U, first));
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    TEST_ASSERT_EQUAL_UINT32(10U, rd(0x2002U, 0x06U));
    TEST_ASSERT_EQUAL_HEX32(0x8AU, rd(0x1014U, 0x00U)); /* node-ID-relative COB-IDs follow */
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    /* and reset node: saved 0x2002:06 = 11, boot-up on 0x70B */
    wr_ok(0x2002U, 0x06U, 11U, 1U);
    save();
    first = port.n_sent;
    RX(0x000U, 0x81, 0x0A);
    ASSERT_FRAME_AT(find_id(0x70BU, first), 0x70BU, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT8(11U, node_id());
    /* the saved node-ID is the LSS configuration: without the stored parameters the node still boots on 11 */
    port.nvm[CO_NVM_PARAMS].stored_len = 0U;
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(11U, node_id());
    TEST_ASSERT_EQUAL_UINT32(11U, rd(0x2002U, 0x06U));
}

/* E15: a 0x1010 save is one store of three areas (parameters, LSS, device flags). Whichever area fails, the
 * answer is 0x06060000 and after a power cycle everything is as before the save; a confirmed save keeps all. */
static void save_failing_at_any_area_keeps_everything_old(void)
{
    for (unsigned area = 0U; area < 3U; area++) {
        start(16U, NULL);
        wr_ok(0x1017U, 0x00U, 3000U, 2U);
        wr_ok(0x2002U, 0x06U, 21U, 1U);
        port.nvm_fail_area_mask = (uint8_t)(1U << area);
        TEST_ASSERT_EQUAL_HEX32_MESSAGE(0x06060000UL, wr(0x1010U, 1U, 0x65766173UL, 4U), "save answered success");
        port.nvm_fail_area_mask = 0U;
        for (unsigned a = 0U; a < 3U; a++) {
            TEST_ASSERT_EQUAL_UINT32_MESSAGE(0U, port.nvm[a].commits, "an area of the failed save was stored");
        }
        power_cycle();
        TEST_ASSERT_EQUAL_UINT8(16U, node_id());
        TEST_ASSERT_EQUAL_UINT32(1000U, rd(0x1017U, 0x00U));
        TEST_ASSERT_EQUAL_UINT32(16U, rd(0x2002U, 0x06U));
    }
    /* the same save on a healthy port: all three areas, the new node-ID after the power cycle */
    start(16U, NULL);
    wr_ok(0x1017U, 0x00U, 3000U, 2U);
    wr_ok(0x2002U, 0x06U, 21U, 1U);
    save();
    TEST_ASSERT_EQUAL_STRING("2+1+0.", port.nvm_log);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(21U, node_id());
    TEST_ASSERT_EQUAL_UINT32(3000U, rd(0x1017U, 0x00U));
}

static void restore_defaults_keeps_node_id_and_bit_timing(void)
{
    wr_ok(0x2002U, 0x06U, 10U, 1U);
    wr_ok(0x2002U, 0x07U, 3U, 1U);
    wr_ok(0x2002U, 0x01U, 1000U, 2U);
    save();
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    TEST_ASSERT_EQUAL_UINT32(250U, port.bit_rate_kbit); /* index 3 applied through the port */
    TEST_ASSERT_EQUAL_UINT32(1000U, rd(0x2002U, 0x01U));
    restore();
    RX(0x000U, 0x81, 0x0A);
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    TEST_ASSERT_EQUAL_UINT32(500U, rd(0x2002U, 0x01U));
    TEST_ASSERT_EQUAL_UINT32(3U, rd(0x2002U, 0x07U));
    TEST_ASSERT_EQUAL_UINT32(10U, rd(0x2002U, 0x06U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    /* restore on a device that never saved keeps the node-ID it runs with */
    start(7U, NULL);
    restore();
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(7U, node_id());
    TEST_ASSERT_EQUAL_UINT32(7U, rd(0x2002U, 0x06U));
}

static void keyboard_lock_is_never_stored(void)
{
    wr_ok(0x2002U, 0x0FU, 1U, 1U);
    wr_ok(0x2002U, 0x10U, 3U, 1U); /* LED bar mode: stored */
    save();
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x2002U, 0x0FU));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2002U, 0x0FU));
    TEST_ASSERT_EQUAL_UINT32(3U, rd(0x2002U, 0x10U));
}

static void lss_stored_node_id_shows_in_0x2002_06(void)
{
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);    /* switch state global: configuration */
    RX(0x7E5U, 0x11, 20, 0, 0, 0, 0, 0, 0);      /* configure node-ID 20 */
    RX(0x7E5U, 0x17, 0, 0, 0, 0, 0, 0, 0);       /* store configuration */
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);    /* waiting */
    const uint32_t first = port.n_sent;
    RX(0x000U, 0x82, 0x05);
    ASSERT_FRAME_AT(find_id(0x714U, first), 0x714U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(20U, rd(0x2002U, 0x06U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(20U, node_id());
    TEST_ASSERT_EQUAL_UINT32(20U, rd(0x2002U, 0x06U));
    /* the newest configuration wins: a saved 0x2002:06 after the LSS store */
    wr_ok(0x2002U, 0x06U, 30U, 1U);
    save();
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(30U, node_id());
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(30U, node_id());
    /* ... and an LSS store after that saved 0x2002:06 (no reset in between) */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x11, 40, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x17, 0, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(40U, node_id());
    TEST_ASSERT_EQUAL_UINT32(40U, rd(0x2002U, 0x06U));
}

static void lss_configured_but_not_stored_is_lost_at_power_off(void)
{
    wr_ok(0x2002U, 0x06U, 10U, 1U);
    save();
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x11, 20, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    RX(0x000U, 0x81, 0x0A); /* reset node: the LSS-configured ID becomes active */
    TEST_ASSERT_EQUAL_UINT8(20U, node_id());
    TEST_ASSERT_EQUAL_UINT32(20U, rd(0x2002U, 0x06U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(10U, node_id());
}

static void bit_timing_9_deactivates_canopen_until_changed_locally(void)
{
    SDO_EXPECT(0x2F, 0x02, 0x20, 0x07, 0x05, 0x00, 0x00, 0x00, 0x80, 0x02, 0x20, 0x07, 0x30, 0x00, 0x09, 0x06);
    wr_ok(0x2002U, 0x07U, 9U, 1U);
    save();
    uint32_t first = port.n_sent;
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT8(CO_NODE_ID_UNCONFIGURED, node_id());
    TEST_ASSERT_TRUE(logged("CANopen communication deactivated"));
    advance_ms(3000U); /* no boot-up, no heartbeat, no SDO answer */
    const uint8_t req[8] = {0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
    rx(0x605U, 8U, req);
    TEST_ASSERT_EQUAL_UINT32(first, port.n_sent);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(CO_NODE_ID_UNCONFIGURED, node_id());
    TEST_ASSERT_EQUAL_UINT32(first, port.n_sent);
    cmd_ok("bit-timing 4");
    power_cycle();
    ASSERT_FRAME_AT(find_id(0x705U, first), 0x705U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT8(5U, node_id());
    TEST_ASSERT_EQUAL_UINT32(4U, rd(0x2002U, 0x07U));
}

static void bit_timing_9_applies_at_0x82_and_an_lss_store_brings_the_node_back(void)
{
    wr_ok(0x2002U, 0x07U, 9U, 1U);
    save();
    const uint32_t first = port.n_sent;
    RX(0x000U, 0x82, 0x05); /* reset communication applies it too (E1, E3) */
    TEST_ASSERT_EQUAL_UINT8(CO_NODE_ID_UNCONFIGURED, node_id());
    TEST_ASSERT_EQUAL_UINT32(first, port.n_sent);
    n_lines = 0U;
    cmd_ok("get 0x2002:07");
    TEST_ASSERT_TRUE(logged("0x2002:07 = 9"));
    /* an LSS store is newer than the saved 9: an ordinary unconfigured LSS node after the power cycle */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x17, 0, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(CO_NODE_ID_UNCONFIGURED, node_id());
    TEST_ASSERT_FALSE(logged("CANopen communication deactivated"));
    cmd_ok("get 0x2002:07");
    TEST_ASSERT_TRUE(logged("0x2002:07 = 4"));
    /* an LSS master gives the silent node a node-ID and stores it: the newest store wins */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x11, 20, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x17, 0, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    ASSERT_FRAME_AT(find_id(0x714U, first), 0x714U, 1, 0x00);
    TEST_ASSERT_EQUAL_UINT32(4U, rd(0x2002U, 0x07U));
    TEST_ASSERT_EQUAL_UINT32(20U, rd(0x2002U, 0x06U));
    power_cycle();
    TEST_ASSERT_EQUAL_UINT8(20U, node_id());
    TEST_ASSERT_EQUAL_UINT32(4U, rd(0x2002U, 0x07U));
}

static void saved_bit_timing_switches_at_any_nmt_reset_and_lss_activate_shows(void)
{
    const uint32_t calls = port.bit_rate_calls;
    wr_ok(0x2002U, 0x07U, 3U, 1U);
    save();
    advance_ms(100U);
    TEST_ASSERT_EQUAL_UINT32(calls, port.bit_rate_calls); /* saving alone changes nothing */
    RX(0x000U, 0x82, 0x05);
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, port.bit_rate_calls);
    TEST_ASSERT_EQUAL_UINT32(250U, port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT32(3U, rd(0x2002U, 0x07U));
    RX(0x000U, 0x82, 0x05); /* nothing new saved: no switch */
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, port.bit_rate_calls);
    /* written, not saved: gone at the reset */
    wr_ok(0x2002U, 0x07U, 2U, 1U);
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_UINT32(3U, rd(0x2002U, 0x07U));
    TEST_ASSERT_EQUAL_UINT32(calls + 1U, port.bit_rate_calls);
    /* LSS configure + activate bit timing: the rate in effect shows at once */
    RX(0x7E5U, 0x04, 0x01, 0, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x13, 0x00, 0x02, 0, 0, 0, 0, 0);
    RX(0x7E5U, 0x15, 0x0A, 0x00, 0, 0, 0, 0, 0); /* 10 ms */
    advance_ms(30U);
    RX(0x7E5U, 0x04, 0x00, 0, 0, 0, 0, 0, 0);
    TEST_ASSERT_EQUAL_UINT32(500U, port.bit_rate_kbit);
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x2002U, 0x07U));
}

static void local_writes_obey_the_eds_limits_and_leave_measured_values_alone(void)
{
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:06 200")); /* 1..127 */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:01 50"));  /* 100..60000 */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x1017 150"));    /* 100 ms steps */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:35 -101")); /* signed: IZD 10-110 zero point */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:35 -1001")); /* below the EDS limit as well */
    cmd_ok("set 0x2002:35 -100");
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2000:04 5"));   /* counters belong to the model */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x6401:01 100")); /* measured */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x6000:01 1"));
    TEST_ASSERT_EQUAL_UINT32(5U, rd(0x2002U, 0x06U));
    TEST_ASSERT_EQUAL_UINT32(500U, rd(0x2002U, 0x01U));
}

static void power_cycle_keeps_the_environment_and_restarts_the_device(void)
{
    wr_ok(0x1017U, 0x00U, 0U, 2U);
    cmd_ok("load 1 2500");
    cmd_ok("load 2 6000");
    cmd_ok("temperature 65"); /* warning 3: its cause is the environment */
    cmd_ok("hw-release on");
    cmd_ok("error 5");        /* parameter memory error: no cause in the environment */
    cmd_ok("keypad release on");
    advance_ms(3000U);
    TEST_ASSERT_EQUAL_HEX8(0x77U, status());
    const uint32_t first = port.n_sent;
    power_cycle();
    const int boot = find_id(0x705U, first);
    const int e = find_id(0x85U, first);
    ASSERT_FRAME_AT(boot, 0x705U, 1, 0x00);
    ASSERT_FRAME_AT(e, 0x85U, 8, 0x10, 0x42, 0x09, 0x05, 0x03, 0x00, 0x00, 0x00); /* the temperature is still 65 C */
    TEST_ASSERT_TRUE(boot < e);
    TEST_ASSERT_EQUAL_UINT32(1U, count_id(0x85U, first)); /* error 5 is gone */
    TEST_ASSERT_EQUAL_HEX8(0x44U, status()); /* no release, HV off; warning; the hardware input is still on */
    TEST_ASSERT_EQUAL_UINT16(0U, volts());
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, wr(0x2003U, 0x01U, 5U, 1U));
    TEST_ASSERT_EQUAL_UINT32(65U, rd(0x2001U, 0x04U));
    TEST_ASSERT_EQUAL_UINT32(10U, rd(0x2002U, 0x0AU) / 10U); /* still derated */
    cmd_ok("keypad release on");
    advance_ms(6000U);
    /* the loads are still connected (8.5 W at 5000 V, below the derated 10 W limit) */
    TEST_ASSERT_EQUAL_UINT16(5000U, volts());
    TEST_ASSERT_EQUAL_UINT32(2500U, rd(0x2001U, 0x06U));
    TEST_ASSERT_EQUAL_UINT32(6000U, rd(0x2001U, 0x07U));
    /* NMT reset node: the same application restart, the environment stays as well */
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_HEX8(0x44U, status());
    advance_ms(1000U);
    TEST_ASSERT_EQUAL_UINT32(65U, rd(0x2001U, 0x04U));
}

static void heartbeat_time_in_100_ms_steps(void)
{
    TEST_ASSERT_EQUAL_UINT32(1000U, rd(0x1017U, 0x00U)); /* default: every second */
    SDO_EXPECT(0x2B, 0x17, 0x10, 0x00, 0x32, 0x00, 0x00, 0x00, 0x80, 0x17, 0x10, 0x00, 0x32, 0x00, 0x09, 0x06);
    SDO_EXPECT(0x2B, 0x17, 0x10, 0x00, 0x96, 0x00, 0x00, 0x00, 0x80, 0x17, 0x10, 0x00, 0x30, 0x00, 0x09, 0x06);
    SDO_EXPECT(0x2B, 0x17, 0x10, 0x00, 0x78, 0xEB, 0x00, 0x00, 0x80, 0x17, 0x10, 0x00, 0x31, 0x00, 0x09, 0x06);
    TEST_ASSERT_EQUAL_UINT32(1000U, rd(0x1017U, 0x00U));
    wr_ok(0x1017U, 0x00U, 0U, 2U);
    wr_ok(0x1017U, 0x00U, 60000U, 2U);
    run_until(1000000U);
    wr_ok(0x1017U, 0x00U, 200U, 2U);
    const uint32_t first = port.n_sent;
    advance_ms(1000U);
    TEST_ASSERT_EQUAL_UINT32(5U, count_id(0x705U, first));
}

/* ---- Errors and warnings ------------------------------------------------------------------------------------ */

static void error_raise_and_clear_via_0x2003(void)
{
    cmd_ok("keypad release on");
    uint32_t first = port.n_sent;
    cmd_ok("error 4"); /* device over-temperature: 0x4210, temperature register bit, switches HV off */
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x10, 0x42, 0x09, 0x01, 0x04, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX32(0x09U, rd(0x1001U, 0x00U));
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x1003U, 0x00U));
    TEST_ASSERT_EQUAL_HEX32(0x04014210UL, rd(0x1003U, 0x01U));
    TEST_ASSERT_EQUAL_HEX8(0x02U, status()); /* error; HV off and release deleted */

    first = port.n_sent;
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x01, 0x04, 0x00, 0x00, 0x00, 0x60, 0x03, 0x20, 0x01, 0x00, 0x00, 0x00, 0x00);
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x00, 0x01, 0x04, 0x00, 0x00, 0x00);
    TEST_ASSERT_TRUE(find_id(0x585U, first) < find_id(0x85U, first)); /* answer first, then the confirmation */
    TEST_ASSERT_EQUAL_HEX32(0x00U, rd(0x1001U, 0x00U));
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());

    /* not active: "no data available"; not in the table: invalid value */
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x01, 0x04, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x01, 0x24, 0x00, 0x00, 0x08);
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x01, 0x07, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x01, 0x30, 0x00, 0x09, 0x06);
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x01, 0x00, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x01, 0x32, 0x00, 0x09, 0x06);
    /* cause still present: refused (device state) */
    cmd_ok("temperature 80");
    TEST_ASSERT_EQUAL_HEX8(0x06U, status()); /* error 4 and warning 3 (> 60 C) */
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x01, 0x04, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x01, 0x22, 0x00, 0x00, 0x08);
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("clear-error 4"));
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x03, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x02, 0x22, 0x00, 0x00, 0x08);
    first = port.n_sent;
    cmd_ok("temperature 30"); /* cause gone: both stay until deleted (E7) */
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x85U, first));
    TEST_ASSERT_EQUAL_HEX8(0x06U, status());
    cmd_ok("clear-warning 3");
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x09, 0x05, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x02U, status());
    cmd_ok("clear-error 4");
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
}

static void warning_raise_and_clear_via_0x2003(void)
{
    uint32_t first = port.n_sent;
    cmd_ok("warning 1"); /* supply voltage low: 0x3120, voltage register bit */
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x20, 0x31, 0x05, 0x05, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x04U, status());
    TEST_ASSERT_EQUAL_HEX32(0x01053120UL, rd(0x1003U, 0x01U));
    advance_ms(1000U); /* an injected warning stays */
    TEST_ASSERT_EQUAL_HEX8(0x04U, status());
    first = port.n_sent;
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x01, 0x00, 0x00, 0x00, 0x60, 0x03, 0x20, 0x02, 0x00, 0x00, 0x00, 0x00);
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x00, 0x05, 0x01, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x01, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x02, 0x24, 0x00, 0x00, 0x08);

    /* a warning with a cause is raised by it and stays, latched, until deleted (E7) */
    first = port.n_sent;
    cmd_ok("temperature 65");
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x10, 0x42, 0x09, 0x05, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(10U, rd(0x2002U, 0x0AU) / 10U); /* power set point derated to 10.0 W */
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x03, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x02, 0x22, 0x00, 0x00, 0x08);
    first = port.n_sent;
    cmd_ok("temperature 40");
    advance_ms(1000U);
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x85U, first));
    TEST_ASSERT_EQUAL_HEX8(0x04U, status());
    TEST_ASSERT_EQUAL_UINT32(200U, rd(0x2002U, 0x0AU)); /* the derating follows the temperature */
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x03, 0x00, 0x00, 0x00, 0x60, 0x03, 0x20, 0x02, 0x00, 0x00, 0x00, 0x00);
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x00, 0x05, 0x03, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
}

static void active_errors_are_reported_again_after_communication_reset(void)
{
    cmd_ok("error 5");
    const uint32_t first = port.n_sent;
    RX(0x000U, 0x82, 0x05);
    const int boot = find_id(0x705U, first);
    const int e = find_id(0x85U, first);
    ASSERT_FRAME_AT(boot, 0x705U, 1, 0x00);
    ASSERT_FRAME_AT(e, 0x85U, 8, 0x10, 0x63, 0x01, 0x01, 0x05, 0x00, 0x00, 0x00);
    TEST_ASSERT_TRUE(boot < e);
    TEST_ASSERT_EQUAL_HEX8(0x02U, status());
    /* reset node: the application restarts, an error without a cause is gone */
    RX(0x000U, 0x81, 0x05);
    TEST_ASSERT_EQUAL_HEX8(0x00U, status());
    TEST_ASSERT_EQUAL_HEX32(0x00U, rd(0x1001U, 0x00U));
}

static void pollution_warning_is_latched_until_deleted(void)
{
    wr_ok(0x2002U, 0x11U, 1U, 1U);     /* monitoring on */
    wr_ok(0x2002U, 0x15U, 2000U, 2U);  /* nominal power = 0 % */
    wr_ok(0x2002U, 0x19U, 1000U, 2U);  /* limit A = 100 % below */
    wr_ok(0x2002U, 0x1DU, 4000U, 2U);  /* limit B = 100 % above */
    wr_ok(0x2002U, 0x2DU, 1U, 1U);     /* reference point permanently: pollution follows continuously */
    cmd_ok("load 1 2000");
    cmd_ok("keypad release on");
    advance_ms(500U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    uint32_t first = port.n_sent;
    cmd_ok("load 1 3500"); /* (3500 - 2000) / (4000 - 2000) = 75 % > 50 % */
    advance_ms(200U);
    TEST_ASSERT_EQUAL_UINT32(75U, rd(0x2001U, 0x0AU));
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0xFF, 0x81, 0x05, 0x15, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_UINT32(2U, rd(0x6000U, 0x03U));
    TEST_ASSERT_EQUAL_HEX8(0x35U, status());
    first = port.n_sent;
    cmd_ok("load 1 1400"); /* (2000 - 1400) / (2000 - 1000) = 60 % */
    advance_ms(200U);
    TEST_ASSERT_EQUAL_UINT32(60U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x85U, first)); /* still above: nothing new */
    SDO_EXPECT(0x2F, 0x03, 0x20, 0x02, 0x15, 0x00, 0x00, 0x00, 0x80, 0x03, 0x20, 0x02, 0x22, 0x00, 0x00, 0x08);
    cmd_ok("load 1 2400"); /* 20 %: the connection is clean again, the warning stays until deleted */
    advance_ms(200U);
    TEST_ASSERT_EQUAL_UINT32(20U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x85U, first));
    TEST_ASSERT_EQUAL_UINT32(1U, rd(0x6000U, 0x03U)); /* connection status follows the pollution */
    TEST_ASSERT_EQUAL_HEX8(0x35U, status());
    wr_ok(0x2003U, 0x02U, 0x15U, 1U);
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x00, 0x05, 0x15, 0x00, 0x00, 0x00);
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
}

static void pollution_measured_at_hv_start_in_mode_0(void)
{
    wr_ok(0x2002U, 0x11U, 1U, 1U);
    wr_ok(0x2002U, 0x15U, 2000U, 2U);
    wr_ok(0x2002U, 0x19U, 1000U, 2U);
    cmd_ok("load 1 1200"); /* 80 % */
    cmd_ok("keypad release on");
    TEST_ASSERT_TRUE(logged("reference point started"));
    advance_ms(900U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    advance_ms(200U);
    TEST_ASSERT_EQUAL_UINT32(80U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_HEX8(0x35U, status());
    cmd_ok("load 1 2000"); /* not measured again until the next HV start */
    advance_ms(2000U);
    TEST_ASSERT_EQUAL_UINT32(80U, rd(0x2001U, 0x0AU));
    cmd_ok("keypad release off");
    cmd_ok("keypad release on");
    advance_ms(1100U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_HEX8(0x35U, status()); /* measured clean; the warning is latched */
    cmd_ok("clear-warning 21");
    TEST_ASSERT_EQUAL_HEX8(0x31U, status());
}

static void sensor_inputs_of_the_variants(void)
{
    wr_ok(0x2002U, 0x2FU, 2U, 1U); /* E-field sensor mode */
    uint32_t first = port.n_sent;
    cmd_ok("efield 1 900 12");
    TEST_ASSERT_EQUAL_INT16(900, (int16_t)rd(0x6401U, 0x05U));
    TEST_ASSERT_EQUAL_UINT32(12U, rd(0x6401U, 0x06U));
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x90, 0x81, 0x05, 0x1F, 0x00, 0x00, 0x00);
    first = port.n_sent;
    cmd_ok("efield 1 -1100");
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x90, 0x81, 0x01, 0x15, 0x00, 0x00, 0x00);
    /* distance range depends on the sensor type: IZD 10-110 10..50 mm */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_VALUE_HIGH, wr(0x2002U, 0x32U, 60U, 1U));
    wr_ok(0x2002U, 0x31U, 1U, 1U); /* IZD 10-510: its defaults */
    TEST_ASSERT_EQUAL_UINT32(50U, rd(0x2002U, 0x32U));
    TEST_ASSERT_EQUAL_UINT32(28000U, rd(0x2002U, 0x33U));
    wr_ok(0x2002U, 0x32U, 60U, 1U);

    wr_ok(0x2002U, 0x2FU, 1U, 1U); /* speed sensors */
    first = port.n_sent;
    cmd_ok("speed 3 100"); /* below 0x2002:30 = 300 rpm */
    TEST_ASSERT_EQUAL_UINT32(100U, rd(0x2001U, 0x10U));
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x90, 0x81, 0x05, 0x2B, 0x00, 0x00, 0x00);
    first = port.n_sent;
    cmd_ok("speed 3 500");
    TEST_ASSERT_EQUAL_UINT32(0U, count_id(0x85U, first)); /* latched */
    wr_ok(0x2003U, 0x02U, 0x2BU, 1U);
    ASSERT_FRAME_AT(find_id(0x85U, first), 0x85U, 8, 0x00, 0x00, 0x81, 0x05, 0x2B, 0x00, 0x00, 0x00);

    wr_ok(0x2002U, 0x2FU, 3U, 1U); /* extension box */
    wr_ok(0x2002U, 0x3BU, 0x0005U, 2U); /* D1 and D3 */
    cmd_ok("sensor D3 2");
    TEST_ASSERT_EQUAL_HEX32(0x0021U, rd(0x2001U, 0x18U)); /* D1 = 1, D3 = 2 */
    TEST_ASSERT_EQUAL_HEX32(0U, rd(0x2001U, 0x19U));
}

static void cyclic_reference_point_every_minute(void)
{
    wr_ok(0x2002U, 0x11U, 1U, 1U);
    wr_ok(0x2002U, 0x15U, 2000U, 2U);
    wr_ok(0x2002U, 0x19U, 1000U, 2U);
    wr_ok(0x2002U, 0x2DU, 2U, 1U); /* cyclic, 1 minute */
    cmd_ok("load 1 2000");
    cmd_ok("keypad release on"); /* t = 0: one at the HV start */
    advance_ms(1100U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    cmd_ok("load 1 1500"); /* 50 %: measured at t = 60 s, ready at 61 s */
    run_until(60900000U);
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2001U, 0x0AU));
    run_until(61000000U);
    TEST_ASSERT_EQUAL_UINT32(50U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_HEX8(0x31U, status()); /* 50 % is not above the level 50 % */
    cmd_ok("load 1 1400");
    run_until(121000000U);
    TEST_ASSERT_EQUAL_UINT32(60U, rd(0x2001U, 0x0AU));
    TEST_ASSERT_EQUAL_HEX8(0x35U, status());
}

static void commands_reply_and_reject_bad_arguments(void)
{
    n_lines = 0U;
    cmd_ok("status");
    TEST_ASSERT_TRUE(logged("variant full; HV off"));
    TEST_ASSERT_TRUE(logged("connection 1: load 1500 mW"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("load 5 100"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("load 1 20000"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("temperature hot"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("hw-release maybe"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("error 99"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("warning"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("clear-warning 3")); /* not active */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("sensor D11 1"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("bit-timing 5"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_UNKNOWN, cmd("frobnicate"));
    cmd_ok("get 0x2002:06"); /* the framework's commands still work */
    TEST_ASSERT_TRUE(logged("0x2002:06 = 5"));
    cmd_ok("supply 20000"); /* < 21.6 V: warning 1 */
    TEST_ASSERT_EQUAL_HEX8(0x04U, status());
    cmd_ok("supply 19000"); /* < 19.2 V: error 2 as well */
    TEST_ASSERT_EQUAL_HEX8(0x06U, status());
    n_lines = 0U;
    cmd_ok("status");
    TEST_ASSERT_TRUE(logged("error 2 active: supply voltage too low"));
    TEST_ASSERT_TRUE(logged("warning 1 active: supply voltage low"));
}

/* ---- Variants ---------------------------------------------------------------------------------------------------- */

static void variant_hides_entries_with_0x06090011(void)
{
    start(5U, "basic");
    SDO_EXPECT(0x40, 0x01, 0x20, 0x06, 0, 0, 0, 0, 0x80, 0x01, 0x20, 0x06, 0x11, 0x00, 0x09, 0x06);
    SDO_EXPECT(0x2F, 0x02, 0x20, 0x11, 0x01, 0, 0, 0, 0x80, 0x02, 0x20, 0x11, 0x11, 0x00, 0x09, 0x06);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, rd_abort(0x2002U, 0x2FU));
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, rd_abort(0x2001U, 0x0EU));
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6401U, 0x05U)); /* PDO-mapped: never hidden */
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x6000U, 0x03U)); /* no monitoring: 0 */
    TEST_ASSERT_EQUAL_UINT32(0U, rd(0x2002U, 0x0FU)); /* has a keypad */
    TEST_ASSERT_EQUAL_UINT32(24000U, rd(0x2001U, 0x03U)); /* supply voltage */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("set 0x2002:15 100"));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("speed 1 100"));
    /* the errors and warnings of missing features do not exist in this variant */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, wr(0x2003U, 0x01U, 21U, 1U)); /* E-field */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, wr(0x2003U, 0x02U, 11U, 1U)); /* connection monitoring */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_DATA, wr(0x2003U, 0x01U, 11U, 1U));       /* short circuit: every variant */
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("error 21"));
    n_lines = 0U;
    cmd_ok("faults");
    TEST_ASSERT_EQUAL_UINT32(13U, n_lines); /* errors 1-5, 11-14, warnings 1-4 */

    start(5U, "module");
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, rd_abort(0x2002U, 0x0FU));
    TEST_ASSERT_EQUAL_INT(DEVICE_CMD_ERROR, cmd("keypad release on"));

    start(5U, "efield"); /* sensor mode 1 (speed) is not offered */
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_INVALID_VALUE, wr(0x2002U, 0x2FU, 1U, 1U));
    wr_ok(0x2002U, 0x2FU, 2U, 1U);
    TEST_ASSERT_EQUAL_HEX32(CO_ABORT_NO_SUBINDEX, rd_abort(0x2002U, 0x30U));

    now = 0U;
    TEST_ASSERT_EQUAL_INT(CO_ERR_ARG, boot(5U, "deluxe"));
}

/* A save writes every stored row, also those the variant hides (0x2002:11-2E without connection monitoring, 0x2002:30
 * without speed): their records are skipped at the next power-on, never a reason to refuse the file. Every variant
 * but "full" refused each of its saves (CO_NVM_REFUSED, defaults; found by tests/fuzz/target_nvm_file.c). */
static void save_in_a_variant_that_hides_stored_rows_loads_after_power_cycle(void)
{
    static const char *const variants[] = {"monitor", "speed", "efield", "extbox", "basic", "module"};
    for (unsigned i = 0U; i < sizeof variants / sizeof variants[0]; i++) {
        start(5U, variants[i]);
        wr_ok(0x1017U, 0x00U, 3000U, 2U);
        save();
        power_cycle();
        TEST_ASSERT_EQUAL_INT_MESSAGE(CO_NVM_LOADED, dev.node.nvm_status, variants[i]);
        TEST_ASSERT_EQUAL_UINT32_MESSAGE(3000U, rd(0x1017U, 0x00U), variants[i]);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(bus_release_is_ignored_until_canopen_release_is_enabled);
    RUN_TEST(rpdo_release_and_invalid_rpdo_value_ignored);
    RUN_TEST(release_0x0a_starts_reference_point_in_mode_6);
    RUN_TEST(release_timeout_drops_release_exactly_and_refresh_restarts_it);
    RUN_TEST(release_timeout_below_500_ms_reads_zero);
    RUN_TEST(autostart_sets_release_at_power_on_only_when_saved);
    RUN_TEST(hardware_release_input_is_needed_when_bit_4_is_set);
    RUN_TEST(keypad_release_needs_hmi_bit_and_no_keyboard_lock);
    RUN_TEST(voltage_settles_at_setpoint_times_percent_and_falls_to_zero);
    RUN_TEST(power_limit_reduces_voltage_and_warns);
    RUN_TEST(short_circuit_switches_hv_off_until_cleared);
    RUN_TEST(tpdos_every_transfer_time_in_operational_only);
    RUN_TEST(tpdo_cycle_stays_on_its_grid_after_a_late_call);
    RUN_TEST(tpdo_carries_the_mapped_values);
    RUN_TEST(counters_advance_and_survive_power_cycle);
    RUN_TEST(damaged_counter_memory_restarts_at_zero);
    RUN_TEST(node_id_takes_effect_only_after_save_and_reset);
    RUN_TEST(save_failing_at_any_area_keeps_everything_old);
    RUN_TEST(restore_defaults_keeps_node_id_and_bit_timing);
    RUN_TEST(keyboard_lock_is_never_stored);
    RUN_TEST(lss_stored_node_id_shows_in_0x2002_06);
    RUN_TEST(lss_configured_but_not_stored_is_lost_at_power_off);
    RUN_TEST(bit_timing_9_deactivates_canopen_until_changed_locally);
    RUN_TEST(bit_timing_9_applies_at_0x82_and_an_lss_store_brings_the_node_back);
    RUN_TEST(saved_bit_timing_switches_at_any_nmt_reset_and_lss_activate_shows);
    RUN_TEST(local_writes_obey_the_eds_limits_and_leave_measured_values_alone);
    RUN_TEST(power_cycle_keeps_the_environment_and_restarts_the_device);
    RUN_TEST(heartbeat_time_in_100_ms_steps);
    RUN_TEST(error_raise_and_clear_via_0x2003);
    RUN_TEST(warning_raise_and_clear_via_0x2003);
    RUN_TEST(active_errors_are_reported_again_after_communication_reset);
    RUN_TEST(pollution_warning_is_latched_until_deleted);
    RUN_TEST(pollution_measured_at_hv_start_in_mode_0);
    RUN_TEST(cyclic_reference_point_every_minute);
    RUN_TEST(sensor_inputs_of_the_variants);
    RUN_TEST(commands_reply_and_reject_bad_arguments);
    RUN_TEST(variant_hides_entries_with_0x06090011);
    RUN_TEST(save_in_a_variant_that_hides_stored_rows_loads_after_power_cycle);
    return UNITY_END();
}
