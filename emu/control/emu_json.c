/* The JSON framing of the control protocol: see emu_json.h and docs/control-protocol.md. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_json.h"
#include "control/emu_json_request.h"

#include <jansson.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "runtime/emu.h"
#include "control/emu_commands.h"
#include "runtime/emu_output.h"
#include "emu_version.h" /* generated: EMU_VERSION (cmake/version.cmake) */

/* ---- Writing ---------------------------------------------------------------------------------------------- */

/* A JSON string of text; bytes that are not UTF-8 (a device name never has them, but a reply may echo input)
 * become '?', so that nothing is lost silently by a NULL from json_string(). */
json_t *jstr(const char *text)
{
    json_t *j = json_string(text);
    if (j != NULL) {
        return j;
    }
    char clean[4096];
    size_t n = 0U;
    for (; text[n] != '\0' && n < sizeof clean - 1U; n++) {
        clean[n] = (unsigned char)text[n] < 0x80U ? text[n] : '?';
    }
    clean[n] = '\0';
    return json_string(clean);
}

void send_response(emu_session_t *s, json_t *obj)
{
    char *text = json_dumps(obj, JSON_COMPACT | JSON_ENSURE_ASCII); /* no raw C1 control reaches a terminal */
    json_decref(obj);
    if (text == NULL) {
        static const char oom[] = "{\"id\":null,\"ok\":false,\"error\":\"out of memory\"}\n";
        s->write(s->ctx, oom, sizeof oom - 1U);
        return;
    }
    const size_t len = strlen(text);
    text[len] = '\n'; /* json_dumps leaves room for its NUL: the newline takes it */
    s->write(s->ctx, text, len + 1U);
    free(text);
}

json_t *response(json_t *id, bool ok)
{
    json_t *r = json_object();
    (void)json_object_set(r, "id", id != NULL ? id : json_null());
    (void)json_object_set_new(r, "ok", json_boolean(ok));
    return r;
}

static void vfail(emu_session_t *s, json_t *id, const char *fmt, va_list ap) __attribute__((format(printf, 3, 0)));
static void vfail(emu_session_t *s, json_t *id, const char *fmt, va_list ap)
{
    char text[1024];
    (void)vsnprintf(text, sizeof text, fmt, ap);
    json_t *r = response(id, false);
    (void)json_object_set_new(r, "error", jstr(text));
    send_response(s, r);
}

void fail(emu_session_t *s, json_t *id, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(s, id, fmt, ap);
    va_end(ap);
}

void json_error(emu_session_t *s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(s, NULL, fmt, ap);
    va_end(ap);
}

/* ---- Reply lines of the command language, captured ---------------------------------------------------------- */

/* Reply lines of the command language captured into a JSON array (a reply_sink_t's context, with capture_sink). */
typedef struct capture {
    json_t *lines;
    char error[1024]; /* the first error line, without "node N: " and "error: " */
} capture_t;

static void capture_sink(void *ctx, const char *text, size_t len)
{
    capture_t *c = (capture_t *)ctx;
    char line[4096];
    if (len > sizeof line - 1U) {
        len = sizeof line - 1U;
    }
    memcpy(line, text, len);
    line[len] = '\0';
    /* A multi-line reply (help) is one reply with newlines inside: one array element per line. */
    char *save = NULL;
    for (char *l = strtok_r(line, "\n", &save); l != NULL; l = strtok_r(NULL, "\n", &save)) {
        (void)json_array_append_new(c->lines, jstr(l));
        const char *e = l;
        if (strncmp(e, "node ", 5) == 0 && strstr(e, ": ") != NULL) {
            e = strstr(e, ": ") + 2;
        }
        if (c->error[0] == '\0' && strncmp(e, "error: ", 7) == 0) {
            (void)snprintf(c->error, sizeof c->error, "%s", e + 7);
        }
    }
}

/* Runs words as the command language does, the reply lines captured; result and lines into r (stolen). */
static command_result_t run_captured(emu_t *emu, int argc, char **argv, capture_t *c)
{
    c->lines = json_array();
    c->error[0] = '\0';
    const reply_sink_t to = {capture_sink, c};
    return run_command_words(emu, argc, argv, &to);
}

