/*
 * What the two Eltex device models (PRO IONIZER, SDS) share. Their CANopen manuals describe one design;
 * where they say the same, the behaviour is implemented here once. The rules (E1...) are described in
 * docs/devices/eltex.md; the device docs say which apply.
 *
 *   - 0x2002:06/07 are the CANopen view of the core's LSS configuration: a successful 0x1010 save makes
 *     them the pending LSS values and stores them (co_lss_store); any NMT reset (0x81, 0x82) or power
 *     cycle applies them; after every reset they show what is in effect (E1-E4);
 *   - the 0x1017 rule (0 or 100..60000 in steps of 100) and the EDS limits also for local writes (E5, E6);
 *   - the Eltex errors and warnings: a table per device, EMCY `cc cc ER type code 00 00 00`, latched
 *     until deleted through 0x2003:01/02 (same refusal codes), re-reported after a communication reset
 *     (E7-E11);
 *   - the cyclic TPDO grid of 0x2002:01 (E12);
 *   - the operating / HV-on counters of 0x2000 (years/days/hours/minutes) in CO_NVM_DEVICE, one blob
 *     layout (E13).
 *
 * Use: the device's model struct starts with an eltex_t (first member; the module finds it at
 * dev->model). power_on calls eltex_power_on(); the class hooks call the eltex_on_* functions at the
 * places their comments give. Portable C99 like the core: no allocation, no clock, no OS.
 */
#ifndef ELTEX_H
#define ELTEX_H

#include "../device.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ELTEX_ERROR 0x01U   /* EMCY byte 3 of an error; 0x2003:01 deletes it */
#define ELTEX_WARNING 0x05U /* EMCY byte 3 of a warning; 0x2003:02 deletes it */

#define ELTEX_HV_OFF 0x01U  /* eltex_fault_t.flags: the entry switches the high voltage off */

#define ELTEX_FAULTS_MAX 64U

/* One entry of a device's error/warning table. */
typedef struct eltex_fault {
    uint8_t type;       /* ELTEX_ERROR / ELTEX_WARNING */
    uint8_t code;       /* EMCY byte 4, the value written to 0x2003:01/02 */
    uint16_t cia;       /* EMCY bytes 0-1 */
    uint8_t reg;        /* error register bits (the core adds bit 0) */
    uint8_t flags;      /* ELTEX_HV_OFF */
    uint8_t group;      /* device feature the entry needs (0: every variant); judged by available() */
    const char *text;
} eltex_fault_t;

/* A predicate over the entries of the table (i = index into it). */
typedef bool (*eltex_fault_pred_t)(device_t *dev, unsigned i, const void *ctx);

/* What differs between the Eltex devices: a const per class. */
typedef struct eltex_class {
    const eltex_fault_t *faults;    /* the device's own table (at most ELTEX_FAULTS_MAX entries) */
    uint8_t n_faults;
    /* The "internal check" of 0x2003: is the cause of entry i still present? An entry whose cause is gone
     * can be deleted, and is forgotten at an NMT reset node. */
    bool (*cause)(device_t *dev, unsigned i);
    /* Can entry i occur in this instance (variant)? NULL: every entry. */
    bool (*available)(const device_t *dev, unsigned i);
    /* Entry i was raised (true) or deleted (false): the device updates HV, status bits and the OD. May be NULL. */
    void (*changed)(device_t *dev, unsigned i, bool raised);
    char nvm_magic[4];              /* first bytes of the CO_NVM_DEVICE blob */
    uint8_t hv_counter_sub;         /* first sub-index of the HV-on counter in 0x2000 (operating time: 0x01) */
    bool bit_timing_9_off;          /* 0x2002:07 = 9 means "CANopen communication deactivated" */
} eltex_class_t;

/* The shared part of the model state (the first member of the device's model). */
typedef struct eltex {
    const eltex_class_t *cls;
    uint64_t active;                /* bit i: entry i of the table is active */
    /* counters (E13) */
    co_time_us_t last;              /* time the counters were integrated to */
    uint64_t op_us;                 /* operating time including the stored part */
    uint64_t hv_us;                 /* HV-on time including the stored part */
    uint64_t saved_minute;          /* operating minute, counted from the save phase, last written to NVM */
    uint64_t shown_op_minute;       /* op_us and hv_us in minutes as 0x2000 shows them (publish on change) */
    uint64_t shown_hv_minute;
    bool nvm_error_logged;
    /* cyclic TPDOs (E12) */
    co_time_us_t tpdo_next;         /* next grid point, CO_NEVER outside Operational */
    /* node-ID and bit timing (E1-E4) */
    bool booting;                   /* between power_on and the first application reset */
    bool params_stored;             /* 0x1010 saved the parameters (no 0x1011 restore since): persistent */
    bool can_off;                   /* a saved 0x2002:07 = 9 (bit_timing_9_off devices): persistent */
    bool bt_switch;                 /* a saved 0x2002:07 waits for the next reset to switch the bit rate */
    uint8_t bt_effective;           /* bit-timing index the port runs at */
} eltex_t;

