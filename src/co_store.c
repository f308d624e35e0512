/*
 * Store and restore parameters (CiA 301 §7.5.2.13/14, objects 0x1010/0x1011) and the LSS configuration.
 *
 * Parameter blob (area CO_NVM_PARAMS), all numbers little-endian:
 *   header  "COS1" | OD signature (u32) | payload length (u32) | CRC-32 of the payload (u32)
 *   payload records, sorted by (index, sub): index (u16) | sub (u8) | length (u8) | value (wire format)
 * Records name their object, so a blob survives a changed table layout as long as the signature matches.
 * Saving a group (0x1010 sub 2 = 0x1000-0x1FFF, 3 = 0x6000-0x9FFF, 4 = 0x2000-0x5FFF, 1 and others = all)
 * merges the current values of the group with the stored records of the other groups in one pass.
 * Restoring writes a blob without the group's records (except rows marked CO_OD_KEEP), so the defaults
 * return at the next reset, as CiA 301 prescribes; the running values do not change.
 *
 * LSS blob (area CO_NVM_LSS): "COL1" | node-ID (u8) | bit-timing index (u8) | 0 | 0 | CRC-32 of bytes 0..7.
 *
 * A store is answered with the result of the port's last commit, which makes all of it durable (the device's
 * areas of the same store, from the on_store hook, and the core's area) or none of it (co_port_t.nvm_commit).
 */
#include "priv/co_priv.h"

#define SIG_SAVE 0x65766173UL /* "save" */
#define SIG_LOAD 0x64616F6CUL /* "load" */
#define PARAMS_MAGIC 0x31534F43UL /* "COS1" */
#define LSS_MAGIC 0x314C4F43UL    /* "COL1" */
#define HEADER_LEN 16U
#define PAYLOAD_MAX 0x10000UL
#define RECORD_HEAD 4U

uint32_t co_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    crc = ~crc;
    for (size_t i = 0U; i < len; i++) {
        crc ^= data[i];
        for (unsigned b = 0U; b < 8U; b++) {
            crc = (crc >> 1) ^ (0xEDB88320UL & (0U - (crc & 1U)));
        }
    }
    return ~crc;
}

static bool have_read(const co_node_t *node) { return node->port->nvm_read != NULL; }
static bool have_write(const co_node_t *node)
{
    return node->port->nvm_write != NULL && node->port->nvm_commit != NULL;
}

/* Reads the first len bytes of an area's blob (its header): CO_NVM_LOADED when they are there. Otherwise nothing is
 * stored (no storage, or CO_ERR_NO_DATA and not even one byte there), or the blob is shorter than its header (a
 * port that can tell answers other than CO_ERR_NO_DATA, e.g. for an empty file; one that cannot is asked for a
 * single byte). */
static co_nvm_status_t read_header(co_node_t *node, co_nvm_area_t area, uint8_t *h, size_t len)
{
    if (!have_read(node)) {
        return CO_NVM_NONE;
    }
    const co_status_t st = node->port->nvm_read(node->port_ctx, area, 0U, h, len);
    if (st == CO_OK) {
        return CO_NVM_LOADED;
    }
    if (st != CO_ERR_NO_DATA || node->port->nvm_read(node->port_ctx, area, 0U, h, 1U) == CO_OK) {
        return CO_NVM_CORRUPT;
    }
    return CO_NVM_NONE;
}

/* Reads len bytes at pos of the stored payload into dst: true when they are there. */
static bool read_payload(co_node_t *node, uint32_t pos, uint8_t *dst, size_t len)
{
    return node->port->nvm_read(node->port_ctx, CO_NVM_PARAMS, HEADER_LEN + pos, dst, len) == CO_OK;
}

