/*
 * SDO server (CiA 301 §7.2.4): expedited upload/download always; segmented transfer when compiled in
 * (CO_CONFIG_SDO_SEGMENTED) and switched on for the node (CO_OPT_SDO_SEGMENTED); block transfer likewise
 * (CO_CONFIG_SDO_BLOCK, CO_OPT_SDO_BLOCK; co_sdo_block.c), otherwise answered with 0x05040001.
 * Requests: 0x600+node-ID, responses: 0x580+node-ID, DLC 8; each additional server of the OD (0x1201..0x127F)
 * on its own COB-IDs with its own transfer state (co_sdo_server_t). Processing order follows docs/decisions.md
 * (DLC, client abort, NMT state, command, object, access, length, value).
 */
#include "priv/co_priv.h"

enum { SDO_IDLE = CO_SDO_IDLE, SDO_SEG_DOWNLOAD = CO_SDO_SEG_DOWNLOAD, SDO_SEG_UPLOAD = CO_SDO_SEG_UPLOAD };

void co_sdo_respond(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, uint16_t index, uint8_t sub,
                    const uint8_t *data, size_t len)
{
    co_frame_t f = {s->tx_id, 8U, 0U, {0U}};
    f.data[0] = cmd;
    co_put_u16(&f.data[1], index);
    f.data[3] = sub;
    if (data != NULL) {
        memcpy(&f.data[4], data, len);
    }
    co_node_send(node, &f);
}

void co_sdo_abort(co_node_t *node, co_sdo_server_t *s, uint16_t index, uint8_t sub, uint32_t code)
{
    uint8_t d[4];
    co_put_u32(d, code);
    s->state = SDO_IDLE; /* before the frame goes out: the port sees no transfer open behind an abort */
    co_sdo_respond(node, s, 0x80U, index, sub, d, 4U);
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

static void download_expedited(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, uint16_t index, uint8_t sub,
                               const uint8_t *data)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    uint32_t r = e != NULL ? CO_ABORT_NONE : co_od_missing(node->od, index);
    size_t len = 4U;
    if ((cmd & 0x01U) != 0U) {
        len = 4U - ((cmd >> 2) & 0x03U);
    } else if (e != NULL) {
        /* Size not indicated (0x22): the object's own size, as the Eltex masters rely on (decisions.md). */
        const uint16_t size = co_od_type_size(e->type);
        len = size != 0U ? size : (e->size < 4U ? e->size : 4U);
        if (len > 4U) {
            co_sdo_abort(node, s, index, sub, CO_ABORT_LENGTH_HIGH);
            return;
        }
    }
    if (r == CO_ABORT_NONE) {
        r = co_od_write_entry(node, e, data, len, CO_ORIGIN_SDO);
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, index, sub, r);
        return;
    }
    co_sdo_respond(node, s, 0x60U, index, sub, NULL, 0U);
}

/* Reads the object into the transfer buffer. False (and the abort sent) when it cannot be read. */
bool co_sdo_read_object(co_node_t *node, co_sdo_server_t *s, uint16_t index, uint8_t sub, size_t *len)
{
    *len = 0U;
    const uint32_t r = co_od_read(node, index, sub, s->buf, sizeof s->buf, len, CO_ORIGIN_SDO);
    if (r == CO_ABORT_LENGTH_HIGH) { /* larger than any transfer buffer */
        const bool large_transfers = segmented_enabled(node) || (node->options & CO_OPT_SDO_BLOCK) != 0U;
        co_sdo_abort(node, s, index, sub, large_transfers ? CO_ABORT_OUT_OF_MEMORY : CO_ABORT_UNSUPPORTED_ACCESS);
        return false;
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, index, sub, r);
        return false;
    }
    return true;
}

/* The answer to an upload initiate for len bytes read into the buffer: expedited, or the start of a segmented
 * upload. Also the protocol switch of a block upload initiate (CiA 301 §7.2.4.3.13). */
