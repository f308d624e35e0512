/*
 * Object dictionary access: lookup in the generated const table, the read and write paths with their
 * checks, and conversion between the values block (native representation, laid out by the generated
 * struct) and the wire (little-endian).
 */
#include "priv/co_priv.h"

/* An internal check that fully handled a write (an action such as "save"): nothing is stored. */
#define CO_HANDLED 1U

static uint32_t entry_key(uint16_t index, uint8_t sub) { return ((uint32_t)index << 8) | sub; }

/* Index of the first row with a key >= key. */
static unsigned lower_bound_key(const co_od_t *od, uint32_t key)
{
    const co_od_entry_t *rows = od->entries;
    unsigned lo = 0U;
    unsigned hi = od->count;
    while (lo < hi) {
        const unsigned mid = (lo + hi) >> 1;
        if (entry_key(rows[mid].index, rows[mid].sub) < key) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return lo;
}

#if !CO_CONFIG_OD_COMPACT
uint8_t co_od_object_slot_bits(uint16_t n_objects)
{
    uint8_t bits = 1U;
    while ((1UL << bits) < 2UL * n_objects) {
        bits++;
    }
    return bits;
}

bool co_od_object_slots_fill(const co_od_object_t *objects, uint16_t n_objects, uint16_t *slots, uint8_t bits)
{
    if (bits < co_od_object_slot_bits(n_objects) || bits > 17U || n_objects == 0xFFFFU) {
        return false;
    }
    const uint32_t mask = (uint32_t)((1UL << bits) - 1U);
    for (uint32_t h = 0U; h <= mask; h++) {
        slots[h] = 0U;
    }
    for (uint16_t k = 0U; k < n_objects; k++) {
        uint32_t h = co_od_object_slot(objects[k].index, bits);
        while (slots[h] != 0U) {
            h = (h + 1U) & mask;
        }
        slots[h] = (uint16_t)(k + 1U);
    }
    return true;
}
#endif

/* The object table's entry of index by a binary search, or NULL. */
static const co_od_object_t *search_object(const co_od_t *od, uint16_t index)
{
    const co_od_object_t *objects = od->objects;
    unsigned lo = 0U;
    unsigned hi = od->n_objects;
    while (lo < hi) {
        const unsigned mid = (lo + hi) >> 1;
        if (objects[mid].index < index) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return (lo < od->n_objects && objects[lo].index == index) ? &objects[lo] : NULL;
}

/* The object table's entry of index, or NULL (od->objects != NULL). */
static inline const co_od_object_t *find_object(const co_od_t *od, uint16_t index)
{
#if !CO_CONFIG_OD_COMPACT
    if (od->object_slots != NULL) { /* a few instructions where the search takes ~50 (the Buerkert's 38 objects) */
        const uint32_t mask = (uint32_t)((1UL << od->object_slot_bits) - 1U);
        uint32_t h = co_od_object_slot(index, od->object_slot_bits);
        for (uint32_t tries = 0U; tries <= mask; tries++, h = (h + 1U) & mask) { /* bounded: a full table too */
            const unsigned k = od->object_slots[h];
            if (k == 0U) {
                return NULL;
            }
            if (od->objects[k - 1U].index == index) {
                return &od->objects[k - 1U];
            }
        }
        return NULL;
    }
#endif
    return search_object(od, index);
}

/* The rows of object index: [first, *end), empty when the dictionary lacks it. The one search of the table that
 * every look-up by index shares. */
static inline unsigned object_rows(const co_od_t *od, uint16_t index, unsigned *end)
{
    if (od->objects != NULL) {
        const co_od_object_t *o = find_object(od, index);
        if (o == NULL) {
            *end = 0U;
            return 0U;
        }
        *end = o + 1 < od->objects + od->n_objects ? o[1].first : od->count;
        return o->first;
    }
    *end = lower_bound_key(od, entry_key(index, 0U) + 0x100U);
    return lower_bound_key(od, entry_key(index, 0U));
}

const co_od_entry_t *co_od_entry_at(const co_od_entry_t *row, uint8_t k, co_od_entry_t *one)
{
    if (k == 0U) {
        return row;
    }
    *one = *row;
    one->sub = (uint8_t)(row->sub + k);
    one->offset = (co_od_offset_t)(row->offset + (co_od_offset_t)k * row->size);
    one->count = 1U;
    return one;
}

/* The row that holds (index, sub), or NULL: co_od_find_row() and, inline where the compiler optimises for speed (every
 * SDO request and RPDO passes there), co_od_find(). */
static inline const co_od_entry_t *find_row(const co_od_t *od, uint16_t index, uint8_t sub)
{
    const co_od_entry_t *rows = od->entries;
    unsigned end;
    const unsigned first = object_rows(od, index, &end);
    if (first + sub < end && rows[first + sub].sub == sub) {
        return &rows[first + sub]; /* sub-indices 0..n without gaps or runs: the usual case */
    }
    unsigned lo = first;
    unsigned hi = end;
    while (lo < hi) { /* the first row of the object past sub */
        const unsigned mid = (lo + hi) >> 1;
        if (rows[mid].sub <= sub) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    if (lo <= first) {
        return NULL;
    }
    const co_od_entry_t *r = &rows[lo - 1U];
    /* its first sub-index, or one inside its run */
    return (sub == r->sub || (unsigned)(sub - r->sub) < r->count) ? r : NULL;
}

const co_od_entry_t *co_od_find_row(const co_od_t *od, uint16_t index, uint8_t sub) { return find_row(od, index, sub); }

/* co_od_find(), inline where the compiler optimises for speed into the reads and writes of this file. */
static inline const co_od_entry_t *find(const co_od_t *od, uint16_t index, uint8_t sub, co_od_entry_t *one)
{
    const co_od_entry_t *r = find_row(od, index, sub);
    return (r == NULL || r->sub == sub) ? r : co_od_entry_at(r, (uint8_t)(sub - r->sub), one);
}

const co_od_entry_t *co_od_find(const co_od_t *od, uint16_t index, uint8_t sub, co_od_entry_t *one)
{
    return find(od, index, sub, one);
}

bool co_od_exists(const co_od_t *od, uint16_t index, uint8_t sub) { return co_od_find_row(od, index, sub) != NULL; }

uint16_t co_od_first_row(const co_od_t *od, uint16_t index)
{
    unsigned end;
    const unsigned first = object_rows(od, index, &end);
    return (uint16_t)(first < end ? first : od->count);
}

bool co_od_has_index(const co_od_t *od, uint16_t index) { return co_od_first_row(od, index) < od->count; }

uint32_t co_od_missing(const co_od_t *od, uint16_t index)
{
    return co_od_has_index(od, index) ? CO_ABORT_NO_SUBINDEX : CO_ABORT_NO_OBJECT;
}

uint8_t co_od_sub_count(const co_od_t *od, uint16_t index)
{
    unsigned end;
    unsigned n = 0U;
    for (unsigned i = object_rows(od, index, &end); i < end; i++) {
        n += co_od_entry_subs(&od->entries[i]) - (od->entries[i].sub == 0U ? 1U : 0U);
    }
    return (uint8_t)n;
}

uint16_t co_od_type_size(uint8_t type)
{
    switch (type) {
    case CO_T_BOOLEAN:
    case CO_T_INTEGER8:
    case CO_T_UNSIGNED8:
        return 1U;
    case CO_T_INTEGER16:
    case CO_T_UNSIGNED16:
        return 2U;
    case CO_T_INTEGER32:
    case CO_T_UNSIGNED32:
    case CO_T_REAL32:
        return 4U;
    case CO_T_INTEGER64:
    case CO_T_UNSIGNED64:
    case CO_T_REAL64:
        return 8U;
    case CO_T_INTEGER24:
    case CO_T_UNSIGNED24:
        return 3U;
    case CO_T_INTEGER40:
    case CO_T_UNSIGNED40:
        return 5U;
    case CO_T_INTEGER48:
    case CO_T_UNSIGNED48:
    case CO_T_TIME_OF_DAY:
    case CO_T_TIME_DIFFERENCE:
        return 6U;
    case CO_T_INTEGER56:
    case CO_T_UNSIGNED56:
        return 7U;
    default:
        return 0U;
    }
}

/* Strings and domains: bytes as they are (VISIBLE_STRING 0x09, OCTET_STRING 0x0A, UNICODE_STRING 0x0B, DOMAIN 0x0F). */
/* The first test rules out the usual numbers (BOOLEAN up to REAL32) in one compare: the read and write paths of
 * every fixed-size object pass here. */
static bool is_bytes(const co_od_entry_t *e)
{
    return e->type >= CO_T_VISIBLE_STRING && e->type <= CO_T_DOMAIN && ((0x8E00U >> e->type) & 1U) != 0U;
}

/* INTEGER8/16/32 (0x02..0x04), INTEGER24/40/48/56/64 (0x10, 0x12..0x15). */
static bool is_signed(uint8_t type) { return type <= CO_T_INTEGER64 && ((0x003D001CUL >> type) & 1U) != 0U; }

uint8_t *co_od_ptr(co_node_t *node, const co_od_entry_t *e) { return node->values + e->offset; }

/* True on a big-endian core. A constant the compiler folds: the little-endian cores need no conversion code. */
static bool big_endian(void)
{
    const uint16_t probe = 1U;
    uint8_t first;
    memcpy(&first, &probe, 1U);
    return first == 0U;
}

/* Copies n bytes of a row's value between the values block and the wire, either way: the block holds numbers of 2,
 * 4 or 8 bytes as native integers (reversed on a big-endian core), everything else (strings, domains, the 3, 5, 6
 * and 7-byte integers) as the wire's little-endian bytes. */
static void copy_value(const co_od_entry_t *e, uint8_t *dst, const uint8_t *src, size_t n)
{
    if (big_endian() && !is_bytes(e) && (n == 2U || n == 4U || n == 8U)) {
        for (size_t i = 0U; i < n; i++) {
            dst[i] = src[n - 1U - i];
        }
        return;
    }
    memcpy(dst, src, n);
}

/* Rows co_od_entry_u32()/co_od_entry_set_u32() hold: 1, 2 or 4 bytes. */
static bool fits_u32(const co_od_entry_t *e) { return e->size <= 4U && e->size != 3U && e->size != 0U; }

/* The value of n <= 4 little-endian bytes, zero-extended. */
static uint32_t wire_u32(const uint8_t *data, size_t n)
{
    uint32_t u = 0U;
    while (n > 0U) {
        u = (u << 8) | data[--n];
    }
    return u;
}

uint32_t co_od_entry_u32(const co_node_t *node, const co_od_entry_t *e)
{
    if (!fits_u32(e)) {
        return 0U;
    }
    const uint8_t *p = node->values + e->offset;
    uint8_t wire[4];
    if (big_endian()) {
        copy_value(e, wire, p, e->size);
        p = wire;
    }
    return wire_u32(p, e->size);
}

/* Every write of a value passes here or co_od_store_value: a TPDO-mappable one tells the event-driven TPDOs to
 * compare at the next pass (co_pdo.c). */
static void value_written(co_node_t *node, const co_od_entry_t *e)
{
    if ((e->flags & CO_OD_TPDO) != 0U) {
        node->cos_pending = true;
        co_node_wake(node, CO_SVC_PDO);
    }
}

void co_od_entry_set_u32(co_node_t *node, const co_od_entry_t *e, uint32_t v)
{
    value_written(node, e);
    if (fits_u32(e)) {
        uint8_t wire[4];
        co_put_u32(wire, v);
        copy_value(e, node->values + e->offset, wire, e->size);
    }
}

uint32_t co_od_u32_or(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t fallback)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    return e != NULL ? co_od_entry_u32(node, e) : fallback;
}

void co_od_store_value(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    value_written(node, e);
    uint8_t *p = co_od_ptr(node, e);
    const size_t n = len < e->size ? len : e->size; /* a number: its size (checked); a string may be shorter */
    copy_value(e, p, data, n);
    if (is_bytes(e)) { /* one test, which a number fails at once: the rest zeroed, and its length */
        memset(p + n, 0, (size_t)e->size - n);
        co_put_u16(p + e->size, (uint16_t)n);
    }
}

/* Wire length of a string's or domain's current value (is_bytes): its length, kept after it (co_od.h), and a
 * VISIBLE_STRING's up to its first NUL within that (a value written around co_od_write(), NUL-padded). */
static size_t bytes_len(co_node_t *node, const co_od_entry_t *e)
{
    const uint8_t *p = co_od_ptr(node, e);
    const size_t kept = co_get_u16(p + e->size);
    const size_t len = kept < e->size ? kept : e->size;
    if (e->type != CO_T_VISIBLE_STRING) {
        return len;
    }
    size_t n = 0U;
    while (n < len && p[n] != 0U) {
        n++;
    }
    return n;
}

static uint32_t write_hook(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                           co_od_origin_t origin)
{
    if (node->hooks != NULL && node->hooks->on_write != NULL && e->index >= node->hooks->first_index) {
        return node->hooks->on_write(node->hooks_ctx, node, e, data, len, origin);
    }
    return CO_ABORT_NONE;
}

static uint32_t read_hook(co_node_t *node, const co_od_entry_t *e)
{
    if (node->hooks != NULL && node->hooks->on_read != NULL && e->index >= node->hooks->first_index) {
        return node->hooks->on_read(node->hooks_ctx, node, e);
    }
    return CO_ABORT_NONE;
}

#if CO_CONFIG_LARGE_OBJECTS
uint32_t co_od_large_read(co_node_t *node, const co_od_entry_t *e, uint32_t offset, uint8_t *buf, size_t len,
                          uint32_t *length)
{
    const co_hooks_t *h = node->hooks;
    if (h == NULL || h->large_read == NULL) {
        return CO_ABORT_UNSUPPORTED_ACCESS;
    }
    return h->large_read(node->hooks_ctx, node, e, offset, buf, len, length);
}

uint32_t co_od_large_write(co_node_t *node, const co_od_entry_t *e, co_large_step_t step, uint32_t at,
                           const uint8_t *data, size_t len)
{
    const co_hooks_t *h = node->hooks;
    if (h == NULL || h->large_write == NULL) {
        return CO_ABORT_UNSUPPORTED_ACCESS;
    }
    return h->large_write(node->hooks_ctx, node, e, step, at, data, len);
}

#endif

/* Copies a row's current value in wire format (no hook): its length, or CO_ABORT_LENGTH_HIGH when it exceeds cap. */
static uint32_t copy_wire(co_node_t *node, const co_od_entry_t *e, uint8_t *buf, size_t cap, size_t *len)
{
    size_t n = e->size; /* a number's length */
    if (is_bytes(e)) {
#if CO_CONFIG_LARGE_OBJECTS
        if (n == 0U) { /* by value, not through len: its address given away kept a caller's length in memory */
            const uint64_t got = co_od_read_large(node, e, buf, cap); /* co_sdo_large.c */
            *len = (size_t)(got & 0xFFFFFFFFU);
            return (uint32_t)(got >> 32);
        }
#endif
        n = bytes_len(node, e);
    }
    if (n > cap) {
        return CO_ABORT_LENGTH_HIGH;
    }
    copy_value(e, buf, co_od_ptr(node, e), n);
    *len = n;
    return CO_ABORT_NONE;
}

size_t co_od_sample(co_node_t *node, const co_od_entry_t *e, uint8_t *buf, size_t cap)
{
    size_t n = 0U; /* 0 if it does not fit */
    (void)read_hook(node, e); /* a PDO cannot be refused: the value is sent as it is */
    (void)copy_wire(node, e, buf, cap, &n);
    return n;
}

#if CO_CONFIG_OD_LIMITS_64
/* Sign-extended or zero-extended value of wire bytes of a fixed-size integer row. */
static int64_t wire_integer(const co_od_entry_t *e, const uint8_t *data)
{
    uint64_t u = 0U;
    for (uint16_t i = e->size; i > 0U; i--) {
        u = (u << 8) | data[i - 1U];
    }
    if (is_signed(e->type) && e->size < 8U && (u & ((uint64_t)1U << (e->size * 8U - 1U))) != 0U) {
        u |= ~(((uint64_t)1U << (e->size * 8U)) - 1U);
    }
    return (int64_t)u;
}

/* IEEE 754 values compared as integers, so that a REAL limit check needs no floating point (on a core without an
 * FPU, soft-float comparisons and float-to-double conversion would be linked for it). */
#define CO_REAL64_MAGNITUDE 0x7FFFFFFFFFFFFFFFULL
#define CO_REAL64_INFINITY 0x7FF0000000000000ULL

/* The double a REAL32's bits stand for, exactly (every float is a double), as the bits of that double. */
static uint64_t real32_as_real64(uint32_t f)
{
    const uint64_t sign = (uint64_t)(f >> 31) << 63;
    uint32_t exponent = (f >> 23) & 0xFFU;
    uint32_t mantissa = f & 0x7FFFFFU;
    if (exponent == 0xFFU) { /* infinity or NaN */
        return sign | CO_REAL64_INFINITY | ((uint64_t)mantissa << 29);
    }
    if (exponent == 0U) {
        if (mantissa == 0U) {
            return sign; /* zero */
        }
        exponent = 1U; /* subnormal: normal as a double, normalise */
        while ((mantissa & 0x800000U) == 0U) {
            mantissa <<= 1;
            exponent--;
        }
        mantissa &= 0x7FFFFFU;
    }
    return sign | ((uint64_t)(exponent + 1023U - 127U) << 52) | ((uint64_t)mantissa << 29);
}

/* A key that orders doubles (not NaN) as their values: sign and magnitude to two's complement (-0 = +0). */
static int64_t real64_order(uint64_t bits)
{
    const int64_t magnitude = (int64_t)(bits & CO_REAL64_MAGNITUDE);
    return (bits >> 63) != 0U ? -magnitude : magnitude;
}

static bool real64_is_nan(uint64_t bits) { return (bits & CO_REAL64_MAGNITUDE) > CO_REAL64_INFINITY; }

/* A limit's bits as a double's (where double is 32 bits wide, as on AVR, the limit is a float). */
static uint64_t limit_bits(const double *limit)
{
    if (sizeof(double) == sizeof(uint32_t)) {
        uint32_t b;
        memcpy(&b, limit, sizeof b);
        return real32_as_real64(b);
    }
    uint64_t b;
    memcpy(&b, limit, sizeof b);
    return b;
}

static uint32_t check_real_limits(const co_od_entry_t *e, const co_od_limits_t *l, uint64_t bits)
{
    if (e->type == CO_T_REAL32) {
        bits = real32_as_real64((uint32_t)bits);
    }
    if (real64_is_nan(bits)) {
        return CO_ABORT_INVALID_VALUE; /* NaN is inside no limits: an invalid value */
    }
    const uint64_t high = limit_bits(&l->high.r), low = limit_bits(&l->low.r);
    const int64_t v = real64_order(bits);
    if (!real64_is_nan(high) && v > real64_order(high)) {
        return CO_ABORT_VALUE_HIGH;
    }
    return !real64_is_nan(low) && v < real64_order(low) ? CO_ABORT_VALUE_LOW : CO_ABORT_NONE;
}

uint32_t co_od_check_limits(const co_od_t *od, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    const co_od_limits_t *l = co_od_entry_limits(od, e);
    if (l == NULL || is_bytes(e) || len < e->size) {
        return CO_ABORT_NONE;
    }
    if (e->type == CO_T_REAL32 || e->type == CO_T_REAL64) {
        return check_real_limits(e, l, (uint64_t)wire_integer(e, data));
    }
    if (e->type == CO_T_UNSIGNED64) {
        const uint64_t v = (uint64_t)wire_integer(e, data);
        return v > l->high.u ? CO_ABORT_VALUE_HIGH : (v < l->low.u ? CO_ABORT_VALUE_LOW : CO_ABORT_NONE);
    }
    const int64_t v = wire_integer(e, data);
    if (v > l->high.i) {
        return CO_ABORT_VALUE_HIGH;
    }
    if (v < l->low.i) {
        return CO_ABORT_VALUE_LOW;
    }
    return CO_ABORT_NONE;
}
#else
/* 32-bit limit pairs: rows with limits are integers of 1, 2 or 4 bytes (the generated table's check). */
uint32_t co_od_check_limits(const co_od_t *od, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    const co_od_limits_t *l = co_od_entry_limits(od, e);
    if (l == NULL || len < e->size || e->size > 4U) {
        return CO_ABORT_NONE;
    }
    const uint32_t u = wire_u32(data, e->size);
    if (is_signed(e->type)) {
        const uint32_t sign = (uint32_t)1U << (e->size * 8U - 1U);
        const int32_t v = (int32_t)((u ^ sign) - sign); /* sign-extended */
        return v > l->high.i ? CO_ABORT_VALUE_HIGH : (v < l->low.i ? CO_ABORT_VALUE_LOW : CO_ABORT_NONE);
    }
    return u > l->high.u ? CO_ABORT_VALUE_HIGH : (u < l->low.u ? CO_ABORT_VALUE_LOW : CO_ABORT_NONE);
}
#endif

/* Protocol rules of the communication objects, by owner module. CO_HANDLED: an action, nothing to store.
 * stored: a value being loaded (co_priv.h). */
static uint32_t comm_check_write(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len, bool stored)
{
    switch (e->index) {
    case 0x1001:
    case 0x1003:
    case 0x1014:
    case 0x1015:
#if CO_CONFIG_EMCY_HISTORY
        if (e->index == 0x1003 && e->sub == 0U) {
            return co_emcy_write_action(node, e, data, len) ? CO_HANDLED : CO_ABORT_INVALID_VALUE;
        }
#endif
        return co_emcy_check_write(node, e, data, stored);
#if CO_CONFIG_SYNC
    case 0x1005:
    case 0x1006:
    case 0x1007:
    case 0x1019:
        return co_sync_check_write(node, e, data, len, stored);
#endif
    case 0x1010:
    case 0x1011: {
        const uint32_t r = co_store_check_write(node, e, data, len);
        return r == CO_ABORT_NONE ? CO_HANDLED : r;
    }
#if CO_CONFIG_HB_CONSUMER
    case 0x1016:
        return co_hbc_check_write(node, e, data, len);
#endif
    case 0x1017:
        return co_hb_check_write(node, e, data, len);
    default:
        if (e->index >= 0x1400U && e->index <= 0x1BFFU) {
            return co_pdo_check_write(node, e, data, stored);
        }
#if CO_CONFIG_SDO_SERVERS
        if (e->index >= 0x1200U && e->index <= 0x127FU) {
            return co_sdo_check_write(node, e, data, stored);
        }
#endif
        return CO_ABORT_NONE;
    }
}

/* A communication parameter took a new value: its service takes it (the services keep the parameters they use
 * at every frame or pass, rather than look them up) and runs at the next pass. */
static void comm_written(co_node_t *node, const co_od_entry_t *e)
{
    switch (e->index) {
#if CO_CONFIG_SYNC
    case 0x1005:
    case 0x1006:
    case 0x1007:
    case 0x1019:
        co_sync_written(node, e);
        co_node_wake(node, CO_SVC_SYNC);
        break;
#endif
#if CO_CONFIG_HB_CONSUMER
    case 0x1016:
        co_hbc_written(node, e);
        co_node_wake(node, CO_SVC_HBC);
        break;
#endif
    case 0x1017:
        co_hb_written(node, e); /* life guarding, which a heartbeat producer ends, sees it at its deadline */
        break;
    case 0x1014:
    case 0x1015:
        co_emcy_written(node);
        co_node_wake(node, CO_SVC_EMCY);
        break;
#if CO_CONFIG_NODE_GUARDING
    case 0x100C:
    case 0x100D:
        co_guard_written(node);
        co_node_wake(node, CO_SVC_GUARD);
        break;
#endif
    default:
        if (e->index >= 0x1400U && e->index <= 0x1BFFU) {
            co_pdo_written(node, e);
            co_node_wake(node, CO_SVC_PDO);
        }
#if CO_CONFIG_SDO_SERVERS
        if (e->index >= 0x1201U && e->index <= 0x127FU) {
            co_sdo_written(node, e);
            co_node_wake(node, CO_SVC_SDO);
        }
#endif
        break;
    }
}

uint32_t co_od_read(co_node_t *node, uint16_t index, uint8_t sub, void *buf, size_t cap, size_t *len,
                    co_od_origin_t origin)
{
    co_od_entry_t one;
    const co_od_entry_t *e = find(node->od, index, sub, &one);
    uint32_t r;
    *len = 0U;
    if (e == NULL) {
        return co_od_missing(node->od, index);
    }
    if (origin != CO_ORIGIN_LOCAL && (e->flags & CO_OD_READ) == 0U) {
        return (e->flags & CO_OD_WRITE) != 0U ? CO_ABORT_WRITE_ONLY : CO_ABORT_UNSUPPORTED_ACCESS;
    }
#if CO_CONFIG_EMCY_HISTORY
    if (index == 0x1003U) {
        r = co_emcy_check_read(node, e);
        if (r != CO_ABORT_NONE) {
            return r;
        }
    }
#endif
    r = read_hook(node, e);
    if (r != CO_ABORT_NONE) {
        return r;
    }
    return copy_wire(node, e, (uint8_t *)buf, cap, len);
}

uint32_t co_od_write(co_node_t *node, uint16_t index, uint8_t sub, const void *data, size_t len,
                     co_od_origin_t origin)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    return e != NULL ? co_od_write_entry(node, e, data, len, origin) : co_od_missing(node->od, index);
}

/* The value's checks after those of access and length: limits (but for the application's writes), the protocol rules
 * of a communication object (CO_HANDLED: an action, nothing to store), then the device's write hook. stored: a value
 * being loaded (co_od_check_stored, origin CO_ORIGIN_NVM), checked by the rules of its value alone, and where the
 * owner module has handled it, still by the hook. */
static uint32_t check_value(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                            co_od_origin_t origin, bool stored)
{
    uint32_t r = origin != CO_ORIGIN_LOCAL ? co_od_check_limits(node->od, e, data, len) : CO_ABORT_NONE;
    if (r == CO_ABORT_NONE && e->index < 0x2000U) {
        r = comm_check_write(node, e, data, len, stored);
        if (r == CO_HANDLED) {
            if (!stored) {
                return CO_HANDLED;
            }
            r = CO_ABORT_NONE;
        }
    }
    return r == CO_ABORT_NONE ? write_hook(node, e, data, len, origin) : r;
}

uint32_t co_od_write_entry(co_node_t *node, const co_od_entry_t *e, const void *data, size_t len,
                           co_od_origin_t origin)
{
    const uint8_t *bytes = (const uint8_t *)data;
    if ((e->flags & CO_OD_CONST) != 0U) {
        return CO_ABORT_READ_ONLY;
    }
    if (origin == CO_ORIGIN_SDO && (e->flags & CO_OD_WRITE) == 0U) {
        return (e->flags & CO_OD_READ) != 0U ? CO_ABORT_READ_ONLY : CO_ABORT_UNSUPPORTED_ACCESS;
    }
    if (origin == CO_ORIGIN_RPDO && (e->flags & CO_OD_RPDO) == 0U) {
        return CO_ABORT_NOT_MAPPABLE;
    }
#if CO_CONFIG_LARGE_OBJECTS
    /* With large objects: a number of its own size passes with two compares, as without them (below, 12 bytes
     * smaller on a Cortex-M3, where large objects are off) */
    if (len != e->size || is_bytes(e)) {
        if (!is_bytes(e)) {
            return len > e->size ? CO_ABORT_LENGTH_HIGH : CO_ABORT_LENGTH_LOW; /* a number has its size */
        }
        if (e->size == 0U) { /* a large object: the application's (co_sdo_large.c) */
            return origin != CO_ORIGIN_NVM ? co_od_write_large(node, e, bytes, len) : CO_ABORT_UNSUPPORTED_ACCESS;
        }
        if (len > e->size) {
            return CO_ABORT_LENGTH_HIGH; /* a string or domain may be shorter than its capacity, not longer */
        }
    }
#else
    if (len > e->size) {
        return CO_ABORT_LENGTH_HIGH;
    }
    if (len < e->size && !is_bytes(e)) {
        return CO_ABORT_LENGTH_LOW; /* a string or domain may be shorter than its capacity, a number not */
    }
#endif
    const uint32_t r = check_value(node, e, bytes, len, origin, false);
    if (r != CO_ABORT_NONE) {
        return r == CO_HANDLED ? CO_ABORT_NONE : r;
    }
    co_od_store_value(node, e, bytes, len);
    if (e->index < 0x2000U) {
        comm_written(node, e);
    }
    return CO_ABORT_NONE;
}

void co_od_changed(co_node_t *node, uint16_t index, uint8_t sub)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    if (e == NULL) {
        return;
    }
    value_written(node, e);
    if (is_bytes(e)) {
        co_put_u16(co_od_ptr(node, e) + e->size, e->size); /* a string's whole capacity (co_od.h) */
    }
    if (index < 0x2000U) {
        comm_written(node, e);
    }
}

