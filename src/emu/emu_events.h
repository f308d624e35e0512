/*
 * What the nodes report, as the runtime shows it: a device's own messages (device_printf) as reply lines, the core's
 * events (NMT state changes, EMCY, SDO aborts sent, stores and restores, NVM loads, LSS changes, heartbeat and
 * guarding timeouts, frames not sent) as log lines of the level each deserves.
 */
#ifndef EMU_EVENTS_H
#define EMU_EVENTS_H

#include "device.h"

/** device_cfg_t.print of every node. */
void events_device_print(void *ctx, const device_t *dev, const char *line);

/** device_cfg_t.on_event of every node. */
void events_device_event(void *ctx, const device_t *dev, const co_event_t *ev);

#endif /* EMU_EVENTS_H */