/* select_nodes with the reply that explains a refusal kept in c->error instead of written. */
static int select_captured(emu_t *emu, char *word, emu_node_t **out, size_t max, capture_t *c)
{
    c->lines = json_array();
    c->error[0] = '\0';
    const reply_sink_t to = {capture_sink, c};
    const int n = select_nodes(emu, word, out, max, &to);
    json_decref(c->lines);
    c->lines = NULL;
    return n;
}

/* ---- Request fields ------------------------------------------------------------------------------------------ */

/* Every field of the request must be one the command takes: a typo ("nod") is an error, not a default. */
bool only_fields(const request_t *q, const char *const *allowed)
{
    const char *key;
    json_t *value;
    json_object_foreach(q->req, key, value) {
        bool ok = strcmp(key, "id") == 0 || strcmp(key, "cmd") == 0;
        for (size_t i = 0U; !ok && allowed[i] != NULL; i++) {
            ok = strcmp(key, allowed[i]) == 0;
        }
        if (!ok) {
            fail(q->s, q->id, "%s: unknown field '%s'", q->cmd, key);
            return false;
        }
    }
    return true;
}

/* "node": 16, "16", "0x10", "16@vcan1", "all", "all@vcan1" as a word of the command language. */
static bool node_word(const request_t *q, char *word, size_t size, bool required)
{
    json_t *node = json_object_get(q->req, "node");
    if (node == NULL) {
        if (required) {
            fail(q->s, q->id, "%s: needs \"node\"", q->cmd);
        }
        return false;
    }
    if (json_is_integer(node)) {
        (void)snprintf(word, size, "%" JSON_INTEGER_FORMAT, json_integer_value(node));
    } else if (json_is_string(node) && json_string_length(node) < size) {
        (void)snprintf(word, size, "%s", json_string_value(node));
    } else {
        fail(q->s, q->id, "%s: \"node\" must be a node-ID (1..127) or a string such as \"16@vcan1\" or \"all\"", q->cmd);
        return false;
    }
    if (strchr(word, ' ') != NULL || word[0] == '\0') {
        fail(q->s, q->id, "%s: '%s' is not a node-ID", q->cmd, word);
        return false;
    }
    return true;
}

/* Exactly one node for get and set. */
emu_node_t *one_node(const request_t *q)
{
    char word[64];
    if (!node_word(q, word, sizeof word, true)) {
        return NULL;
    }
    emu_node_t *nodes[2];
    capture_t c;
    const int n = select_captured(q->emu, word, nodes, 2U, &c);
    if (n < 0) {
        fail(q->s, q->id, "%s", c.error);
        return NULL;
    }
    if (n == 0) {
        fail(q->s, q->id, "no node %s", word);
        return NULL;
    }
    if (n > 1 || strncmp(word, "all", 3) == 0) {
        fail(q->s, q->id, "%s needs one node, not %s", q->cmd, word);
        return NULL;
    }
    return nodes[0];
}

/* "object": "0x6401:01" (hex, as the command language), or an index number with an optional "sub". */
bool object_address(const request_t *q, uint16_t *index, uint8_t *sub, char *text, size_t size)
{
    json_t *o = json_object_get(q->req, "object");
    json_t *js = json_object_get(q->req, "sub");
    if (json_is_string(o) && js == NULL && device_parse_address(json_string_value(o), index, sub)) {
        (void)snprintf(text, size, "0x%04X:%02X", *index, *sub);
        return true;
    }
    if (json_is_integer(o) && json_integer_value(o) >= 0 && json_integer_value(o) <= 0xFFFF &&
        (js == NULL || (json_is_integer(js) && json_integer_value(js) >= 0 && json_integer_value(js) <= 0xFF))) {
        *index = (uint16_t)json_integer_value(o);
        *sub = js != NULL ? (uint8_t)json_integer_value(js) : 0U;
        (void)snprintf(text, size, "0x%04X:%02X", *index, *sub);
        return true;
    }
    fail(q->s, q->id, "%s: \"object\" must be \"INDEX[:SUB]\" in hex (\"0x6401:01\") or an index number with an "
                      "optional \"sub\"", q->cmd);
    return false;
}

