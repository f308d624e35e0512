/*
 * canopen-emu: emulated CANopen devices on a SocketCAN interface.
 *
 *   canopen-emu [-i IFACE] [--nvm-dir DIR] [options] DEVICE[/VARIANT][:NODE-ID] ...
 *
 * Each DEVICE becomes one node with its own NVM files. All nodes share one CAN socket: a frame read from the
 * bus is offered to every node (the core ignores what is not for it), and a frame one node sends is also
 * offered to the other local nodes (the kernel does not loop a socket's frames back to itself), through a
 * queue drained by the main loop so that no node is re-entered while it runs. One socket instead of one
 * per node keeps the system calls per bus frame at one, which matters with 127 nodes. One poll loop sleeps
 * until the earliest deadline any node returns or until a frame, a control command or a signal arrives.
 * See docs/emulator.md.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <getopt.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "emu.h"
#include "emu_cmdline.h"
#include "emu_commands.h"
#include "emu_control.h"
#include "emu_output.h"
#include "emu_script.h"
#include "emu_version.h" /* generated: EMU_VERSION, EMU_GIT_REVISION (cmake/version.cmake) */

static volatile sig_atomic_t stop_signal;

static void on_signal(int sig) { stop_signal = sig; }

static emu_t emu;

/* The port's lines are all problems or their end (interface down / up again, gone / back, error frames, frames
 * lost, a failed send): shown with -q too, which keeps only problems. */
static void can_log(void *ctx, const char *line)
{
    (void)ctx;
    logline(LOG_QUIET, "%s", line);
}

static void device_print(void *ctx, const device_t *dev, const char *line)
{
    (void)ctx;
    /* Before co_node_init (a model loading its own NVM at power-on) the node has no ID yet: the configured one. */
    const unsigned id = co_node_id(&dev->node) != 0U ? co_node_id(&dev->node) : dev->cfg.node_id;
    reply("node %u: %s", id, line);
}

static void device_event(void *ctx, const device_t *dev, const co_event_t *ev)
{
    (void)ctx;
    const unsigned id = co_node_id(&dev->node);
    const char *name = dev->cls->name;
    switch (ev->kind) {
    case CO_EV_NMT_STATE:
        logline(LOG_NORMAL, "node %u (%s): NMT %s -> %s", id, name, co_nmt_state_name((co_nmt_state_t)ev->code), co_nmt_state_name((co_nmt_state_t)ev->value));
        break;
    case CO_EV_SDO_ABORT:
        logline(LOG_NORMAL, "node %u (%s): SDO abort 0x%08lX on 0x%04X:%02X (%s)", id, name, (unsigned long)ev->code,
                ev->index, ev->sub, co_abort_text(ev->code));
        break;
    case CO_EV_EMCY:
        logline(LOG_NORMAL, "node %u (%s): EMCY 0x%04lX, error register 0x%02lX", id, name, (unsigned long)ev->value,
                (unsigned long)ev->code);
        break;
    case CO_EV_STORE:
    case CO_EV_RESTORE: {
        const int level = ev->code == 0U ? LOG_NORMAL : LOG_QUIET; /* a failed store is a problem: shown with -q */
        if (ev->index == 0x7E5U) {
            logline(level, "node %u (%s): LSS store configuration (node-ID %lu): %s", id, name,
                    (unsigned long)ev->value, ev->code == 0U ? "stored" : "failed");
        } else {
            logline(level, "node %u (%s): %s 0x%04X:%02X: %s", id, name, ev->kind == CO_EV_STORE ? "store" : "restore",
                    ev->index, ev->sub, ev->code == 0U ? "done" : co_abort_text(ev->code));
        }
        break;
    }
    case CO_EV_NVM_LOADED:
        if (ev->index == 0x7E5U) {
            if (ev->value == CO_NVM_CORRUPT) {
                logline(LOG_QUIET, "node %u (%s): stored LSS configuration is damaged; using the command-line "
                        "node-ID and the default bit timing", id, name);
            }
        } else if (ev->value == CO_NVM_CORRUPT || ev->value == CO_NVM_FOREIGN) {
            logline(LOG_QUIET, "node %u (%s): stored parameters %s; starting from defaults", id, name,
                    ev->value == CO_NVM_CORRUPT ? "are damaged (bad header, length or CRC)" : "belong to another device");
        } else {
            logline(LOG_VERBOSE, "node %u (%s): stored parameters %s", id, name,
                    ev->value == CO_NVM_LOADED ? "loaded" : "none, defaults used");
        }
        break;
    case CO_EV_NVM_REFUSED: /* then CO_EV_NVM_LOADED with CO_NVM_REFUSED, which needs no second line */
        logline(LOG_QUIET, "node %u (%s): stored parameters refused: 0x%04X:%02X holds a value a write would be "
                "refused for (%s); starting from defaults", id, name, ev->index, ev->sub, co_abort_text(ev->code));
        break;
    case CO_EV_LSS_NODE_ID:
        logline(LOG_NORMAL, "node %u (%s): LSS pending node-ID %lu", id, name, (unsigned long)ev->value);
        break;
    case CO_EV_LSS_BIT_TIMING:
        logline(LOG_NORMAL, "node %u (%s): LSS pending bit timing %lu", id, name, (unsigned long)ev->value);
        break;
    case CO_EV_LSS_ACTIVATE:
        logline(LOG_NORMAL, "node %u (%s): LSS activated %lu kbit/s", id, name, (unsigned long)ev->value);
        break;
    case CO_EV_HB_TIMEOUT:
        logline(LOG_NORMAL, "node %u (%s): heartbeat of node %lu missing", id, name, (unsigned long)ev->value);
        break;
    case CO_EV_GUARD_TIMEOUT:
        logline(LOG_NORMAL, "node %u (%s): life guarding: no guard request in time", id, name);
        break;
    case CO_EV_TX_DROPPED:
        logline(LOG_VERBOSE, "node %u (%s): frame 0x%03lX not sent", id, name, (unsigned long)ev->value);
        break;
    default:
        break;
    }
}

