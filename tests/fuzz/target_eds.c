/*
 * Fuzz target "eds": the EDS/DCF reader (eds/) on any bytes, as canopen-eds and canopen-emu read a file.
 *
 * Input: the file's bytes; or, when the first byte is 0x01, a size case: 0x01, K, HEAD, 0x02, UNIT, 0x02, TAIL
 * (a missing 0x02 ends a part) is the file HEAD, UNIT written 2^(K % 17) times with each '@' in it replaced by the
 * copy's number as four hexadecimal digits ("[@]" makes 65536 objects), TAIL; at most 4 MiB. Inputs are short
 * (-max_len=4096): the size case reaches the sizes where a cost that grows faster than the file shows
 * (libFuzzer's -timeout and -rss_limit_mb catch it: 40,000 sections took 10 s before the reader was linear). A size
 * case is read and its model checked, not written back: the writer gives a CompactSubObj object as up to 254 sub-index
 * sections, each with the object's default, so the DCF of a large file can exceed what the reader takes (16 MiB).
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
 *  - written with current values as canopen-emu's export-dcf gives them (strings cut from the file's own text, so
 *    line breaks and section headers among them), the DCF is refused with the entry named, or reads again with
 *    those values (leading and trailing blanks aside, which CiA 306 trims) and nothing else changed: no value
 *    writes sections or keys of its own;
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

/* A diagnostic a written file may have: a value kept as it is, or a note that groups more of a kind given above
 * ("... and N more like this") or counts problems not shown (only after more lines than the cap). */
static bool kept_or_note(const eds_file_t *g, const char *d)
{
    const bool grouped = strstr(d, ": note: ... and ") != NULL && strstr(d, " more like this") != NULL;
    const bool not_shown = strstr(d, ": note: ") != NULL && strstr(d, "of other kinds not shown") != NULL &&
                           g->n_diagnostics > EDS_MAX_DIAGNOSTICS;
    return strstr(d, "; kept") != NULL || grouped || not_shown;
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

/* ---- Current values: what an SDO master could have written into the strings -------------------------------- */

typedef struct text {
    const char *data;
    size_t len;
} text_t;

/* A string entry's current value: up to 64 bytes of the file's text, from a place its index and sub-index pick. */
static size_t current_slice(const text_t *t, const eds_entry_t *e, const char **at)
{
    if (t->len == 0U || (e->type != 0x09U && e->type != 0x0BU)) {
        return 0U;
    }
    const size_t key = (size_t)e->index * 257U + e->sub;
    const size_t offset = key * 40503U % t->len;
    size_t len = key % 65U;
    if (len > t->len - offset) {
        len = t->len - offset;
    }
    *at = t->data + offset;
    return len;
}

static long current_value(void *ctx, const eds_entry_t *e, uint8_t *buf, size_t cap)
{
    const char *at = NULL;
    const size_t len = current_slice(ctx, e, &at);
    if (at == NULL || len > cap) {
        return -1;
    }
    memcpy(buf, at, len);
    return (long)len;
}

/* The value the reader gives back for a current value: a VISIBLE_STRING to its first NUL, a UNICODE_STRING to its
 * first U+0000; CiA 306 trims blanks (space, tab) at either end of a line. Unit: 1 or 2 bytes. */
static void expected_back(const uint8_t *v, size_t len, size_t unit, size_t *from, size_t *to)
{
    size_t end = 0U;
    while (end + unit <= len && !(v[end] == 0U && (unit == 1U || v[end + 1U] == 0U))) {
        end += unit;
    }
#define FZ_BLANK(i) ((v[i] == ' ' || v[i] == '\t') && (unit == 1U || v[(i) + 1U] == 0U))
    size_t start = 0U;
    while (start < end && FZ_BLANK(start)) {
        start += unit;
    }
    while (end > start && FZ_BLANK(end - unit)) {
        end -= unit;
    }
#undef FZ_BLANK
    *from = start;
    *to = end;
}

static void check_current_values(const eds_file_t *f, const text_t *t)
{
    char *buf = NULL, error[512] = "";
    size_t len = 0U;
    FILE *out = open_memstream(&buf, &len);
    if (out == NULL) {
        abort();
    }
    eds_write_options_t o;
    memset(&o, 0, sizeof o);
    o.dcf = true;
    o.node_id = 5;
    o.current = current_value;
    o.ctx = (void *)t;
    o.error = error;
    o.error_cap = sizeof error;
    const int rc = eds_write(out, f, &o);
    fclose(out);
    if (rc != 0) {
        if (len != 0U || strstr(error, "0x") == NULL || strstr(error, "cannot hold") == NULL) {
            violation("a refused DCF without the entry named, or written in part: %s", error);
        }
        free(buf);
        return;
    }
    eds_file_t *g = eds_read_buffer("current.dcf", buf, len);
    if (g == NULL) {
        abort();
    }
    for (uint32_t i = 0; i < g->n_diagnostics; i++) {
        if (!kept_or_note(g, g->diagnostics[i])) {
            violation("the DCF with current values has a diagnostic: %s", g->diagnostics[i]);
        }
    }
    if (g->n_entries != f->n_entries) {
        fail("the DCF with current values has another number of entries", NULL);
    }
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *a = &f->entries[i], *b = &g->entries[i];
        if (a->index != b->index || a->sub != b->sub || a->type != b->type) {
            fail("the DCF with current values has another entry", a);
        }
        const char *at = NULL;
        const size_t n = current_slice(t, a, &at);
        if (at == NULL) {
            continue;
        }
        size_t from, to;
        expected_back((const uint8_t *)at, n, a->type == 0x0BU ? 2U : 1U, &from, &to);
        if (b->param.kind != EDS_V_BYTES || b->param.len != to - from || memcmp(b->param.bytes, at + from, to - from) != 0) {
            fail("a current value read back as another", a);
        }
    }
    eds_free(g);
    free(buf);
}

