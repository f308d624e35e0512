/*
 * The shared behaviour of the Eltex device models (see eltex.h; rules E1... in docs/devices/eltex.md).
 */
#include "eltex.h"

#include <string.h>

#define SEC_US 1000000ULL
#define MINUTE_US (60ULL * SEC_US)
#define MIN_PER_YEAR 525600U /* 365-day years */
#define MIN_PER_DAY 1440U

eltex_t *eltex_of(device_t *dev) { return (eltex_t *)dev->model; }
const eltex_t *eltex_const(const device_t *dev) { return (const eltex_t *)dev->model; }

static const eltex_class_t *ecls(const device_t *dev) { return eltex_const(dev)->cls; }

/* ---- Small helpers ------------------------------------------------------------------------------------------ */

uint64_t eltex_isqrt(uint64_t x)
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

/* Sets an integer object of up to 4 bytes directly (no hooks: the model owns it). */
static void set_value(device_t *dev, uint16_t index, uint8_t sub, uint32_t v)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(dev->cls->od, index, sub, &one);
    if (e == NULL) {
        return;
    }
    uint8_t *p = (uint8_t *)dev->values + e->offset;
    if (e->size == 1U) {
        p[0] = (uint8_t)v;
    } else if (e->size == 2U) {
        const uint16_t v16 = (uint16_t)v;
        memcpy(p, &v16, sizeof v16);
    } else if (e->size == 4U) {
        memcpy(p, &v, sizeof v);
    }
}


/* ---- Persistent data (E13) -------------------------------------------------------------------------------------
 * CO_NVM_DEVICE blob, 20 bytes, little-endian: magic (4, per device) | version 2 | flags | 0 0 |
 * operating seconds u32 | HV seconds u32 | CRC-32 (IEEE) of bytes 0..15. Flags: bit 0 = parameters stored
 * by 0x1010, bit 1 = 0x2002:07 = 9 saved (CANopen deactivated). Anything else counts as empty. */

#define NVM_LEN 20U
#define NVM_VERSION 2U
#define NVM_FLAG_PARAMS_STORED 0x01U
#define NVM_FLAG_CAN_OFF 0x02U

static void nvm_load(device_t *dev)
{
    eltex_t *x = eltex_of(dev);
    const co_port_t *p = dev->cfg.port;
    uint8_t b[NVM_LEN];
    if (p == NULL || p->nvm_read == NULL) {
        return;
    }
    const co_status_t st = p->nvm_read(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, NVM_LEN);
    if (st == CO_ERR_NO_DATA) {
        return; /* nothing stored: counters start at 0 */
    }
    if (st != CO_OK || memcmp(b, x->cls->nvm_magic, 4U) != 0 || b[4] != NVM_VERSION ||
        get_u32(&b[16]) != co_crc32(0U, b, 16U)) {
        device_printf(dev, "%s: counter memory damaged; counters start at 0", dev->cls->name);
        return;
    }
    x->params_stored = (b[5] & NVM_FLAG_PARAMS_STORED) != 0U;
    x->can_off = (b[5] & NVM_FLAG_CAN_OFF) != 0U;
    x->op_us = (uint64_t)get_u32(&b[8]) * SEC_US;
    x->hv_us = (uint64_t)get_u32(&b[12]) * SEC_US;
}

/* Operating time counted from the node's save phase (device_save_phase_us): the counters are written whenever it
 * completes a minute. */
static uint64_t op_from_phase(const device_t *dev, uint64_t op_us)
{
    return op_us + MINUTE_US - device_save_phase_us(dev);
}

static uint64_t save_minute(const device_t *dev, uint64_t op_us) { return op_from_phase(dev, op_us) / MINUTE_US; }

/* Writes the blob with these flags (the counters as they are) and commits it: on its own (commit_flags
 * CO_NVM_BACKGROUND: the periodic save) or as one area of a store in progress (CO_NVM_MORE: the core commits the
 * store's last area, E13/E15). */
