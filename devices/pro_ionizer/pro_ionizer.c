/*
 * Eltex PRO IONIZER (ES61) power supply. Object dictionary: od/pro-ionizer.eds (decisions:
 * docs/devices/pro-ionizer.md). Behaviour, simulation constants, error/warning table, variants, control
 * commands and the decisions taken here: docs/devices/pro-ionizer-behaviour.md (decisions "B1".."Bn").
 *
 * The model in one paragraph: a software release (autostart, keypad, CANopen 0x6200:01) and an optional
 * hardware-release input switch the high voltage on; the output voltage follows its target (0x2002:08 x
 * 0x2002:0B %) as a first-order lag sampled every 100 ms; four connections carry loads given as their power
 * at the maximum voltage (P = L x (U / Umax)^2), from which currents, powers, capacity, overload and
 * pollution follow; inputs (loads, temperature, supply, sensors) come from control commands; errors and
 * warnings come from a fixed table and go out as Eltex EMCY frames; operating/discharging time is counted
 * and kept in the port's CO_NVM_DEVICE area. Portable C99: no allocation, no clock, no OS.
 *
 * What the Eltex devices share (0x2002:06/07 as the LSS configuration, 0x1017, errors and warnings through
 * 0x2003, the 0x2002:01 TPDO grid, the 0x2000 counters in CO_NVM_DEVICE) is in devices/eltex/eltex.c
 * (rules E1..., docs/devices/eltex.md).
 */
#include "pro_ionizer.h"

#include <stddef.h>
#include <string.h>

#include "../eltex/eltex.h"
#include "pro_ionizer_od.h"

/* ---- Simulation constants (documented in pro-ionizer-behaviour.md, "Simulation model") ---------------- */
#define UMAX_V 5000U              /* maximum discharge voltage = reference-point voltage (0x2002:08 high limit) */
#define UMAX_MV 5000000ULL
#define TICK_US 100000U           /* measurement period: process values move on this grid */
#define ALPHA_Q16 18577           /* 1 - exp(-TICK / TAU) in Q16 with TAU = 300 ms */
#define SNAP_MV 4                 /* closer than this to the target: settled (integer steps stop there) */
#define CATCH_UP_TICKS 200U       /* more missed ticks than this: jump to the settled value */
#define REF_US 1000000U           /* duration of one reference-point measurement */
#define PSET_MW 20000U            /* output power limit (0x2002:0A = 200 x 0.1 W) */
#define PSET_DERATED_MW 10000U    /* ... while the temperature warning is active */
#define CONN_OVERLOAD_MW 4000U    /* connection overload threshold (actual power) */
#define LOAD_MAX_MW 10000U        /* largest load the "load" command accepts */
#define TEMP_WARN_C 60
#define TEMP_ERR_C 75
#define SUPPLY_WARN_LOW_MV 21600U
#define SUPPLY_WARN_HIGH_MV 26400U
#define SUPPLY_ERR_LOW_MV 19200U
#define SUPPLY_ERR_HIGH_MV 28800U
#define MINUTE_US 60000000ULL

#define T_ERR ELTEX_ERROR
#define T_WARN ELTEX_WARNING
#define F_HVOFF ELTEX_HV_OFF      /* switches the high voltage off and deletes the software release */

/* ---- Variants: feature groups of docs/devices/pro-ionizer.md, "Device variants" -------------------------- */
enum {
    G_KEYPAD = 0x01U,
    G_MONITOR = 0x02U,
    G_SENSOR = 0x04U,
    G_SPEED = 0x08U,
    G_EFIELD = 0x10U,
    G_EXTBOX = 0x20U,
    G_ALL = 0x3FU
};

static const char *const variants[] = {"full", "monitor", "speed", "efield", "extbox", "basic", "module", NULL};
static const uint8_t variant_groups[] = {
    G_ALL,
    G_KEYPAD | G_MONITOR,
    G_KEYPAD | G_MONITOR | G_SENSOR | G_SPEED,
    G_KEYPAD | G_MONITOR | G_SENSOR | G_EFIELD,
    G_KEYPAD | G_MONITOR | G_SENSOR | G_EXTBOX,
    G_KEYPAD,
    0U,
};

/* ---- Errors and warnings (the emulator's own table: the operating manual with the real list is not available) */

