/*
 * Bürkert mass flow controller, the representative of the Bürkert CANopen devices.
 * Object dictionary: od/buerkert-flow-controller.eds (decisions: docs/devices/buerkert-flow-controller.md).
 * Behaviour, constants, fault table and control commands: docs/devices/buerkert-behaviour.md.
 *
 * The model:
 *   - a first-order flow loop: every TICK_US the physical flow q moves towards the target by the exact
 *     discrete factor exp(-TICK/TAU); the target is the set-point 0x2540:01 clamped to 0..FULL_SCALE
 *     (0 while the flow sensor is faulty: the valve closes; frozen while the valve is stuck);
 *     0x2500:01 reports q rounded to RESOLUTION (0.0 while the sensor is faulty);
 *   - device status 0x2004: NAMUR NE 107 state/mode byte, temperature, supply voltage, operating time and
 *     min/max drag indicators (the last three kept in the port's CO_NVM_DEVICE area);
 *   - 0x2001 bus configuration: address and baud rate are saved when written and become active at the
 *     next reset; 0x2001:04 performs a communication or device reset (deferred to step());
 *   - faults raise/clear CiA EMCY codes and set the NAMUR state.
 */
#include "buerkert.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "buerkert_fc_od.h"

/* Bürkert's table (manual §2.3): index 5 = 100 kbit/s, no index 1 (800 kbit/s). */
static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 0U, 500U, 250U, 125U, 100U, 50U, 20U, 10U, 0U};

/* ---- Constants of the simulation (documented in docs/devices/buerkert-behaviour.md) ------------------ */

#define TICK_US 10000U              /* control loop / measurement period: 10 ms */
#define TAU_US 200000U              /* time constant of the flow response: 200 ms */
#define DECAY 0.951229424500714f    /* exp(-TICK_US / TAU_US) = exp(-0.05) */
#define MAX_TICKS 2000U             /* a gap longer than 2000 ticks (100 tau) jumps straight to the target */
#define FULL_SCALE 100.0f           /* nominal flow (0x2500:01/0x2540:01 range) */
#define RESOLUTION 0.01f            /* reported flow resolution */
#define SNAP 0.001f                 /* |q - target| below this: settled */
#define SAVE_PERIOD_US 60000000U    /* operating time saved every emulated minute */

#define SUPPLY_NOMINAL 24.0f
#define SUPPLY_LOW 21.6f            /* 24 V -10 % */
#define SUPPLY_HIGH 26.4f           /* 24 V +10 % */
#define TEMP_NOMINAL 25U
#define TEMP_HIGH 70U               /* device temperature above this: out of specification */

/* NAMUR NE 107 status byte 0x2004:01: bits 3..0 state, bits 5..4 mode (manual 0x2004). */
enum { NAMUR_NORMAL = 0, NAMUR_DIAGNOSE = 1, NAMUR_MAINTENANCE = 2, NAMUR_OUT_OF_SPEC = 3, NAMUR_WARNING = 4,
       NAMUR_ERROR = 5 };
enum { MODE_AUTO = 0, MODE_HAND = 1, MODE_FLASHING = 2 };

/* EMCY codes of the device's own faults. */
#define EMCY_SENSOR 0x5010U         /* device hardware: flow sensor */
#define EMCY_VALVE 0x5020U          /* device hardware: valve (actuator) */
#define EMCY_SUPPLY_HIGH 0x3110U    /* mains (supply) over-voltage */
#define EMCY_SUPPLY_LOW 0x3120U     /* mains (supply) under-voltage */
#define EMCY_TEMP_HIGH 0x4210U      /* excess temperature, device */

#define ER_GENERIC 0x01U
#define ER_CURRENT 0x02U
#define ER_VOLTAGE 0x04U
#define ER_TEMPERATURE 0x08U
#define ER_COMMUNICATION 0x10U
#define ER_PROFILE 0x20U
#define ER_MANUFACTURER 0x80U

/* Built-in faults (index into bk_model_t.active). */
enum { F_SENSOR = 0, F_VALVE, F_SUPPLY_LOW, F_SUPPLY_HIGH, F_TEMP_HIGH, F_COUNT };

typedef struct fault_def {
    uint16_t code;
    uint8_t reg;
    uint8_t namur;
} fault_def_t;

static const fault_def_t faults[F_COUNT] = {
    {EMCY_SENSOR, ER_GENERIC, NAMUR_ERROR},
    {EMCY_VALVE, ER_GENERIC, NAMUR_ERROR},
    {EMCY_SUPPLY_LOW, ER_VOLTAGE, NAMUR_OUT_OF_SPEC},
    {EMCY_SUPPLY_HIGH, ER_VOLTAGE, NAMUR_OUT_OF_SPEC},
    {EMCY_TEMP_HIGH, ER_TEMPERATURE, NAMUR_OUT_OF_SPEC},
};

