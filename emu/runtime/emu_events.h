/*
 * What the nodes report, as the runtime shows it: a device's own messages (device_printf) as reply lines, the core's
 * events (NMT state changes, EMCY, SDO aborts sent, stores and restores, NVM loads, LSS changes, heartbeat and
 * guarding timeouts, frames not sent) as log lines of the level each deserves; and each of them, with the
 * interfaces' troubles and the frames on the buses, as an event to the control sessions that subscribed
 * (emu_session.h), stamped with the emulator's clock (µs since its start, the log's clock).
 */
#ifndef EMU_EVENTS_H
#define EMU_EVENTS_H

#include "device.h"
#include "runtime/emu.h"

/** device_cfg_t.print of every node (ctx: its emu_node_t). */
void events_device_print(void *ctx, const device_t *dev, const char *line);

/** device_cfg_t.on_event of every node (ctx: its emu_node_t). */
void events_device_event(void *ctx, const device_t *dev, const co_event_t *ev);

/** Sessions that may subscribe (at most MAX_SESSIONS; a transport adds each and removes it before freeing it). */
void events_add_session(emu_t *emu, emu_session_t *s);
void events_remove_session(emu_t *emu, emu_session_t *s);

/** A line about the bus's interface (down, up, gone, back, error frames, lost frames). */
void events_interface(emu_bus_t *bus, const char *line);

/** A protocol fault of node n: kind ("sdo-ignore"...), action ("injected", "cleared", "ended"); logged too. */
void events_fault(emu_node_t *n, const char *kind, const char *action, const char *text);

/** Publishes a frame to the sessions whose subscription takes it (events_frame's work when a session exists). */
void events_frame_publish(emu_t *emu, emu_bus_t *bus, const emu_node_t *from, const co_frame_t *f, co_time_us_t at);

/** A frame on the bus at time at: sent by from, or received (from NULL). Inline: every frame comes this way, and
 *  without a session (the common case) it costs a comparison, not a call. bus->emu is set (before bus_open). */
static inline void events_frame(emu_bus_t *bus, const emu_node_t *from, const co_frame_t *f, co_time_us_t at)
{
    emu_t *emu = bus->emu;
    if (emu->n_sessions != 0U) {
        events_frame_publish(emu, bus, from, f, at);
    }
}

#endif /* EMU_EVENTS_H */
