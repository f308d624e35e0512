/**
 * @file eds_pdo.c
 * @brief PDO checks of the EDS reader: communication and mapping objects pair up, every mapping entry names an
 * existing mappable object of the right size and direction (dummy entries only where [DummyUsage] allows),
 * at most 64 bits; sub-index 0 = 0xFE (both ways) or 0xFF (receive) is an MPDO. A PDO whose mapping is wrong is
 * disabled with an empty mapping, so the device still loads. An entry above the count is kept as it is, with a
 * warning where a master could not write it back.
 */
#include "eds_internal.h"

#include <stdlib.h>
#include <string.h>

/* The value a node starts with: a DCF's ParameterValue, else the default. */
static eds_value_t *effective(eds_entry_t *e)
{
    return e->param.kind != EDS_V_NONE ? &e->param : &e->def;
}

/* Objects left out by the PDO checks: marked while checking and removed together at the end (removing each at
 * once moved every entry after it: 2048 PDO objects in a file of many entries took seconds). */
typedef struct dropped {
    uint8_t index[65536U / 8U];
    bool any;
} dropped_t;

static bool is_dropped(const dropped_t *d, uint16_t index)
{
    return ((unsigned)d->index[index / 8U] >> (index % 8U) & 1U) != 0U;
}

static void drop_object(dropped_t *d, uint16_t index)
{
    d->index[index / 8U] = (uint8_t)(d->index[index / 8U] | 1U << (index % 8U));
    d->any = true;
}

/* Checks one mapping entry value; returns its bits, or -1 with a reason. */
static long entry_bits(const eds_file_t *f, const dropped_t *dropped, uint64_t v, bool receive, char *why, size_t cap)
{
    uint16_t index = (uint16_t)(v >> 16);
    uint8_t sub = (uint8_t)(v >> 8), bits = (uint8_t)v;
    if (index >= 0x0001U && index <= 0x0007U && sub == 0U) {
        if (!receive) {
            snprintf(why, cap, "maps dummy 0x%04X into a TPDO (dummy entries are for RPDOs)", (unsigned)index);
            return -1;
        }
        if ((f->dummy_usage & (1U << index)) == 0U) {
            snprintf(why, cap, "maps dummy 0x%04X while [DummyUsage] Dummy%04X is not 1", (unsigned)index, (unsigned)index);
            return -1;
        }
        if (bits != eds_type_size((uint8_t)index) * 8U) {
            snprintf(why, cap, "maps %u bits of dummy 0x%04X, a %u-bit type", (unsigned)bits, (unsigned)index,
                     (unsigned)(eds_type_size((uint8_t)index) * 8U));
            return -1;
        }
        return bits;
    }
    const eds_entry_t *t = is_dropped(dropped, index) ? NULL : eds_find(f, index, sub);
    if (t == NULL) {
        snprintf(why, cap, "maps 0x%04X:%02X, which does not exist", (unsigned)index, (unsigned)sub);
        return -1;
    }
    if (!t->pdo_mapping) {
        snprintf(why, cap, "maps 0x%04X:%02X, which has PDOMapping=0", (unsigned)index, (unsigned)sub);
        return -1;
    }
    if (!eds_access_maps(t->access, receive)) {
        snprintf(why, cap, "maps 0x%04X:%02X (AccessType=%s) into a %cPDO", (unsigned)index, (unsigned)sub,
                 eds_access_name(t->access), receive ? 'R' : 'T');
        return -1;
    }
    size_t size = eds_type_size(t->type);
    if (size == 0U || bits != size * 8U) {
        snprintf(why, cap, "maps %u bits of 0x%04X:%02X, a %u-bit object", (unsigned)bits, (unsigned)index,
                 (unsigned)sub, (unsigned)(size * 8U));
        return -1;
    }
    return bits;
}

