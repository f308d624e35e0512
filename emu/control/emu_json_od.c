/* The object dictionary commands of the control protocol's JSON framing: get, set and objects (docs/control-protocol.md). */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "runtime/emu.h"
#include "control/emu_json_request.h"
#include "runtime/emu_output.h"

/* The longest string "value" of a set: as a word of the command language once, now what device_set_value writes. */
#define SET_TEXT_MAX 512U

/* ---- Typed values ------------------------------------------------------------------------------------------ */

json_t *hex_string(const uint8_t *b, size_t len)
{
    char text[2U * 256U + 1U];
    for (size_t i = 0U; i < len && i < 256U; i++) {
        (void)snprintf(text + 2U * i, 3U, "%02X", b[i]);
    }
    text[2U * (len < 256U ? len : 256U)] = '\0';
    return json_string(text);
}

/* A REAL32/REAL64 as JSON: a number, or "nan", "inf", "-inf", which JSON lacks. */
static json_t *real_json(double d)
{
    if (isnan(d)) {
        return json_string("nan");
    }
    if (isinf(d)) {
        return json_string(d > 0.0 ? "inf" : "-inf");
    }
    return json_real(d);
}

/* An unsigned integer as JSON: a number, above 2^63-1 a decimal string. */
static json_t *unsigned_json(uint64_t u)
{
    if (u > (uint64_t)LLONG_MAX) {
        char text[24];
        (void)snprintf(text, sizeof text, "%llu", (unsigned long long)u);
        return json_string(text);
    }
    return json_integer((json_int_t)u);
}

/* The value as JSON: integers as numbers (an UNSIGNED64 above 2^63-1 as a decimal string), BOOLEAN as true/false,
 * REAL32 as a number (NaN and infinities, which JSON lacks, as "nan", "inf", "-inf"), VISIBLE_STRING as a string,
 * OCTET_STRING, UNICODE_STRING and DOMAIN as hex. */
/* A VISIBLE_STRING as JSON text (jstr: bytes that are not UTF-8 become '?'). */
static json_t *text_json(const uint8_t *bytes, size_t len)
{
    char text[257];
    const size_t n = len < sizeof text - 1U ? len : sizeof text - 1U;
    memcpy(text, bytes, n);
    text[n] = '\0';
    return jstr(text);
}

static json_t *value_json(const device_value_t *v)
{
    switch (v->kind) {
    case DEVICE_VALUE_BOOLEAN:
        return json_boolean(v->as.b);
    case DEVICE_VALUE_REAL:
        return real_json(v->as.r);
    case DEVICE_VALUE_TEXT:
        return text_json(v->bytes, v->len);
    case DEVICE_VALUE_BYTES:
        return hex_string(v->bytes, v->len);
    case DEVICE_VALUE_SIGNED:
        return json_integer((json_int_t)v->as.i);
    case DEVICE_VALUE_UNSIGNED:
        break;
    }
    return unsigned_json(v->as.u);
}

/* {"node", "object", "value", "type", "name"} of one object of n, or false after a failure response. */
static bool describe_value(const request_t *q, emu_node_t *n, uint16_t index, uint8_t sub, json_t *r)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(n->dev.cls->od, index, sub, &one);
    if (e == NULL) {
        fail(q->s, q->id, "node %u has no object 0x%04X:%02X", co_node_id(&n->dev.node), index, sub);
        return false;
    }
    uint8_t buf[256];
    device_value_t value;
    q->emu->in_command = true;
    const uint32_t abort_code = device_get_value(&n->dev, index, sub, socketcan_now_us(), buf, sizeof buf, &value);
    q->emu->in_command = false;
    node_mark_dirty(n);
    if (abort_code != 0U) {
        fail(q->s, q->id, "0x%04X:%02X: %s (0x%08lX)", index, sub, co_abort_text(abort_code), (unsigned long)abort_code);
        return false;
    }
    char object[16];
    (void)snprintf(object, sizeof object, "0x%04X:%02X", index, sub);
    (void)json_object_set_new(r, "node", json_integer(co_node_id(&n->dev.node)));
    (void)json_object_set_new(r, "object", json_string(object));
    (void)json_object_set_new(r, "value", value_json(&value));
    (void)json_object_set_new(r, "type", json_string(device_type_name(e->type)));
    const char *name = device_object_name(n->dev.cls, e);
    if (name != NULL) {
        (void)json_object_set_new(r, "name", jstr(name));
    }
    const char *unit = device_object_unit(n->dev.cls, e);
    if (unit != NULL) {
        (void)json_object_set_new(r, "unit", jstr(unit));
    }
    return true;
}

