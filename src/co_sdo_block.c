/*
 * SDO block transfer, server side (CiA 301 §7.2.4.3.9-16): block download and block upload of one object
 * through the SDO buffer, with the CRC when the client supports it, and the protocol switch of a block upload
 * to an expedited or segmented upload for objects of at most pst bytes. Compiled in with CO_CONFIG_SDO_BLOCK,
 * used by nodes with CO_OPT_SDO_BLOCK; co_sdo_server.c routes the frames here. Decisions where CiA 301 leaves
 * a choice (lost and repeated segments, the block size offered): docs/decisions.md.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_SDO_BLOCK

#define BLK_SEG_DATA 7U    /* data bytes per segment */
#define BLK_SIZE_MAX 127U  /* segments per block */
#define BLK_LAST 0x80U     /* "c" bit of a segment: no more segments follow */

/* CRC-16 of CiA 301 §7.2.4.3.16: polynomial x^16 + x^12 + x^5 + 1, start value 0 ("123456789" -> 0x31C3).
 * Bitwise rather than by table: it runs once per transfer, and 512 bytes of table would outweigh the service.
 * Continued from start: a large object's CRC is taken piece by piece. */
uint16_t co_sdo_crc(uint16_t start, const uint8_t *data, uint32_t len)
{
    uint32_t crc = start; /* bits above 15 are shifted out of the CRC, never fed back: cut once, at the end */
    for (uint32_t i = 0U; i < len; i++) {
        crc ^= (uint32_t)data[i] << 8;
        for (unsigned bit = 0U; bit < 8U; bit++) {
            crc = (crc << 1) ^ ((crc & 0x8000U) != 0U ? 0x1021U : 0U);
        }
    }
    return (uint16_t)crc;
}

/* Segments the server takes in the next block of a download, pos bytes received: as many as the rest of the buffer
 * can hold (the last one may carry fewer than 7 bytes), at least 1. */
static uint8_t download_block_size(uint32_t pos)
{
    const uint32_t room = pos < CO_SDO_BUF_SIZE ? CO_SDO_BUF_SIZE - pos : 0U;
    if (room >= BLK_SIZE_MAX * BLK_SEG_DATA) {
        return BLK_SIZE_MAX;
    }
    /* ceil(room / 7) as a multiplication, equal to the division for every room below 127 x 7: a core without a
     * divide instruction links no library division for it */
    const uint32_t segments = ((room + BLK_SEG_DATA - 1U) * 9363U) >> 16;
    return (uint8_t)(segments == 0U ? 1U : segments);
}

/* Initiate block download (byte 0 0b110x_xcs0: c client CRC, s size indicated) or block upload (0b101x_xc00, byte 4
 * block size, byte 5 protocol switch threshold). The object checks come first, as for a segmented download. */
void co_sdo_block_initiate(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *data)
{
    const bool client_crc = (cmd & 0x04U) != 0U;
    if ((cmd & 0xE0U) == 0xC0U) {
        const bool sized = (cmd & 0x02U) != 0U;
        const uint32_t size = sized ? co_get_u32(data) : 0U;
        const uint32_t r = co_sdo_download_checks(node, s, sized, size, true);
        if (r != CO_ABORT_NONE) {
            co_sdo_abort(node, s, r);
            return;
        }
        co_sdo_start(s, CO_SDO_BLK_DOWNLOAD, size);
        s->crc = client_crc;
#if CO_CONFIG_LARGE_OBJECTS
        const uint32_t begun = co_sdo_large_begin(node, s, size);
        if (begun != CO_ABORT_NONE) {
            co_sdo_abort(node, s, begun);
            return;
        }
#endif
        /* a constant; a large object takes whole blocks, its buffer handed over as it fills */
        s->blksize = CO_SDO_IS_LARGE(s) ? BLK_SIZE_MAX : download_block_size(0U);
        co_sdo_respond(node, s, 0xA4U, s->blksize); /* server CRC support: always */
        return;
    }
    const uint8_t blksize = data[0];
    const uint8_t pst = data[1];
    if (blksize == 0U || blksize > BLK_SIZE_MAX) {
        co_sdo_abort(node, s, CO_ABORT_BLOCK_SIZE);
        return;
    }
    size_t len;
    if (!co_sdo_read_object(node, s, &len)) {
        return;
    }
    if (pst != 0U && len <= pst) {
        co_sdo_upload_answer(node, s, len); /* protocol switch: the client accepts an ordinary upload */
        return;
    }
    co_sdo_start(s, CO_SDO_BLK_UPLOAD_START, (uint32_t)len);
    s->crc = client_crc;
    s->blksize = blksize;
    co_sdo_respond(node, s, 0xC6U, (uint32_t)len); /* server CRC support, size indicated */
}

