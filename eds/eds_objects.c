/**
 * @file eds_objects.c
 * @brief The model of an EDS/DCF from its sections: device info, object lists, objects and their sub-indices
 * (explicit or CompactSubObj), values, DCF commissioning. Each defect is repaired and reported.
 */
#include "eds_internal.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>

/* An [xxxxObjectLinks] entry with its line, checked once every object is read. */
typedef struct link_ref {
    uint16_t owner, target;
    uint32_t line;
} link_ref_t;

typedef struct builder {
    eds_file_t *f;
    const ini_t *ini;
    size_t cap_entries, cap_objects;
    bool oom;
    uint64_t identity[3];     /* VendorNumber, ProductNumber, RevisionNumber; UINT64_MAX: not in [DeviceInfo] */
    uint32_t *listed_line;    /* line of the object list key that names each index */
    link_ref_t *links;        /* every [xxxxObjectLinks] entry read, in the order of the objects and their links */
    size_t n_links, cap_links;
} builder_t;

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

static const char *text_of(const builder_t *b, const ini_section_t *s, const char *key)
{
    const ini_key_t *k = ini_get(b->ini, s, key);
    return k != NULL ? k->value : NULL;
}

/* An unsigned number key; absent -> dflt silently, malformed -> dflt with a warning. */
static uint64_t number_of(builder_t *b, const ini_section_t *s, const char *key, uint64_t max, uint64_t dflt)
{
    const ini_key_t *k = ini_get(b->ini, s, key);
    if (k == NULL) {
        return dflt;
    }
    uint64_t v;
    const char *text = ini_number_text(b->f, k);
    if (*text == '\0') {
        return dflt;
    }
    if (!eds_parse_unsigned(text, max, &v)) {
        eds_warn(b->f, k->line, "[%s] %s: '%s' is not a number from 0 to %llu; %llu used", s->name, k->key, text,
                 (unsigned long long)max, (unsigned long long)dflt);
        return dflt;
    }
    return v;
}

/* ---- [DeviceInfo], [DummyUsage], [DeviceComissioning], and the keys kept for the writer ----------------------- */

