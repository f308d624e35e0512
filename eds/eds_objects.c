/**
 * @file eds_objects.c
 * @brief The model of an EDS/DCF from its sections: objects and their sub-indices (explicit or CompactSubObj), then
 * the whole model (sorted, links checked, identity). Each defect is repaired and reported. The device's own sections
 * and the object lists: eds_info.c; one entry's keys: eds_entries.c.
 */
#include "eds_builder.h"

#include <stdlib.h>
#include <string.h>

static void push_link(builder_t *b, uint16_t owner, uint16_t target, uint32_t line)
{
    if (b->n_links == b->cap_links) {
        size_t cap = b->cap_links == 0U ? 64U : b->cap_links * 2U;
        link_ref_t *l = realloc(b->links, cap * sizeof *l);
        if (l == NULL) {
            b->oom = true;
            return;
        }
        b->links = l;
        b->cap_links = cap;
    }
    b->links[b->n_links++] = (link_ref_t){owner, target, line};
}

static eds_entry_t *push_entry(builder_t *b)
{
    eds_file_t *f = b->f;
    if (f->n_entries == b->cap_entries) {
        size_t cap = b->cap_entries == 0U ? 256U : b->cap_entries * 2U;
        eds_entry_t *e = realloc(f->entries, cap * sizeof *e);
        if (e == NULL) {
            b->oom = true;
            return NULL;
        }
        f->entries = e;
        b->cap_entries = cap;
    }
    eds_entry_t *e = &f->entries[f->n_entries++];
    memset(e, 0, sizeof *e);
    return e;
}

static eds_object_t *push_object(builder_t *b)
{
    eds_file_t *f = b->f;
    if (f->n_objects == b->cap_objects) {
        size_t cap = b->cap_objects == 0U ? 64U : b->cap_objects * 2U;
        eds_object_t *o = realloc(f->objects, cap * sizeof *o);
        if (o == NULL) {
            b->oom = true;
            return NULL;
        }
        f->objects = o;
        b->cap_objects = cap;
    }
    eds_object_t *o = &f->objects[f->n_objects++];
    memset(o, 0, sizeof *o);
    return o;
}

static bool is_mapping(uint16_t index)
{
    return (index >= 0x1600U && index <= 0x17FFU) || (index >= 0x1A00U && index <= 0x1BFFU);
}

/* Sub-index 0 of a PDO mapping that lacks it: the number of entries from sub-index 1 on that map something (the
 * highest sub-index counted the unused entries too, so the PDO was disabled for mapping 0x0000:00), writable
 * where the entries are (dynamic mapping); a DCF's value likewise from the entries' values. */
static void mapping_count(const eds_entry_t *subs, uint32_t n, eds_entry_t *sub0)
{
    bool any_param = false;
    for (uint32_t i = 0; i < n; i++) {
        any_param = any_param || subs[i].param.kind != EDS_V_NONE;
    }
    for (int pass = 0; pass < (any_param ? 2 : 1); pass++) {
        uint64_t count = 0U;
        for (uint32_t i = 0; i < n && subs[i].sub == count + 1U; i++) {
            const eds_value_t *v = pass == 1 && subs[i].param.kind != EDS_V_NONE ? &subs[i].param : &subs[i].def;
            if (v->kind != EDS_V_UINT || v->nodeid || v->u == 0U) {
                break;
            }
            count++;
        }
        eds_value_t *out = pass == 0 ? &sub0->def : &sub0->param;
        out->kind = EDS_V_UINT;
        out->u = count;
    }
    sub0->access = n > 0U && eds_access_writable(subs[0].access) ? EDS_RW : EDS_RO;
}

/* Sub-index 0 of an ARRAY/RECORD counts active entries rather than giving the highest sub-index. */
static bool counts_entries(uint16_t index)
{
    return index == 0x1003U || (index >= 0x1600U && index <= 0x17FFU) || (index >= 0x1A00U && index <= 0x1BFFU) ||
           index == 0x1F81U || index == 0x1016U;
}

