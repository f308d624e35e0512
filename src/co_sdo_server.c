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

/* Whether a transfer can stay open after a request: with expedited transfer alone a server is always idle. */
#define SDO_TRANSFERS (CO_CONFIG_SDO_SEGMENTED || CO_CONFIG_SDO_BLOCK)

void co_sdo_send(co_node_t *node, const co_sdo_server_t *s, uint8_t cmd, const uint8_t *data, size_t len)
{
    co_frame_t f = {s->tx_id, 8U, 0U, {cmd, 0U, 0U, 0U, 0U, 0U, 0U, 0U}};
    if (data != NULL) {
        memcpy(&f.data[1], data, len);
    }
    co_node_send(node, &f);
}

/* An expedited upload answers with the buffer's first 4 bytes, read whole (co_sdo_upload_answer), set to 0 before
 * the object is read into it (co_sdo_read_object). */
typedef char sdo_buffer_holds_an_expedited_value[CO_SDO_BUF_SIZE >= 4U ? 1 : -1];

void co_sdo_respond(co_node_t *node, const co_sdo_server_t *s, uint8_t cmd, uint32_t data)
{
    /* the command, then the multiplexer: the index (little-endian) and the sub-index; field by field, not an
     * initialiser, which also zeroes the structure's padding (x86-64, callgrind: 16 instructions, not 19) */
    co_frame_t f;
    f.id = s->tx_id;
    f.len = 8U;
    f.flags = 0U;
    f.data[0] = cmd;
    co_put_u16(&f.data[1], s->index);
    f.data[3] = s->sub;
    co_put_u32(&f.data[4], data);
    co_node_send(node, &f);
}

void co_sdo_abort(co_node_t *node, co_sdo_server_t *s, uint32_t code)
{
    co_sdo_end(node, s); /* before the frame goes out: the port sees no transfer open behind an abort */
    co_sdo_respond(node, s, 0x80U, code);
    node->stats.sdo_aborts++;
    co_node_event(node, CO_EV_SDO_ABORT, s->index, s->sub, 0U, code);
}

void co_sdo_start(co_sdo_server_t *s, uint8_t state, uint32_t size)
{
    s->state = state;
    s->size = size;
    s->pos = 0U;
    s->toggle = 0U; /* the toggle bit of the next segment, in place: bit 4 of its command byte */
    s->seq = 0U;
#if CO_CONFIG_LARGE_OBJECTS
    s->done = 0U;
    s->crc_value = 0U;
#endif
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

static void download_expedited(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *data)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, s->index, s->sub, &one);
    uint32_t r;
    if (e == NULL) {
        r = co_od_missing(node->od, s->index);
    } else {
        size_t len = 4U - ((cmd >> 2) & 0x03U);
        if ((cmd & 0x01U) == 0U) {
            /* Size not indicated (0x22): the object's own size, as the Eltex masters rely on (decisions.md). */
            const uint16_t size = co_od_type_size(e->type);
            len = size != 0U ? size : (e->size < 4U ? e->size : 4U);
        }
        r = len > 4U ? CO_ABORT_LENGTH_HIGH : co_od_write_entry(node, e, data, len, CO_ORIGIN_SDO);
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, r);
        return;
    }
    co_sdo_respond(node, s, 0x60U, 0U);
}

/* Reads the object of the request into the transfer buffer. False (and the abort sent) when it cannot be read.
 * Static, and inline where the compiler optimises for speed: every upload request comes this way, and a layer of
 * call costs it about 15 instructions (co_sdo_read_object() for the block upload). */