static const eltex_fault_t items[] = {
    {T_ERR, 1U, 0x5000U, 0x01U, F_HVOFF, 0U, "HV generator fault"},
    {T_ERR, 2U, 0x3120U, 0x04U, F_HVOFF, 0U, "supply voltage too low (< 19.2 V)"},
    {T_ERR, 3U, 0x3110U, 0x04U, F_HVOFF, 0U, "supply voltage too high (> 28.8 V)"},
    {T_ERR, 4U, 0x4210U, 0x08U, F_HVOFF, 0U, "device over-temperature (> 75 C)"},
    {T_ERR, 5U, 0x6310U, 0x01U, 0U, 0U, "parameter memory error"},
    {T_ERR, 11U, 0x2320U, 0x02U, F_HVOFF, 0U, "connection 1: short circuit / device defect"},
    {T_ERR, 12U, 0x2320U, 0x02U, F_HVOFF, 0U, "connection 2: short circuit / device defect"},
    {T_ERR, 13U, 0x2320U, 0x02U, F_HVOFF, 0U, "connection 3: short circuit / device defect"},
    {T_ERR, 14U, 0x2320U, 0x02U, F_HVOFF, 0U, "connection 4: short circuit / device defect"},
    {T_ERR, 21U, 0x9000U, 0x80U, 0U, G_EFIELD, "E-field sensor 1 above error level"},
    {T_ERR, 22U, 0x9000U, 0x80U, 0U, G_EFIELD, "E-field sensor 2 above error level"},
    {T_ERR, 31U, 0x9000U, 0x80U, 0U, G_EXTBOX, "sensor extension box: sensor error"},
    {T_WARN, 1U, 0x3120U, 0x04U, 0U, 0U, "supply voltage low (< 21.6 V)"},
    {T_WARN, 2U, 0x3110U, 0x04U, 0U, 0U, "supply voltage high (> 26.4 V)"},
    {T_WARN, 3U, 0x4210U, 0x08U, 0U, 0U, "device temperature high (> 60 C): power derated to 50 %"},
    {T_WARN, 4U, 0x2310U, 0x02U, 0U, 0U, "output power limited (voltage limiter active)"},
    {T_WARN, 11U, 0x2310U, 0x02U, 0U, G_MONITOR, "connection 1 overload (> 4.0 W)"},
    {T_WARN, 12U, 0x2310U, 0x02U, 0U, G_MONITOR, "connection 2 overload (> 4.0 W)"},
    {T_WARN, 13U, 0x2310U, 0x02U, 0U, G_MONITOR, "connection 3 overload (> 4.0 W)"},
    {T_WARN, 14U, 0x2310U, 0x02U, 0U, G_MONITOR, "connection 4 overload (> 4.0 W)"},
    {T_WARN, 21U, 0xFF00U, 0x80U, 0U, G_MONITOR, "connection 1 pollution above warning level"},
    {T_WARN, 22U, 0xFF00U, 0x80U, 0U, G_MONITOR, "connection 2 pollution above warning level"},
    {T_WARN, 23U, 0xFF00U, 0x80U, 0U, G_MONITOR, "connection 3 pollution above warning level"},
    {T_WARN, 24U, 0xFF00U, 0x80U, 0U, G_MONITOR, "connection 4 pollution above warning level"},
    {T_WARN, 31U, 0x9000U, 0x80U, 0U, G_EFIELD, "E-field sensor 1 above warning level"},
    {T_WARN, 32U, 0x9000U, 0x80U, 0U, G_EFIELD, "E-field sensor 2 above warning level"},
    {T_WARN, 41U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 1 below minimum"},
    {T_WARN, 42U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 2 below minimum"},
    {T_WARN, 43U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 3 below minimum"},
    {T_WARN, 44U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 4 below minimum"},
    {T_WARN, 45U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 5 below minimum"},
    {T_WARN, 46U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 6 below minimum"},
    {T_WARN, 47U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 7 below minimum"},
    {T_WARN, 48U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 8 below minimum"},
    {T_WARN, 49U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 9 below minimum"},
    {T_WARN, 50U, 0x9000U, 0x80U, 0U, G_SPEED, "speed sensor 10 below minimum"},
    {T_WARN, 51U, 0x9000U, 0x80U, 0U, G_EXTBOX, "sensor extension box: sensor warning"},
};
#define N_ITEMS (sizeof items / sizeof items[0])
typedef char pi_items_fit[N_ITEMS <= ELTEX_FAULTS_MAX ? 1 : -1]; /* one bit each in eltex_t.active */

/* ---- Model state ----------------------------------------------------------------------------------------- */

/* Inputs from the device's surroundings (set by control commands): the outside world, kept across a power
 * cycle and NMT resets; the defaults (B15) are set once by pi_init. */
typedef struct pi_env {
    uint16_t load_mw[4];    /* power each connection draws at Umax; 0 = nothing connected */
    bool shorted[4];
    int16_t temp_c;
    uint16_t supply_mv;
    bool hw_in;             /* hardware-release input */
    bool speed_on[10];
    uint16_t speed_rpm[10];
    int16_t efield_v[2];
    uint16_t ripple_v[2];
    uint8_t box[12];        /* sensor extension box: D1..D10, A1, A2, states 0..3 */
} pi_env_t;

typedef struct pi_model {
    eltex_t eltex;          /* shared Eltex state (counters, errors, TPDO grid, node-ID): first member */
    pi_env_t env;
    co_time_us_t next_tick;
    int32_t v_mv;           /* actual output voltage */
    bool limited;           /* voltage limiter active (0x2001:05 bit 8) */
    bool sw_rel;            /* software release */
    bool bus_owned;         /* the release came from the bus: the release timeout applies */
    co_time_us_t bus_t;     /* time of the last bus release */
    bool hv_on;
    bool ref_active;
    bool ref_request;
    co_time_us_t ref_end;
    co_time_us_t ref_next;
    uint8_t pollution[4];
    bool pol_warn[4];
} pi_model_t;
/* devices/eltex finds its state at dev->model: eltex_t must be the first member. */
typedef char pi_model_eltex_first[offsetof(pi_model_t, eltex) == 0U ? 1 : -1];

static pi_model_t *M(device_t *dev) { return (pi_model_t *)dev->model; }
static pro_ionizer_od_values_t *V(device_t *dev) { return (pro_ionizer_od_values_t *)dev->values; }
static uint8_t groups(const device_t *dev) { return variant_groups[dev->variant]; }
static bool has(const device_t *dev, uint8_t g) { return (groups(dev) & g) == g; }

/* LSS bit-timing table of 0x2002:07 read as CiA 305 (decision pro-ionizer.md #42): 5 unsupported, 9 = CAN off. */
static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};

/* ---- Small helpers --------------------------------------------------------------------------------------- */

static uint16_t clamp_u16(uint64_t v) { return v > 0xFFFFU ? (uint16_t)0xFFFFU : (uint16_t)v; }
static int16_t clamp_i16(int32_t v) { return v > 32767 ? (int16_t)32767 : (v < -32768 ? (int16_t)-32768 : (int16_t)v); }
static co_time_us_t min_t(co_time_us_t a, co_time_us_t b) { return a < b ? a : b; }

static const char *type_name(uint8_t type) { return type == T_ERR ? "error" : "warning"; }

/* Per-connection parameters as pointers into the values block (n = 0..3). */
static uint8_t *p_detect(device_t *dev, unsigned n)
{
    pro_ionizer_od_values_t *v = V(dev);
    uint8_t *const p[4] = {&v->x2002_11, &v->x2002_12, &v->x2002_13, &v->x2002_14};
    return p[n];
}
static uint16_t *p_nominal(device_t *dev, unsigned n)
{
    pro_ionizer_od_values_t *v = V(dev);
    uint16_t *const p[4] = {&v->x2002_15, &v->x2002_16, &v->x2002_17, &v->x2002_18};
    return p[n];
}
static uint16_t limit_a(device_t *dev, unsigned n)
{
    const pro_ionizer_od_values_t *v = V(dev);
    const uint16_t a[4] = {v->x2002_19, v->x2002_1a, v->x2002_1b, v->x2002_1c};
    return a[n];
}
static uint16_t limit_b(device_t *dev, unsigned n)
{
    const pro_ionizer_od_values_t *v = V(dev);
    const uint16_t b[4] = {v->x2002_1d, v->x2002_1e, v->x2002_1f, v->x2002_20};
    return b[n];
}
static uint8_t warn_level(device_t *dev, unsigned n)
{
    const pro_ionizer_od_values_t *v = V(dev);
    const uint8_t w[4] = {v->x2002_29, v->x2002_2a, v->x2002_2b, v->x2002_2c};
    return w[n];
}

/* Sensor input mode, or 0 when the variant lacks the mode's group. */
static uint8_t sensor_mode(device_t *dev)
{
    const uint8_t mode = V(dev)->x2002_2f;
    static const uint8_t need[4] = {0U, G_SPEED, G_EFIELD, G_EXTBOX};
    if (!has(dev, G_SENSOR) || mode > 3U || !has(dev, need[mode])) {
        return 0U;
    }
    return mode;
}

static bool monitoring_any(device_t *dev)
{
    if (!has(dev, G_MONITOR)) {
        return false;
    }
    for (unsigned n = 0U; n < 4U; n++) {
        if (*p_detect(dev, n) != 0U) {
            return true;
        }
    }
    return false;
}

/* Feature group an entry of 0x2001/0x2002 needs (0: present in every variant). pro-ionizer.md "Device variants". */
static uint8_t entry_group(uint16_t index, uint8_t sub)
{
    if (index == 0x2001U) {
        if (sub >= 0x06U && sub <= 0x0DU) {
            return G_MONITOR;
        }
        if (sub >= 0x0EU && sub <= 0x17U) {
            return G_SPEED;
        }
        if (sub == 0x18U || sub == 0x19U) {
            return G_EXTBOX;
        }
    } else if (index == 0x2002U) {
        if (sub == 0x0FU || sub == 0x10U) {
            return G_KEYPAD;
        }
        if (sub >= 0x11U && sub <= 0x2EU) {
            return G_MONITOR;
        }
        if (sub == 0x2FU) {
            return G_SENSOR;
        }
        if (sub == 0x30U) {
            return G_SPEED;
        }
        if (sub >= 0x31U && sub <= 0x3AU) {
            return G_EFIELD;
        }
        if (sub == 0x3BU) {
            return G_EXTBOX;
        }
    }
    return 0U;
}

static bool hidden(const device_t *dev, const co_od_entry_t *e)
{
    const uint8_t g = entry_group(e->index, e->sub);
    return g != 0U && !has(dev, g);
}

/* ---- Counters (0x2000, in CO_NVM_DEVICE: devices/eltex) ------------------------------------------------------- */

/* The time up to now counts with the HV state it had. */
static void advance(device_t *dev, co_time_us_t now) { eltex_count(dev, now, M(dev)->hv_on); }

/* ---- The electrical model ------------------------------------------------------------------------------- */

static uint32_t pset_mw(device_t *dev)
{
    return M(dev)->env.temp_c > TEMP_WARN_C ? PSET_DERATED_MW : PSET_MW;
}

/* Load a connection demands at Umax (a short counts as the largest load until the error switches off). */
static uint32_t demand_mw(device_t *dev, unsigned n)
{
    const pi_env_t *env = &M(dev)->env;
    return env->shorted[n] ? LOAD_MAX_MW : env->load_mw[n];
}

static bool ref_permanent(device_t *dev) { return V(dev)->x2002_2d == 1U && monitoring_any(dev); }

/* Target output voltage in mV; sets *limited when the power limit cuts it. */
static uint32_t target_mv(device_t *dev, bool *limited)
{
    pi_model_t *m = M(dev);
    const pro_ionizer_od_values_t *v = V(dev);
    *limited = false;
    if (!m->hv_on) {
        return 0U;
    }
    uint64_t t = (m->ref_active || ref_permanent(dev)) ? UMAX_MV : (uint64_t)v->x2002_08 * v->x2002_0b * 10U;
    uint64_t sum = 0U;
    for (unsigned n = 0U; n < 4U; n++) {
        sum += demand_mw(dev, n);
    }
    /* demand at t: sum x (t / Umax)^2 */
    const uint64_t p = pset_mw(dev);
    if (sum > 0U && sum * t * t > p * UMAX_MV * UMAX_MV) {
        const uint64_t lim = eltex_isqrt(p * UMAX_MV * UMAX_MV / sum);
        if (lim < t) {
            t = lim;
            *limited = true;
        }
    }
    return (uint32_t)t;
}

/* Actual power of a connection in mW at the actual voltage. */
static uint32_t conn_mw(device_t *dev, unsigned n)
{
    const uint64_t u = (uint64_t)(M(dev)->v_mv > 0 ? M(dev)->v_mv : 0);
    return (uint32_t)(((uint64_t)demand_mw(dev, n) * u * u + UMAX_MV * UMAX_MV / 2U) / (UMAX_MV * UMAX_MV));
}

static uint32_t total_mw(device_t *dev)
{
    uint32_t s = 0U;
    for (unsigned n = 0U; n < 4U; n++) {
        s += conn_mw(dev, n);
    }
    return s;
}

/* Pollution of every monitored connection from its reference power (the load at Umax). A calibration
 * (0x2002:11+n = 2) takes the reference power as the new nominal power and switches monitoring on. */
static void evaluate_pollution(device_t *dev)
{
    pi_model_t *m = M(dev);
    for (unsigned n = 0U; n < 4U; n++) {
        uint8_t *det = p_detect(dev, n);
        const uint32_t p = m->env.load_mw[n];
        if (*det == 2U) {
            *p_nominal(dev, n) = (uint16_t)(p > 3500U ? 3500U : p);
            *det = 1U;
            device_printf(dev, "pro-ionizer: connection %u calibrated: nominal power %u mW", n + 1U,
                          (unsigned)*p_nominal(dev, n));
        }
        if (*det != 1U || p == 0U) {
            m->pollution[n] = 0U;
            continue;
        }
        const uint32_t nom = *p_nominal(dev, n);
        const uint32_t a = limit_a(dev, n);
        const uint32_t b = limit_b(dev, n);
        uint32_t pol = 0U;
        if (p < nom && a < nom) {
            pol = (nom - p) * 100U / (nom - a);
        } else if (p > nom && b > nom) {
            pol = (p - nom) * 100U / (b - nom);
        }
        m->pollution[n] = (uint8_t)(pol > 100U ? 100U : pol);
    }
}

static void tick(device_t *dev)
{
    pi_model_t *m = M(dev);
    bool lim;
    const int64_t target = (int64_t)target_mv(dev, &lim);
    const int64_t diff = target - m->v_mv;
    if (diff > -SNAP_MV && diff < SNAP_MV) {
        m->v_mv = (int32_t)target;
    } else {
        m->v_mv = (int32_t)(m->v_mv + diff * ALPHA_Q16 / 65536);
    }
    if (m->hv_on && ref_permanent(dev)) {
        evaluate_pollution(dev);
    }
}

/* ---- Errors and warnings ---------------------------------------------------------------------------------- */

static void drop_release(device_t *dev, const char *why)
{
    pi_model_t *m = M(dev);
    if (m->sw_rel) {
        device_printf(dev, "pro-ionizer: software release deleted (%s)", why);
    }
    m->sw_rel = false;
    m->bus_owned = false;
    m->ref_request = false;
}

/* E-field sensor s reading after the zero-point correction (0x6401:05/07), and its magnitude. */
static int32_t efield_value(device_t *dev, unsigned s)
{
    const pro_ionizer_od_values_t *v = V(dev);
    return (int32_t)M(dev)->env.efield_v[s] - (s == 0U ? v->x2002_35 : v->x2002_3a);
}

static int32_t efield_abs(device_t *dev, unsigned s)
{
    const int32_t x = efield_value(dev, s);
    return x < 0 ? -x : x;
}

/* Whether the cause of an item is present now (inputs, parameters, state): raises it, and is the "internal
 * check" that refuses its deletion. */
static bool cause(device_t *dev, unsigned i)
{
    pi_model_t *m = M(dev);
    const pro_ionizer_od_values_t *v = V(dev);
    const eltex_fault_t *it = &items[i];
    const uint8_t mode = sensor_mode(dev);
    if (it->group != 0U && !has(dev, it->group)) {
        return false;
    }
    if (it->type == T_ERR) {
        switch (it->code) {
        case 2:
            return m->env.supply_mv < SUPPLY_ERR_LOW_MV;
        case 3:
            return m->env.supply_mv > SUPPLY_ERR_HIGH_MV;
        case 4:
            return m->env.temp_c > TEMP_ERR_C;
        case 11:
        case 12:
        case 13:
        case 14:
            return m->hv_on && m->env.shorted[it->code - 11U];
        case 21:
        case 22: {
            const unsigned s = it->code - 21U;
            return mode == 2U && efield_abs(dev, s) > (int32_t)(s == 0U ? v->x2002_34 : v->x2002_39);
        }
        case 31:
            break;
        default:
            return false;
        }
    } else {
        switch (it->code) {
        case 1:
            return m->env.supply_mv < SUPPLY_WARN_LOW_MV;
        case 2:
            return m->env.supply_mv > SUPPLY_WARN_HIGH_MV;
        case 3:
            return m->env.temp_c > TEMP_WARN_C;
        case 4:
            return m->hv_on && m->limited;
        case 11:
        case 12:
        case 13:
        case 14:
            return v->x2002_2e == 1U && m->hv_on && conn_mw(dev, it->code - 11U) > CONN_OVERLOAD_MW;
        case 21:
        case 22:
        case 23:
        case 24:
            return m->pol_warn[it->code - 21U];
        case 31:
        case 32: {
            const unsigned s = it->code - 31U;
            return mode == 2U && efield_abs(dev, s) > (int32_t)(s == 0U ? v->x2002_33 : v->x2002_38);
        }
        case 51:
            break;
        default:
            if (it->code >= 41U && it->code <= 50U) {
                const unsigned s = it->code - 41U;
                return mode == 1U && m->env.speed_on[s] && m->env.speed_rpm[s] < v->x2002_30;
            }
            return false;
        }
    }
    /* sensor extension box: error 31 = a selected sensor in state 3, warning 51 = in state 2 */
    if (mode != 3U) {
        return false;
    }
    for (unsigned s = 0U; s < 12U; s++) {
        if ((v->x2002_3b & (1U << s)) != 0U && m->env.box[s] == (it->type == T_ERR ? 3U : 2U)) {
            return true;
        }
    }
    return false;
}

static bool cause_pred(device_t *dev, unsigned i, const void *ctx)
{
    (void)ctx;
    return cause(dev, i);
}

static bool item_available(const device_t *dev, unsigned i) { return items[i].group == 0U || has(dev, items[i].group); }

/* An item was raised or deleted (devices/eltex): an HV-off error switches the HV off and deletes the
 * software release (B6); the status follows at the next publish. */
static void item_changed(device_t *dev, unsigned i, bool raised)
{
    pi_model_t *m = M(dev);
    if (raised && (items[i].flags & F_HVOFF) != 0U) {
        drop_release(dev, "error");
        m->hv_on = false;
        m->ref_active = false;
    }
}

static const eltex_class_t pi_eltex = {
    .faults = items,
    .n_faults = (uint8_t)N_ITEMS,
    .cause = cause,
    .available = item_available,
    .changed = item_changed,
    .nvm_magic = {'P', 'I', 'C', '2'},
    .hv_counter_sub = 0x09U,
    .bit_timing_9_off = true, /* "9 - CANopen Communication deactivated" (B11) */
};

/* ---- HV release --------------------------------------------------------------------------------------------- */

static bool release_conditions(device_t *dev)
{
    const pi_model_t *m = M(dev);
    const uint8_t mode = V(dev)->x2002_02;
    const bool sw_needed = (mode & 0x0FU) != 0U;
    const bool hw_needed = (mode & 0x10U) != 0U;
    return (sw_needed || hw_needed) && (!sw_needed || m->sw_rel) && (!hw_needed || m->env.hw_in);
}

static uint16_t release_timeout_ms(device_t *dev)
{
    uint16_t *t = &V(dev)->x2002_04;
    if (*t != 0U && *t < 500U) {
        *t = 0U; /* "For values less than 500 ms, the value is set to 0" (decision B5) */
    }
    return *t;
}

static co_time_us_t ref_interval_us(device_t *dev)
{
    static const uint16_t minutes[4] = {1U, 10U, 30U, 60U};
    const uint8_t mode = V(dev)->x2002_2d;
    return (mode >= 2U && mode <= 5U) ? (co_time_us_t)minutes[mode - 2U] * MINUTE_US : 0U;
}

/* ---- Publishing the model into the object dictionary ----------------------------------------------------- */

static uint8_t conn_status(device_t *dev, unsigned n)
{
    const pi_model_t *m = M(dev);
    if (!has(dev, G_MONITOR)) {
        return 0U;
    }
    if (eltex_fault_active(dev, (unsigned)eltex_fault_find(dev, T_ERR, (uint8_t)(11U + n)))) {
        return 4U;
    }
    if (m->env.load_mw[n] == 0U && !m->env.shorted[n]) {
        return 0U;
    }
    if (conn_mw(dev, n) > CONN_OVERLOAD_MW) {
        return 3U;
    }
    if (m->pol_warn[n]) {
        return 2U;
    }
    return 1U;
}

static uint8_t status_byte(device_t *dev)
{
    const pi_model_t *m = M(dev);
    uint8_t s = 0U;
    if (m->hv_on) {
        s |= 0x01U;
        if (V(dev)->x2002_0e == 1U) {
            s |= 0x10U;
        }
    }
    if (eltex_any_active(dev, T_ERR, 0U)) {
        s |= 0x02U;
    }
    if (eltex_any_active(dev, T_WARN, 0U)) {
        s |= 0x04U;
    }
    if (m->sw_rel) {
        s |= 0x20U;
    }
    if (m->env.hw_in) {
        s |= 0x40U;
    }
    return s;
}

static void publish(device_t *dev)
{
    pi_model_t *m = M(dev);
    pro_ionizer_od_values_t *v = V(dev);
    const uint64_t u_mv = (uint64_t)(m->v_mv > 0 ? m->v_mv : 0);
    const uint8_t mode = sensor_mode(dev);
    uint64_t sum_load = 0U;
    for (unsigned n = 0U; n < 4U; n++) {
        sum_load += demand_mw(dev, n);
    }
    const uint32_t p_total = total_mw(dev);
    const uint32_t i_ac = (uint32_t)((sum_load * u_mv + 12500000U) / 25000000U); /* I = P / U = L x U / Umax^2 */
    const bool in_ref = m->ref_active || (m->hv_on && ref_permanent(dev));
    const int32_t balance = in_ref ? 50 : (int32_t)v->x2002_0d;

    v->x6000_01 = status_byte(dev);
    v->x6000_02 = (uint8_t)(p_total * 100U / pset_mw(dev) > 100U ? 100U : p_total * 100U / pset_mw(dev));
    v->x6000_03 = conn_status(dev, 0U);
    v->x6000_04 = conn_status(dev, 1U);
    v->x6000_05 = conn_status(dev, 2U);
    v->x6000_06 = conn_status(dev, 3U);

    v->x6401_01 = clamp_u16((u_mv + 500U) / 1000U);
    v->x6401_02 = clamp_u16(i_ac);
    v->x6401_03 = (int16_t)((int32_t)(i_ac > 30000U ? 30000U : i_ac) * (balance - 100) / 200);
    v->x6401_04 = clamp_u16((p_total + 50U) / 100U);
    if (mode == 2U) {
        v->x6401_05 = clamp_i16(efield_value(dev, 0U));
        v->x6401_06 = m->env.ripple_v[0];
        v->x6401_07 = clamp_i16(efield_value(dev, 1U));
        v->x6401_08 = m->env.ripple_v[1];
    } else {
        v->x6401_05 = 0;
        v->x6401_06 = 0U;
        v->x6401_07 = 0;
        v->x6401_08 = 0U;
    }

    const uint32_t u_v = (uint32_t)((u_mv + 500U) / 1000U);
    const uint32_t pos_cut = balance < 100 ? (uint32_t)(100 - balance) : 0U;
    const uint32_t neg_cut = balance > 100 ? (uint32_t)(balance - 100) : 0U;
    v->x2001_01 = clamp_u16(u_v * (400U - pos_cut) / 400U);
    v->x2001_02 = clamp_u16(u_v * (400U - neg_cut) / 400U);
    v->x2001_03 = m->env.supply_mv;
    v->x2001_04 = (uint8_t)(m->env.temp_c < 0 ? 0 : (m->env.temp_c > 255 ? 255 : m->env.temp_c));
    v->x2001_05 = (uint16_t)(((v->x6000_01 & 0x10U) != 0U ? 1U : 0U) | (m->limited && m->hv_on ? 0x100U : 0U));
    uint16_t *const pw[4] = {&v->x2001_06, &v->x2001_07, &v->x2001_08, &v->x2001_09};
    uint8_t *const pol[4] = {&v->x2001_0a, &v->x2001_0b, &v->x2001_0c, &v->x2001_0d};
    for (unsigned n = 0U; n < 4U; n++) {
        *pw[n] = clamp_u16(conn_mw(dev, n));
        *pol[n] = m->pollution[n];
    }
    uint16_t *const rpm[10] = {&v->x2001_0e, &v->x2001_0f, &v->x2001_10, &v->x2001_11, &v->x2001_12,
                               &v->x2001_13, &v->x2001_14, &v->x2001_15, &v->x2001_16, &v->x2001_17};
    for (unsigned s = 0U; s < 10U; s++) {
        *rpm[s] = (mode == 1U && m->env.speed_on[s]) ? m->env.speed_rpm[s] : 0U;
    }
    uint32_t box_lo = 0U;
    uint32_t box_hi = 0U;
    if (mode == 3U) {
        for (unsigned s = 0U; s < 12U; s++) {
            const uint32_t st = (v->x2002_3b & (1U << s)) != 0U ? (uint32_t)(m->env.box[s] & 3U) : 0U;
            if (s < 8U) {
                box_lo |= st << (2U * s);
            } else {
                box_hi |= st << (2U * (s - 8U));
            }
        }
    }
    v->x2001_18 = (uint16_t)box_lo;
    v->x2001_19 = (uint16_t)box_hi;

    const uint64_t u_set = (uint64_t)v->x2002_08 * v->x2002_0b / 100U;
    v->x2002_09 = u_set > 0U ? clamp_u16((uint64_t)pset_mw(dev) * 1000U / u_set) : 0U;
    v->x2002_0a = (uint16_t)(pset_mw(dev) / 100U);
}

/* Pollution monitoring switched off or nothing connected: no pollution. Otherwise the warning compares the
 * last measured pollution with the connection's warning level (0x2002:29-2C). */
static void update_pollution_warnings(device_t *dev)
{
    pi_model_t *m = M(dev);
    for (unsigned n = 0U; n < 4U; n++) {
        const uint8_t det = *p_detect(dev, n);
        if (!has(dev, G_MONITOR) || det == 0U || m->env.load_mw[n] == 0U) {
            m->pollution[n] = 0U;
        }
        m->pol_warn[n] = has(dev, G_MONITOR) && det == 1U && m->env.load_mw[n] != 0U &&
                         m->pollution[n] > warn_level(dev, n);
    }
}

/* ---- Evaluation of the discrete state (release, reference point, errors) ----------------------------------- */

static void evaluate(device_t *dev, co_time_us_t now)
{
    pi_model_t *m = M(dev);
    const uint16_t timeout = release_timeout_ms(dev);
    if (m->sw_rel && m->bus_owned && timeout != 0U && now >= m->bus_t + (co_time_us_t)timeout * 1000U) {
        drop_release(dev, "release timeout 0x2002:04");
    }
    for (int pass = 0; pass < 2; pass++) {
        const bool on = release_conditions(dev) && !eltex_any_active(dev, T_ERR, F_HVOFF);
        if (on && !m->hv_on) {
            device_printf(dev, "pro-ionizer: high voltage on");
            if (V(dev)->x2002_2d != 6U && V(dev)->x2002_2d != 1U) {
                m->ref_request = true; /* modes 0 and 2..5: a reference point at every HV start */
            }
            m->ref_next = now + ref_interval_us(dev);
        } else if (!on && m->hv_on) {
            device_printf(dev, "pro-ionizer: high voltage off");
            m->ref_active = false;
        }
        m->hv_on = on;
        bool lim;
        (void)target_mv(dev, &lim);
        m->limited = lim;
        if (m->hv_on) {
            const co_time_us_t iv = ref_interval_us(dev);
            if (iv != 0U && now >= m->ref_next) {
                m->ref_request = true;
                m->ref_next += iv * (1U + (now - m->ref_next) / iv);
            }
            if (m->ref_active && now >= m->ref_end) {
                m->ref_active = false;
                evaluate_pollution(dev);
                device_printf(dev, "pro-ionizer: reference point measured");
            }
            if (m->ref_request && !m->ref_active) {
                m->ref_request = false;
                if (monitoring_any(dev) && !ref_permanent(dev)) {
                    m->ref_active = true;
                    m->ref_end = now + REF_US;
                    device_printf(dev, "pro-ionizer: reference point started");
                }
            }
        }
        update_pollution_warnings(dev);
        eltex_faults_raise_where(dev, cause_pred, NULL); /* may switch the HV off (second pass settles it) */
    }
}

/* ---- Hooks ------------------------------------------------------------------------------------------------- */

/* The environment at the first power-on (B15). */
static void pi_init(device_t *dev)
{
    pi_env_t *env = &M(dev)->env;
    env->load_mw[0] = 1500U; /* one ionizing bar at connection 1 */
    env->temp_c = 35;
    env->supply_mv = 24000U;
    for (unsigned s = 0U; s < 12U; s++) {
        env->box[s] = 1U;
    }
}

/* A power-on: the running state starts afresh (no release, HV off, no active items, voltage 0, the
 * measurement grid from now); the environment stays as it was. */
static void power_on(device_t *dev, co_time_us_t now)
{
    pi_model_t *m = M(dev);
    device_clear_running_state(dev, offsetof(pi_model_t, env), sizeof(pi_env_t));
    m->next_tick = now + TICK_US;
    eltex_power_on(dev, &pi_eltex, now);
}

static void on_reset(device_t *dev, co_reset_t what)
{
    pi_model_t *m = M(dev);
    if (what == CO_RESET_COMMUNICATION) {
        eltex_on_reset(dev, what); /* node-ID / bit timing view, active items reported again (E1-E4, E11) */
        return;
    }
    advance(dev, dev->now); /* the time up to the reset counts with the state it had */
    /* the device application restarts (B12): release off (autostart sets it), HV off, pollution 0 */
    m->sw_rel = (V(dev)->x2002_02 & 0x01U) != 0U;
    if (m->sw_rel) {
        device_printf(dev, "pro-ionizer: autostart: software release set");
    }
    m->bus_owned = false;
    m->hv_on = false;
    m->ref_active = false;
    m->ref_request = false;
    memset(m->pollution, 0, sizeof m->pollution);
    memset(m->pol_warn, 0, sizeof m->pol_warn);
    eltex_on_reset(dev, what); /* items whose cause is gone are forgotten (E10) */
    publish(dev);
}

static void on_nmt_change(device_t *dev, co_nmt_state_t from, co_nmt_state_t to)
{
    (void)from;
    eltex_on_nmt_change(dev, to); /* E12 */
}

/* 0x6200:01 from SDO, RPDO or the set command. */
static uint32_t write_release(device_t *dev, uint8_t value)
{
    pi_model_t *m = M(dev);
    if (value != 0x00U && value != 0x0AU && value != 0x0FU) {
        return CO_ABORT_INVALID_VALUE;
    }
    if ((V(dev)->x2002_02 & 0x04U) == 0U) {
        device_printf(dev, "pro-ionizer: 0x6200:01 = 0x%02X ignored: release via CANopen is off (0x2002:02 bit 2)",
                      value);
        return 0U; /* decision B1: accepted, no effect */
    }
    if (value == 0x00U) {
        drop_release(dev, "0x6200:01 = 0");
        return 0U;
    }
    if (!m->sw_rel) {
        device_printf(dev, "pro-ionizer: software release set by CANopen");
    }
    m->sw_rel = true;
    m->bus_owned = true;
    m->bus_t = dev->now;
    if (value == 0x0AU && V(dev)->x2002_2d == 6U) {
        m->ref_request = true;
    }
    return 0U;
}

/* Sensor-type dependent ranges of 0x2002:32-35 / 37-3A (pro-ionizer.md decision #36). */
static uint32_t check_efield(device_t *dev, uint8_t sub, const uint8_t *data)
{
    const pro_ionizer_od_values_t *v = V(dev);
    const unsigned s = sub >= 0x36U ? 1U : 0U;
    const unsigned k = (unsigned)(sub - (s == 0U ? 0x32U : 0x37U)); /* 0 distance, 1 warning, 2 error, 3 zero */
    const uint8_t type = s == 0U ? v->x2002_31 : v->x2002_36;
    static const int32_t lo[2][4] = {{10, 0, 0, -100}, {25, 0, 0, -1000}};
    static const int32_t hi[2][4] = {{50, 1000, 1000, 100}, {75, 30000, 30000, 1000}};
    int32_t val;
    if (k == 0U) {
        val = data[0];
    } else if (k == 3U) {
        val = (int16_t)(uint16_t)(data[0] | (uint16_t)(data[1] << 8));
    } else {
        val = (int32_t)(data[0] | (uint32_t)data[1] << 8);
    }
    const unsigned t = type > 1U ? 1U : type;
    if (val > hi[t][k]) {
        return CO_ABORT_VALUE_HIGH;
    }
    if (val < lo[t][k]) {
        return CO_ABORT_VALUE_LOW;
    }
    return 0U;
}

/* A new E-field sensor type loads that type's defaults for distance and levels. */
static void efield_type_defaults(device_t *dev, unsigned s, uint8_t type)
{
    pro_ionizer_od_values_t *v = V(dev);
    const uint8_t dist = type == 0U ? 25U : 50U;
    const uint16_t warn = type == 0U ? 800U : 28000U;
    const uint16_t err = type == 0U ? 1000U : 30000U;
    if (s == 0U) {
        v->x2002_32 = dist;
        v->x2002_33 = warn;
        v->x2002_34 = err;
        v->x2002_35 = 0;
    } else {
        v->x2002_37 = dist;
        v->x2002_38 = warn;
        v->x2002_39 = err;
        v->x2002_3a = 0;
    }
}

/* The value rules of 0x2002 beyond the EDS limits (no action: also for stored values being loaded). */
static uint32_t check_param(device_t *dev, uint8_t sub, const uint8_t *data)
{
    if (sub == 0x2FU) {
        static const uint8_t need[4] = {0U, G_SPEED, G_EFIELD, G_EXTBOX};
        return (data[0] <= 3U && has(dev, need[data[0]])) ? 0U : CO_ABORT_INVALID_VALUE;
    }
    if ((sub >= 0x32U && sub <= 0x35U) || (sub >= 0x37U && sub <= 0x3AU)) {
        return check_efield(dev, sub, data);
    }
    return 0U;
}

static uint32_t on_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len, co_od_origin_t origin)
{
    if (hidden(dev, e)) {
        return CO_ABORT_NO_SUBINDEX;
    }
    const bool act = origin != CO_ORIGIN_NVM; /* a stored value being loaded is only checked */
    if (e->index == 0x2003U && act) {
        advance(dev, dev->now);
    }
    const uint32_t r = eltex_on_write(dev, e, data, len, origin); /* 0x1017, 0x2002:01/07, 0x2003, E6 */
    if (r != 0U) {
        return r;
    }
    if (!act) {
        return e->index == 0x2002U ? check_param(dev, e->sub, data) : 0U;
    }
    if (e->index == 0x2003U) {
        publish(dev); /* a deleted item: status at once */
        return 0U;
    }
    if (e->index == 0x6200U && e->sub == 0x01U) {
        return write_release(dev, data[0]);
    }
    if (e->index != 0x2002U) {
        return 0U;
    }
    switch (e->sub) {
    case 0x31:
    case 0x36: {
        const unsigned s = e->sub == 0x36U ? 1U : 0U;
        const uint8_t old = s == 0U ? V(dev)->x2002_31 : V(dev)->x2002_36;
        if (data[0] != old && data[0] <= 1U) {
            efield_type_defaults(dev, s, data[0]);
        }
        return 0U;
    }
    default:
        return check_param(dev, e->sub, data);
    }
}

static uint32_t on_read(device_t *dev, const co_od_entry_t *e)
{
    if (hidden(dev, e)) {
        return CO_ABORT_NO_SUBINDEX;
    }
    if (e->index == 0x2002U && e->sub == 0x04U) {
        (void)release_timeout_ms(dev); /* a value below 500 reads (and is saved) as 0 */
    }
    return 0U;
}

static co_time_us_t step(device_t *dev, co_time_us_t now)
{
    pi_model_t *m = M(dev);
    advance(dev, now);
    if (m->next_tick <= now) {
        const co_time_us_t missed = (now - m->next_tick) / TICK_US + 1U;
        if (missed > CATCH_UP_TICKS) {
            bool lim;
            m->v_mv = (int32_t)target_mv(dev, &lim); /* a long jump: settled */
            tick(dev);
            m->next_tick += missed * TICK_US;
        } else {
            while (m->next_tick <= now) {
                tick(dev);
                m->next_tick += TICK_US;
            }
        }
    }
    evaluate(dev, now);
    publish(dev);

    co_time_us_t next = min_t(m->next_tick, eltex_tpdo_step(dev, now)); /* TPDO1-3 on the 0x2002:01 grid */
    const uint16_t timeout = release_timeout_ms(dev);
    if (m->sw_rel && m->bus_owned && timeout != 0U) {
        next = min_t(next, m->bus_t + (co_time_us_t)timeout * 1000U);
    }
    if (m->ref_active) {
        next = min_t(next, m->ref_end);
    }
    if (m->hv_on && ref_interval_us(dev) != 0U) {
        next = min_t(next, m->ref_next);
    }
    return next;
}

/* ---- Control commands --------------------------------------------------------------------------------------- */

static bool parse_on_off(const char *s, bool *out)
{
    if (strcmp(s, "on") == 0 || strcmp(s, "1") == 0) {
        *out = true;
        return true;
    }
    if (strcmp(s, "off") == 0 || strcmp(s, "0") == 0) {
        *out = false;
        return true;
    }
    return false;
}

static device_cmd_result_t bad(device_t *dev, const char *usage)
{
    device_printf(dev, "error: usage: %s", usage);
    return DEVICE_CMD_ERROR;
}

static device_cmd_result_t need_group(device_t *dev, const char *what)
{
    device_printf(dev, "error: variant '%s' has no %s", variants[dev->variant], what);
    return DEVICE_CMD_ERROR;
}

static void print_status(device_t *dev)
{
    pi_model_t *m = M(dev);
    const pro_ionizer_od_values_t *v = V(dev);
    bool lim;
    const uint32_t target = target_mv(dev, &lim);
    device_printf(dev, "variant %s; HV %s (release: software %s%s, hardware input %s, mode 0x2002:02 = 0x%02X)%s%s",
                  variants[dev->variant], m->hv_on ? "on" : "off", m->sw_rel ? "set" : "not set",
                  m->sw_rel && m->bus_owned ? " by CANopen" : "", m->env.hw_in ? "on" : "off", v->x2002_02,
                  m->ref_active ? ", reference point running" : "",
                  co_node_id(&dev->node) == CO_NODE_ID_UNCONFIGURED ? ", CANopen deactivated (LSS only)" : "");
    device_printf(dev, "voltage %u V (target %u V%s), current %u uA, power %u.%u W, capacity %u %%", v->x6401_01,
                  (unsigned)((target + 500U) / 1000U), lim ? ", power-limited" : "", v->x6401_02,
                  (unsigned)(v->x6401_04 / 10U), (unsigned)(v->x6401_04 % 10U), v->x6000_02);
    for (unsigned n = 0U; n < 4U; n++) {
        device_printf(dev, "connection %u: load %s%u mW, power %u mW, status %u, pollution %u %%", n + 1U,
                      m->env.shorted[n] ? "SHORT " : "", (unsigned)m->env.load_mw[n], (unsigned)conn_mw(dev, n),
                      conn_status(dev, n), m->pollution[n]);
    }
    device_printf(dev, "temperature %d C, supply %u mV, operating %lu min, discharging %lu min",
                  (int)m->env.temp_c, (unsigned)m->env.supply_mv, (unsigned long)(m->eltex.op_us / MINUTE_US),
                  (unsigned long)(m->eltex.hv_us / MINUTE_US));
    for (unsigned i = 0U; i < N_ITEMS; i++) {
        if (eltex_fault_active(dev, i)) {
            device_printf(dev, "%s %u active: %s", type_name(items[i].type), items[i].code, items[i].text);
        }
    }
}

static int box_sensor(const char *name)
{
    static const char *const names[12] = {"D1", "D2", "D3", "D4", "D5", "D6", "D7", "D8", "D9", "D10", "A1", "A2"};
    for (int i = 0; i < 12; i++) {
        if (strcmp(name, names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

static device_cmd_result_t command(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
    pi_model_t *m = M(dev);
    const char *cmd = argv[0];
    long long a;
    long long b;
    bool on;
    if (strcmp(cmd, "status") == 0) {
        print_status(dev);
        return DEVICE_CMD_OK;
    }
    advance(dev, now);
    const device_cmd_result_t fr = eltex_fault_command(dev, argc, argv); /* error, warning, clear-..., faults */
    if (fr != DEVICE_CMD_UNKNOWN) {
        publish(dev);
        return fr;
    }
    if (strcmp(cmd, "load") == 0) {
        if (argc != 3 || !device_parse_int(argv[1], 1, 4, &a)) {
            return bad(dev, "load N MILLIWATT|short   (N = 1..4, 0..10000 mW at 5000 V; 0 = nothing connected)");
        }
        const unsigned n = (unsigned)(a - 1);
        if (strcmp(argv[2], "short") == 0) {
            m->env.shorted[n] = true;
        } else if (device_parse_int(argv[2], 0, LOAD_MAX_MW, &b)) {
            m->env.shorted[n] = false;
            m->env.load_mw[n] = (uint16_t)b;
        } else {
            return bad(dev, "load N MILLIWATT|short   (N = 1..4, 0..10000 mW at 5000 V; 0 = nothing connected)");
        }
        device_printf(dev, "connection %u: %s%u mW at 5000 V", n + 1U, m->env.shorted[n] ? "short circuit, " : "",
                      (unsigned)m->env.load_mw[n]);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "temperature") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], -40, 150, &a)) {
            return bad(dev, "temperature CELSIUS   (-40..150)");
        }
        m->env.temp_c = (int16_t)a;
        device_printf(dev, "temperature %lld C", a);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "supply") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 40000, &a)) {
            return bad(dev, "supply MILLIVOLT   (0..40000)");
        }
        m->env.supply_mv = (uint16_t)a;
        device_printf(dev, "supply %lld mV", a);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "hw-release") == 0) {
        if (argc != 2 || !parse_on_off(argv[1], &on)) {
            return bad(dev, "hw-release on|off");
        }
        m->env.hw_in = on;
        device_printf(dev, "hardware-release input %s", on ? "on" : "off");
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "keypad") == 0) {
        if (argc != 3 || strcmp(argv[1], "release") != 0 || !parse_on_off(argv[2], &on)) {
            return bad(dev, "keypad release on|off");
        }
        if (!has(dev, G_KEYPAD)) {
            return need_group(dev, "keypad");
        }
        if ((V(dev)->x2002_02 & 0x02U) == 0U) {
            device_printf(dev, "error: keypad release refused: HMI release is off (0x2002:02 bit 1)");
            return DEVICE_CMD_ERROR;
        }
        if (V(dev)->x2002_0f != 0U) {
            device_printf(dev, "error: keypad release refused: keyboard locked (0x2002:0F)");
            return DEVICE_CMD_ERROR;
        }
        if (on) {
            m->sw_rel = true;
            m->bus_owned = false;
            device_printf(dev, "software release set by the keypad");
        } else {
            drop_release(dev, "keypad");
            device_printf(dev, "software release deleted by the keypad");
        }
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "speed") == 0) {
        if (!has(dev, G_SPEED)) {
            return need_group(dev, "speed sensors");
        }
        if (argc != 3 || !device_parse_int(argv[1], 1, 10, &a)) {
            return bad(dev, "speed N RPM|off   (N = 1..10)");
        }
        const unsigned s = (unsigned)(a - 1);
        if (strcmp(argv[2], "off") == 0) {
            m->env.speed_on[s] = false;
            m->env.speed_rpm[s] = 0U;
        } else if (device_parse_int(argv[2], 0, 65535, &b)) {
            m->env.speed_on[s] = true;
            m->env.speed_rpm[s] = (uint16_t)b;
        } else {
            return bad(dev, "speed N RPM|off   (N = 1..10)");
        }
        device_printf(dev, "speed sensor %u: %s", s + 1U, m->env.speed_on[s] ? argv[2] : "not connected");
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "efield") == 0) {
        if (!has(dev, G_EFIELD)) {
            return need_group(dev, "E-field sensors");
        }
        long long r = 0;
        if ((argc != 3 && argc != 4) || !device_parse_int(argv[1], 1, 2, &a) ||
            !device_parse_int(argv[2], -32768, 32767, &b) || (argc == 4 && !device_parse_int(argv[3], 0, 65535, &r))) {
            return bad(dev, "efield N VOLT [RIPPLE]   (N = 1..2)");
        }
        m->env.efield_v[(size_t)(a - 1)] = (int16_t)b;
        m->env.ripple_v[(size_t)(a - 1)] = (uint16_t)r;
        device_printf(dev, "E-field sensor %lld: %lld V, ripple %lld V", a, b, r);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "sensor") == 0) {
        if (!has(dev, G_EXTBOX)) {
            return need_group(dev, "sensor extension box");
        }
        const int s = argc == 3 ? box_sensor(argv[1]) : -1;
        if (s < 0 || !device_parse_int(argv[2], 0, 3, &a)) {
            return bad(dev, "sensor D1..D10|A1|A2 STATE   (0 off, 1 ok, 2 warning, 3 error)");
        }
        m->env.box[s] = (uint8_t)a;
        device_printf(dev, "extension box sensor %s: state %lld", argv[1], a);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "bit-timing") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 9, &a) || a == 5) {
            return bad(dev, "bit-timing N   (0..9 without 5; stored at once, active after power-cycle)");
        }
        V(dev)->x2002_07 = (uint8_t)a;
        const uint8_t sig[4] = {'s', 'a', 'v', 'e'};
        const uint32_t r = co_od_write(&dev->node, 0x1010U, 0x01U, sig, sizeof sig, CO_ORIGIN_LOCAL);
        if (r != 0U) {
            device_printf(dev, "error: parameters not stored: %s (0x%08lX)", co_abort_text(r), (unsigned long)r);
            return DEVICE_CMD_ERROR;
        }
        device_printf(dev, "bit timing %lld stored (with all parameters); active after the next power-cycle", a);
        return DEVICE_CMD_OK;
    }
    return DEVICE_CMD_UNKNOWN;
}

