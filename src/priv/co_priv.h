/*
 * Internal interfaces between the core's service modules. Not installed; applications use include/co/.
 * Each service module (co_nmt.c, co_hb.c, ...) exposes here its rx/process/reset functions and the
 * checks it applies to writes of the communication objects it owns.
 */
#ifndef CO_PRIV_H
#define CO_PRIV_H

#include <string.h>

#include "co/co.h"

/* ---- Little-endian codec: CANopen puts every multi-byte number on the wire LSB first. ---- */
static inline uint16_t co_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (uint16_t)(p[1] << 8)); }
static inline uint32_t co_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline void co_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void co_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
/* The earlier of two deadlines (CO_NEVER is later than any). */
static inline co_time_us_t co_min_time(co_time_us_t a, co_time_us_t b)
{
#if CO_CONFIG_TIME32
    if (a == CO_NEVER || b == CO_NEVER) {
        return a == CO_NEVER ? b : a;
    }
#endif
    return co_time_before(b, a) ? b : a;
}

/* The time us after t, as a deadline: with 32-bit time a sum that lands on CO_NEVER (no deadline) is taken 1 µs
 * earlier, or the service would never be due again. */
static inline co_time_us_t co_time_after(co_time_us_t t, uint32_t us)
{
    const co_time_us_t d = (co_time_us_t)(t + us);
#if CO_CONFIG_TIME32
    return d == CO_NEVER ? d - 1U : d;
#else
    return d;
#endif
}

/* A time that has not come yet; CO_NEVER: none. */
static inline bool co_time_pending(co_time_us_t now, co_time_us_t t) { return t != CO_NEVER && !co_time_reached(now, t); }

/* With 32-bit time, a time that has come is set to CO_NEVER: kept, it would look ahead again 2^31 µs later. (64-bit
 * time keeps it: a past time stays past.) */
static inline void co_time_retire(co_time_us_t now, co_time_us_t *t)
{
#if CO_CONFIG_TIME32
    if (co_time_reached(now, *t)) {
        *t = CO_NEVER;
    }
#else
    (void)now;
    (void)t;
#endif
}

/* What a service whose state holds a past-to-be time t (an inhibit time's end) returns when nothing else is due:
 * with 32-bit time, t itself, so that a pass comes then and retires it (sets it to CO_NEVER) before the clock
 * wraps far enough to make it look ahead again; with 64-bit time nothing (a past time stays past). */
#if CO_CONFIG_TIME32
#define CO_TIME32_RETIRE(t) (t)
#else
#define CO_TIME32_RETIRE(t) CO_NEVER
#endif

/* Time arithmetic without 64-bit multiplication or division: on a 32-bit core without them in hardware (Cortex-M0+)
 * they would link libgcc's __aeabi_lmul and __aeabi_uldivmod (~500 bytes) for the periodic services. */

/* Long timers (life guarding: up to 4.6 hours; the SYNC timeout: up to 107 minutes): a deadline at most
 * CO_TIME_STEP_MS ahead, which a 32-bit time holds safely, and the ms still to wait after it. */
#define CO_TIME_STEP_MS 1000000U /* 16.7 minutes */
static inline co_time_us_t co_long_timer_start(co_time_us_t now, uint32_t ms, uint32_t *rest_ms)
{
    const uint32_t step = ms > CO_TIME_STEP_MS ? CO_TIME_STEP_MS : ms;
    *rest_ms = ms - step;
    return co_time_after(now, step * 1000U);
}
/* True when the timer has run out at time now; else its deadline moves on by as many steps as have passed (a late
 * call may have missed several: the deadline returned is never in the past). */
static inline bool co_long_timer_expired(co_time_us_t now, co_time_us_t *deadline, uint32_t *rest_ms)
{
    while (co_time_reached(now, *deadline)) {
        if (*rest_ms == 0U) {
            return true;
        }
        const uint32_t step = *rest_ms > CO_TIME_STEP_MS ? CO_TIME_STEP_MS : *rest_ms;
        *rest_ms -= step;
        *deadline = co_time_after(*deadline, step * 1000U);
    }
    return false;
}

/* a / b and a % b by binary long division (b > 0), for the rare paths that divide (a late periodic timer, a long
 * timer's start): a core without a divide instruction (Cortex-M0+, AVR) links no ~270-byte library division. */
