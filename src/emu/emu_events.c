/* What the nodes report: see emu_events.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "emu_events.h"

#include "emu_output.h"

void events_device_print(void *ctx, const device_t *dev, const char *line)
{
    (void)ctx;
    /* Before co_node_init (a model loading its own NVM at power-on) the node has no ID yet: the configured one. */
    const unsigned id = co_node_id(&dev->node) != 0U ? co_node_id(&dev->node) : dev->cfg.node_id;
    reply("node %u: %s", id, line);
}

void events_device_event(void *ctx, const device_t *dev, const co_event_t *ev)
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