static void read_device_info(builder_t *b)
{
    eds_file_t *f = b->f;
    const ini_section_t *s = ini_find_named(b->ini, "DeviceInfo");
    if (s == NULL) {
        eds_warn(f, 0U, "no [DeviceInfo]; the identity comes from object 0x1018 where it has one");
    } else {
        f->device_info_line = s->line;
    }
    static const char *const required[] = {"VendorName", "VendorNumber", "ProductName", "ProductNumber",
                                           "RevisionNumber", "NrOfRXPDO", "NrOfTXPDO"};
    for (size_t i = 0; s != NULL && i < sizeof required / sizeof required[0]; i++) {
        if (ini_get(b->ini, s, required[i]) == NULL) {
            eds_warn(f, s->line, "[DeviceInfo] has no %s; %s", required[i],
                     strncmp(required[i], "Nr", 2) == 0 ? "counted from the PDO objects" :
                     (strstr(required[i], "Name") != NULL ? "left empty" : "taken from object 0x1018 (or 0)"));
        }
    }
    const char *v = text_of(b, s, "VendorName");
    f->vendor_name = v != NULL ? v : "";
    v = text_of(b, s, "ProductName");
    f->product_name = v != NULL ? v : "";
    /* UINT64_MAX: not given; filled from 0x1018 once the objects are read (identity_from_1018). */
    b->identity[0] = number_of(b, s, "VendorNumber", UINT32_MAX, UINT64_MAX);
    b->identity[1] = number_of(b, s, "ProductNumber", UINT32_MAX, UINT64_MAX);
    b->identity[2] = number_of(b, s, "RevisionNumber", UINT32_MAX, UINT64_MAX);
    f->nr_of_rxpdo = (uint16_t)number_of(b, s, "NrOfRXPDO", 512U, 0xFFFFU);
    f->nr_of_txpdo = (uint16_t)number_of(b, s, "NrOfTXPDO", 512U, 0xFFFFU);
    f->granularity = (uint8_t)number_of(b, s, "Granularity", 64U, 8U);
    f->lss_supported = number_of(b, s, "LSS_Supported", 1U, 0U) != 0U;
    for (unsigned i = 0; i < EDS_CIA305_RATES; i++) {
        char key[24];
        snprintf(key, sizeof key, "BaudRate_%u", (unsigned)eds_cia305_kbit[i]);
        if (eds_cia305_kbit[i] != 0U && number_of(b, s, key, 1U, 0U) != 0U) {
            f->baud_rates = (uint16_t)(f->baud_rates | (1U << i));
        }
    }
    const ini_section_t *d = ini_find_named(b->ini, "DummyUsage");
    for (unsigned t = 1U; t <= 7U; t++) {
        char key[16];
        snprintf(key, sizeof key, "Dummy%04X", t);
        if (number_of(b, d, key, 1U, 0U) != 0U) {
            f->dummy_usage = (uint8_t)(f->dummy_usage | (1U << t));
        }
    }
    const ini_section_t *c = ini_find_named(b->ini, "DeviceComissioning");
    if (c == NULL) {
        c = ini_find_named(b->ini, "DeviceCommissioning");
        if (c != NULL) {
            eds_warn(f, c->line, "[DeviceCommissioning]: CiA 306 spells it [DeviceComissioning]; read as such");
        }
    }
    if (c != NULL) {
        f->is_dcf = true;
        f->comm.present = true;
        const ini_key_t *node_id = ini_get(b->ini, c, "NodeID");
        const char *id_text = node_id != NULL ? ini_number_text(f, node_id) : "";
        f->comm.node_id_given = *id_text != '\0';
        uint64_t id = 0U;
        if (f->comm.node_id_given && (!eds_parse_unsigned(id_text, UINT64_MAX, &id) || id < 1U || id > 127U)) {
            /* 0 and 255 too (255: how some tools write "not configured"): the node-ID must come from elsewhere */
            eds_warn(f, node_id->line, "[DeviceComissioning] NodeID=%s is not a node-ID (1..127); ignored", id_text);
            id = 0U;
        }
        f->comm.node_id = (uint8_t)id;
        f->comm.baudrate_kbit = (uint16_t)number_of(b, c, "Baudrate", 1000U, 0U);
        f->comm.node_name = text_of(b, c, "NodeName");
        f->comm.net_number = (uint32_t)number_of(b, c, "NetNumber", UINT32_MAX, 0U);
        f->comm.network_name = text_of(b, c, "NetworkName");
        f->comm.canopen_manager = number_of(b, c, "CANopenManager", 1U, 0U) != 0U;
        f->comm.lss_serial_number = (uint32_t)number_of(b, c, "LSS_SerialNumber", UINT32_MAX, 0U);
    }
    /* [FileInfo], [DeviceInfo] and [Comments] as written, for the writer (each section looked up once: a look-up
     * per key made a file of many sections take quadratic time). */
    static const char *const kept[] = {"FileInfo", "DeviceInfo", "Comments"};
    const ini_section_t *kept_section[3];
    size_t n = 0U;
    for (size_t j = 0; j < 3U; j++) {
        kept_section[j] = ini_find_named(b->ini, kept[j]);
        n += kept_section[j] != NULL ? kept_section[j]->count : 0U;
    }
    f->info = eds_alloc(f, (n + 1U) * sizeof *f->info);
    for (uint32_t i = 0; f->info != NULL && i < b->ini->n_keys; i++) {
        const ini_key_t *k = &b->ini->file_order[i];
        const ini_section_t *sec = &b->ini->sections[k->section];
        for (size_t j = 0; j < 3U; j++) {
            if (sec == kept_section[j]) {
                f->info[f->n_info].section = kept[j];
                f->info[f->n_info].key = k->key;
                f->info[f->n_info].value = k->value;
                f->n_info++;
            }
        }
    }
}