uint32_t co_div_u32(uint32_t a, uint32_t b, uint32_t *rem);
static inline uint32_t co_rem_u32(uint32_t a, uint32_t b)
{
    uint32_t r;
    (void)co_div_u32(a, b, &r);
    return r;
}

/* The first deadline after now on the grid due + k * period (k >= 1, due <= now, period > 0): a late call does not
 * shift the grid. More than 2^32 µs late (71 minutes without a call), a new grid starts at now. */
static inline co_time_us_t co_next_on_grid(co_time_us_t due, uint32_t period, co_time_us_t now)
{
    const co_time_us_t late = now - due;
    if (late < period) {
        return co_time_after(due, period);
    }
#if CO_CONFIG_TIME32
    return co_time_after(now, period - co_rem_u32(late, period));
#else
    return co_time_after(now, period - (late <= UINT32_MAX ? co_rem_u32((uint32_t)late, period) : 0U));
#endif
}

/* COB-ID bits (0x1005, 0x1014, 0x14xx/0x18xx sub 1). */
#define CO_COBID_INVALID 0x80000000UL
#define CO_COBID_NO_RTR 0x40000000UL   /* TPDO: no RTR */
#define CO_COBID_SYNC_GEN 0x40000000UL /* 0x1005: this node produces the SYNC */
#define CO_COBID_FRAME 0x20000000UL    /* 29-bit frame */
#define CO_COBID_CAN_ID 0x000007FFUL

/* ---- OD internals (co_od.c) ---- */
uint8_t *co_od_ptr(co_node_t *node, const co_od_entry_t *e);
/* Raw value get/set of a row (native LE bytes in the values block); u32 helpers widen/narrow 1..4 bytes. */
uint32_t co_od_entry_u32(const co_node_t *node, const co_od_entry_t *e);
void co_od_entry_set_u32(co_node_t *node, const co_od_entry_t *e, uint32_t v);
/* Same by index/sub; 'fallback' when the row does not exist. */
uint32_t co_od_u32_or(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t fallback);
/* Re-initialises the rows with first <= index <= last from defaults (node-ID added) then stored values. */
void co_od_reset_area(co_node_t *node, uint16_t first, uint16_t last);
/* Number of sub-indices > 0 an object has in the table (e.g. size of 0x1003 or 0x1016). */
uint8_t co_od_sub_count(const co_od_t *od, uint16_t index);
/* The table row that holds (index, sub) (a run holds several sub-indices), or NULL: its flags, type, size and limits
 * are the sub-index's; its sub and offset are the run's first (co_od_entry_at() narrows). */
const co_od_entry_t *co_od_find_row(const co_od_t *od, uint16_t index, uint8_t sub);
/* True when the dictionary has (index, sub). */
bool co_od_exists(const co_od_t *od, uint16_t index, uint8_t sub);
/* Index of the first row of an object, or od->count. */
uint16_t co_od_first_row(const co_od_t *od, uint16_t index);
/* The abort code of a row co_od_find did not find: 0x06020000 no such object, 0x06090011 no such sub-index. */
uint32_t co_od_missing(const co_od_t *od, uint16_t index);
/* co_od_write of a row already found (no second look-up). */
uint32_t co_od_write_entry(co_node_t *node, const co_od_entry_t *e, const void *data, size_t len,
                           co_od_origin_t origin);
/* Writes an entry's value from a buffer; len may be shorter for strings (rest zeroed). No checks. */
void co_od_store_value(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);
/* Reads a row for a PDO or SDO after the device's read hook (no access check). Returns bytes copied. */
size_t co_od_sample(co_node_t *node, const co_od_entry_t *e, uint8_t *buf, size_t cap);
/* The checks a stored value of e passes before it is loaded (CO_ORIGIN_NVM): limits, the owner module's value
 * rules, the write hook. 0 or the abort code an SDO write of it would get. */
uint32_t co_od_check_stored(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);
/* Sets the values of [first, last] to their defaults (node-ID-relative rows with the node-ID added). */
void co_od_defaults_area(co_node_t *node, uint16_t first, uint16_t last);
/* A large object's row (co_hooks_t.large_read): a string or domain of size 0, whose value the application keeps. */
static inline bool co_od_is_large(const co_od_entry_t *e)
{
    return CO_CONFIG_LARGE_OBJECTS && e->size == 0U && co_od_type_has_length(e->type);
}
#if CO_CONFIG_LARGE_OBJECTS
/* The hooks of a large object, or 0x06010000 without them. */
uint32_t co_od_large_read(co_node_t *node, const co_od_entry_t *e, uint32_t offset, uint8_t *buf, size_t len,
                          uint32_t *length);
