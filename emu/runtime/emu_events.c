/* What the nodes report: see emu_events.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "runtime/emu_events.h"

#include <jansson.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "runtime/emu_bus.h"
#include "control/emu_json_request.h" /* hex_string: the events write bytes as the answers do */
#include "runtime/emu_output.h"
#include "text_escape.h"

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

static bool anyone_wants(const emu_t *emu, event_kind_t kind, uint8_t id, const emu_bus_t *bus, uint32_t cob_id)
{
    for (size_t i = 0U; i < emu->n_sessions; i++) {
        if (session_wants(emu->sessions[i], kind, id, bus, cob_id)) {
            return true;
        }
    }
    return false;
}

/* One event to every session that wants it: JSON built once, text formatted once. fields is consumed. */
static void publish(emu_t *emu, event_kind_t kind, const emu_node_t *n, const emu_bus_t *bus, co_time_us_t at,
                    uint32_t cob_id, const char *text, json_t *fields)
{
    const uint8_t id = n != NULL ? co_node_id(&n->dev.node) : 0U;
    char *json_line = NULL;
    size_t json_len = 0U;
    char text_line[1024];
    size_t text_len = 0U;
    const co_time_us_t t = emu_since_start(emu, at);
    for (size_t i = 0U; i < emu->n_sessions; i++) {
        emu_session_t *s = emu->sessions[i];
        if (!session_wants(s, kind, id, bus, cob_id)) {
            continue;
        }
        if (s->events_json) {
            if (json_line == NULL) {
                json_t *o = json_object();
                (void)json_object_set_new(o, "event", json_string(event_kind_name(kind)));
                (void)json_object_set_new(o, "time_us", json_integer((json_int_t)t));
                if (bus != NULL) {
                    (void)json_object_set_new(o, "bus", json_string(bus->can.name));
                }
                if (n != NULL) {
                    (void)json_object_set_new(o, "node", json_integer(id));
                    (void)json_object_set_new(o, "device", jstr(n->dev.cls->name)); /* an EDS file's name: any bytes */
                }
                if (fields != NULL) {
                    (void)json_object_update(o, fields);
                }
                if (text != NULL) {
                    (void)json_object_set_new(o, "text", jstr(text));
                }
                /* ASCII only: jansson writes DEL and the C1 controls (U+0080..U+009F, a CSI to some terminals) as
                 * they are otherwise, and a raw event stream may be read on a terminal. */
                json_line = json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
                json_decref(o);
                if (json_line == NULL) {
                    continue;
                }
                json_len = strlen(json_line);
                json_line[json_len++] = '\n'; /* in the NUL's room: written with its length */
            }
            s->write(s->ctx, json_line, json_len);
        } else {
            if (text_len == 0U) {
                /* The device's name (an EDS file's) and the text (a model's message) are shown escaped, as the
                 * log shows them (text_escape.h): one line, nothing a terminal acts on. */
                char raw[sizeof text_line];
                int w;
                if (n != NULL) {
                    w = snprintf(raw, sizeof raw, "event %s %.6f node %u@%s (%s): %s", event_kind_name(kind),
                                 (double)t / 1e6, id, bus->can.name, n->dev.cls->name, text != NULL ? text : "");
                } else {
                    w = snprintf(raw, sizeof raw, "event %s %.6f %s: %s", event_kind_name(kind),
                                 (double)t / 1e6, bus != NULL ? bus->can.name : "-", text != NULL ? text : "");
                }
                const size_t raw_len = w < 0 ? 0U : (size_t)w < sizeof raw ? (size_t)w : sizeof raw - 1U;
                text_len = text_escape(text_line, sizeof text_line - 1U, raw, raw_len, TEXT_ONE_LINE);
                text_line[text_len++] = '\n'; /* a line cut to size still ends with its newline */
            }
            s->write(s->ctx, text_line, text_len);
        }
    }
    free(json_line);
    json_decref(fields);
}

/* The log line and the event of one report. fmt gives the text after "node N (device): ". */
static void report(emu_node_t *n, event_kind_t kind, int level, json_t *fields, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void report(emu_node_t *n, event_kind_t kind, int level, json_t *fields, const char *fmt, ...)
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
    if (emu != NULL && anyone_wants(emu, kind, co_node_id(&n->dev.node), n->bus, 0U)) {
        /* The node's time: that of the call in which it acted (the frame's arrival, its deadline). */
        publish(emu, kind, n, n->bus, n->dev.now != 0U ? n->dev.now : socketcan_now_us(), 0U, text, fields);
    } else {
        json_decref(fields);
    }
}

void events_device_print(void *ctx, const device_t *dev, const char *line)
{
    emu_node_t *n = (emu_node_t *)ctx;
    /* Before co_node_init (a model loading its own NVM at power-on) the node has no ID yet: the configured one. */
    const unsigned id = co_node_id(&dev->node) != 0U ? co_node_id(&dev->node) : dev->cfg.node_id;
    reply(&output_stdout_replies, "node %u: %s", id, line);
    emu_t *emu = n != NULL && n->bus != NULL ? n->bus->emu : NULL;
    if (emu != NULL && !emu->in_command && anyone_wants(emu, EVENT_MESSAGE, (uint8_t)id, n->bus, 0U)) {
        publish(emu, EVENT_MESSAGE, n, n->bus, n->dev.now != 0U ? n->dev.now : socketcan_now_us(), 0U, line, NULL);
    }
}