static void read_compact(builder_t *b, const ini_section_t *s, eds_object_t *o, uint64_t n)
{
    eds_file_t *f = b->f;
    uint32_t first = f->n_entries;
    eds_entry_t *e = push_entry(b);
    if (e == NULL) {
        return;
    }
    e->index = o->index;
    e->line = s->line;
    e->name = "NrOfObjects";
    e->type = 0x05;
    e->access = EDS_RO;
    e->def.kind = EDS_V_UINT;
    e->def.u = n;
    /* The sub-indices share the object's type, access, limits and default: read once (reading them for each
     * sub-index copied a long string default up to 254 times: a file of 16 MiB took gigabytes). */
    eds_entry_t shared;
    if (!eds_read_fields(b, s, o->index, 1U, "", 0U, &shared)) {
        f->n_entries = first; /* the object goes: sub-index 0 too */
        return;
    }
    const ini_section_t *names = ini_find(b->ini, INI_NAME, o->index, 0U);
    const ini_section_t *values = ini_find(b->ini, INI_VALUE, o->index, 0U);
    bool own_param_read = false; /* the object's ParameterValue: the value of each sub-index [xxxxValue] lacks */
    eds_value_t own_param;
    for (unsigned sub = 1U; sub <= n; sub++) {
        char key[8];
        snprintf(key, sizeof key, "%u", sub);
        const char *name = text_of(b, names, key);
        if (name == NULL) {
            /* Sized to the name, not cut: a cut could split a UTF-8 sequence (the written DCF would not be UTF-8). */
            const size_t cap = strlen(o->name) + sizeof key;
            char *formed = eds_alloc(f, cap);
            if (formed == NULL) {
                return;
            }
            snprintf(formed, cap, "%s%u", o->name, sub);
            name = formed;
        }
        e = push_entry(b);
        if (e == NULL) {
            return;
        }
        *e = shared;
        e->sub = (uint8_t)sub;
        e->name = name;
        const ini_key_t *value_key = ini_get(b->ini, values, key);
        if (value_key != NULL) {
            eds_read_param(b, s, value_key, e);
        } else if (own_param_read) {
            e->param = own_param;
        } else {
            eds_read_param(b, s, NULL, e);
            own_param = e->param;
            own_param_read = true;
        }
    }
}

/* The ObjectType of a section without one: CiA 306 makes it a VAR, but an object with sub-index sections is a
 * RECORD (read as a VAR it had no DataType and was left out: a [1018] so made the file "miss object 0x1018"), one
 * with CompactSubObj an ARRAY (CompactSubObj is for ARRAYs only). */
static uint64_t without_object_type(builder_t *b, const ini_section_t *s)
{
    uint32_t n_subs;
    (void)ini_find_subs(b->ini, s->index, &n_subs);
    const ini_key_t *compact_key = ini_get(b->ini, s, "CompactSubObj"); /* read (and warned about) later */
    uint64_t zero = 1U;
    const bool compact = compact_key != NULL && compact_key->value[0] != '\0' &&
                         !(eds_parse_unsigned(compact_key->value, UINT64_MAX, &zero) && zero == 0U);
    if (n_subs == 0U && !compact) {
        return 0x7U;
    }
    eds_warn(b->f, s->line, "[%s] has no ObjectType but %s; read as %s", s->name,
             compact ? "CompactSubObj" : "sub-index sections", compact ? "an ARRAY (0x8)" : "a RECORD (0x9)");
    return compact ? 0x8U : 0x9U;
}