void co_sdo_upload_answer(co_node_t *node, co_sdo_server_t *s, uint16_t index, uint8_t sub, size_t len)
{
    const uint8_t *buf = s->buf;
    if (len >= 1U && len <= 4U) {
        co_sdo_respond(node, s, (uint8_t)(0x43U | ((4U - len) << 2)), index, sub, buf, len);
        return;
    }
    if (!segmented_enabled(node)) {
        if (len == 0U) { /* an empty string: one NUL byte is the shortest expedited answer */
            const uint8_t nul = 0U;
            co_sdo_respond(node, s, 0x4FU, index, sub, &nul, 1U);
            return;
        }
        co_sdo_abort(node, s, index, sub, CO_ABORT_UNSUPPORTED_ACCESS); /* > 4 bytes need segmented transfer */
        return;
    }
    uint8_t size[4];
    co_put_u32(size, (uint32_t)len);
    co_sdo_respond(node, s, 0x41U, index, sub, size, 4U);
    s->state = SDO_SEG_UPLOAD;
    s->index = index;
    s->sub = sub;
    s->size = (uint32_t)len;
    s->pos = 0U;
    s->toggle = 0U;
    s->deadline = co_time_after(node->now, CO_SDO_TIMEOUT_US);
}

/* The checks of a segmented or block download initiate before the transfer (the object's existence, access and
 * the size indicated, if sized), also where the transfer type is off: they come first, so a missing object answers
 * 0x06020000 rather than 0x06010000 (docs/decisions.md). staged: the transfer goes through the SDO buffer, which
 * the object must fit (0x05040005). 0 or the abort code. */
uint32_t co_sdo_download_checks(const co_node_t *node, uint16_t index, uint8_t sub, bool sized, uint32_t size,
                                bool staged)
{
    const co_od_entry_t *e = co_od_find_row(node->od, index, sub); /* flags and size are the sub-index's */
    if (e == NULL) {
        return co_od_has_index(node->od, index) ? CO_ABORT_NO_SUBINDEX : CO_ABORT_NO_OBJECT;
    }
    if ((e->flags & CO_OD_WRITE) == 0U || (e->flags & CO_OD_CONST) != 0U) {
        return (e->flags & CO_OD_READ) != 0U ? CO_ABORT_READ_ONLY : CO_ABORT_UNSUPPORTED_ACCESS;
    }
    if (sized && size > e->size) {
        return CO_ABORT_LENGTH_HIGH;
    }
    return (staged && e->size > CO_SDO_BUF_SIZE) ? CO_ABORT_OUT_OF_MEMORY : CO_ABORT_NONE;
}

#if CO_CONFIG_SDO_SEGMENTED
/* After co_sdo_download_checks passed (staged). */
static void download_initiate_segmented(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, uint16_t index, uint8_t sub,
                                        const uint8_t *data)
{
    const uint32_t size = (cmd & 0x01U) != 0U ? co_get_u32(data) : 0U;
    s->state = SDO_SEG_DOWNLOAD;
    s->index = index;
    s->sub = sub;
    s->size = size;
    s->pos = 0U;
    s->toggle = 0U;
    s->deadline = co_time_after(node->now, CO_SDO_TIMEOUT_US);
    co_sdo_respond(node, s, 0x60U, index, sub, NULL, 0U);
}

static void download_segment(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *seg)
{
    const uint8_t toggle = (uint8_t)((cmd >> 4) & 1U);
    if (toggle != s->toggle) {
        co_sdo_abort(node, s, s->index, s->sub, CO_ABORT_TOGGLE);
        return;
    }
    const uint32_t n = 7U - ((cmd >> 1) & 0x07U);
    if (s->pos + n > sizeof s->buf) {
        co_sdo_abort(node, s, s->index, s->sub, CO_ABORT_LENGTH_HIGH);
        return;
    }
    memcpy(&s->buf[s->pos], seg, (size_t)n);
    s->pos += n;
    s->toggle ^= 1U;
    s->deadline = co_time_after(node->now, CO_SDO_TIMEOUT_US);
    if ((cmd & 0x01U) == 0U) {
        co_sdo_respond(node, s, (uint8_t)(0x20U | ((uint32_t)toggle << 4)), 0U, 0U, NULL, 0U);
        return;
    }
    if (s->size != 0U && s->pos != s->size) {
        co_sdo_abort(node, s, s->index, s->sub, s->pos > s->size ? CO_ABORT_LENGTH_HIGH : CO_ABORT_LENGTH_LOW);
        return;
    }
    const uint32_t r = co_od_write(node, s->index, s->sub, s->buf, (size_t)s->pos, CO_ORIGIN_SDO);
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, s->index, s->sub, r);
        return;
    }
    s->state = SDO_IDLE;
    co_sdo_respond(node, s, (uint8_t)(0x20U | ((uint32_t)toggle << 4)), 0U, 0U, NULL, 0U);
}