/* The response of get and set: the object's value as it is now. */
static void answer_value(const request_t *q, emu_node_t *n, uint16_t index, uint8_t sub)
{
    json_t *r = response(q->id, true);
    if (!describe_value(q, n, index, sub, r)) {
        json_decref(r);
        return;
    }
    send_response(q->s, r);
}

/* Why a value cannot be read, as an SDO upload of it would be answered: "no data available (0x08000024)". */
static json_t *abort_json(uint32_t abort_code)
{
    char text[160];
    (void)snprintf(text, sizeof text, "%s (0x%08lX)", co_abort_text(abort_code), (unsigned long)abort_code);
    return json_string(text);
}

/* get with "objects": the values of up to GET_OBJECTS_MAX objects of one node in one answer (what a view that plots
 * or refreshes several values asks for at every turn), each {object, value, type} or {object, error}, and the time
 * they were read. */
#define GET_OBJECTS_MAX 64U

static void answer_values(const request_t *q, emu_node_t *n, const json_t *list)
{
    if (!json_is_array(list) || json_array_size(list) == 0U || json_array_size(list) > GET_OBJECTS_MAX ||
        json_object_get(q->req, "object") != NULL || json_object_get(q->req, "sub") != NULL) {
        fail(q->s, q->id, "get: \"objects\" must be a list of 1 to %u objects (\"0x6401:01\"), without \"object\"",
             GET_OBJECTS_MAX);
        return;
    }
    uint16_t index[GET_OBJECTS_MAX];
    uint8_t sub[GET_OBJECTS_MAX];
    for (size_t i = 0U; i < json_array_size(list); i++) {
        const json_t *o = json_array_get(list, i);
        if (!json_is_string(o) || strlen(json_string_value(o)) != json_string_length(o) ||
            !device_parse_address(json_string_value(o), &index[i], &sub[i])) {
            fail(q->s, q->id, "get: \"objects\"[%zu] is not \"INDEX[:SUB]\" in hex (\"0x6401:01\")", i);
            return;
        }
    }
    json_t *values = json_array();
    const co_time_us_t now = socketcan_now_us();
    q->emu->in_command = true;
    for (size_t i = 0U; i < json_array_size(list); i++) {
        json_t *v = json_object();
        char object[16];
        (void)snprintf(object, sizeof object, "0x%04X:%02X", index[i], sub[i]);
        (void)json_object_set_new(v, "object", json_string(object));
        uint8_t buf[256];
        device_value_t value;
        const uint32_t abort_code = device_get_value(&n->dev, index[i], sub[i], now, buf, sizeof buf, &value);
        if (abort_code == 0U) {
            (void)json_object_set_new(v, "value", value_json(&value));
            (void)json_object_set_new(v, "type", json_string(device_type_name(value.type)));
        } else {
            (void)json_object_set_new(v, "error", abort_json(abort_code));
        }
        (void)json_array_append_new(values, v);
    }
    q->emu->in_command = false;
    node_mark_dirty(n);
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "node", json_integer(co_node_id(&n->dev.node)));
    (void)json_object_set_new(r, "values", values);
    /* When they were read, on the events' clock: a plot puts the values at their time, whenever the answer comes. */
    (void)json_object_set_new(r, "time_us", json_integer((json_int_t)emu_since_start(q->emu, now)));
    send_response(q->s, r);
}

void cmd_get(const request_t *q)
{
    static const char *const fields[] = {"node", "object", "sub", "objects", NULL};
    uint16_t index;
    uint8_t sub;
    char object[16];
    emu_node_t *n;
    if (!only_fields(q, fields) || (n = one_node(q)) == NULL) {
        return;
    }
    const json_t *list = json_object_get(q->req, "objects");
    if (list != NULL) {
        answer_values(q, n, list);
    } else if (object_address(q, &index, &sub, object, sizeof object)) {
        answer_value(q, n, index, sub);
    }
}

/* "value" as the device takes it (device_set_value): a number, true/false, or a string (a VISIBLE_STRING's text, or a
 * number's word: "0x2A"); false after a failure response. The string stays the request's. */