uint32_t co_od_check_stored(co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len)
{
    return check_value(node, e, data, len, CO_ORIGIN_NVM, true);
}

void *co_od_value(co_node_t *node, uint16_t index, uint8_t sub)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    return e != NULL ? co_od_ptr(node, e) : NULL;
}

static uint32_t get_sized(co_node_t *node, uint16_t index, uint8_t sub, uint16_t size)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(node->od, index, sub, &one);
    return (e != NULL && e->size == size && !is_bytes(e)) ? co_od_entry_u32(node, e) : 0U;
}

uint8_t co_od_get_u8(co_node_t *node, uint16_t index, uint8_t sub) { return (uint8_t)get_sized(node, index, sub, 1U); }
uint16_t co_od_get_u16(co_node_t *node, uint16_t index, uint8_t sub)
{
    return (uint16_t)get_sized(node, index, sub, 2U);
}
uint32_t co_od_get_u32(co_node_t *node, uint16_t index, uint8_t sub) { return get_sized(node, index, sub, 4U); }

static uint32_t set_local(co_node_t *node, uint16_t index, uint8_t sub, uint32_t value, size_t size)
{
    uint8_t wire[4];
    co_put_u32(wire, value);
    return co_od_write(node, index, sub, wire, size, CO_ORIGIN_LOCAL);
}

