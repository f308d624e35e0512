/**
 * @file co_types.h
 * @brief Basic types shared by every part of the CANopen slave core: time, CAN frames, status codes.
 *
 * Contract: time is always a caller-supplied monotonic count of microseconds (co_time_us_t). With 64-bit time (the
 * default on a host) it never wraps in practice (2^64 µs is 584,000 years). With CO_CONFIG_TIME32 (co_config.h: the
 * default on a microcontroller) it is 32 bits wide and wraps every 71.6 minutes: compare times with co_time_before() / co_time_reached(), never with < or >=.
 */
#ifndef CO_TYPES_H
#define CO_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "co_config.h"

#ifdef __cplusplus
extern "C" {
#endif

#if CO_CONFIG_TIME32
/** Monotonic time in microseconds, supplied by the caller; wraps every 2^32 µs. */
typedef uint32_t co_time_us_t;
/** "No deadline": returned by the process functions when nothing is due, ever. Never a deadline itself. */
#define CO_NEVER UINT32_MAX
/** Time a is earlier than time b (they are less than 2^31 µs apart). */
static inline bool co_time_before(co_time_us_t a, co_time_us_t b) { return (int32_t)(a - b) < 0; }
/** The deadline has come at time now (CO_NEVER never comes). */
static inline bool co_time_reached(co_time_us_t now, co_time_us_t deadline)
{
    return deadline != CO_NEVER && (int32_t)(now - deadline) >= 0;
}
#else
/** Monotonic time in microseconds, supplied by the caller. */
typedef uint64_t co_time_us_t;
/** "No deadline": returned by the process functions when nothing is due, ever. */
#define CO_NEVER UINT64_MAX
/** Time a is earlier than time b. */
static inline bool co_time_before(co_time_us_t a, co_time_us_t b) { return a < b; }
/** The deadline has come at time now (CO_NEVER never comes: no time reaches it). */
static inline bool co_time_reached(co_time_us_t now, co_time_us_t deadline) { return now >= deadline; }
#endif

/** Frame flag: remote transmission request (RTR). */
#define CO_FRAME_RTR 0x01U
/** Frame flag: 29-bit extended identifier. The core ignores such frames (CANopen uses 11-bit IDs). */
#define CO_FRAME_EFF 0x02U
/** Frame flag: error frame reported by the controller. The core ignores such frames. */
#define CO_FRAME_ERR 0x04U

/** A classic CAN frame. */
typedef struct co_frame {
    uint32_t id;      /**< CAN identifier (11 bits for CANopen). */
    uint8_t len;      /**< Data length code, 0..8. */
    uint8_t flags;    /**< CO_FRAME_RTR / CO_FRAME_EFF / CO_FRAME_ERR. */
    uint8_t data[8];  /**< Payload; bytes past len are undefined on receive and zero on transmit. */
} co_frame_t;

/** Status codes of the core's and the port's functions. */
typedef enum co_status {
    CO_OK = 0,           /**< Done. */
    CO_ERR_BUSY = -1,    /**< Port: no transmit slot now; the core keeps the frame and retries. */
    CO_ERR_IO = -2,      /**< Port: hardware or storage failure. */
    CO_ERR_NO_DATA = -3, /**< Port: nothing stored (or less than asked for). */
    CO_ERR_ARG = -4,     /**< Invalid argument or configuration. */
    CO_ERR_RANGE = -5    /**< Configuration exceeds a compile-time limit (see co_config.h). */
} co_status_t;

/** NMT states; the numeric value is the state byte of heartbeat and node-guarding frames. */
typedef enum co_nmt_state {
    CO_NMT_INITIALISING = 0x00,
    CO_NMT_STOPPED = 0x04,
    CO_NMT_OPERATIONAL = 0x05,
    CO_NMT_PRE_OPERATIONAL = 0x7F
} co_nmt_state_t;

/** Node-ID value meaning "not configured" (LSS only). */
#define CO_NODE_ID_UNCONFIGURED 0xFFU

typedef struct co_node co_node_t;

#ifdef __cplusplus
}
#endif
#endif /* CO_TYPES_H */
