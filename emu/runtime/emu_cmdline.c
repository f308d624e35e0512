/* The command line of canopen-emu: see emu_cmdline.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_cmdline.h"

#include <limits.h>
#include <stdlib.h>

#include "eds_class/eds_class.h"
#include <string.h>

void usage(FILE *out)
{
    fprintf(out,
            "usage: canopen-emu [-i BUS]... [--nvm-dir DIR] [options] DEVICE[/VARIANT][:NODE-ID][@BUS] ...\n"
            "       canopen-emu [options] FILE.eds:NODE-ID[@BUS] FILE.dcf[:NODE-ID][@BUS] ...\n"
            "Emulates CANopen devices on CAN buses (default vcan0): the built-in ones (--list-devices)\n"
            "and any device from its EDS or DCF (docs/eds.md), in any mix.\n\n"
            "  -i, --interface BUS     the bus (default vcan0); repeat it for several buses: nodes without @BUS go\n"
            "                          to the first. BUS is python-can's interface name and channel:\n"
            "                            IFACE, socketcan:IFACE  a SocketCAN interface (vcan0, can0)\n"
            "                            udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME]  python-can's\n"
            "                                udp_multicast: no kernel CAN, no root (default 239.74.163.2:43113,\n"
            "                                TTL 1; IPv6 as [ff15::1]:43113); whoever is on the link is on the bus\n"
            "                            virtual:NAME  a bus inside this process only (docs/buses.md)\n"
            "      --nvm-dir DIR       where stored parameters live (default $XDG_STATE_HOME/canopen-emu\n"
            "                          or ~/.local/state/canopen-emu)\n"
            "      --control -         read control commands from stdin even when it is not a terminal\n"
            "      --control-socket PATH  accept control clients on a Unix socket (mode 0600)\n"
            "      --control-tcp HOST:PORT  accept control clients on TCP (127.0.0.1:5020; port 0: any free one)\n"
            "      --control-token-file FILE  TCP clients must first say hello with the token in FILE (required\n"
            "                          when --control-tcp is not a loopback address)\n"
            "      --web HOST:PORT     serve the web view to browsers (127.0.0.1:8080, then open\n"
            "                          http://127.0.0.1:8080/; port 0: any free one; docs/web.md)\n"
            "      --socketcand HOST:PORT  serve every bus as a socketcand channel of its name (127.0.0.1:29536;\n"
            "                          python-can's interface='socketcand'); whoever reaches it is on the buses\n"
            "      --script FILE       run control commands from FILE ('@MS command' lines, see canopen-emu(1))\n"
            "      --rules FILE        behaviour rules (YAML) for a device read from an EDS/DCF (docs/eds.md)\n"
            "      --list-devices      list the device types and exit\n"
            "  -v, --verbose           log every frame sent and received as well\n"
            "  -q, --quiet             log only problems\n"
            "  -h, --help              this help\n"
            "      --version           the version (and the git revision it was built from) and exit\n\n"
            "NODE-ID is 1..127, decimal or 0x-hex; default: the device's own (see --list-devices); unique per bus.\n"
            "Example: canopen-emu pro-ionizer:0x10 sds/E:11 buerkert:12 drive.eds:20\n"
            "         canopen-emu -i vcan0 -i vcan1 sds:16 sds:16@vcan1\n"
            "         canopen-emu -i udp_multicast sds:16     (python-can: interface='udp_multicast',\n"
            "                                                  channel='239.74.163.2')\n");
}

void list_devices(FILE *out)
{
    for (size_t i = 0U; device_classes[i] != NULL; i++) {
        const device_class_t *c = device_classes[i];
        fprintf(out, "%-12s node-ID %-3u %s", c->name, c->default_node_id, c->summary);
        if (c->variants != NULL) {
            fprintf(out, " (variants:");
            for (size_t v = 0U; c->variants[v] != NULL; v++) {
                fprintf(out, " %s%s", c->variants[v], v == 0U ? "*" : "");
            }
            fprintf(out, ")");
        }
        fprintf(out, "\n");
    }
}

static bool parse_node_id(const char *text, const char *arg, node_spec_t *spec)
{
    long long v;
    if (!device_parse_int(text, 1, 127, &v)) {
        fprintf(stderr, "canopen-emu: bad node-ID '%s' in '%s': use 1..127 (decimal or 0x-hex)\n", text, arg);
        return false;
    }
    spec->id = (uint8_t)v;
    return true;
}

/* DEVICE[/VARIANT][:NODE-ID][@BUS], or FILE.eds|FILE.dcf[:NODE-ID][@BUS] */
bool parse_spec(const char *arg, node_spec_t *spec, bool quiet)
{
    char text[PATH_MAX + 64];
    char name[PATH_MAX];
    memset(spec, 0, sizeof *spec);
    if (strlen(arg) >= sizeof text) {
        fprintf(stderr, "canopen-emu: '%s' is not DEVICE[/VARIANT][:NODE-ID][@BUS]\n", arg);
        return false;
    }
    (void)snprintf(text, sizeof text, "%s", arg);
    char *at = strchr(text, '@');
    if (at != NULL) {
        *at++ = '\0';
        if (at[0] == '\0' || strlen(at) >= sizeof spec->bus || strchr(at, '/') != NULL) {
            fprintf(stderr, "canopen-emu: bad bus '%s' in '%s'\n", at, arg);
            return false;
        }
        (void)snprintf(spec->bus, sizeof spec->bus, "%s", at);
    }
    const char *colon = strchr(text, ':');
    const size_t nlen = colon != NULL ? (size_t)(colon - text) : strlen(text);
    if (nlen == 0U || nlen >= sizeof name) {
        fprintf(stderr, "canopen-emu: '%s' is not DEVICE[/VARIANT][:NODE-ID][@BUS]\n", arg);
        return false;
    }
    memcpy(name, text, nlen);
    name[nlen] = '\0';
    if (eds_class_is_file(name)) {
        spec->cls = eds_class_load(name, stderr, quiet);
        if (spec->cls == NULL) {
            return false;
        }
        spec->id = spec->cls->default_node_id;
        if (colon == NULL && spec->id == 0U) {
            fprintf(stderr, "canopen-emu: %s: give the node-ID (%s:ID): the file has no [DeviceComissioning] NodeID in 1..127\n",
                    arg, name);
            return false;
        }
        if (colon != NULL && !parse_node_id(colon + 1, arg, spec)) {
            return false;
        }
        eds_class_warn_node_id(spec->cls, spec->id, stderr, quiet);
        return true;
    }
    char *slash = strchr(name, '/');
    if (slash != NULL) {
        *slash = '\0';
        (void)snprintf(spec->variant, sizeof spec->variant, "%s", slash + 1);
    }
    spec->cls = device_find_class(name);
    if (spec->cls == NULL) {
        fprintf(stderr, "canopen-emu: unknown device '%s'; known devices:\n", name);
        list_devices(stderr);
        return false;
    }
    spec->id = spec->cls->default_node_id;
    if (colon != NULL && !parse_node_id(colon + 1, arg, spec)) {
        return false;
    }
    if (spec->variant[0] != '\0') {
        bool found = false;
        for (size_t v = 0U; spec->cls->variants != NULL && spec->cls->variants[v] != NULL; v++) {
            found = found || strcmp(spec->cls->variants[v], spec->variant) == 0;
        }
        if (!found) {
            fprintf(stderr, "canopen-emu: device %s has no variant '%s' (see --list-devices)\n", name, spec->variant);
            return false;
        }
    }
    return true;
}

const char *default_nvm_dir(char *buf, size_t len)
{
    const char *state = getenv("XDG_STATE_HOME");
    const char *home = getenv("HOME");
    if (state != NULL && state[0] == '/') {
        (void)snprintf(buf, len, "%s/canopen-emu", state);
    } else if (home != NULL && home[0] != '\0') {
        (void)snprintf(buf, len, "%s/.local/state/canopen-emu", home);
    } else {
        (void)snprintf(buf, len, "./canopen-emu-nvm");
    }
    return buf;
}
