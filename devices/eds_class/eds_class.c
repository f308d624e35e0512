/* A device class from an EDS/DCF: see eds_class.h and docs/eds.md ("How a file becomes a device"). */
#define _GNU_SOURCE
#include "eds_class/eds_class.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "eds.h"
#include "eds_class/eds_large.h"
#include "eds_class/rules.h"

#if CO_CONFIG_OD_COMPACT
#error "canopen-emu builds dictionaries of any size at run time: build it with CO_CONFIG_OD_COMPACT 0"
#endif

typedef struct eds_class {
    device_class_t cls;
    co_od_t od;
    eds_file_t *file;        /* owns the names */
    co_od_entry_t *rows;
    co_od_object_t *objects; /* the object table of rows (co_od_t.objects) */
    uint16_t *object_slots;  /* the objects hashed by index (co_od_t.object_slots) */
    co_od_limits_t *limits;
    uint8_t *defaults;
    const char **names;
    const char **object_names; /* per entry of objects */
    char *path;
    char *name;
    char *summary;
    rules_t *rules;          /* --rules, or NULL */
    eds_large_t *large;      /* its DOMAINs and long strings (eds_large.h), or NULL */
    struct eds_class *next;
} eds_class_t;

static eds_class_t *loaded; /* the program's classes, one per file */

bool eds_class_is_file(const char *name)
{
    const size_t n = strlen(name);
    return n > 4U && (strcasecmp(name + n - 4U, ".eds") == 0 || strcasecmp(name + n - 4U, ".dcf") == 0);
}

/* The value a node starts with: a DCF's ParameterValue where it has one. */
static const eds_value_t *start_value(const eds_entry_t *e)
{
    return e->param.kind != EDS_V_NONE ? &e->param : &e->def;
}

/* Bytes of a row: its type's, or for strings and domains a capacity (docs/eds.md): what the file's value needs,
 * and for a writable one at least what one SDO transfer of the core moves; never more than that. */
static uint16_t capacity(const eds_entry_t *e, FILE *log, const char *path, bool quiet)
{
    const size_t fixed = eds_type_size(e->type);
    if (fixed > 0U) {
        return (uint16_t)fixed;
    }
    if (CO_CONFIG_LARGE_OBJECTS && eds_large_entry(e)) {
        return 0U; /* a large object: its value of any length is eds_large.c's (co_hooks_t.large_read) */
    }
    size_t len = start_value(e)->len;
    if (len > CO_SDO_BUF_SIZE) {
        if (!quiet) {
            fprintf(log, "%s:%lu: warning: 0x%04X:%02X holds %lu bytes; the SDO server moves at most %u: cut to %u\n",
                    path, (unsigned long)e->line, (unsigned)e->index, (unsigned)e->sub, (unsigned long)len,
                    (unsigned)CO_SDO_BUF_SIZE, (unsigned)CO_SDO_BUF_SIZE);
        }
        len = CO_SDO_BUF_SIZE;
    }
    if (eds_access_writable(e->access) && len < CO_SDO_BUF_SIZE) {
        len = CO_SDO_BUF_SIZE;
    }
    return (uint16_t)(len > 0U ? len : 1U);
}

static uint8_t flags_of(const eds_entry_t *e)
{
    unsigned f = 0U;
    const bool w = eds_access_writable(e->access);
    if (e->access != EDS_WO) {
        f |= CO_OD_READ;
    }
    if (w) {
        f |= CO_OD_WRITE;
    }
    if (e->access == EDS_CONST) {
        f |= CO_OD_CONST;
    }
    if (e->pdo_mapping && eds_access_maps(e->access, false)) {
        f |= CO_OD_TPDO;
    }
    if (e->pdo_mapping && eds_access_maps(e->access, true)) {
        f |= CO_OD_RPDO;
    }
    if (start_value(e)->nodeid) {
        f |= CO_OD_NODEID;
    }
    /* 0x1010 saves every writable parameter but the command objects, the error history and program data. */
    if (w && e->index != 0x1010U && e->index != 0x1011U && e->index != 0x1003U && e->type != CO_T_DOMAIN &&
        !(e->index >= 0x1F50U && e->index <= 0x1F5FU) && !(CO_CONFIG_LARGE_OBJECTS && eds_large_entry(e))) {
        f |= CO_OD_STORE;
    }
    return (uint8_t)f;
}

