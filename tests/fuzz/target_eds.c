/*
 * Fuzz target "eds": the EDS/DCF reader (src/eds/) on any bytes, as canopen-eds and canopen-emu read a file.
 *
 * Input: the file's bytes.
 * Invariants (a violation prints "==fuzz== INVARIANT VIOLATION" and aborts):
 *  - a file read without errors is a model the emulator can use: entries sorted by (index, sub) and unique, each of
 *    a known type, its default (and DCF value) of the type's kind and representable in it (node-ID-relative ones
 *    for every node-ID 1..127), limits ordered; objects in index order, each owning exactly its entries; every
 *    PDO's mapping as a node starts with it (a DCF's values where it has them, else the defaults) names existing,
 *    mappable objects of the right size and direction or allowed dummies, at most 64 bits;
 *  - the model written back as a DCF (eds_write) reads again without an error or a warning (except those of what
 *    the reader keeps as it is: "; kept"), as the same model
 *    (every entry's type, access, mapping flag, name, default, limits, DCF value), and written again gives the
 *    same bytes (the writer reaches a fixed point at once);
 *  - no crash, leak, hang or undefined behaviour (ASan, UBSan, LeakSanitizer, libFuzzer's timeout).
 */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eds.h"
#include "fuzz_abort.h"

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void violation(const char *fmt, ...)
{
    fprintf(stderr, "==fuzz== INVARIANT VIOLATION [eds] ");
    va_list ap;
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

#if defined(__GNUC__)
__attribute__((noreturn))
#endif
static void fail(const char *what, const eds_entry_t *e)
{
    if (e != NULL) {
        violation("%s (0x%04X:%02X)", what, (unsigned)e->index, (unsigned)e->sub);
    }
    violation("%s", what);
}

static bool value_ok(uint8_t type, const eds_value_t *v)
{
    if (eds_type_is_bytes(type)) {
        return v->kind == EDS_V_BYTES && v->bytes != NULL;
    }
    return eds_value_fits(type, v);
}

static bool same_value(const eds_value_t *a, const eds_value_t *b)
{
    if (a->kind != b->kind || a->nodeid != b->nodeid) {
        return false;
    }
    switch (a->kind) {
    case EDS_V_INT:
        return a->i == b->i;
    case EDS_V_UINT:
        return a->u == b->u;
    case EDS_V_REAL:
        return a->r == b->r;
    case EDS_V_BYTES:
        return a->len == b->len && memcmp(a->bytes, b->bytes, a->len) == 0;
    default:
        return true;
    }
}

static void check_mapping(const eds_file_t *f, const eds_entry_t *count, bool receive, bool param)
{
    const eds_value_t *n = param && count->param.kind != EDS_V_NONE ? &count->param : &count->def;
    if (n->kind == EDS_V_UINT && (n->u == 0xFEU || (n->u == 0xFFU && receive))) {
        return; /* an MPDO (the core's CO_CONFIG_MPDO): its entries are not used */
    }
    if (n->kind != EDS_V_UINT || n->u > 64U) {
        fail("a mapping count the core refuses", count);
    }
    unsigned bits = 0U;
    for (unsigned s = 1U; s <= n->u; s++) {
        const eds_entry_t *e = eds_find(f, count->index, (uint8_t)s);
        if (e == NULL) {
            fail("a mapping entry missing", count);
        }
        const eds_value_t *v = param && e->param.kind != EDS_V_NONE ? &e->param : &e->def;
        if (v->kind != EDS_V_UINT || v->nodeid) {
            fail("a mapping entry that is not a plain number", e);
        }
        uint16_t index = (uint16_t)(v->u >> 16);
        uint8_t sub = (uint8_t)(v->u >> 8), len = (uint8_t)v->u;
        if (index >= 1U && index <= 7U && sub == 0U) {
            if (!receive || (f->dummy_usage & (1U << index)) == 0U || eds_type_size((uint8_t)index) * 8U != len) {
                fail("a dummy mapping [DummyUsage] does not allow, or of another length than its type", e);
            }
        } else {
            const eds_entry_t *t = eds_find(f, index, sub);
            if (t == NULL || !t->pdo_mapping || eds_type_size(t->type) * 8U != len ||
                (receive ? (t->access == EDS_RO || t->access == EDS_CONST || t->access == EDS_RWR)
                         : (t->access == EDS_WO || t->access == EDS_RWW))) {
                fail("a mapping entry the core refuses", e);
            }
        }
        bits += len;
    }
    if (bits > 64U) {
        fail("a mapping of more than 64 bits", count);
    }
}

static void check_model(const eds_file_t *f)
{
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        if (i > 0U) {
            const eds_entry_t *p = &f->entries[i - 1U];
            if (p->index > e->index || (p->index == e->index && p->sub >= e->sub)) {
                fail("entries not sorted and unique", e);
            }
        }
        if (eds_type_name(e->type) == NULL || e->name == NULL) {
            fail("an entry of an unknown type or without a name", e);
        }
        if (!value_ok(e->type, &e->def) || (e->param.kind != EDS_V_NONE && !value_ok(e->type, &e->param))) {
            fail("a value not representable in its type", e);
        }
        if (e->low.kind != EDS_V_NONE && e->high.kind != EDS_V_NONE && eds_value_cmp(&e->low, &e->high) > 0) {
            fail("limits out of order", e);
        }
    }
    uint32_t covered = 0U;
    for (uint32_t i = 0; i < f->n_objects; i++) {
        const eds_object_t *o = &f->objects[i];
        if ((i > 0U && f->objects[i - 1U].index >= o->index) || o->count == 0U || o->first != covered) {
            fail("objects out of order or not owning their entries", NULL);
        }
        for (uint32_t k = 0; k < o->count; k++) {
            if (f->entries[o->first + k].index != o->index) {
                fail("an object owning another's entry", &f->entries[o->first + k]);
            }
        }
        covered += o->count;
    }
    if (covered != f->n_entries) {
        fail("entries that belong to no object", NULL);
    }
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        bool rx = e->index >= 0x1600U && e->index <= 0x17FFU, tx = e->index >= 0x1A00U && e->index <= 0x1BFFU;
        if ((rx || tx) && e->sub == 0U && e->type == 0x05U) {
            check_mapping(f, e, rx, true); /* the mapping a node starts with (a DCF's values where it has them) */
        }
    }
}