#define USER_ERRORS_MAX 4U

/* ---- Persistent data: CO_NVM_DEVICE blob ----------------------------------------------------------------
 *   0  "BKF1"
 *   4  u8 version (2) | 3 bytes reserved (0)
 *   8  u32 operating time [s]
 *  12  u16 max temperature | u16 min temperature
 *  16  u32 max voltage (REAL32 bits) | u32 min voltage (REAL32 bits)
 *  24  u32 reserved (0) | u32 reserved (0)
 * The address and baud rate (0x2001:01/02) are not here: they are the LSS configuration and live in the
 * core's LSS area (co_lss_store), so LSS and 0x2001 can never disagree.
 *  32  u32 CRC-32 of bytes 0..31
 * All numbers little-endian. */
#define BLOB_LEN 36U

/* The environment (set by the temperature/supply commands): the outside world, kept over a power cycle. */
typedef struct bk_env {
    uint16_t temp_c;
    float supply_v;
} bk_env_t;

typedef struct bk_model {
    bk_env_t env;
    /* physics */
    float q;                    /* physical flow */
    float hold;                 /* flow at which the stuck valve holds */
    bool moving;
    co_time_us_t next_tick;
    /* faults and status */
    bool sensor_fault;
    bool valve_fault;
    bool active[F_COUNT];       /* built-in faults whose EMCY is raised */
    uint16_t user_code[USER_ERRORS_MAX];
    uint8_t user_state[USER_ERRORS_MAX];
    uint8_t n_user;
    uint8_t mode;
    uint8_t status;             /* last 0x2004:01 */
    /* persistent */
    uint64_t op_us;
    uint16_t tmax, tmin;
    float vmax, vmin;
    /* bus configuration */
    uint8_t baud_cfg;           /* 0x2001:01: bit rate after the next device reset */
    uint8_t baud_active;        /* bit rate the port runs at */
    uint8_t lss_active_seen;    /* core's active LSS bit timing when last looked at */
    uint8_t reset_request;      /* 0x2001:04 written: 1 = communication, 2 = device; done in step() */
    bool booting;               /* the next application reset is the power-on one */
    /* time */
    co_time_us_t last_now;
    co_time_us_t next_save;
    uint32_t saves;
} bk_model_t;

static bk_model_t *model_of(device_t *dev) { return (bk_model_t *)dev->model; }
static buerkert_fc_od_values_t *values_of(device_t *dev) { return (buerkert_fc_od_values_t *)dev->values; }

/* ---- little helpers ------------------------------------------------------------------------------------ */

static void put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void put_u32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0U; i < 4U; i++) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
}
static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint32_t float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static float bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }
static float absf(float v) { return v < 0.0f ? -v : v; }

/* The reported flow: q rounded to RESOLUTION (q is never negative). */
static float quantize(float q)
{
    const long steps = (long)(q / RESOLUTION + 0.5f);
    return (float)steps * RESOLUTION;
}

/* ---- NVM ---------------------------------------------------------------------------------------------- */

/* False when the port has storage and the blob could not be stored (true without storage: nothing to keep).
 * commit_flags: CO_NVM_BACKGROUND for the model's own saves that no answer waits for (the port may write them
 * later: 1,016 nodes' fsyncs held the emulator's loop), 0 for a write answered once it is durable. */
static bool nvm_save(device_t *dev, uint32_t commit_flags)
{
    bk_model_t *m = model_of(dev);
    const co_port_t *p = dev->cfg.port;
    if (p == NULL || p->nvm_write == NULL || p->nvm_commit == NULL) {
        return true;
    }
    uint8_t b[BLOB_LEN];
    memset(b, 0, sizeof b);
    memcpy(b, "BKF1", 4U);
    b[4] = 2U;
    put_u32(&b[8], (uint32_t)(m->op_us / 1000000U));
    put_u16(&b[12], m->tmax);
    put_u16(&b[14], m->tmin);
    put_u32(&b[16], float_bits(m->vmax));
    put_u32(&b[20], float_bits(m->vmin));
    put_u32(&b[32], co_crc32(0U, b, 32U));
    if (p->nvm_write(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, sizeof b) != CO_OK ||
        p->nvm_commit(dev->cfg.port_ctx, CO_NVM_DEVICE, BLOB_LEN | commit_flags) != CO_OK) {
        return false;
    }
    m->saves++;
    return true;
}

/* What the .device blob keeps of the model. */
typedef struct bk_stored {
    uint64_t op_us;
    co_time_us_t last_now;
    uint16_t tmax, tmin;
    float vmax, vmin;
} bk_stored_t;

static bk_stored_t stored_of(const bk_model_t *m)
{
    const bk_stored_t s = {m->op_us, m->last_now, m->tmax, m->tmin, m->vmax, m->vmin};
    return s;
}

