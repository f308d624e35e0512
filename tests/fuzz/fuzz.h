/*
 * libFuzzer harness of the CANopen slave core and the emulated devices: the engine (fuzz_harness.c) decodes
 * the input into power-on, frames, time steps, process calls, control commands, power cycles, port faults
 * and NVM corruption, and checks the invariants after every call; a target (target_core.c or
 * target_device.c) says how to run one node. Input format and invariants: docs/fuzzing.md.
 */
#ifndef FUZZ_H
#define FUZZ_H

#include <stdio.h>
#include <stdlib.h>

#include "co/co.h"
#include "fake_port.h"

/* ---- Input reader: reading past the end gives zeros --------------------------------------------------- */

typedef struct fz_in {
    const uint8_t *p;
    size_t n;
    size_t pos;
} fz_in_t;

uint8_t fz_u8(fz_in_t *in);
uint16_t fz_u16(fz_in_t *in);
uint32_t fz_u32(fz_in_t *in);
uint64_t fz_u64(fz_in_t *in);

/* ---- Engine state ------------------------------------------------------------------------------------- */

typedef enum fz_call {
    FZ_CALL_NONE = 0,
    FZ_CALL_INIT,    /* co_node_init / device_init */
    FZ_CALL_RX,      /* co_node_rx / device_rx of h->rx */
    FZ_CALL_PROCESS, /* co_node_process / device_process */
    FZ_CALL_APP,     /* a control command or an application call of the core API */
    FZ_CALL_POWER    /* a power cycle */
} fz_call_t;

typedef struct fz {
    fake_port_t fp;           /* first member: the port functions get &fp as ctx and cast it back */
    co_port_t port;           /* fp.port with send replaced by the checking one; NVM functions optional */
    co_time_us_t now;
    co_time_us_t next;        /* deadline returned by the last process call */
    bool dirty;               /* a frame arrived since the last process call */
    unsigned long sends;      /* calls of the port's send, all of them (the skip oracle counts them) */
    bool after_process;       /* the last call was a (device) process call: its deadline is all a runner keeps */

    /* Set by the target at init. */
    co_node_t *node;
    const co_od_t *od;
    uint8_t *values;
    uint32_t options;         /* the node's CO_OPT_* */
    const char *target;

    /* Read-only rows: the rows checked, the values expected now and the power-on image. */
    co_od_entry_t *ro_subs;         /* the read-only sub-indices (those of a run one by one) */
    uint16_t n_ro;
    bool has_history;               /* the OD has 0x1003 */
    uint8_t history_subs;           /* its sub-indices 1..n */
    uint8_t *expect;
    uint8_t *poweron;
    uint8_t poweron_id;
    bool er_skip;             /* 0x1001 was overwritten by a local write: not comparable until the next EMCY/reset */

    /* The call in progress. */
    fz_call_t call;
    co_frame_t rx;
    co_nmt_state_t state0;
    uint8_t id0;
    bool sdo_open0;           /* a segmented or block transfer was open when the call began */
    uint8_t sdo_state0;       /* the SDO server's state then (enum co_sdo_state) */
    bool clean0;              /* port healthy, TX queue empty, not silenced: a response must go out at once */
    uint32_t sdo_resp;        /* SDO responses sent directly during the call */
    uint32_t lss_resp;
    uint32_t guard_resp;
    uint32_t bootups;
    uint32_t resets;          /* bit 0: communication area re-initialised, bit 1: application area */
    bool reset_in_call;       /* the node reset during the call in progress (a device may reset in its step) */
    uint32_t sdo_timeouts;    /* CO_EV_SDO_ABORT with 0x05040000 during the call */
    uint32_t emcy_events;

    /* Whole-run ledger of SDO requests and responses (covers frames that waited in the TX queue). */
    uint64_t sdo_req_total;
    uint64_t sdo_resp_total;
    uint64_t sdo_timeout_total;
    uint64_t sdo_segments_allowed; /* block upload segments the requests so far allowed (127 per block) */

    uint32_t step;            /* records decoded so far, for messages */
    uint32_t loop_budget;     /* process calls left for time loops in this input */
} fz_t;

/* Reports an invariant violation and aborts (libFuzzer saves the input). */
#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 2, 3)))
#endif
void fz_fail(const fz_t *h, const char *fmt, ...);

/* True when FUZZ_IGNORE lists the tag of a known bug: its check is skipped (default: nothing skipped). */
bool fz_known(const char *tag);

/* Called by the target's hooks. */
void fz_note_reset(fz_t *h, co_reset_t what);
void fz_note_event(fz_t *h, const co_event_t *ev);

/* ---- Target interface (target_core.c or target_device.c) ------------------------------------------------ */

/* Powers the node on from the 4 header bytes; sets h->node/od/values/options. False when the configuration
 * was (correctly) refused: the input ends there. h->port is ready. */
bool fzt_init(fz_t *h, const uint8_t hdr[4]);
void fzt_fini(fz_t *h);
/* A frame: true when the node took it (co_node_rx / device_rx); *pending: it left work for the pass, as a runner of
 * many nodes learns it (taken, and not co_node_settled / device_settled on the last deadline). */
bool fzt_rx(fz_t *h, const co_frame_t *f, bool *pending);
/* direct: the device target calls co_node_process without the model step. */
co_time_us_t fzt_process(fz_t *h, bool direct);
/* A control command / application call decoded from the input. Returns true when it may have changed
 * read-only values legitimately (a local write), false for pure reads. */
bool fzt_app(fz_t *h, fz_in_t *in);
/* A power cycle with the configuration of fzt_init; false when it failed (an invariant violation). */
bool fzt_power_cycle(fz_t *h);
/* Read-only rows the device or the core may change (process values, counters); 0x1001/0x1003 are
 * checked separately and need not be listed. */
bool fzt_ro_exempt(const co_od_entry_t *e);

#endif /* FUZZ_H */
