/*
 * The device framework: an instance's life (set-up, power cycles, the hook trampolines into the device class), its
 * output, and what the class's generated tables tell of its objects. The commands every device understands are in
 * device_commands.c, typed values in device_value.c, the command language's words in device_words.c.
 */
#include "device.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static device_t *dev_of(void *ctx) { return (device_t *)ctx; }

static uint32_t tramp_write(void *ctx, co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                            co_od_origin_t origin)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    if (e->index >= 0x2000U) {
        dev->touched = true; /* a communication object is the core's: no step for it (an SDO client's 0x1017) */
    }
    return dev->cls->on_write != NULL ? dev->cls->on_write(dev, e, data, len, origin) : 0U;
}

static uint32_t tramp_read(void *ctx, co_node_t *node, const co_od_entry_t *e)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    return dev->cls->on_read != NULL ? dev->cls->on_read(dev, e) : 0U;
}

static void tramp_nmt(void *ctx, co_node_t *node, co_nmt_state_t from, co_nmt_state_t to)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    dev->touched = true;
    if (dev->cls->on_nmt_change != NULL) {
        dev->cls->on_nmt_change(dev, from, to);
    }
}

static void tramp_reset(void *ctx, co_node_t *node, co_reset_t what)
{
    device_t *dev = dev_of(ctx);
    dev->touched = true;
    if (what == CO_RESET_COMMUNICATION && dev->cfg.serial != 0U) {
        (void)co_od_set_u32(node, 0x1018, 4, dev->cfg.serial); /* the 0x1000 area was just re-initialised */
    }
    if (dev->cls->on_reset != NULL) {
        dev->cls->on_reset(dev, what);
    }
}

static co_status_t tramp_store(void *ctx, co_node_t *node, uint16_t index, uint8_t sub)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    dev->touched = true;
    return dev->cls->on_store != NULL ? dev->cls->on_store(dev, index, sub) : CO_OK;
}

static void tramp_event(void *ctx, co_node_t *node, const co_event_t *ev)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    if (ev->kind != CO_EV_RX_FILTER && ev->kind != CO_EV_TX_DROPPED) {
        dev->touched = true; /* an LSS change, a timeout, an EMCY...: the model may follow it */
    }
    if (dev->cls->on_event != NULL) {
        dev->cls->on_event(dev, ev);
    }
    if (dev->cfg.on_event != NULL) {
        dev->cfg.on_event(dev->cfg.event_ctx, dev, ev);
    }
}

static co_status_t boot(device_t *dev, co_time_us_t now)
{
    dev->now = now;
    dev->touched = true;
    co_od_copy_defaults(dev->cls->od, 0U, dev->cls->od->values_size, dev->values);
    /* The model block is not cleared here: power_on re-initialises the running state and keeps the
     * environment (device.h). */
    if (dev->cls->power_on != NULL) {
        dev->cls->power_on(dev, now);
    }
    co_node_cfg_t nc;
    memset(&nc, 0, sizeof nc);
    nc.od = dev->cls->od;
    nc.values = dev->values;
    nc.port = dev->cfg.port;
    nc.port_ctx = dev->cfg.port_ctx;
    nc.hooks = &dev->hooks;
    nc.hooks_ctx = dev;
    nc.node_id = dev->cfg.node_id;
    nc.bit_timing = dev->cls->default_bit_timing;
    nc.bit_rates_kbit = dev->cls->bit_rates_kbit;
    nc.options = dev->cls->core_options;
    uint8_t *core_state = (uint8_t *)dev->model;
    const device_class_t *cls = dev->cls;
    if (cls->rpdo_count > 0U || cls->tpdo_count > 0U || cls->sdo_server_count > 0U) {
        nc.rpdo = (co_rpdo_t *)core_state;
        nc.rpdo_count = cls->rpdo_count;
        core_state += (size_t)cls->rpdo_count * sizeof(co_rpdo_t);
        nc.tpdo = (co_tpdo_t *)core_state;
        nc.tpdo_count = cls->tpdo_count;
        core_state += (size_t)cls->tpdo_count * sizeof(co_tpdo_t);
        nc.sdo_servers = (co_sdo_server_t *)core_state;
        nc.sdo_server_count = cls->sdo_server_count;
        core_state += (size_t)cls->sdo_server_count * sizeof(co_sdo_server_t);
        nc.routes = (co_rx_route_t *)core_state;
        nc.route_count = (uint16_t)(CO_RX_ROUTES_FIXED + cls->rpdo_count + cls->sdo_server_count);
    }
    return co_node_init(&dev->node, &nc, now);
}

size_t device_core_state_size(const device_class_t *cls)
{
    if (cls->rpdo_count == 0U && cls->tpdo_count == 0U && cls->sdo_server_count == 0U) {
        return 0U; /* the node's own arrays */
    }
    const size_t size = (size_t)cls->rpdo_count * sizeof(co_rpdo_t) + (size_t)cls->tpdo_count * sizeof(co_tpdo_t) +
                        (size_t)cls->sdo_server_count * sizeof(co_sdo_server_t) +
                        (CO_RX_ROUTES_FIXED + (size_t)cls->rpdo_count + cls->sdo_server_count) * sizeof(co_rx_route_t);
    return (size + 15U) & ~(size_t)15U; /* the model's state that follows keeps any alignment it needs */
}