/* A write of 0x2004 that is stored at once (the manual has no save step): answered only once it is durable,
 * else 0x06060000 with the model as it was before the write (the store rule, docs/robustness.md). */
static uint32_t store_write(device_t *dev, const bk_stored_t *before)
{
    bk_model_t *m = model_of(dev);
    if (nvm_save(dev, 0U)) {
        return CO_ABORT_NONE;
    }
    m->op_us = before->op_us;
    m->last_now = before->last_now;
    m->tmax = before->tmax;
    m->tmin = before->tmin;
    m->vmax = before->vmax;
    m->vmin = before->vmin;
    return CO_ABORT_HARDWARE;
}

/* Loads the blob; false (model left at its power-on defaults) when there is none or it is damaged. */
static bool nvm_load(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    const co_port_t *p = dev->cfg.port;
    uint8_t b[BLOB_LEN];
    if (p == NULL || p->nvm_read == NULL) {
        return false;
    }
    const co_status_t st = p->nvm_read(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, sizeof b);
    if (st == CO_ERR_NO_DATA) {
        return false; /* nothing stored yet */
    }
    if (st != CO_OK || memcmp(b, "BKF1", 4U) != 0 || b[4] != 2U || get_u32(&b[32]) != co_crc32(0U, b, 32U)) {
        device_printf(dev, "buerkert: device memory damaged; counters, drag indicators and the maximum temperature "
                           "start afresh");
        return false;
    }
    m->op_us = (uint64_t)get_u32(&b[8]) * 1000000U;
    m->tmax = get_u16(&b[12]);
    m->tmin = get_u16(&b[14]);
    m->vmax = bits_float(get_u32(&b[16]));
    m->vmin = bits_float(get_u32(&b[20]));
    if (!isfinite(m->vmax) || !isfinite(m->vmin)) {
        m->vmax = m->vmin = m->env.supply_v;
    }
    return true;
}

/* ---- model state -> object dictionary -------------------------------------------------------------- */

static uint8_t er_bits_of(uint16_t code)
{
    switch (code >> 12) {
    case 0x2:
        return ER_CURRENT;
    case 0x3:
        return ER_VOLTAGE;
    case 0x4:
        return ER_TEMPERATURE;
    case 0x8:
        return (code & 0x0F00U) == 0x0100U || (code & 0x0F00U) == 0x0200U ? ER_COMMUNICATION : ER_GENERIC;
    case 0xF:
        return (code & 0xFF00U) == 0xFF00U ? ER_MANUFACTURER : ER_GENERIC;
    default:
        return ER_GENERIC;
    }
}

static bool fault_condition(const bk_model_t *m, unsigned f)
{
    switch (f) {
    case F_SENSOR:
        return m->sensor_fault;
    case F_VALVE:
        return m->valve_fault;
    case F_SUPPLY_LOW:
        return m->env.supply_v < SUPPLY_LOW;
    case F_SUPPLY_HIGH:
        return m->env.supply_v > SUPPLY_HIGH;
    default:
        return m->env.temp_c > TEMP_HIGH;
    }
}

static uint8_t namur_status(const bk_model_t *m)
{
    uint8_t state = NAMUR_NORMAL;
    for (unsigned f = 0U; f < F_COUNT; f++) {
        if (fault_condition(m, f) && faults[f].namur > state) {
            state = faults[f].namur;
        }
    }
    for (uint8_t i = 0U; i < m->n_user; i++) {
        if (m->user_state[i] > state) {
            state = m->user_state[i];
        }
    }
    return (uint8_t)(state | (m->mode << 4));
}

/* Brings 0x2004:01 and the EMCYs of the built-in faults up to date with the model's conditions.
 * EMCY bytes 3..7 = 00 00 SS 00 00, SS = the status byte after the change. */
static void evaluate(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    m->status = namur_status(m);
    values_of(dev)->x2004_01 = m->status;
    const uint8_t msef[5] = {0U, 0U, m->status, 0U, 0U};
    for (unsigned f = 0U; f < F_COUNT; f++) {
        const bool want = fault_condition(m, f);
        if (want && !m->active[f]) {
            m->active[f] = co_emcy_raise(&dev->node, faults[f].code, faults[f].reg, msef);
        } else if (!want && m->active[f]) {
            (void)co_emcy_clear(&dev->node, faults[f].code, msef);
            m->active[f] = false;
        }
    }
}

