/* python-can's udp_multicast datagrams: see udp_datagram.h. */
#include "udp_datagram.h"

#include <msgpack.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

/* Nesting a datagram may have: python-can's is a flat map (1); a channel could be a list (2). msgpack-c's own limit
 * (32) is reached only by inputs that are malformed anyway. */
#define SHAPE_DEPTH_MAX 8U

static void say(char *why, size_t whylen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void say(char *why, size_t whylen, const char *fmt, ...)
{
    if (why != NULL && whylen > 0U) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(why, whylen, fmt, ap);
        va_end(ap);
    }
}

/* The big-endian length of n bytes at p. */
static uint64_t be(const uint8_t *p, unsigned n)
{
    uint64_t v = 0U;
    for (unsigned i = 0U; i < n; i++) {
        v = (v << 8) | p[i];
    }
    return v;
}

/* Walks the msgpack object at p[*pos..len) without decoding it: false when it is cut short, uses the byte msgpack
 * never uses (0xC1), nests deeper than SHAPE_DEPTH_MAX or has a container that claims more entries than bytes are
 * left (each entry takes one byte at least). Then msgpack-c's allocation for the whole datagram is bounded by its
 * length. Each step consumes a byte, so the walk is linear in len. */
static bool shape_ok(const uint8_t *p, size_t len, size_t *pos, unsigned depth)
{
    if (*pos >= len || depth > SHAPE_DEPTH_MAX) {
        return false;
    }
    const uint8_t b = p[(*pos)++];
    uint64_t skip = 0U;      /* bytes of payload after the header */
    uint64_t entries = 0U;   /* objects that follow (a map's: keys and values) */
    unsigned head = 0U;      /* bytes of the length field */
    if (b <= 0x7FU || b >= 0xE0U || b == 0xC0U || b == 0xC2U || b == 0xC3U) {
        return true; /* fixint, nil, bool */
    } else if (b <= 0x8FU) {
        entries = 2U * (uint64_t)(b & 0x0FU);
    } else if (b <= 0x9FU) {
        entries = b & 0x0FU;
    } else if (b <= 0xBFU) {
        skip = b & 0x1FU;
    } else {
        switch (b) {
        case 0xC4: case 0xD9: head = 1U; break;                       /* bin8, str8 */
        case 0xC5: case 0xDA: head = 2U; break;                       /* bin16, str16 */
        case 0xC6: case 0xDB: head = 4U; break;                       /* bin32, str32 */
        case 0xC7: head = 1U; skip = 1U; break;                       /* ext8: length, then the type */
        case 0xC8: head = 2U; skip = 1U; break;
        case 0xC9: head = 4U; skip = 1U; break;
        case 0xCA: skip = 4U; break;                                  /* float32 */
        case 0xCB: skip = 8U; break;                                  /* float64 */
        case 0xCC: case 0xD0: skip = 1U; break;
        case 0xCD: case 0xD1: skip = 2U; break;
        case 0xCE: case 0xD2: skip = 4U; break;
        case 0xCF: case 0xD3: skip = 8U; break;
        case 0xD4: skip = 2U; break;                                  /* fixext 1..16: type and data */
        case 0xD5: skip = 3U; break;
        case 0xD6: skip = 5U; break;
        case 0xD7: skip = 9U; break;
        case 0xD8: skip = 17U; break;
        case 0xDC: case 0xDE: head = 2U; break;                       /* array16, map16 */
        case 0xDD: case 0xDF: head = 4U; break;                       /* array32, map32 */
        default: return false;                                        /* 0xC1 */
        }
        if (head > 0U) {
            if (len - *pos < head) {
                return false;
            }
            const uint64_t n = be(&p[*pos], head);
            *pos += head;
            if (b == 0xDC || b == 0xDD) {
                entries = n;
            } else if (b == 0xDE || b == 0xDF) {
                entries = 2U * n;
            } else {
                skip += n;
            }
        }
    }
    if (skip > len - *pos || entries > len - *pos) {
        return false;
    }
    *pos += (size_t)skip;
    for (uint64_t i = 0U; i < entries; i++) {
        if (!shape_ok(p, len, pos, depth + 1U)) {
            return false;
        }
    }
    return true;
}

/* The fields of a can.Message, with its constructor's defaults. */
typedef struct message {
    bool extended;            /* can.Message's default: True */
    bool remote, error, fd, brs, esi;
    bool id_negative;
    uint64_t id;
    bool dlc_given, dlc_negative;
    uint64_t dlc;
    const uint8_t *data;
    size_t data_len;
    const msgpack_object *data_object; /* NULL: nil or absent */
} message_t;

static bool key_is(const msgpack_object *k, const char *name)
{
    return k->via.str.size == strlen(name) && memcmp(k->via.str.ptr, name, k->via.str.size) == 0;
}