static char *write_dcf(const eds_file_t *f, size_t *len)
{
    char *buf = NULL;
    FILE *out = open_memstream(&buf, len);
    if (out == NULL) {
        abort();
    }
    eds_write_options_t o;
    memset(&o, 0, sizeof o);
    o.dcf = true;
    o.node_id = 5;
    if (eds_write(out, f, &o) != 0) {
        fail("the writer failed", NULL);
    }
    fclose(out);
    return buf;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    eds_file_t *f = eds_read_buffer("fuzz.eds", (const char *)data, size);
    if (f == NULL) {
        return 0;
    }
    if (f->errors == 0U) {
        check_model(f);
        size_t len1 = 0U, len2 = 0U;
        char *text1 = write_dcf(f, &len1);
        eds_file_t *g = eds_read_buffer("rewritten.dcf", text1, len1);
        if (g == NULL) {
            abort();
        }
        /* Only what the reader reports and keeps may be reported again; every repair must hold. The reader stores
         * the first EDS_MAX_DIAGNOSTICS lines and a note that more follow: those are checked, the rest cannot be
         * (a file of many objects with kept non-ASCII strings has more). */
        const bool capped = g->warnings + g->errors > EDS_MAX_DIAGNOSTICS;
        const uint32_t stored = capped ? EDS_MAX_DIAGNOSTICS : g->warnings + g->errors;
        const char *repeated = g->n_diagnostics < stored ? "(fewer lines than problems)" : NULL;
        for (uint32_t i = 0; i < stored && i < g->n_diagnostics && repeated == NULL; i++) {
            if (strstr(g->diagnostics[i], "; kept") == NULL) {
                repeated = g->diagnostics[i];
            }
        }
        if (repeated != NULL) {
            violation("the rewritten file has a diagnostic: %s", repeated);
        }
        if (g->n_entries != f->n_entries) {
            fail("the rewritten file has another number of entries", NULL);
        }
        for (uint32_t i = 0; i < f->n_entries; i++) {
            const eds_entry_t *a = &f->entries[i], *b = &g->entries[i];
            const eds_value_t *av = a->param.kind != EDS_V_NONE ? &a->param : &a->def;
            if (a->index != b->index || a->sub != b->sub || a->type != b->type || a->access != b->access ||
                a->pdo_mapping != b->pdo_mapping || strcmp(a->name, b->name) != 0 || !same_value(&a->def, &b->def) ||
                !same_value(&a->low, &b->low) || !same_value(&a->high, &b->high) || !same_value(av, &b->param)) {
                fail("the rewritten file reads as another entry", a);
            }
        }
        check_model(g);
        char *text2 = write_dcf(g, &len2);
        if (len1 != len2 || memcmp(text1, text2, len1) != 0) {
            fail("writing the rewritten file gives other bytes", NULL);
        }
        free(text1);
        free(text2);
        eds_free(g);
    }
    eds_free(f);
    return 0;
}