uint32_t co_od_large_write(co_node_t *node, const co_od_entry_t *e, co_large_step_t step, uint32_t at,
                           const uint8_t *data, size_t len);
/* co_od_read/co_od_write of a large object, in one piece (co_sdo_large.c: out of the paths of the numbers). The read
 * returns the abort code in its high 32 bits and the length in its low ones. */
uint64_t co_od_read_large(co_node_t *node, const co_od_entry_t *e, uint8_t *buf, size_t cap);
uint32_t co_od_write_large(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);
#endif

/* ---- node (co_node.c) ---- */
/* The services of co_node_process(), in the order it runs them: their index (co_node_t.svc_due) and their bit of
 * co_node_t.wake. A module that changes a service's state outside that service's process function (a frame, an API
 * call, a written parameter) marks it, so that the next pass runs it and takes its new deadline, or, where only a
 * timer moved, gives the new deadline (co_node_due); a pass at next_due runs the services whose deadline came. */
enum co_service_index {
    CO_SVC_I_LSS,
    CO_SVC_I_HB,
    CO_SVC_I_GUARD,
    CO_SVC_I_HBC,
    CO_SVC_I_SDO,
    CO_SVC_I_SYNC,
    CO_SVC_I_PDO,
    CO_SVC_I_EMCY
};
enum co_service {
    CO_SVC_LSS = 1U << CO_SVC_I_LSS,
    CO_SVC_HB = 1U << CO_SVC_I_HB,
    CO_SVC_GUARD = 1U << CO_SVC_I_GUARD,
    CO_SVC_HBC = 1U << CO_SVC_I_HBC,
    CO_SVC_SDO = 1U << CO_SVC_I_SDO,
    CO_SVC_SYNC = 1U << CO_SVC_I_SYNC,
    CO_SVC_PDO = 1U << CO_SVC_I_PDO,
    CO_SVC_EMCY = 1U << CO_SVC_I_EMCY,
    CO_SVC_ALL = 0xFFU
};
/* The services compiled in: a mark of one left out would never be taken, and every pass would return now. */
#define CO_SVC_PRESENT                                                                                            \
    ((unsigned)CO_SVC_ALL & ~((CO_CONFIG_NODE_GUARDING ? 0U : (unsigned)CO_SVC_GUARD) |                             \
                              (CO_CONFIG_HB_CONSUMER ? 0U : (unsigned)CO_SVC_HBC) |                                \
                              (CO_CONFIG_SYNC ? 0U : (unsigned)CO_SVC_SYNC)))
/* Bucket of a CAN-ID in co_node_t.route_hash: the low node-ID bits mixed with the function code, so that the
 * COB-IDs of one node and those of its neighbours fall apart. */
#define CO_ROUTE_HASH(id) ((unsigned)((id) ^ ((id) >> 7)) & 15U)
static inline void co_node_wake(co_node_t *node, unsigned services)
{
    node->wake = (uint8_t)(node->wake | (services & CO_SVC_PRESENT));
}
/* A service's new deadline, where its change needs no pass of the service now (a timer restarted by a frame):
 * the service (its index) runs no later than t, and the next pass comes no later than t. */
static inline void co_node_due(co_node_t *node, enum co_service_index service, co_time_us_t t)
{
    /* inline: an RPDO's and a SYNC's reception restart a timer here */
    node->svc_due[service] = co_min_time(node->svc_due[service], t);
    node->next_due = co_min_time(node->next_due, t);
}

/* Queues/sends a frame through the port; frames are retried when the port is busy. */
void co_node_send(co_node_t *node, const co_frame_t *frame);
void co_node_event(co_node_t *node, co_event_kind_t kind, uint16_t index, uint8_t sub, uint32_t value,
                   uint32_t code);
void co_node_set_state(co_node_t *node, co_nmt_state_t state);
/* Keeps a function out of its callers where the compiler can be told (GCC, Clang): the early return of a hot function
 * (co_node_rx: a frame for other nodes) then saves no registers for the rest of its work. */
#if defined(__GNUC__)
#define CO_NOINLINE __attribute__((noinline))
#else
#define CO_NOINLINE
#endif

