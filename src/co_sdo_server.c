/*
 * SDO server (CiA 301 §7.2.4): expedited upload/download always; segmented transfer when compiled in
 * (CO_CONFIG_SDO_SEGMENTED) and switched on for the node (CO_OPT_SDO_SEGMENTED). Block transfer is not
 * supported and answered with 0x05040001. Requests: 0x600+node-ID, responses: 0x580+node-ID, DLC 8.
 * Processing order follows docs/decisions.md (DLC, client abort, NMT state, command, object, access,
 * length, value).
 */
#include "priv/co_priv.h"

enum { SDO_IDLE = 0, SDO_SEG_DOWNLOAD = 1, SDO_SEG_UPLOAD = 2 };

static void respond(co_node_t *node, uint8_t cmd, uint16_t index, uint8_t sub, const uint8_t *data, size_t len)
{
    co_frame_t f = {0x580U + node->node_id, 8U, 0U, {0U}};
    f.data[0] = cmd;
    co_put_u16(&f.data[1], index);
    f.data[3] = sub;
    if (data != NULL) {
        memcpy(&f.data[4], data, len);
    }
    co_node_send(node, &f);
}

static void sdo_abort(co_node_t *node, uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t d[4];
    co_put_u32(d, code);
    respond(node, 0x80U, index, sub, d, 4U);
    node->sdo.state = SDO_IDLE;
    node->stats.sdo_aborts++;
    co_node_event(node, CO_EV_SDO_ABORT, index, sub, 0U, code);
}

static bool segmented_enabled(const co_node_t *node)
{
#if CO_CONFIG_SDO_SEGMENTED
    return (node->options & CO_OPT_SDO_SEGMENTED) != 0U;
#else
    (void)node;
    return false;
#endif
}

static void download_expedited(co_node_t *node, uint8_t cmd, uint16_t index, uint8_t sub, const uint8_t *data)
{
    size_t len;
    if ((cmd & 0x01U) != 0U) {
        len = 4U - ((cmd >> 2) & 0x03U);
    } else {
        /* Size not indicated (0x22): the object's own size, as the Eltex masters rely on (decisions.md). */
        const co_od_entry_t *e = co_od_find(node->od, index, sub);
        len = 4U;
        if (e != NULL) {
            const uint16_t size = co_od_type_size(e->type);
            len = size != 0U ? size : (e->size < 4U ? e->size : 4U);
        }
        if (len > 4U) {
            sdo_abort(node, index, sub, CO_ABORT_LENGTH_HIGH);
            return;
        }
    }
    const uint32_t r = co_od_write(node, index, sub, data, len, CO_ORIGIN_SDO);
    if (r != CO_ABORT_NONE) {
        sdo_abort(node, index, sub, r);
        return;
    }
    respond(node, 0x60U, index, sub, NULL, 0U);
}

static void upload_initiate(co_node_t *node, uint16_t index, uint8_t sub)
{
    size_t len = 0U;
    uint8_t *buf = node->sdo.buf;
    const uint32_t r = co_od_read(node, index, sub, buf, sizeof node->sdo.buf, &len, CO_ORIGIN_SDO);
    if (r == CO_ABORT_LENGTH_HIGH) { /* larger than any transfer buffer */
        sdo_abort(node, index, sub, segmented_enabled(node) ? CO_ABORT_OUT_OF_MEMORY : CO_ABORT_UNSUPPORTED_ACCESS);
        return;
    }
    if (r != CO_ABORT_NONE) {
        sdo_abort(node, index, sub, r);
        return;
    }
    if (len >= 1U && len <= 4U) {
        respond(node, (uint8_t)(0x43U | ((4U - len) << 2)), index, sub, buf, len);
        return;
    }
    if (!segmented_enabled(node)) {
        if (len == 0U) { /* an empty string: one NUL byte is the shortest expedited answer */
            const uint8_t nul = 0U;
            respond(node, 0x4FU, index, sub, &nul, 1U);
            return;
        }
        sdo_abort(node, index, sub, CO_ABORT_UNSUPPORTED_ACCESS); /* > 4 bytes need segmented transfer */
        return;
    }
    uint8_t size[4];
    co_put_u32(size, (uint32_t)len);
    respond(node, 0x41U, index, sub, size, 4U);
    node->sdo.state = SDO_SEG_UPLOAD;
    node->sdo.index = index;
    node->sdo.sub = sub;
    node->sdo.size = (uint32_t)len;
    node->sdo.pos = 0U;
    node->sdo.toggle = 0U;
    node->sdo.deadline = node->now + CO_SDO_TIMEOUT_US;
}

