/*
 * Eltex SDS ionising bar. Object dictionary: od/sds.eds (decisions: docs/devices/sds.md).
 * Behaviour, simulation model and its constants, error/warning table, control commands and the numbered
 * decisions (D1...) quoted below: docs/devices/sds-behaviour.md.
 *
 * What the Eltex devices share (0x2002:06/07 as the LSS configuration, 0x1017, errors and warnings through
 * 0x2003, the 0x2002:01 TPDO grid, the 0x2000 counters in CO_NVM_DEVICE, blob "SDSM") is in
 * devices/eltex/eltex.c (rules E1..., docs/devices/eltex.md).
 *
 * Portable like the core: no allocation, no clock (time is the `now` argument), no OS. The model state is
 * sds_model_t in the caller's memory (device_t.model).
 */
#include "sds.h"

#include <stddef.h>
#include <string.h>

#include "../eltex/eltex.h"
#include "sds_od.h"

/* ---- Constants of the simulation (docs/devices/sds-behaviour.md, "Simulation model") ------------------ */

#define SEC_US 1000000ULL
#define TICK_US 100000ULL              /* measurement period: 100 ms, on a grid from power-on */
#define CATCH_UP_TICKS 200U            /* more missed ticks than this: the earlier ones are not simulated */
#define RELEASE_US (10ULL * SEC_US)    /* HV release timeout of 0x6200:01 */
#define FILTER_A_Q16 11880             /* first order, tau 0.5 s: 1 - exp(-0.1 / 0.5) = 0.18127 in Q16 */
#define SNAP_Q8 128                    /* a voltage within 0.5 V of its target takes the target */
#define V_ONSET 2000                   /* corona onset, V */
#define V_NOM_BASE 3000                /* nominal voltage per polarity = 3000 V + 200 V/cm * distance */
#define V_NOM_PER_CM 200
#define I_MAX_UA 150                   /* generator limit per polarity, µA (capacity 100 %) */
#define DUTY_PERCENT 50U               /* share of the positive phase of the pulse period */

#define POLLUTION_WARN 80
#define POLLUTION_ERROR 100
#define CAPACITY_WARN 90
#define CAPACITY_ERROR 100
#define SUPPLY_NOMINAL_DV 240          /* 24.0 V */
#define SUPPLY_WARN_LOW_DV 216         /* ±10 % */
#define SUPPLY_WARN_HIGH_DV 264
#define SUPPLY_ERROR_LOW_DV 192        /* ±20 % */
#define SUPPLY_ERROR_HIGH_DV 288
#define TEMP_DEFAULT_C 35
#define TEMP_WARN_C 60
#define TEMP_ERROR_C 70
#define G_DEFAULT_PS 375U              /* 5 % of the default pollution factor 75 */
#define AIR_DEFAULT 5                  /* µA per kV above the onset */

#define STATUS_HV 0x01U
#define STATUS_ERROR 0x02U
#define STATUS_WARNING 0x04U

enum { VARIANT_N = 0, VARIANT_E = 1 };

/* ---- Error / warning table (the numbers are the emulator's choice, D8) ---------------------------------- */

enum fault_id {
    F_E_SHORT,
    F_E_OVERLOAD,
    F_E_POLLUTION,
    F_E_SUPPLY_LOW,
    F_E_SUPPLY_HIGH,
    F_E_TEMP,
    F_E_HV_GENERATOR,
    F_E_PARAM_MEMORY,
    F_E_INTERNAL,
    F_W_POLLUTION,
    F_W_CAPACITY,
    F_W_SUPPLY,
    F_W_TEMP,
    F_COUNT
};

#define E_ ELTEX_ERROR
#define W_ ELTEX_WARNING
#define HV ELTEX_HV_OFF