/* co_node_rx() of a frame that may be the node's (after its early return). */
CO_NOINLINE bool co_node_take(co_node_t *node, const co_frame_t *frame);
/* The processing pass of co_node_process() (after its early return). */
co_time_us_t co_node_pass(co_node_t *node, co_time_us_t now);
/* Rebuilds the frame router's table (after a reset and whenever a COB-ID the node takes changes); reports
 * CO_EV_RX_FILTER. */
void co_node_routes_update(co_node_t *node);

/* ---- NMT (co_nmt.c) ---- */
void co_nmt_rx(co_node_t *node, const co_frame_t *f);

/* ---- Heartbeat producer (co_hb.c) ---- */
void co_hb_written(co_node_t *node, const co_od_entry_t *e);
/* A reset takes 0x1017 as a write of it would: one path, so the period's start is one copy of the code. */
static inline void co_hb_reset(co_node_t *node) { co_hb_written(node, NULL); }
/* Sends a state byte on 0x700 + node-ID: the heartbeat (node->nmt_state), or the boot-up (CO_NMT_INITIALISING). */
void co_hb_send(co_node_t *node, co_nmt_state_t state);
co_time_us_t co_hb_process(co_node_t *node);
/* Any value of 0x1017 within its limits goes: range limits come from the OD, device-specific steps from the device
 * hook. */
static inline uint32_t co_hb_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    (void)node;
    (void)e;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}

/* ---- Heartbeat consumer (co_hb_consumer.c) ---- */
void co_hbc_reset(co_node_t *node);
/* A data frame on 0x701..0x77F: true when it is a heartbeat this node consumes. */
bool co_hbc_rx(co_node_t *node, const co_frame_t *f);
co_time_us_t co_hbc_process(co_node_t *node);
uint32_t co_hbc_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);
void co_hbc_written(co_node_t *node, const co_od_entry_t *e);

/* ---- Node guarding (co_guard.c) ---- */
void co_guard_reset(co_node_t *node);
void co_guard_rx(co_node_t *node, const co_frame_t *f);
co_time_us_t co_guard_process(co_node_t *node);
void co_guard_written(co_node_t *node);

/* The modules' write checks take `stored`: true for a stored value being loaded (co_od_check_stored), which is
 * judged as a value only, not as a change of the present configuration (CiA 301's procedures for changing a
 * valid PDO or EMCY COB-ID do not apply to the values a store of the whole configuration brings back). */

/* ---- EMCY (co_emcy.c) ---- */
void co_emcy_reset(co_node_t *node);
co_time_us_t co_emcy_process(co_node_t *node);
uint32_t co_emcy_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored);
uint32_t co_emcy_check_read(co_node_t *node, const co_od_entry_t *e);
void co_emcy_written(co_node_t *node);
bool co_emcy_write_action(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);

/* ---- SDO server (co_sdo_server.c; block transfer in co_sdo_block.c) ---- */
enum co_sdo_state {
    CO_SDO_IDLE = 0,
    CO_SDO_SEG_DOWNLOAD = 1,
    CO_SDO_SEG_UPLOAD = 2,
    CO_SDO_BLK_DOWNLOAD = 3,     /* receiving the segments of a block */
    CO_SDO_BLK_DOWNLOAD_END = 4, /* last segment confirmed, waiting for the end request */
    CO_SDO_BLK_UPLOAD_START = 5, /* initiate answered, waiting for the start request */
    CO_SDO_BLK_UPLOAD = 6,       /* sending a block, or waiting for its confirmation */
    CO_SDO_BLK_UPLOAD_END = 7    /* end request sent, waiting for the end response */
};
co_status_t co_sdo_count(co_node_t *node, co_sdo_server_t *servers, uint8_t capacity);
void co_sdo_reset(co_node_t *node);
void co_sdo_rx(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f);
co_time_us_t co_sdo_process(co_node_t *node);
#if CO_CONFIG_SDO_SERVERS
uint32_t co_sdo_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored);
void co_sdo_written(co_node_t *node, const co_od_entry_t *e);
#endif
/* The transfer's object (s->index, s->sub) is the request's from its initiate on, or 0 and 0 (a segment with no
 * transfer open). A response to the client: cmd, the object's multiplexer, then the four data bytes, data as a
 * little-endian number (a size, an abort code, an expedited value: co_get_u32 of its bytes, 0 past them). */