static void upload_segment(co_node_t *node, co_sdo_server_t *s, uint8_t cmd)
{
    const uint8_t toggle = (uint8_t)((cmd >> 4) & 1U);
    if (toggle != s->toggle) {
        co_sdo_abort(node, s, s->index, s->sub, CO_ABORT_TOGGLE);
        return;
    }
    const uint32_t left = s->size - s->pos;
    const uint32_t n = left < 7U ? left : 7U;
    const bool last = s->pos + n >= s->size;
    co_frame_t f = {s->tx_id, 8U, 0U, {0U}};
    f.data[0] = (uint8_t)(((uint32_t)toggle << 4) | ((7U - n) << 1) | (last ? 1U : 0U));
    memcpy(&f.data[1], &s->buf[s->pos], (size_t)n);
    co_node_send(node, &f);
    s->pos += n;
    s->toggle ^= 1U;
    s->deadline = co_time_after(node->now, CO_SDO_TIMEOUT_US);
    if (last) {
        s->state = SDO_IDLE;
    }
}
#endif /* CO_CONFIG_SDO_SEGMENTED */

void co_sdo_rx(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f)
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
        s->state = SDO_IDLE; /* client abort: no answer */
        return;
    }
#if CO_CONFIG_SDO_BLOCK
    if (s->state > SDO_SEG_UPLOAD && co_sdo_block_rx(node, s, f)) {
        return;
    }
#endif
#if CO_CONFIG_SDO_SEGMENTED
    if (s->state == SDO_SEG_DOWNLOAD && (cmd & 0xE0U) == 0x00U) {
        download_segment(node, s, cmd, &f->data[1]);
        return;
    }
    if (s->state == SDO_SEG_UPLOAD && (cmd & 0xEFU) == 0x60U) {
        upload_segment(node, s, cmd);
        return;
    }
#endif
    s->state = SDO_IDLE; /* a new initiate (or garbage) ends any transfer in progress */
    if ((cmd & 0xF0U) == 0x20U) {
        if ((cmd & 0x02U) != 0U) {
            download_expedited(node, s, cmd, index, sub, &f->data[4]);
            return;
        }
        const uint32_t r = co_sdo_download_checks(node, index, sub, (cmd & 0x01U) != 0U, co_get_u32(&f->data[4]),
                                                  segmented_enabled(node));
        if (r != CO_ABORT_NONE || !segmented_enabled(node)) {
            co_sdo_abort(node, s, index, sub, r != CO_ABORT_NONE ? r : CO_ABORT_UNSUPPORTED_ACCESS);
        } else {
#if CO_CONFIG_SDO_SEGMENTED
            download_initiate_segmented(node, s, cmd, index, sub, &f->data[4]);
#endif
        }
        return;
    }
    if (cmd == 0x40U) {
        size_t len;
        if (co_sdo_read_object(node, s, index, sub, &len)) {
            co_sdo_upload_answer(node, s, index, sub, len);
        }
        return;
    }
    const uint8_t ccs = (uint8_t)(cmd >> 5);
    /* Initiates of block upload (ccs 5) and block download (ccs 6): sub-command 0 in the low bits. */
    const bool block_initiate = (ccs == 5U && (cmd & 0x03U) == 0U) || (ccs == 6U && (cmd & 0x01U) == 0U);
#if CO_CONFIG_SDO_BLOCK
    if (block_initiate && (node->options & CO_OPT_SDO_BLOCK) != 0U) {
        co_sdo_block_initiate(node, s, cmd, index, sub, &f->data[4]);
        return;
    }
#endif
    if (ccs == 0U || ccs == 3U || ((ccs == 5U || ccs == 6U) && !block_initiate)) {
        /* A segment, or a block sub-command, with no transfer open: its bytes 1..3 are no multiplexer to echo. */
        co_sdo_abort(node, s, 0U, 0U, CO_ABORT_COMMAND);
        return;
    }
    co_sdo_abort(node, s, index, sub, CO_ABORT_COMMAND); /* block transfer switched off, unknown commands */
}

