/* The runtime's start and stop, and its signals: see emu_runtime.h (the loop itself: emu_loop.c). */
#define _GNU_SOURCE /* PATH_MAX and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_runtime.h"

#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/emu_bus.h"
#include "control/emu_control.h"
#include "runtime/emu_loop.h"
#include "runtime/emu_output.h"
#include "scripts/emu_script.h"
#include "control/emu_socket.h"
#include "web/emu_web.h"

static volatile sig_atomic_t stop_signal;

static void on_signal(int sig) { stop_signal = sig; }

int runtime_start(emu_t *emu, const emu_config_t *cfg)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    char err[512];
    /* From here on the log and the replies go through emu_output.c, which never blocks (it ignores SIGPIPE). */
    sockets_init(&emu->sockets);
    web_init(&emu->web);
    socketcand_init(&emu->socketcand);
    if (cfg->control_socket != NULL) {
        if (sockets_listen_unix(&emu->sockets, cfg->control_socket, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
        logline(LOG_NORMAL, "control: listening on unix %s", cfg->control_socket);
    }
    if (cfg->control_token_file != NULL && cfg->control_tcp == NULL) {
        output_error("--control-token-file is the token of --control-tcp, which is not given");
        return 1;
    }
    if (cfg->control_tcp != NULL) {
        if (cfg->control_token_file != NULL &&
            sockets_load_token(&emu->sockets, cfg->control_token_file, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
        bool remote = false;
        if (sockets_listen_tcp(&emu->sockets, cfg->control_tcp, &remote, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
        if (remote && emu->sockets.tcp_token == NULL) {
            /* Whoever reaches the port would control the nodes, and write files with export-dcf. */
            output_error("--control-tcp %s is not a loopback address: give --control-token-file FILE too (clients "
                         "then say hello with its token first), or listen on 127.0.0.1", emu->sockets.tcp_name);
            return 1;
        }
        logline(LOG_NORMAL, "control: listening on tcp %s%s", emu->sockets.tcp_name,
                emu->sockets.tcp_token != NULL ? " (clients give the token first)" : "");
        if (remote) {
            logline(LOG_QUIET, "control: warning: tcp %s is not a loopback address: whoever has the token controls "
                    "the emulated nodes, and the connection is not encrypted", emu->sockets.tcp_name);
        }
    }
    if (cfg->web != NULL) {
        if (web_start(emu, &emu->web, cfg->web, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
        logline(LOG_NORMAL, "web: listening on http://%s/", emu->web.listener.name);
        if (emu->web.listener.remote) {
            logline(LOG_QUIET, "web: warning: %s is not a loopback address: anyone who reaches it can change the "
                    "devices (the page hands its token to whoever loads it)", emu->web.listener.name);
        }
    }
    if (cfg->socketcand != NULL) {
        if (socketcand_start(&emu->socketcand, cfg->socketcand, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
        logline(LOG_NORMAL, "socketcand: listening on %s: every bus is a channel of its name",
                emu->socketcand.listener.name);
        if (emu->socketcand.listener.remote) {
            logline(LOG_QUIET, "socketcand: warning: %s is not a loopback address: whoever reaches it is on the "
                    "buses (reads every frame, sends any), and the connection is not encrypted",
                    emu->socketcand.listener.name);
        }
    }
    for (size_t i = 0U; i < cfg->n_buses; i++) {
        emu_bus_t *b = calloc(1U, sizeof *b);
        if (b == NULL) {
            output_error("out of memory");
            return 1;
        }
        emu->buses[emu->n_buses++] = b;
        b->emu = emu;
        if (bus_open(b, &cfg->buses[i], emu->log_level, err, sizeof err) != 0) {
            output_error("%s", err);
            return 1;
        }
    }
    /* One power-on time for all nodes: their periodic deadlines (heartbeats, model ticks, cyclic TPDOs of
     * equal periods) then fall on the same instants and one wake-up serves them all. */
    const co_time_us_t power_on = socketcan_now_us();
    for (size_t i = 0U; i < cfg->n_specs; i++) {
        const node_spec_t *s = &cfg->specs[i];
        const size_t bus = s->bus_index;
        emu_node_t *n = node_create(emu->buses[bus], bus == 0U, s, cfg->nvm_dir, power_on);
        if (n == NULL) {
            return 1;
        }
        emu->nodes[emu->n_nodes++] = n;
    }
    control_start(emu);
    return 0;
}

int runtime_loop(emu_t *emu)
{
    return loop_run(emu, &stop_signal);
}

void runtime_stop(emu_t *emu)
{
    logline(LOG_NORMAL, "stopping%s", stop_signal != 0 ? " (signal)" : "");
    sockets_close(emu, &emu->sockets);
    web_stop(emu, &emu->web);
    socketcand_stop(emu, &emu->socketcand);
    unsigned long sent = 0UL, dropped = 0UL, rx_lost = 0UL;
    for (size_t i = 0U; i < emu->n_buses; i++) {
        bus_close(emu->buses[i], &sent, &dropped, &rx_lost);
    }
    /* Shown also with -q when frames were lost either way: a quiet run must not hide a loss. */
    logline(dropped > 0UL || rx_lost > 0UL ? LOG_QUIET : LOG_NORMAL,
            "%lu frame(s) sent, %lu dropped; %lu received frame(s) lost (receive buffer full)", sent, dropped, rx_lost);
    for (size_t i = 0U; i < emu->n_nodes; i++) {
        node_destroy(emu->nodes[i]);
    }
    for (size_t i = 0U; i < emu->n_buses; i++) {
        free(emu->buses[i]);
    }
    script_free(&emu->script);
}
