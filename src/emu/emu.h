/*
 * The canopen-emu program's state, shared by its modules: the nodes, the queue of frames between local nodes,
 * the control inputs. The program itself (main loop, ports of the nodes) is canopen_emu.c; the other modules are
 * emu_cmdline.c (the command line), emu_output.c (log and replies, never blocking), emu_commands.c (the command
 * language), emu_lines.c (command lines cut from a byte stream), emu_control.c (command lines from stdin),
 * emu_script.c (--script) and emu_fd_flags.c (stdin's O_NONBLOCK, cleared at exit).
 */
#ifndef EMU_H
#define EMU_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../linux/nvm_file.h"
#include "../linux/socketcan.h"
#include "device.h"
#include "emu_control.h"
#include "emu_script.h"

#define MAX_NODES 127

#define LOCAL_QUEUE_LEN 4096U

typedef struct emu_node {
    device_t dev;
    void *values;
    void *model;
    co_port_t port;
    nvm_file_t nvm;
    uint8_t cmdline_id;
    size_t index;           /* position in emu.nodes */
    char key[64];
    co_time_us_t deadline;  /* what device_process last returned */
    bool dirty;             /* a frame concerned the node or a command ran on it: process before sleeping */
} emu_node_t;

/* Frames sent by local nodes, waiting to be offered to the other local nodes. */
typedef struct local_frame {
    co_frame_t frame;
    size_t sender;
} local_frame_t;

typedef struct emu {
    emu_node_t *nodes[MAX_NODES];
    size_t n_nodes;
    socketcan_t can;
    local_frame_t local[LOCAL_QUEUE_LEN];
    size_t local_head;
    size_t local_count;
    unsigned long local_lost;
    co_time_us_t start;
    int log_level;          /* as given on the command line; emu_output.c keeps the same for logline() */
    emu_script_t script;
    emu_control_t control;
    bool quit;
} emu_t;

#endif /* EMU_H */