void co_sdo_respond(co_node_t *node, const co_sdo_server_t *s, uint8_t cmd, uint32_t data);
/* A frame of a transfer without multiplexer: cmd, then len <= 7 bytes of data (NULL: zeros). */
void co_sdo_send(co_node_t *node, const co_sdo_server_t *s, uint8_t cmd, const uint8_t *data, size_t len);
/* Ends the transfer with an abort of its object. */
void co_sdo_abort(co_node_t *node, co_sdo_server_t *s, uint32_t code);
/* Starts a transfer of the request's object (co_sdo_rx then starts its timeout). */
void co_sdo_start(co_sdo_server_t *s, uint8_t state, uint32_t size);
uint32_t co_sdo_download_checks(const co_node_t *node, co_sdo_server_t *s, bool sized, uint32_t size, bool staged);
void co_sdo_download_end(co_node_t *node, co_sdo_server_t *s, uint32_t len, bool crc_ok, uint8_t answer);
/* CRC-16 of CiA 301 block transfer (x^16 + x^12 + x^5 + 1), continued from crc over len more bytes. */
uint16_t co_sdo_crc(uint16_t crc, const uint8_t *data, uint32_t len);

/* ---- Large objects over SDO (co_sdo_large.c; CO_CONFIG_LARGE_OBJECTS): the buffer holds a piece of the value, the
 * application's hooks the rest. Without them these are what an ordinary transfer does, and cost nothing. ---- */
#if CO_CONFIG_LARGE_OBJECTS
#define CO_SDO_IS_LARGE(s) ((s)->large)
#define CO_SDO_DONE(s) ((s)->done)
/* An upload whose object did not fit the buffer (co_od_read: 0x06070012): a large object's length in *len, the
 * transfer then reads it piece by piece; 0x05040005 for an object too large for the buffer that is not one. */
uint32_t co_sdo_large_upload(co_node_t *node, co_sdo_server_t *s, size_t *len);
const uint8_t *co_sdo_large_bytes(co_node_t *node, co_sdo_server_t *s, uint32_t offset, size_t n);
/* A large download: BEGIN with the indicated size; before n more bytes go into the buffer, what it holds goes to the
 * application when they would not fit (room); at the end, the rest (flush). 0 or the abort code. */
uint32_t co_sdo_large_begin(co_node_t *node, co_sdo_server_t *s, uint32_t size);
uint32_t co_sdo_large_room(co_node_t *node, co_sdo_server_t *s, uint32_t n);
uint32_t co_sdo_large_flush(co_node_t *node, co_sdo_server_t *s, uint32_t len);
uint32_t co_sdo_large_end(co_node_t *node, co_sdo_server_t *s, uint32_t len);
/* The CRC of a large upload's len bytes (read piece by piece); false when a read failed (and the abort was sent). */
bool co_sdo_large_crc(co_node_t *node, co_sdo_server_t *s, uint16_t *crc);
/* A large download that ends without its END: ABORT to the application. */
void co_sdo_large_drop(co_node_t *node, co_sdo_server_t *s);
#else
#define CO_SDO_IS_LARGE(s) false
#define CO_SDO_DONE(s) 0U
static inline uint32_t co_sdo_large_upload(co_node_t *node, co_sdo_server_t *s, size_t *len)
{
    (void)node;
    (void)s;
    (void)len;
    return CO_ABORT_OUT_OF_MEMORY;
}
#endif
/* n bytes of the upload from offset: in the buffer, or a large object's read into it (NULL: failed, abort sent). */
static inline const uint8_t *co_sdo_upload_bytes(co_node_t *node, co_sdo_server_t *s, uint32_t offset, size_t n)
{
#if CO_CONFIG_LARGE_OBJECTS
    if (s->large) {
        return co_sdo_large_bytes(node, s, offset, n);
    }
#endif
    (void)node;
    (void)n;
    return &s->buf[offset];
}
/* The transfer is over (any way): a large download not completed is dropped. */
static inline void co_sdo_end(co_node_t *node, co_sdo_server_t *s)
{
#if CO_CONFIG_LARGE_OBJECTS
    if (s->large) {
        co_sdo_large_drop(node, s);
    }
#else
    (void)node;
#endif
    s->state = CO_SDO_IDLE;
}
#if CO_CONFIG_SDO_BLOCK
/* The upload initiate's read and answer, for the block upload (which may switch to it). */
bool co_sdo_read_object(co_node_t *node, co_sdo_server_t *s, size_t *len);
void co_sdo_upload_answer(co_node_t *node, co_sdo_server_t *s, size_t len);
void co_sdo_block_initiate(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *data);
bool co_sdo_block_rx(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f);
co_time_us_t co_sdo_block_process(co_node_t *node, co_sdo_server_t *s);
#endif

