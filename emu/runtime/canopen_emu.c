/*
 * canopen-emu: emulated CANopen devices on CAN buses: SocketCAN interfaces, UDP multicast groups, virtual buses.
 *
 *   canopen-emu [-i BUS]... [--nvm-dir DIR] [options] DEVICE[/VARIANT][:NODE-ID][@BUS] ...
 *
 * This file reads the options and hands them to the runtime (emu_runtime.h); emu.h says where everything else
 * lives. See docs/emulator.md.
 */
#define _GNU_SOURCE
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runtime/emu.h"
#include "runtime/emu_cmdline.h"
#include "eds_class/eds_class.h"
#include "runtime/emu_output.h"
#include "runtime/emu_runtime.h"
#include "scripts/emu_script.h"
#include "control/emu_tcp.h"
#include "emu_version.h" /* generated: EMU_VERSION, EMU_GIT_REVISION (cmake/version.cmake) */

static emu_t emu;
static emu_config_t config;

static void print_version(void)
{
    /* The revision tells builds of one version apart (a CI artefact, a bug report). */
    if (EMU_GIT_REVISION[0] != '\0') {
        printf("canopen-emu %s (git %s)\n", EMU_VERSION, EMU_GIT_REVISION);
    } else {
        printf("canopen-emu %s\n", EMU_VERSION);
    }
}

/* The bus that text (-i BUS, or NODE@BUS) names: one already given under the same name, or a new one. A bare name
 * (vcan1) names a bus of that name of any kind (@plant after -i virtual:plant); two kinds, or two sets of options,
 * under one name are refused. Its index, or -1 after a message. */
static int add_bus(emu_config_t *cfg, const char *text)
{
    if (text[0] == '\0') {
        fprintf(stderr, "canopen-emu: -i/--interface needs a bus (an interface name, udp_multicast[:GROUP[:PORT]], "
                "virtual:NAME), not an empty one\n");
        return -1;
    }
    can_channel_spec_t spec;
    char err[256];
    if (can_channel_parse(text, &spec, err, sizeof err) != 0) {
        fprintf(stderr, "canopen-emu: %s\n", err);
        return -1;
    }
    for (size_t i = 0U; i < cfg->n_buses; i++) {
        const can_channel_spec_t *b = &cfg->buses[i];
        if (strcmp(b->name, spec.name) != 0) {
            continue;
        }
        if (spec.kind_given && (b->kind != spec.kind || memcmp(&b->udp, &spec.udp, sizeof spec.udp) != 0)) {
            fprintf(stderr, "canopen-emu: '%s' names bus %s (%s) again, as another kind or with other options\n", text,
                    b->name, can_channel_kind_name(b->kind));
            return -1;
        }
        return (int)i; /* named twice (-i and @BUS): one bus */
    }
    if (cfg->n_buses == MAX_BUSES) {
        fprintf(stderr, "canopen-emu: at most %d buses\n", MAX_BUSES);
        return -1;
    }
    cfg->buses[cfg->n_buses] = spec;
    return (int)cfg->n_buses++;
}

/* --control-tcp, --web and --socketcand: HOST:PORT, checked before anything starts (the address is resolved later). */
static bool host_port_option(const char *option, const char *example_port, const char *arg, const char **out)
{
    if (!tcp_host_port_ok(arg)) {
        fprintf(stderr, "canopen-emu: %s takes HOST:PORT (127.0.0.1:%s, [::1]:%s, localhost:0; port 0: any free one), "
                "not '%s'\n", option, example_port, example_port, arg);
        return false;
    }
    *out = arg;
    return true;
}

/* Every spec parsed before anything starts, so a bad one fails first; a node-ID is unique per bus. */
static bool parse_specs(emu_config_t *cfg, int argc, char **argv, bool quiet)
{
    for (int a = 0; a < argc; a++) {
        node_spec_t *s = &cfg->specs[cfg->n_specs];
        if (!parse_spec(argv[a], s, quiet)) {
            return false;
        }
        const int bus = s->bus[0] == '\0' ? 0 : add_bus(cfg, s->bus);
        if (bus < 0) {
            return false;
        }
        s->bus_index = (size_t)bus;
        for (size_t k = 0U; k < cfg->n_specs; k++) {
            if (cfg->specs[k].id == s->id && cfg->specs[k].bus_index == s->bus_index) {
                fprintf(stderr, "canopen-emu: node-ID %u is given twice on %s (%s and %s); each node of a bus needs its "
                        "own\n", s->id, cfg->buses[bus].name, argv[k], argv[a]);
                return false;
            }
        }
        cfg->n_specs++;
    }
    return true;
}