/* Validates the stored parameter blob; returns its payload length through *len. */
static co_nvm_status_t params_check(co_node_t *node, uint32_t *len)
{
    uint8_t h[HEADER_LEN];
    *len = 0U;
    const co_nvm_status_t st = read_header(node, CO_NVM_PARAMS, h, HEADER_LEN);
    if (st != CO_NVM_LOADED) {
        return st;
    }
    const uint32_t payload = co_get_u32(&h[8]);
    if (co_get_u32(h) != PARAMS_MAGIC || payload > PAYLOAD_MAX) {
        return CO_NVM_CORRUPT;
    }
    uint32_t crc = 0U;
    uint8_t chunk[32];
    for (uint32_t pos = 0U; pos < payload; pos += sizeof chunk) {
        const size_t n = (payload - pos) < sizeof chunk ? (size_t)(payload - pos) : sizeof chunk;
        if (!read_payload(node, pos, chunk, n)) {
            return CO_NVM_CORRUPT; /* truncated */
        }
        crc = co_crc32(crc, chunk, n);
    }
    if (crc != co_get_u32(&h[12])) {
        return CO_NVM_CORRUPT;
    }
    if (co_get_u32(&h[4]) != node->od->signature) {
        return CO_NVM_FOREIGN;
    }
    *len = payload;
    return CO_NVM_LOADED;
}

#define READER_END UINT32_MAX /* the key past the last record: above every index << 8 | sub */

/* Sequential reader of the stored records. A record is kept as stored, head and value in one buffer: a save
 * copies it with one write. */
typedef struct record_reader {
    co_node_t *node;
    uint32_t pos;
    uint32_t end;
    uint32_t key; /* index << 8 | sub of the record in rec; READER_END: none (the end, or a record cut short) */
    uint8_t rec[RECORD_HEAD + 255U];
} record_reader_t;

static void reader_next(record_reader_t *r)
{
    uint8_t *rec = r->rec;
    const uint32_t at = r->pos;
    r->key = READER_END;
    if (at + RECORD_HEAD > r->end || !read_payload(r->node, at, rec, RECORD_HEAD)) {
        return;
    }
    r->pos = at + RECORD_HEAD + rec[3]; /* past the record; unused if it proves cut short (key READER_END) */
    if (r->pos > r->end || !read_payload(r->node, at + RECORD_HEAD, &rec[RECORD_HEAD], rec[3])) {
        return;
    }
    r->key = ((uint32_t)co_get_u16(rec) << 8) | rec[2];
}

static co_nvm_status_t reader_open(record_reader_t *r, co_node_t *node)
{
    r->node = node;
    r->pos = 0U;
    r->key = READER_END;
    const co_nvm_status_t st = params_check(node, &r->end);
    if (st == CO_NVM_LOADED) {
        reader_next(r);
    }
    return st;
}

/* Advances to the first record whose key is >= (index, sub); true when it is exactly that key. */
static bool reader_seek(record_reader_t *r, uint16_t index, uint8_t sub)
{
    const uint32_t key = ((uint32_t)index << 8) | sub;
    while (r->key < key) {
        reader_next(r);
    }
    return r->key == key;
}

/* Loads the records of [first, last] in index order, each checked as a write of it would be (co_od_check_stored:
 * a value SDO would refuse, e.g. a restricted PDO COB-ID, must not come back through a file). Checks that depend
 * on another stored value see it loaded when it precedes (an E-field type before its limits). One refused
 * record refuses the area: it returns to its defaults and the node reports it (CO_EV_NVM_REFUSED, then
 * CO_NVM_REFUSED), as for a damaged blob. A record of a sub-index the node does not have (the device's hook
 * answers 0x06090011: a variant without it) is skipped, as one of a row the OD lacks. */