/* ---- the port of one node: its CAN socket and its NVM files ---- */

static co_status_t port_send(void *ctx, const co_frame_t *f)
{
    emu_node_t *n = (emu_node_t *)ctx;
    /* A store is durable before the core answers it: the port's last commit of the store does it (nvm_file.h). */
    const co_status_t st = socketcan_send(&emu.can, f);
    if (st == CO_OK && emu.n_nodes > 1U) {
        if (emu.local_count == LOCAL_QUEUE_LEN) {
            emu.local_lost++; /* the other local nodes miss this frame; counted, reported at exit */
        } else {
            local_frame_t *l = &emu.local[(emu.local_head + emu.local_count) % LOCAL_QUEUE_LEN];
            l->frame = *f;
            l->sender = n->index;
            emu.local_count++;
        }
    }
    if (st == CO_OK && emu.log_level >= LOG_VERBOSE) {
        char hex[24] = "";
        for (uint8_t i = 0U; i < f->len; i++) {
            (void)snprintf(hex + 2U * i, sizeof hex - 2U * i, "%02X", f->data[i]);
        }
        logline(LOG_VERBOSE, "node %u tx %03X#%s", co_node_id(&n->dev.node), (unsigned)f->id, hex);
    }
    return st;
}
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
    logline(LOG_NORMAL, "node %u (%s): bit rate %lu kbit/s requested; the interface's rate is the system's "
            "(ip link set %s type can bitrate %lu000)", co_node_id(&n->dev.node), n->dev.cls->name,
            (unsigned long)kbit, emu.can.ifname, (unsigned long)kbit);
    return CO_OK;
}