/* Measurements into 0x2004:02/03 and the drag indicators; a new extreme is saved at once. */
static void measure(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    buerkert_fc_od_values_t *v = values_of(dev);
    bool changed = false;
    v->x2004_02 = m->env.temp_c;
    v->x2004_03 = m->env.supply_v;
    if (m->env.temp_c > m->tmax) {
        m->tmax = m->env.temp_c;
        changed = true;
    }
    if (m->env.temp_c < m->tmin) {
        m->tmin = m->env.temp_c;
        changed = true;
    }
    if (m->env.supply_v > m->vmax) {
        m->vmax = m->env.supply_v;
        changed = true;
    }
    if (m->env.supply_v < m->vmin) {
        m->vmin = m->env.supply_v;
        changed = true;
    }
    v->x2004_05 = m->tmax;
    v->x2004_06 = m->tmin;
    v->x2004_07 = m->vmax;
    v->x2004_08 = m->vmin;
    if (changed) {
        (void)nvm_save(dev, CO_NVM_BACKGROUND); /* a measured extreme: no answer waits for it; retried at the next
                                                  * change or period */
    }
}

static void update_op_time(device_t *dev, co_time_us_t now)
{
    bk_model_t *m = model_of(dev);
    if (now > m->last_now) {
        m->op_us += now - m->last_now;
        m->last_now = now;
    }
    values_of(dev)->x2004_04 = (uint32_t)(m->op_us / 1000000U);
}

static float target_flow(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    if (m->sensor_fault) {
        return 0.0f; /* no measurement: the controller closes the valve */
    }
    if (m->valve_fault) {
        return m->hold; /* the valve does not move */
    }
    const float sp = values_of(dev)->x2540_01;
    return isfinite(sp) ? clampf(sp, 0.0f, FULL_SCALE) : 0.0f;
}

static void report_flow(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    values_of(dev)->x2500_01 = m->sensor_fault ? 0.0f : quantize(m->q);
}

/* Follows LSS Activate Bit Timing (the core switched the port): that rate is now configured and active. */
static void sync_lss(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    const uint8_t active = dev->node.lss.active_bit_timing;
    if (active != m->lss_active_seen) {
        m->lss_active_seen = active;
        m->baud_cfg = m->baud_active = active;
    }
}

static void switch_bit_rate(device_t *dev, uint8_t index)
{
    bk_model_t *m = model_of(dev);
    if (index >= CO_LSS_BIT_TIMING_COUNT || bit_rates[index] == 0U || index == m->baud_active) {
        return;
    }
    if (dev->cfg.port != NULL && dev->cfg.port->set_bit_rate != NULL) {
        (void)dev->cfg.port->set_bit_rate(dev->cfg.port_ctx, bit_rates[index]);
    }
    m->baud_active = index;
    device_printf(dev, "bit rate %u kbit/s (0x2001:01 = %u)", bit_rates[index], index);
}

/* Writes every model-owned value into the OD (after an area reset put defaults there). */
static void publish(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    buerkert_fc_od_values_t *v = values_of(dev);
    v->x2001_01 = m->baud_cfg;
    v->x2001_02 = dev->node.lss.pending_node_id;
    v->x2001_04 = 0U;
    measure(dev);
    update_op_time(dev, dev->now);
    report_flow(dev);
    v->x2004_01 = m->status;
}

/* ---- class hooks --------------------------------------------------------------------------------------- */

/* The environment at the first power-on (device_init). */
static void bk_init(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    m->env.temp_c = TEMP_NOMINAL;
    m->env.supply_v = SUPPLY_NOMINAL;
}

/* A power-on: the running state starts afresh (flow 0, no faults, no injected errors, auto mode, bus
 * configuration from the core); the environment stays as it was (decision 19). */
static void bk_power_on(device_t *dev, co_time_us_t now)
{
    bk_model_t *m = model_of(dev);
    device_clear_running_state(dev, offsetof(bk_model_t, env), sizeof(bk_env_t));
    m->tmax = m->tmin = m->env.temp_c; /* drag indicators without a stored blob: the present values */
    m->vmax = m->vmin = m->env.supply_v;
    m->mode = MODE_AUTO;
    m->last_now = now;
    /* the first save at the node's phase in the first minute (at its end for phase 0), then every minute */
    const co_time_us_t phase = device_save_phase_us(dev);
    m->next_save = now + (phase != 0U ? phase : SAVE_PERIOD_US);
    m->booting = true;
    (void)nvm_load(dev);
}

/* The power-on application reset: the core loaded the stored LSS configuration (written by LSS store or
 * by a 0x2001 write, see bk_on_write) and switched the port to its bit rate already. */
static void choose_bus_config(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    const co_node_t *n = &dev->node;
    m->lss_active_seen = n->lss.active_bit_timing;
    m->baud_active = n->lss.active_bit_timing;
    m->baud_cfg = n->lss.pending_bit_timing;
}