void co_store_load_area(co_node_t *node, uint16_t first, uint16_t last)
{
    record_reader_t local;
    node->nvm_status = reader_open(&local, node);
    for (; local.key != READER_END; reader_next(&local)) {
        const uint16_t index = (uint16_t)(local.key >> 8);
        const uint8_t len = local.rec[3];
        const uint8_t *value = &local.rec[RECORD_HEAD];
        if (index < first || index > last) {
            continue;
        }
        co_od_entry_t one;
        const co_od_entry_t *e = co_od_find(node->od, index, (uint8_t)local.key, &one);
        if (e == NULL || (e->flags & CO_OD_STORE) == 0U || co_od_is_large(e)) {
            continue; /* a large object is the application's to keep */
        }
        const uint16_t fixed = co_od_type_size(e->type);
        if ((fixed != 0U && len != fixed) || len > e->size) {
            continue;
        }
        const uint32_t r = co_od_check_stored(node, e, value, len);
        if (r == CO_ABORT_NO_SUBINDEX) {
            /* The device says this node has no such sub-index (a PRO IONIZER variant hides rows of others): skipped
             * like a row the OD lacks. A save writes every stored row, so refusing here refused every save of such
             * a variant at the next power-on. Only a hook answers this for a row the OD has. */
            continue;
        }
        if (r != CO_ABORT_NONE) {
            co_node_event(node, CO_EV_NVM_REFUSED, e->index, e->sub, 0U, r);
            co_od_defaults_area(node, first, last);
            node->nvm_status = CO_NVM_REFUSED;
            return;
        }
        co_od_store_value(node, e, value, len);
    }
}

/* The groups of 0x1010/0x1011 sub 2..4 as sets of the index's top hex digit: 2 = 0x1000-0x1FFF, 3 = 0x6000-0x9FFF,
 * 4 = 0x2000-0x5FFF; sub 1 and others: every index. */
static bool in_group(uint8_t sub, uint16_t index)
{
    static const uint16_t top_digits[3] = {0x0002U, 0x03C0U, 0x003CU};
    return sub < 2U || sub > 4U || ((top_digits[sub - 2U] >> (index >> 12)) & 1U) != 0U;
}

/* Streams records to the staging area and keeps the running CRC. */
typedef struct blob_writer {
    uint32_t pos;
    uint32_t crc;
    bool ok;
} blob_writer_t;

/* Appends a record: head and value in one buffer, as record_reader_t.rec holds it. */
static void writer_put(co_node_t *node, blob_writer_t *w, const uint8_t *rec)
{
    const size_t size = RECORD_HEAD + (size_t)rec[3];
    w->ok = w->ok &&
            node->port->nvm_write(node->port_ctx, CO_NVM_PARAMS, HEADER_LEN + w->pos, rec, size) == CO_OK;
    w->crc = co_crc32(w->crc, rec, size);
    w->pos += (uint32_t)size;
}

/* True when a row holds its node-ID-relative default: not stored, so a new node-ID moves it along. While the node-ID
 * is unconfigured that default is the bare table value, as co_od_defaults_area leaves it: comparing with value +
 * 0xFF stored it, e.g. TPDO1's COB-ID 0x180, which the next load refused as a restricted COB-ID (and with it every
 * value of that save). */
static bool at_relative_default(co_node_t *node, const co_od_entry_t *e)
{
    if ((e->flags & CO_OD_NODEID) == 0U) {
        return false;
    }
    uint32_t def = 0U;
    co_od_copy_defaults(node->od, e->offset, e->size < 4U ? e->size : 4U, &def);
    const uint32_t id = node->node_id != CO_NODE_ID_UNCONFIGURED ? node->node_id : 0U;
    return co_od_entry_u32(node, e) == def + id;
}

/* A store is one transaction of the port (co_port_t.nvm_commit): the device's areas first, committed with
 * CO_NVM_MORE by its on_store hook, then the core's own area, staged and committed last, which makes the whole
 * store durable or none of it. The device goes first because a port may stage one area at a time. */
static void discard_store(co_node_t *node, co_nvm_area_t own)
{
    (void)node->port->nvm_commit(node->port_ctx, own, CO_NVM_DISCARD);
}