static co_time_us_t server_process(co_node_t *node, co_sdo_server_t *s)
{
    if (s->state == SDO_IDLE) {
        return CO_NEVER;
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        s->state = SDO_IDLE; /* Stopped: the transfer ends silently (SDO says nothing in Stopped) */
        return CO_NEVER;
    }
    if (co_time_reached(node->now, s->deadline)) {
        co_sdo_abort(node, s, s->index, s->sub, CO_ABORT_TIMEOUT);
        return CO_NEVER;
    }
#if CO_CONFIG_SDO_BLOCK
    if (s->state == CO_SDO_BLK_UPLOAD) {
        return co_min_time(s->deadline, co_sdo_block_process(node, s));
    }
#endif
    return s->deadline;
}

co_time_us_t co_sdo_process(co_node_t *node)
{
    co_time_us_t next = server_process(node, &node->sdo);
#if CO_CONFIG_SDO_SERVERS
    for (uint8_t i = 0U; i < node->n_sdo_extra; i++) {
        next = co_min_time(next, server_process(node, &node->sdo_extra[i]));
    }
#endif
    return next;
}

/* ---- Additional SDO servers (0x1201..0x127F) ---------------------------------------------------------------- */

co_status_t co_sdo_count(co_node_t *node, co_sdo_server_t *servers, uint8_t capacity)
{
    uint8_t n = 0U;
    for (uint16_t index = 0x1201U; index <= 0x127FU; index++) {
        if (!co_od_has_index(node->od, index)) {
            continue;
        }
        if (n >= capacity || !CO_CONFIG_SDO_SERVERS) {
            return CO_ERR_RANGE;
        }
        servers[n].param_index = index;
        n++;
    }
    node->sdo_extra = servers;
    node->n_sdo_extra = n;
    return CO_OK;
}

#if CO_CONFIG_SDO_SERVERS

/* The CAN-IDs of an additional server from its parameter object: it takes requests only while both COB-IDs are
 * valid (bit 31 clear). A transfer in progress ends when they change. */
static void load_server(co_node_t *node, co_sdo_server_t *s)
{
    const uint32_t rx = co_od_u32_or(node, s->param_index, 1U, CO_COBID_INVALID);
    const uint32_t tx = co_od_u32_or(node, s->param_index, 2U, CO_COBID_INVALID);
    const bool valid = ((rx | tx) & CO_COBID_INVALID) == 0U;
    s->rx_id = valid ? (uint16_t)(rx & CO_COBID_CAN_ID) : CO_SDO_NO_ID;
    s->tx_id = (uint16_t)(tx & CO_COBID_CAN_ID);
    s->state = SDO_IDLE;
}

/* CiA 301 rules for the COB-IDs of an additional server (sub 1 client to server, sub 2 server to client), as for a
 * PDO (co_cob_id_check; bit 30 "dynamic" is kept as the master wrote it): the COB-ID is in use while its own valid
 * bit is clear. stored: a value being loaded, not a change. */
uint32_t co_sdo_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, bool stored)
{
    if (e->index == 0x1200U || (e->sub != 1U && e->sub != 2U) || e->size != 4U) {
        return CO_ABORT_NONE;
    }
    const uint32_t cur = co_od_entry_u32(node, e);
    return co_cob_id_check(co_get_u32(data), cur, !stored && (cur & CO_COBID_INVALID) == 0U);
}

void co_sdo_written(co_node_t *node, const co_od_entry_t *e)
{
    for (uint8_t i = 0U; i < node->n_sdo_extra; i++) {
        co_sdo_server_t *s = &node->sdo_extra[i];
        if (s->param_index == e->index) {
            const uint16_t was = s->rx_id;
            load_server(node, s);
            if (s->rx_id != was) {
                co_node_routes_update(node); /* the requests it takes come on another COB-ID */
            }
        }
    }
}
#endif /* CO_CONFIG_SDO_SERVERS */

void co_sdo_reset(co_node_t *node)
{
    node->sdo.state = SDO_IDLE;
    node->sdo.param_index = 0x1200U;
    node->sdo.rx_id = (uint16_t)(0x600U + node->node_id);
    node->sdo.tx_id = (uint16_t)(0x580U + node->node_id);
#if CO_CONFIG_SDO_SERVERS
    for (uint8_t i = 0U; i < node->n_sdo_extra; i++) {
        load_server(node, &node->sdo_extra[i]);
    }
#endif
}