static void put_default(uint8_t *dst, const co_od_entry_t *row, const eds_value_t *v)
{
    switch (v->kind) {
    case EDS_V_BYTES: {
        const size_t n = v->len < row->size ? v->len : row->size;
        memcpy(dst, v->bytes, n);
        if (co_od_type_has_length(row->type)) { /* the default's length, after the value (co_od.h) */
            dst[row->size] = (uint8_t)n;
            dst[row->size + 1U] = (uint8_t)(n >> 8);
        }
        return;
    }
    case EDS_V_REAL:
        if (row->size == 4U) {
            const float f = (float)v->r;
            memcpy(dst, &f, sizeof f);
        } else {
            memcpy(dst, &v->r, sizeof v->r);
        }
        return;
    default: {
        const uint64_t u = v->kind == EDS_V_INT ? (uint64_t)v->i : v->u;
        if (row->size == 1U || row->size == 2U || row->size == 4U || row->size == 8U) {
            const uint8_t u8 = (uint8_t)u;
            const uint16_t u16 = (uint16_t)u;
            const uint32_t u32 = (uint32_t)u;
            memcpy(dst, row->size == 1U ? (const void *)&u8 : row->size == 2U ? (const void *)&u16
                        : row->size == 4U ? (const void *)&u32 : (const void *)&u, row->size);
        } else {
            for (uint16_t i = 0U; i < row->size; i++) { /* odd sizes: little-endian bytes (co_od.h) */
                dst[i] = (uint8_t)(u >> (8U * i));
            }
        }
        return;
    }
    }
}

static co_od_limit_t limit_of(const eds_entry_t *e, const eds_value_t *v, bool high)
{
    eds_value_t bound;
    if (v->kind == EDS_V_NONE) {
        eds_type_bound(e->type, high, &bound);
        v = &bound;
    }
    co_od_limit_t l;
    if (v->kind == EDS_V_REAL) {
        l.r = v->r;
    } else if (v->kind == EDS_V_UINT && e->type == CO_T_UNSIGNED64) {
        l.u = v->u;
    } else {
        l.i = v->kind == EDS_V_INT ? v->i : (int64_t)v->u;
    }
    return l;
}

static uint8_t bit_timing_of(const eds_file_t *f)
{
    for (uint8_t i = 0U; i < EDS_CIA305_RATES; i++) {
        if (f->comm.baudrate_kbit != 0U && eds_cia305_kbit[i] == f->comm.baudrate_kbit) {
            return i;
        }
    }
    return 4U; /* 125 kbit/s */
}

static uint16_t pdo_count(const eds_file_t *f, uint16_t base)
{
    uint16_t n = 0U;
    for (uint32_t i = 0; i < f->n_objects; i++) {
        const uint16_t x = f->objects[i].index;
        if (x >= base && x < base + 0x200U) {
            n = (uint16_t)(x - base + 1U);
        }
    }
    return n;
}

/* Additional SDO servers: the objects 0x1201..0x127F of the file (CiA 301), each served by the core. */
static uint8_t sdo_server_count(const eds_file_t *f)
{
    uint8_t n = 0U;
    for (uint32_t i = 0; i < f->n_objects; i++) {
        if (f->objects[i].index >= 0x1201U && f->objects[i].index <= 0x127FU) {
            n++;
        }
    }
    return n;
}

static void free_class(eds_class_t *c)
{
    if (c == NULL) {
        return;
    }
    free(c->rows);
    free(c->objects);
    free(c->object_slots);
    free(c->limits);
    free(c->defaults);
    free(c->names);
    free(c->object_names);
    free(c->path);
    free(c->name);
    free(c->summary);
    rules_free(c->rules);
    eds_large_free(c->large);
    eds_free(c->file);
    free(c);
}