static void bk_on_reset(device_t *dev, co_reset_t what)
{
    bk_model_t *m = model_of(dev);
    if (what == CO_RESET_APPLICATION) {
        if (m->booting) {
            m->booting = false;
            choose_bus_config(dev);
        } else {
            sync_lss(dev);
            switch_bit_rate(dev, m->baud_cfg); /* a device reset starts with the configured bit rate */
        }
        /* 0x2000-0x9FFF were re-initialised: the model's values go back in. The set-point is 0.0 again,
         * so the flow decays from where it was. */
        publish(dev);
        (void)co_lss_set_pending_node_id(&dev->node, values_of(dev)->x2001_02);
        return;
    }
    /* Communication reset: 0x1018 holds the node's serial number now (the runner may give each node its own):
     * 0x2000:07 is the same number (decision 30). */
    (void)co_od_set_u32(&dev->node, 0x2000U, 7U, co_od_get_u32(&dev->node, 0x1018U, 4U));
    /* The core dropped every active EMCY; persisting faults are raised again (sent after the boot-up). */
    memset(m->active, 0, sizeof m->active);
    values_of(dev)->x2001_02 = dev->node.lss.pending_node_id;
    evaluate(dev);
    for (uint8_t i = 0U; i < m->n_user; i++) {
        const uint8_t msef[5] = {0U, 0U, m->status, 0U, 0U};
        (void)co_emcy_raise(&dev->node, m->user_code[i], er_bits_of(m->user_code[i]), msef);
    }
}

static float wire_float(const uint8_t *data) { return bits_float(get_u32(data)); }

/* The value rules of bk_on_write without its actions: for stored values being loaded (CO_ORIGIN_NVM). */
static uint32_t check_stored(const device_t *dev, uint32_t key, const uint8_t *data)
{
    switch (key) {
    case 0x254001U:
    case 0x200403U:
    case 0x200407U:
    case 0x200408U:
        return isfinite(wire_float(data)) ? CO_ABORT_NONE : CO_ABORT_INVALID_VALUE;
    case 0x200101U:
        if (data[0] >= CO_LSS_BIT_TIMING_COUNT) {
            return CO_ABORT_VALUE_HIGH;
        }
        return dev->node.bit_rates_kbit[data[0]] != 0U ? CO_ABORT_NONE : CO_ABORT_INVALID_VALUE;
    case 0x200102U:
        return (data[0] >= 1U && data[0] <= 127U) ? CO_ABORT_NONE : CO_ABORT_INVALID_VALUE;
    case 0x200104U:
        return data[0] > 2U ? CO_ABORT_VALUE_HIGH : CO_ABORT_NONE;
    default:
        return CO_ABORT_NONE;
    }
}

static uint32_t bk_on_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len,
                            co_od_origin_t origin)
{
    bk_model_t *m = model_of(dev);
    (void)len;
    const uint32_t key = ((uint32_t)e->index << 8) | e->sub;
    if (origin == CO_ORIGIN_NVM) {
        return check_stored(dev, key, data);
    }
    /* (objects from 0x2000 on only: hooks_first_index; the communication objects are the core's) */
    const bk_stored_t before = stored_of(m);
    switch (key) {
    case 0x254001U: {
        if (!isfinite(wire_float(data))) {
            return CO_ABORT_INVALID_VALUE;
        }
        if (origin != CO_ORIGIN_LOCAL && m->mode == MODE_HAND) {
            return CO_ABORT_LOCAL_CONTROL; /* hand mode: only the local set-point acts */
        }
        return CO_ABORT_NONE;
    }
    case 0x250001U:
        return CO_ABORT_LOCAL_CONTROL; /* a measured value: the device sets it */
    case 0x200101U: {
        /* The address and baud rate are the LSS configuration: pending at once, stored at once (the manual
         * has no save step), active after the next communication (address) / device (baud) reset. A store that
         * fails refuses the write (0x06060000), and a refused write changes nothing: the pending value and the
         * configured rate go back (they stayed, showed in 0x2001:01/02 and took effect at the next reset). */
        const uint8_t pending = dev->node.lss.pending_bit_timing;
        const uint8_t cfg = m->baud_cfg;
        if (!co_lss_set_pending_bit_timing(&dev->node, data[0])) {
            return data[0] > 8U ? CO_ABORT_VALUE_HIGH : CO_ABORT_INVALID_VALUE;
        }
        m->baud_cfg = data[0];
        if (co_lss_store(&dev->node) == CO_OK) {
            return CO_ABORT_NONE;
        }
        (void)co_lss_set_pending_bit_timing(&dev->node, pending);
        m->baud_cfg = cfg;
        return CO_ABORT_HARDWARE;
    }
    case 0x200102U: {
        const uint8_t pending = dev->node.lss.pending_node_id;
        if (!co_lss_set_pending_node_id(&dev->node, data[0])) {
            return CO_ABORT_INVALID_VALUE;
        }
        if (co_lss_store(&dev->node) == CO_OK) {
            return CO_ABORT_NONE;
        }
        (void)co_lss_set_pending_node_id(&dev->node, pending);
        return CO_ABORT_HARDWARE;
    }
    case 0x200104U:
        if (data[0] > 2U) {
            return CO_ABORT_VALUE_HIGH;
        }
        /* Not here: this runs inside co_node_rx, before the SDO confirmation is sent. */
        m->reset_request = data[0];
        return CO_ABORT_NONE;
    case 0x200107U:
    case 0x200109U:
        return CO_ABORT_NONE; /* drag indicator: the read hook shows the current maximum again */
    case 0x200403U:
    case 0x200407U:
    case 0x200408U:
        if (!isfinite(wire_float(data))) {
            return CO_ABORT_INVALID_VALUE;
        }
        if (e->sub == 3U) {
            return CO_ABORT_NONE;
        }
        if (e->sub == 7U) {
            m->vmax = wire_float(data);
        } else {
            m->vmin = wire_float(data);
        }
        return store_write(dev, &before);
    case 0x200404U:
        m->op_us = (uint64_t)get_u32(data) * 1000000U;
        m->last_now = dev->now;
        return store_write(dev, &before);
    case 0x200405U:
        m->tmax = get_u16(data);
        return store_write(dev, &before);
    case 0x200406U:
        m->tmin = get_u16(data);
        return store_write(dev, &before);
    default:
        return CO_ABORT_NONE;
    }
}

