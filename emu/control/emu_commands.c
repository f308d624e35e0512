/* The command language: see emu_commands.h. Device commands are device_command()'s (devices/device.c). */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_commands.h"

#include <string.h>

#include "eds_class/eds_class.h"
#include "runtime/emu_output.h"

/* The command table: help's text, and the usage a command with too few words is answered with (device_help_usage
 * reads its "  USAGE  TEXT" lines). */
static const char help_text[] =
    "commands (NODE = node-ID, decimal or 0x-hex, or 'all'; NODE@IFACE on one bus of several):\n"
    "  list                         the nodes\n"
    "  show NODE                    NMT state, node-ID, active errors\n"
    "  get NODE INDEX[:SUB]         an object's value (hex index/sub: 0x2002:06 or 2002:6)\n"
    "  set NODE INDEX[:SUB] VALUE   write a value as the device itself would (inputs, measurements)\n"
    "  power-cycle NODE             restart the node as switching its supply off and on would\n"
    "  emcy NODE CODE [REG [B0..B4]]  raise a raw CiA error (EMCY, 0x1001, 0x1003)\n"
    "  emcy-clear NODE CODE [B0..B4]  clear it (error-reset EMCY)\n"
    "  fault NODE KIND [ARGS]       make the node misbehave on the bus (kinds: fault NODE)\n"
    "  fault-clear NODE [KIND]      end its faults (all when no KIND is given)\n"
    "  faults NODE                  the node's faults and their effect\n"
    "  export-dcf NODE FILE         a node read from an EDS/DCF, its current values as a DCF\n"
    "  help [NODE]                  this text, or the device commands of NODE\n"
    "  subscribe KIND[,KIND...] [NODE...]  events of these kinds (or all) to this session\n"
    "  subscribe frame COB-ID[x][/MASK] ...  11-bit frames matching one (at most 4) as events; x: 29-bit ones\n"
    "  unsubscribe [KIND[,KIND...]]  stop them\n"
    "  quit                         stop the emulator";

/* NODE of a command: ID, ID@IFACE, all or all@IFACE. */
typedef struct node_selector {
    bool all;
    long long id;
    const emu_bus_t *bus; /* NULL: any */
} node_selector_t;

/* The node answers to id: its node-ID, or, while it has none (LSS unconfigured), the one it was started with. */
static bool has_id(const emu_node_t *n, long long id)
{
    const uint8_t now = co_node_id(&n->dev.node);
    return now == id || (now == CO_NODE_ID_UNCONFIGURED && n->cmdline_id == id);
}

static bool selects(const node_selector_t *sel, const emu_node_t *n)
{
    return (sel->bus == NULL || n->bus == sel->bus) && (sel->all || has_id(n, sel->id));
}

static bool parse_selector(const emu_t *emu, char *word, node_selector_t *sel, bool any_bus, const reply_sink_t *to)
{
    sel->bus = NULL;
    sel->id = -1;
    char *at = strchr(word, '@');
    if (at != NULL) {
        *at = '\0';
        for (size_t i = 0U; i < emu->n_buses; i++) {
            if (strcmp(emu->buses[i]->can.name, at + 1) == 0) {
                sel->bus = emu->buses[i];
            }
        }
        if (sel->bus == NULL) {
            reply(to, "error: no interface '%s'", at + 1);
            return false;
        }
    }
    sel->all = strcmp(word, "all") == 0;
    if (!sel->all && !device_parse_int(word, 0, 255, &sel->id)) {
        reply(to, "error: '%s' is not a node-ID", word);
        return false;
    }
    if (!sel->all && sel->bus == NULL && !any_bus) {
        /* The same node-ID on two buses: the command must say which. */
        const emu_bus_t *found = NULL;
        for (size_t i = 0U; i < emu->n_nodes; i++) {
            const emu_node_t *n = emu->nodes[i];
            if (has_id(n, sel->id)) {
                if (found != NULL && found != n->bus) {
                    reply(to, "error: node %lld is on %s and on %s: say %lld@%s", sel->id, found->can.name,
                          n->bus->can.name, sel->id, found->can.name);
                    return false;
                }
                found = n->bus;
            }
        }
    }
    if (at != NULL) {
        *at = '@'; /* "no node 16@vcan1" names what was asked for */
    }
    return true;
}

static int select_on(emu_t *emu, char *word, emu_node_t **out, size_t max, bool any_bus, const reply_sink_t *to)
{
    node_selector_t sel;
    if (!parse_selector(emu, word, &sel, any_bus, to)) {
        return -1;
    }
    size_t n = 0U;
    for (size_t i = 0U; i < emu->n_nodes && n < max; i++) {
        if (selects(&sel, emu->nodes[i])) {
            out[n++] = emu->nodes[i];
        }
    }
    return (int)n;
}

int select_nodes(emu_t *emu, char *word, emu_node_t **out, size_t max, const reply_sink_t *to)
{
    return select_on(emu, word, out, max, false, to);
}

int select_nodes_any_bus(emu_t *emu, char *word, emu_node_t **out, size_t max, const reply_sink_t *to)
{
    return select_on(emu, word, out, max, true, to);
}

/* A device's reply line to the command's sink, with the node it is of: "node 16: 0x1017:00 = 5000 (0x1388)". */
static void node_reply(void *ctx, const device_t *dev, const char *line)
{
    /* Before co_node_init (a model loading its own NVM at power-on) the node has no ID yet: the configured one. */
    const unsigned id = co_node_id(&dev->node) != 0U ? co_node_id(&dev->node) : dev->cfg.node_id;
    reply((const reply_sink_t *)ctx, "node %u: %s", id, line);
}