static json_t *pack_state(const char *key1, uint32_t v1, const char *key2, uint32_t v2)
{
    json_t *o = json_object();
    (void)json_object_set_new(o, key1, json_integer(v1));
    if (key2 != NULL) {
        (void)json_object_set_new(o, key2, json_integer(v2));
    }
    return o;
}

static void store_report(emu_node_t *n, const co_event_t *ev)
{
    const int level = ev->code == 0U ? LOG_NORMAL : LOG_QUIET; /* a failed store is a problem: shown with -q */
    json_t *f = json_object();
    (void)json_object_set_new(f, "what", json_string(ev->index == 0x7E5U ? "lss-store" : ev->kind == CO_EV_STORE ? "store" : "restore"));
    (void)json_object_set_new(f, "index", json_integer(ev->index));
    (void)json_object_set_new(f, "sub", json_integer(ev->sub));
    (void)json_object_set_new(f, "ok", json_boolean(ev->code == 0U));
    (void)json_object_set_new(f, "abort_code", json_integer(ev->code));
    if (ev->index == 0x7E5U) {
        report(n, EVENT_STORE, level, f, "LSS store configuration (node-ID %lu): %s", (unsigned long)ev->value,
               ev->code == 0U ? "stored" : "failed");
    } else {
        report(n, EVENT_STORE, level, f, "%s 0x%04X:%02X: %s", ev->kind == CO_EV_STORE ? "store" : "restore", ev->index,
               ev->sub, ev->code == 0U ? "done" : co_abort_text(ev->code));
    }
}

static void nvm_report(emu_node_t *n, const co_event_t *ev)
{
    static const char *const status[] = {"none", "loaded", "damaged", "foreign", "refused"};
    json_t *f = json_object();
    (void)json_object_set_new(f, "area", json_string(ev->index == 0x7E5U ? "lss" : "parameters"));
    (void)json_object_set_new(f, "status", json_string(ev->value < 5U ? status[ev->value] : "?"));
    if (ev->index == 0x7E5U) {
        if (ev->value == CO_NVM_CORRUPT) {
            report(n, EVENT_NVM, LOG_QUIET, f, "stored LSS configuration is damaged; using the command-line node-ID and "
                   "the default bit timing");
        } else {
            report(n, EVENT_NVM, -1, f, "stored LSS configuration %s", ev->value == CO_NVM_LOADED ? "loaded" : "none");
        }
    } else if (ev->value == CO_NVM_CORRUPT || ev->value == CO_NVM_FOREIGN) {
        report(n, EVENT_NVM, LOG_QUIET, f, "stored parameters %s; starting from defaults",
               ev->value == CO_NVM_CORRUPT ? "are damaged (bad header, length or CRC)" : "belong to another device");
    } else if (ev->value == CO_NVM_REFUSED) {
        report(n, EVENT_NVM, -1, f, "stored parameters refused; defaults used"); /* CO_EV_NVM_REFUSED logged it */
    } else {
        report(n, EVENT_NVM, LOG_VERBOSE, f, "stored parameters %s", ev->value == CO_NVM_LOADED ? "loaded" : "none, defaults used");
    }
}