/* The start of a store: false when there is no storage or the device's part failed (then nothing is kept). */
static bool stage_device_areas(co_node_t *node, co_nvm_area_t own, uint16_t index, uint8_t sub)
{
    if (!have_write(node)) {
        return false; /* nothing to discard */
    }
    const co_hooks_t *h = node->hooks;
    if (h == NULL || h->on_store == NULL || h->on_store(node->hooks_ctx, node, index, sub) == CO_OK) {
        return true;
    }
    discard_store(node, own); /* what the hook committed before it failed */
    return false;
}

/* The last commit of a store: the core's area gets its header (head_len bytes at offset 0; whatever follows it is
 * staged: staged_ok) and is committed with total_len bytes. If anything of it failed, the store is dropped. */
static co_status_t commit_store(co_node_t *node, co_nvm_area_t own, const uint8_t *head, size_t head_len,
                                uint32_t total_len, bool staged_ok)
{
    if (!staged_ok || node->port->nvm_write(node->port_ctx, own, 0U, head, head_len) != CO_OK) {
        discard_store(node, own);
        return CO_ERR_IO;
    }
    return node->port->nvm_commit(node->port_ctx, own, total_len) == CO_OK ? CO_OK : CO_ERR_IO;
}

/* req: the sub-index of 0x1010 (save) or 0x1011 written, its sub the group.
 * save: the group's rows get their current values; restore: the group's rows are dropped (KEEP rows stay).
 * Returns the store's abort code: CO_ABORT_HARDWARE when there is no storage or the port failed; CO_ABORT_STORE
 * (0x08000020) when a value to save is one its load would refuse (co_od_check_stored: a value the application
 * wrote past the object's limits, which only a local write can do): nothing of the store is kept, rather than a
 * save confirmed now and loaded as defaults at the next start. */
static uint32_t rewrite(co_node_t *node, const co_od_entry_t *req, bool save)
{
    const uint8_t group = req->sub;
    record_reader_t old;
    blob_writer_t w = {0U, 0U, true};
    if (!stage_device_areas(node, CO_NVM_PARAMS, req->index, group)) {
        return CO_ABORT_HARDWARE;
    }
    (void)reader_open(&old, node); /* a damaged or foreign blob counts as empty */
    for (unsigned i = 0U; i < node->od->count; i++) {
        const co_od_entry_t *row = &node->od->entries[i];
        if ((row->flags & CO_OD_STORE) == 0U || co_od_is_large(row)) {
            continue;
        }
        for (uint8_t k = 0U; k < co_od_entry_subs(row); k++) {
            co_od_entry_t one;
            const co_od_entry_t *e = co_od_entry_at(row, k, &one);
            const bool stored = reader_seek(&old, e->index, e->sub);
            const bool grouped = in_group(group, e->index);
            if (save && grouped) {
                if (!at_relative_default(node, e)) {
                    uint8_t rec[RECORD_HEAD + 255U];
                    uint8_t *value = &rec[RECORD_HEAD];
                    const size_t n = co_od_sample(node, e, value, 255U);
                    /* As the load will check it (a sub-index the node hides is skipped there); a check that
                     * depends on another stored value sees the present one here, the loaded one there: the same
                     * for every value saved before it in index order. */
                    const uint32_t refused = co_od_check_stored(node, e, value, n);
                    if (refused != CO_ABORT_NONE && refused != CO_ABORT_NO_SUBINDEX) {
                        co_node_event(node, CO_EV_NVM_REFUSED, e->index, e->sub, 1U, refused);
                        discard_store(node, CO_NVM_PARAMS);
                        return CO_ABORT_STORE;
                    }
                    co_put_u16(rec, e->index);
                    rec[2] = e->sub;
                    rec[3] = (uint8_t)n;
                    writer_put(node, &w, rec);
                }
            } else if (stored && (save || !grouped || (e->flags & CO_OD_KEEP) != 0U)) {
                writer_put(node, &w, old.rec);
            }
        }
    }
    uint8_t h[HEADER_LEN];
    co_put_u32(h, PARAMS_MAGIC);
    co_put_u32(&h[4], node->od->signature);
    co_put_u32(&h[8], w.pos);
    co_put_u32(&h[12], w.crc);
    const co_status_t st = commit_store(node, CO_NVM_PARAMS, h, HEADER_LEN, HEADER_LEN + w.pos, w.ok);
    return st == CO_OK ? CO_ABORT_NONE : CO_ABORT_HARDWARE;
}