static emu_node_t *add_node(const device_class_t *cls, const char *variant, uint8_t id, const char *iface,
                            const char *nvm_dir, size_t index, co_time_us_t power_on)
{
    emu_node_t *n = calloc(1U, sizeof *n);
    if (n == NULL) {
        output_error("out of memory");
        return NULL;
    }
    n->values = calloc(1U, cls->od->values_size);
    n->model = cls->model_size > 0U ? calloc(1U, cls->model_size) : NULL;
    if (n->values == NULL || (cls->model_size > 0U && n->model == NULL)) {
        output_error("out of memory");
        return NULL;
    }
    n->cmdline_id = id;
    n->index = index;
    (void)snprintf(n->key, sizeof n->key, "%s-%u", cls->name, id);
    char err[512];
    n->dev.cls = cls; /* for logs before device_init */
    if (nvm_file_open(&n->nvm, nvm_dir, n->key, err, sizeof err) != 0) {
        output_error("%s", err);
        return NULL;
    }
    n->port.send = port_send;
    n->port.nvm_write = port_nvm_write;
    n->port.nvm_commit = port_nvm_commit;
    n->port.nvm_read = port_nvm_read;
    n->port.set_bit_rate = port_bit_rate;
    device_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.node_id = id;
    cfg.serial = device_default_serial(cls) + id; /* distinct LSS identities (docs/emulator.md) */
    cfg.variant = variant[0] != '\0' ? variant : NULL;
    cfg.port = &n->port;
    cfg.port_ctx = n;
    cfg.print = device_print;
    cfg.on_event = device_event;
    const co_status_t st = device_init(&n->dev, cls, n->values, n->model, &cfg, power_on);
    if (st != CO_OK) {
        output_error("%s:%u: the node could not start (%d)", cls->name, id, (int)st);
        return NULL;
    }
    logline(LOG_NORMAL, "node %u (%s%s%s) on %s, NVM %s/%s.*", co_node_id(&n->dev.node), cls->name,
            variant[0] != '\0' ? "/" : "", variant, iface, nvm_dir, n->key);
    return n;
}

