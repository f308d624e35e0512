#include "co_bm_clock.h"

void co_bm_clock_init(co_bm_clock_t *c, uint32_t (*read)(void *ctx), void *ctx, uint32_t hz, uint8_t bits,
                      co_time_us_t start_us)
{
    c->read = read;
    c->ctx = ctx;
    c->hz = hz;
    c->mask = bits >= 32U ? UINT32_MAX : (uint32_t)((1UL << bits) - 1UL);
    c->last = read(ctx) & c->mask;
    c->rem = 0U;
    c->us = start_us;
}

co_time_us_t co_bm_clock_now(co_bm_clock_t *c)
{
    const uint32_t raw = c->read(c->ctx) & c->mask;
    const uint32_t ticks = (raw - c->last) & c->mask; /* modulo the counter width: the wrap is handled */
    c->last = raw;
    if (c->hz == 1000000UL) {
        c->us += ticks;
    } else {
        /* ticks * 10^6 < 2^52: no overflow; the remainder stays below hz. */
        const uint64_t scaled = (uint64_t)ticks * 1000000U + c->rem;
        c->us += (co_time_us_t)(scaled / c->hz);
        c->rem = (uint32_t)(scaled % c->hz);
    }
    return c->us;
}

uint32_t co_bm_clock_ticks_until(const co_bm_clock_t *c, co_time_us_t now, co_time_us_t deadline, uint32_t max_ticks)
{
    if (deadline == CO_NEVER) {
        return max_ticks;
    }
    if (!co_time_before(now, deadline)) { /* (wrap-safe with CO_CONFIG_TIME32) */
        return 0U;
    }
    const uint64_t us = (co_time_us_t)(deadline - now);
    if (us >= (UINT64_MAX / c->hz)) {
        return max_ticks;
    }
    const uint64_t ticks = (us * c->hz + 999999U) / 1000000U; /* rounded up: never wake up early */
    return ticks > max_ticks ? max_ticks : (uint32_t)ticks;
}