static bool request_value(const request_t *q, device_value_t *v)
{
    json_t *j = json_object_get(q->req, "value");
    memset(v, 0, sizeof *v);
    if (json_is_integer(j)) {
        v->kind = DEVICE_VALUE_SIGNED;
        v->as.i = (int64_t)json_integer_value(j);
    } else if (json_is_real(j)) {
        v->kind = DEVICE_VALUE_REAL;
        v->as.r = json_real_value(j);
    } else if (json_is_boolean(j)) {
        v->kind = DEVICE_VALUE_BOOLEAN;
        v->as.b = json_is_true(j);
    } else if (json_is_string(j) && strlen(json_string_value(j)) == json_string_length(j) &&
               json_string_length(j) < SET_TEXT_MAX) {
        v->kind = DEVICE_VALUE_TEXT;
        v->bytes = (const uint8_t *)json_string_value(j);
        v->len = json_string_length(j);
    } else {
        fail(q->s, q->id, "set: \"value\" must be a number, true/false or a string (without NUL, under %u bytes)",
             SET_TEXT_MAX);
        return false;
    }
    return true;
}

void cmd_set(const request_t *q)
{
    static const char *const fields[] = {"node", "object", "sub", "value", NULL};
    uint16_t index;
    uint8_t sub;
    char object[16];
    emu_node_t *n;
    device_value_t value;
    if (!only_fields(q, fields) || (n = one_node(q)) == NULL || !object_address(q, &index, &sub, object, sizeof object) ||
        !request_value(q, &value)) {
        return;
    }
    /* Written as the device's `set` writes it (its checks and messages), on the one node. */
    char why[512];
    q->emu->in_command = true;
    const bool written = device_set_value(&n->dev, index, sub, &value, socketcan_now_us(), why, sizeof why);
    q->emu->in_command = false;
    node_mark_dirty(n);
    if (!written) {
        fail(q->s, q->id, "%s", why);
        return;
    }
    answer_value(q, n, index, sub);
}

/* ---- objects: the dictionary of a node ------------------------------------------------------------------------ */

/* The access of a row as its EDS gives it. */
static const char *access_name(unsigned flags)
{
    if ((flags & CO_OD_CONST) != 0U) {
        return "const";
    }
    if ((flags & CO_OD_READ) != 0U) {
        return (flags & CO_OD_WRITE) != 0U ? "rw" : "ro";
    }
    return "wo";
}

/* A limit in the row's type: numbers, an UNSIGNED64 above 2^63-1 as a decimal string (as values). */
static json_t *limit_json(uint8_t type, const co_od_limit_t *l)
{
#if CO_CONFIG_OD_LIMITS_64
    if (type == CO_T_REAL32 || type == CO_T_REAL64) {
        return real_json(l->r);
    }
    if (type == CO_T_UNSIGNED64) {
        return unsigned_json(l->u);
    }
    return json_integer((json_int_t)l->i); /* every other integer type's limits are held in i */
#else
    return device_type_is_signed(type) ? json_integer((json_int_t)l->i) : json_integer((json_int_t)l->u);
#endif
}

/* One row of objects: its address, name, type, access, PDO mapping, storage, unit, limits and (with values) its
 * value or why it cannot be read; NULL when the node does not have it (a variant's hidden row). */
static json_t *object_row(emu_node_t *n, const co_od_entry_t *e, bool values)
{
    uint8_t buf[256];
    device_value_t value;
    const uint32_t abort_code = device_get_value(&n->dev, e->index, e->sub, n->dev.now, buf, sizeof buf, &value);
    if (abort_code == CO_ABORT_NO_SUBINDEX || abort_code == CO_ABORT_NO_OBJECT) {
        return NULL;
    }
    const device_class_t *cls = n->dev.cls;
    json_t *o = json_object();
    char object[16];
    (void)snprintf(object, sizeof object, "0x%04X:%02X", e->index, e->sub);
    (void)json_object_set_new(o, "object", json_string(object));
    const char *name = device_object_name(cls, e);
    (void)json_object_set_new(o, "name", name != NULL ? jstr(name) : json_null());
    const char *title = device_object_title(cls, e->index);
    (void)json_object_set_new(o, "object_name", title != NULL ? jstr(title) : json_null());
    (void)json_object_set_new(o, "type", json_string(device_type_name(e->type)));
    (void)json_object_set_new(o, "access", json_string(access_name(e->flags)));
    (void)json_object_set_new(o, "tpdo", json_boolean((e->flags & CO_OD_TPDO) != 0U));
    (void)json_object_set_new(o, "rpdo", json_boolean((e->flags & CO_OD_RPDO) != 0U));
    (void)json_object_set_new(o, "stored", json_boolean((e->flags & CO_OD_STORE) != 0U));
    const char *unit = device_object_unit(cls, e);
    if (unit != NULL) {
        (void)json_object_set_new(o, "unit", jstr(unit));
    }
    const co_od_limits_t *lim = co_od_entry_limits(cls->od, e);
    if (lim != NULL) {
        (void)json_object_set_new(o, "low", limit_json(e->type, &lim->low));
        (void)json_object_set_new(o, "high", limit_json(e->type, &lim->high));
    }
    if (values) {
        if (abort_code == 0U) {
            (void)json_object_set_new(o, "value", value_json(&value));
        } else {
            (void)json_object_set_new(o, "error", abort_json(abort_code));
        }
    }
    return o;
}