/* Disables a PDO: COB-ID bit 31 set, mapping count 0 (the value a node starts with and the default). */
static void disable(eds_file_t *f, uint16_t comm, uint16_t map)
{
    eds_entry_t *cob = eds_find_mut(f, comm, 1U);
    eds_entry_t *count = eds_find_mut(f, map, 0U);
    if (cob != NULL && cob->type == 0x07U) {
        cob->def.u |= 0x80000000U;
        if (cob->param.kind == EDS_V_UINT) {
            cob->param.u |= 0x80000000U;
        }
        cob->high.kind = EDS_V_NONE; /* a HighLimit below bit 31 would refuse the disabled COB-ID */
    }
    if (count != NULL) {
        count->def.u = 0U;
        if (count->param.kind == EDS_V_UINT) {
            count->param.u = 0U;
        }
        /* A LowLimit above 0 would refuse the empty mapping: the written DCF would not read back as written. */
        count->low.kind = EDS_V_NONE;
    }
}

/* Entries above the count of a mapping the node takes: CiA 301 checks the entries up to the count only, so the node
 * keeps them as the file has them, but a master's write of an entry is checked when written (step 3 of the mapping
 * procedure, as CANopenNode and Lely do: docs/decisions.md): one that names what cannot be mapped here could not be
 * written back (issue 35, rule 3: the reader says so at load, by line). */
static void check_above_count(eds_file_t *f, const dropped_t *dropped, uint16_t map, bool receive)
{
    eds_entry_t *count = eds_find_mut(f, map, 0U);
    const eds_value_t *n = effective(count);
    if (n->kind != EDS_V_UINT || n->u == 0xFEU || (n->u == 0xFFU && receive)) {
        return;
    }
    for (unsigned sub = (unsigned)n->u + 1U; sub <= 0x40U; sub++) {
        eds_entry_t *e = eds_find_mut(f, map, (uint8_t)sub);
        const eds_value_t *v = e != NULL ? effective(e) : NULL;
        char why[128];
        if (v == NULL || v->kind != EDS_V_UINT || v->nodeid || e->type != 0x07U || v->u == 0U ||
            entry_bits(f, dropped, v->u, receive, why, sizeof why) >= 0) {
            continue;
        }
        eds_warn(f, e->line, "[%04Xsub%X] 0x%08llX, above the count %llu, %s, which a master cannot write back; "
                 "kept (CiA 301 checks the entries up to the count)", (unsigned)map, sub, (unsigned long long)v->u,
                 (unsigned long long)n->u, why);
    }
}

static void check_mapping(eds_file_t *f, const dropped_t *dropped, uint16_t comm, uint16_t map, bool receive)
{
    eds_entry_t *count = eds_find_mut(f, map, 0U);
    if (count == NULL || count->type != 0x05U) {
        return;
    }
    /* A DCF's mapping (ParameterValue, [xxxxValue]) is the one a node starts with: when it has one, it alone is
     * checked (a Lely-style DCF leaves the defaults 0); otherwise the defaults. */
    bool dcf = count->param.kind != EDS_V_NONE;
    for (unsigned sub = 1U; sub <= 0x40U && !dcf; sub++) {
        const eds_entry_t *e = eds_find(f, map, (uint8_t)sub);
        dcf = e != NULL && e->param.kind != EDS_V_NONE;
    }
    for (int pass = dcf ? 1 : 0; pass < 2; pass++) { /* the default, or a DCF's ParameterValue */
        eds_value_t *n = pass == 0 ? &count->def : effective(count);
        if (n->kind != EDS_V_UINT) {
            continue;
        }
        const char *key = pass == 0 ? "DefaultValue" : "ParameterValue";
        if (n->u == 0xFEU || (n->u == 0xFFU && receive)) {
            continue; /* an MPDO (CiA 301: 0xFE source, 0xFF destination address mode): the entries are not used */
        }
        if (n->u > 0x40U) {
            eds_warn(f, count->line, "[%04Xsub0] %s %llu: a mapping has at most 64 entries; the PDO is disabled",
                     (unsigned)map, key, (unsigned long long)n->u);
            disable(f, comm, map);
            return;
        }
        unsigned bits = 0U;
        for (unsigned sub = 1U; sub <= n->u; sub++) {
            eds_entry_t *e = eds_find_mut(f, map, (uint8_t)sub);
            char why[128];
            if (e == NULL) {
                eds_warn(f, count->line, "[%04Xsub0] %s %llu but sub-index %u is missing; the PDO is disabled",
                         (unsigned)map, key, (unsigned long long)n->u, sub);
                disable(f, comm, map);
                return;
            }
            eds_value_t *v = pass == 0 ? &e->def : effective(e);
            if (v->kind != EDS_V_UINT || v->nodeid || e->type != 0x07U) {
                eds_warn(f, e->line, "[%04Xsub%X] a mapping entry is a plain UNSIGNED32; the PDO is disabled",
                         (unsigned)map, sub);
                disable(f, comm, map);
                return;
            }
            long b = entry_bits(f, dropped, v->u, receive, why, sizeof why);
            if (b < 0) {
                eds_warn(f, e->line, "[%04Xsub%X] %s 0x%08llX %s; the PDO is disabled", (unsigned)map, sub, key,
                         (unsigned long long)v->u, why);
                disable(f, comm, map);
                return;
            }
            bits += (unsigned)b;
        }
        if (bits > 64U) {
            eds_warn(f, count->line, "[%04Xsub0] the mapping (%s) has %u bits, more than 64; the PDO is disabled",
                     (unsigned)map, key, bits);
            disable(f, comm, map);
            return;
        }
    }
    check_above_count(f, dropped, map, receive);
}