static inline bool read_object(co_node_t *node, co_sdo_server_t *s, size_t *len)
{
    *len = 0U;
    co_put_u32(s->buf, 0U); /* an expedited answer sends these 4 bytes: 0 past a shorter value */
    uint32_t r = co_od_read(node, s->index, s->sub, s->buf, sizeof s->buf, len, CO_ORIGIN_SDO);
    if (r == CO_ABORT_LENGTH_HIGH) { /* larger than the transfer buffer: a large object's, or too large */
        const bool large_transfers = segmented_enabled(node) || (node->options & CO_OPT_SDO_BLOCK) != 0U;
        r = large_transfers ? co_sdo_large_upload(node, s, len) : CO_ABORT_UNSUPPORTED_ACCESS;
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, r);
        return false;
    }
    return true;
}

/* The answer to an upload initiate for len bytes read into the buffer: expedited, or the start of a segmented
 * upload. Also the protocol switch of a block upload initiate (CiA 301 §7.2.4.3.13). */
static inline void upload_answer(co_node_t *node, co_sdo_server_t *s, size_t len)
{
    const bool segmented = segmented_enabled(node);
    if (len <= 4U && (len != 0U || !segmented)) {
        /* An empty string without segmented transfer: one NUL byte, the shortest expedited answer (0x4F). */
        const size_t shown = len != 0U ? len : 1U;
        co_sdo_respond(node, s, (uint8_t)(0x43U | ((4U - shown) << 2)), co_get_u32(s->buf)); /* 0 past len */
        return;
    }
    if (!segmented) {
        co_sdo_abort(node, s, CO_ABORT_UNSUPPORTED_ACCESS); /* > 4 bytes need segmented transfer */
        return;
    }
    co_sdo_respond(node, s, 0x41U, (uint32_t)len);
    co_sdo_start(s, SDO_SEG_UPLOAD, (uint32_t)len);
}

#if CO_CONFIG_SDO_BLOCK
bool co_sdo_read_object(co_node_t *node, co_sdo_server_t *s, size_t *len) { return read_object(node, s, len); }
void co_sdo_upload_answer(co_node_t *node, co_sdo_server_t *s, size_t len) { upload_answer(node, s, len); }
#endif

/* The checks of a segmented or block download initiate before the transfer (the object's existence, access and
 * the size indicated, if sized), also where the transfer type is off: they come first, so a missing object answers
 * 0x06020000 rather than 0x06010000 (docs/decisions.md). staged: the transfer goes through the SDO buffer, which
 * the object must fit (0x05040005). 0 or the abort code. */
uint32_t co_sdo_download_checks(const co_node_t *node, co_sdo_server_t *s, bool sized, uint32_t size, bool staged)
{
    const co_od_entry_t *e = co_od_find_row(node->od, s->index, s->sub); /* flags and size are the sub-index's */
    if (e == NULL) {
        return co_od_missing(node->od, s->index);
    }
    if ((e->flags & CO_OD_WRITE) == 0U || (e->flags & CO_OD_CONST) != 0U) {
        return (e->flags & CO_OD_READ) != 0U ? CO_ABORT_READ_ONLY : CO_ABORT_UNSUPPORTED_ACCESS;
    }
#if CO_CONFIG_LARGE_OBJECTS
    s->large = co_od_is_large(e); /* its size the application's to judge (co_sdo_large_begin) */
    if (s->large) {
        return CO_ABORT_NONE;
    }
#endif
    if (sized && size > e->size) {
        return CO_ABORT_LENGTH_HIGH;
    }
    return (staged && e->size > CO_SDO_BUF_SIZE) ? CO_ABORT_OUT_OF_MEMORY : CO_ABORT_NONE;
}

/* The end of a segmented or block download with len bytes in the buffer: against the size indicated (if any), then
 * crc_ok (a block download's CRC), then the write. The transfer is over either way. */