static const eltex_fault_t faults[F_COUNT] = {
    {E_, 0x01U, 0x2320U, 0x02U, HV, 0U, "HV short circuit / arcing"},
    {E_, 0x02U, 0x2310U, 0x02U, HV, 0U, "HV overload (capacity >= 100 %)"},
    {E_, 0x03U, 0x2300U, 0x02U, HV, 0U, "pollution error (>= 100 % of the pollution factor)"},
    {E_, 0x04U, 0x3120U, 0x04U, HV, 0U, "supply voltage too low (< 19.2 V)"},
    {E_, 0x05U, 0x3110U, 0x04U, HV, 0U, "supply voltage too high (> 28.8 V)"},
    {E_, 0x06U, 0x4210U, 0x08U, HV, 0U, "over-temperature (>= 70 C)"},
    {E_, 0x07U, 0x3300U, 0x04U, HV, 0U, "HV generator fault (set voltage not reached)"},
    {E_, 0x08U, 0x6300U, 0x00U, 0U, 0U, "parameter memory error"},
    {E_, 0x09U, 0x6100U, 0x80U, HV, 0U, "internal error"},
    {W_, 0x01U, 0x2300U, 0x02U, 0U, 0U, "pollution warning (>= 80 % of the pollution factor)"},
    {W_, 0x02U, 0x2310U, 0x02U, 0U, 0U, "capacity warning (>= 90 %)"},
    {W_, 0x03U, 0x3100U, 0x04U, 0U, 0U, "supply voltage out of tolerance (outside 21.6-26.4 V)"},
    {W_, 0x04U, 0x4200U, 0x08U, 0U, 0U, "temperature high (>= 60 C)"},
};

#undef E_
#undef W_
#undef HV

/* ---- Model state ---------------------------------------------------------------------------------------- */

/* The outside world, set by the input commands: kept over a power cycle (and NMT resets). */
typedef struct sds_env {
    uint32_t g_ps;             /* pollution conductance between the tip rows, pS */
    int32_t load_ua;           /* web charge current, µA (+ = positively charged web) */
    int32_t air;               /* air ionisation, µA per kV above the onset */
    int32_t supply_dv;         /* supply voltage, 0.1 V */
    int32_t temp_c;            /* internal temperature, °C */
} sds_env_t;

typedef struct sds_model {
    eltex_t eltex;             /* shared Eltex state (counters, faults, TPDO grid, node-ID): first member */
    sds_env_t env;
    co_time_us_t tick_next;    /* next measurement tick */
    co_time_us_t release_until;/* end of the HV release (valid while released) */
    int32_t vp_q8;             /* measured positive / negative voltage magnitudes, V * 256 */
    int32_t vn_q8;
    bool released;             /* 0x6200:01 = 0x0F received and not timed out / revoked */
    bool hv_on;                /* HV generator on (status bit 0) */
} sds_model_t;
/* devices/eltex finds its state at dev->model: eltex_t must be the first member. */
typedef char sds_model_eltex_first[offsetof(sds_model_t, eltex) == 0U ? 1 : -1];

typedef struct readings {
    int32_t vp, vn;            /* V */
    int32_t iap, ian;          /* active currents, µA (negative polarity <= 0) */
    int32_t ilp, iln;          /* leakage currents */
    int32_t ipp, ipn;          /* passive discharge currents */
    int32_t veff, ieff, idc;
    int32_t bal, cap, poll;
} readings_t;

static const uint16_t bit_rates[CO_LSS_BIT_TIMING_COUNT] = {1000U, 800U, 500U, 250U, 125U, 0U, 50U, 20U, 10U, 0U};
static const char *const variants[] = {"N", "E", NULL};

static sds_model_t *model(device_t *dev) { return (sds_model_t *)dev->model; }
static sds_od_values_t *vals(device_t *dev) { return (sds_od_values_t *)dev->values; }

/* ---- Small arithmetic helpers --------------------------------------------------------------------------- */

static int64_t div_round(int64_t a, int64_t b) /* a >= 0, b > 0 */
{
    return (a + b / 2) / b;
}

static int32_t clamp16(int64_t x) { return (int32_t)(x > 32767 ? 32767 : (x < -32768 ? -32768 : x)); }
static int32_t clamp_u8(int64_t x) { return (int32_t)(x > 255 ? 255 : (x < 0 ? 0 : x)); }

/* round(sqrt((a^2 + b^2) / 2)): the RMS of a square wave with 50 % duty cycle. */
static int32_t rms2(int32_t a, int32_t b)
{
    const uint64_t q = (uint64_t)((int64_t)a * a) + (uint64_t)((int64_t)b * b);
    uint64_t s = eltex_isqrt(q / 2U);
    if (q >= 2U * s * s + 2U * s + 1U) {
        s++;
    }
    return (int32_t)s;
}
/* ---- The physical model --------------------------------------------------------------------------------- */