/* A node powers on: its large objects take their file values again (eds_large.c). */
static void large_power_on(device_t *dev, co_time_us_t now)
{
    (void)now;
    eds_large_power_on(((const eds_class_t *)(const void *)dev->cls)->large, dev);
}

/* Builds the table of a file read without errors. */
static eds_class_t *build(eds_file_t *f, const char *path, FILE *log, bool quiet)
{
    eds_class_t *c = calloc(1U, sizeof *c);
    if (c == NULL) {
        return NULL;
    }
    const uint32_t n = f->n_entries; /* c->file is set at the end: until then the caller owns f */
    c->rows = calloc(n, sizeof *c->rows);
    c->objects = calloc(n > 0U ? n : 1U, sizeof *c->objects);
    c->limits = calloc(n, sizeof *c->limits);
    c->names = calloc(n, sizeof *c->names);
    c->object_names = calloc(n > 0U ? n : 1U, sizeof *c->object_names);
    c->path = strdup(path);
    const char *base = strrchr(path, '/');
    c->name = strdup(base != NULL ? base + 1 : path);
    if (c->rows == NULL || c->objects == NULL || c->limits == NULL || c->names == NULL || c->object_names == NULL ||
        c->path == NULL || c->name == NULL || n > 0xFFFFU) {
        free_class(c);
        return NULL;
    }
    uint32_t offset = 0U, hash = 2166136261U; /* FNV-1a of the layout: stored values of another layout are refused */
    for (uint32_t i = 0; i < n; i++) {
        const eds_entry_t *e = &f->entries[i];
        co_od_entry_t *r = &c->rows[i];
        r->index = e->index;
        r->sub = e->sub;
        r->type = e->type;
        r->flags = flags_of(e);
        r->count = 1U; /* one row per sub-index: the rows are built here, not generated */
        r->size = capacity(e, log, path, quiet);
        const uint32_t align = (r->size == 2U || r->size == 4U || r->size == 8U) ? r->size : 1U;
        offset = (offset + align - 1U) / align * align;
        r->offset = offset;
        offset += r->size + (co_od_type_has_length(r->type) ? CO_OD_LEN_SIZE : 0U); /* a length after it (co_od.h) */
        if (e->low.kind != EDS_V_NONE || e->high.kind != EDS_V_NONE) {
            c->limits[i].low = limit_of(e, &e->low, false);
            c->limits[i].high = limit_of(e, &e->high, true);
            r->limits = &c->limits[i];
        }
        c->names[i] = e->name;
        const uint8_t key[6] = {(uint8_t)e->index, (uint8_t)(e->index >> 8), e->sub, e->type, (uint8_t)r->size,
                                (uint8_t)(r->size >> 8)};
        for (size_t k = 0; k < sizeof key; k++) {
            hash = (hash ^ key[k]) * 16777619U;
        }
    }
    c->defaults = calloc(1U, offset > 0U ? offset : 1U);
    if (c->defaults == NULL) {
        free_class(c);
        return NULL;
    }
    for (uint32_t i = 0; i < n; i++) {
        put_default(c->defaults + c->rows[i].offset, &c->rows[i], start_value(&f->entries[i]));
    }
    char summary[256];
    snprintf(summary, sizeof summary, "%s%s%s (from %s)", f->vendor_name, f->vendor_name[0] != '\0' ? " " : "",
             f->product_name[0] != '\0' ? f->product_name : "device", c->name);
    c->summary = strdup(summary);
    bool large_failed = false;
    c->large = CO_CONFIG_LARGE_OBJECTS ? eds_large_create(&c->od, f, &large_failed) : NULL;
    if (large_failed) {
        free_class(c);
        return NULL;
    }
    c->file = f;
    c->od.name = c->name;
    c->od.entries = c->rows;
    c->od.count = (uint16_t)n;
    c->od.defaults = c->defaults;
    c->od.values_size = offset;
    c->od.signature = hash;
    c->od.dummy_usage = f->dummy_usage;
    c->od.objects = c->objects;
    for (uint32_t i = 0; i < n; i++) {
        if (i == 0U || c->rows[i - 1U].index != c->rows[i].index) { /* the reader's entries are in (index, sub) order */
            c->objects[c->od.n_objects].index = c->rows[i].index;
            c->objects[c->od.n_objects].first = (uint16_t)i;
            const eds_object_t *object = eds_find_object(f, c->rows[i].index);
            c->object_names[c->od.n_objects] = object != NULL ? object->name : NULL;
            c->od.n_objects++;
        }
    }
    /* Without room for the hash (or past 65,534 objects) look-ups search the object table: slower, as right. */
    const uint8_t bits = co_od_object_slot_bits(c->od.n_objects);
    c->object_slots = calloc((size_t)1U << bits, sizeof *c->object_slots);
    if (c->object_slots != NULL && co_od_object_slots_fill(c->objects, c->od.n_objects, c->object_slots, bits)) {
        c->od.object_slots = c->object_slots;
        c->od.object_slot_bits = bits;
    }
    device_class_t *cls = &c->cls;
    cls->name = c->name;
    cls->summary = c->summary != NULL ? c->summary : c->name;
    cls->od = &c->od;
    cls->od_names = c->names;
    cls->od_object_names = c->object_names;
    cls->default_node_id = f->comm.node_id; /* 0: the command line must give one */
    cls->default_bit_timing = bit_timing_of(f);
    cls->core_options = CO_OPT_SDO_SEGMENTED | CO_OPT_SDO_BLOCK | (f->lss_supported ? 0U : CO_OPT_NO_LSS);
    cls->rpdo_count = pdo_count(f, 0x1400U);
    cls->tpdo_count = pdo_count(f, 0x1800U);
    cls->sdo_server_count = sdo_server_count(f);
    cls->model_size = device_core_state_size(cls);
    cls->power_on = c->large != NULL ? large_power_on : NULL;
    return c;
}

