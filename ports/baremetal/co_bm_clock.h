/*
 * Microsecond time (co_time_us_t: 64 bits that never wrap, or 32 bits with CO_CONFIG_TIME32) from a wrapping
 * hardware counter: a free-running
 * timer (16, 24 or 32 bits, any frequency) or a millisecond tick counter incremented by an interrupt
 * (SysTick: 32 bits at 1000 Hz). The conversion is exact (the remainder is kept), so there is no drift.
 *
 * Rule: co_bm_clock_now() must be called at least once per counter period (2^bits / hz seconds: 71 min
 * for a 32-bit 1 MHz timer, 49 days for a 32-bit ms tick, only 65 ms for a 16-bit 1 MHz timer, which
 * then needs a call from its overflow interrupt or a periodic wake-up). It is not reentrant: call it
 * from one context (the main loop), never from the CAN interrupt.
 */
#ifndef CO_BM_CLOCK_H
#define CO_BM_CLOCK_H

#include "co/co_types.h"

typedef struct co_bm_clock {
    uint32_t (*read)(void *ctx); /**< Raw counter value; counts up and wraps from 2^bits - 1 to 0. */
    void *ctx;
    uint32_t hz;                 /**< Counter frequency. */
    uint32_t mask;               /**< 2^bits - 1. */
    uint32_t last;               /**< Raw value at the previous call. */
    uint32_t rem;                /**< Sub-microsecond remainder, in 1/hz µs units. */
    co_time_us_t us;             /**< Time at the previous call. */
} co_bm_clock_t;

/** Starts the clock at 0 µs (or any start value) from the counter's current value. bits: 1..32. */
void co_bm_clock_init(co_bm_clock_t *c, uint32_t (*read)(void *ctx), void *ctx, uint32_t hz, uint8_t bits,
                      co_time_us_t start_us);

/** Current time in µs: the ticks since the previous call (one wrap at most) converted and added. */
co_time_us_t co_bm_clock_now(co_bm_clock_t *c);

/** Converts an absolute deadline into counter ticks from now (for arming a compare or wake-up timer);
 *  0 when it is due, saturates at max_ticks. */
uint32_t co_bm_clock_ticks_until(const co_bm_clock_t *c, co_time_us_t now, co_time_us_t deadline, uint32_t max_ticks);

#endif /* CO_BM_CLOCK_H */