/* ---- Commands ---------------------------------------------------------------------------------------------- */

static json_t *node_summary(const emu_t *emu, const emu_node_t *n)
{
    json_t *o = json_object();
    (void)json_object_set_new(o, "node", json_integer(co_node_id(&n->dev.node)));
    (void)json_object_set_new(o, "device", json_string(n->dev.cls->name));
    (void)json_object_set_new(o, "variant", n->dev.cls->variants != NULL ? json_string(n->dev.cls->variants[n->dev.variant])
                                                                          : json_null());
    (void)json_object_set_new(o, "started_as", json_integer(n->cmdline_id));
    (void)json_object_set_new(o, "state", json_string(co_nmt_state_name(co_node_state(&n->dev.node))));
    (void)json_object_set_new(o, "bus", json_string(n->bus != NULL ? n->bus->can.name : ""));
    /* The kind beside the name: "vcan0" or "plant" alone does not say whether a python-can master reaches it */
    (void)json_object_set_new(o, "bus_kind", json_string(n->bus != NULL ? can_channel_kind_name(n->bus->can.kind) : ""));
    (void)emu;
    return o;
}

static void cmd_hello(const request_t *q)
{
    /* "token": the first request of a connection that needs one (emu_session_lines.c checks it); taken and
     * ignored elsewhere, so that a client may always send it. */
    static const char *const fields[] = {"token", NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    const json_t *token = json_object_get(q->req, "token");
    if (token != NULL && !json_is_string(token)) {
        fail(q->s, q->id, "hello: \"token\" must be a string");
        return;
    }
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "program", json_string("canopen-emu"));
    (void)json_object_set_new(r, "version", json_string(EMU_VERSION));
    (void)json_object_set_new(r, "protocol", json_integer(CONTROL_PROTOCOL_VERSION));
    json_t *kinds = json_array();
    for (int k = 0; k < (int)EVENT_KIND_COUNT; k++) {
        (void)json_array_append_new(kinds, json_string(event_kind_name((event_kind_t)k)));
    }
    (void)json_object_set_new(r, "events", kinds);
    json_t *buses = json_array();
    for (size_t i = 0U; i < q->emu->n_buses; i++) {
        (void)json_array_append_new(buses, json_string(q->emu->buses[i]->can.name));
    }
    (void)json_object_set_new(r, "buses", buses);
    /* Added to version 1 beside "buses" (which stays a list of names for the clients that read it): each bus's kind
     * by its name, python-can's interface name ("socketcan", "udp_multicast", "virtual"). */
    json_t *bus_kinds = json_object();
    for (size_t i = 0U; i < q->emu->n_buses; i++) {
        const can_channel_t *c = &q->emu->buses[i]->can;
        (void)json_object_set_new(bus_kinds, c->name, json_string(can_channel_kind_name(c->kind)));
    }
    (void)json_object_set_new(r, "bus_kinds", bus_kinds);
    /* The events' clock (µs since the start) and the wall clock read together: a client turns time_us into dates
     * (a candump log's time stamps) without a second request. */
    struct timespec wall;
    (void)clock_gettime(CLOCK_REALTIME, &wall);
    const co_time_us_t now = socketcan_now_us();
    json_t *clock = json_object();
    (void)json_object_set_new(clock, "time_us",
                              json_integer((json_int_t)emu_since_start(q->emu, now)));
    (void)json_object_set_new(clock, "unix_us",
                              json_integer((json_int_t)wall.tv_sec * 1000000 + (json_int_t)(wall.tv_nsec / 1000)));
    (void)json_object_set_new(r, "clock", clock);
    send_response(q->s, r);
}