static void download_segment(co_node_t *node, co_sdo_server_t *s, const uint8_t *frame)
{
    const uint8_t seqno = (uint8_t)(frame[0] & 0x7FU);
    if (seqno == 0U || seqno > s->blksize) {
        co_sdo_abort(node, s, CO_ABORT_SEQUENCE);
        return;
    }
    const bool in_order = seqno == s->seq + 1U;
    if (in_order) {
#if CO_CONFIG_LARGE_OBJECTS
        /* the segments held so far are not the last: handed over whole when this one would not fit */
        const uint32_t refused = co_sdo_large_room(node, s, BLK_SEG_DATA);
        if (refused != CO_ABORT_NONE) {
            co_sdo_abort(node, s, refused);
            return;
        }
#endif
        const uint32_t held = s->pos - CO_SDO_DONE(s);
        if (held >= sizeof s->buf) {
            co_sdo_abort(node, s, CO_ABORT_OUT_OF_MEMORY);
            return;
        }
        const uint32_t room = (uint32_t)sizeof s->buf - held;
        memcpy(&s->buf[held], &frame[1], (size_t)(room < BLK_SEG_DATA ? room : BLK_SEG_DATA));
        s->pos += BLK_SEG_DATA;
        s->seq = seqno;
    }
    /* A segment out of order (one was lost) or repeated is ignored; the block ends at its last segment (sequence
     * number blksize, or the c bit) all the same, and the confirmation names the last one taken in order, from
     * which the client repeats. */
    const bool last = in_order && (frame[0] & BLK_LAST) != 0U;
    if (!last && seqno != s->blksize && (frame[0] & BLK_LAST) == 0U) {
        return;
    }
    const uint8_t ackseq = s->seq;
    if (last) {
        s->state = CO_SDO_BLK_DOWNLOAD_END;
    } else {
        s->seq = 0U;
        s->blksize = CO_SDO_IS_LARGE(s) ? BLK_SIZE_MAX : download_block_size(s->pos);
    }
    const uint8_t confirmation[2] = {ackseq, s->blksize};
    co_sdo_send(node, s, 0xA2U, confirmation, 2U);
}

static void download_end(co_node_t *node, co_sdo_server_t *s, uint8_t cmd, const uint8_t *frame)
{
    const uint32_t unused = (uint32_t)(cmd >> 2) & 0x07U;
    const uint32_t len = s->pos - unused; /* pos >= 7: the last segment was taken */
#if CO_CONFIG_LARGE_OBJECTS
    if (s->large) { /* the rest to the application, then its CRC is complete */
        const uint32_t refused = co_sdo_large_flush(node, s, len);
        if (refused != CO_ABORT_NONE) {
            co_sdo_abort(node, s, refused);
            return;
        }
        co_sdo_download_end(node, s, len, !s->crc || co_get_u16(&frame[1]) == s->crc_value, 0xA1U);
        return;
    }
#endif
    if (len > sizeof s->buf) {
        co_sdo_abort(node, s, CO_ABORT_OUT_OF_MEMORY);
        return;
    }
    co_sdo_download_end(node, s, len, !s->crc || co_get_u16(&frame[1]) == co_sdo_crc(0U, s->buf, len), 0xA1U);
}

/* Bytes of the upload, counted in segments: an empty object still takes one segment (with 7 unused bytes). */
static uint32_t upload_end_of_block(const co_sdo_server_t *s) { return s->pos + (uint32_t)s->seq * BLK_SEG_DATA; }

/* Sends the segments of the current block while the port takes frames at once, so a block of up to 127
 * segments never floods the node's transmit queue: what is left goes out from co_sdo_block_process. True when
 * the block is out (blksize segments, or fewer that reach the end of the object). */
static bool upload_send_block(co_node_t *node, co_sdo_server_t *s)
{
    for (;;) {
        const uint32_t offset = upload_end_of_block(s);
        if (s->seq >= s->blksize || (s->seq > 0U && offset >= s->size)) {
            return true;
        }
        if (node->txq.count != 0U) {
            return false;
        }
        const uint32_t left = s->size - offset;
        const size_t n = (size_t)(left < BLK_SEG_DATA ? left : BLK_SEG_DATA);
        const uint8_t *bytes = co_sdo_upload_bytes(node, s, offset, n);
        if (bytes == NULL) {
            return true; /* aborted: nothing more to send */
        }
        s->seq++;
        co_sdo_send(node, s, (uint8_t)(s->seq | (left <= BLK_SEG_DATA ? BLK_LAST : 0U)), bytes, n);
    }
}