int main(int argc, char **argv)
{
    char nvm_default[PATH_MAX];
    emu.log_level = LOG_NORMAL;
    emu.start = socketcan_now_us();
    emu.control.enabled = isatty(STDIN_FILENO) != 0;
    static const struct option opts[] = {
        {"interface", required_argument, NULL, 'i'}, {"nvm-dir", required_argument, NULL, 'n'},
        {"control", required_argument, NULL, 'c'},   {"script", required_argument, NULL, 's'},
        {"list-devices", no_argument, NULL, 'l'},    {"verbose", no_argument, NULL, 'v'},
        {"quiet", no_argument, NULL, 'q'},           {"help", no_argument, NULL, 'h'},
        {"version", no_argument, NULL, 'V'},         {"control-socket", required_argument, NULL, 'u'},
        {"control-tcp", required_argument, NULL, 't'}, {"rules", required_argument, NULL, 'r'},
        {"web", required_argument, NULL, 'w'},       {"control-token-file", required_argument, NULL, 'T'},
        {"socketcand", required_argument, NULL, 'S'},
        {NULL, 0, NULL, 0}};
    const char *rules[16];
    size_t n_rules = 0U;
    int opt;
    while ((opt = getopt_long(argc, argv, "i:vqh", opts, NULL)) != -1) {
        switch (opt) {
        case 'i':
            if (add_bus(&config, optarg) < 0) {
                return 2;
            }
            break;
        case 'n':
            config.nvm_dir = optarg;
            if (config.nvm_dir[0] == '\0') { /* nvm_file_check_dir would read past the end of "" */
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
            config.script = optarg;
            break;
        case 'r':
            if (n_rules == sizeof rules / sizeof rules[0]) {
                fprintf(stderr, "canopen-emu: at most %zu --rules files\n", sizeof rules / sizeof rules[0]);
                return 2;
            }
            rules[n_rules++] = optarg;
            break;
        case 'u':
            config.control_socket = optarg;
            break;
        case 't':
            if (!host_port_option("--control-tcp", "5020", optarg, &config.control_tcp)) {
                return 2;
            }
            break;
        case 'T':
            config.control_token_file = optarg;
            break;
        case 'w':
            if (!host_port_option("--web", "8080", optarg, &config.web)) {
                return 2;
            }
            break;
        case 'S':
            if (!host_port_option("--socketcand", "29536", optarg, &config.socketcand)) {
                return 2;
            }
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
            print_version();
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
    if (argc - optind > MAX_NODES_ALL) {
        fprintf(stderr, "canopen-emu: at most %d nodes\n", MAX_NODES_ALL);
        return 2;
    }
    if (config.n_buses == 0U) {
        (void)add_bus(&config, "vcan0");
    }
    atexit(eds_class_free_all); /* the classes read from EDS files outlive every node */
    if (!parse_specs(&config, argc - optind, &argv[optind], emu.log_level == LOG_QUIET)) {
        return 2;
    }
    for (size_t i = 0U; i < n_rules; i++) {
        if (!eds_class_attach_rules(rules[i], stderr)) {
            return 2;
        }
    }
    if (config.nvm_dir == NULL) {
        config.nvm_dir = default_nvm_dir(nvm_default, sizeof nvm_default);
    }
    char err[512];
    if (nvm_file_check_dir(config.nvm_dir, err, sizeof err) != 0) {
        fprintf(stderr, "canopen-emu: %s\n", err);
        return 1;
    }
    if (config.script != NULL && !script_load(&emu.script, config.script)) {
        return 2;
    }
    config.log_level = emu.log_level;
    int status = runtime_start(&emu, &config);
    if (status != 0) {
        sockets_close(&emu, &emu.sockets); /* a socket file made before the failure goes */
        web_stop(&emu, &emu.web);
        socketcand_stop(&emu, &emu.socketcand);
        return status;
    }
    status = runtime_loop(&emu);
    runtime_stop(&emu);
    return status;
}