static co_status_t nvm_write_blob(device_t *dev, bool params_stored, bool can_off, uint32_t commit_flags)
{
    const eltex_t *x = eltex_of(dev);
    const co_port_t *p = dev->cfg.port;
    uint8_t b[NVM_LEN];
    if (p == NULL || p->nvm_write == NULL || p->nvm_commit == NULL) {
        return CO_ERR_IO;
    }
    memset(b, 0, sizeof b);
    memcpy(b, x->cls->nvm_magic, 4U);
    b[4] = NVM_VERSION;
    b[5] = (uint8_t)((params_stored ? NVM_FLAG_PARAMS_STORED : 0U) | (can_off ? NVM_FLAG_CAN_OFF : 0U));
    put_u32(&b[8], (uint32_t)(x->op_us / SEC_US));
    put_u32(&b[12], (uint32_t)(x->hv_us / SEC_US));
    put_u32(&b[16], co_crc32(0U, b, 16U));
    if (p->nvm_write(dev->cfg.port_ctx, CO_NVM_DEVICE, 0U, b, NVM_LEN) != CO_OK ||
        p->nvm_commit(dev->cfg.port_ctx, CO_NVM_DEVICE, NVM_LEN | commit_flags) != CO_OK) {
        return CO_ERR_IO;
    }
    return CO_OK;
}

/* The periodic save of the counters (no store of the master's: nobody waits for an answer). */
static void nvm_save(device_t *dev)
{
    eltex_t *x = eltex_of(dev);
    x->saved_minute = save_minute(dev, x->op_us);
    const co_port_t *p = dev->cfg.port;
    if (p == NULL || p->nvm_write == NULL || p->nvm_commit == NULL) {
        return;
    }
    /* In the background (co_port.h): the port may write it later, so its fsync never holds a bus of many nodes; a
     * failure is then said by a later save, which is soon enough for a log line. */
    if (nvm_write_blob(dev, x->params_stored, x->can_off, CO_NVM_BACKGROUND) != CO_OK && !x->nvm_error_logged) {
        x->nvm_error_logged = true;
        device_printf(dev, "%s: counters could not be stored (NVM error)", dev->cls->name);
    }
}

/* ---- Counters (E13) ---------------------------------------------------------------------------------------------- */

static void publish_time(device_t *dev, uint8_t sub, uint64_t us)
{
    const uint64_t min = us / MINUTE_US;
    const uint64_t years = min / MIN_PER_YEAR;
    set_value(dev, 0x2000U, sub, (uint32_t)(years > 255U ? 255U : years));
    set_value(dev, 0x2000U, (uint8_t)(sub + 1U), (uint32_t)((min % MIN_PER_YEAR) / MIN_PER_DAY));
    set_value(dev, 0x2000U, (uint8_t)(sub + 2U), (uint32_t)((min % MIN_PER_DAY) / 60U));
    set_value(dev, 0x2000U, (uint8_t)(sub + 3U), (uint32_t)(min % 60U));
}

void eltex_counters_publish(device_t *dev)
{
    eltex_t *x = eltex_of(dev);
    x->shown_op_minute = x->op_us / MINUTE_US;
    x->shown_hv_minute = x->hv_us / MINUTE_US;
    publish_time(dev, 0x01U, x->op_us);
    publish_time(dev, x->cls->hv_counter_sub, x->hv_us);
}

void eltex_count(device_t *dev, co_time_us_t t, bool hv_on)
{
    eltex_t *x = eltex_of(dev);
    if (t > x->last) {
        x->op_us += t - x->last;
        if (hv_on) {
            x->hv_us += t - x->last;
        }
        x->last = t;
    }
    /* 0x2000 shows whole minutes and nothing else writes it (read-only, refused to `set`, re-published at every
     * application reset): the eight OD writes are needed only when a minute is full. */
    if (x->op_us / MINUTE_US != x->shown_op_minute || x->hv_us / MINUTE_US != x->shown_hv_minute) {
        eltex_counters_publish(dev);
    }
    if (save_minute(dev, x->op_us) != x->saved_minute) {
        nvm_save(dev); /* at least once per emulated minute of operating time, at the node's phase */
    }
}

co_time_us_t eltex_count_deadline(const device_t *dev, co_time_us_t now)
{
    return now + (MINUTE_US - op_from_phase(dev, eltex_const(dev)->op_us) % MINUTE_US);
}

/* ---- Cyclic TPDOs (E12) ----------------------------------------------------------------------------------------- */

static co_time_us_t tpdo_period_us(device_t *dev)
{
    const uint16_t ms = co_od_get_u16(&dev->node, 0x2002U, 0x01U);
    return (co_time_us_t)(ms < 100U ? 100U : ms) * 1000U;
}