/* Block confirmation from the client: ackseq segments of the block arrived in order, blksize for the next one.
 * All taken: the end request with the unused bytes of the last segment and the CRC; otherwise the next block,
 * starting after the last segment confirmed (a lost segment is repeated). */
static void upload_confirmation(co_node_t *node, co_sdo_server_t *s, const uint8_t *frame)
{
    const uint8_t ackseq = frame[1];
    const uint8_t blksize = frame[2];
    if (ackseq > s->seq) {
        co_sdo_abort(node, s, CO_ABORT_SEQUENCE);
        return;
    }
    if (blksize == 0U || blksize > BLK_SIZE_MAX) {
        co_sdo_abort(node, s, CO_ABORT_BLOCK_SIZE);
        return;
    }
    /* Every segment sent confirmed, at least one (a block the port had no room for yet has none), and they reach
     * the end of the object. */
    const bool all_taken = ackseq == s->seq && ackseq != 0U && upload_end_of_block(s) >= s->size;
    if (all_taken) {
        const uint32_t unused = upload_end_of_block(s) - s->size;
        uint16_t value = 0U;
#if CO_CONFIG_LARGE_OBJECTS
        if (s->large && s->crc && !co_sdo_large_crc(node, s, &value)) {
            return;
        }
        if (!s->large && s->crc) {
            value = co_sdo_crc(0U, s->buf, s->size);
        }
#else
        value = s->crc ? co_sdo_crc(0U, s->buf, s->size) : 0U;
#endif
        uint8_t crc[2];
        co_put_u16(crc, value);
        s->state = CO_SDO_BLK_UPLOAD_END; /* before the frame: only segments go out in CO_SDO_BLK_UPLOAD */
        co_sdo_send(node, s, (uint8_t)(0xC1U | (unused << 2)), crc, 2U);
        return;
    }
    s->pos += (uint32_t)ackseq * BLK_SEG_DATA;
    s->seq = 0U;
    s->blksize = blksize;
    (void)upload_send_block(node, s);
}

/* The client's next step in each state from CO_SDO_BLK_DOWNLOAD_END on: its command byte without the bits that
 * carry values (cmd & 0xE3). */
static const uint8_t next_step[] = {
    0xC1U, /* CO_SDO_BLK_DOWNLOAD_END: end request */
    0xA3U, /* CO_SDO_BLK_UPLOAD_START: start request */
    0xA2U, /* CO_SDO_BLK_UPLOAD: block confirmation */
    0xA1U, /* CO_SDO_BLK_UPLOAD_END: end response */
};

bool co_sdo_block_rx(co_node_t *node, co_sdo_server_t *s, const co_frame_t *f)
{
    const uint8_t cmd = f->data[0];
    const uint8_t state = s->state;
    /* In CO_SDO_BLK_DOWNLOAD every frame but an abort (0x80, handled before) is a segment. */
    if (state != CO_SDO_BLK_DOWNLOAD && (cmd & 0xE3U) != next_step[state - CO_SDO_BLK_DOWNLOAD_END]) {
        return false; /* not this transfer's next step: co_sdo_rx ends it and reads the frame as a new request */
    }
    switch (state) {
    case CO_SDO_BLK_DOWNLOAD:
        download_segment(node, s, f->data);
        break;
    case CO_SDO_BLK_DOWNLOAD_END:
        download_end(node, s, cmd, f->data);
        break;
    case CO_SDO_BLK_UPLOAD_START:
        s->state = CO_SDO_BLK_UPLOAD;
        (void)upload_send_block(node, s);
        break;
    case CO_SDO_BLK_UPLOAD:
        upload_confirmation(node, s, f->data);
        break;
    default:
        s->state = CO_SDO_IDLE; /* end response: the transfer is complete, nothing to answer */
        break;
    }
    return true; /* co_sdo_rx restarts the timeout of a transfer still open */
}

co_time_us_t co_sdo_block_process(co_node_t *node, co_sdo_server_t *s)
{
    return upload_send_block(node, s) ? CO_NEVER : co_time_after(node->now, CO_TX_RETRY_US);
}

#endif /* CO_CONFIG_SDO_BLOCK */
