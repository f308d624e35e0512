#include "fixture.h"

#include <string.h>

fixture_t fx;

static uint32_t hook_write(void *ctx, co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                           co_od_origin_t origin)
{
    fixture_t *f = (fixture_t *)ctx;
    (void)node;
    (void)data;
    (void)len;
    (void)origin;
    f->write_hooks++;
    if (f->refuse_code != 0U && (f->refuse_index == 0U || f->refuse_index == e->index)) {
        return f->refuse_code;
    }
    return 0U;
}

static uint32_t hook_read(void *ctx, co_node_t *node, const co_od_entry_t *e)
{
    fixture_t *f = (fixture_t *)ctx;
    (void)node;
    f->read_hooks++;
    return (f->hide_index != 0U && f->hide_index == e->index) ? CO_ABORT_NO_SUBINDEX : 0U;
}

static void hook_nmt(void *ctx, co_node_t *node, co_nmt_state_t from, co_nmt_state_t to)
{
    fixture_t *f = (fixture_t *)ctx;
    (void)node;
    f->last_from = from;
    f->last_to = to;
    f->nmt_changes++;
}

static void hook_reset(void *ctx, co_node_t *node, co_reset_t what)
{
    fixture_t *f = (fixture_t *)ctx;
    (void)node;
    if (what == CO_RESET_APPLICATION) {
        f->resets_app++;
    } else {
        f->resets_comm++;
    }
}

static void hook_event(void *ctx, co_node_t *node, const co_event_t *ev)
{
    fixture_t *f = (fixture_t *)ctx;
    (void)node;
    if (f->n_events < sizeof f->events / sizeof f->events[0]) {
        f->events[f->n_events++] = *ev;
    }
}

static co_status_t hook_store(void *ctx, co_node_t *node, uint16_t index, uint8_t sub)
{
    fixture_t *f = (fixture_t *)ctx;
    f->store_hooks++;
    f->store_index = index;
    f->store_sub = sub;
    if (f->store_device_area) {
        const co_port_t *p = node->port;
        if (p->nvm_write(node->port_ctx, CO_NVM_DEVICE, 0U, "DEV1", 4U) != CO_OK ||
            p->nvm_commit(node->port_ctx, CO_NVM_DEVICE, 4U | CO_NVM_MORE) != CO_OK) {
            return CO_ERR_IO;
        }
    }
    return f->store_fail ? CO_ERR_IO : CO_OK;
}

co_hooks_t fixture_hooks = {.on_write = hook_write, .on_read = hook_read, .on_nmt_change = hook_nmt, .on_reset = hook_reset,
                             .on_event = hook_event, .on_store = hook_store};

void fx_start(uint8_t id, uint32_t options) { fx_start_at(id, options, 0U); }

void fx_start_at(uint8_t id, uint32_t options, co_time_us_t t0)
{
    memset(&fx, 0, sizeof fx);
    fx.now = t0;
    fake_port_init(&fx.port, &fx.now);
    fx.cfg.od = &test_od;
    fx.cfg.values = &fx.values;
    fx.cfg.port = &fx.port.port;
    fx.cfg.port_ctx = &fx.port;
    fx.cfg.hooks = &fixture_hooks;
    fx.cfg.hooks_ctx = &fx;
    fx.cfg.node_id = id;
    fx.cfg.bit_timing = 4U;
    fx.cfg.options = options;
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&fx.node, &fx.cfg, fx.now));
}

void fx_power_cycle(void)
{
    TEST_ASSERT_EQUAL_INT(CO_OK, co_node_init(&fx.node, &fx.cfg, fx.now));
}

void fx_rx(uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t f = {id, len, 0U, {0U}};
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    co_node_rx(&fx.node, &f, fx.now);
    (void)co_node_process(&fx.node, fx.now);
}

void fx_rx_rtr(uint32_t id)
{
    const co_frame_t f = {id, 0U, CO_FRAME_RTR, {0U}};
    co_node_rx(&fx.node, &f, fx.now);
    (void)co_node_process(&fx.node, fx.now);
}

co_time_us_t fx_process(void) { return co_node_process(&fx.node, fx.now); }

void fx_run_until(co_time_us_t t)
{
    for (;;) {
        const co_time_us_t next = co_node_process(&fx.node, fx.now);
        if (next == CO_NEVER || co_time_before(t, next)) { /* (wrap-safe with 32-bit time) */
            break;
        }
        TEST_ASSERT_TRUE_MESSAGE(!co_time_before(next, fx.now), "deadline in the past");
        if (next == fx.now) {
            /* Due now and still due after processing: a service that does not advance would spin. */
            const co_time_us_t again = co_node_process(&fx.node, fx.now);
            TEST_ASSERT_TRUE_MESSAGE(again == CO_NEVER || co_time_before(fx.now, again),
                                     "process() did not advance its deadline");
            continue;
        }
        fx.now = next;
    }
    fx.now = t;
    (void)co_node_process(&fx.node, fx.now);
}

void fx_advance(co_time_us_t d) { fx_run_until(fx.now + d); }

const co_frame_t *fx_sdo(const uint8_t req[8])
{
    const uint32_t before = fx.port.n_sent;
    fx_rx(0x600U + co_node_id(&fx.node), 8U, req);
    TEST_ASSERT_EQUAL_UINT32_MESSAGE(before + 1U, fx.port.n_sent, "expected exactly one SDO response");
    const co_frame_t *f = &fx.port.sent[before];
    TEST_ASSERT_EQUAL_HEX32(0x580U + co_node_id(&fx.node), f->id);
    TEST_ASSERT_EQUAL_UINT8(8U, f->len);
    return f;
}

static uint32_t abort_code_of(const co_frame_t *f) {
    return (uint32_t)f->data[4] | ((uint32_t)f->data[5] << 8) | ((uint32_t)f->data[6] << 16) | ((uint32_t)f->data[7] << 24);
}

uint32_t fx_sdo_write_u32(uint16_t index, uint8_t sub, uint32_t v, uint8_t size)
{
    const uint8_t cmd = (uint8_t)(0x23U | ((4U - size) << 2));
    const uint8_t req[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub,
                            (uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    const co_frame_t *f = fx_sdo(req);
    if (f->data[0] == 0x80U) {
        return abort_code_of(f);
    }
    TEST_ASSERT_EQUAL_HEX8(0x60U, f->data[0]);
    return 0U;
}

uint32_t fx_sdo_read_u32(uint16_t index, uint8_t sub, uint32_t *v)
{
    const uint8_t req[8] = {0x40U, (uint8_t)index, (uint8_t)(index >> 8), sub, 0U, 0U, 0U, 0U};
    const co_frame_t *f = fx_sdo(req);
    if (f->data[0] == 0x80U) {
        return abort_code_of(f);
    }
    *v = abort_code_of(f);
    return 0U;
}

uint32_t fx_count(uint32_t id)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.port.n_sent; i++) {
        if (fx.port.sent[i].id == id) {
            n++;
        }
    }
    return n;
}

int fx_last(uint32_t id)
{
    for (uint32_t i = fx.port.n_sent; i > 0U; i--) {
        if (fx.port.sent[i - 1U].id == id) {
            return (int)(i - 1U);
        }
    }
    return -1;
}