/* export-dcf NODE FILE: one node's current values as a DCF (eds_class.h). */
static command_result_t export_dcf(int argc, char **argv, emu_node_t **nodes, int n_sel, const reply_sink_t *to)
{
    if (argc != 3 || n_sel != 1) {
        reply(to, "error: export-dcf takes one node and a file: export-dcf NODE FILE");
        return COMMAND_ERROR;
    }
    char why[512];
    emu_node_t *n = nodes[0];
    if (!eds_class_export(&n->dev, argv[2], why, sizeof why)) {
        reply(to, "node %u: error: export-dcf: %s", co_node_id(&n->dev.node), why);
        return COMMAND_ERROR;
    }
    reply(to, "node %u: DCF written to %s", co_node_id(&n->dev.node), argv[2]);
    return COMMAND_OK;
}

command_result_t run_command(emu_t *emu, char *line, const reply_sink_t *to)
{
    char *argv[MAX_ARGS];
    const int argc = device_split_words(line, argv, MAX_ARGS);
    if (argc < 0) {
        reply(to, "error: too many words (at most %d)", MAX_ARGS);
        return COMMAND_ERROR;
    }
    if (argc == 0) {
        return COMMAND_OK;
    }
    return run_command_words(emu, argc, argv, to);
}

const char *command_restriction(const char *word)
{
    if (strcmp(word, "quit") == 0 || strcmp(word, "exit") == 0) {
        return "stops the emulator";
    }
    return strcmp(word, "export-dcf") == 0 ? "writes a file" : NULL;
}

command_result_t run_command_words(emu_t *emu, int argc, char **argv, const reply_sink_t *to)
{
    const co_time_us_t now = socketcan_now_us();
    const char *refused = emu->command_restricted ? command_restriction(argv[0]) : NULL;
    if (refused != NULL) {
        reply(to, "error: %s is refused in a web session: it %s", argv[0], refused);
        return COMMAND_ERROR;
    }
    if (strcmp(argv[0], "quit") == 0 || strcmp(argv[0], "exit") == 0) {
        emu->quit = true;
        return COMMAND_OK;
    }
    if (strcmp(argv[0], "help") == 0 && argc == 1) {
        reply(to, "%s", help_text);
        return COMMAND_OK;
    }
    if (strcmp(argv[0], "list") == 0) {
        for (size_t i = 0U; i < emu->n_nodes; i++) {
            const emu_node_t *n = emu->nodes[i];
            reply(to, "node %u: %s (started as %u) %s%s%s", co_node_id(&n->dev.node), n->dev.cls->name, n->cmdline_id,
                  co_nmt_state_name(co_node_state(&n->dev.node)), emu->n_buses > 1U ? " on " : "",
                  emu->n_buses > 1U ? n->bus->can.name : "");
        }
        return COMMAND_OK;
    }
    if (argc < 2) {
        const char *args;
        size_t args_len;
        if (device_help_usage(help_text, argv[0], &args, &args_len)) {
            reply(to, "error: %s takes %.*s", argv[0], (int)args_len, args);
        } else {
            reply(to, "error: '%s' needs a NODE (try help)", argv[0]);
        }
        return COMMAND_ERROR;
    }
    emu_node_t *nodes[MAX_NODES_ALL];
    const int n_sel = select_nodes(emu, argv[1], nodes, MAX_NODES_ALL, to);
    if (n_sel < 0) {
        return COMMAND_ERROR;
    }
    if (n_sel == 0) {
        reply(to, "error: no node %s", argv[1]);
        return COMMAND_ERROR;
    }
    if (strcmp(argv[0], "export-dcf") == 0) {
        return export_dcf(argc, argv, nodes, n_sel, to);
    }
    command_result_t result = COMMAND_OK;
    const char *const cmd = argv[0];
    reply_sink_t sink = *to;
    const device_output_t node_replies = {node_reply, &sink};
    const bool injects = strcmp(cmd, "fault") == 0 || strcmp(cmd, "fault-clear") == 0; /* emu_faults.h, not the device */
    for (int i = 0; i < n_sel; i++) {
        emu_node_t *n = nodes[i];
        if (strcmp(cmd, "help") == 0) {
            reply(to, "node %u (%s) commands:\n%s", co_node_id(&n->dev.node), n->dev.cls->name,
                  n->dev.cls->commands_help != NULL ? n->dev.cls->commands_help : "  (only the common ones)");
            continue;
        }
        char *saved = argv[1];
        argv[1] = argv[0];
        device_cmd_result_t r = DEVICE_CMD_UNKNOWN;
        emu->in_command = true;
        if (!injects) {
            r = device_command(&n->dev, argc - 1, (const char *const *)&argv[1], now, &node_replies);
        }
        if (injects || strcmp(cmd, "faults") == 0) {
            /* Protocol faults (emu_faults.h); `faults` of an Eltex device lists its own errors first. */
            n->dev.now = now;
            r = faults_command(n, argc - 1, &argv[1], now, to) == 0 && r != DEVICE_CMD_ERROR ? DEVICE_CMD_OK : DEVICE_CMD_ERROR;
        }
        emu->in_command = false;
        argv[1] = saved;
        node_mark_dirty(n);
        if (r == DEVICE_CMD_UNKNOWN) {
            reply(to, "node %u: error: unknown command '%s' (try help %u)", co_node_id(&n->dev.node), cmd,
                  co_node_id(&n->dev.node));
        }
        if (r != DEVICE_CMD_OK) {
            result = COMMAND_ERROR;
        }
    }
    return result;
}