static void cmd_list(const request_t *q)
{
    static const char *const fields[] = {NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    json_t *nodes = json_array();
    for (size_t i = 0U; i < q->emu->n_nodes; i++) {
        (void)json_array_append_new(nodes, node_summary(q->emu, q->emu->nodes[i]));
    }
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "nodes", nodes);
    send_response(q->s, r);
}

/* What a view of the network shows of a node beside its state: device type, heartbeat period and the time of its
 * last heartbeat, the protocol faults in force, the last EMCY (times on the events' clock). */
static void show_overview(const emu_t *emu, emu_node_t *n, json_t *o)
{
    co_node_t *node = &n->dev.node;
    (void)json_object_set_new(o, "device_type", json_integer(co_od_get_u32(node, 0x1000U, 0U)));
    (void)json_object_set_new(o, "heartbeat_ms", json_integer(co_od_get_u16(node, 0x1017U, 0U)));
    (void)json_object_set_new(o, "last_heartbeat_us", n->last_heartbeat > emu->start
                                                          ? json_integer((json_int_t)(n->last_heartbeat - emu->start))
                                                          : json_null());
    json_t *faults = json_array();
    for (unsigned k = 0U; k < (unsigned)FAULT_KIND_COUNT; k++) {
        if ((n->faults.active & (1UL << k)) != 0U) {
            (void)json_array_append_new(faults, json_string(fault_kind_name((fault_kind_t)k)));
        }
    }
    (void)json_object_set_new(o, "faults", faults);
    json_t *emcy = json_null();
    if (n->last_emcy.at != 0U) {
        emcy = json_object();
        (void)json_object_set_new(emcy, "code", json_integer(n->last_emcy.code));
        (void)json_object_set_new(emcy, "register", json_integer(n->last_emcy.reg));
        (void)json_object_set_new(emcy, "info", hex_string(n->last_emcy.info, sizeof n->last_emcy.info));
        (void)json_object_set_new(emcy, "time_us", json_integer((json_int_t)emu_since_start(emu, n->last_emcy.at)));
    }
    (void)json_object_set_new(o, "last_emcy", emcy);
}

/* The nodes heard on the buses named by `word` ("all", "all@BUS") that this program does not emulate there: what
 * the overview shows of the rest of the network. NULL for any other word (one node, a list). */
static json_t *heard_nodes(const emu_t *emu, const char *word)
{
    const char *bus_name = strncmp(word, "all@", 4U) == 0 ? word + 4 : NULL;
    if (bus_name == NULL && strcmp(word, "all") != 0) {
        return NULL;
    }
    json_t *list = json_array();
    for (size_t k = 0U; k < emu->n_buses; k++) {
        const emu_bus_t *b = emu->buses[k];
        if (bus_name != NULL && strcmp(bus_name, b->can.name) != 0) {
            continue;
        }
        bool ours[128] = {false};
        for (size_t i = 0U; i < b->n_nodes; i++) {
            ours[b->nodes[i]->dev.node.node_id & 0x7FU] = true;
        }
        for (unsigned id = 1U; id < 128U; id++) {
            const heard_node_t *h = &b->heard[id];
            if (h->at == 0U || ours[id]) {
                continue;
            }
            json_t *o = json_object();
            (void)json_object_set_new(o, "node", json_integer(id));
            (void)json_object_set_new(o, "bus", json_string(b->can.name));
            (void)json_object_set_new(o, "bus_kind", json_string(can_channel_kind_name(b->can.kind)));
            /* a boot-up (0x00) means it is now PRE-OPERATIONAL */
            (void)json_object_set_new(o, "state", json_string(h->state == 0U ? "PRE-OPERATIONAL"
                                                                             : co_nmt_state_name((co_nmt_state_t)h->state)));
            (void)json_object_set_new(o, "boot_up", json_boolean(h->state == 0U));
            (void)json_object_set_new(o, "last_heartbeat_us",
                                      json_integer((json_int_t)emu_since_start(emu, h->at)));
            (void)json_array_append_new(list, o);
        }
    }
    return list;
}

