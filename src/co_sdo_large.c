/*
 * Large objects over SDO (CO_CONFIG_LARGE_OBJECTS): a string or DOMAIN whose value the application keeps
 * (co_hooks_t.large_read / large_write) moves by segmented or block transfer in pieces, the SDO buffer holding one
 * piece at a time, so a transfer of any length (a firmware image, a log) costs the core no more memory than an
 * ordinary one. An upload reads the piece each segment carries; a download hands over the buffer whenever the next
 * bytes would not fit, then the rest and END at the end, or ABORT when the transfer ends any other way. The CRC of a
 * block download is taken as the pieces go; that of a block upload by reading the object once more at the end.
 * docs/architecture.md ("Large objects") and docs/decisions.md.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_LARGE_OBJECTS

/* A large object's value in one piece (co_od_read; here, out of the read path every number takes): the abort code
 * (CO_ABORT_LENGTH_HIGH when it exceeds cap) << 32 | its length. */
uint64_t co_od_read_large(co_node_t *node, const co_od_entry_t *e, uint8_t *buf, size_t cap)
{
    uint32_t length = 0U;
    uint32_t r = co_od_large_read(node, e, 0U, buf, 0U, &length);
    if (r == CO_ABORT_NONE && length > cap) {
        r = CO_ABORT_LENGTH_HIGH;
    }
    if (r == CO_ABORT_NONE && length > 0U) {
        r = co_od_large_read(node, e, 0U, buf, length, &length);
    }
    return ((uint64_t)r << 32) | (r == CO_ABORT_NONE ? length : 0U);
}

/* A large object written in one piece (co_od_write; here, out of its write path): BEGIN, DATA, END; a refused DATA
 * is followed by ABORT. */
uint32_t co_od_write_large(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    uint32_t r = co_od_large_write(node, e, CO_LARGE_BEGIN, (uint32_t)len, NULL, 0U);
    if (r != CO_ABORT_NONE) {
        return r;
    }
    if (len > 0U) {
        r = co_od_large_write(node, e, CO_LARGE_DATA, 0U, data, len);
        if (r != CO_ABORT_NONE) {
            (void)co_od_large_write(node, e, CO_LARGE_ABORT, 0U, NULL, 0U);
            return r;
        }
    }
    return co_od_large_write(node, e, CO_LARGE_END, (uint32_t)len, NULL, 0U);
}

/* The transfer's object: a large one is a row of its own (strings and domains are never runs). */
static const co_od_entry_t *object_of(const co_node_t *node, const co_sdo_server_t *s)
{
    return co_od_find_row(node->od, s->index, s->sub);
}

uint32_t co_sdo_large_upload(co_node_t *node, co_sdo_server_t *s, size_t *len)
{
    const co_od_entry_t *e = object_of(node, s);
    if (e == NULL || !co_od_is_large(e)) {
        return CO_ABORT_OUT_OF_MEMORY; /* a value in the values block larger than the SDO buffer */
    }
    uint32_t length = 0U;
    const uint32_t r = co_od_large_read(node, e, 0U, NULL, 0U, &length);
    if (r == CO_ABORT_NONE) {
        s->large = true; /* cleared when the transfer ends (co_sdo_end) */
        *len = length;
    }
    return r;
}

const uint8_t *co_sdo_large_bytes(co_node_t *node, co_sdo_server_t *s, uint32_t offset, size_t n)
{
    uint32_t length = 0U;
    uint32_t r = co_od_large_read(node, object_of(node, s), offset, s->buf, n, &length);
    if (r == CO_ABORT_NONE && (uint64_t)offset + n > length) {
        r = CO_ABORT_NO_DATA; /* the value became shorter during the upload */
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, r);
        return NULL;
    }
    return s->buf;
}

#if CO_CONFIG_SDO_BLOCK
bool co_sdo_large_crc(co_node_t *node, co_sdo_server_t *s, uint16_t *crc)
{
    uint16_t value = 0U;
    for (uint32_t at = 0U; at < s->size; at += CO_SDO_BUF_SIZE) {
        const uint32_t n = s->size - at < CO_SDO_BUF_SIZE ? s->size - at : CO_SDO_BUF_SIZE;
        const uint8_t *piece = co_sdo_large_bytes(node, s, at, n);
        if (piece == NULL) {
            return false;
        }
        value = co_sdo_crc(value, piece, n);
    }
    *crc = value;
    return true;
}
#endif

uint32_t co_sdo_large_begin(co_node_t *node, co_sdo_server_t *s, uint32_t size)
{
    if (!s->large) {
        return CO_ABORT_NONE;
    }
    const uint32_t r = co_od_large_write(node, object_of(node, s), CO_LARGE_BEGIN, size, NULL, 0U);
    if (r != CO_ABORT_NONE) {
        s->large = false; /* refused: nothing to drop */
    }
    return r;
}

/* Hands the buffer's n bytes over (the next piece from s->done on), with the CRC of a block download. */
static uint32_t hand_over(co_node_t *node, co_sdo_server_t *s, uint32_t n)
{
    if (n == 0U) {
        return CO_ABORT_NONE;
    }
#if CO_CONFIG_SDO_BLOCK
    if (s->crc) {
        s->crc_value = co_sdo_crc(s->crc_value, s->buf, n);
    }
#endif
    const uint32_t at = s->done;
    s->done += n;
    return co_od_large_write(node, object_of(node, s), CO_LARGE_DATA, at, s->buf, n);
}

uint32_t co_sdo_large_room(co_node_t *node, co_sdo_server_t *s, uint32_t n)
{
    const uint32_t held = s->pos - s->done;
    if (!s->large || held + n <= CO_SDO_BUF_SIZE) {
        return CO_ABORT_NONE;
    }
    return hand_over(node, s, held);
}

uint32_t co_sdo_large_flush(co_node_t *node, co_sdo_server_t *s, uint32_t len)
{
    return len > s->done ? hand_over(node, s, len - s->done) : CO_ABORT_NONE;
}

uint32_t co_sdo_large_end(co_node_t *node, co_sdo_server_t *s, uint32_t len)
{
    uint32_t r = co_sdo_large_flush(node, s, len);
    if (r != CO_ABORT_NONE) {
        return r; /* co_sdo_abort drops it (still large) */
    }
    s->large = false; /* END decides: accepted or dropped by the application itself */
    return co_od_large_write(node, object_of(node, s), CO_LARGE_END, len, NULL, 0U);
}

void co_sdo_large_drop(co_node_t *node, co_sdo_server_t *s)
{
    s->large = false;
    if (s->state == CO_SDO_SEG_DOWNLOAD || s->state == CO_SDO_BLK_DOWNLOAD || s->state == CO_SDO_BLK_DOWNLOAD_END) {
        (void)co_od_large_write(node, object_of(node, s), CO_LARGE_ABORT, 0U, NULL, 0U);
    }
}

#endif /* CO_CONFIG_LARGE_OBJECTS */