static void distance_range(const device_t *dev, uint8_t *lo, uint8_t *hi)
{
    *lo = dev->variant == VARIANT_E ? 15U : 10U;
    *hi = dev->variant == VARIANT_E ? 30U : 15U;
}

static int32_t v_nominal(device_t *dev) { return V_NOM_BASE + V_NOM_PER_CM * (int32_t)vals(dev)->x2002_08; }

/* Set voltages per polarity from the working distance and the balance 0x2002:04 (D9). */
static void set_voltages(device_t *dev, int32_t *vsp, int32_t *vsn)
{
    const int32_t nom = v_nominal(dev);
    int32_t s = (int32_t)vals(dev)->x2002_04;
    s = s < 1 ? 1 : (s > 99 ? 99 : s);
    if (s <= 50) {
        *vsn = nom;
        *vsp = (int32_t)div_round((int64_t)nom * s, 100 - s);
    } else {
        *vsp = nom;
        *vsn = (int32_t)div_round((int64_t)nom * (100 - s), s);
    }
}

/* Every reading from the two voltage magnitudes and the inputs (all integer, as documented). */
static void compute(device_t *dev, int32_t vp, int32_t vn, readings_t *r)
{
    const sds_model_t *m = model(dev);
    const int64_t nom = v_nominal(dev);
    const int64_t g = m->env.g_ps;
    const int64_t pf = vals(dev)->x2002_02;
    int32_t vsp, vsn;
    set_voltages(dev, &vsp, &vsn);
    r->vp = vp;
    r->vn = vn;
    const int64_t emp = vp > V_ONSET ? div_round((int64_t)m->env.air * (vp - V_ONSET), 1000) : 0;
    const int64_t emn = vn > V_ONSET ? div_round((int64_t)m->env.air * (vn - V_ONSET), 1000) : 0;
    const int64_t web_n = m->env.load_ua > 0 ? div_round((int64_t)m->env.load_ua * vn, nom) : 0;
    const int64_t web_p = m->env.load_ua < 0 ? div_round(-(int64_t)m->env.load_ua * vp, nom) : 0;
    r->iap = clamp16(emp + web_p);
    r->ian = clamp16(-(emn + web_n));
    r->ilp = clamp16(div_round((int64_t)vp * g, 1000000));
    r->iln = clamp16(-div_round((int64_t)vn * g, 1000000));
    r->ipp = clamp16(div_round(web_p, 4));
    r->ipn = clamp16(-div_round(web_n, 4));
    r->veff = clamp16(rms2(vp, vn));
    r->ieff = clamp16(rms2(r->iap, r->ian));
    r->idc = clamp16((int64_t)r->iap + r->ilp + r->ian + r->iln);
    r->bal = vp + vn >= 100 ? (int32_t)div_round(100 * (int64_t)vp, (int64_t)vp + vn) : 0;
    const int64_t load_p = (int64_t)r->iap + r->ilp;
    const int64_t load_n = -((int64_t)r->ian + r->iln);
    r->cap = clamp_u8(div_round(100 * (load_p > load_n ? load_p : load_n), I_MAX_UA));
    r->poll = (pf > 0 && vsp + vsn > 0) ? clamp_u8(div_round(g * (vp + vn), pf * (vsp + vsn))) : 0;
}

static int32_t q8_to_v(int32_t q8) { return (q8 + 128) / 256; }

static int32_t filter(int32_t x, int32_t target)
{
    const int32_t d = target - x;
    if (d <= SNAP_Q8 && d >= -SNAP_Q8) {
        return target;
    }
    return x + (int32_t)(((int64_t)d * FILTER_A_Q16) / 65536);
}

/* ---- Faults --------------------------------------------------------------------------------------------- */

/* Is the condition there now (measured readings r), i.e. would the device raise the fault? */
static bool condition(device_t *dev, unsigned id, const void *ctx)
{
    const sds_env_t *env = &model(dev)->env;
    const readings_t *r = (const readings_t *)ctx;
    switch (id) {
    case F_E_OVERLOAD:
        return r->cap >= CAPACITY_ERROR;
    case F_W_CAPACITY:
        return r->cap >= CAPACITY_WARN;
    case F_E_POLLUTION:
        return r->poll >= POLLUTION_ERROR;
    case F_W_POLLUTION:
        return r->poll >= POLLUTION_WARN;
    case F_E_SUPPLY_LOW:
        return env->supply_dv < SUPPLY_ERROR_LOW_DV;
    case F_E_SUPPLY_HIGH:
        return env->supply_dv > SUPPLY_ERROR_HIGH_DV;
    case F_W_SUPPLY:
        return env->supply_dv < SUPPLY_WARN_LOW_DV || env->supply_dv > SUPPLY_WARN_HIGH_DV;
    case F_E_TEMP:
        return env->temp_c >= TEMP_ERROR_C;
    case F_W_TEMP:
        return env->temp_c >= TEMP_WARN_C;
    default:
        return false; /* injected faults are momentary events */
    }
}