void eltex_on_nmt_change(device_t *dev, co_nmt_state_t to)
{
    /* The core sends every TPDO once on entering Operational; the grid starts there. */
    eltex_of(dev)->tpdo_next = to == CO_NMT_OPERATIONAL ? dev->now + tpdo_period_us(dev) : CO_NEVER;
}

co_time_us_t eltex_tpdo_step(device_t *dev, co_time_us_t now)
{
    eltex_t *x = eltex_of(dev);
    if (x->tpdo_next != CO_NEVER && now >= x->tpdo_next) {
        if (co_node_state(&dev->node) == CO_NMT_OPERATIONAL) {
            for (uint8_t n = 0U; n < dev->node.n_tpdo; n++) {
                co_tpdo_trigger(&dev->node, n);
            }
        }
        const co_time_us_t p = tpdo_period_us(dev);
        x->tpdo_next += p * (1U + (now - x->tpdo_next) / p); /* stays on the grid; missed periods skipped */
    }
    return x->tpdo_next;
}

/* ---- Errors and warnings (E7-E11) ----------------------------------------------------------------------------- */

static uint64_t bit(unsigned i) { return (uint64_t)1U << i; }

static const char *type_name(uint8_t type) { return type == ELTEX_ERROR ? "error" : "warning"; }

static bool available(const device_t *dev, unsigned i)
{
    return ecls(dev)->available == NULL || ecls(dev)->available(dev, i);
}

static void emcy_raise(device_t *dev, unsigned i)
{
    const eltex_fault_t *f = &ecls(dev)->faults[i];
    const uint8_t msef[5] = {f->type, f->code, 0U, 0U, 0U};
    if (!co_emcy_raise(&dev->node, f->cia, f->reg, msef)) {
        device_printf(dev, "%s: %s %u not reported by EMCY (active list full)", dev->cls->name, type_name(f->type),
                      f->code);
    }
}

bool eltex_fault_active(const device_t *dev, unsigned i) { return (eltex_const(dev)->active & bit(i)) != 0U; }

bool eltex_any_active(const device_t *dev, uint8_t type, uint8_t flags)
{
    const eltex_class_t *c = ecls(dev);
    /* Runs at every model tick: only the active entries are looked at (usually none). */
    uint64_t a = eltex_const(dev)->active;
    for (unsigned i = 0U; a != 0U; i++, a >>= 1) {
        if ((a & 1U) != 0U && c->faults[i].type == type && (c->faults[i].flags & flags) == flags) {
            return true;
        }
    }
    return false;
}

int eltex_fault_find(const device_t *dev, uint8_t type, uint8_t code)
{
    const eltex_class_t *c = ecls(dev);
    for (unsigned i = 0U; i < c->n_faults; i++) {
        if (c->faults[i].type == type && c->faults[i].code == code) {
            return (int)i;
        }
    }
    return -1;
}

bool eltex_fault_raise(device_t *dev, unsigned i)
{
    eltex_t *x = eltex_of(dev);
    const eltex_fault_t *f = &x->cls->faults[i];
    if (eltex_fault_active(dev, i)) {
        return false;
    }
    x->active |= bit(i);
    emcy_raise(dev, i);
    device_printf(dev, "%s: %s %u raised: %s", dev->cls->name, type_name(f->type), f->code, f->text);
    if (x->cls->changed != NULL) {
        x->cls->changed(dev, i, true);
    }
    return true;
}

void eltex_faults_raise_where(device_t *dev, eltex_fault_pred_t pred, const void *ctx)
{
    const eltex_class_t *c = ecls(dev);
    static const uint8_t order[2] = {ELTEX_WARNING, ELTEX_ERROR};
    for (unsigned k = 0U; k < 2U; k++) {
        for (unsigned i = 0U; i < c->n_faults; i++) {
            if (c->faults[i].type == order[k] && !eltex_fault_active(dev, i) && available(dev, i) && pred(dev, i, ctx)) {
                (void)eltex_fault_raise(dev, i);
            }
        }
    }
}

