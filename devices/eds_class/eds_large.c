/* Large objects of a device made from an EDS/DCF: see eds_large.h. */
#include "eds_class/eds_large.h"

#include <stdlib.h>
#include <string.h>

/* One node's value of one large object, and the download in progress that replaces it at its END. */
typedef struct large_value {
    uint8_t *data;
    uint32_t len;
    uint8_t *next;
    uint32_t next_len;
    uint32_t next_cap;
    bool receiving;
} large_value_t;

/* One node's values, one per large object of its class. */
typedef struct large_node {
    const device_t *dev;
    struct large_node *next;
    large_value_t *values;
} large_node_t;

typedef struct large_file_value {
    const uint8_t *bytes; /* the file's value (the class's file owns it) */
    uint32_t len;
} large_file_value_t;

struct eds_large {
    const co_od_t *od;
    uint32_t n;
    uint16_t *index;         /* per large object: its index and sub-index, in table order */
    uint8_t *sub;
    large_file_value_t *file_value;
    large_node_t *nodes;
    struct eds_large *next;
};

static eds_large_t *classes; /* every class's, to find them from a hook's node (its od) */

/* The value a node starts with: a DCF's ParameterValue where it has one (as eds_class.c's start_value). */
static const eds_value_t *start_value(const eds_entry_t *e)
{
    return e->param.kind != EDS_V_NONE ? &e->param : &e->def;
}

bool eds_large_entry(const eds_entry_t *e)
{
    if (!co_od_type_has_length(e->type) || e->pdo_mapping) {
        return false;
    }
    return e->type == CO_T_DOMAIN || start_value(e)->len > CO_SDO_BUF_SIZE;
}

eds_large_t *eds_large_create(const co_od_t *od, const eds_file_t *f, bool *failed)
{
    *failed = false;
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < f->n_entries; i++) {
        n += eds_large_entry(&f->entries[i]) ? 1U : 0U;
    }
    if (n == 0U) {
        return NULL;
    }
    eds_large_t *l = calloc(1U, sizeof *l);
    if (l != NULL) {
        l->index = calloc(n, sizeof *l->index);
        l->sub = calloc(n, sizeof *l->sub);
        l->file_value = calloc(n, sizeof *l->file_value);
    }
    if (l == NULL || l->index == NULL || l->sub == NULL || l->file_value == NULL) {
        eds_large_free(l);
        *failed = true;
        return NULL;
    }
    l->od = od;
    for (uint32_t i = 0U; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        if (eds_large_entry(e)) {
            const eds_value_t *v = start_value(e);
            l->index[l->n] = e->index;
            l->sub[l->n] = e->sub;
            l->file_value[l->n].bytes = v->kind == EDS_V_BYTES ? v->bytes : NULL;
            l->file_value[l->n].len = v->kind == EDS_V_BYTES && v->len <= EDS_LARGE_MAX ? (uint32_t)v->len : 0U;
            l->n++;
        }
    }
    l->next = classes;
    classes = l;
    return l;
}

static void drop_next(large_value_t *v)
{
    free(v->next);
    v->next = NULL;
    v->next_len = 0U;
    v->next_cap = 0U;
    v->receiving = false;
}

static void free_node(large_node_t *ln, uint32_t n)
{
    for (uint32_t k = 0U; ln->values != NULL && k < n; k++) {
        free(ln->values[k].data);
        drop_next(&ln->values[k]);
    }
    free(ln->values);
    free(ln);
}

void eds_large_free(eds_large_t *l)
{
    if (l == NULL) {
        return;
    }
    for (eds_large_t **p = &classes; *p != NULL; p = &(*p)->next) {
        if (*p == l) {
            *p = l->next;
            break;
        }
    }
    while (l->nodes != NULL) {
        large_node_t *next = l->nodes->next;
        free_node(l->nodes, l->n);
        l->nodes = next;
    }
    free(l->index);
    free(l->sub);
    free(l->file_value);
    free(l);
}

/* The node's values of its class's large objects, or NULL (no such class or node). */
static large_value_t *values_of(const co_node_t *node, const device_t *dev, const co_od_entry_t *e, uint32_t *k)
{
    const eds_large_t *l = classes;
    while (l != NULL && l->od != node->od) {
        l = l->next;
    }
    if (l == NULL) {
        return NULL;
    }
    const large_node_t *ln = l->nodes;
    while (ln != NULL && ln->dev != dev) {
        ln = ln->next;
    }
    for (uint32_t i = 0U; ln != NULL && i < l->n; i++) {
        if (l->index[i] == e->index && l->sub[i] == e->sub) {
            *k = i;
            return ln->values;
        }
    }
    return NULL;
}