/* Does the cause persist (the "internal check" of 0x2003, D11)? Pollution and capacity are judged at the
 * full set voltages, so a bar that is still dirty cannot be cleared while its HV is off. */
static bool cause_present(device_t *dev, unsigned id)
{
    int32_t vsp, vsn;
    readings_t full;
    set_voltages(dev, &vsp, &vsn);
    compute(dev, vsp, vsn, &full);
    return condition(dev, id, &full);
}

static void write_status(device_t *dev)
{
    const sds_model_t *m = model(dev);
    vals(dev)->x6000_01 = (uint8_t)((m->hv_on ? STATUS_HV : 0U) | (eltex_any_active(dev, ELTEX_ERROR, 0U) ? STATUS_ERROR : 0U) |
                                    (eltex_any_active(dev, ELTEX_WARNING, 0U) ? STATUS_WARNING : 0U));
    vals(dev)->x2001_0a = (uint8_t)(m->hv_on ? DUTY_PERCENT : 0U);
}

static void hv_apply(device_t *dev)
{
    sds_model_t *m = model(dev);
    if (eltex_any_active(dev, ELTEX_ERROR, ELTEX_HV_OFF)) {
        m->released = false; /* D7: a blocking error cancels the release */
    }
    m->hv_on = m->released;
    write_status(dev);
}

/* An entry was raised or deleted: HV and the status bits follow. */
static void fault_changed(device_t *dev, unsigned id, bool raised)
{
    (void)id;
    (void)raised;
    hv_apply(dev);
}

static const eltex_class_t sds_eltex = {
    .faults = faults,
    .n_faults = F_COUNT,
    .cause = cause_present,
    .available = NULL,
    .changed = fault_changed,
    .nvm_magic = {'S', 'D', 'S', 'M'},
    .hv_counter_sub = 0x05U,
    .bit_timing_9_off = false,
};

/* ---- Model update --------------------------------------------------------------------------------------- */

/* Readings into the OD, then the conditions (which may raise faults and switch HV off). */
static void refresh(device_t *dev)
{
    sds_model_t *m = model(dev);
    sds_od_values_t *v = vals(dev);
    readings_t r;
    compute(dev, q8_to_v(m->vp_q8), q8_to_v(m->vn_q8), &r);
    v->x2001_01 = (uint16_t)r.vp;
    v->x2001_02 = (int16_t)r.iap;
    v->x2001_03 = (int16_t)r.ilp;
    v->x2001_04 = (int16_t)r.ipp;
    v->x2001_05 = (uint16_t)r.vn;
    v->x2001_06 = (int16_t)r.ian;
    v->x2001_07 = (int16_t)r.iln;
    v->x2001_08 = (int16_t)r.ipn;
    v->x2001_09 = v->x2002_09;
    v->x6000_02 = (uint8_t)r.bal;
    v->x6000_03 = (uint8_t)r.cap;
    v->x6000_04 = (uint8_t)r.poll;
    v->x6000_05 = v->x2002_08;
    v->x6401_01 = (int16_t)r.veff;
    v->x6401_02 = (int16_t)r.ieff;
    v->x6401_03 = (int16_t)r.idc;
    eltex_faults_raise_where(dev, condition, &r); /* warnings before errors (E8, D18) */
    write_status(dev);
}

static void tick(device_t *dev)
{
    sds_model_t *m = model(dev);
    int32_t tp = 0, tn = 0;
    if (m->hv_on) {
        set_voltages(dev, &tp, &tn);
    }
    m->vp_q8 = filter(m->vp_q8, tp * 256);
    m->vn_q8 = filter(m->vn_q8, tn * 256);
    refresh(dev);
}