const device_class_t *eds_class_load(const char *path, FILE *log, bool quiet)
{
    for (eds_class_t *c = loaded; c != NULL; c = c->next) {
        if (strcmp(c->path, path) == 0) {
            return &c->cls;
        }
    }
    eds_file_t *f = eds_read_file(path);
    if (f == NULL) {
        fprintf(log, "canopen-emu: %s: out of memory\n", path);
        return NULL;
    }
    for (uint32_t i = 0; i < f->n_diagnostics; i++) {
        if (!quiet || f->errors > 0U) {
            fprintf(log, "%s\n", f->diagnostics[i]);
        }
    }
    if (f->errors > 0U) {
        fprintf(log, "canopen-emu: %s cannot be emulated (%lu errors)\n", path, (unsigned long)f->errors);
        eds_free(f);
        return NULL;
    }
    eds_class_t *c = build(f, path, log, quiet);
    if (c == NULL) {
        fprintf(log, "canopen-emu: %s: out of memory\n", path);
        eds_free(f);
        return NULL;
    }
    c->next = loaded;
    loaded = c;
    return &c->cls;
}

/* The current value of an entry: what an SDO upload would give, without access rights. */
void eds_class_warn_node_id(const device_class_t *cls, uint8_t node_id, FILE *log, bool quiet)
{
    if (!quiet) {
        (void)eds_node_id_warnings(((const eds_class_t *)(const void *)cls)->file, node_id, log);
    }
}

static long current_value(void *ctx, const eds_entry_t *e, uint8_t *buf, size_t cap)
{
    device_t *dev = ctx;
    size_t len = 0U;
    if (co_od_read(&dev->node, e->index, e->sub, buf, cap, &len, CO_ORIGIN_LOCAL) != 0U) {
        return -1;
    }
    return (long)len;
}