static bool take_bool(const msgpack_object *v, bool *out)
{
    if (v->type != MSGPACK_OBJECT_BOOLEAN) {
        return false;
    }
    *out = v->via.boolean;
    return true;
}

static bool take_int(const msgpack_object *v, uint64_t *out, bool *negative)
{
    if (v->type == MSGPACK_OBJECT_POSITIVE_INTEGER) {
        *out = v->via.u64;
        *negative = false;
        return true;
    }
    if (v->type == MSGPACK_OBJECT_NEGATIVE_INTEGER) {
        *out = 0U;
        *negative = true;
        return true;
    }
    return false;
}

/* One entry of the map into m; false with why when can.Message would not take it or its type is not the format's. */
static bool take_field(const msgpack_object_kv *kv, message_t *m, char *why, size_t whylen)
{
    const msgpack_object *k = &kv->key;
    const msgpack_object *v = &kv->val;
    if (k->type != MSGPACK_OBJECT_STR) {
        say(why, whylen, "a key is not a string (msgpack type %d)", (int)k->type);
        return false;
    }
    bool ok = true;
    if (key_is(k, "timestamp") || key_is(k, "channel") || key_is(k, "is_rx")) {
        /* python-can replaces the time stamp by the time of arrival; channel and direction say nothing to a node */
    } else if (key_is(k, "arbitration_id")) {
        ok = take_int(v, &m->id, &m->id_negative);
    } else if (key_is(k, "dlc")) {
        m->dlc_given = v->type != MSGPACK_OBJECT_NIL;
        ok = !m->dlc_given || take_int(v, &m->dlc, &m->dlc_negative);
    } else if (key_is(k, "data")) {
        m->data_object = v->type == MSGPACK_OBJECT_NIL ? NULL : v;
    } else if (key_is(k, "is_extended_id")) {
        ok = take_bool(v, &m->extended);
    } else if (key_is(k, "is_remote_frame")) {
        ok = take_bool(v, &m->remote);
    } else if (key_is(k, "is_error_frame")) {
        ok = take_bool(v, &m->error);
    } else if (key_is(k, "is_fd")) {
        ok = take_bool(v, &m->fd);
    } else if (key_is(k, "bitrate_switch")) {
        ok = take_bool(v, &m->brs);
    } else if (key_is(k, "error_state_indicator")) {
        ok = take_bool(v, &m->esi);
    } else {
        say(why, whylen, "unknown key '%.*s'", k->via.str.size > 40U ? 40 : (int)k->via.str.size, k->via.str.ptr);
        return false;
    }
    if (!ok) {
        say(why, whylen, "'%.*s' has the wrong type (msgpack type %d)", (int)k->via.str.size, k->via.str.ptr,
            (int)v->type);
    }
    return ok;
}

/* can.Message(check=True)'s checks, in its order, on the fields as its constructor leaves them. */
static bool message_valid(message_t *m, char *why, size_t whylen)
{
    if (m->remote) {
        m->data_len = 0U; /* the constructor drops a remote frame's data, whatever it is */
    } else if (m->data_object == NULL) {
        m->data_len = 0U;
    } else if (m->data_object->type == MSGPACK_OBJECT_BIN) {
        m->data = (const uint8_t *)m->data_object->via.bin.ptr;
        m->data_len = m->data_object->via.bin.size;
    } else {
        say(why, whylen, "'data' is not a bin (msgpack type %d)", (int)m->data_object->type);
        return false;
    }
    if (!m->dlc_given) {
        m->dlc = m->data_len;
    }
    if (m->remote && (m->error || m->fd)) {
        say(why, whylen, "a remote frame that is also an %s frame", m->error ? "error" : "FD");
        return false;
    }
    if (m->id_negative || m->id >= (m->extended ? 0x20000000U : 0x800U)) {
        say(why, whylen, "identifier out of range for a%s identifier", m->extended ? "n extended" : " standard");
        return false;
    }
    if (m->dlc_negative || m->dlc > (m->fd ? 64U : 8U)) {
        say(why, whylen, "DLC out of range (0..%u)", m->fd ? 64U : 8U);
        return false;
    }
    if (!m->remote && m->dlc != m->data_len) {
        say(why, whylen, "DLC %u but %zu data bytes", (unsigned)m->dlc, m->data_len);
        return false;
    }
    if (!m->fd && (m->brs || m->esi)) {
        say(why, whylen, "bitrate_switch or error_state_indicator on a frame that is not CAN FD");
        return false;
    }
    return true;
}