void co_sdo_download_end(co_node_t *node, co_sdo_server_t *s, uint32_t len, bool crc_ok, uint8_t answer)
{
    uint32_t r;
    if (s->size != 0U && len != s->size) {
        r = len > s->size ? CO_ABORT_LENGTH_HIGH : CO_ABORT_LENGTH_LOW;
    } else if (!crc_ok) {
        r = CO_ABORT_CRC;
    } else if (CO_SDO_IS_LARGE(s)) {
#if CO_CONFIG_LARGE_OBJECTS
        r = co_sdo_large_end(node, s, len); /* the rest, then END: the transfer is no longer the application's */
#endif
    } else {
        r = co_od_write(node, s->index, s->sub, s->buf, (size_t)len, CO_ORIGIN_SDO);
    }
    if (r != CO_ABORT_NONE) {
        co_sdo_abort(node, s, r);
        return;
    }
    s->state = SDO_IDLE;
    co_sdo_send(node, s, answer, NULL, 0U);
}

#if CO_CONFIG_SDO_SEGMENTED
/* A segment of the transfer, its toggle bit checked and taken (cmd & 0x10). */
static void download_segment(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *seg)
{
    const uint32_t n = 7U - ((cmd >> 1) & 0x07U);
#if CO_CONFIG_LARGE_OBJECTS
    const uint32_t refused = co_sdo_large_room(node, s, n);
    if (refused != CO_ABORT_NONE) {
        co_sdo_abort(node, s, refused);
        return;
    }
#endif
    const uint32_t held = s->pos - CO_SDO_DONE(s);
    if (held + n > sizeof s->buf) {
        co_sdo_abort(node, s, CO_ABORT_LENGTH_HIGH);
        return;
    }
    memcpy(&s->buf[held], seg, (size_t)n);
    s->pos += n;
    const uint8_t answer = (uint8_t)(0x20U | (cmd & 0x10U));
    if ((cmd & 0x01U) == 0U) {
        co_sdo_send(node, s, answer, NULL, 0U);
        return;
    }
    co_sdo_download_end(node, s, s->pos, true, answer);
}

static void upload_segment(co_node_t *node, co_sdo_server_t *s, uint8_t cmd)
{
    const uint32_t left = s->size - s->pos;
    const uint32_t n = left < 7U ? left : 7U;
    const bool last = left <= 7U;
    const uint8_t answer = (uint8_t)((cmd & 0x10U) | ((7U - n) << 1) | (last ? 1U : 0U));
    const uint8_t *bytes = co_sdo_upload_bytes(node, s, s->pos, (size_t)n);
    if (bytes == NULL) {
        return; /* aborted */
    }
    co_sdo_send(node, s, answer, bytes, (size_t)n);
    s->pos += n;
    if (last) {
        s->state = SDO_IDLE;
    }
}
#endif /* CO_CONFIG_SDO_SEGMENTED */

