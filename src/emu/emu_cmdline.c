/* The command line of canopen-emu: see emu_cmdline.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_cmdline.h"

#include <stdlib.h>
#include <string.h>

void usage(FILE *out)
{
    fprintf(out,
            "usage: canopen-emu [-i IFACE] [--nvm-dir DIR] [options] DEVICE[/VARIANT][:NODE-ID] ...\n"
            "Emulates CANopen devices on a SocketCAN interface (default vcan0).\n\n"
            "  -i, --interface IFACE   CAN interface (default vcan0)\n"
            "      --nvm-dir DIR       where stored parameters live (default $XDG_STATE_HOME/canopen-emu\n"
            "                          or ~/.local/state/canopen-emu)\n"
            "      --control -         read control commands from stdin even when it is not a terminal\n"
            "      --script FILE       run control commands from FILE ('@MS command' lines, see canopen-emu(1))\n"
            "      --list-devices      list the device types and exit\n"
            "  -v, --verbose           log every frame sent and received as well\n"
            "  -q, --quiet             log only problems\n"
            "  -h, --help              this help\n"
            "      --version           the version (and the git revision it was built from) and exit\n\n"
            "NODE-ID is 1..127, decimal or 0x-hex; default: the device's own (see --list-devices).\n"
            "Example: canopen-emu pro-ionizer:0x10 sds/E:11 buerkert:12\n");
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

/* DEVICE[/VARIANT][:NODE-ID] */
bool parse_spec(const char *spec, const device_class_t **cls, char *variant, size_t vlen, uint8_t *id)
{
    char name[64];
    const char *colon = strchr(spec, ':');
    const size_t nlen = colon != NULL ? (size_t)(colon - spec) : strlen(spec);
    if (nlen == 0U || nlen >= sizeof name) {
        fprintf(stderr, "canopen-emu: '%s' is not DEVICE[/VARIANT][:NODE-ID]\n", spec);
        return false;
    }
    memcpy(name, spec, nlen);
    name[nlen] = '\0';
    variant[0] = '\0';
    char *slash = strchr(name, '/');
    if (slash != NULL) {
        *slash = '\0';
        (void)snprintf(variant, vlen, "%s", slash + 1);
    }
    *cls = device_find_class(name);
    if (*cls == NULL) {
        fprintf(stderr, "canopen-emu: unknown device '%s'; known devices:\n", name);
        list_devices(stderr);
        return false;
    }
    *id = (*cls)->default_node_id;
    if (colon != NULL) {
        long long v;
        if (!device_parse_int(colon + 1, 1, 127, &v)) {
            fprintf(stderr, "canopen-emu: bad node-ID '%s' in '%s': use 1..127 (decimal or 0x-hex)\n", colon + 1, spec);
            return false;
        }
        *id = (uint8_t)v;
    }
    if (variant[0] != '\0') {
        bool found = false;
        for (size_t v = 0U; (*cls)->variants != NULL && (*cls)->variants[v] != NULL; v++) {
            found = found || strcmp((*cls)->variants[v], variant) == 0;
        }
        if (!found) {
            fprintf(stderr, "canopen-emu: device %s has no variant '%s' (see --list-devices)\n", name, variant);
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