/* The checks of a segmented download initiate before the transfer (the object's existence, access and the size
 * indicated), also where segmented transfer is off: they come first, so a missing object answers 0x06020000
 * rather than 0x06010000 (docs/decisions.md). 0 or the abort code. */
static uint32_t download_initiate_checks(const co_node_t *node, uint8_t cmd, uint16_t index, uint8_t sub,
                                         const uint8_t *data)
{
    const co_od_entry_t *e = co_od_find(node->od, index, sub);
    if (e == NULL) {
        return co_od_has_index(node->od, index) ? CO_ABORT_NO_SUBINDEX : CO_ABORT_NO_OBJECT;
    }
    if ((e->flags & CO_OD_WRITE) == 0U || (e->flags & CO_OD_CONST) != 0U) {
        return (e->flags & CO_OD_READ) != 0U ? CO_ABORT_READ_ONLY : CO_ABORT_UNSUPPORTED_ACCESS;
    }
    return ((cmd & 0x01U) != 0U && co_get_u32(data) > e->size) ? CO_ABORT_LENGTH_HIGH : CO_ABORT_NONE;
}

#if CO_CONFIG_SDO_SEGMENTED
/* After download_initiate_checks passed. */
static void download_initiate_segmented(co_node_t *node, uint8_t cmd, uint16_t index, uint8_t sub,
                                        const uint8_t *data)
{
    const co_od_entry_t *e = co_od_find(node->od, index, sub);
    const uint32_t size = (cmd & 0x01U) != 0U ? co_get_u32(data) : 0U;
    if (size > sizeof node->sdo.buf || e->size > sizeof node->sdo.buf) {
        sdo_abort(node, index, sub, CO_ABORT_OUT_OF_MEMORY);
        return;
    }
    node->sdo.state = SDO_SEG_DOWNLOAD;
    node->sdo.index = index;
    node->sdo.sub = sub;
    node->sdo.size = size;
    node->sdo.pos = 0U;
    node->sdo.toggle = 0U;
    node->sdo.deadline = node->now + CO_SDO_TIMEOUT_US;
    respond(node, 0x60U, index, sub, NULL, 0U);
}

static void download_segment(co_node_t *node, uint8_t cmd, const uint8_t *seg)
{
    co_sdo_server_t *s = &node->sdo;
    const uint8_t toggle = (uint8_t)((cmd >> 4) & 1U);
    if (toggle != s->toggle) {
        sdo_abort(node, s->index, s->sub, CO_ABORT_TOGGLE);
        return;
    }
    const uint32_t n = 7U - ((cmd >> 1) & 0x07U);
    if (s->pos + n > sizeof s->buf) {
        sdo_abort(node, s->index, s->sub, CO_ABORT_LENGTH_HIGH);
        return;
    }
    memcpy(&s->buf[s->pos], seg, n);
    s->pos += n;
    s->toggle ^= 1U;
    s->deadline = node->now + CO_SDO_TIMEOUT_US;
    if ((cmd & 0x01U) == 0U) {
        respond(node, (uint8_t)(0x20U | ((uint32_t)toggle << 4)), 0U, 0U, NULL, 0U);
        return;
    }
    if (s->size != 0U && s->pos != s->size) {
        sdo_abort(node, s->index, s->sub, s->pos > s->size ? CO_ABORT_LENGTH_HIGH : CO_ABORT_LENGTH_LOW);
        return;
    }
    const uint32_t r = co_od_write(node, s->index, s->sub, s->buf, s->pos, CO_ORIGIN_SDO);
    if (r != CO_ABORT_NONE) {
        sdo_abort(node, s->index, s->sub, r);
        return;
    }
    s->state = SDO_IDLE;
    respond(node, (uint8_t)(0x20U | ((uint32_t)toggle << 4)), 0U, 0U, NULL, 0U);
}