static void cmd_show(const request_t *q)
{
    static const char *const fields[] = {"node", NULL};
    char word[64];
    if (!only_fields(q, fields) || !node_word(q, word, sizeof word, true)) {
        return;
    }
    json_t *heard = heard_nodes(q->emu, word); /* before select_nodes, which may change the word */
    emu_node_t *sel[MAX_NODES_ALL];
    capture_t c;
    const int n = select_captured(q->emu, word, sel, MAX_NODES_ALL, &c);
    if (n <= 0) {
        json_decref(heard);
        fail(q->s, q->id, "%s", n < 0 ? c.error : "no such node");
        return;
    }
    json_t *nodes = json_array();
    for (int i = 0; i < n; i++) {
        const co_node_t *node = &sel[i]->dev.node;
        json_t *o = node_summary(q->emu, sel[i]);
        (void)json_object_set_new(o, "error_register", json_integer(co_od_get_u8(&sel[i]->dev.node, 0x1001U, 0U)));
        json_t *errors = json_array();
        for (uint8_t k = 0U; k < node->emcy.n_active; k++) {
            const co_emcy_error_t *er = &node->emcy.active[k];
            json_t *e = json_object();
            (void)json_object_set_new(e, "code", json_integer(er->code));
            (void)json_object_set_new(e, "register", json_integer(er->reg));
            (void)json_object_set_new(e, "info", hex_string(er->msef, sizeof er->msef));
            (void)json_array_append_new(errors, e);
        }
        (void)json_object_set_new(o, "errors", errors);
        show_overview(q->emu, sel[i], o);
        (void)json_object_set_new(o, "tx_frames", json_integer((json_int_t)node->stats.tx_frames));
        (void)json_object_set_new(o, "rx_frames", json_integer((json_int_t)node->stats.rx_frames));
        (void)json_object_set_new(o, "tx_dropped", json_integer((json_int_t)node->stats.tx_dropped));
        (void)json_array_append_new(nodes, o);
    }
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "nodes", nodes);
    if (heard != NULL) {
        (void)json_object_set_new(r, "heard", heard);
    }
    /* The events' clock now: a view tells how long ago the times above were without an event to compare with. */
    const co_time_us_t now = socketcan_now_us();
    (void)json_object_set_new(r, "time_us", json_integer((json_int_t)emu_since_start(q->emu, now)));
    send_response(q->s, r);
}

/* Any other command of the language: "args" are its words after NODE; the reply lines come back as "lines". */
/* The device commands of one node's help, as a list a page can make controls of: each "  USAGE  TEXT" line of the
 * reply as {usage, text} (the usage ends at the first two blanks in a row). NULL unless the lines are one node's. */
static json_t *command_list(const json_t *lines)
{
    size_t headers = 0U;
    json_t *list = json_array();
    for (size_t i = 0U; i < json_array_size(lines); i++) {
        const char *line = json_string_value(json_array_get(lines, i));
        if (line == NULL) {
            continue;
        }
        if (strncmp(line, "node ", 5U) == 0) {
            headers++; /* "node 16 (sds) commands:" */
            continue;
        }
        if (strncmp(line, "  ", 2U) != 0 || line[2] == ' ' || line[2] == '(' || line[2] == '\0') {
            continue; /* "  (only the common ones)" or a continuation */
        }
        const char *usage = line + 2;
        const char *gap = strstr(usage, "  ");
        const size_t usage_len = gap != NULL ? (size_t)(gap - usage) : strlen(usage);
        const char *text = gap != NULL ? gap + strspn(gap, " ") : "";
        json_t *c = json_object();
        (void)json_object_set_new(c, "usage", json_stringn(usage, usage_len));
        (void)json_object_set_new(c, "text", jstr(text));
        (void)json_array_append_new(list, c);
    }
    if (headers != 1U) {
        json_decref(list);
        return NULL;
    }
    return list;
}