uint32_t eltex_fault_clear(device_t *dev, uint8_t type, uint8_t code)
{
    eltex_t *x = eltex_of(dev);
    const int found = eltex_fault_find(dev, type, code);
    if (found < 0 || !available(dev, (unsigned)found)) {
        return CO_ABORT_INVALID_VALUE; /* not a code of this device */
    }
    const unsigned i = (unsigned)found;
    if (!eltex_fault_active(dev, i)) {
        return CO_ABORT_NO_DATA; /* nothing to delete */
    }
    if (x->cls->cause(dev, i)) {
        return CO_ABORT_DEVICE_STATE; /* the internal check fails: the cause persists */
    }
    x->active &= ~bit(i);
    const uint8_t msef[5] = {type, code, 0U, 0U, 0U};
    (void)co_emcy_clear(&dev->node, x->cls->faults[i].cia, msef); /* confirmation 0000 | ER | type | code */
    device_printf(dev, "%s: %s %u deleted", dev->cls->name, type_name(type), code);
    if (x->cls->changed != NULL) {
        x->cls->changed(dev, i, false);
    }
    return 0U;
}

static void print_fault(device_t *dev, unsigned i)
{
    const eltex_fault_t *f = &ecls(dev)->faults[i];
    device_printf(dev, "%s %u: %s; EMCY 0x%04X register 0x%02X type 0x%02X%s%s", type_name(f->type), f->code, f->text,
                  f->cia, (unsigned)(f->reg | 0x01U), f->type, (f->flags & ELTEX_HV_OFF) != 0U ? ", switches HV off" : "",
                  eltex_fault_active(dev, i) ? ": ACTIVE" : "");
}

device_cmd_result_t eltex_fault_command(device_t *dev, int argc, const char *const *argv)
{
    const char *c = argv[0];
    const bool clear = strcmp(c, "clear-error") == 0 || strcmp(c, "clear-warning") == 0;
    if (strcmp(c, "faults") == 0 && argc == 1) {
        for (unsigned i = 0U; i < ecls(dev)->n_faults; i++) {
            if (available(dev, i)) {
                print_fault(dev, i);
            }
        }
        return DEVICE_CMD_OK;
    }
    if (!clear && strcmp(c, "error") != 0 && strcmp(c, "warning") != 0) {
        return DEVICE_CMD_UNKNOWN;
    }
    const uint8_t type = strstr(c, "error") != NULL ? ELTEX_ERROR : ELTEX_WARNING;
    long long code;
    if (argc != 2 || !device_parse_int(argv[1], 0, 0xFF, &code)) {
        device_printf(dev, "error: usage: %s CODE", c);
        return DEVICE_CMD_ERROR;
    }
    const int found = eltex_fault_find(dev, type, (uint8_t)code);
    if (found < 0 || !available(dev, (unsigned)found)) {
        device_printf(dev, "error: %s %lld is not in this device's table (see `faults`)", type_name(type), code);
        return DEVICE_CMD_ERROR;
    }
    if (!clear) {
        if (!eltex_fault_raise(dev, (unsigned)found)) {
            device_printf(dev, "%s %lld is already active", type_name(type), code);
        }
        return DEVICE_CMD_OK;
    }
    const uint32_t r = eltex_fault_clear(dev, type, (uint8_t)code);
    if (r != 0U) {
        device_printf(dev, "error: %s %lld not deleted: %s (0x%08lX)", type_name(type), code, co_abort_text(r),
                      (unsigned long)r);
        return DEVICE_CMD_ERROR;
    }
    return DEVICE_CMD_OK;
}

/* ---- Hooks --------------------------------------------------------------------------------------------------- */

void eltex_power_on(device_t *dev, const eltex_class_t *cls, co_time_us_t now)
{
    eltex_t *x = eltex_of(dev);
    memset(x, 0, sizeof *x);
    x->cls = cls;
    x->last = now;
    x->tpdo_next = CO_NEVER;
    x->booting = true;
    nvm_load(dev);
    x->saved_minute = save_minute(dev, x->op_us);
}

/* E2: which 0x2002:07 values the device accepts. */
static uint32_t check_bit_timing(const device_t *dev, uint8_t v)
{
    if (v >= CO_LSS_BIT_TIMING_COUNT) {
        return CO_ABORT_VALUE_HIGH;
    }
    if (v == 9U && ecls(dev)->bit_timing_9_off) {
        return 0U;
    }
    const uint16_t *rates = dev->node.bit_rates_kbit; /* the device's table (the core's default when NULL) */
    return rates[v] == 0U ? CO_ABORT_INVALID_VALUE : 0U; /* e.g. 5 "not supported" */
}