static uint32_t bk_on_read(device_t *dev, const co_od_entry_t *e)
{
    buerkert_fc_od_values_t *v = values_of(dev);
    if (e->index == 0x2001U) {
        sync_lss(dev);
        v->x2001_01 = model_of(dev)->baud_cfg;
        v->x2001_02 = dev->node.lss.pending_node_id; /* the address the node has after its next reset */
        v->x2001_07 = v->x2001_06;                   /* no CAN errors are emulated: counts stay 0 */
        v->x2001_09 = v->x2001_08;
    } else if (e->index == 0x2004U && e->sub == 4U) {
        update_op_time(dev, dev->now);
    }
    return CO_ABORT_NONE;
}

static co_time_us_t bk_step(device_t *dev, co_time_us_t now)
{
    bk_model_t *m = model_of(dev);
    update_op_time(dev, now);
    sync_lss(dev);
    if (m->reset_request != 0U) {
        /* 0x2001:04 was written: the SDO confirmation is out, now the reset (see bk_on_write). */
        const co_reset_t what = m->reset_request == 1U ? CO_RESET_COMMUNICATION : CO_RESET_APPLICATION;
        m->reset_request = 0U;
        values_of(dev)->x2001_04 = 0U;
        co_node_reset(&dev->node, what, now);
    }

    const float target = target_flow(dev);
    if (!m->moving && m->q != target) {
        m->moving = true;
        m->next_tick = now + TICK_US; /* the response starts with the next control period */
    }
    if (m->moving && now >= m->next_tick && (now - m->next_tick) / TICK_US >= MAX_TICKS) {
        m->q = target; /* a very long gap: long settled */
        m->moving = false;
    }
    while (m->moving && now >= m->next_tick) {
        m->q = target + (m->q - target) * DECAY;
        if (absf(m->q - target) < SNAP) {
            m->q = target;
            m->moving = false;
        }
        m->next_tick += TICK_US;
    }
    report_flow(dev);
    measure(dev);
    evaluate(dev);

    if (now >= m->next_save) {
        (void)nvm_save(dev, CO_NVM_BACKGROUND);
        m->next_save += SAVE_PERIOD_US * (1U + (now - m->next_save) / SAVE_PERIOD_US);
    }
    co_time_us_t next = m->next_save;
    if (m->moving && m->next_tick < next) {
        next = m->next_tick;
    }
    return next;
}

/* ---- control commands ------------------------------------------------------------------------------- */

static bool parse_float(const char *text, float lo, float hi, float *out)
{
    char *end = NULL;
    const float f = strtof(text, &end);
    if (end == text || *end != '\0' || !isfinite(f) || f < lo || f > hi) {
        return false;
    }
    *out = f;
    return true;
}

static int parse_on_off(const char *text)
{
    return strcmp(text, "on") == 0 ? 1 : (strcmp(text, "off") == 0 ? 0 : -1);
}

static bool builtin_code(uint16_t code)
{
    for (unsigned f = 0U; f < F_COUNT; f++) {
        if (faults[f].code == code) {
            return true;
        }
    }
    return false;
}

