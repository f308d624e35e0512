/*
 * Eltex SDS ionising bar. Object dictionary: od/sds.eds (decisions: docs/devices/sds.md).
 * Behaviour, simulation model and its constants, error/warning table, control commands and the numbered
 * decisions (D1...) quoted below: docs/devices/sds-behaviour.md.
 *
 * Portable like the core: no allocation, no clock (time is the `now` argument), no OS. The model state is
 * sds_model_t in the caller's memory (device_t.model); persistent counters live in the port's
 * CO_NVM_DEVICE area (blob "SDSM", see nvm_save()).
 */
#include "sds.h"

#include <string.h>

#include "sds_od.h"

/* ---- Constants of the simulation (docs/devices/sds-behaviour.md, "Simulation model") ------------------ */

#define SEC_US 1000000ULL
#define MINUTE_US (60ULL * SEC_US)
#define TICK_US 100000ULL              /* measurement period: 100 ms, on a grid from power-on */
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

#define TYPE_ERROR 0x01U
#define TYPE_WARNING 0x05U

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

typedef struct sds_fault {
    uint8_t type;      /* TYPE_ERROR / TYPE_WARNING: EMCY byte 3 */
    uint8_t code;      /* EMCY byte 4, the value written to 0x2003:01 / 0x2003:02 */
    uint16_t cia;      /* EMCY bytes 0-1 */
    uint8_t reg;       /* error register bits (bit 0 is added by the core) */
    bool hv_off;       /* switches HV off and cancels the release */
    const char *name;
} sds_fault_t;

static const sds_fault_t faults[F_COUNT] = {
    {TYPE_ERROR, 0x01U, 0x2320U, 0x02U, true, "HV short circuit / arcing"},
    {TYPE_ERROR, 0x02U, 0x2310U, 0x02U, true, "HV overload (capacity >= 100 %)"},
    {TYPE_ERROR, 0x03U, 0x2300U, 0x02U, true, "pollution error (>= 100 % of the pollution factor)"},
    {TYPE_ERROR, 0x04U, 0x3120U, 0x04U, true, "supply voltage too low (< 19.2 V)"},
    {TYPE_ERROR, 0x05U, 0x3110U, 0x04U, true, "supply voltage too high (> 28.8 V)"},
    {TYPE_ERROR, 0x06U, 0x4210U, 0x08U, true, "over-temperature (>= 70 C)"},
    {TYPE_ERROR, 0x07U, 0x3300U, 0x04U, true, "HV generator fault (set voltage not reached)"},
    {TYPE_ERROR, 0x08U, 0x6300U, 0x00U, false, "parameter memory error"},
    {TYPE_ERROR, 0x09U, 0x6100U, 0x80U, true, "internal error"},
    {TYPE_WARNING, 0x01U, 0x2300U, 0x02U, false, "pollution warning (>= 80 % of the pollution factor)"},
    {TYPE_WARNING, 0x02U, 0x2310U, 0x02U, false, "capacity warning (>= 90 %)"},
    {TYPE_WARNING, 0x03U, 0x3100U, 0x04U, false, "supply voltage out of tolerance (outside 21.6-26.4 V)"},
    {TYPE_WARNING, 0x04U, 0x4200U, 0x08U, false, "temperature high (>= 60 C)"},
};

/* ---- Model state ---------------------------------------------------------------------------------------- */

typedef struct sds_model {
    co_time_us_t last;         /* time the counters were integrated to */
    co_time_us_t tick_next;    /* next measurement tick */
    co_time_us_t release_until;/* end of the HV release (valid while released) */
    co_time_us_t tpdo_next;    /* next cyclic TPDO1/TPDO2, CO_NEVER outside Operational */
    uint64_t op_us;            /* operating time including the stored part */
    uint64_t hv_us;            /* HV-on time including the stored part */
    uint64_t saved_minute;     /* operating minute last written to NVM */
    int32_t vp_q8;             /* measured positive / negative voltage magnitudes, V * 256 */
    int32_t vn_q8;
    uint32_t g_ps;             /* input: pollution conductance between the tip rows, pS */
    int32_t load_ua;           /* input: web charge current, µA (+ = positively charged web) */
    int32_t air;               /* input: air ionisation, µA per kV above the onset */
    int32_t supply_dv;         /* input: supply voltage, 0.1 V */
    int32_t temp_c;            /* input: internal temperature, °C */
    uint32_t active;           /* bit (1 << fault_id) per active error/warning */
    bool released;             /* 0x6200:01 = 0x0F received and not timed out / revoked */
    bool hv_on;                /* HV generator on (status bit 0) */
    bool booting;              /* between power_on and the first on_reset(APPLICATION) */
    bool params_stored;        /* 0x1010 saved the parameters (and no 0x1011 restore since): persistent, D4 */
    bool bt_switch;            /* a saved 0x2002:07 waits for the next reset to switch the bit rate (D6) */
    uint8_t bt_effective;      /* bit-timing index the port runs at */
} sds_model_t;

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

