/* The medium of one bus, by kind: see can_channel.h. */
#define _GNU_SOURCE
#include "can_channel.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static const char KIND_SOCKETCAN[] = "socketcan:";
static const char KIND_UDP[] = "udp_multicast";
static const char KIND_VIRTUAL[] = "virtual:";

static bool starts_with(const char *text, const char *prefix)
{
    return strncmp(text, prefix, strlen(prefix)) == 0;
}

int can_channel_parse(const char *text, can_channel_spec_t *spec, char *err, size_t errlen)
{
    memset(spec, 0, sizeof *spec);
    spec->kind_given = true;
    const char *name = text;
    if (starts_with(text, KIND_UDP) && (text[sizeof KIND_UDP - 1U] == '\0' || text[sizeof KIND_UDP - 1U] == ':' ||
                                        text[sizeof KIND_UDP - 1U] == ',')) {
        spec->kind = CAN_CHANNEL_UDP_MULTICAST;
        const int e = udp_multicast_parse(text + sizeof KIND_UDP - 1U, &spec->udp, err, errlen);
        if (e == 0) {
            udp_multicast_name(&spec->udp, spec->name, sizeof spec->name);
        }
        return e;
    }
    if (starts_with(text, KIND_VIRTUAL)) {
        spec->kind = CAN_CHANNEL_VIRTUAL;
        name = text + sizeof KIND_VIRTUAL - 1U;
        /* the name is the bus's in NODE@NAME and in the NVM files' names (DEVICE-ID@NAME) */
        if (name[0] == '\0' || strlen(name) >= 48U || strpbrk(name, "/@,") != NULL) {
            (void)snprintf(err, errlen, "virtual:NAME takes a name of 1..47 characters without '/', '@' or ',', "
                           "not '%s'", name);
            return EINVAL;
        }
    } else if (starts_with(text, KIND_SOCKETCAN)) {
        spec->kind = CAN_CHANNEL_SOCKETCAN;
        name = text + sizeof KIND_SOCKETCAN - 1U;
    } else if (strcmp(text, "virtual") == 0) {
        (void)snprintf(err, errlen, "a virtual bus needs a name: virtual:NAME");
        return EINVAL;
    } else {
        const char *colon = strchr(text, ':');
        if (colon != NULL) {
            (void)snprintf(err, errlen, "unknown bus kind '%.*s' in '%s' (socketcan:IFACE, "
                           "udp_multicast[:GROUP[:PORT]], virtual:NAME, or an interface name alone)",
                           (int)(colon - text), text, text);
            return EINVAL;
        }
        spec->kind = CAN_CHANNEL_SOCKETCAN;
        spec->kind_given = false;
    }
    if (spec->kind == CAN_CHANNEL_SOCKETCAN && (name[0] == '\0' || strlen(name) >= IF_NAMESIZE)) {
        (void)snprintf(err, errlen, "'%s' is not a CAN interface name (1..%d characters)", name, IF_NAMESIZE - 1);
        return EINVAL;
    }
    (void)snprintf(spec->name, sizeof spec->name, "%s", name);
    return 0;
}

int can_channel_open(can_channel_t *c, const can_channel_spec_t *spec, can_channel_log_fn log, void *log_ctx,
                     char *err, size_t errlen)
{
    c->kind = spec->kind;
    c->virtual_frames = 0U;
    (void)snprintf(c->name, sizeof c->name, "%s", spec->name);
    c->socketcan.fd = -1;
    c->udp.rx_fd = -1;
    c->udp.tx_fd = -1;
    switch (spec->kind) {
    case CAN_CHANNEL_UDP_MULTICAST:
        return udp_multicast_open(&c->udp, &spec->udp, spec->name, log, log_ctx, err, errlen);
    case CAN_CHANNEL_VIRTUAL:
        return 0;
    default:
        return socketcan_open(&c->socketcan, spec->name, log, log_ctx, err, errlen);
    }
}

bool can_channel_describe(const can_channel_t *c, char *out, size_t len)
{
    if (c->kind == CAN_CHANNEL_UDP_MULTICAST) {
        const udp_multicast_t *u = &c->udp;
        (void)snprintf(out, len, "%s: group %s port %u joined on %s, %s %u: whoever is on that link is on the bus "
                       "(docs/buses.md)", c->name, u->cfg.group_text, (unsigned)u->cfg.port, u->ifname,
                       u->cfg.group.ss_family == AF_INET6 ? "hop limit" : "TTL", (unsigned)u->cfg.hop_limit);
        return true;
    }
    if (c->kind == CAN_CHANNEL_VIRTUAL) {
        (void)snprintf(out, len, "%s: a virtual bus inside this process: its nodes hear each other and nothing else",
                       c->name);
        return true;
    }
    return false;
}

co_status_t can_channel_send_other(can_channel_t *c, const co_frame_t *frame)
{
    if (c->kind == CAN_CHANNEL_UDP_MULTICAST) {
        return udp_multicast_send(&c->udp, frame);
    }
    c->virtual_frames++; /* no medium: the bus gives the frame to its other nodes (emu_bus.c) */
    return CO_OK;
}

void can_channel_flush_log(can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        socketcan_flush_log(&c->socketcan);
    } else if (c->kind == CAN_CHANNEL_UDP_MULTICAST) {
        udp_multicast_flush_log(&c->udp);
    }
}

unsigned long can_channel_rx_dropped(const can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        return c->socketcan.rx_dropped;
    }
    return c->kind == CAN_CHANNEL_UDP_MULTICAST ? c->udp.rx_dropped : 0UL;
}

void can_channel_close(can_channel_t *c)
{
    if (c->kind == CAN_CHANNEL_SOCKETCAN) {
        socketcan_close(&c->socketcan);
    } else if (c->kind == CAN_CHANNEL_UDP_MULTICAST) {
        udp_multicast_close(&c->udp);
    }
}