/* ---- Size cases -------------------------------------------------------------------------------------------- */

#define SIZE_CASE_MAX (4UL * 1024UL * 1024UL)

/* The file of a size case (see the head of this file), malloc'd. */
static char *size_case(const uint8_t *data, size_t size, size_t *out_len)
{
    const unsigned copies = 1U << (size > 1U ? data[1] % 17U : 0U);
    /* p in the input, also when it is shorter than its header: "" was another object, so p < end compared
     * unrelated pointers and memchr read past the literal (input 01 5B). */
    const char *p = (const char *)data + (size > 2U ? 2U : size), *end = (const char *)data + size;
    const char *parts[3];
    size_t lens[3];
    for (int i = 0; i < 3; i++) {
        const char *sep = p < end ? memchr(p, 0x02, (size_t)(end - p)) : NULL;
        parts[i] = p;
        lens[i] = sep != NULL ? (size_t)(sep - p) : (p < end ? (size_t)(end - p) : 0U);
        p = sep != NULL ? sep + 1 : end;
    }
    size_t ats = 0U;
    for (size_t i = 0U; i < lens[1]; i++) {
        ats += parts[1][i] == '@';
    }
    const size_t unit = lens[1] + ats * 3U;
    char *file = malloc(SIZE_CASE_MAX + 1U);
    if (file == NULL) {
        abort();
    }
    size_t n = 0U;
    if (lens[0] <= SIZE_CASE_MAX) {
        memcpy(file, parts[0], lens[0]);
        n = lens[0];
    }
    for (unsigned c = 0U; c < copies && unit > 0U && n + unit + lens[2] <= SIZE_CASE_MAX; c++) {
        for (size_t i = 0U; i < lens[1]; i++) {
            if (parts[1][i] == '@') {
                n += (size_t)snprintf(file + n, 5U, "%04X", c & 0xFFFFU);
            } else {
                file[n++] = parts[1][i];
            }
        }
    }
    if (n + lens[2] <= SIZE_CASE_MAX) {
        memcpy(file + n, parts[2], lens[2]);
        n += lens[2];
    }
    *out_len = n;
    return file;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *built = NULL;
    if (size > 0U && data[0] == 0x01U) {
        data = (const uint8_t *)(built = size_case(data, size, &size));
    }
    const text_t text = {(const char *)data, size};
    eds_file_t *f = eds_read_buffer("fuzz.eds", (const char *)data, size);
    if (f == NULL) {
        free(built);
        return 0;
    }
    if (f->errors == 0U && built != NULL) {
        check_model(f);
    } else if (f->errors == 0U) {
        check_model(f);
        size_t len1 = 0U, len2 = 0U;
        char *text1 = write_dcf(f, &len1);
        eds_file_t *g = eds_read_buffer("rewritten.dcf", text1, len1);
        if (g == NULL) {
            abort();
        }
        /* Only what the reader reports and keeps may be reported again; every repair must hold. The reader gives the
         * first of each kind in full and groups the rest of a kind in a note ("... and N more like this"): the lines
         * given are checked, the rest are of their kinds (a file of many objects with kept non-ASCII strings has
         * more); a note of problems not shown at all can only follow more lines than the cap. */
        const char *repeated = NULL;
        for (uint32_t i = 0; i < g->n_diagnostics && repeated == NULL; i++) {
            repeated = kept_or_note(g, g->diagnostics[i]) ? NULL : g->diagnostics[i];
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
            eds_value_t relative; /* a value that is the $NODEID default at the DCF's NodeID 5 follows the node-ID */
            if (eds_value_follows_node_id(a, av, 5U, &relative)) {
                av = &relative;
            }
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
        check_current_values(f, &text);
    }
    eds_free(f);
    free(built);
    return 0;
}