static uint64_t isqrt(uint64_t x)
{
    uint64_t r = 0U;
    uint64_t bit = (uint64_t)1U << 62;
    while (bit > x) {
        bit >>= 2;
    }
    while (bit != 0U) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return r;
}

/* round(sqrt((a^2 + b^2) / 2)): the RMS of a square wave with 50 % duty cycle. */
static int32_t rms2(int32_t a, int32_t b)
{
    const uint64_t q = (uint64_t)((int64_t)a * a) + (uint64_t)((int64_t)b * b);
    uint64_t s = isqrt(q / 2U);
    if (q >= 2U * s * s + 2U * s + 1U) {
        s++;
    }
    return (int32_t)s;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0U; i < 4U; i++) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint32_t crc32(const uint8_t *d, size_t n)
{
    uint32_t crc = 0xFFFFFFFFUL;
    for (size_t i = 0U; i < n; i++) {
        crc ^= d[i];
        for (unsigned b = 0U; b < 8U; b++) {
            crc = (crc >> 1) ^ (0xEDB88320UL & (0U - (crc & 1U)));
        }
    }
    return ~crc;
}

/* ---- Persistent data (CO_NVM_DEVICE) --------------------------------------------------------------------
 * Blob, 20 bytes, little-endian: "SDSM" | version 2 | flags (bit 0: parameters stored) | 0 0 |
 * operating seconds u32 | HV seconds u32 | CRC-32 of bytes 0..15. Anything else counts as empty. */

#define NVM_LEN 20U
#define NVM_VERSION 2U
#define NVM_FLAG_PARAMS_STORED 0x01U

static void nvm_load(device_t *dev)
{
    sds_model_t *m = model(dev);
    const co_port_t *p = dev->cfg.port;
    uint8_t b[NVM_LEN];
    if (p == NULL || p->nvm_read == NULL || p->nvm_read(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, NVM_LEN) != CO_OK ||
        memcmp(b, "SDSM", 4U) != 0 || b[4] != NVM_VERSION || get_u32(&b[16]) != crc32(b, 16U)) {
        return; /* nothing stored or damaged: counters start at 0 */
    }
    m->params_stored = (b[5] & NVM_FLAG_PARAMS_STORED) != 0U;
    m->op_us = (uint64_t)get_u32(&b[8]) * SEC_US;
    m->hv_us = (uint64_t)get_u32(&b[12]) * SEC_US;
}

