/*
 * The canopen-emu runtime's state, shared by its modules. Where each concern lives:
 *   canopen_emu.c   main: the options, then emu_runtime
 *   emu_runtime.c   start (buses, nodes), the exit summary; emu_loop.c the main loop (one poll for everything)
 *   emu_bus.c       one bus: its channel (ports/linux/can_channel.h), the frames between its local nodes, routing each frame to
 *                   the nodes that take its CAN-ID; emu_bus_pass.c a pass of the loop for it (frames in, nodes run)
 *   emu_node.c      one emulated node: the device, its port (CAN through its bus, NVM files)
 *   emu_faults.c    protocol faults injected between a node and its bus
 *   emu_events.c    what the nodes report (NMT changes, EMCY, aborts, stores...) turned into log lines
 *   emu_session.c   the control protocol: a session's lines (the command language or JSON: emu_json.c),
 *                   its answers and its event subscriptions; emu_control.c (stdin), emu_socket.c (the
 *                   control sockets; emu_tcp.c binds TCP) and emu_web.c (the web view, --web: HTTP checks and
 *                   answers in emu_web_checks.c, emu_web_answers.c, sessions in emu_web_sessions.c) are its
 *                   transports
 *   emu_socketcand.c  --socketcand: the buses as channels of linux-can socketcand's protocol (socketcand_proto.c)
 *   emu_commands.c  the command language; emu_script.c (--script) feeds it lines too; emu_lines.c cuts lines
 *   emu_cmdline.c   help, device list, DEVICE[/VARIANT][:NODE-ID][@IFACE] arguments
 *   emu_output.c    log and replies, never blocking; emu_fd_flags.c stdin's O_NONBLOCK, cleared at exit
 */
#ifndef EMU_H
#define EMU_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nvm_file.h"
#include "can_channel.h"
#include "device.h"
#include "control/emu_control.h"
#include "faults/emu_faults.h"
#include "runtime/emu_schedule.h"
#include "scripts/emu_script.h"
#include "control/emu_session.h"
#include "control/emu_socket.h"
#include "socketcand/emu_socketcand.h"
#include "web/emu_web.h"

/** Nodes on one bus: node-IDs 1..127. */
#define MAX_NODES 127 /* per bus: SCHEDULE_NODES_MAX */
/** CAN interfaces one process serves. */
#define MAX_BUSES 8
/** Nodes of one process, all buses. */
#define MAX_NODES_ALL (MAX_NODES * MAX_BUSES)

#define LOCAL_QUEUE_LEN 4096U
/** Control sessions: stdin, the clients of the control sockets, the web view's sessions. */
#define MAX_SESSIONS (1 + MAX_CLIENTS + WEB_SESSIONS_MAX)

struct emu_bus;
struct emu;

typedef struct emu_node {
    device_t dev;
    void *values;
    void *model;
    co_port_t port;
    nvm_file_t nvm;
    struct emu_bus *bus;
    uint8_t cmdline_id;
    size_t index;           /* position in its bus's nodes */
    char key[160];          /* NVM file name stem: DEVICE-ID, or DEVICE-ID@BUS on every bus but the first */
    node_faults_t faults;   /* protocol faults injected (emu_faults.h) */
    co_time_us_t last_heartbeat; /* when it last sent its heartbeat or boot-up (emulator clock), 0: never */
    struct {
        co_time_us_t at;    /* 0: no EMCY yet */
        uint16_t code;
        uint8_t reg;
        uint8_t info[5];
    } last_emcy;            /* the last EMCY it sent or queued (show) */
} emu_node_t;

/* Frames sent by local nodes, waiting to be offered to the other local nodes of the same bus. */
typedef struct local_frame {
    co_frame_t frame;
    size_t sender;
} local_frame_t;

/* A node-ID heard on the bus from outside the program (another emulator, a real device): its last heartbeat,
 * boot-up or node-guarding answer, for the overview (show all: "heard"). */
typedef struct heard_node {
    co_time_us_t at; /* when it was read; 0: never heard */
    uint8_t state;   /* the state byte without the guarding toggle bit: 0x00 boot-up, 0x04, 0x05, 0x7F */
} heard_node_t;

typedef struct emu_bus {
    struct emu *emu;
    can_channel_t can;      /* its medium: a SocketCAN interface, a multicast group, none (can_channel.h) */
    emu_node_t *nodes[MAX_NODES];
    size_t n_nodes;
    local_frame_t local[LOCAL_QUEUE_LEN];
    size_t local_head;
    size_t local_count;
    unsigned long local_lost;
    int log_level;
    uint64_t takes[0x800][2]; /* bit i (word i / 64): node i takes frames on this CAN-ID (co_node_rx_ids) */
    /* The nodes' deadlines (what device_process last returned, or earlier when a fault must run), the nodes marked
     * to run (a frame concerned them, a command or a fault changed them) and those with refused frames: a pass runs
     * only the nodes marked or due. */
    emu_schedule_t schedule;
    heard_node_t heard[128];  /* by node-ID; frames of this program's own nodes never come back to its socket */
    size_t socketcand_readers; /* socketcand clients in rawmode on this bus: its frames go to them (emu_socketcand.h) */
} emu_bus_t;

typedef struct emu {
    emu_bus_t *buses[MAX_BUSES];
    size_t n_buses;
    emu_node_t *nodes[MAX_NODES_ALL]; /* every node, in command-line order */
    size_t n_nodes;
    co_time_us_t start;
    int log_level;          /* as given on the command line; emu_output.c keeps the same for logline() */
    emu_script_t script;
    emu_control_t control;
    emu_sockets_t sockets;
    emu_web_t web;
    emu_socketcand_t socketcand; /* --socketcand: the buses as socketcand channels */
    emu_session_t *sessions[MAX_SESSIONS]; /* those that may subscribe to events */
    size_t n_sessions;
    size_t session_turn;    /* the session sessions_work begins with: each pass goes on where the last one stopped */
    bool in_command;        /* a command runs: a device's messages are its reply, not events */
    bool command_restricted; /* the command line running comes from a restricted session (emu_session_t) */
    bool quit;
} emu_t;

/** The node is to be processed before the loop sleeps: a frame concerned it, a command or a fault changed it. */
static inline void node_mark_dirty(emu_node_t *n)
{
    schedule_mark(&n->bus->schedule, (uint32_t)n->index);
}

/** A time of the monotonic clock on the events' clock: µs since the emulator started (0 for a time before it). */
static inline co_time_us_t emu_since_start(const emu_t *emu, co_time_us_t at)
{
    return at > emu->start ? at - emu->start : 0U;
}

/** ppoll's timeout until `deadline` (0 when it has passed, in *ts), or NULL to wait without one (CO_NEVER). */
static inline struct timespec *emu_poll_timeout(co_time_us_t deadline, co_time_us_t now, struct timespec *ts)
{
    if (deadline == CO_NEVER) {
        return NULL;
    }
    const co_time_us_t wait = deadline > now ? deadline - now : 0U;
    if (wait < 1000000U) { /* the common case, without the divisions */
        ts->tv_sec = 0;
        ts->tv_nsec = (long)wait * 1000L;
    } else {
        ts->tv_sec = (time_t)(wait / 1000000U);
        ts->tv_nsec = (long)(wait % 1000000U) * 1000L;
    }
    return ts;
}

#endif /* EMU_H */