static void print_status(device_t *dev)
{
    bk_model_t *m = model_of(dev);
    buerkert_fc_od_values_t *v = values_of(dev);
    static const char *const state_names[] = {"normal", "diagnose active", "maintenance required",
                                              "out of specification", "warning", "error"};
    static const char *const mode_names[] = {"auto", "hand", "flashing"};
    update_op_time(dev, dev->now);
    device_printf(dev, "set-point %g, target %g, flow %g (reported %g)%s%s", (double)v->x2540_01,
                  (double)target_flow(dev), (double)m->q, (double)v->x2500_01, m->sensor_fault ? ", SENSOR FAULT" : "",
                  m->valve_fault ? ", VALVE FAULT" : "");
    device_printf(dev, "status 0x%02X: %s, mode %s; temperature %u C (min %u, max %u); supply %g V (min %g, max %g)",
                  m->status, state_names[m->status & 0x0FU], mode_names[(m->status >> 4) & 0x03U], m->env.temp_c,
                  m->tmin, m->tmax, (double)m->env.supply_v, (double)m->vmin, (double)m->vmax);
    device_printf(dev, "operating time %lu s; bit rate index %u (configured %u); address %u (active %u)",
                  (unsigned long)(m->op_us / 1000000U), m->baud_active, m->baud_cfg, dev->node.lss.pending_node_id,
                  co_node_id(&dev->node));
    for (uint8_t i = 0U; i < m->n_user; i++) {
        device_printf(dev, "  user error 0x%04X, NAMUR state %u", m->user_code[i], m->user_state[i]);
    }
}

static device_cmd_result_t cmd_user_error(device_t *dev, int argc, const char *const *argv, bool raise)
{
    bk_model_t *m = model_of(dev);
    long long code;
    long long state = NAMUR_ERROR;
    if (argc < 2 || argc > (raise ? 3 : 2) || !device_parse_int(argv[1], 1, 0xFFFF, &code) ||
        (argc == 3 && !device_parse_int(argv[2], 1, NAMUR_ERROR, &state))) {
        device_printf(dev, raise ? "usage: error CODE [STATE 1..5]" : "usage: clear-error CODE");
        return DEVICE_CMD_ERROR;
    }
    const uint16_t c = (uint16_t)code;
    if (builtin_code(c)) {
        device_printf(dev, "error: 0x%04X belongs to a built-in fault (flow-fault, valve-fault, supply, temperature)", c);
        return DEVICE_CMD_ERROR;
    }
    uint8_t i = 0U;
    while (i < m->n_user && m->user_code[i] != c) {
        i++;
    }
    if (raise) {
        if (i == m->n_user) {
            if (m->n_user == USER_ERRORS_MAX) {
                device_printf(dev, "error: at most %u errors can be raised by command", USER_ERRORS_MAX);
                return DEVICE_CMD_ERROR;
            }
            m->n_user++;
        }
        m->user_code[i] = c;
        m->user_state[i] = (uint8_t)state;
        m->status = namur_status(m);
        const uint8_t msef[5] = {0U, 0U, m->status, 0U, 0U};
        if (!co_emcy_raise(&dev->node, c, er_bits_of(c), msef)) {
            device_printf(dev, "note: EMCY 0x%04X not raised (active error list full)", c);
        }
        evaluate(dev);
        device_printf(dev, "error 0x%04X raised, status 0x%02X", c, m->status);
        return DEVICE_CMD_OK;
    }
    if (i == m->n_user) {
        device_printf(dev, "error: 0x%04X is not raised", c);
        return DEVICE_CMD_ERROR;
    }
    m->user_code[i] = m->user_code[m->n_user - 1U];
    m->user_state[i] = m->user_state[m->n_user - 1U];
    m->n_user--;
    m->status = namur_status(m);
    const uint8_t msef[5] = {0U, 0U, m->status, 0U, 0U};
    (void)co_emcy_clear(&dev->node, c, msef);
    evaluate(dev);
    device_printf(dev, "error 0x%04X cleared, status 0x%02X", c, m->status);
    return DEVICE_CMD_OK;
}