uint32_t co_od_set_u8(co_node_t *node, uint16_t index, uint8_t sub, uint8_t value)
{
    return set_local(node, index, sub, value, 1U);
}
uint32_t co_od_set_u16(co_node_t *node, uint16_t index, uint8_t sub, uint16_t value)
{
    return set_local(node, index, sub, value, 2U);
}
uint32_t co_od_set_u32(co_node_t *node, uint16_t index, uint8_t sub, uint32_t value)
{
    return set_local(node, index, sub, value, 4U);
}

void co_od_copy_defaults(const co_od_t *od, uint32_t offset, size_t len, void *dst)
{
    const uint32_t have = od->defaults_size != 0U ? od->defaults_size : od->values_size;
    size_t n = offset < have ? (size_t)(have - offset) : 0U;
    n = n < len ? n : len;
    if (n > 0U) {
        memcpy(dst, (const uint8_t *)od->defaults + offset, n);
    }
    memset((uint8_t *)dst + n, 0, len - n);
}

void co_od_defaults_area(co_node_t *node, uint16_t first, uint16_t last)
{
    const co_od_t *od = node->od;
    for (unsigned i = lower_bound_key(od, entry_key(first, 0U)); i < od->count && od->entries[i].index <= last; i++) {
        const co_od_entry_t *row = &od->entries[i];
        const unsigned subs = co_od_entry_subs(row);
        /* a string's or domain's length with it (runs are numbers: co_od.h) */
        const size_t n = (size_t)row->size * subs + (is_bytes(row) ? CO_OD_LEN_SIZE : 0U);
        co_od_copy_defaults(od, row->offset, n, node->values + row->offset);
        if ((row->flags & CO_OD_NODEID) != 0U && node->node_id != CO_NODE_ID_UNCONFIGURED) {
            for (unsigned k = 0U; k < subs; k++) {
                co_od_entry_t one;
                const co_od_entry_t *e = co_od_entry_at(row, (uint8_t)k, &one);
                co_od_entry_set_u32(node, e, co_od_entry_u32(node, e) + node->node_id);
            }
        }
    }
}

void co_od_reset_area(co_node_t *node, uint16_t first, uint16_t last)
{
    co_od_defaults_area(node, first, last);
    co_store_load_area(node, first, last);
}