/* Runs every model event up to now, in time order: release timeout, measurement ticks, TPDO grid, counters. */
static void advance(device_t *dev, co_time_us_t now)
{
    sds_model_t *m = model(dev);
    if (now > m->tick_next && (now - m->tick_next) / TICK_US > CATCH_UP_TICKS) {
        /* A long gap (a late wake-up, a suspended host): the values settle within a few time constants, so
         * only the last CATCH_UP_TICKS ticks are simulated; the time before them is counted in one step. */
        const co_time_us_t skip_to = m->tick_next + ((now - m->tick_next) / TICK_US - CATCH_UP_TICKS) * TICK_US;
        if (m->released && m->release_until <= skip_to) {
            eltex_count(dev, m->release_until, m->hv_on);
            m->released = false; /* not refreshed within 10 s */
            hv_apply(dev);
        }
        eltex_count(dev, skip_to, m->hv_on);
        m->tick_next = skip_to;
    }
    for (;;) {
        co_time_us_t t = m->tick_next;
        if (m->released && m->release_until < t) {
            t = m->release_until;
        }
        if (t > now) {
            break;
        }
        eltex_count(dev, t, m->hv_on);
        if (m->released && t >= m->release_until) {
            m->released = false; /* not refreshed within 10 s */
            hv_apply(dev);
        }
        if (t >= m->tick_next) {
            tick(dev);
            m->tick_next += TICK_US;
        }
    }
    eltex_count(dev, now, m->hv_on);
    (void)eltex_tpdo_step(dev, now);
}

static co_time_us_t next_deadline(device_t *dev, co_time_us_t now)
{
    const sds_model_t *m = model(dev);
    co_time_us_t next = m->tick_next;
    if (m->released && m->release_until < next) {
        next = m->release_until;
    }
    if (m->eltex.tpdo_next < next) {
        next = m->eltex.tpdo_next;
    }
    const co_time_us_t minute = eltex_count_deadline(dev, now);
    return minute < next ? minute : next;
}

/* ---- Class hooks ---------------------------------------------------------------------------------------- */

/* The environment at the first power-on (device_init). */
static void sds_init(device_t *dev)
{
    sds_env_t *env = &model(dev)->env;
    env->g_ps = G_DEFAULT_PS;
    env->air = AIR_DEFAULT;
    env->supply_dv = SUPPLY_NOMINAL_DV;
    env->temp_c = TEMP_DEFAULT_C;
}

/* A power-on: the running state starts afresh (HV off, no release, no active entries, voltages 0, the
 * measurement grid from now); the environment stays as it was (D17). */
static void sds_power_on(device_t *dev, co_time_us_t now)
{
    sds_model_t *m = model(dev);
    device_clear_running_state(dev, offsetof(sds_model_t, env), sizeof(sds_env_t));
    m->tick_next = now + TICK_US;
    eltex_power_on(dev, &sds_eltex, now);
}

static void sds_on_reset(device_t *dev, co_reset_t what)
{
    sds_model_t *m = model(dev);
    sds_od_values_t *v = vals(dev);
    if (what == CO_RESET_COMMUNICATION) {
        eltex_on_reset(dev, what); /* E1-E4, E11 */
        return;
    }
    advance(dev, dev->now);
    /* D4: variant default where 0x1010 stored nothing (a stored distance outside the variant's range was refused
     * at the load: the parameters are then the defaults, reported as CO_NVM_REFUSED). */
    if (dev->variant == VARIANT_E && (!m->eltex.params_stored || dev->node.nvm_status != CO_NVM_LOADED)) {
        v->x2002_09 = 40U;
    }
    /* The application restarts: HV off, momentary faults forgotten, persisting ones kept (E10, D12). */
    m->released = false;
    m->hv_on = false;
    eltex_on_reset(dev, what);
    refresh(dev);
}

/* act false: a stored value being loaded, only checked. */
static uint32_t write_param(device_t *dev, uint8_t sub, const uint8_t *data, bool act)
{
    const uint8_t u8 = data[0];
    if (!act) {
        if (sub == 0x08U) {
            uint8_t lo, hi;
            distance_range(dev, &lo, &hi);
            return u8 > hi ? CO_ABORT_VALUE_HIGH : (u8 < lo ? CO_ABORT_VALUE_LOW : 0U);
        }
        return 0U;
    }
    switch (sub) {
    case 0x08: {
        const uint32_t r = write_param(dev, sub, data, false);
        if (r != 0U) {
            return r;
        }
        vals(dev)->x6000_05 = u8; /* read back at once; voltages follow at the next ticks */
        return 0U;
    }
    case 0x09:
        vals(dev)->x2001_09 = u8;
        return 0U;
    default:
        return 0U;
    }
}