co_status_t device_init(device_t *dev, const device_class_t *cls, void *values, void *model, const device_cfg_t *cfg,
                        co_time_us_t now)
{
    if (dev == NULL || cls == NULL || values == NULL || cfg == NULL || (cls->model_size > 0U && model == NULL)) {
        return CO_ERR_ARG;
    }
    memset(dev, 0, sizeof *dev);
    dev->cls = cls;
    dev->values = values;
    dev->model = model;
    dev->cfg = *cfg;
    if (dev->cfg.node_id == 0U) {
        dev->cfg.node_id = cls->default_node_id;
    }
    if (cfg->variant != NULL) {
        bool found = false;
        for (uint8_t i = 0U; cls->variants != NULL && cls->variants[i] != NULL; i++) {
            if (strcmp(cls->variants[i], cfg->variant) == 0) {
                dev->variant = i;
                found = true;
            }
        }
        if (!found) {
            return CO_ERR_ARG;
        }
    }
    dev->hooks.on_write = tramp_write;
    dev->hooks.on_read = tramp_read;
    dev->hooks.first_index = cls->hooks_first_index;
    dev->hooks.on_nmt_change = tramp_nmt;
    dev->hooks.on_reset = tramp_reset;
    dev->hooks.on_event = tramp_event;
    dev->hooks.on_store = tramp_store;
    if (cls->model_size > 0U) {
        memset(model, 0, cls->model_size); /* only here: a power cycle keeps the environment */
    }
    if (cls->init != NULL) {
        cls->init(dev);
    }
    return boot(dev, now);
}

co_status_t device_power_cycle(device_t *dev, co_time_us_t now) { return boot(dev, now); }

void device_clear_running_state(device_t *dev, size_t env_offset, size_t env_size)
{
    uint8_t *m = (uint8_t *)dev->model;
    const size_t size = dev->cls->model_size;
    if (m == NULL || env_offset > size || env_size > size - env_offset) {
        return;
    }
    memset(m, 0, env_offset);
    memset(m + env_offset + env_size, 0, size - env_offset - env_size);
}

void device_printf(const device_t *dev, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (dev->replies != NULL) {
        if (dev->replies->print != NULL) {
            dev->replies->print(dev->replies->ctx, dev, line);
        }
    } else if (dev->cfg.print != NULL) {
        dev->cfg.print(dev->cfg.print_ctx, dev, line);
    }
}

/* The text of sub-index e in a table with one per sub-index of the dictionary, in order (a run of the table's rows
 * has one text per sub-index). */
static const char *row_text(const device_class_t *cls, const char *const *table, const co_od_entry_t *e)
{
    const co_od_t *od = cls->od;
    size_t ordinal = 0U;
    for (uint16_t i = 0U; table != NULL && i < od->count; i++) {
        const co_od_entry_t *row = &od->entries[i];
        const unsigned k = (unsigned)(e->sub - row->sub);
        if (row->index == e->index && e->sub >= row->sub && k < co_od_entry_subs(row)) {
            return table[ordinal + k];
        }
        ordinal += co_od_entry_subs(row);
    }
    return NULL;
}

const char *device_object_name(const device_class_t *cls, const co_od_entry_t *e)
{
    return row_text(cls, cls->od_names, e);
}

const char *device_object_unit(const device_class_t *cls, const co_od_entry_t *e)
{
    return row_text(cls, cls->od_units, e);
}

const char *device_object_title(const device_class_t *cls, uint16_t index)
{
    const co_od_t *od = cls->od;
    size_t lo = 0U;
    size_t hi = cls->od_object_names != NULL && od->objects != NULL ? od->n_objects : 0U;
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2U;
        if (od->objects[mid].index < index) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return lo < od->n_objects && cls->od_object_names != NULL && od->objects != NULL && od->objects[lo].index == index
               ? cls->od_object_names[lo]
               : NULL;
}

co_time_us_t device_save_phase_us(const device_t *dev)
{
    return (co_time_us_t)(dev->cfg.node_id % 60U) * 1000000U;
}

uint32_t device_default_serial(const device_class_t *cls)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(cls->od, 0x1018, 4, &one);
    uint32_t serial = 0U;
    if (e != NULL && e->size == sizeof serial) {
        co_od_copy_defaults(cls->od, e->offset, sizeof serial, &serial);
    }
    return serial;
}

const device_class_t *device_find_class(const char *name)
{
    for (size_t i = 0U; device_classes[i] != NULL; i++) {
        if (strcmp(device_classes[i]->name, name) == 0) {
            return device_classes[i];
        }
    }
    return NULL;
}