const device_class_t pro_ionizer_class = {
    .name = "pro-ionizer",
    .summary = "Eltex PRO IONIZER power supply (ES61): HV release, discharge values, counters",
    .od = &pro_ionizer_od,
    .od_names = pro_ionizer_od_names,
    .od_units = pro_ionizer_od_units,
    .od_object_names = pro_ionizer_od_object_names,
    .default_node_id = 99U,
    .default_bit_timing = 4U,
    .core_options = CO_OPT_NMT_ACCEPT_LONG | CO_OPT_TPDO_NO_COS, /* TPDOs: the 0x2002:01 grid only (E12) */
    .bit_rates_kbit = bit_rates,
    .model_size = sizeof(pi_model_t),
    .variants = variants,
    .commands_help =
        "  status                      model state: release, HV, voltage, loads, errors\n"
        "  load N MW|short             connection N (1-4): load in mW at 5000 V (0 = none), or a short circuit\n"
        "  temperature C               device temperature (warning > 60, error > 75)\n"
        "  supply MV                   supply voltage in mV (warnings < 21600 / > 26400, errors < 19200 / > 28800)\n"
        "  hw-release on|off           hardware-release input (needed when 0x2002:02 bit 4 is set)\n"
        "  keypad release on|off       release via the keypad (0x2002:02 bit 1, not while 0x2002:0F locks it)\n"
        "  speed N RPM|off             speed sensor N (1-10), variants full/speed\n"
        "  efield N VOLT [RIPPLE]      E-field sensor N (1-2) reading, variants full/efield\n"
        "  sensor D1..D10|A1|A2 STATE  extension-box sensor state 0-3, variants full/extbox\n"
        "  bit-timing N                keypad menu: set 0x2002:07 and store all parameters (way back from 9)\n"
        ELTEX_FAULT_COMMANDS_HELP,
    .init = pi_init,
    .power_on = power_on,
    .on_write = on_write,
    .on_read = on_read,
    .on_nmt_change = on_nmt_change,
    .on_reset = on_reset,
    .step = step,
    .command = command,
    .on_event = eltex_on_event,
    .on_store = eltex_on_store,
};