void events_device_event(void *ctx, const device_t *dev, const co_event_t *ev)
{
    emu_node_t *n = (emu_node_t *)ctx;
    switch (ev->kind) {
    case CO_EV_NMT_STATE: {
        const char *from = co_nmt_state_name((co_nmt_state_t)ev->code), *to = co_nmt_state_name((co_nmt_state_t)ev->value);
        json_t *f = json_object();
        (void)json_object_set_new(f, "from", json_string(from));
        (void)json_object_set_new(f, "to", json_string(to));
        report(n, EVENT_NMT, LOG_NORMAL, f, "NMT %s -> %s", from, to);
        if (ev->code == CO_NMT_INITIALISING && ev->value == CO_NMT_PRE_OPERATIONAL) {
            report(n, EVENT_BOOT_UP, -1, NULL, "boot-up"); /* the core sends it on this transition */
        }
        break;
    }
    case CO_EV_SDO_ABORT: {
        json_t *f = pack_state("index", ev->index, "sub", ev->sub);
        (void)json_object_set_new(f, "abort_code", json_integer(ev->code));
        report(n, EVENT_SDO_ABORT, LOG_NORMAL, f, "SDO abort 0x%08lX on 0x%04X:%02X (%s)", (unsigned long)ev->code,
               ev->index, ev->sub, co_abort_text(ev->code));
        break;
    }
    case CO_EV_EMCY: {
        /* Its 8 bytes are the newest of the node's EMCY queue (co_node.h, CO_EV_EMCY). */
        const co_emcy_t *em = &n->dev.node.emcy;
        const uint8_t *data = em->queue[(unsigned)(em->q_head + em->q_count + CO_EMCY_QUEUE_LEN - 1U) % CO_EMCY_QUEUE_LEN];
        n->last_emcy.at = n->dev.now != 0U ? n->dev.now : socketcan_now_us();
        n->last_emcy.code = (uint16_t)ev->value;
        n->last_emcy.reg = (uint8_t)ev->code;
        memcpy(n->last_emcy.info, &data[3], sizeof n->last_emcy.info);
        json_t *f = pack_state("code", ev->value, "register", ev->code);
        (void)json_object_set_new(f, "info", hex_string(n->last_emcy.info, sizeof n->last_emcy.info));
        report(n, EVENT_EMCY, LOG_NORMAL, f, "EMCY 0x%04lX, error register 0x%02lX", (unsigned long)ev->value,
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
        if (ev->value == 1U) {
            report(n, EVENT_NVM, LOG_QUIET, pack_state("index", ev->index, "sub", ev->sub),
                   "save refused: 0x%04X:%02X holds a value its load would refuse (%s); nothing stored", ev->index,
                   ev->sub, co_abort_text(ev->code));
        } else {
            report(n, EVENT_NVM, LOG_QUIET, pack_state("index", ev->index, "sub", ev->sub),
                   "stored parameters refused: 0x%04X:%02X holds a value a write would be refused for (%s); starting "
                   "from defaults", ev->index, ev->sub, co_abort_text(ev->code));
        }
        break;
    case CO_EV_LSS_NODE_ID:
        report(n, EVENT_LSS, LOG_NORMAL, pack_state("pending_node_id", ev->value, NULL, 0U), "LSS pending node-ID %lu",
               (unsigned long)ev->value);
        break;
    case CO_EV_LSS_BIT_TIMING:
        report(n, EVENT_LSS, LOG_NORMAL, pack_state("pending_bit_timing", ev->value, NULL, 0U),
               "LSS pending bit timing %lu", (unsigned long)ev->value);
        break;
    case CO_EV_LSS_ACTIVATE:
        report(n, EVENT_LSS, LOG_NORMAL, pack_state("kbit_s", ev->value, NULL, 0U), "LSS activated %lu kbit/s",
               (unsigned long)ev->value);
        break;
    case CO_EV_HB_TIMEOUT:
        report(n, EVENT_HEARTBEAT, LOG_NORMAL, pack_state("producer", ev->value, NULL, 0U), "heartbeat of node %lu missing",
               (unsigned long)ev->value);
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
    json_t *f = json_object();
    (void)json_object_set_new(f, "fault", json_string(kind));
    (void)json_object_set_new(f, "action", json_string(action));
    report(n, EVENT_FAULT, LOG_NORMAL, f, "%s", text);
}

void events_interface(emu_bus_t *bus, const char *line)
{
    emu_t *emu = bus->emu;
    if (emu != NULL && anyone_wants(emu, EVENT_INTERFACE, 0U, bus, 0U)) {
        publish(emu, EVENT_INTERFACE, NULL, bus, socketcan_now_us(), 0U, line, NULL);
    }
}

/* Out of line: its buffers would otherwise make every frame pay for a stack frame nobody uses. */
__attribute__((noinline)) void events_frame_publish(emu_t *emu, emu_bus_t *bus, const emu_node_t *from,
                                                    const co_frame_t *f, co_time_us_t at)
{
    /* The format is part of the frame's identity (session_wants): an extended 0x181 is no TPDO1 of node 1. */
    const bool eff = (f->flags & CO_FRAME_EFF) != 0U;
    const uint32_t identity = f->id | (eff ? SESSION_FRAME_EFF : 0U);
    if (!anyone_wants(emu, EVENT_FRAME, from != NULL ? co_node_id(&from->dev.node) : 0U, bus, identity)) {
        return; /* nothing is built for a frame nobody's filter takes */
    }
    json_t *fields = json_object();
    char hex[17] = "";
    for (uint8_t i = 0U; i < f->len && i < 8U; i++) {
        (void)snprintf(hex + 2U * i, 3U, "%02X", f->data[i]);
    }
    (void)json_object_set_new(fields, "dir", json_string(from != NULL ? "tx" : "rx"));
    (void)json_object_set_new(fields, "id", json_integer(f->id));
    (void)json_object_set_new(fields, "data", json_string(hex));
    if ((f->flags & CO_FRAME_RTR) != 0U) {
        (void)json_object_set_new(fields, "rtr", json_true());
    }
    if (eff) {
        (void)json_object_set_new(fields, "eff", json_true());
    }
    char text[64];
    /* candump's form: 3 hex digits for an 11-bit identifier, 8 for a 29-bit one, whatever its value */
    (void)snprintf(text, sizeof text, "%s %0*X#%s%s", from != NULL ? "tx" : "rx", eff ? 8 : 3, (unsigned)f->id, hex,
                   (f->flags & CO_FRAME_RTR) != 0U ? "R" : "");
    publish(emu, EVENT_FRAME, from, bus, at, identity, text, fields);
}