/* Rows of an `objects` answer written per piece of its stream: some 0.1 ms of work and a few KiB, so that the
 * pass's budget (SESSION_PASS_BUDGET_US) is kept and the reader's output grows in small steps. */
#define OBJECTS_ROWS_PER_PIECE 32U

/* Writes the rows of st's node from its place on, at most max of them ("," before each but the first), through
 * emit; false once the last row is written (the answer's "]}" is the caller's). */
static bool objects_rows(emu_t *emu, session_stream_t *st, unsigned max, void (*emit)(void *ctx, const char *, size_t),
                         void *ctx)
{
    emu_node_t *n = (emu_node_t *)st->node;
    const co_od_t *od = n->dev.cls->od;
    n->dev.now = socketcan_now_us(); /* a model's read hook brings the value up to now */
    emu->in_command = true;
    unsigned written = 0U;
    while (st->entry < od->count && written < max) {
        const co_od_entry_t *row = &od->entries[st->entry];
        if (st->sub >= co_od_entry_subs(row)) {
            st->entry++;
            st->sub = 0U;
            continue;
        }
        co_od_entry_t one;
        json_t *o = object_row(n, co_od_entry_at(row, st->sub, &one), st->values);
        st->sub++;
        char *text = o != NULL ? json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII) : NULL;
        json_decref(o);
        if (text != NULL) {
            if (st->count++ > 0U) {
                emit(ctx, ",", 1U);
            }
            emit(ctx, text, strlen(text));
            free(text);
            written++;
        }
    }
    emu->in_command = false;
    node_mark_dirty(n);
    return st->entry < od->count;
}

static void emit_to_stream(void *ctx, const char *text, size_t len) { session_stream_write((emu_session_t *)ctx, text, len); }

/* session_stream_t.step of `objects`: the next rows, then the end of the line. */
static bool objects_step(emu_t *emu, emu_session_t *s)
{
    if (objects_rows(emu, &s->stream, OBJECTS_ROWS_PER_PIECE, emit_to_stream, s)) {
        return true;
    }
    session_stream_write(s, "]}\n", 3U);
    return false;
}

static void emit_to_buffer(void *ctx, const char *text, size_t len)
{
    (void)byte_buffer_append((byte_buffer_t *)ctx, text, len, (size_t)-1); /* out of memory: the line is cut short */
}

/* A large dictionary's answer is megabytes (12,357 entries: some 3 MB with values): it is streamed, written as the
 * client takes it (emu_session_work.c), with the same bytes as one answer built at once. A session that cannot
 * stream (stdin's) gets it at once. */
void cmd_objects(const request_t *q)
{
    static const char *const fields[] = {"node", "values", NULL};
    emu_node_t *n;
    if (!only_fields(q, fields) || (n = one_node(q)) == NULL) {
        return;
    }
    json_t *jv = json_object_get(q->req, "values");
    if (jv != NULL && !json_is_boolean(jv)) {
        fail(q->s, q->id, "objects: \"values\" must be true or false");
        return;
    }
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "node", json_integer(co_node_id(&n->dev.node)));
    char *head = json_dumps(r, JSON_COMPACT | JSON_ENSURE_ASCII); /* {"id":..,"ok":true,"node":N}: the rows go before its '}' */
    json_decref(r);
    if (head == NULL) {
        fail(q->s, q->id, "out of memory");
        return;
    }
    head[strlen(head) - 1U] = '\0';
    static const char objects_key[] = ",\"objects\":[";
    const session_stream_t stream = {.step = objects_step, .node = n, .values = json_is_true(jv)};
    if (session_stream_start(q->s, &stream)) {
        session_stream_write(q->s, head, strlen(head));
        session_stream_write(q->s, objects_key, sizeof objects_key - 1U);
        free(head);
        return;
    }
    byte_buffer_t whole = {NULL, 0U, 0U};
    emit_to_buffer(&whole, head, strlen(head));
    emit_to_buffer(&whole, objects_key, sizeof objects_key - 1U);
    free(head);
    session_stream_t st = stream;
    while (objects_rows(q->emu, &st, UINT_MAX, emit_to_buffer, &whole)) {
    }
    emit_to_buffer(&whole, "]}\n", 3U);
    q->s->write(q->s->ctx, whole.data, whole.len);
    byte_buffer_free(&whole);
}