uint32_t eltex_on_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len, co_od_origin_t origin)
{
    eltex_t *x = eltex_of(dev);
    if (origin == CO_ORIGIN_LOCAL) {
        /* E6: the EDS limits also for local writes (the core checks them for SDO and RPDO only). */
        const uint32_t r = co_od_check_limits(dev->node.od, e, data, len);
        if (r != 0U) {
            return r;
        }
    }
    switch (e->index) {
    case 0x2000:
    case 0x2001:
    case 0x6000:
    case 0x6401:
        /* E6: measured values belong to the model, which recomputes them; `set` cannot fake them. */
        return origin == CO_ORIGIN_LOCAL ? CO_ABORT_LOCAL_CONTROL : 0U;
    case 0x1017: { /* E5: 0 or 100..60000 in steps of 100 */
        const uint16_t ms = (uint16_t)(data[0] | (data[1] << 8));
        if (ms > 60000U) {
            return CO_ABORT_VALUE_HIGH;
        }
        if (ms != 0U && ms < 100U) {
            return CO_ABORT_VALUE_LOW;
        }
        return (ms % 100U) != 0U ? CO_ABORT_INVALID_VALUE : 0U;
    }
    case 0x2002:
        if (e->sub == 0x01U && x->tpdo_next != CO_NEVER && origin != CO_ORIGIN_NVM) {
            const uint16_t ms = (uint16_t)(data[0] | (data[1] << 8));
            x->tpdo_next = dev->now + (co_time_us_t)(ms < 100U ? 100U : ms) * 1000U; /* E12: restarts at the write */
        } else if (e->sub == 0x07U) {
            return check_bit_timing(dev, data[0]);
        }
        return 0U;
    case 0x2003:
        if (e->sub != 0x01U && e->sub != 0x02U) {
            return 0U;
        }
        return eltex_fault_clear(dev, e->sub == 0x01U ? ELTEX_ERROR : ELTEX_WARNING, data[0]);
    default:
        return 0U;
    }
}

/* What a 0x1010 save makes of 0x2002:06/07 (E3): the node-ID and bit timing for the LSS area, and whether
 * CANopen is off (0x2002:07 = 9 on devices with bit_timing_9_off: the node-ID becomes "unconfigured"). */
typedef struct saved_lss {
    uint8_t node_id;
    uint8_t bit_timing;   /* the pending one stays when the saved index is not in the device's table */
    bool can_off;
    bool bit_timing_valid;
} saved_lss_t;

static saved_lss_t lss_of_save(device_t *dev)
{
    const eltex_t *x = eltex_of(dev);
    const uint8_t id = co_od_get_u8(&dev->node, 0x2002U, 0x06U);
    const uint8_t bt = co_od_get_u8(&dev->node, 0x2002U, 0x07U);
    saved_lss_t s;
    s.can_off = bt == 9U && x->cls->bit_timing_9_off;
    s.node_id = s.can_off ? CO_NODE_ID_UNCONFIGURED : id;
    s.bit_timing_valid = !s.can_off && bt < CO_LSS_BIT_TIMING_COUNT && dev->node.bit_rates_kbit[bt] != 0U;
    s.bit_timing = s.bit_timing_valid ? bt : dev->node.lss.pending_bit_timing;
    return s;
}

/*
 * A store's own data (E15): a 0x1010 save also writes the device flags (parameters stored, CANopen off) and
 * the LSS area (0x2002:06/07 are the node-ID and bit timing, as LSS store configuration would write them); a
 * 0x1011 restore clears the stored flag; an LSS store configuration clears "CANopen off". All of it becomes
 * durable together with the core's area, or none of it (the store is then answered 0x06060000 / LSS error 2);
 * the model's state changes only when eltex_on_event() reports success.
 */