/* Leaves the dropped objects out of the model (entries and objects), in one pass. */
static void remove_dropped(eds_file_t *f, const dropped_t *dropped)
{
    uint32_t objects = 0U, entries = 0U;
    for (uint32_t i = 0; i < f->n_objects; i++) {
        eds_object_t o = f->objects[i];
        if (is_dropped(dropped, o.index)) {
            continue;
        }
        memmove(&f->entries[entries], &f->entries[o.first], o.count * sizeof *f->entries);
        o.first = entries;
        entries += o.count;
        f->objects[objects++] = o;
    }
    f->n_objects = objects;
    f->n_entries = entries;
}

/* The types CiA 301 gives the sub-indices of PDO communication and mapping objects (the core relies on them). */
static bool pdo_types_ok(const eds_file_t *f, const eds_object_t *c, const eds_object_t *m, char *why, size_t cap)
{
    static const uint8_t comm_types[7] = {0x05, 0x07, 0x05, 0x06, 0x05, 0x06, 0x05};
    for (uint32_t i = 0; i < c->count; i++) {
        const eds_entry_t *e = &f->entries[c->first + i];
        uint8_t want = e->sub < 7U ? comm_types[e->sub] : 0U;
        if (want != 0U && e->type != want) {
            snprintf(why, cap, "sub-index %u is %s, not %s", (unsigned)e->sub, eds_type_name(e->type), eds_type_name(want));
            return false;
        }
    }
    for (uint32_t i = 0; i < m->count; i++) {
        const eds_entry_t *e = &f->entries[m->first + i];
        uint8_t want = e->sub == 0U ? 0x05U : 0x07U;
        if (e->type != want) {
            snprintf(why, cap, "mapping 0x%04X sub-index %u is %s, not %s", (unsigned)m->index, (unsigned)e->sub,
                     eds_type_name(e->type), eds_type_name(want));
            return false;
        }
    }
    return true;
}

/* Inserts a VAR object of one entry into the sorted model. False when out of memory. */
static bool insert_var(eds_file_t *f, const eds_entry_t *entry)
{
    eds_entry_t *entries = realloc(f->entries, ((size_t)f->n_entries + 1U) * sizeof *entries);
    if (entries == NULL) {
        return false;
    }
    f->entries = entries;
    eds_object_t *objects = realloc(f->objects, ((size_t)f->n_objects + 1U) * sizeof *objects);
    if (objects == NULL) {
        return false;
    }
    f->objects = objects;
    uint32_t at = 0U;
    while (at < f->n_objects && f->objects[at].index < entry->index) {
        at++;
    }
    const uint32_t first = at < f->n_objects ? f->objects[at].first : f->n_entries;
    memmove(&f->entries[first + 1U], &f->entries[first], (f->n_entries - first) * sizeof *f->entries);
    f->entries[first] = *entry;
    f->n_entries++;
    memmove(&f->objects[at + 1U], &f->objects[at], (f->n_objects - at) * sizeof *f->objects);
    eds_object_t *o = &f->objects[at];
    memset(o, 0, sizeof *o);
    o->index = entry->index;
    o->object_type = 0x7U;
    o->name = entry->name;
    o->first = first;
    o->count = 1U;
    o->line = entry->line;
    f->n_objects++;
    for (uint32_t i = at + 1U; i < f->n_objects; i++) {
        f->objects[i].first++;
    }
    return true;
}