/* A request: the next frame of the transfer in progress, or a new request, which ends any transfer in progress. */
static void serve(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f)
{
    const uint8_t cmd = f->data[0];
    if (cmd == 0x80U) {
        co_sdo_end(node, s); /* client abort: no answer */
        return;
    }
#if CO_CONFIG_SDO_BLOCK
    if (s->state > SDO_SEG_UPLOAD && co_sdo_block_rx(node, s, f)) {
        return;
    }
#endif
#if CO_CONFIG_SDO_SEGMENTED
    const bool download = s->state == SDO_SEG_DOWNLOAD && (cmd & 0xE0U) == 0x00U;
    if (download || (s->state == SDO_SEG_UPLOAD && (cmd & 0xEFU) == 0x60U)) {
        if ((cmd & 0x10U) != s->toggle) {
            co_sdo_abort(node, s, CO_ABORT_TOGGLE);
            return;
        }
        s->toggle ^= 0x10U;
        if (download) {
            download_segment(node, s, cmd, &f->data[1]);
        } else {
            upload_segment(node, s, cmd);
        }
        return;
    }
#endif
    co_sdo_end(node, s); /* a new initiate (or garbage) ends any transfer in progress */
    s->index = co_get_u16(&f->data[1]);
    s->sub = f->data[3];
    if ((cmd & 0xF0U) == 0x20U) {
        if ((cmd & 0x02U) != 0U) {
            download_expedited(node, s, cmd, &f->data[4]);
            return;
        }
        const bool segmented = segmented_enabled(node);
        const uint32_t size = (cmd & 0x01U) != 0U ? co_get_u32(&f->data[4]) : 0U;
        uint32_t r = co_sdo_download_checks(node, s, (cmd & 0x01U) != 0U, size, segmented);
        if (r == CO_ABORT_NONE && !segmented) {
            r = CO_ABORT_UNSUPPORTED_ACCESS;
        }
        if (r == CO_ABORT_NONE) {
            co_sdo_start(s, SDO_SEG_DOWNLOAD, size);
#if CO_CONFIG_LARGE_OBJECTS
            r = co_sdo_large_begin(node, s, size);
#endif
        }
        if (r != CO_ABORT_NONE) {
            co_sdo_abort(node, s, r);
            return;
        }
        co_sdo_respond(node, s, 0x60U, 0U);
        return;
    }
    if (cmd == 0x40U) {
        size_t len;
        if (read_object(node, s, &len)) {
            upload_answer(node, s, len);
        }
        return;
    }
    const uint8_t ccs = (uint8_t)(cmd >> 5);
    /* Initiates of block upload (ccs 5) and block download (ccs 6): sub-command 0 in the low bits. */
    const bool block_initiate = (ccs == 5U && (cmd & 0x03U) == 0U) || (ccs == 6U && (cmd & 0x01U) == 0U);
#if CO_CONFIG_SDO_BLOCK
    if (block_initiate && (node->options & CO_OPT_SDO_BLOCK) != 0U) {
        co_sdo_block_initiate(node, s, cmd, &f->data[4]);
        return;
    }
#endif
    if (ccs == 0U || ccs == 3U || ((ccs == 5U || ccs == 6U) && !block_initiate)) {
        /* A segment, or a block sub-command, with no transfer open: its bytes 1..3 are no multiplexer to echo. */
        s->index = 0U;
        s->sub = 0U;
    }
    co_sdo_abort(node, s, CO_ABORT_COMMAND); /* block transfer switched off, unknown commands */
}

void co_sdo_rx(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f)
{
    if (f->len != 8U) {
        return; /* not an SDO frame: ignored */
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        return; /* SDO is silent in Stopped */
    }
    serve(node, s, f);
    if (SDO_TRANSFERS && s->state != SDO_IDLE) {
        s->deadline = co_time_after(node->now, CO_SDO_TIMEOUT_US); /* the client's last frame starts the timeout */
        co_node_wake(node, CO_SVC_SDO); /* the pass takes the deadline, and sends the segments of a block */
    }
}

static co_time_us_t server_process(co_node_t *node, co_sdo_server_t *s)
{
    if (!SDO_TRANSFERS || s->state == SDO_IDLE) {
        return CO_NEVER;
    }
    if (node->nmt_state != CO_NMT_PRE_OPERATIONAL && node->nmt_state != CO_NMT_OPERATIONAL) {
        co_sdo_end(node, s); /* Stopped: the transfer ends silently (SDO says nothing in Stopped) */
        return CO_NEVER;
    }
    if (co_time_reached(node->now, s->deadline)) {
        co_sdo_abort(node, s, CO_ABORT_TIMEOUT);
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
#if CO_CONFIG_LARGE_OBJECTS
        servers[n].large = false; /* the caller's memory: no transfer to drop at the first reset */
#endif
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
    co_sdo_end(node, s);
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
    co_sdo_end(node, &node->sdo);
    node->sdo.param_index = 0x1200U;
    node->sdo.rx_id = (uint16_t)(0x600U + node->node_id);
    node->sdo.tx_id = (uint16_t)(0x580U + node->node_id);
#if CO_CONFIG_SDO_SERVERS
    for (uint8_t i = 0U; i < node->n_sdo_extra; i++) {
        load_server(node, &node->sdo_extra[i]);
    }
#endif
}