static uint32_t write_release(device_t *dev, uint8_t value)
{
    sds_model_t *m = model(dev);
    if (value == 0x0FU) {
        m->released = true; /* hv_apply() ends it again while a blocking error is active (D7) */
        m->release_until = dev->now + RELEASE_US;
    } else if (value == 0x00U) {
        m->released = false;
    } else {
        return CO_ABORT_INVALID_VALUE; /* an RPDO refusal is dropped silently by the core */
    }
    hv_apply(dev);
    return 0U;
}

static uint32_t sds_on_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len,
                             co_od_origin_t origin)
{
    const bool act = origin != CO_ORIGIN_NVM; /* a stored value being loaded is only checked */
    if (act && (e->index == 0x2002U || e->index == 0x2003U || e->index == 0x6200U)) {
        advance(dev, dev->now); /* the model's state of now decides */
    }
    const uint32_t r = eltex_on_write(dev, e, data, len, origin); /* 0x1017, 0x2002:01/07, 0x2003, E6, E14 */
    if (r != 0U) {
        return r;
    }
    if (e->index == 0x2002U) {
        return write_param(dev, e->sub, data, act);
    }
    if (!act) {
        return 0U;
    }
    if (e->index == 0x6200U && e->sub == 1U) {
        return write_release(dev, data[0]);
    }
    return 0U;
}

static uint32_t sds_on_read(device_t *dev, const co_od_entry_t *e)
{
    if (e->index == 0x2000U || e->index == 0x2001U || e->index == 0x6000U || e->index == 0x6401U) {
        advance(dev, dev->now); /* an SDO read between two process calls sees the value of now */
    }
    return 0U;
}

static void sds_on_nmt_change(device_t *dev, co_nmt_state_t from, co_nmt_state_t to)
{
    (void)from;
    eltex_on_nmt_change(dev, to); /* E12 */
}

static co_time_us_t sds_step(device_t *dev, co_time_us_t now)
{
    advance(dev, now);
    return next_deadline(dev, now);
}

/* ---- Control commands ----------------------------------------------------------------------------------- */

/* "24", "23.5", "18.25" -> tenths (rounded half up). */
static bool parse_tenths(const char *s, long lo, long hi, long *out)
{
    long whole = 0, tenths = 0;
    int digits = 0, frac = 0;
    bool round_up = false;
    if (s == NULL || *s == '\0') {
        return false;
    }
    for (; *s >= '0' && *s <= '9'; s++, digits++) {
        whole = whole * 10 + (*s - '0');
        if (whole > 100000) {
            return false;
        }
    }
    if (*s == '.') {
        for (s++; *s >= '0' && *s <= '9'; s++, frac++) {
            if (frac == 0) {
                tenths = *s - '0';
            } else if (frac == 1) {
                round_up = *s >= '5';
            }
        }
    }
    if (*s != '\0' || (digits == 0 && frac == 0)) {
        return false;
    }
    const long v = whole * 10 + tenths + (round_up ? 1 : 0);
    if (v < lo || v > hi) {
        return false;
    }
    *out = v;
    return true;
}

static void print_model(device_t *dev)
{
    sds_model_t *m = model(dev);
    int32_t vsp, vsn;
    readings_t r;
    set_voltages(dev, &vsp, &vsn);
    compute(dev, q8_to_v(m->vp_q8), q8_to_v(m->vn_q8), &r);
    device_printf(dev, "variant SDS/%s, HV %s, release %s", variants[dev->variant], m->hv_on ? "on" : "off",
                  m->released ? "active" : "none");
    device_printf(dev, "inputs: conductance %lu pS, load %ld uA, air %ld uA/kV, supply %ld.%ld V, temperature %ld C",
                  (unsigned long)m->env.g_ps, (long)m->env.load_ua, (long)m->env.air, (long)(m->env.supply_dv / 10),
                  (long)(m->env.supply_dv % 10), (long)m->env.temp_c);
    device_printf(dev, "set voltages +%ld V / -%ld V; measured +%ld V / -%ld V, Veff %ld V", (long)vsp, (long)vsn,
                  (long)r.vp, (long)r.vn, (long)r.veff);
    device_printf(dev, "currents (uA): active %+ld/%+ld, leakage %+ld/%+ld, passive %+ld/%+ld, Ieff %ld, DC %+ld",
                  (long)r.iap, (long)r.ian, (long)r.ilp, (long)r.iln, (long)r.ipp, (long)r.ipn, (long)r.ieff,
                  (long)r.idc);
    device_printf(dev, "balance %ld %%, capacity %ld %%, pollution %ld %%", (long)r.bal, (long)r.cap, (long)r.poll);
}