static void nvm_save(device_t *dev)
{
    const sds_model_t *m = model(dev);
    const co_port_t *p = dev->cfg.port;
    uint8_t b[NVM_LEN];
    if (p == NULL || p->nvm_write == NULL || p->nvm_commit == NULL) {
        return;
    }
    memset(b, 0, sizeof b);
    memcpy(b, "SDSM", 4U);
    b[4] = NVM_VERSION;
    b[5] = m->params_stored ? NVM_FLAG_PARAMS_STORED : 0U;
    put_u32(&b[8], (uint32_t)(m->op_us / SEC_US));
    put_u32(&b[12], (uint32_t)(m->hv_us / SEC_US));
    put_u32(&b[16], crc32(b, 16U));
    if (p->nvm_write(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, NVM_LEN) == CO_OK) {
        (void)p->nvm_commit(dev->cfg.port_ctx, CO_NVM_DEVICE, NVM_LEN);
    }
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
    const int64_t g = m->g_ps;
    const int64_t pf = vals(dev)->x2002_02;
    int32_t vsp, vsn;
    set_voltages(dev, &vsp, &vsn);
    r->vp = vp;
    r->vn = vn;
    const int64_t emp = vp > V_ONSET ? div_round((int64_t)m->air * (vp - V_ONSET), 1000) : 0;
    const int64_t emn = vn > V_ONSET ? div_round((int64_t)m->air * (vn - V_ONSET), 1000) : 0;
    const int64_t web_n = m->load_ua > 0 ? div_round((int64_t)m->load_ua * vn, nom) : 0;
    const int64_t web_p = m->load_ua < 0 ? div_round(-(int64_t)m->load_ua * vp, nom) : 0;
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

static bool fault_active(const sds_model_t *m, unsigned id) { return (m->active & ((uint32_t)1U << id)) != 0U; }

static bool any_of_type(const sds_model_t *m, uint8_t type)
{
    for (unsigned i = 0U; i < F_COUNT; i++) {
        if (faults[i].type == type && fault_active(m, i)) {
            return true;
        }
    }
    return false;
}

static bool hv_blocked(const sds_model_t *m)
{
    for (unsigned i = 0U; i < F_COUNT; i++) {
        if (faults[i].hv_off && fault_active(m, i)) {
            return true;
        }
    }
    return false;
}

static int find_fault(uint8_t type, uint8_t code)
{
    for (unsigned i = 0U; i < F_COUNT; i++) {
        if (faults[i].type == type && faults[i].code == code) {
            return (int)i;
        }
    }
    return -1;
}

/* Is the condition there now (measured readings r), i.e. would the device raise the fault? */
static bool condition(const sds_model_t *m, const readings_t *r, unsigned id)
{
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
        return m->supply_dv < SUPPLY_ERROR_LOW_DV;
    case F_E_SUPPLY_HIGH:
        return m->supply_dv > SUPPLY_ERROR_HIGH_DV;
    case F_W_SUPPLY:
        return m->supply_dv < SUPPLY_WARN_LOW_DV || m->supply_dv > SUPPLY_WARN_HIGH_DV;
    case F_E_TEMP:
        return m->temp_c >= TEMP_ERROR_C;
    case F_W_TEMP:
        return m->temp_c >= TEMP_WARN_C;
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
    return condition(model(dev), &full, id);
}

static void write_status(device_t *dev)
{
    const sds_model_t *m = model(dev);
    vals(dev)->x6000_01 = (uint8_t)((m->hv_on ? STATUS_HV : 0U) | (any_of_type(m, TYPE_ERROR) ? STATUS_ERROR : 0U) |
                                    (any_of_type(m, TYPE_WARNING) ? STATUS_WARNING : 0U));
    vals(dev)->x2001_0a = (uint8_t)(m->hv_on ? DUTY_PERCENT : 0U);
}

static void hv_apply(device_t *dev)
{
    sds_model_t *m = model(dev);
    if (hv_blocked(m)) {
        m->released = false; /* D7: a blocking error cancels the release */
    }
    m->hv_on = m->released;
    write_status(dev);
}

static void emcy_raise(device_t *dev, unsigned id)
{
    const sds_fault_t *f = &faults[id];
    const uint8_t msef[5] = {f->type, f->code, 0U, 0U, 0U};
    (void)co_emcy_raise(&dev->node, f->cia, f->reg, msef);
}

static void fault_raise(device_t *dev, unsigned id)
{
    sds_model_t *m = model(dev);
    if (fault_active(m, id)) {
        return;
    }
    m->active |= (uint32_t)1U << id;
    emcy_raise(dev, id);
    hv_apply(dev);
}

/* 0x2003:01/02 and the clear-error/clear-warning commands. Returns 0 or the abort code (D10, D11). */
static uint32_t fault_clear(device_t *dev, uint8_t type, uint8_t code)
{
    sds_model_t *m = model(dev);
    const int found = find_fault(type, code);
    if (found < 0) {
        return CO_ABORT_INVALID_VALUE; /* not a code of the table */
    }
    const unsigned id = (unsigned)found;
    if (!fault_active(m, id)) {
        return CO_ABORT_NO_DATA; /* nothing to delete */
    }
    if (cause_present(dev, id)) {
        return CO_ABORT_DEVICE_STATE; /* the internal check fails: the cause persists */
    }
    m->active &= ~((uint32_t)1U << id);
    const uint8_t msef[5] = {type, code, 0U, 0U, 0U};
    (void)co_emcy_clear(&dev->node, faults[id].cia, msef); /* confirmation EMCY 0000 | ER | type | code */
    write_status(dev);
    return 0U;
}

/* ---- Model update --------------------------------------------------------------------------------------- */

static void write_counters(device_t *dev)
{
    sds_od_values_t *v = vals(dev);
    const sds_model_t *m = model(dev);
    const uint64_t op = m->op_us / MINUTE_US;
    const uint64_t hv = m->hv_us / MINUTE_US;
    v->x2000_01 = (uint8_t)(op / 525600U > 255U ? 255U : op / 525600U);
    v->x2000_02 = (uint16_t)((op % 525600U) / 1440U);
    v->x2000_03 = (uint8_t)((op % 1440U) / 60U);
    v->x2000_04 = (uint8_t)(op % 60U);
    v->x2000_05 = (uint8_t)(hv / 525600U > 255U ? 255U : hv / 525600U);
    v->x2000_06 = (uint16_t)((hv % 525600U) / 1440U);
    v->x2000_07 = (uint8_t)((hv % 1440U) / 60U);
    v->x2000_08 = (uint8_t)(hv % 60U);
}

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
    /* Warnings before errors: a reading that jumps past both raises both, in this order. */
    static const unsigned order[] = {F_W_POLLUTION, F_W_CAPACITY, F_W_SUPPLY, F_W_TEMP,    F_E_POLLUTION,
                                     F_E_OVERLOAD,  F_E_SUPPLY_LOW, F_E_SUPPLY_HIGH, F_E_TEMP};
    for (size_t i = 0U; i < sizeof order / sizeof order[0]; i++) {
        if (condition(m, &r, order[i])) {
            fault_raise(dev, order[i]);
        }
    }
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

static void integrate(sds_model_t *m, co_time_us_t t)
{
    if (t <= m->last) {
        return;
    }
    m->op_us += t - m->last;
    if (m->hv_on) {
        m->hv_us += t - m->last;
    }
    m->last = t;
}

static uint64_t tpdo_period_us(device_t *dev)
{
    const uint16_t ms = vals(dev)->x2002_01;
    return (uint64_t)(ms < 100U ? 100U : ms) * 1000U;
}

/* Runs every model event up to now, in time order: release timeout, measurement ticks, TPDO grid, NVM. */
static void advance(device_t *dev, co_time_us_t now)
{
    sds_model_t *m = model(dev);
    for (;;) {
        co_time_us_t t = m->tick_next;
        if (m->released && m->release_until < t) {
            t = m->release_until;
        }
        if (t > now) {
            break;
        }
        integrate(m, t);
        if (m->released && t >= m->release_until) {
            m->released = false; /* not refreshed within 10 s */
            hv_apply(dev);
        }
        if (t >= m->tick_next) {
            tick(dev);
            m->tick_next += TICK_US;
        }
    }
    integrate(m, now);
    if (m->tpdo_next != CO_NEVER && now >= m->tpdo_next) {
        if (co_node_state(&dev->node) == CO_NMT_OPERATIONAL) {
            co_tpdo_trigger(&dev->node, 0U);
            co_tpdo_trigger(&dev->node, 1U);
        }
        const uint64_t p = tpdo_period_us(dev);
        m->tpdo_next += p * (1U + (now - m->tpdo_next) / p); /* stays on the grid; missed periods skipped */
    }
    write_counters(dev);
    if (m->op_us / MINUTE_US != m->saved_minute) {
        m->saved_minute = m->op_us / MINUTE_US;
        nvm_save(dev);
    }
}

static co_time_us_t next_deadline(device_t *dev, co_time_us_t now)
{
    const sds_model_t *m = model(dev);
    co_time_us_t next = m->tick_next;
    if (m->released && m->release_until < next) {
        next = m->release_until;
    }
    if (m->tpdo_next < next) {
        next = m->tpdo_next;
    }
    const co_time_us_t minute = now + (MINUTE_US - m->op_us % MINUTE_US);
    return minute < next ? minute : next;
}

/* ---- Class hooks ---------------------------------------------------------------------------------------- */

static void sds_power_on(device_t *dev, co_time_us_t now)
{
    sds_model_t *m = model(dev); /* zeroed by the framework */
    m->last = now;
    m->tick_next = now + TICK_US;
    m->tpdo_next = CO_NEVER;
    m->g_ps = G_DEFAULT_PS;
    m->air = AIR_DEFAULT;
    m->supply_dv = SUPPLY_NOMINAL_DV;
    m->temp_c = TEMP_DEFAULT_C;
    m->booting = true;
    nvm_load(dev);
    m->saved_minute = m->op_us / MINUTE_US;
}

static void sds_on_reset(device_t *dev, co_reset_t what)
{
    sds_model_t *m = model(dev);
    sds_od_values_t *v = vals(dev);
    if (what == CO_RESET_COMMUNICATION) {
        /* D5/D6: 0x2002:06/07 are views of the LSS setting; the node-ID was just adopted from it. */
        if (m->bt_switch && dev->node.lss.pending_bit_timing != m->bt_effective) {
            m->bt_effective = dev->node.lss.pending_bit_timing;
            (void)co_lss_apply_bit_timing(&dev->node); /* the port switches; the core records it */
        }
        m->bt_switch = false;
        if (dev->node.node_id >= 1U && dev->node.node_id <= 127U) {
            v->x2002_06 = dev->node.node_id;
        }
        v->x2002_07 = m->bt_effective;
        /* The core forgot its active errors and 0x1003: report those that persist again (after the boot-up). */
        for (unsigned i = 0U; i < F_COUNT; i++) {
            if (fault_active(m, i)) {
                emcy_raise(dev, i);
            }
        }
        return;
    }
    advance(dev, dev->now);
    if (m->booting) {
        m->bt_effective = dev->node.lss.active_bit_timing; /* the core set the port at power-on */
        m->booting = false;
    }
    /* D4: variant default where 0x1010 stored nothing; a stored distance outside the range is clamped. */
    if (dev->variant == VARIANT_E && !m->params_stored) {
        v->x2002_09 = 40U;
    }
    uint8_t lo, hi;
    distance_range(dev, &lo, &hi);
    v->x2002_08 = v->x2002_08 < lo ? lo : (v->x2002_08 > hi ? hi : v->x2002_08);
    /* The application restarts: HV off, momentary faults forgotten, persisting ones kept (D12). */
    m->released = false;
    m->hv_on = false;
    for (unsigned i = 0U; i < F_COUNT; i++) {
        if (fault_active(m, i) && !cause_present(dev, i)) {
            m->active &= ~((uint32_t)1U << i);
        }
    }
    m->tpdo_next = CO_NEVER;
    write_counters(dev);
    refresh(dev);
}

static uint32_t write_param(device_t *dev, uint8_t sub, const uint8_t *data)
{
    sds_model_t *m = model(dev);
    const uint8_t u8 = data[0];
    switch (sub) {
    case 0x01: {
        const uint16_t ms = (uint16_t)(data[0] | (data[1] << 8));
        if (ms < 100U) {
            return CO_ABORT_VALUE_LOW;
        }
        if (ms > 60000U) {
            return CO_ABORT_VALUE_HIGH;
        }
        if (m->tpdo_next != CO_NEVER) {
            m->tpdo_next = dev->now + (co_time_us_t)ms * 1000U; /* D13: a new period starts at the write */
        }
        return 0U;
    }
    case 0x02:
        return u8 < 1U ? CO_ABORT_VALUE_LOW : (u8 > 100U ? CO_ABORT_VALUE_HIGH : 0U);
    case 0x04:
        return u8 < 35U ? CO_ABORT_VALUE_LOW : (u8 > 65U ? CO_ABORT_VALUE_HIGH : 0U);
    case 0x06:
        return u8 < 1U ? CO_ABORT_VALUE_LOW : (u8 > 127U ? CO_ABORT_VALUE_HIGH : 0U);
    case 0x07:
        if (u8 > 8U) {
            return CO_ABORT_VALUE_HIGH;
        }
        return bit_rates[u8] == 0U ? CO_ABORT_INVALID_VALUE : 0U; /* index 5 is not in the table */
    case 0x08: {
        uint8_t lo, hi;
        distance_range(dev, &lo, &hi);
        if (u8 > hi) {
            return CO_ABORT_VALUE_HIGH;
        }
        if (u8 < lo) {
            return CO_ABORT_VALUE_LOW;
        }
        vals(dev)->x6000_05 = u8; /* read back at once; voltages follow at the next ticks */
        return 0U;
    }
    case 0x09:
        if (u8 < 30U || u8 > 50U) {
            return u8 < 30U ? CO_ABORT_VALUE_LOW : CO_ABORT_VALUE_HIGH;
        }
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
    (void)len;
    switch (e->index) {
    case 0x1017: {
        const uint16_t ms = (uint16_t)(data[0] | (data[1] << 8));
        if (ms > 60000U) {
            return CO_ABORT_VALUE_HIGH;
        }
        if (ms != 0U && ms < 100U) {
            return CO_ABORT_VALUE_LOW;
        }
        return (ms % 100U) != 0U ? CO_ABORT_INVALID_VALUE : 0U; /* 100 ms steps */
    }
    case 0x2000:
    case 0x2001:
    case 0x6000:
    case 0x6401:
        /* Measured values belong to the model: the command line's `set` cannot fake them (use the inputs). */
        return origin == CO_ORIGIN_LOCAL ? CO_ABORT_LOCAL_CONTROL : 0U;
    case 0x2002:
        advance(dev, dev->now);
        return write_param(dev, e->sub, data);
    case 0x2003:
        if (e->sub != 1U && e->sub != 2U) {
            return 0U;
        }
        advance(dev, dev->now);
        return fault_clear(dev, e->sub == 1U ? TYPE_ERROR : TYPE_WARNING, data[0]);
    case 0x6200:
        if (e->sub != 1U) {
            return 0U;
        }
        advance(dev, dev->now);
        return write_release(dev, data[0]);
    default:
        return 0U;
    }
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
    sds_model_t *m = model(dev);
    (void)from;
    if (to == CO_NMT_OPERATIONAL) {
        /* The core sends both TPDOs once on entering Operational; the cyclic grid starts here. */
        m->tpdo_next = dev->now + tpdo_period_us(dev);
    } else {
        m->tpdo_next = CO_NEVER;
    }
}

/*
 * D4/D5/D6: follows what the core stored. A successful 0x1010 save also makes the saved 0x2002:06/07 the
 * LSS setting (pending + LSS store), so LSS and 0x2002:06/07 are one setting: the newest store wins, the
 * next reset (NMT 0x81/0x82) or power cycle applies it. 0x1011 restore brings the variant defaults back.
 */
static void sds_on_event(device_t *dev, const co_event_t *ev)
{
    sds_model_t *m = model(dev);
    const sds_od_values_t *v = vals(dev);
    if (ev->kind == CO_EV_STORE && ev->index == 0x1010U && ev->code == 0U) {
        m->params_stored = true;
        nvm_save(dev);
        (void)co_lss_set_pending_node_id(&dev->node, v->x2002_06);
        if (co_lss_set_pending_bit_timing(&dev->node, v->x2002_07)) {
            m->bt_switch = v->x2002_07 != m->bt_effective;
        }
        if (co_lss_store(&dev->node) != CO_OK) {
            device_printf(dev, "warning: node-ID/bit timing could not be stored in the LSS area");
        }
    } else if (ev->kind == CO_EV_RESTORE && ev->index == 0x1011U && ev->code == 0U) {
        m->params_stored = false;
        nvm_save(dev);
    } else if (ev->kind == CO_EV_LSS_ACTIVATE) {
        m->bt_effective = dev->node.lss.active_bit_timing;
    }
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

static void print_fault(device_t *dev, unsigned id, const char *what)
{
    const sds_fault_t *f = &faults[id];
    device_printf(dev, "%s 0x%02X (%s): EMCY 0x%04X register 0x%02X type 0x%02X%s%s",
                  f->type == TYPE_ERROR ? "error" : "warning", f->code, f->name, f->cia, (unsigned)(f->reg | 0x01U),
                  f->type, f->hv_off ? ", switches HV off" : "", what);
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
                  (unsigned long)m->g_ps, (long)m->load_ua, (long)m->air, (long)(m->supply_dv / 10),
                  (long)(m->supply_dv % 10), (long)m->temp_c);
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

static device_cmd_result_t cmd_fault(device_t *dev, int argc, const char *const *argv, uint8_t type, bool clear)
{
    long long code;
    if (argc != 2 || !device_parse_int(argv[1], 0, 0xFF, &code)) {
        return usage(dev, clear ? (type == TYPE_ERROR ? "clear-error CODE" : "clear-warning CODE")
                                : (type == TYPE_ERROR ? "error CODE" : "warning CODE"));
    }
    const int found = find_fault(type, (uint8_t)code);
    if (found < 0) {
        device_printf(dev, "error: %s code 0x%02X is not in the table (see `faults`)",
                      type == TYPE_ERROR ? "error" : "warning", (unsigned)code);
        return DEVICE_CMD_ERROR;
    }
    if (!clear) {
        if (fault_active(model(dev), (unsigned)found)) {
            print_fault(dev, (unsigned)found, ": already active");
            return DEVICE_CMD_OK;
        }
        fault_raise(dev, (unsigned)found);
        print_fault(dev, (unsigned)found, ": raised");
        return DEVICE_CMD_OK;
    }
    const uint32_t r = fault_clear(dev, type, (uint8_t)code);
    if (r != 0U) {
        device_printf(dev, "error: clearing 0x%02X refused: %s (0x%08lX)", (unsigned)code, co_abort_text(r),
                      (unsigned long)r);
        return DEVICE_CMD_ERROR;
    }
    print_fault(dev, (unsigned)found, ": cleared");
    return DEVICE_CMD_OK;
}

static device_cmd_result_t sds_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
    sds_model_t *m = model(dev);
    const char *c = argv[0];
    long long x;
    long t;
    if (strcmp(c, "error") == 0 || strcmp(c, "warning") == 0 || strcmp(c, "clear-error") == 0 ||
        strcmp(c, "clear-warning") == 0) {
        advance(dev, now);
        return cmd_fault(dev, argc, argv, strstr(c, "error") != NULL ? TYPE_ERROR : TYPE_WARNING,
                         strncmp(c, "clear-", 6U) == 0);
    }
    if (strcmp(c, "pollution") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 255, &x)) {
            return usage(dev, "pollution PERCENT (0..255, of the pollution factor 0x2002:02)");
        }
        advance(dev, now);
        m->g_ps = (uint32_t)x * vals(dev)->x2002_02;
    } else if (strcmp(c, "conductance") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 10000000, &x)) {
            return usage(dev, "conductance PICOSIEMENS (0..10000000)");
        }
        advance(dev, now);
        m->g_ps = (uint32_t)x;
    } else if (strcmp(c, "load") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], -1000, 1000, &x)) {
            return usage(dev, "load MICROAMPERE (-1000..1000, + = positively charged web)");
        }
        advance(dev, now);
        m->load_ua = (int32_t)x;
    } else if (strcmp(c, "air") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], 0, 100, &x)) {
            return usage(dev, "air MICROAMPERE_PER_KV (0..100)");
        }
        advance(dev, now);
        m->air = (int32_t)x;
    } else if (strcmp(c, "supply") == 0) {
        if (argc != 2 || !parse_tenths(argv[1], 0, 600, &t)) {
            return usage(dev, "supply VOLTS (0..60, e.g. 23.5)");
        }
        advance(dev, now);
        m->supply_dv = (int32_t)t;
    } else if (strcmp(c, "temperature") == 0) {
        if (argc != 2 || !device_parse_int(argv[1], -40, 150, &x)) {
            return usage(dev, "temperature CELSIUS (-40..150)");
        }
        advance(dev, now);
        m->temp_c = (int32_t)x;
    } else if (strcmp(c, "faults") == 0 && argc == 1) {
        for (unsigned i = 0U; i < F_COUNT; i++) {
            print_fault(dev, i, fault_active(m, i) ? ": ACTIVE" : "");
        }
        return DEVICE_CMD_OK;
    } else if (strcmp(c, "model") == 0 && argc == 1) {
        advance(dev, now);
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
    .default_node_id = 99U,
    .default_bit_timing = 4U,
    .core_options = CO_OPT_NMT_ACCEPT_LONG,
    .bit_rates_kbit = bit_rates,
    .model_size = sizeof(sds_model_t),
    .variants = variants,
    .commands_help = "pollution PERCENT     pollution as % of the pollution factor 0x2002:02 (sets the conductance)\n"
                     "conductance PS        pollution conductance between the tip rows, picosiemens\n"
                     "load UA               web charge current in uA (+ = positively charged web)\n"
                     "air UA_PER_KV         air ionisation: emission current per kV above 2000 V (default 5)\n"
                     "supply VOLTS          supply voltage (default 24.0)\n"
                     "temperature C         internal temperature (default 35)\n"
                     "error CODE            raise error CODE of the table (`faults`); warning CODE likewise\n"
                     "clear-error CODE      delete it as 0x2003:01 does (same checks); clear-warning CODE likewise\n"
                     "faults                the error/warning table with the active entries\n"
                     "model                 inputs, set values and readings of the simulation",
    .power_on = sds_power_on,
    .on_write = sds_on_write,
    .on_read = sds_on_read,
    .on_nmt_change = sds_on_nmt_change,
    .on_reset = sds_on_reset,
    .step = sds_step,
    .command = sds_command,
    .on_event = sds_on_event,
};