/* A synchronous PDO (transmission type 0..240, or a TPDO's 252) waits for SYNC, which the core consumes on the
 * COB-ID of 0x1005: without the object such a PDO never ran. CiA 301's default COB-ID 0x80 is added. */
static void sync_for_synchronous_pdos(eds_file_t *f)
{
    if (eds_find_object(f, 0x1005U) != NULL) {
        return;
    }
    eds_entry_t *first = NULL;
    unsigned synchronous = 0U;
    for (uint32_t i = 0; i < f->n_entries; i++) {
        eds_entry_t *e = &f->entries[i];
        const bool receive = e->index >= 0x1400U && e->index <= 0x15FFU;
        if (e->sub != 2U || e->type != 0x05U || !(receive || (e->index >= 0x1800U && e->index <= 0x19FFU))) {
            continue;
        }
        const uint64_t type = effective(e)->u;
        if (type <= 240U || (!receive && type == 252U)) {
            first = first != NULL ? first : e;
            synchronous++;
        }
    }
    if (first == NULL) {
        return;
    }
    eds_entry_t sync;
    memset(&sync, 0, sizeof sync);
    sync.index = 0x1005U;
    sync.type = 0x07U;
    sync.access = EDS_RW;
    sync.name = "COB-ID SYNC message";
    sync.def.kind = EDS_V_UINT;
    sync.def.u = 0x80U;
    sync.line = first->line;
    const uint16_t index = first->index;
    const uint64_t type = effective(first)->u; /* first moves with the entries: what the warning says, now */
    if (!insert_var(f, &sync)) {
        eds_error(f, 0U, "out of memory");
        return;
    }
    eds_warn(f, sync.line, "[%04Xsub2] transmission type %llu is synchronous%s, but the file has no SYNC object "
             "0x1005; added with CiA 301's default COB-ID 0x80", (unsigned)index, (unsigned long long)type,
             synchronous > 1U ? " (and so are other PDOs of the file)" : "");
}

void eds_check_pdos(eds_file_t *f)
{
    static const struct {
        uint16_t comm, map;
        bool receive;
        const char *key;
    } dirs[] = {{0x1400, 0x1600, true, "NrOfRXPDO"}, {0x1800, 0x1A00, false, "NrOfTXPDO"}};
    dropped_t marks;
    dropped_t *const dropped = &marks;
    memset(dropped, 0, sizeof *dropped);
    for (size_t d = 0; d < 2U; d++) {
        unsigned pdos = 0U;
        for (unsigned n = 0U; n < 0x200U; n++) {
            uint16_t comm = (uint16_t)(dirs[d].comm + n), map = (uint16_t)(dirs[d].map + n);
            const eds_object_t *c = eds_find_object(f, comm), *m = eds_find_object(f, map);
            if (c == NULL && m == NULL) {
                continue;
            }
            if (c == NULL || m == NULL) {
                const eds_object_t *lone = c != NULL ? c : m;
                eds_warn(f, lone->line, "[%04X] has no %s object 0x%04X; left out", (unsigned)lone->index,
                         c != NULL ? "mapping" : "communication", (unsigned)(c != NULL ? map : comm));
                drop_object(dropped, lone->index);
                continue;
            }
            char why[96];
            if (!pdo_types_ok(f, c, m, why, sizeof why)) {
                eds_warn(f, c->line, "[%04X] %s; the PDO (0x%04X and 0x%04X) is left out", (unsigned)comm, why,
                         (unsigned)comm, (unsigned)map);
                drop_object(dropped, comm);
                drop_object(dropped, map);
                continue;
            }
            pdos++;
            check_mapping(f, dropped, comm, map, dirs[d].receive);
        }
        uint16_t *said = dirs[d].receive ? &f->nr_of_rxpdo : &f->nr_of_txpdo;
        if (*said != 0xFFFFU && *said != pdos) {
            eds_warn(f, f->device_info_line, "[DeviceInfo] %s=%u but the file has %u such PDOs; %u used", dirs[d].key, (unsigned)*said,
                     pdos, pdos);
        }
        *said = (uint16_t)pdos;
    }
    if (dropped->any) {
        remove_dropped(f, dropped);
    }
    sync_for_synchronous_pdos(f);
}