/* ---- Multiplexed PDOs (co_mpdo.c) ---- */
#define CO_MPDO_SAM 0xFEU /* mapping sub 0 of a source address mode MPDO */
#define CO_MPDO_DAM 0xFFU /* ... of a destination address mode MPDO */
#if CO_CONFIG_MPDO
/* Fills the 8 bytes of the next SAM-MPDO of the scanner list (after p->scan_next, wrapping); false when the list
 * has no object that can go out. */
bool co_mpdo_sam_next(co_node_t *node, co_tpdo_t *p, uint8_t frame[8]);
/* An MPDO received by RPDO p (8 bytes): written to the object it addresses (1), ignored (0), or a DAM-MPDO whose
 * object could not be written (-1: EMCY 0x8230, raised by the caller). */
int co_mpdo_receive(co_node_t *node, const co_rpdo_t *p, const uint8_t frame[8]);
#endif

/* ---- SYNC (co_sync.c) ---- */
void co_sync_reset(co_node_t *node);
void co_sync_rx(co_node_t *node, const co_frame_t *f);
co_time_us_t co_sync_process(co_node_t *node);
uint32_t co_sync_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len, bool stored);
void co_sync_written(co_node_t *node, const co_od_entry_t *e);
#if CO_CONFIG_SYNC
/* The CAN-ID of the SYNCs the node takes from the bus: 0x1005's, none without it or while the node produces them. */
static inline uint16_t co_sync_rx_id(const co_node_t *node)
{
#if CO_CONFIG_SYNC_PRODUCER
    if (node->sync.producer) {
        return CO_NO_CAN_ID;
    }
#endif
    return node->sync.can_id;
}
#endif

/* ---- PDO (co_pdo.c) ---- */
void co_pdo_reset(co_node_t *node);
/* A frame on the COB-ID of RPDO n. */
void co_rpdo_rx(co_node_t *node, uint16_t n, const co_frame_t *f);
co_time_us_t co_pdo_process(co_node_t *node);
void co_pdo_on_sync(co_node_t *node, uint8_t counter);
void co_pdo_on_state(co_node_t *node, co_nmt_state_t from, co_nmt_state_t to);
#if CO_CONFIG_TPDO_RTR
/* A remote frame on id: true when a TPDO answers remote requests there (valid, COB-ID bit 30 clear, type 252..255),
 * which answers it in Operational: 252 with what the last SYNC sampled, 253 sampled now, 254/255 as an event. */
bool co_tpdo_rtr(co_node_t *node, uint16_t id);
/* The lowest CAN-ID >= from on which a TPDO answers remote requests, or 0x800 (co_node_rx_ids). */
uint32_t co_tpdo_rtr_next(const co_node_t *node, uint32_t from);
#endif
uint32_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored);
void co_pdo_written(co_node_t *node, const co_od_entry_t *e);
co_status_t co_pdo_count(co_node_t *node);

/* ---- Store / restore (co_store.c) ---- */
uint32_t co_store_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len);
/* Loads stored values of the rows first..last into the values block. Sets node->nvm_status. */
void co_store_load_area(co_node_t *node, uint16_t first, uint16_t last);
co_status_t co_store_lss_save(co_node_t *node, uint8_t node_id, uint8_t bit_timing);
co_nvm_status_t co_store_lss_load(co_node_t *node, uint8_t *node_id, uint8_t *bit_timing);

/* ---- LSS slave (co_lss_slave.c) ---- */
void co_lss_init(co_node_t *node);
void co_lss_rx(co_node_t *node, const co_frame_t *f);
co_time_us_t co_lss_process(co_node_t *node);

/* ---- COB-ID rules shared by SYNC, EMCY, PDO and SDO servers (co_node.c) ---- */
/* True when a CAN-ID may not be used for SYNC/TIME/EMCY/PDO/SDO (CiA 301 restricted identifiers). */
bool co_cob_id_restricted(uint32_t can_id);
/* CiA 301 rules for a new COB-ID v (old cur) of a PDO or an additional SDO server: 11-bit CAN-IDs only (bit 29 and
 * the reserved bits 11..28 clear; bit 30 is not looked at), no restricted CAN-ID while valid, and the CAN-ID of an
 * object in use changes only by way of "not valid". 0 or 0x06090030. */
uint32_t co_cob_id_check(uint32_t v, uint32_t cur, bool in_use);

#endif /* CO_PRIV_H */