static void read_object(builder_t *b, uint16_t index)
{
    eds_file_t *f = b->f;
    const ini_section_t *s = ini_find(b->ini, INI_OBJECT, index, 0U);
    if (s == NULL) {
        eds_warn(f, b->listed_line[index], "object 0x%04X is listed but has no section [%04X]; left out", (unsigned)index,
                 (unsigned)index);
        return;
    }
    uint64_t otype = number_of(b, s, "ObjectType", 0xFFU, 0x7U);
    const ini_key_t *otype_key = ini_get(b->ini, s, "ObjectType");
    if (otype_key == NULL || otype_key->value[0] == '\0') {
        otype = without_object_type(b, s);
    }
    if (otype == 0x0U) {
        eds_warn(f, s->line, "[%s] ObjectType=0 (NULL): nothing to emulate; left out", s->name);
        return;
    }
    if (otype != 0x2U && (otype < 0x5U || otype > 0x9U)) {
        eds_warn(f, s->line, "[%s] ObjectType=0x%llX is not DOMAIN, DEFTYPE, DEFSTRUCT, VAR, ARRAY or RECORD; left out",
                 s->name, (unsigned long long)otype);
        return;
    }
    uint32_t before = f->n_entries;
    eds_object_t *o = push_object(b);
    if (o == NULL) {
        return;
    }
    o->index = index;
    o->object_type = (uint8_t)otype;
    o->line = s->line;
    o->name = text_of(b, s, "ParameterName");
    if (o->name == NULL) {
        o->name = "";
    }
    o->denotation = text_of(b, s, "Denotation");
    const ini_section_t *links = ini_find(b->ini, INI_LINKS, index, 0U);
    if (links != NULL) {
        uint64_t nl = number_of(b, links, "ObjectLinks", 0xFFFFU, 0U);
        o->links = eds_alloc(f, (size_t)(nl + 1U) * sizeof(uint16_t));
        for (unsigned i = 1U; o->links != NULL && i <= nl; i++) {
            char key[8];
            snprintf(key, sizeof key, "%u", i);
            uint64_t v = number_of(b, links, key, 0xFFFFU, 0x10000U);
            if (v <= 0xFFFFU) {
                o->links[o->n_links++] = (uint16_t)v;
                push_link(b, index, (uint16_t)v, ini_get(b->ini, links, key)->line);
            }
        }
    }
    /* DOMAIN and DEFTYPE objects are one value like a VAR; DEFSTRUCT has sub-indices like a RECORD. */
    bool var = otype == 0x7U || otype == 0x2U || otype == 0x5U;
    uint64_t compact = number_of(b, s, "CompactSubObj", 0xFEU, 0U);
    o->compact = (uint8_t)compact;
    if (var) {
        if (compact != 0U || ini_get(b->ini, s, "SubNumber") != NULL) {
            eds_warn(f, s->line, "[%s] a VAR has no sub-indices; SubNumber/CompactSubObj ignored", s->name);
        }
        eds_entry_t tmp;
        /* a DOMAIN object may omit its data type */
        if (eds_read_entry(b, s, index, 0U, o->name, otype == 0x2U ? 0x0FU : 0U, &tmp)) {
            eds_entry_t *e = push_entry(b);
            if (e != NULL) {
                *e = tmp;
            }
        }
    } else if (compact != 0U) {
        read_compact(b, s, o, compact);
    } else {
        uint8_t highest = 0U;
        uint32_t n_subs;
        const ini_section_t *subs = ini_find_subs(b->ini, index, &n_subs);
        for (uint32_t i = 0; i < n_subs; i++) {
            const ini_section_t *ss = &subs[i];
            const uint8_t sub = ss->sub;
            eds_entry_t tmp;
            if (eds_read_entry(b, ss, index, sub, NULL, 0U, &tmp)) {
                eds_entry_t *e = push_entry(b);
                if (e == NULL) {
                    return;
                }
                *e = tmp;
                highest = sub;
            }
        }
        uint32_t got = f->n_entries - before;
        uint64_t subnumber = number_of(b, s, "SubNumber", 0xFFFFU, got);
        if (got == 0U) {
            eds_warn(f, s->line, "[%s] an %s without sub-index sections; left out", s->name,
                     otype == 0x8U ? "ARRAY" : "RECORD");
        } else if (subnumber != got) {
            eds_warn(f, s->line, "[%s] SubNumber=%llu but %lu sub-index sections are usable; those are read", s->name,
                     (unsigned long long)subnumber, (unsigned long)got);
        }
        eds_entry_t *sub0 = got > 0U ? &f->entries[before] : NULL;
        if (sub0 != NULL && sub0->sub != 0U) {
            eds_entry_t added;
            memset(&added, 0, sizeof added);
            added.index = index;
            added.line = s->line;
            added.name = "Highest sub-index supported";
            added.type = 0x05;
            added.access = EDS_RO;
            added.def.kind = EDS_V_UINT;
            added.def.u = highest;
            if (is_mapping(index)) {
                mapping_count(&f->entries[before], f->n_entries - before, &added);
                eds_warn(f, s->line, "[%s] has no sub-index 0; added as the number of mapping entries present "
                         "(UNSIGNED8, %s, %u)", s->name, eds_access_name(added.access), (unsigned)added.def.u);
            } else {
                eds_warn(f, s->line, "[%s] has no sub-index 0; added (UNSIGNED8, ro, %u)", s->name, (unsigned)highest);
            }
            eds_entry_t *e = push_entry(b);
            if (e == NULL) {
                return;
            }
            *e = added;
            sub0 = NULL;
        }
        if (sub0 != NULL && sub0->type != 0x05U) {
            eds_warn(f, sub0->line, "[%ssub0] sub-index 0 of an ARRAY/RECORD is UNSIGNED8, not %s; read as UNSIGNED8",
                     s->name, eds_type_name(sub0->type));
            uint64_t v = sub0->def.kind == EDS_V_UINT ? sub0->def.u : (sub0->def.kind == EDS_V_INT && sub0->def.i > 0 ? (uint64_t)sub0->def.i : 0U);
            memset(&sub0->def, 0, sizeof sub0->def);
            sub0->def.kind = EDS_V_UINT;
            sub0->def.u = v > 0xFFU ? 0xFFU : v;
            sub0->type = 0x05;
            sub0->low.kind = sub0->high.kind = sub0->param.kind = EDS_V_NONE;
        }
        if (sub0 != NULL && sub0->def.u < highest && !counts_entries(index)) {
            eds_warn(f, sub0->line, "[%ssub0] DefaultValue %llu is below the highest sub-index %u; kept (the "
                                    "sub-indices above it still answer)", s->name, (unsigned long long)sub0->def.u,
                     (unsigned)highest);
        }
    }
    if (f->n_entries == before) {
        f->n_objects--;
    }
}