/* ---- Object lists ------------------------------------------------------------------------------------------------- */

static int u16_cmp(const void *a, const void *b)
{
    return (int)*(const uint16_t *)a - (int)*(const uint16_t *)b;
}

typedef struct list_item {
    uint32_t pos;
    const ini_key_t *key;
} list_item_t;

static int item_cmp(const void *a, const void *b)
{
    uint32_t x = ((const list_item_t *)a)->pos, y = ((const list_item_t *)b)->pos;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* The indices the object lists name, sorted and unique; sections no list names are added (with a warning). */
static uint16_t *object_indices(builder_t *b, uint32_t *count)
{
    eds_file_t *f = b->f;
    static const char *const lists[] = {"MandatoryObjects", "OptionalObjects", "ManufacturerObjects"};
    uint8_t *listed = eds_alloc(f, 65536U);
    uint16_t *out = eds_alloc(f, 65536U * sizeof(uint16_t));
    b->listed_line = eds_alloc(f, 65536U * sizeof(uint32_t));
    uint32_t n = 0U;
    if (listed == NULL || out == NULL || b->listed_line == NULL) {
        b->oom = true;
        return NULL;
    }
    bool any_list = false;
    for (size_t l = 0; l < 3U; l++) {
        const ini_section_t *s = ini_find_named(b->ini, lists[l]);
        if (s == NULL) {
            continue;
        }
        any_list = true;
        uint64_t supported = number_of(b, s, "SupportedObjects", 65535U, 0U);
        /* The keys are sorted as text ("10" before "2"): take them in the order of their numbers. */
        list_item_t *items = eds_alloc(f, ((size_t)s->count + 1U) * sizeof *items);
        if (items == NULL) {
            b->oom = true;
            return NULL;
        }
        uint32_t found = 0U;
        for (uint32_t i = s->first; i < s->first + s->count; i++) {
            const ini_key_t *k = &b->ini->keys[i];
            uint64_t pos;
            if (!eds_parse_unsigned(k->key, 65535U, &pos)) {
                if (k != ini_get(b->ini, s, "SupportedObjects")) {
                    eds_warn(f, k->line, "[%s] %s: not a position number; ignored", lists[l], k->key);
                }
                continue;
            }
            items[found].pos = (uint32_t)pos;
            items[found].key = k;
            found++;
        }
        qsort(items, found, sizeof *items, item_cmp);
        long previous = -1;
        bool warned_order = false;
        for (uint32_t i = 0; i < found; i++) {
            const ini_key_t *k = items[i].key;
            uint64_t index;
            if (items[i].pos == 0U || items[i].pos > supported) {
                eds_warn(f, k->line, "[%s] %s: position outside 1..SupportedObjects (%llu); the object is read anyway",
                         lists[l], k->key, (unsigned long long)supported);
            }
            const char *text = ini_number_text(f, k);
            if (!eds_parse_unsigned(text, 0xFFFFU, &index)) {
                eds_warn(f, k->line, "[%s] %s: '%s' is not an object index; ignored", lists[l], k->key, text);
                continue;
            }
            if (listed[index] != 0U) {
                eds_warn(f, k->line, "[%s] %s: object 0x%04llX is listed twice; read once", lists[l], k->key,
                         (unsigned long long)index);
                continue;
            }
            if ((long)index < previous && !warned_order) {
                eds_warn(f, k->line, "[%s] %s: object 0x%04llX out of order (after 0x%04lX); the objects are sorted",
                         lists[l], k->key, (unsigned long long)index, previous);
                warned_order = true;
            }
            previous = (long)index;
            listed[index] = 1U;
            b->listed_line[index] = k->line;
            out[n++] = (uint16_t)index;
        }
        if (found != supported) {
            eds_warn(f, s->line, "[%s] SupportedObjects=%llu but %lu entries are listed; the listed ones are read",
                     lists[l], (unsigned long long)supported, (unsigned long)found);
        }
    }
    if (!any_list) {
        eds_warn(f, 0U, "no object lists ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects]); every "
                        "object section is read");
    }
    for (uint32_t i = 0; i < b->ini->n_sections; i++) {
        const ini_section_t *s = &b->ini->sections[i];
        if (s->kind == INI_OBJECT && listed[s->index] == 0U) {
            if (any_list) {
                eds_warn(f, s->line, "[%s] is in no object list; read as an object of the device", s->name);
            }
            listed[s->index] = 1U;
            out[n++] = s->index;
        }
    }
    qsort(out, n, sizeof *out, u16_cmp);
    *count = n;
    return out;
}

/* ---- Entries ------------------------------------------------------------------------------------------------------- */

static bool read_access(builder_t *b, const ini_section_t *s, eds_access_t *out)
{
    const ini_key_t *k = ini_get(b->ini, s, "AccessType");
    if (k == NULL) {
        eds_warn(b->f, s->line, "[%s] has no AccessType; ro used", s->name);
        *out = EDS_RO;
        return true;
    }
    char a[8];
    size_t n = strlen(k->value);
    for (size_t i = 0; i < n && i < sizeof a - 1U; i++) {
        a[i] = (char)tolower((unsigned char)k->value[i]);
    }
    a[n < sizeof a - 1U ? n : sizeof a - 1U] = '\0';
    static const char *const names[] = {"ro", "wo", "rw", "rwr", "rww", "const"};
    for (unsigned i = 0; i < 6U && n < sizeof a; i++) {
        if (strcmp(a, names[i]) == 0) {
            *out = (eds_access_t)i;
            return true;
        }
    }
    if (strcmp(a, "r") == 0 || strcmp(a, "w") == 0) {
        *out = a[0] == 'r' ? EDS_RO : EDS_WO;
        eds_warn(b->f, k->line, "[%s] AccessType=%s is not CiA 306; read as %s", s->name, k->value, eds_access_name(*out));
        return true;
    }
    eds_warn(b->f, k->line, "[%s] AccessType=%s is not ro, wo, rw, rwr, rww or const; ro used", s->name, k->value);
    *out = EDS_RO;
    return true;
}

static void read_value(builder_t *b, const ini_section_t *s, const ini_key_t *k, const char *text, uint8_t type,
                       eds_value_t *out, bool allow_nodeid)
{
    char why[160];
    eds_parse_t r = eds_parse_value(b->f, type, text, out, why, sizeof why);
    char used[96];
    if (r == EDS_PARSE_BAD) {
        eds_parse_value(b->f, type, "", out, why + strlen(why), 0U);
        eds_warn(b->f, k->line, "[%s] %s: '%s' %s; %s used", s->name, k->key, text, why,
                 eds_type_is_bytes(type) ? "an empty value" : "0");
        return;
    }
    if (r == EDS_PARSE_RANGE) {
        eds_format_value(used, sizeof used, type, out);
        eds_warn(b->f, k->line, "[%s] %s: '%s' %s; %s used", s->name, k->key, text, why, used);
        return;
    }
    if (why[0] != '\0') {
        eds_warn(b->f, k->line, "[%s] %s: '%s' %s", s->name, k->key, text, why);
    }
    if (out->nodeid && !allow_nodeid) {
        out->nodeid = false;
        eds_warn(b->f, k->line, "[%s] %s: a limit cannot depend on the node-ID; '%s' read without $NODEID", s->name,
                 k->key, text);
    }
    if (type == 0x09) {
        for (size_t i = 0; i < out->len; i++) {
            if (out->bytes[i] >= 0x7FU || out->bytes[i] < 0x20U) {
                eds_warn(b->f, k->line, "[%s] %s: VISIBLE_STRING with %s (ISO 646 has neither); kept as it is",
                         s->name, k->key, out->bytes[i] >= 0x80U ? "non-ASCII text" : "a control character");
                break;
            }
        }
    }
}

/* The value text of a key: strings verbatim, numbers without an inline comment. */
static const char *value_text(builder_t *b, const ini_key_t *k, uint8_t type)
{
    return eds_type_is_bytes(type) ? k->value : ini_number_text(b->f, k);
}

/* A value outside the limits would be refused when stored and loaded again: it is moved into them. */
static void into_limits(eds_file_t *f, const ini_section_t *s, const eds_entry_t *e, eds_value_t *v, const char *key,
                        uint32_t line, bool empty)
{
    for (int i = 0; i < 2 && !eds_type_is_bytes(e->type) && !v->nodeid; i++) {
        const eds_value_t *lim = i == 0 ? &e->low : &e->high;
        if (lim->kind == EDS_V_NONE || (i == 0 ? eds_value_cmp(v, lim) >= 0 : eds_value_cmp(v, lim) <= 0)) {
            continue;
        }
        char was[64], now[64];
        eds_format_value(was, sizeof was, e->type, v);
        *v = *lim;
        eds_format_value(now, sizeof now, e->type, v);
        eds_warn(f, line, "[%s] %s %s is outside LowLimit..HighLimit; %s (the %s) used", s->name, key,
                 empty ? "(none, so 0)" : was, now, i == 0 ? "LowLimit" : "HighLimit");
    }
}

/* The DCF value of an entry: value_key (the [xxxxValue] key of a compact sub-object), else its ParameterValue. */
static void read_param(builder_t *b, const ini_section_t *s, const ini_key_t *value_key, eds_entry_t *e)
{
    const ini_key_t *k = value_key != NULL ? value_key : ini_get(b->ini, s, "ParameterValue");
    if (k != NULL) {
        b->f->is_dcf = true;
        /* An empty number is no value (Lely and python-canopen keep the default); it used to become 0, and a DCF
         * with "ParameterValue=" everywhere started with SYNC COB-ID 0 and vendor-ID 0. An empty string is the
         * empty string (python-canopen reads it so, and export-dcf writes a string emptied over SDO so). */
        if (!eds_type_is_bytes(e->type) && *value_text(b, k, e->type) == '\0') {
            char def[64];
            eds_format_value(def, sizeof def, e->type, &e->def);
            eds_warn(b->f, k->line, "[%s%s] %s is empty; DefaultValue %s kept", s->name,
                     value_key != NULL ? "Value" : "", k->key, def);
            return;
        }
        read_value(b, s, k, value_text(b, k, e->type), e->type, &e->param, true);
        into_limits(b->f, s, e, &e->param, k->key, k->line, false);
    }
}

/*
 * Reads an entry but for its DCF value from section s (for CompactSubObj objects, the object's own section). name
 * overrides ParameterName (compact sub-objects). Returns false when the entry cannot be emulated (unknown data
 * type): the caller leaves it out.
 */
static bool read_fields(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
                        uint8_t default_type, eds_entry_t *e)
{
    eds_file_t *f = b->f;
    memset(e, 0, sizeof *e);
    e->index = index;
    e->sub = sub;
    e->line = s->line;
    const ini_key_t *k;
    e->name = name != NULL ? name : text_of(b, s, "ParameterName");
    if (e->name == NULL) {
        char buf[32];
        snprintf(buf, sizeof buf, sub == 0U ? "Object %04X" : "Object %04X sub %u", (unsigned)index, (unsigned)sub);
        eds_warn(f, s->line, "[%s] has no ParameterName; '%s' used", s->name, buf);
        e->name = eds_strndup(f, buf, strlen(buf));
    }
    e->denotation = text_of(b, s, "Denotation");
    k = ini_get(b->ini, s, "DataType");
    uint64_t type = default_type;
    if (k == NULL && default_type == 0U) {
        eds_warn(f, s->line, "[%s] has no DataType; the entry is left out", s->name);
        return false;
    }
    const char *tt = k != NULL ? ini_number_text(f, k) : "0x000F";
    if (k != NULL && (!eds_parse_unsigned(tt, 0xFFFFU, &type) || type > 0xFFU || eds_type_name((uint8_t)type) == NULL)) {
        eds_warn(f, k->line, "[%s] DataType=%s is not a CiA 301 basic data type this reader knows; the entry is "
                             "left out", s->name, tt);
        return false;
    }
    e->type = (uint8_t)type;
    read_access(b, s, &e->access);
    k = ini_get(b->ini, s, "PDOMapping");
    if (k != NULL) {
        const char *t = ini_number_text(f, k);
        uint64_t flag = 0U;
        /* A number in any CiA 306 form: python-canopen's export writes 0x0 and 0x1. */
        if (*t == '\0' || eds_parse_unsigned(t, 1U, &flag)) {
            e->pdo_mapping = flag != 0U;
        } else {
            e->pdo_mapping = t[0] == 't' || t[0] == 'T';
            eds_warn(f, k->line, "[%s] PDOMapping=%s is not 0 or 1; read as %d", s->name, t, e->pdo_mapping ? 1 : 0);
        }
    }
    static const char *const limit_keys[] = {"LowLimit", "HighLimit"};
    for (int i = 0; i < 2; i++) {
        k = ini_get(b->ini, s, limit_keys[i]);
        if (k == NULL || k->value[0] == '\0') {
            continue;
        }
        if (eds_type_is_bytes(e->type)) {
            eds_warn(f, k->line, "[%s] %s on a %s; ignored", s->name, k->key, eds_type_name(e->type));
            continue;
        }
        read_value(b, s, k, value_text(b, k, e->type), e->type, i == 0 ? &e->low : &e->high, false);
    }
    if (e->low.kind != EDS_V_NONE && e->high.kind != EDS_V_NONE && eds_value_cmp(&e->low, &e->high) > 0) {
        char lo[64], hi[64];
        eds_format_value(lo, sizeof lo, e->type, &e->low);
        eds_format_value(hi, sizeof hi, e->type, &e->high);
        eds_warn(f, s->line, "[%s] LowLimit %s > HighLimit %s; both ignored", s->name, lo, hi);
        e->low.kind = EDS_V_NONE;
        e->high.kind = EDS_V_NONE;
    }
    k = ini_get(b->ini, s, "DefaultValue");
    if (k != NULL) {
        read_value(b, s, k, value_text(b, k, e->type), e->type, &e->def, true);
    } else {
        eds_parse_value(f, e->type, "", &e->def, (char[8]){0}, 8U);
    }
    bool empty = k == NULL || k->value[0] == '\0';
    into_limits(f, s, e, &e->def, "DefaultValue", k != NULL ? k->line : s->line, empty);
    return true;
}

static bool read_entry(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
                       uint8_t default_type, eds_entry_t *e)
{
    if (!read_fields(b, s, index, sub, name, default_type, e)) {
        return false;
    }
    read_param(b, s, NULL, e);
    return true;
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
    if (!read_fields(b, s, o->index, 1U, "", 0U, &shared)) {
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
            read_param(b, s, value_key, e);
        } else if (own_param_read) {
            e->param = own_param;
        } else {
            read_param(b, s, NULL, e);
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
        if (read_entry(b, s, index, 0U, o->name, otype == 0x2U ? 0x0FU : 0U, &tmp)) {
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
            if (read_entry(b, ss, index, sub, NULL, 0U, &tmp)) {
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
    read_device_info(&b);
    uint32_t n = 0U;
    uint16_t *indices = object_indices(&b, &n);
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
