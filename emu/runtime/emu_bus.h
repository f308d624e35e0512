/*
 * One bus of canopen-emu and the nodes on it. All nodes of a bus share one channel (a SocketCAN socket, a multicast
 * group's sockets or none: can_channel.h): a frame read from
 * the bus is given to the nodes of the bus that take its CAN-ID (a table per CAN-ID, from each node's
 * co_node_rx_ids, kept up to date by CO_EV_RX_FILTER: the cost of a frame does not grow with the number of nodes),
 * and a frame one node sends is also given to the bus's other nodes (the kernel does not loop a socket's frames back to itself), through a
 * queue drained by the main loop so that no node is re-entered while it runs. One socket instead of one per node
 * keeps the system calls per bus frame at one, which matters with 127 nodes. Buses are independent: a node-ID is
 * unique per bus, each bus has its own channel and its own error handling (socketcan.c, udp_multicast.c).
 */
#ifndef EMU_BUS_H
#define EMU_BUS_H

#include <signal.h>

#include "runtime/emu.h"

/** Opens the bus's channel (b->emu set by the caller) and logs what the user should know of it (where a multicast
 *  group is joined); 0, or an errno with a message in err. */
int bus_open(emu_bus_t *b, const can_channel_spec_t *spec, int log_level, char *err, size_t errlen);

/** Adds a node (at most MAX_NODES); sets its bus and index. */
void bus_add_node(emu_bus_t *b, emu_node_t *n);

/** The node added last leaves the bus (its start failed): its routes, its place in the schedule. */
void bus_remove_last_node(emu_bus_t *b, emu_node_t *n);

/** The node's CAN-IDs changed (CO_EV_RX_FILTER, and once it is added): the routing table follows. */
void bus_routes_update(emu_bus_t *b, const emu_node_t *n);

/** The node leaves the routing table. */
void bus_routes_remove(emu_bus_t *b, const emu_node_t *n);

/** A node's frame: onto the interface, and, once sent, queued for the bus's other nodes. */
co_status_t bus_send(emu_bus_t *b, emu_node_t *from, const co_frame_t *f);

/** co_port_t.send of every node (ctx: its emu_node_t): bus_send, through the node's faults when it has any
 *  (emu_faults.h: a frame may be dropped, changed or held back). */
co_status_t bus_node_send(void *ctx, const co_frame_t *f);

/** One pass of the main loop for the bus. First what woke it (revents of its socket): reads what the interface has (at
 *  most 1024 frames) and gives each frame to the nodes that take it, stopping early once the clock reaches due (the
 *  loop's earliest deadline) so that timers run between frames of a flood; after POLLOUT, the nodes with queued
 *  frames retry. Then offers the queued frames of local nodes to the others and processes every node that is due or
 *  was concerned by a frame or a command, until no local frame waits. *now: the time of the pass, read again after
 *  each batch of a flood. Returns the earliest deadline of its nodes and of the interface; *tx_pending tells whether a
 *  node has frames the interface did not take yet. */
co_time_us_t bus_pass(emu_bus_t *b, co_time_us_t *now, short revents, co_time_us_t due, bool *tx_pending);

/** The main loop while it has one bus and nothing else to wait for: no control input, control socket or web view, no
 *  script line to come (none of them appears later), no output waiting. The same pass and sleep as loop_run's for
 *  that case, without looking at what is not there. Returns 0 when output waits to be written (loop_run polls for
 *  that), at quit or on a signal, 1 when poll fails. revents: what woke the bus last; *now: the time of the pass;
 *  *next: the deadline of its last pass, for a flood's reading. */
int bus_run_alone(emu_t *emu, const volatile sig_atomic_t *stop, co_time_us_t *now, co_time_us_t *next,
                  short revents);

/** A frame from outside the program that did not come through the bus's medium (a socketcand client's): an event,
 *  the overview's heard nodes and the nodes that take it, as a frame read from the medium. now: the time of the
 *  pass; the nodes run at the bus's next pass. */
void bus_frame_in(emu_bus_t *b, const co_frame_t *f, co_time_us_t now);

/** The exit report of the bus (its lost frames), its counts added to sent, dropped and rx_lost; closes the channel. */
void bus_close(emu_bus_t *b, unsigned long *sent, unsigned long *dropped, unsigned long *rx_lost);

#endif /* EMU_BUS_H */