bool eds_class_export(device_t *dev, const char *path, char *why, size_t cap)
{
    const eds_class_t *c = loaded;
    while (c != NULL && &c->cls != dev->cls) {
        c = c->next;
    }
    if (c == NULL) {
        snprintf(why, cap, "%s is a built-in device: export-dcf writes devices read from an EDS or DCF (its EDS is "
                           "od/ in the sources)", dev->cls->name);
        return false;
    }
    char tmp[4096];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp) {
        snprintf(why, cap, "path too long");
        return false;
    }
    FILE *out = fopen(tmp, "w");
    if (out == NULL) {
        snprintf(why, cap, "%s: %s", tmp, strerror(errno));
        return false;
    }
    eds_write_options_t o;
    memset(&o, 0, sizeof o);
    o.dcf = true;
    o.node_id = co_node_id(&dev->node) <= 127U ? co_node_id(&dev->node) : 0U;
    const char *base = strrchr(path, '/');
    o.file_name = base != NULL ? base + 1 : path;
    o.current = current_value;
    o.ctx = dev;
    why[0] = '\0';
    o.error = why; /* a value a CiA 306 line cannot hold (a line break written over SDO): the entry named */
    o.error_cap = cap;
    const int written = eds_write(out, c->file, &o);
    const bool closed = fflush(out) == 0 && fsync(fileno(out)) == 0;
    if (fclose(out) != 0 || written != 0 || !closed) {
        if (written == 0 || why[0] == '\0') {
            snprintf(why, cap, "%s: %s", tmp, strerror(errno != 0 ? errno : EIO));
        }
        (void)unlink(tmp);
        return false;
    }
    if (rename(tmp, path) != 0) {
        snprintf(why, cap, "%s: %s", path, strerror(errno));
        (void)unlink(tmp);
        return false;
    }
    return true;
}

/* ---- Rules: the class's hooks when a rules file is attached ---------------------------------------------------- */

static const eds_class_t *class_of(const device_t *dev) { return (const eds_class_t *)(const void *)dev->cls; }

static void *rules_state(device_t *dev) { return (uint8_t *)dev->model + device_core_state_size(dev->cls); }

static co_time_us_t rules_hook_step(device_t *dev, co_time_us_t now)
{
    return rules_step(class_of(dev)->rules, rules_state(dev), dev, now);
}

static uint32_t rules_hook_write(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len,
                                 co_od_origin_t origin)
{
    (void)origin;
    return rules_on_write(class_of(dev)->rules, rules_state(dev), dev, e, data, len);
}

/* The rules start (again) when the application area has its values: at power-on after NVM is loaded, and at an NMT
 * reset application; not in power_on, which runs before the node exists. */
static void rules_hook_reset(device_t *dev, co_reset_t what)
{
    if (what == CO_RESET_APPLICATION) {
        rules_power_on(class_of(dev)->rules, rules_state(dev), dev, dev->now);
    }
}

bool eds_class_attach_rules(const char *path, FILE *log)
{
    if (loaded == NULL) {
        fprintf(log, "%s: error: --rules is for devices read from an EDS/DCF; none is on the command line\n", path);
        return false;
    }
    /* parsed against the first class first: the file's device: key may then name another */
    const char *device = NULL;
    rules_t *r = rules_load(path, &loaded->od, log, &device);
    eds_class_t *c = loaded;
    if (r != NULL && device != NULL) {
        for (c = loaded; c != NULL && strcmp(c->name, device) != 0; c = c->next) {
        }
        if (c == NULL) {
            fprintf(log, "%s: error: device: %s is not an EDS/DCF on the command line\n", path, device);
            rules_free(r);
            return false;
        }
        if (c != loaded) { /* resolved against the wrong table: again against its own */
            rules_free(r);
            r = rules_load(path, &c->od, log, &device);
        }
    } else if (r != NULL && loaded->next != NULL) {
        fprintf(log, "%s: error: several EDS/DCF devices are on the command line: say which with 'device: NAME'\n",
                path);
        rules_free(r);
        return false;
    }
    if (r == NULL) {
        return false;
    }
    if (c->rules != NULL) {
        fprintf(log, "%s: error: %s has rules already\n", path, c->name);
        rules_free(r);
        return false;
    }
    c->rules = r;
    device_class_t *cls = &c->cls;
    cls->step = rules_hook_step;
    cls->on_write = rules_hook_write;
    cls->on_reset = rules_hook_reset;
    cls->model_size = device_core_state_size(cls) + rules_state_size(r);
    return true;
}

void eds_class_free_all(void)
{
    while (loaded != NULL) {
        eds_class_t *next = loaded->next;
        free_class(loaded);
        loaded = next;
    }
}
