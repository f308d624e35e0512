/*
 * Shared test fixture: one node of the test OD on a fake port with a simulated clock, plus helpers to
 * feed frames in candump-like notation and to assert exact frames out.
 */
#ifndef FIXTURE_H
#define FIXTURE_H

#include "fake_port.h"
#include "test_od.h"
#include "unity.h"

typedef struct fixture {
    co_node_t node;
    test_od_values_t values;
    fake_port_t port;
    co_time_us_t now;
    co_node_cfg_t cfg;
    uint32_t read_hooks;     /* on_read calls */
    uint32_t write_hooks;    /* on_write calls */
    uint32_t refuse_code;    /* on_write answers this (0 = accept) */
    uint16_t refuse_index;   /* ... for this index only (0 = all) */
    uint16_t hide_index;     /* on_read answers 0x06090011 for this index (0 = none) */
    co_nmt_state_t last_from, last_to;
    uint32_t nmt_changes;
    uint32_t resets_app, resets_comm;
    co_event_t events[64];
    uint32_t n_events;
    uint32_t store_hooks;    /* on_store calls */
    uint16_t store_index;    /* ... the last one's index and sub */
    uint8_t store_sub;
    bool store_device_area;  /* on_store stages 4 bytes "DEV1" in CO_NVM_DEVICE (CO_NVM_MORE) */
    bool store_fail;         /* on_store answers CO_ERR_IO (after staging, if it stages) */
} fixture_t;

extern fixture_t fx;   /* test-only global: each test program has exactly one fixture */
extern co_hooks_t fixture_hooks;

/* Powers the node on with node-ID id (options as co_node_cfg_t.options); clears the recorded frames
 * unless keep_bootup. */
void fx_start(uint8_t id, uint32_t options);
/* The same at time t0 instead of 0 (near the wrap of a 32-bit clock: tests/unit/test_time_wrap.c). */
void fx_start_at(uint8_t id, uint32_t options, co_time_us_t t0);
/* Re-runs co_node_init on the same values/port (a power cycle that keeps NVM). */
void fx_power_cycle(void);
/* Feeds a frame: fx_rx(0x605, 8, (uint8_t[]){...}). */
void fx_rx(uint32_t id, uint8_t len, const uint8_t *data);
void fx_rx_rtr(uint32_t id);
/* Advances the clock to t (absolute µs), calling co_node_process at every deadline on the way. */
void fx_run_until(co_time_us_t t);
/* Advances by d µs. */
void fx_advance(co_time_us_t d);
/* Calls co_node_process once at the current time. */
co_time_us_t fx_process(void);

/* SDO helpers: send 0x600+id request, expect one response; return it. */
const co_frame_t *fx_sdo(const uint8_t req[8]);
uint32_t fx_sdo_write_u32(uint16_t index, uint8_t sub, uint32_t v, uint8_t size); /* 0 or abort code */
uint32_t fx_sdo_read_u32(uint16_t index, uint8_t sub, uint32_t *v);               /* 0 or abort code */

/* Asserts that frame i of the recorded ones has this id/len/data. */
#define ASSERT_FRAME(i, id_, len_, ...)                                                  \
    do {                                                                                 \
        const uint8_t expect_[] = {__VA_ARGS__};                                         \
        TEST_ASSERT_TRUE_MESSAGE((i) < fx.port.n_sent, "frame missing");                 \
        TEST_ASSERT_EQUAL_HEX32((id_), fx.port.sent[(i)].id);                             \
        TEST_ASSERT_EQUAL_UINT8((len_), fx.port.sent[(i)].len);                           \
        if ((len_) > 0) {                                                                \
            TEST_ASSERT_EQUAL_HEX8_ARRAY(expect_, fx.port.sent[(i)].data, (len_));       \
        }                                                                                \
    } while (0)
#define ASSERT_FRAME0(i, id_)                                                            \
    do {                                                                                 \
        TEST_ASSERT_TRUE_MESSAGE((i) < fx.port.n_sent, "frame missing");                 \
        TEST_ASSERT_EQUAL_HEX32((id_), fx.port.sent[(i)].id);                             \
        TEST_ASSERT_EQUAL_UINT8(0, fx.port.sent[(i)].len);                                \
    } while (0)
#define RX(id, ...)                                                                      \
    do {                                                                                 \
        const uint8_t d_[] = {__VA_ARGS__};                                              \
        fx_rx((id), (uint8_t)sizeof d_, d_);                                             \
    } while (0)
#define RX0(id) fx_rx((id), 0U, NULL)

/* Number of recorded frames with this CAN-ID. */
uint32_t fx_count(uint32_t id);
/* Index of the last recorded frame with this CAN-ID, or -1. */
int fx_last(uint32_t id);

#endif