co_status_t eltex_on_store(device_t *dev, uint16_t index, uint8_t sub)
{
    const eltex_t *x = eltex_of(dev);
    (void)sub;
    if (index == 0x1010U) {
        const saved_lss_t l = lss_of_save(dev);
        if (nvm_write_blob(dev, true, l.can_off, CO_NVM_MORE) != CO_OK) {
            return CO_ERR_IO;
        }
        return co_lss_stage(&dev->node, l.node_id, l.bit_timing);
    }
    if (index == 0x1011U) {
        return nvm_write_blob(dev, false, x->can_off, CO_NVM_MORE);
    }
    if (index == 0x7E5U && x->can_off) {
        return nvm_write_blob(dev, x->params_stored, false, CO_NVM_MORE);
    }
    return CO_OK;
}

/*
 * E1/E2: a successful 0x1010 save makes the saved 0x2002:06/07 the pending LSS configuration and stores it
 * in the LSS area, as LSS store configuration would; so LSS and 0x2002:06/07 are one setting and the newest
 * store wins. E3: 0x2002:07 = 9 (devices with bit_timing_9_off) makes the pending node-ID "unconfigured":
 * after the next reset or power cycle the node runs LSS only. 0x1011 restore clears the stored flag. The data
 * was written by eltex_on_store(); here the store succeeded and the model follows it.
 */
void eltex_on_event(device_t *dev, const co_event_t *ev)
{
    eltex_t *x = eltex_of(dev);
    if (ev->kind == CO_EV_STORE && ev->index == 0x1010U && ev->code == 0U) {
        const saved_lss_t l = lss_of_save(dev);
        x->params_stored = true;
        x->can_off = l.can_off;
        (void)co_lss_set_pending_node_id(&dev->node, l.node_id);
        if (l.bit_timing_valid && co_lss_set_pending_bit_timing(&dev->node, l.bit_timing)) {
            x->bt_switch = l.bit_timing != x->bt_effective;
        }
    } else if (ev->kind == CO_EV_STORE && ev->index == 0x7E5U && ev->code == 0U) {
        x->can_off = false; /* an LSS store configuration is newer than the saved 0x2002:07 = 9 */
    } else if (ev->kind == CO_EV_RESTORE && ev->index == 0x1011U && ev->code == 0U) {
        x->params_stored = false;
    } else if (ev->kind == CO_EV_LSS_ACTIVATE) {
        x->bt_effective = dev->node.lss.active_bit_timing;
        set_value(dev, 0x2002U, 0x07U, x->bt_effective); /* the rate in effect changed */
    }
}

void eltex_on_reset(device_t *dev, co_reset_t what)
{
    eltex_t *x = eltex_of(dev);
    co_node_t *node = &dev->node;
    x->tpdo_next = CO_NEVER; /* the grid restarts when Operational is entered again */
    if (what == CO_RESET_APPLICATION) {
        if (x->booting) {
            x->bt_effective = node->lss.active_bit_timing; /* the core set the port at power-on */
            x->booting = false;
        }
        /* E10: the application restarts; entries whose cause persists stay, the others are forgotten. */
        for (unsigned i = 0U; i < x->cls->n_faults; i++) {
            if (eltex_fault_active(dev, i) && !x->cls->cause(dev, i)) {
                x->active &= ~bit(i);
            }
        }
        eltex_counters_publish(dev);
        return;
    }
    /* E1/E2: the node-ID was just adopted from the pending LSS configuration; a saved bit timing switches now,
     * before the boot-up; 0x2002:06/07 show what is in effect. */
    if (x->bt_switch && node->lss.pending_bit_timing != x->bt_effective) {
        (void)co_lss_apply_bit_timing(node); /* the port switches; CO_EV_LSS_ACTIVATE records it */
    }
    x->bt_switch = false;
    if (node->node_id >= 1U && node->node_id <= 127U) {
        set_value(dev, 0x2002U, 0x06U, node->node_id);
        set_value(dev, 0x2002U, 0x07U, x->bt_effective);
    } else if (x->can_off) {
        set_value(dev, 0x2002U, 0x07U, 9U);
        device_printf(dev, "%s: bit timing 9: CANopen communication deactivated (only LSS answers)", dev->cls->name);
    } else {
        set_value(dev, 0x2002U, 0x07U, x->bt_effective);
    }
    /* E11: the core forgot its active errors and 0x1003: report those still active again (after the boot-up). */
    for (unsigned i = 0U; i < x->cls->n_faults; i++) {
        if (eltex_fault_active(dev, i)) {
            emcy_raise(dev, i);
        }
    }
}