static device_cmd_result_t bk_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
    bk_model_t *m = model_of(dev);
    const char *cmd = argv[0];
    (void)now;
    if (strcmp(cmd, "setpoint") == 0 && argc == 2) {
        float f;
        if (!parse_float(argv[1], -1.0e6f, 1.0e6f, &f)) {
            device_printf(dev, "error: '%s' is not a number", argv[1]);
            return DEVICE_CMD_ERROR;
        }
        uint8_t wire[4];
        put_u32(wire, float_bits(f));
        const uint32_t r = co_od_write(&dev->node, 0x2540U, 1U, wire, 4U, CO_ORIGIN_LOCAL);
        if (r != 0U) {
            device_printf(dev, "error: %s", co_abort_text(r));
            return DEVICE_CMD_ERROR;
        }
        device_printf(dev, "set-point %g (controller target %g)", (double)f, (double)target_flow(dev));
        return DEVICE_CMD_OK;
    }
    if ((strcmp(cmd, "flow-fault") == 0 || strcmp(cmd, "valve-fault") == 0) && argc == 2) {
        const int on = parse_on_off(argv[1]);
        if (on < 0) {
            device_printf(dev, "usage: %s on|off", cmd);
            return DEVICE_CMD_ERROR;
        }
        if (cmd[0] == 'f') {
            m->sensor_fault = on != 0;
        } else {
            if (on != 0 && !m->valve_fault) {
                m->hold = m->q;
            }
            m->valve_fault = on != 0;
        }
        report_flow(dev);
        evaluate(dev);
        device_printf(dev, "%s %s, status 0x%02X", cmd, on != 0 ? "on" : "off", m->status);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "supply") == 0 && argc == 2) {
        float f;
        if (!parse_float(argv[1], 0.0f, 60.0f, &f)) {
            device_printf(dev, "error: supply voltage 0..60 V");
            return DEVICE_CMD_ERROR;
        }
        m->env.supply_v = f;
        measure(dev);
        evaluate(dev);
        device_printf(dev, "supply %g V, status 0x%02X", (double)f, m->status);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "temperature") == 0 && argc == 2) {
        long long t;
        if (!device_parse_int(argv[1], 0, 150, &t)) {
            device_printf(dev, "error: temperature 0..150 (degrees C, whole numbers: 0x2004:02 is UNSIGNED16)");
            return DEVICE_CMD_ERROR;
        }
        m->env.temp_c = (uint16_t)t;
        measure(dev);
        evaluate(dev);
        device_printf(dev, "temperature %u C, status 0x%02X", m->env.temp_c, m->status);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "error") == 0) {
        return cmd_user_error(dev, argc, argv, true);
    }
    if (strcmp(cmd, "clear-error") == 0) {
        return cmd_user_error(dev, argc, argv, false);
    }
    if (strcmp(cmd, "mode") == 0 && argc == 2) {
        static const char *const names[] = {"auto", "hand", "flashing"};
        for (uint8_t i = 0U; i < 3U; i++) {
            if (strcmp(argv[1], names[i]) == 0) {
                m->mode = i;
                evaluate(dev);
                device_printf(dev, "mode %s, status 0x%02X", names[i], m->status);
                return DEVICE_CMD_OK;
            }
        }
        device_printf(dev, "usage: mode auto|hand|flashing");
        return DEVICE_CMD_ERROR;
    }
    if (strcmp(cmd, "status") == 0 && argc == 1) {
        print_status(dev);
        return DEVICE_CMD_OK;
    }
    return DEVICE_CMD_UNKNOWN;
}

const device_class_t buerkert_class = {
    .name = "buerkert",
    .summary = "Buerkert mass flow controller: set-point by RPDO/SDO, first-order flow, NAMUR status",
    .od = &buerkert_fc_od,
    .od_names = buerkert_fc_od_names,
    .od_units = buerkert_fc_od_units,
    .od_object_names = buerkert_fc_od_object_names,
    .default_node_id = 1U,
    .default_bit_timing = 2U,
    .core_options = CO_OPT_SDO_SEGMENTED | CO_OPT_SDO_BLOCK | CO_OPT_LSS_NO_UNCONFIGURE,
    .bit_rates_kbit = bit_rates,
    .model_size = sizeof(bk_model_t),
    .variants = NULL,
    .commands_help =
        "  setpoint VALUE            flow set-point 0x2540:01 as a local write (controller limits it to 0..100)\n"
        "  flow-fault on|off         flow sensor fault: EMCY 0x5010, NAMUR error, reads 0.0, valve closes\n"
        "  valve-fault on|off        valve stuck: EMCY 0x5020, NAMUR error, flow stays where it is\n"
        "  supply VOLTS              supply voltage (24.0; outside 21.6..26.4: EMCY 0x3120/0x3110, out of spec.)\n"
        "  temperature C             device temperature 0..150 (25; above 70: EMCY 0x4210, out of spec.)\n"
        "  error CODE [STATE]        raise any EMCY error code with NAMUR state STATE 1..5 (default 5 = error)\n"
        "  clear-error CODE          clear an error raised with 'error'\n"
        "  mode auto|hand|flashing   NAMUR mode bits; hand: bus set-points refused (0x08000021), 'setpoint' acts\n"
        "  status                    set-point, flow, faults, NAMUR status, temperature, supply, operating time",
    .init = bk_init,
    .power_on = bk_power_on,
    .on_write = bk_on_write,
    .on_read = bk_on_read,
    .hooks_first_index = 0x2000U, /* no rule for a communication object: they are the core's */
    .on_nmt_change = NULL,
    .on_reset = bk_on_reset,
    .step = bk_step,
    .command = bk_command,
};