static uint32_t large_read(void *ctx, co_node_t *node, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                           size_t len, uint32_t *length)
{
    uint32_t k = 0U;
    const large_value_t *values = values_of(node, ctx, entry, &k);
    if (values == NULL) {
        return CO_ABORT_UNSUPPORTED_ACCESS;
    }
    const large_value_t *v = &values[k];
    *length = v->len;
    if (len == 0U) {
        return CO_ABORT_NONE;
    }
    if (offset > v->len || len > v->len - offset) {
        return CO_ABORT_NO_DATA; /* replaced by a shorter value during an upload */
    }
    memcpy(buf, v->data + offset, len);
    return CO_ABORT_NONE;
}

/* Room for len more bytes of the download: the buffer doubles as it fills, up to EDS_LARGE_MAX. */
static uint32_t make_room(large_value_t *v, size_t len)
{
    if (len > EDS_LARGE_MAX - v->next_len) {
        return CO_ABORT_LENGTH_HIGH;
    }
    const uint32_t need = v->next_len + (uint32_t)len;
    if (need <= v->next_cap) {
        return CO_ABORT_NONE;
    }
    uint32_t cap = v->next_cap > 0U ? v->next_cap : 4096U;
    while (cap < need) {
        cap = cap > EDS_LARGE_MAX / 2U ? (uint32_t)EDS_LARGE_MAX : cap * 2U;
    }
    uint8_t *grown = realloc(v->next, cap);
    if (grown == NULL) {
        return CO_ABORT_OUT_OF_MEMORY;
    }
    v->next = grown;
    v->next_cap = cap;
    return CO_ABORT_NONE;
}

static uint32_t large_write(void *ctx, co_node_t *node, const co_od_entry_t *entry, co_large_step_t step, uint32_t at,
                            const uint8_t *data, size_t len)
{
    uint32_t k = 0U;
    large_value_t *values = values_of(node, ctx, entry, &k);
    if (values == NULL) {
        return CO_ABORT_UNSUPPORTED_ACCESS;
    }
    large_value_t *v = &values[k];
    switch (step) {
    case CO_LARGE_BEGIN: {
        drop_next(v); /* another server's download of it, unfinished, is overtaken */
        if (at > EDS_LARGE_MAX) {
            return CO_ABORT_LENGTH_HIGH;
        }
        const uint32_t r = make_room(v, at); /* the size indicated, at once: a refusal comes before any data */
        v->receiving = r == CO_ABORT_NONE;
        return r;
    }
    case CO_LARGE_DATA: {
        if (!v->receiving || at != v->next_len) {
            return CO_ABORT_GENERAL; /* not this download's next bytes (another server began one meanwhile) */
        }
        const uint32_t r = make_room(v, len);
        if (r == CO_ABORT_NONE) {
            memcpy(v->next + v->next_len, data, len);
            v->next_len += (uint32_t)len;
        }
        return r;
    }
    case CO_LARGE_END:
        if (!v->receiving || at != v->next_len) {
            drop_next(v);
            return CO_ABORT_GENERAL;
        }
        free(v->data);
        v->data = v->next; /* the new value, with its length */
        v->len = v->next_len;
        v->next = NULL;
        drop_next(v);
        return CO_ABORT_NONE;
    default:
        drop_next(v);
        return CO_ABORT_NONE;
    }
}

void eds_large_power_on(eds_large_t *l, device_t *dev)
{
    if (l == NULL) {
        return;
    }
    dev->hooks.large_read = large_read;
    dev->hooks.large_write = large_write;
    large_node_t *ln = l->nodes;
    while (ln != NULL && ln->dev != dev) {
        ln = ln->next;
    }
    if (ln == NULL) {
        ln = calloc(1U, sizeof *ln);
        if (ln != NULL) {
            ln->values = calloc(l->n, sizeof *ln->values);
        }
        if (ln == NULL || ln->values == NULL) {
            free(ln);
            return; /* the objects then answer 0x06010000 */
        }
        ln->dev = dev;
        ln->next = l->nodes;
        l->nodes = ln;
    }
    for (uint32_t k = 0U; k < l->n; k++) { /* RAM lost at power-off: the file's values again */
        large_value_t *v = &ln->values[k];
        free(v->data);
        drop_next(v);
        v->data = NULL;
        v->len = 0U;
        const large_file_value_t *fv = &l->file_value[k];
        if (fv->len > 0U && (v->data = malloc(fv->len)) != NULL) {
            memcpy(v->data, fv->bytes, fv->len);
            v->len = fv->len;
        }
    }
}
