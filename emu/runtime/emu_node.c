/* One emulated node and its port: see emu_node.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_node.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/emu_bus.h"
#include "runtime/emu_events.h"
#include "runtime/emu_output.h"

static co_status_t port_nvm_write(void *ctx, co_nvm_area_t a, uint32_t off, const void *d, size_t len)
{
    return nvm_file_write(&((emu_node_t *)ctx)->nvm, a, off, d, len);
}
static co_status_t port_nvm_commit(void *ctx, co_nvm_area_t a, uint32_t total)
{
    return nvm_file_commit(&((emu_node_t *)ctx)->nvm, a, total);
}
static co_status_t port_nvm_read(void *ctx, co_nvm_area_t a, uint32_t off, void *d, size_t len)
{
    return nvm_file_read(&((emu_node_t *)ctx)->nvm, a, off, d, len);
}
static co_status_t port_bit_rate(void *ctx, uint32_t kbit)
{
    emu_node_t *n = (emu_node_t *)ctx;
    if (n->bus->can.kind != CAN_CHANNEL_SOCKETCAN) {
        logline(LOG_NORMAL, "node %u (%s): bit rate %lu kbit/s requested; a %s bus has none", co_node_id(&n->dev.node),
                n->dev.cls->name, (unsigned long)kbit, can_channel_kind_name(n->bus->can.kind));
        return CO_OK;
    }
    logline(LOG_NORMAL, "node %u (%s): bit rate %lu kbit/s requested; the interface's rate is the system's "
            "(ip link set %s type can bitrate %lu000)", co_node_id(&n->dev.node), n->dev.cls->name,
            (unsigned long)kbit, n->bus->can.name, (unsigned long)kbit);
    return CO_OK;
}

emu_node_t *node_create(emu_bus_t *bus, bool first_bus, const node_spec_t *spec, const char *nvm_dir,
                        co_time_us_t power_on)
{
    const device_class_t *cls = spec->cls;
    emu_node_t *n = calloc(1U, sizeof *n);
    if (n == NULL) {
        output_error("out of memory");
        return NULL;
    }
    n->values = calloc(1U, cls->od->values_size);
    n->model = cls->model_size > 0U ? calloc(1U, cls->model_size) : NULL;
    if (n->values == NULL || (cls->model_size > 0U && n->model == NULL)) {
        output_error("out of memory");
        node_destroy(n);
        return NULL;
    }
    n->cmdline_id = spec->id;
    n->bus = bus;
    faults_init(&n->faults);
    /* Nodes on the first interface keep the files they had before there were several buses. */
    if (first_bus) {
        (void)snprintf(n->key, sizeof n->key, "%s-%u", cls->name, spec->id);
    } else {
        (void)snprintf(n->key, sizeof n->key, "%s-%u@%s", cls->name, spec->id, bus->can.name);
    }
    char err[512];
    n->dev.cls = cls; /* for logs before device_init */
    if (nvm_file_open(&n->nvm, nvm_dir, n->key, err, sizeof err) != 0) {
        output_error("%s", err);
        node_destroy(n);
        return NULL;
    }
    n->port.send = bus_node_send;
    n->port.nvm_write = port_nvm_write;
    n->port.nvm_commit = port_nvm_commit;
    n->port.nvm_read = port_nvm_read;
    n->port.set_bit_rate = port_bit_rate;
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = spec->id;
    cfg.serial = device_default_serial(cls) + spec->id; /* distinct LSS identities (docs/emulator.md) */
    cfg.variant = spec->variant[0] != '\0' ? spec->variant : NULL;
    cfg.port = &n->port;
    cfg.port_ctx = n;
    cfg.print = events_device_print;
    cfg.print_ctx = n;
    cfg.on_event = events_device_event;
    cfg.event_ctx = n;
    bus_add_node(bus, n); /* before the power-on: its boot-up goes to the bus's other nodes too */
    const co_status_t st = device_init(&n->dev, cls, n->values, n->model, &cfg, power_on);
    if (st != CO_OK) {
        output_error("%s:%u: the node could not start (%d)", cls->name, spec->id, (int)st);
        bus_remove_last_node(bus, n);
        node_destroy(n);
        return NULL;
    }
    logline(LOG_NORMAL, "node %u (%s%s%s) on %s, NVM %s/%s.*", co_node_id(&n->dev.node), cls->name,
            spec->variant[0] != '\0' ? "/" : "", spec->variant, bus->can.name, nvm_dir, n->key);
    return n;
}

void node_destroy(emu_node_t *n)
{
    if (n == NULL) {
        return;
    }
    if (n->dev.cls != NULL) {
        nvm_file_close(&n->nvm);
    }
    free(n->values);
    free(n->model);
    free(n);
}