static device_cmd_result_t usage(device_t *dev, const char *text)
{
    device_printf(dev, "error: usage: %s", text);
    return DEVICE_CMD_ERROR;
}

static device_cmd_result_t sds_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
    sds_model_t *m = model(dev);
    const char *c = argv[0];
    long long x;
    long t;
    advance(dev, now);
    const device_cmd_result_t fr = eltex_fault_command(dev, argc, argv); /* error, warning, clear-..., faults */
    if (fr != DEVICE_CMD_UNKNOWN) {
        return fr;
    }
    if (strcmp(c, "pollution") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 255, &x)) {
            return usage(dev, "pollution PERCENT (0..255, of the pollution factor 0x2002:02)");
        }
        m->env.g_ps = (uint32_t)x * vals(dev)->x2002_02;
    } else if (strcmp(c, "conductance") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 10000000, &x)) {
            return usage(dev, "conductance PICOSIEMENS (0..10000000)");
        }
        m->env.g_ps = (uint32_t)x;
    } else if (strcmp(c, "load") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], -1000, 1000, &x)) {
            return usage(dev, "load MICROAMPERE (-1000..1000, + = positively charged web)");
        }
        m->env.load_ua = (int32_t)x;
    } else if (strcmp(c, "air") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 100, &x)) {
            return usage(dev, "air MICROAMPERE_PER_KV (0..100)");
        }
        m->env.air = (int32_t)x;
    } else if (strcmp(c, "supply") == 0) {
        if (argc != 2 || !parse_tenths(argv[1], 0, 600, &t)) {
            return usage(dev, "supply VOLTS (0..60, e.g. 23.5)");
        }
        m->env.supply_dv = (int32_t)t;
    } else if (strcmp(c, "temperature") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], -40, 150, &x)) {
            return usage(dev, "temperature CELSIUS (-40..150)");
        }
        m->env.temp_c = (int32_t)x;
    } else if (strcmp(c, "model") == 0 && argc == 1) {
        print_model(dev);
        return DEVICE_CMD_OK;
    } else {
        return DEVICE_CMD_UNKNOWN;
    }
    refresh(dev); /* an input changed: readings and conditions at once */
    print_model(dev);
    return DEVICE_CMD_OK;
}

const device_class_t sds_class = {
    .name = "sds",
    .summary = "Eltex SDS ionising bar: HV release with 10 s timeout, balance, pollution, variants N/E",
    .od = &sds_od,
    .od_names = sds_od_names,
    .od_units = sds_od_units,
    .od_object_names = sds_od_object_names,
    .default_node_id = 99U,
    .default_bit_timing = 4U,
    .core_options = CO_OPT_NMT_ACCEPT_LONG | CO_OPT_TPDO_NO_COS, /* TPDOs: the 0x2002:01 grid only (E12) */
    .bit_rates_kbit = bit_rates,
    .model_size = sizeof(sds_model_t),
    .variants = variants,
    .commands_help = "  pollution PERCENT           pollution as % of the pollution factor 0x2002:02 (sets the conductance)\n"
                     "  conductance PS              pollution conductance between the tip rows, picosiemens\n"
                     "  load UA                     web charge current in uA (+ = positively charged web)\n"
                     "  air UA_PER_KV               air ionisation: emission current per kV above 2000 V (default 5)\n"
                     "  supply VOLTS                supply voltage (default 24.0)\n"
                     "  temperature C               internal temperature (default 35)\n"
                     "  model                       inputs, set values and readings of the simulation\n"
                     ELTEX_FAULT_COMMANDS_HELP,
    .init = sds_init,
    .power_on = sds_power_on,
    .on_write = sds_on_write,
    .on_read = sds_on_read,
    .on_nmt_change = sds_on_nmt_change,
    .on_reset = sds_on_reset,
    .step = sds_step,
    .command = sds_command,
    .on_event = eltex_on_event,
    .on_store = eltex_on_store,
};
