/* What the nodes report: see emu_events.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_events.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "runtime/emu_bus.h"
#include "runtime/emu_events_publish.h"
#include "runtime/emu_output.h"

void events_add_session(emu_t *emu, emu_session_t *s)
{
    if (emu->n_sessions < MAX_SESSIONS) {
        emu->sessions[emu->n_sessions++] = s;
    }
}

void events_remove_session(emu_t *emu, emu_session_t *s)
{
    for (size_t i = 0U; i < emu->n_sessions; i++) {
        if (emu->sessions[i] == s) {
            emu->sessions[i] = emu->sessions[--emu->n_sessions];
            return;
        }
    }
}

/* The log line and the event of one report. fmt gives the text after "node N (device): "; fields are the event's
 * members of its kind (NULL: none). */
static void report(emu_node_t *n, event_kind_t kind, int level, const event_writer_t *fields, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void report(emu_node_t *n, event_kind_t kind, int level, const event_writer_t *fields, const char *fmt, ...)
{
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (level >= 0) {
        logline(level, "node %u (%s): %s", co_node_id(&n->dev.node), n->dev.cls->name, text);
    }
    emu_t *emu = n->bus != NULL ? n->bus->emu : NULL;
    if (emu == NULL) {
        return;
    }
    emu_session_t *to[MAX_SESSIONS];
    const size_t n_to = events_sessions_wanting(emu, kind, co_node_id(&n->dev.node), n->bus, 0U, to);
    if (n_to != 0U) {
        /* The node's time: that of the call in which it acted (the frame's arrival, its deadline). */
        const event_t ev = {kind, n, n->bus, emu_since_start(emu, n->dev.now != 0U ? n->dev.now : socketcan_now_us()),
                            text, false, fields};
        events_publish(&ev, to, n_to);
    }
}

void events_device_print(void *ctx, const device_t *dev, const char *line)
{
    emu_node_t *n = (emu_node_t *)ctx;
    /* Before co_node_init (a model loading its own NVM at power-on) the node has no ID yet: the configured one. */
    const unsigned id = co_node_id(&dev->node) != 0U ? co_node_id(&dev->node) : dev->cfg.node_id;
    reply(&output_stdout_replies, "node %u: %s", id, line);
    emu_t *emu = n != NULL && n->bus != NULL ? n->bus->emu : NULL;
    if (emu == NULL || emu->in_command) {
        return;
    }
    emu_session_t *to[MAX_SESSIONS];
    const size_t n_to = events_sessions_wanting(emu, EVENT_MESSAGE, (uint8_t)id, n->bus, 0U, to);
    if (n_to != 0U) {
        const event_t ev = {EVENT_MESSAGE, n, n->bus,
                            emu_since_start(emu, n->dev.now != 0U ? n->dev.now : socketcan_now_us()), line, false,
                            NULL};
        events_publish(&ev, to, n_to);
    }
}

/* The fields of an event of one or two numbers (key2 NULL: one); keys of EVENT_KEY. */
static void pack_state(event_writer_t *f, char *room, size_t size, const char *key1, size_t key1_len, uint32_t v1,
                       const char *key2, size_t key2_len, uint32_t v2)
{
    writer_init(f, room, size);
    writer_member_uint(f, key1, key1_len, v1);
    if (key2 != NULL) {
        writer_member_uint(f, key2, key2_len, v2);
    }
}

static void store_report(emu_node_t *n, const co_event_t *ev)
{
    const int level = ev->code == 0U ? LOG_NORMAL : LOG_QUIET; /* a failed store is a problem: shown with -q */
    char room[EVENT_FIELDS_ROOM];
    event_writer_t f;
    writer_init(&f, room, sizeof room);
    writer_member_string(&f, EVENT_KEY("what"), ev->index == 0x7E5U ? "lss-store" : ev->kind == CO_EV_STORE ? "store" : "restore");
    writer_member_uint(&f, EVENT_KEY("index"), ev->index);
    writer_member_uint(&f, EVENT_KEY("sub"), ev->sub);
    writer_member_bool(&f, EVENT_KEY("ok"), ev->code == 0U);
    writer_member_uint(&f, EVENT_KEY("abort_code"), ev->code);
    if (ev->index == 0x7E5U) {
        report(n, EVENT_STORE, level, &f, "LSS store configuration (node-ID %lu): %s", (unsigned long)ev->value,
               ev->code == 0U ? "stored" : "failed");
    } else {
        report(n, EVENT_STORE, level, &f, "%s 0x%04X:%02X: %s", ev->kind == CO_EV_STORE ? "store" : "restore", ev->index,
               ev->sub, ev->code == 0U ? "done" : co_abort_text(ev->code));
    }
}

static void nvm_report(emu_node_t *n, const co_event_t *ev)
{
    static const char *const status[] = {"none", "loaded", "damaged", "foreign", "refused"};
    char room[EVENT_FIELDS_ROOM];
    event_writer_t f;
    writer_init(&f, room, sizeof room);
    writer_member_string(&f, EVENT_KEY("area"), ev->index == 0x7E5U ? "lss" : "parameters");
    writer_member_string(&f, EVENT_KEY("status"), ev->value < 5U ? status[ev->value] : "?");
    if (ev->index == 0x7E5U) {
        if (ev->value == CO_NVM_CORRUPT) {
            report(n, EVENT_NVM, LOG_QUIET, &f, "stored LSS configuration is damaged; using the command-line node-ID and "
                   "the default bit timing");
        } else {
            report(n, EVENT_NVM, -1, &f, "stored LSS configuration %s", ev->value == CO_NVM_LOADED ? "loaded" : "none");
        }
    } else if (ev->value == CO_NVM_CORRUPT || ev->value == CO_NVM_FOREIGN) {
        report(n, EVENT_NVM, LOG_QUIET, &f, "stored parameters %s; starting from defaults",
               ev->value == CO_NVM_CORRUPT ? "are damaged (bad header, length or CRC)" : "belong to another device");
    } else if (ev->value == CO_NVM_REFUSED) {
        report(n, EVENT_NVM, -1, &f, "stored parameters refused; defaults used"); /* CO_EV_NVM_REFUSED logged it */
    } else {
        report(n, EVENT_NVM, LOG_VERBOSE, &f, "stored parameters %s", ev->value == CO_NVM_LOADED ? "loaded" : "none, defaults used");
    }
}

void events_device_event(void *ctx, const device_t *dev, const co_event_t *ev)
{
    emu_node_t *n = (emu_node_t *)ctx;
    char room[EVENT_FIELDS_ROOM];
    event_writer_t f;
    switch (ev->kind) {
    case CO_EV_NMT_STATE: {
        const char *from = co_nmt_state_name((co_nmt_state_t)ev->code), *to = co_nmt_state_name((co_nmt_state_t)ev->value);
        writer_init(&f, room, sizeof room);
        writer_member_string(&f, EVENT_KEY("from"), from);
        writer_member_string(&f, EVENT_KEY("to"), to);
        report(n, EVENT_NMT, LOG_NORMAL, &f, "NMT %s -> %s", from, to);
        if (ev->code == CO_NMT_INITIALISING && ev->value == CO_NMT_PRE_OPERATIONAL) {
            report(n, EVENT_BOOT_UP, -1, NULL, "boot-up"); /* the core sends it on this transition */
        }
        break;
    }
    case CO_EV_SDO_ABORT:
        pack_state(&f, room, sizeof room, EVENT_KEY("index"), ev->index, EVENT_KEY("sub"), ev->sub);
        writer_member_uint(&f, EVENT_KEY("abort_code"), ev->code);
        report(n, EVENT_SDO_ABORT, LOG_NORMAL, &f, "SDO abort 0x%08lX on 0x%04X:%02X (%s)", (unsigned long)ev->code,
               ev->index, ev->sub, co_abort_text(ev->code));
        break;
    case CO_EV_EMCY: {
        /* Its 8 bytes are the newest of the node's EMCY queue (co_node.h, CO_EV_EMCY). */
        const co_emcy_t *em = &n->dev.node.emcy;
        const uint8_t *data = em->queue[(unsigned)(em->q_head + em->q_count + CO_EMCY_QUEUE_LEN - 1U) % CO_EMCY_QUEUE_LEN];
        n->last_emcy.at = n->dev.now != 0U ? n->dev.now : socketcan_now_us();
        n->last_emcy.code = (uint16_t)ev->value;
        n->last_emcy.reg = (uint8_t)ev->code;
        memcpy(n->last_emcy.info, &data[3], sizeof n->last_emcy.info);
        pack_state(&f, room, sizeof room, EVENT_KEY("code"), ev->value, EVENT_KEY("register"), ev->code);
        writer_member_hex(&f, EVENT_KEY("info"), n->last_emcy.info, sizeof n->last_emcy.info); /* as the answers' hex_string */
        report(n, EVENT_EMCY, LOG_NORMAL, &f, "EMCY 0x%04lX, error register 0x%02lX", (unsigned long)ev->value,
               (unsigned long)ev->code);
        break;
    }
    case CO_EV_STORE:
    case CO_EV_RESTORE:
        store_report(n, ev);
        break;
    case CO_EV_NVM_LOADED:
        nvm_report(n, ev);
        break;
    case CO_EV_NVM_REFUSED: /* value 0: then CO_EV_NVM_LOADED with CO_NVM_REFUSED; 1: a save that fails */
        pack_state(&f, room, sizeof room, EVENT_KEY("index"), ev->index, EVENT_KEY("sub"), ev->sub);
        if (ev->value == 1U) {
            report(n, EVENT_NVM, LOG_QUIET, &f,
                   "save refused: 0x%04X:%02X holds a value its load would refuse (%s); nothing stored", ev->index,
                   ev->sub, co_abort_text(ev->code));
        } else {
            report(n, EVENT_NVM, LOG_QUIET, &f,
                   "stored parameters refused: 0x%04X:%02X holds a value a write would be refused for (%s); starting "
                   "from defaults", ev->index, ev->sub, co_abort_text(ev->code));
        }
        break;
    case CO_EV_LSS_NODE_ID:
        pack_state(&f, room, sizeof room, EVENT_KEY("pending_node_id"), ev->value, NULL, 0U, 0U);
        report(n, EVENT_LSS, LOG_NORMAL, &f, "LSS pending node-ID %lu", (unsigned long)ev->value);
        break;
    case CO_EV_LSS_BIT_TIMING:
        pack_state(&f, room, sizeof room, EVENT_KEY("pending_bit_timing"), ev->value, NULL, 0U, 0U);
        report(n, EVENT_LSS, LOG_NORMAL, &f, "LSS pending bit timing %lu", (unsigned long)ev->value);
        break;
    case CO_EV_LSS_ACTIVATE:
        pack_state(&f, room, sizeof room, EVENT_KEY("kbit_s"), ev->value, NULL, 0U, 0U);
        report(n, EVENT_LSS, LOG_NORMAL, &f, "LSS activated %lu kbit/s", (unsigned long)ev->value);
        break;
    case CO_EV_HB_TIMEOUT:
        pack_state(&f, room, sizeof room, EVENT_KEY("producer"), ev->value, NULL, 0U, 0U);
        report(n, EVENT_HEARTBEAT, LOG_NORMAL, &f, "heartbeat of node %lu missing", (unsigned long)ev->value);
        break;
    case CO_EV_GUARD_TIMEOUT:
        report(n, EVENT_GUARDING, LOG_NORMAL, NULL, "life guarding: no guard request in time");
        break;
    case CO_EV_RX_FILTER:
        bus_routes_update(n->bus, n);
        break;
    case CO_EV_TX_DROPPED:
        if (dev->cls != NULL) {
            logline(LOG_VERBOSE, "node %u (%s): frame 0x%03lX not sent", co_node_id(&dev->node), dev->cls->name,
                    (unsigned long)ev->value);
        }
        break;
    default:
        break;
    }
}

void events_fault(emu_node_t *n, const char *kind, const char *action, const char *text)
{
    char room[EVENT_FIELDS_ROOM];
    event_writer_t f;
    writer_init(&f, room, sizeof room);
    writer_member_string(&f, EVENT_KEY("fault"), kind);
    writer_member_string(&f, EVENT_KEY("action"), action);
    report(n, EVENT_FAULT, LOG_NORMAL, &f, "%s", text);
}

void events_interface(emu_bus_t *bus, const char *line)
{
    emu_t *emu = bus->emu;
    if (emu == NULL) {
        return;
    }
    emu_session_t *to[MAX_SESSIONS];
    const size_t n_to = events_sessions_wanting(emu, EVENT_INTERFACE, 0U, bus, 0U, to);
    if (n_to != 0U) {
        const event_t ev = {EVENT_INTERFACE, NULL, bus, emu_since_start(emu, socketcan_now_us()), line, false,
                            NULL};
        events_publish(&ev, to, n_to);
    }
}
