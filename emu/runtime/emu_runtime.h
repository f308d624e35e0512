/*
 * The canopen-emu runtime: what the command line asked for (emu_config_t) started, then one loop that sleeps in a
 * single poll until the earliest deadline of any node, a frame on any bus, a control line, room in a blocked
 * output or a signal, and runs whatever is due.
 */
#ifndef EMU_RUNTIME_H
#define EMU_RUNTIME_H

#include "runtime/emu.h"
#include "runtime/emu_node.h"

typedef struct emu_config {
    can_channel_spec_t buses[MAX_BUSES]; /* the first is where nodes without @BUS go */
    size_t n_buses;
    node_spec_t specs[MAX_NODES_ALL];
    size_t n_specs;
    const char *nvm_dir;
    const char *script;              /* NULL: none */
    bool control;                    /* commands from stdin */
    const char *control_socket;      /* Unix socket path, or NULL */
    const char *control_tcp;         /* HOST:PORT, or NULL */
    const char *control_token_file;  /* the token TCP clients must give first, or NULL (required off loopback) */
    const char *web;                 /* HOST:PORT of the web view, or NULL */
    const char *socketcand;          /* HOST:PORT of the socketcand server, or NULL */
    int log_level;
} emu_config_t;

/** Opens the control sockets, the web view and the buses, powers the nodes on (one power-on time for all) and
 *  starts the control inputs. Returns 0, or the exit status (1) after a message. The script must be loaded already
 *  (emu->script). */
int runtime_start(emu_t *emu, const emu_config_t *cfg);

/** Runs until `quit`, SIGINT or SIGTERM; returns the exit status. */
int runtime_loop(emu_t *emu);

/** The exit summary; closes the buses and frees the nodes. */
void runtime_stop(emu_t *emu);

#endif /* EMU_RUNTIME_H */
