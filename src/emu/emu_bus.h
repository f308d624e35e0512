/*
 * One CAN interface of canopen-emu and the nodes on it. All nodes of a bus share one CAN socket: a frame read from
 * the bus is offered to every node of the bus (the core ignores what is not for it), and a frame one node sends is
 * also offered to the bus's other nodes (the kernel does not loop a socket's frames back to itself), through a
 * queue drained by the main loop so that no node is re-entered while it runs. One socket instead of one per node
 * keeps the system calls per bus frame at one, which matters with 127 nodes. Buses are independent: a node-ID is
 * unique per bus, each bus has its own socket and its own error handling (socketcan.c).
 */
#ifndef EMU_BUS_H
#define EMU_BUS_H

#include "emu.h"

/** Opens the interface (b->emu set by the caller); 0, or an errno with a message in err. */
int bus_open(emu_bus_t *b, const char *ifname, int log_level, char *err, size_t errlen);

/** Adds a node (at most MAX_NODES); sets its bus and index. */
void bus_add_node(emu_bus_t *b, emu_node_t *n);

/** A node's frame: onto the interface, and, once sent, queued for the bus's other nodes. */
co_status_t bus_send(emu_bus_t *b, const emu_node_t *from, const co_frame_t *f);

/** Offers the queued frames of local nodes to the others, then processes every node that is due or was concerned
 *  by a frame or a command, until no local frame waits. Returns the earliest deadline of its nodes and of the
 *  interface; *tx_pending tells whether a node has frames the interface did not take yet. */
co_time_us_t bus_run(emu_bus_t *b, co_time_us_t now, bool *tx_pending);

/** Reads what the interface has (at most 1024 frames) and offers each frame to every node. */
void bus_receive(emu_bus_t *b, co_time_us_t now);

/** The interface has room again: the nodes with queued frames retry in the next pass. */
void bus_tx_ready(emu_bus_t *b);

/** The exit report of the bus (its lost frames), its counts added to sent, dropped and rx_lost; closes the socket. */
void bus_close(emu_bus_t *b, unsigned long *sent, unsigned long *dropped, unsigned long *rx_lost);

#endif /* EMU_BUS_H */