static void upload_segment(co_node_t *node, uint8_t cmd)
{
    co_sdo_server_t *s = &node->sdo;
    const uint8_t toggle = (uint8_t)((cmd >> 4) & 1U);
    if (toggle != s->toggle) {
        sdo_abort(node, s->index, s->sub, CO_ABORT_TOGGLE);
        return;
    }
    const uint32_t left = s->size - s->pos;
    const uint32_t n = left < 7U ? left : 7U;
    const bool last = s->pos + n >= s->size;
    co_frame_t f = {0x580U + node->node_id, 8U, 0U, {0U}};
    f.data[0] = (uint8_t)(((uint32_t)toggle << 4) | ((7U - n) << 1) | (last ? 1U : 0U));
    memcpy(&f.data[1], &s->buf[s->pos], n);
    co_node_send(node, &f);
    s->pos += n;
    s->toggle ^= 1U;
    s->deadline = node->now + CO_SDO_TIMEOUT_US;
    if (last) {
        s->state = SDO_IDLE;
    }
}
#endif /* CO_CONFIG_SDO_SEGMENTED */

void co_sdo_rx(co_node_t *node, const co_frame_t *f)
{
    if (f->len != 8U) {
        return; /* not an SDO frame: ignored */
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        return; /* SDO is silent in Stopped */
    }
    const uint8_t cmd = f->data[0];
    const uint16_t index = co_get_u16(&f->data[1]);
    const uint8_t sub = f->data[3];
    if (cmd == 0x80U) {
        node->sdo.state = SDO_IDLE; /* client abort: no answer */
        return;
    }
#if CO_CONFIG_SDO_SEGMENTED
    if (node->sdo.state == SDO_SEG_DOWNLOAD && (cmd & 0xE0U) == 0x00U) {
        download_segment(node, cmd, &f->data[1]);
        return;
    }
    if (node->sdo.state == SDO_SEG_UPLOAD && (cmd & 0xEFU) == 0x60U) {
        upload_segment(node, cmd);
        return;
    }
#endif
    node->sdo.state = SDO_IDLE; /* a new initiate (or garbage) ends any transfer in progress */
    if ((cmd & 0xF0U) == 0x20U) {
        if ((cmd & 0x02U) != 0U) {
            download_expedited(node, cmd, index, sub, &f->data[4]);
            return;
        }
        const uint32_t r = download_initiate_checks(node, cmd, index, sub, &f->data[4]);
        if (r != CO_ABORT_NONE || !segmented_enabled(node)) {
            sdo_abort(node, index, sub, r != CO_ABORT_NONE ? r : CO_ABORT_UNSUPPORTED_ACCESS);
        } else {
#if CO_CONFIG_SDO_SEGMENTED
            download_initiate_segmented(node, cmd, index, sub, &f->data[4]);
#endif
        }
        return;
    }
    if (cmd == 0x40U) {
        upload_initiate(node, index, sub);
        return;
    }
    const uint8_t ccs = (uint8_t)(cmd >> 5);
    if (ccs == 0U || ccs == 3U) {
        /* A segment with no transfer open: its bytes 1..3 are data, there is no multiplexer to echo. */
        sdo_abort(node, 0U, 0U, CO_ABORT_COMMAND);
        return;
    }
    sdo_abort(node, index, sub, CO_ABORT_COMMAND); /* block transfer, unknown commands */
}

co_time_us_t co_sdo_process(co_node_t *node)
{
    if (node->sdo.state == SDO_IDLE) {
        return CO_NEVER;
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        node->sdo.state = SDO_IDLE; /* Stopped: the transfer ends silently (SDO says nothing in Stopped) */
        return CO_NEVER;
    }
    if (node->now >= node->sdo.deadline) {
        sdo_abort(node, node->sdo.index, node->sdo.sub, CO_ABORT_TIMEOUT);
        return CO_NEVER;
    }
    return node->sdo.deadline;
}

void co_sdo_reset(co_node_t *node) { node->sdo.state = SDO_IDLE; }