/* The shared state of a device that uses this module. */
eltex_t *eltex_of(device_t *dev);
const eltex_t *eltex_const(const device_t *dev);

/* ---- Lifecycle and class hooks ---------------------------------------------------------------------------- */

/* From the device's power_on, after it re-initialised its running state: resets the shared state, loads
 * the counters and flags from CO_NVM_DEVICE. */
void eltex_power_on(device_t *dev, const eltex_class_t *cls, co_time_us_t now);

/* The shared write rules: EDS limits for local writes (E6), measured objects not writable locally (E6),
 * 0x1017 (E5), 0x2002:01 restarts the TPDO grid (E12), 0x2002:07 indices without a bit rate (E2),
 * 0x2003:01/02 deletes an entry (E9). Call it first in the write hook (after hiding entries); 0 = no
 * objection, else the abort code to return. */
uint32_t eltex_on_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len, co_od_origin_t origin);

/* From on_reset. Application: the first one after power-on takes the bit rate the core set; entries whose
 * cause is gone are forgotten (E10). Communication: switches to a saved bit timing, puts 0x2002:06/07 to
 * what is in effect, reports every active entry again (after the boot-up, E11). */
void eltex_on_reset(device_t *dev, co_reset_t what);

/* From on_nmt_change: the TPDO grid starts on entering Operational and stops on leaving it. */
void eltex_on_nmt_change(device_t *dev, co_nmt_state_t to);

/* The class's on_event hook (0x1010 save, 0x1011 restore, LSS store, LSS activate bit timing). */
void eltex_on_event(device_t *dev, const co_event_t *ev);
/** The class's on_store: the device flags and the LSS area that belong to a store (E14). */
co_status_t eltex_on_store(device_t *dev, uint16_t index, uint8_t sub);

/* ---- Counters (E13) ------------------------------------------------------------------------------------------ */

/* Counts [last, t) as operating time, and as HV time when hv_on; writes 0x2000; saves at every completed
 * operating minute. */
void eltex_count(device_t *dev, co_time_us_t t, bool hv_on);

/* Writes the counters into 0x2000 (after an application reset re-initialised the area). */
void eltex_counters_publish(device_t *dev);

/* When the operating time completes its next minute (a deadline for the runner). */
co_time_us_t eltex_count_deadline(const device_t *dev, co_time_us_t now);

/* ---- Cyclic TPDOs (E12) --------------------------------------------------------------------------------------- */

/* Triggers every TPDO at a due grid point (Operational only) and keeps the grid; returns the next grid
 * point or CO_NEVER. */
co_time_us_t eltex_tpdo_step(device_t *dev, co_time_us_t now);

/* ---- Errors and warnings (E7-E11) --------------------------------------------------------------------------- */

bool eltex_fault_active(const device_t *dev, unsigned i);
/* Any active entry of this type with all of these flags (0: any)? */
bool eltex_any_active(const device_t *dev, uint8_t type, uint8_t flags);
/* Index of (type, code) in the table, or -1. */
int eltex_fault_find(const device_t *dev, uint8_t type, uint8_t code);
/* Raises entry i (EMCY, then changed()); false when it was active already. */
bool eltex_fault_raise(device_t *dev, unsigned i);
/* Raises every inactive, available entry for which pred holds: warnings first, then errors (E8). */
void eltex_faults_raise_where(device_t *dev, eltex_fault_pred_t pred, const void *ctx);
/* The request of 0x2003:01/02 and of the clear-error/clear-warning commands: 0 (deleted, confirmation EMCY
 * sent) or the abort code (E9). */
uint32_t eltex_fault_clear(device_t *dev, uint8_t type, uint8_t code);
/* The commands error/warning/clear-error/clear-warning CODE and faults; DEVICE_CMD_UNKNOWN for others. */
device_cmd_result_t eltex_fault_command(device_t *dev, int argc, const char *const *argv);
#define ELTEX_FAULT_COMMANDS_HELP                                                                             \
    "  error CODE / warning CODE   raise an error / a warning of the table (EMCY type 0x01 / 0x05, latched)\n" \
    "  clear-error CODE            delete it as 0x2003:01 does (same checks, confirmation EMCY)\n"             \
    "  clear-warning CODE          delete it as 0x2003:02 does\n"                                              \
    "  faults                      the error/warning table with the active entries"

/* ---- Helpers ---------------------------------------------------------------------------------------------------- */

/* floor(sqrt(x)). */
uint64_t eltex_isqrt(uint64_t x);

#ifdef __cplusplus
}
#endif
#endif /* ELTEX_H */