static void cmd_words(const request_t *q)
{
    static const char *const fields[] = {"node", "args", NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    char words[MAX_ARGS][128];
    char *argv[MAX_ARGS];
    int argc = 0;
    (void)snprintf(words[argc], sizeof words[argc], "%s", q->cmd);
    argv[argc] = words[argc];
    argc++;
    if (node_word(q, words[argc], sizeof words[argc], false)) {
        argv[argc] = words[argc];
        argc++;
    } else if (json_object_get(q->req, "node") != NULL) {
        return; /* a bad node: answered */
    }
    json_t *args = json_object_get(q->req, "args");
    if (args != NULL && !json_is_array(args)) {
        fail(q->s, q->id, "%s: \"args\" must be an array of strings and numbers", q->cmd);
        return;
    }
    size_t i;
    json_t *a;
    json_array_foreach(args, i, a) {
        if (argc == MAX_ARGS) {
            fail(q->s, q->id, "%s: too many words (at most %d)", q->cmd, MAX_ARGS);
            return;
        }
        if (json_is_integer(a)) {
            (void)snprintf(words[argc], sizeof words[argc], "%" JSON_INTEGER_FORMAT, json_integer_value(a));
        } else if (json_is_real(a)) {
            (void)snprintf(words[argc], sizeof words[argc], "%.9g", json_real_value(a));
        } else if (json_is_string(a) && json_string_length(a) < sizeof words[argc] && json_string_length(a) > 0U &&
                   strlen(json_string_value(a)) == json_string_length(a) && strpbrk(json_string_value(a), " \t\r\n") == NULL) {
            (void)snprintf(words[argc], sizeof words[argc], "%s", json_string_value(a));
        } else {
            fail(q->s, q->id, "%s: argument %zu must be a number or a word (no blanks, 1..127 bytes)", q->cmd, i + 1U);
            return;
        }
        argv[argc] = words[argc];
        argc++;
    }
    capture_t c;
    const command_result_t res = run_captured(q->emu, argc, argv, &c);
    json_t *r = response(q->id, res == COMMAND_OK);
    if (res != COMMAND_OK) {
        /* The reason: the first "error:" line, else the last line the command said ("emcy-clear 0x3210: not active"). */
        const size_t n = json_array_size(c.lines);
        const char *last = n > 0U ? json_string_value(json_array_get(c.lines, n - 1U)) : NULL;
        if (c.error[0] == '\0' && last != NULL) {
            const char *colon = strncmp(last, "node ", 5) == 0 ? strstr(last, ": ") : NULL;
            (void)snprintf(c.error, sizeof c.error, "%s", colon != NULL ? colon + 2 : last);
        }
        (void)json_object_set_new(r, "error", jstr(c.error[0] != '\0' ? c.error : "refused"));
    }
    json_t *commands = res == COMMAND_OK && strcmp(q->cmd, "help") == 0 ? command_list(c.lines) : NULL;
    if (commands != NULL) {
        (void)json_object_set_new(r, "commands", commands);
    }
    (void)json_object_set_new(r, "lines", c.lines);
    send_response(q->s, r);
}

bool json_parse_frame_filter(const char *text, uint32_t *id, uint32_t *mask)
{
    char buf[64];
    if (strlen(text) >= sizeof buf) {
        return false;
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    char *slash = strchr(buf, '/');
    long long v, m = 0x1FFFFFFF;
    if (slash != NULL) {
        *slash = '\0';
        if (!device_parse_int(slash + 1, 0, 0x1FFFFFFF, &m)) {
            return false;
        }
    }
    /* The frame format is part of the identity, as candump writes it and a SocketCAN filter with CAN_EFF_FLAG in
     * its mask tells it: an extended frame 0x181 is not TPDO1 of node 1, so a filter takes one format only, 29-bit
     * frames when its COB-ID ends in x. A bare "0x" is a hex prefix without digits, refused, not COB-ID 0 marked. */
    const size_t len = strlen(buf);
    const bool eff = len > 1U && (buf[len - 1U] == 'x' || buf[len - 1U] == 'X') && !(len == 2U && buf[0] == '0');
    if (eff) {
        buf[len - 1U] = '\0';
    }
    if (!device_parse_int(buf, 0, eff ? 0x1FFFFFFF : 0x7FF, &v)) {
        return false; /* an 11-bit COB-ID above 0x7FF is a mistake, not a 29-bit filter by accident */
    }
    *mask = (uint32_t)m | SESSION_FRAME_EFF;
    *id = ((uint32_t)v | (eff ? SESSION_FRAME_EFF : 0U)) & *mask;
    return true;
}

static bool event_mask(const request_t *q, json_t *events, uint32_t *mask)
{
    *mask = 0U;
    if (json_is_string(events) && strcmp(json_string_value(events), "all") == 0) {
        *mask = (((uint32_t)1U << EVENT_KIND_COUNT) - 1U) & ~((uint32_t)1U << EVENT_FRAME); /* frames need their own filter */
        return true;
    }
    if (!json_is_array(events) || json_array_size(events) == 0U) {
        fail(q->s, q->id, "%s: \"events\" must be \"all\" or a non-empty array of event kinds", q->cmd);
        return false;
    }
    size_t i;
    json_t *k;
    json_array_foreach(events, i, k) {
        const int kind = json_is_string(k) ? event_kind_of(json_string_value(k)) : -1;
        if (kind < 0) {
            fail(q->s, q->id, "%s: unknown event kind %s", q->cmd, json_is_string(k) ? json_string_value(k) : "(not a string)");
            return false;
        }
        *mask |= (uint32_t)1U << (unsigned)kind;
    }
    return true;
}

/* "frames": one "COB-ID[x][/MASK]" or a list of 1 to SESSION_FRAME_FILTERS of them, into ff (n: how many). */
static bool frame_filters(const json_t *frames, session_frame_filter_t *ff, size_t *n)
{
    if (json_is_string(frames)) {
        *n = 1U;
        return json_parse_frame_filter(json_string_value(frames), &ff[0].id, &ff[0].mask);
    }
    if (!json_is_array(frames) || json_array_size(frames) == 0U || json_array_size(frames) > SESSION_FRAME_FILTERS) {
        return false;
    }
    for (size_t i = 0U; i < json_array_size(frames); i++) {
        const json_t *f = json_array_get(frames, i);
        if (!json_is_string(f) || !json_parse_frame_filter(json_string_value(f), &ff[i].id, &ff[i].mask)) {
            return false;
        }
    }
    *n = json_array_size(frames);
    return true;
}

static void cmd_subscribe(const request_t *q)
{
    static const char *const fields[] = {"events", "nodes", "frames", NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    uint32_t mask;
    if (!event_mask(q, json_object_get(q->req, "events"), &mask)) {
        return;
    }
    emu_session_t *s = q->s;
    json_t *frames = json_object_get(q->req, "frames");
    session_frame_filter_t ff[SESSION_FRAME_FILTERS];
    size_t n_ff = s->n_frames;
    memcpy(ff, s->frames, sizeof ff);
    if ((mask & ((uint32_t)1U << EVENT_FRAME)) != 0U) {
        if (!frame_filters(frames, ff, &n_ff)) {
            fail(q->s, q->id, "subscribe: frame events need \"frames\": \"COB-ID[/MASK]\" (\"COB-IDx[/MASK]\": "
                              "29-bit frames) or a list of at most %d (\"0x700/0x780\": every heartbeat)",
                 SESSION_FRAME_FILTERS);
            return;
        }
    } else if (frames != NULL) {
        fail(q->s, q->id, "subscribe: \"frames\" goes with the event kind \"frame\"");
        return;
    }
    session_node_filter_t filters[SESSION_NODE_FILTERS];
    size_t n_filters = 0U;
    json_t *nodes = json_object_get(q->req, "nodes");
    if (nodes != NULL) {
        if (!json_is_array(nodes) || json_array_size(nodes) > SESSION_NODE_FILTERS) {
            fail(q->s, q->id, "subscribe: \"nodes\" must be an array of at most %d nodes", SESSION_NODE_FILTERS);
            return;
        }
        size_t i;
        json_t *node;
        json_array_foreach(nodes, i, node) {
            char word[64];
            if (json_is_integer(node)) {
                (void)snprintf(word, sizeof word, "%" JSON_INTEGER_FORMAT, json_integer_value(node));
            } else if (json_is_string(node) && json_string_length(node) < sizeof word) {
                (void)snprintf(word, sizeof word, "%s", json_string_value(node));
            } else {
                fail(q->s, q->id, "subscribe: node %zu is not a node-ID or \"ID@IFACE\"", i + 1U);
                return;
            }
            char err[256];
            if (!session_node_filter(q->emu, word, &filters[n_filters], err, sizeof err)) {
                fail(q->s, q->id, "subscribe: %s", err[0] != '\0' ? err : "no such node");
                return;
            }
            n_filters++;
        }
    }
    s->events |= mask;
    s->events_json = true;
    memcpy(s->frames, ff, sizeof ff);
    s->n_frames = n_ff;
    memcpy(s->nodes, filters, sizeof filters[0] * n_filters);
    s->n_nodes = n_filters;
    json_t *r = response(q->id, true);
    json_t *kinds = json_array();
    for (int k = 0; k < (int)EVENT_KIND_COUNT; k++) {
        if ((s->events & ((uint32_t)1U << (unsigned)k)) != 0U) {
            (void)json_array_append_new(kinds, json_string(event_kind_name((event_kind_t)k)));
        }
    }
    (void)json_object_set_new(r, "events", kinds);
    send_response(q->s, r);
}

static void cmd_unsubscribe(const request_t *q)
{
    static const char *const fields[] = {"events", NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    uint32_t mask = 0xFFFFFFFFUL;
    json_t *events = json_object_get(q->req, "events");
    if (events != NULL && !event_mask(q, events, &mask)) {
        return;
    }
    q->s->events &= ~mask;
    send_response(q->s, response(q->id, true));
}

static void cmd_quit(const request_t *q)
{
    static const char *const fields[] = {NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    q->emu->quit = true;
    send_response(q->s, response(q->id, true));
}

void json_run(emu_t *emu, emu_session_t *s, const char *line)
{
    json_error_t err;
    json_t *req = json_loads(line, JSON_REJECT_DUPLICATES, &err);
    if (req == NULL) {
        json_error(s, "malformed JSON at column %d: %s", err.column, err.text);
        return;
    }
    request_t q = {emu, s, req, json_object_get(req, "id"), ""};
    if (q.id != NULL && !json_is_string(q.id) && !json_is_integer(q.id) && !json_is_null(q.id)) {
        json_error(s, "\"id\" must be a string, an integer or null");
    } else if (!json_is_string(json_object_get(req, "cmd"))) {
        fail(s, q.id, "a request needs \"cmd\": a command name (hello, list, show, get, set, subscribe, ...)");
    } else {
        q.cmd = json_string_value(json_object_get(req, "cmd"));
        static const struct {
            const char *name;
            void (*run)(const request_t *q);
        } table[] = {{"hello", cmd_hello}, {"list", cmd_list},           {"show", cmd_show},
                     {"get", cmd_get},     {"set", cmd_set},             {"objects", cmd_objects},             {"subscribe", cmd_subscribe},
                     {"unsubscribe", cmd_unsubscribe}, {"tables", cmd_tables}, {"quit", cmd_quit}, {"exit", cmd_quit}};
        size_t i = 0U;
        while (i < sizeof table / sizeof table[0] && strcmp(table[i].name, q.cmd) != 0) {
            i++;
        }
        const char *refused = s->restricted ? command_restriction(q.cmd) : NULL;
        if (refused != NULL) {
            fail(s, q.id, "%s is refused in a web session: it %s", q.cmd, refused);
        } else if (i < sizeof table / sizeof table[0]) {
            table[i].run(&q);
        } else if (strlen(q.cmd) == 0U || strpbrk(q.cmd, " \t\r\n") != NULL || strlen(q.cmd) >= 64U) {
            fail(s, q.id, "'%s' is not a command", q.cmd);
        } else {
            cmd_words(&q); /* help, emcy, emcy-clear, power-cycle, the devices' commands; unknown ones answered there */
        }
    }
    json_decref(req);
}