/* ---- The whole model ----------------------------------------------------------------------------------------------- */

static int entry_cmp(const void *pa, const void *pb)
{
    const eds_entry_t *a = pa, *b = pb;
    if (a->index != b->index) {
        return a->index < b->index ? -1 : 1;
    }
    return (int)a->sub - (int)b->sub;
}

static void orphan_subs(builder_t *b)
{
    for (uint32_t i = 0; i < b->ini->n_sections; i++) {
        const ini_section_t *s = &b->ini->sections[i];
        if ((s->kind == INI_SUB || s->kind == INI_NAME || s->kind == INI_VALUE) &&
            eds_find_object(b->f, s->index) == NULL) {
            eds_warn(b->f, s->line, "[%s] belongs to no object of the device; ignored", s->name);
        }
    }
}

/* Links to objects the device does not have are left out with a warning (they were kept, naming nothing). The
 * entries of b->links are in the order of the objects (read by index) and of each object's links. */
static void check_links(builder_t *b)
{
    size_t r = 0U;
    for (uint32_t i = 0; i < b->f->n_objects; i++) {
        eds_object_t *o = &b->f->objects[i];
        while (r < b->n_links && b->links[r].owner < o->index) {
            r++; /* links of an object that was left out */
        }
        uint16_t kept = 0U;
        for (uint16_t k = 0U; k < o->n_links; k++, r++) {
            if (eds_find_object(b->f, o->links[k]) != NULL) {
                o->links[kept++] = o->links[k];
            } else if (r < b->n_links) {
                eds_warn(b->f, b->links[r].line, "[%04XObjectLinks] names object 0x%04X, which the device does not "
                         "have; the link is left out", (unsigned)o->index, (unsigned)o->links[k]);
            }
        }
        o->n_links = kept;
    }
}

/* The identity numbers [DeviceInfo] lacks, from 0x1018 sub 1..3 (a device's own statement of them). */
static void identity_from_1018(builder_t *b)
{
    uint32_t *fields[3] = {&b->f->vendor_number, &b->f->product_number, &b->f->revision_number};
    for (uint8_t i = 0; i < 3U; i++) {
        const eds_entry_t *e = eds_find(b->f, 0x1018U, (uint8_t)(i + 1U));
        if (b->identity[i] != UINT64_MAX) {
            *fields[i] = (uint32_t)b->identity[i];
        } else if (e != NULL && e->def.kind == EDS_V_UINT) {
            *fields[i] = (uint32_t)e->def.u;
        }
    }
}

void eds_read_model(eds_file_t *f, const ini_t *ini)
{
    builder_t b;
    memset(&b, 0, sizeof b);
    b.f = f;
    b.ini = ini;
    eds_read_device_info(&b);
    uint32_t n = 0U;
    uint16_t *indices = eds_object_indices(&b, &n);
    for (uint32_t i = 0; indices != NULL && i < n && !b.oom; i++) {
        read_object(&b, indices[i]);
    }
    if (b.oom) {
        free(b.links);
        eds_error(f, 0U, "out of memory");
        return;
    }
    if (f->n_entries > 0U) {
        qsort(f->entries, f->n_entries, sizeof *f->entries, entry_cmp);
    }
    uint32_t e = 0U;
    for (uint32_t i = 0; i < f->n_objects; i++) { /* objects were read in index order */
        eds_object_t *o = &f->objects[i];
        while (e < f->n_entries && f->entries[e].index < o->index) {
            e++;
        }
        o->first = e;
        while (e < f->n_entries && f->entries[e].index == o->index) {
            e++;
        }
        o->count = (uint16_t)(e - o->first);
    }
    orphan_subs(&b);
    check_links(&b);
    free(b.links);
    identity_from_1018(&b);
    if (f->n_objects == 0U) {
        eds_error(f, 0U, "no objects: not a device description");
        return;
    }
    static const uint16_t mandatory[] = {0x1000, 0x1001, 0x1018};
    for (size_t i = 0; i < 3U; i++) {
        if (eds_find_object(f, mandatory[i]) == NULL) {
            eds_error(f, 0U, "object 0x%04X is missing; every CANopen device has it (CiA 301)", (unsigned)mandatory[i]);
        }
    }
}
