/*
 * One emulated node: a device model (devices/device.h) with its port, whose CAN side is the node's bus
 * (emu_bus.h) and whose NVM side is the node's files (ports/linux/nvm_file.h), named by emu_node_t.key.
 */
#ifndef EMU_NODE_H
#define EMU_NODE_H

#include "runtime/emu.h"

/** What the command line asked for: DEVICE[/VARIANT][:NODE-ID][@BUS]. */
typedef struct node_spec {
    const device_class_t *cls;
    char variant[32];       /* "" for the default */
    uint8_t id;
    char bus[CAN_CHANNEL_NAME_MAX]; /* the text after @ (can_channel.h): "" for the first bus */
    size_t bus_index;       /* the bus it names, among the command line's (set by the caller of parse_spec) */
} node_spec_t;

/** Creates and powers on the node of spec on bus (key: see emu_node_t), then adds it to the bus. NULL, with a
 *  message, when it cannot start. first_bus: the bus is the process's first (its nodes keep the plain key). */
emu_node_t *node_create(emu_bus_t *bus, bool first_bus, const node_spec_t *spec, const char *nvm_dir,
                        co_time_us_t power_on);

void node_destroy(emu_node_t *n);

#endif /* EMU_NODE_H */