udp_datagram_kind_t udp_datagram_decode(const uint8_t *data, size_t len, co_frame_t *frame, char *why, size_t whylen)
{
    size_t pos = 0U;
    if (len > UDP_DATAGRAM_MAX) {
        say(why, whylen, "longer than %u bytes", UDP_DATAGRAM_MAX);
        return UDP_DATAGRAM_MALFORMED;
    }
    if (!shape_ok(data, len, &pos, 1U)) {
        say(why, whylen, "not msgpack (cut short, or a container longer than the datagram)");
        return UDP_DATAGRAM_MALFORMED;
    }
    if (pos != len) {
        say(why, whylen, "%zu bytes after the message", len - pos);
        return UDP_DATAGRAM_MALFORMED;
    }
    msgpack_unpacked result;
    msgpack_unpacked_init(&result);
    size_t off = 0U;
    const msgpack_unpack_return ret = msgpack_unpack_next(&result, (const char *)data, len, &off);
    udp_datagram_kind_t kind = UDP_DATAGRAM_MALFORMED;
    message_t m;
    memset(&m, 0, sizeof m);
    m.extended = true;
    if (ret != MSGPACK_UNPACK_SUCCESS || off != len) {
        say(why, whylen, "not msgpack (msgpack-c: %d)", (int)ret);
    } else if (result.data.type != MSGPACK_OBJECT_MAP) {
        say(why, whylen, "not a map (msgpack type %d)", (int)result.data.type);
    } else {
        bool ok = true;
        for (uint32_t i = 0U; ok && i < result.data.via.map.size; i++) {
            ok = take_field(&result.data.via.map.ptr[i], &m, why, whylen);
        }
        if (ok && message_valid(&m, why, whylen)) {
            kind = m.error ? UDP_DATAGRAM_ERROR_FRAME : m.fd ? UDP_DATAGRAM_FD : UDP_DATAGRAM_FRAME;
        }
    }
    if (kind == UDP_DATAGRAM_FRAME) {
        memset(frame, 0, sizeof *frame);
        frame->id = (uint32_t)m.id;
        frame->len = (uint8_t)m.dlc;
        frame->flags = (uint8_t)((m.remote ? CO_FRAME_RTR : 0U) | (m.extended ? CO_FRAME_EFF : 0U));
        if (m.data_len > 0U) {
            memcpy(frame->data, m.data, m.data_len);
        }
    }
    msgpack_unpacked_destroy(&result); /* after the copy: the data pointed into msgpack-c's zone or the datagram */
    return kind;
}

/* msgpack-c's packer writes into a buffer of the caller's: no allocation per frame. */
typedef struct out_buf {
    uint8_t *p;
    size_t cap;
    size_t len;
} out_buf_t;

static int out_write(void *ctx, const char *buf, size_t len)
{
    out_buf_t *o = (out_buf_t *)ctx;
    if (len > o->cap - o->len) {
        return -1;
    }
    memcpy(o->p + o->len, buf, len);
    o->len += len;
    return 0;
}

static int pack_key(msgpack_packer *pk, const char *key)
{
    const size_t n = strlen(key);
    return msgpack_pack_str(pk, n) | msgpack_pack_str_body(pk, key, n);
}

static int pack_bool(msgpack_packer *pk, const char *key, bool v)
{
    return pack_key(pk, key) | (v ? msgpack_pack_true(pk) : msgpack_pack_false(pk));
}

size_t udp_datagram_encode(const co_frame_t *frame, double timestamp, uint8_t *out, size_t cap)
{
    if ((frame->flags & CO_FRAME_ERR) != 0U || frame->len > 8U) {
        return 0U;
    }
    out_buf_t o = {out, cap, 0U};
    msgpack_packer pk;
    msgpack_packer_init(&pk, &o, out_write);
    const bool remote = (frame->flags & CO_FRAME_RTR) != 0U;
    /* python-can's pack_message, key by key; a remote frame has no data (can.Message drops it), its DLC says the
     * length asked for */
    int r = msgpack_pack_map(&pk, 11U);
    r |= pack_key(&pk, "timestamp") | msgpack_pack_double(&pk, timestamp);
    r |= pack_key(&pk, "arbitration_id") | msgpack_pack_uint32(&pk, frame->id);
    r |= pack_bool(&pk, "is_extended_id", (frame->flags & CO_FRAME_EFF) != 0U);
    r |= pack_bool(&pk, "is_remote_frame", remote);
    r |= pack_bool(&pk, "is_error_frame", false);
    r |= pack_key(&pk, "channel") | msgpack_pack_nil(&pk);
    r |= pack_key(&pk, "dlc") | msgpack_pack_uint8(&pk, frame->len);
    r |= pack_key(&pk, "data") | msgpack_pack_bin(&pk, remote ? 0U : frame->len);
    if (!remote && frame->len > 0U) {
        r |= msgpack_pack_bin_body(&pk, frame->data, frame->len);
    }
    r |= pack_bool(&pk, "is_fd", false);
    r |= pack_bool(&pk, "bitrate_switch", false);
    r |= pack_bool(&pk, "error_state_indicator", false);
    return r == 0 ? o.len : 0U;
}