int main(int argc, char **argv)
{
    const char *iface = "vcan0";
    const char *nvm_dir = NULL;
    const char *script = NULL;
    char nvm_default[PATH_MAX];
    emu.log_level = LOG_NORMAL;
    emu.start = socketcan_now_us();
    emu.control.enabled = isatty(STDIN_FILENO) != 0;
    static const struct option opts[] = {
        {"interface", required_argument, NULL, 'i'}, {"nvm-dir", required_argument, NULL, 'n'},
        {"control", required_argument, NULL, 'c'},   {"script", required_argument, NULL, 's'},
        {"list-devices", no_argument, NULL, 'l'},    {"verbose", no_argument, NULL, 'v'},
        {"quiet", no_argument, NULL, 'q'},           {"help", no_argument, NULL, 'h'},
        {"version", no_argument, NULL, 'V'},         {NULL, 0, NULL, 0}};
    int opt;
    while ((opt = getopt_long(argc, argv, "i:vqh", opts, NULL)) != -1) {
        switch (opt) {
        case 'i':
            iface = optarg;
            if (iface[0] == '\0') {
                fprintf(stderr, "canopen-emu: -i/--interface needs an interface name, not an empty one\n");
                return 2;
            }
            break;
        case 'n':
            nvm_dir = optarg;
            if (nvm_dir[0] == '\0') { /* nvm_file_check_dir would read past the end of "" */
                fprintf(stderr, "canopen-emu: --nvm-dir needs a directory name, not an empty one\n");
                return 2;
            }
            break;
        case 'c':
            if (strcmp(optarg, "-") != 0) {
                fprintf(stderr, "canopen-emu: --control takes '-' (stdin)\n");
                return 2;
            }
            emu.control.enabled = true;
            break;
        case 's':
            script = optarg;
            break;
        case 'l':
            list_devices(stdout);
            return 0;
        case 'v':
            emu.log_level = LOG_VERBOSE;
            break;
        case 'q':
            emu.log_level = LOG_QUIET;
            break;
        case 'h':
            usage(stdout);
            return 0;
        case 'V':
            /* The revision tells builds of one version apart (a CI artefact, a bug report). */
            if (EMU_GIT_REVISION[0] != '\0') {
                printf("canopen-emu %s (git %s)\n", EMU_VERSION, EMU_GIT_REVISION);
            } else {
                printf("canopen-emu %s\n", EMU_VERSION);
            }
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    output_init(emu.start, emu.log_level);
    if (optind >= argc) {
        fprintf(stderr, "canopen-emu: no device given\n");
        usage(stderr);
        return 2;
    }
    if (argc - optind > MAX_NODES) {
        fprintf(stderr, "canopen-emu: at most %d nodes\n", MAX_NODES);
        return 2;
    }
    if (nvm_dir == NULL) {
        nvm_dir = default_nvm_dir(nvm_default, sizeof nvm_default);
    }
    char err[512];
    if (nvm_file_check_dir(nvm_dir, err, sizeof err) != 0) {
        fprintf(stderr, "canopen-emu: %s\n", err);
        return 1;
    }
    if (script != NULL && !script_load(&emu.script, script)) {
        return 2;
    }
    /* Parse every spec first, so a bad one fails before anything starts. */
    const device_class_t *cls[MAX_NODES];
    char variants[MAX_NODES][32];
    uint8_t ids[MAX_NODES];
    const size_t n_specs = (size_t)(argc - optind);
    for (size_t i = 0U; i < n_specs; i++) {
        if (!parse_spec(argv[optind + (int)i], &cls[i], variants[i], sizeof variants[i], &ids[i])) {
            return 2;
        }
        for (size_t k = 0U; k < i; k++) {
            if (ids[k] == ids[i]) {
                fprintf(stderr, "canopen-emu: node-ID %u is given twice (%s and %s); each node needs its own\n", ids[i],
                        argv[optind + (int)k], argv[optind + (int)i]);
                return 2;
            }
        }
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    /* From here on the log and the replies go through emu_output.c, which never blocks (it ignores SIGPIPE). */
    if (socketcan_open(&emu.can, iface, can_log, NULL, err, sizeof err) != 0) {
        output_error("%s", err);
        return 1;
    }
    /* One power-on time for all nodes: their periodic deadlines (heartbeats, model ticks, cyclic TPDOs of
     * equal periods) then fall on the same instants and one wake-up serves them all. */
    const co_time_us_t power_on = socketcan_now_us();
    for (size_t i = 0U; i < n_specs; i++) {
        emu_node_t *n = add_node(cls[i], variants[i], ids[i], iface, nvm_dir, i, power_on);
        if (n == NULL) {
            return 1;
        }
        emu.nodes[emu.n_nodes++] = n;
    }
    control_start(&emu.control);

    struct pollfd pfd[4]; /* the CAN socket, stdin, stdout and stderr when output waits */
    while (!emu.quit && stop_signal == 0) {
        co_time_us_t now = socketcan_now_us();
        char line[COMMAND_LINE_MAX + 1];
        /* quit ends the run at once: a script line due at the same time after it must not run (a save there stored) */
        while (!emu.quit && script_take_due(&emu.script, now - emu.start, line, sizeof line)) {
            run_command(&emu, line);
        }
        /* Frames local nodes sent are offered to the others (which may answer: loop until quiet). */
        co_time_us_t next = CO_NEVER;
        bool tx_pending = false;
        do {
            while (emu.local_count > 0U) {
                const local_frame_t l = emu.local[emu.local_head];
                emu.local_head = (emu.local_head + 1U) % LOCAL_QUEUE_LEN;
                emu.local_count--;
                for (size_t i = 0U; i < emu.n_nodes; i++) {
                    if (i != l.sender && device_rx(&emu.nodes[i]->dev, &l.frame, now)) {
                        emu.nodes[i]->dirty = true;
                    }
                }
            }
            /* Only nodes that are due or were concerned by a frame or a command run: with 127 nodes on one
             * bus, processing every node at every wake-up cost O(nodes^2) per second (docs/performance.md). */
            next = CO_NEVER;
            tx_pending = false;
            for (size_t i = 0U; i < emu.n_nodes; i++) {
                emu_node_t *n = emu.nodes[i];
                if (n->dirty || now >= n->deadline) {
                    n->dirty = false;
                    n->deadline = device_process(&n->dev, now);
                }
                next = n->deadline < next ? n->deadline : next;
                tx_pending = tx_pending || n->dev.node.txq.count > 0U;
            }
        } while (emu.local_count > 0U);
        const co_time_us_t r = socketcan_service(&emu.can, now);
        next = r < next ? r : next;
        const co_time_us_t script_at = script_next_at(&emu.script);
        if (script_at != CO_NEVER && emu.start + script_at < next) {
            next = emu.start + script_at;
        }
        output_flush(); /* what this pass logged and replied, as far as the readers take it */
        nfds_t nfds = 0U;
        pfd[nfds].fd = emu.can.fd; /* -1 while the interface is gone: poll ignores it */
        pfd[nfds].events = socketcan_poll_events(&emu.can, tx_pending); /* no POLLOUT after ENOBUFS: it would spin */
        pfd[nfds].revents = 0;
        nfds++;
        const nfds_t stdin_index = emu.control.open ? nfds : 0U;
        if (emu.control.open) {
            pfd[nfds].fd = STDIN_FILENO;
            pfd[nfds].events = POLLIN;
            pfd[nfds].revents = 0;
            nfds++;
        }
        nfds += output_poll_fds(&pfd[nfds]); /* POLLOUT wakes the loop to write more: the next pass does */
        now = socketcan_now_us();
        struct timespec ts;
        struct timespec *timeout = NULL;
        if (next != CO_NEVER) {
            const co_time_us_t wait = next > now ? next - now : 0U;
            ts.tv_sec = (time_t)(wait / 1000000U);
            ts.tv_nsec = (long)(wait % 1000000U) * 1000L;
            timeout = &ts;
        }
        const int ready = ppoll(pfd, nfds, timeout, NULL);
        if (ready < 0) {
            if (errno == EINTR) {
                continue;
            }
            output_error("poll: %s", strerror(errno));
            return 1;
        }
        if ((pfd[0].revents & (POLLIN | POLLERR | POLLHUP)) != 0) {
            now = socketcan_now_us();
            co_frame_t f;
            for (int k = 0; k < 1024 && socketcan_read(&emu.can, &f) == 1; k++) {
                if (emu.log_level >= LOG_VERBOSE) {
                    logline(LOG_VERBOSE, "rx %03X [%u]%s", (unsigned)f.id, f.len, (f.flags & CO_FRAME_RTR) != 0U ? " RTR" : "");
                }
                for (size_t i = 0U; i < emu.n_nodes; i++) {
                    if (device_rx(&emu.nodes[i]->dev, &f, now)) {
                        emu.nodes[i]->dirty = true;
                    }
                }
            }
        }
        if ((pfd[0].revents & POLLOUT) != 0) {
            /* Room in the socket's buffer: nodes with queued frames retry now. Without this the loop would poll
             * again, get POLLOUT at once, and spin until their retry deadline. */
            for (size_t i = 0U; i < emu.n_nodes; i++) {
                if (emu.nodes[i]->dev.node.txq.count > 0U) {
                    emu.nodes[i]->dirty = true;
                }
            }
        }
        if (stdin_index != 0U && (pfd[stdin_index].revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
            control_read(&emu);
        }
    }
    logline(LOG_NORMAL, "stopping%s", stop_signal != 0 ? " (signal)" : "");
    if (emu.local_lost > 0U) {
        logline(LOG_QUIET, "%lu frame(s) between local nodes were lost (queue full)", emu.local_lost);
    }
    unsigned long sent = 0UL, dropped = 0UL;
    for (size_t i = 0U; i < emu.n_nodes; i++) {
        const co_node_stats_t *st = &emu.nodes[i]->dev.node.stats;
        sent += st->tx_frames;
        dropped += st->tx_dropped;
        if (st->tx_dropped > 0U) {
            logline(LOG_QUIET, "node %u (%s): %lu frame(s) could not be sent", co_node_id(&emu.nodes[i]->dev.node),
                    emu.nodes[i]->dev.cls->name, (unsigned long)st->tx_dropped);
        }
    }
    socketcan_flush_log(&emu.can);
    /* Shown also with -q when frames were lost either way: a quiet run must not hide a loss. */
    logline(dropped > 0UL || emu.can.rx_dropped > 0UL ? LOG_QUIET : LOG_NORMAL,
            "%lu frame(s) sent, %lu dropped; %lu received frame(s) lost (receive buffer full)", sent, dropped,
            emu.can.rx_dropped);
    socketcan_close(&emu.can);
    for (size_t i = 0U; i < emu.n_nodes; i++) {
        nvm_file_close(&emu.nodes[i]->nvm);
        free(emu.nodes[i]->values);
        free(emu.nodes[i]->model);
        free(emu.nodes[i]);
    }
    script_free(&emu.script);
    return 0;
}