uint32_t co_store_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    const bool save = e->index == 0x1010U;
    if (e->sub == 0U || len != 4U) {
        return CO_ABORT_READ_ONLY;
    }
    if (co_get_u32(data) != (save ? SIG_SAVE : SIG_LOAD)) {
        return CO_ABORT_STORE; /* wrong signature */
    }
    const uint32_t r = rewrite(node, e, save);
    co_node_event(node, save ? CO_EV_STORE : CO_EV_RESTORE, e->index, e->sub, 0U, r);
    return r;
}

#define LSS_BLOB_LEN 12U

static void lss_blob(uint8_t b[LSS_BLOB_LEN], uint8_t node_id, uint8_t bit_timing)
{
    co_put_u32(b, LSS_MAGIC);
    b[4] = node_id;
    b[5] = bit_timing;
    b[6] = 0U;
    b[7] = 0U;
    co_put_u32(&b[8], co_crc32(0U, b, 8U));
}

co_status_t co_store_lss_save(co_node_t *node, uint8_t node_id, uint8_t bit_timing)
{
    uint8_t b[LSS_BLOB_LEN];
    if (!stage_device_areas(node, CO_NVM_LSS, 0x7E5U, 0x17U)) {
        return CO_ERR_IO;
    }
    lss_blob(b, node_id, bit_timing);
    return commit_store(node, CO_NVM_LSS, b, sizeof b, sizeof b, true);
}

co_status_t co_lss_stage(co_node_t *node, uint8_t node_id, uint8_t bit_timing)
{
    uint8_t b[LSS_BLOB_LEN];
    lss_blob(b, node_id, bit_timing);
    if (!have_write(node) || node->port->nvm_write(node->port_ctx, CO_NVM_LSS, 0U, b, sizeof b) != CO_OK) {
        return CO_ERR_IO;
    }
    return node->port->nvm_commit(node->port_ctx, CO_NVM_LSS, LSS_BLOB_LEN | CO_NVM_MORE) == CO_OK ? CO_OK : CO_ERR_IO;
}

co_nvm_status_t co_store_lss_load(co_node_t *node, uint8_t *node_id, uint8_t *bit_timing)
{
    uint8_t b[LSS_BLOB_LEN];
    const co_nvm_status_t st = read_header(node, CO_NVM_LSS, b, sizeof b);
    if (st != CO_NVM_LOADED) {
        return st;
    }
    if (co_get_u32(b) != LSS_MAGIC || co_get_u32(&b[8]) != co_crc32(0U, b, 8U)) {
        return CO_NVM_CORRUPT;
    }
    /* A valid CRC over values this node never writes is not ours: a node-ID out of range, "unconfigured" where LSS
     * may not unconfigure, a bit timing outside the table or not in the device's: what LSS configure refuses.
     * Loaded, a Buerkert showed them in its stored 0x2001:01/02, and the next load of its parameters refused them,
     * and so every value saved (found by tests/fuzz/target_nvm_file.c). The checks are LSS's own setters: the
     * pending values they set are the ones co_lss_init sets after this load (the node's node-ID and bit timing). */
    if (!co_lss_set_pending_node_id(node, b[4]) || !co_lss_set_pending_bit_timing(node, b[5])) {
        return CO_NVM_CORRUPT;
    }
    *node_id = b[4];
    *bit_timing = b[5];
    return CO_NVM_LOADED;
}
