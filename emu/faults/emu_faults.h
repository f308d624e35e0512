/*
 * Protocol fault injection: a node made to misbehave on the bus the way real devices do, so that a master's
 * error handling can be tested (docs/emulator.md "Protocol faults"). The faults sit between the node and its bus:
 * frames the node receives may be dropped or answered in its place, frames it sends may be dropped, changed or
 * delayed. The core and the device model never know: what they do is what a healthy device would do.
 *
 *   fault NODE sdo-ignore [N | P% [SEED]]   ignore the next N SDO requests (default 1), or a share P of them
 *   fault NODE sdo-delay MS                  answer every SDO request MS ms late
 *   fault NODE sdo-abort INDEX[:SUB] CODE    answer requests for that object with the abort code
 *   fault NODE heartbeat-stop                send no heartbeat (boot-ups still go out)
 *   fault NODE heartbeat-jitter MS           send each heartbeat 0..MS ms late (random)
 *   fault NODE heartbeat-state BYTE          send this state byte in the heartbeat
 *   fault NODE tpdo-freeze N                 TPDO N (1..4) keeps sending the data it had
 *   fault NODE tpdo-drop N EVERY             drop every EVERY-th frame of TPDO N
 *   fault NODE tpdo-length N LEN             send TPDO N with LEN (0..8) data bytes
 *   fault NODE emcy-burst COUNT [CODE]       COUNT EMCY frames at once, past the inhibit time (one-shot)
 *   fault NODE reboot                        restart silently, as after a brown-out (one-shot)
 *   fault NODE bus-off MS                    no frame out or in for MS ms, then recover (EMCY 0x8140)
 *   fault NODE lss-silent                    no answer to LSS
 *   fault-clear NODE [KIND | all]            end faults (all when no KIND is given)
 *   faults NODE                              the node's faults and their effect
 */
#ifndef EMU_FAULTS_H
#define EMU_FAULTS_H

#include <stdbool.h>
#include <stdint.h>

#include "co/co.h"
#include "faults/fault_kinds.h" /* fault_kind_t; the kinds' names, usages and texts */
#include "runtime/emu_output.h"

struct emu_node;

/** Frames a fault holds back (SDO answers, heartbeats) per node; more are sent without the delay. */
#define FAULT_DELAYED_MAX 32U

typedef struct fault_tpdo {
    bool freeze;
    bool have_frozen;
    uint8_t frozen[8];
    uint8_t frozen_len;
    uint32_t drop_every;    /* 0: none */
    uint32_t drop_count;
    int16_t length;         /* -1: none */
} fault_tpdo_t;

typedef struct fault_delayed {
    co_time_us_t due;
    co_frame_t frame;
} fault_delayed_t;

typedef struct node_faults {
    uint32_t active;                /* bit per fault_kind_t (the lasting ones) */
    uint32_t sdo_ignore_left;       /* requests still to ignore; 0 with sdo_ignore_ppm: a share */
    uint32_t sdo_ignore_ppm;        /* share of requests ignored, parts per million */
    uint64_t rng;                   /* xorshift64 state: a share ignores the same requests with the same seed */
    uint32_t sdo_delay_ms;
    uint16_t abort_index;
    uint8_t abort_sub;
    bool abort_whole_object;        /* INDEX without :SUB: every sub-index */
    uint32_t abort_code;
    uint32_t hb_jitter_ms;
    uint8_t hb_state;
    fault_tpdo_t tpdo[CO_TPDO_MAX];
    co_time_us_t bus_off_until;
    fault_delayed_t delayed[FAULT_DELAYED_MAX];
    uint32_t n_delayed;
    unsigned long dropped;          /* frames the faults dropped, both ways */
} node_faults_t;

void faults_init(node_faults_t *f);

/** No fault is active and no frame is held: faults_rx/_tx/_run have nothing to do (inline: the common case costs
 *  the callers a compare, not a call). */
static inline bool faults_none(const node_faults_t *f) { return (f->active | f->n_delayed) == 0U; } /* one test */

/** A frame for the node: false when a fault takes it (dropped, or answered in the node's place). */
bool faults_rx(struct emu_node *n, const co_frame_t *frame, co_time_us_t now);

typedef enum fault_tx {
    FAULT_TX_SEND = 0,      /* send it (the fault may have changed it) */
    FAULT_TX_DROP,          /* lost, as on a bus it never reached */
    FAULT_TX_HELD           /* held back: faults_run sends it when due */
} fault_tx_t;

/** A frame the node sends: what the faults do with it (frame may be changed). */
fault_tx_t faults_tx(struct emu_node *n, co_frame_t *frame, co_time_us_t now);

/** Sends the frames that are due, ends a bus-off; returns when it must run again (CO_NEVER: nothing waits). */
co_time_us_t faults_run(struct emu_node *n, co_time_us_t now);

/** The fault commands of the command language (fault, fault-clear, faults) for one node; replies to `to`
 *  (emu_output.h). 0: done; 1: refused (the reply says why). argv[0] is the command. */
int faults_command(struct emu_node *n, int argc, char **argv, co_time_us_t now, const reply_sink_t *to);

#endif /* EMU_FAULTS_H */
