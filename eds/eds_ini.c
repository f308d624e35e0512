/**
 * @file eds_ini.c
 * @brief The INI layer of the EDS reader: arena, sections and keys with their line numbers (diagnostics:
 * eds_diag.c).
 *
 * Hand-written rather than taken from an INI library (docs/eds.md, "Why its own INI layer"): diagnostics need
 * the line of every key, real files need tolerance (keys before the first section, duplicate sections that
 * must be merged, lines without '='), and the grammar is a few lines.
 */
#include "eds_internal.h"

#include <ctype.h>
#include <stdlib.h>
#include <string.h>

/* ---- Arena ------------------------------------------------------------------------------------------------ */

/* C99 has no eds_align_t: the strictest of the types stored. */
typedef union eds_align {
    long double ld;
    long long ll;
    double d;
    void *p;
} eds_align_t;

struct eds_arena {
    struct eds_arena *next;
    size_t used, cap;
    eds_align_t data[];
};

void *eds_alloc(eds_file_t *f, size_t size)
{
    size = (size + sizeof(eds_align_t) - 1U) / sizeof(eds_align_t) * sizeof(eds_align_t);
    if (size == 0U) {
        size = sizeof(eds_align_t);
    }
    eds_arena_t *a = f->arena;
    if (a == NULL || a->cap - a->used < size) {
        size_t cap = size > 65536U ? size : 65536U;
        eds_arena_t *b = malloc(sizeof(*b) + cap);
        if (b == NULL) {
            return NULL;
        }
        b->next = a;
        b->used = 0U;
        b->cap = cap;
        f->arena = b;
        a = b;
    }
    void *p = (char *)a->data + a->used;
    a->used += size;
    memset(p, 0, size);
    return p;
}

char *eds_strndup(eds_file_t *f, const char *s, size_t n)
{
    char *p = eds_alloc(f, n + 1U);
    if (p != NULL) {
        memcpy(p, s, n);
        p[n] = '\0';
    }
    return p;
}

void eds_arena_free(eds_arena_t *arena)
{
    while (arena != NULL) {
        eds_arena_t *next = arena->next;
        free(arena);
        arena = next;
    }
}

/* ---- Sections --------------------------------------------------------------------------------------------------- */

static int hexval(int c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    c = tolower(c);
    return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

static int casecmp_n(const char *a, const char *b, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        int d = tolower((unsigned char)a[i]) - tolower((unsigned char)b[i]);
        if (d != 0 || a[i] == '\0') {
            return d;
        }
    }
    return 0;
}

int eds_casecmp(const char *a, const char *b)
{
    for (;; a++, b++) {
        int d = tolower((unsigned char)*a) - tolower((unsigned char)*b);
        if (d != 0 || *a == '\0') {
            return d;
        }
    }
}

/* Classifies a section name: object sections by their numbers, so [1018sub01] and [1018SUB1] are one. */
static void classify(ini_section_t *s)
{
    const char *n = s->name;
    s->kind = INI_OTHER;
    int v = 0;
    for (int i = 0; i < 4; i++) {
        int h = hexval((unsigned char)n[i]);
        if (h < 0) {
            return;
        }
        v = v * 16 + h;
    }
    const char *rest = n + 4;
    s->index = (uint16_t)v;
    if (*rest == '\0') {
        s->kind = INI_OBJECT;
    } else if (casecmp_n(rest, "sub", 3) == 0) {
        const char *d = rest + 3;
        size_t len = strlen(d);
        if (len < 1U || len > 2U || hexval((unsigned char)d[0]) < 0 || (len == 2U && hexval((unsigned char)d[1]) < 0)) {
            return;
        }
        s->sub = (uint8_t)(len == 1U ? hexval((unsigned char)d[0]) : hexval((unsigned char)d[0]) * 16 + hexval((unsigned char)d[1]));
        s->kind = INI_SUB;
    } else if (eds_casecmp(rest, "Name") == 0) {
        s->kind = INI_NAME;
    } else if (eds_casecmp(rest, "Value") == 0) {
        s->kind = INI_VALUE;
    } else if (eds_casecmp(rest, "ObjectLinks") == 0) {
        s->kind = INI_LINKS;
    }
}

static int section_cmp(const ini_section_t *a, const ini_section_t *b)
{
    if (a->kind != b->kind) {
        return (int)a->kind - (int)b->kind;
    }
    if (a->kind == INI_OTHER) {
        return eds_casecmp(a->name, b->name);
    }
    if (a->index != b->index) {
        return (int)a->index - (int)b->index;
    }
    return (int)a->sub - (int)b->sub;
}

static int section_qsort(const void *a, const void *b)
{
    int d = section_cmp(a, b);
    return d != 0 ? d : (int)((const ini_section_t *)a)->line - (int)((const ini_section_t *)b)->line;
}

static int key_qsort(const void *pa, const void *pb)
{
    const ini_key_t *a = pa, *b = pb;
    if (a->section != b->section) {
        return a->section < b->section ? -1 : 1;
    }
    int d = eds_casecmp(a->key, b->key);
    if (d != 0) {
        return d;
    }
    return a->line < b->line ? -1 : (a->line > b->line ? 1 : 0);
}

static int line_qsort(const void *pa, const void *pb)
{
    const ini_key_t *a = pa, *b = pb;
    return a->line < b->line ? -1 : (a->line > b->line ? 1 : 0);
}

static char *trim(char *s, char **end)
{
    while (*s == ' ' || *s == '\t') {
        s++;
    }
    char *e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r')) {
        e--;
    }
    *e = '\0';
    if (end != NULL) {
        *end = e;
    }
    return s;
}

/* Growable arrays of the parse (malloc'd; moved into the arena at the end). */
typedef struct grow {
    void *data;
    size_t n, cap, size;
} grow_t;

static void *grow_push(grow_t *g)
{
    if (g->n == g->cap) {
        size_t cap = g->cap == 0U ? 64U : g->cap * 2U;
        void *d = realloc(g->data, cap * g->size);
        if (d == NULL) {
            return NULL;
        }
        g->data = d;
        g->cap = cap;
    }
    void *p = (char *)g->data + g->n * g->size;
    memset(p, 0, g->size);
    g->n++;
    return p;
}

bool ini_parse(eds_file_t *f, ini_t *ini, char *text, size_t len)
{
    grow_t secs = {NULL, 0U, 0U, sizeof(ini_section_t)};
    grow_t keys = {NULL, 0U, 0U, sizeof(ini_key_t)};
    bool ok = true;
    long current = -1;
    bool warned_hash = false, warned_outside = false;
    uint32_t line = 0U;
    char *p = text, *end = text + len;
    while (p < end && ok) {
        line++;
        char *eol = p;
        while (eol < end && *eol != '\n' && *eol != '\r') {
            eol++;
        }
        char *next = eol; /* \n, \r\n and a lone \r end a line */
        if (next < end && *next == '\r') {
            next++;
        }
        if (next < end && *next == '\n') {
            next++;
        }
        *eol = '\0';
        char *s = trim(p, NULL);
        p = next;
        if (*s == '\0' || *s == ';') {
            continue;
        }
        if (*s == '#') {
            if (!warned_hash) {
                eds_warn(f, line, "'#' starts a comment only in some tools (CiA 306: ';'); read as a comment");
                warned_hash = true;
            }
            continue;
        }
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (close == NULL) {
                eds_warn(f, line, "section header without ']'; read as [%s]", s + 1);
                close = s + strlen(s);
            } else if (close[1] != '\0' && close[1] != ';') {
                eds_warn(f, line, "text after the section header ignored: '%s'", close + 1);
            }
            *close = '\0';
            char *name = trim(s + 1, NULL);
            ini_section_t *sec = grow_push(&secs);
            if (sec == NULL || (sec->name = eds_strndup(f, name, strlen(name))) == NULL) {
                ok = false;
                break;
            }
            sec->line = line;
            classify(sec);
            current = (long)secs.n - 1;
            continue;
        }
        char *eq = strchr(s, '=');
        if (eq == NULL) {
            eds_warn(f, line, "neither a [section] nor a key=value line; ignored");
            continue;
        }
        if (current < 0) {
            if (!warned_outside) {
                eds_warn(f, line, "key=value before the first [section]; ignored");
                warned_outside = true;
            }
            continue;
        }
        *eq = '\0';
        char *key = trim(s, NULL);
        char *value = trim(eq + 1, NULL);
        if (*key == '\0') {
            eds_warn(f, line, "a key=value line without a key; ignored");
            continue;
        }
        ini_key_t *k = grow_push(&keys);
        if (k == NULL || (k->key = eds_strndup(f, key, strlen(key))) == NULL ||
            (k->value = eds_strndup(f, value, strlen(value))) == NULL) {
            ok = false;
            break;
        }
        k->line = line;
        k->section = (uint32_t)current;
    }
    if (!ok) {
        free(secs.data);
        free(keys.data);
        eds_error(f, 0U, "out of memory");
        return false;
    }

    /* Merge duplicate sections: sort (stable by line), map each to its first occurrence. */
    ini_section_t *sv = secs.data;
    uint32_t *slot = malloc((secs.n + 1U) * sizeof(uint32_t));
    ini_section_t *sorted = malloc((secs.n + 1U) * sizeof(ini_section_t));
    if (slot == NULL || sorted == NULL) {
        free(slot), free(sorted), free(secs.data), free(keys.data);
        eds_error(f, 0U, "out of memory");
        return false;
    }
    for (size_t i = 0; i < secs.n; i++) {
        sv[i].first = (uint32_t)i; /* remember the original position through the sort */
    }
    if (secs.n > 0U) { /* memcpy and qsort take no NULL, even for 0 bytes */
        memcpy(sorted, sv, secs.n * sizeof(ini_section_t));
        qsort(sorted, secs.n, sizeof(ini_section_t), section_qsort);
    }
    uint32_t n_unique = 0U;
    for (size_t i = 0; i < secs.n; i++) {
        if (n_unique > 0U && section_cmp(&sorted[n_unique - 1U], &sorted[i]) == 0) {
            eds_warn(f, sorted[i].line, "section [%s] appears again (first at line %lu); its keys are merged into it",
                     sorted[i].name, (unsigned long)sorted[n_unique - 1U].line);
        } else {
            sorted[n_unique++] = sorted[i];
        }
        slot[sorted[i].first] = n_unique - 1U;
    }
    ini_key_t *kv = keys.data;
    for (size_t i = 0; i < keys.n; i++) {
        kv[i].section = slot[kv[i].section];
    }
    if (keys.n > 0U) {
        qsort(kv, keys.n, sizeof(ini_key_t), key_qsort);
    }
    /* Drop duplicate keys, keeping the later one. */
    size_t n_keys = 0U;
    for (size_t i = 0; i < keys.n; i++) {
        if (i + 1U < keys.n && kv[i + 1U].section == kv[i].section && eds_casecmp(kv[i + 1U].key, kv[i].key) == 0) {
            eds_warn(f, kv[i].line, "key %s appears again in [%s] (line %lu); the later value is used", kv[i].key,
                     sorted[kv[i].section].name, (unsigned long)kv[i + 1U].line);
            continue;
        }
        kv[n_keys++] = kv[i];
    }
    for (uint32_t s = 0U; s < n_unique; s++) {
        sorted[s].first = 0U;
        sorted[s].count = 0U;
    }
    for (size_t i = n_keys; i-- > 0U;) {
        sorted[kv[i].section].first = (uint32_t)i;
        sorted[kv[i].section].count++;
    }
    ini->sections = eds_alloc(f, (n_unique + 1U) * sizeof(ini_section_t));
    ini->keys = eds_alloc(f, (n_keys + 1U) * sizeof(ini_key_t));
    ini->file_order = eds_alloc(f, (n_keys + 1U) * sizeof(ini_key_t));
    if (ini->sections == NULL || ini->keys == NULL || ini->file_order == NULL) {
        ok = false;
    } else {
        memcpy(ini->sections, sorted, n_unique * sizeof(ini_section_t));
        if (n_keys > 0U) {
            memcpy(ini->keys, kv, n_keys * sizeof(ini_key_t));
            memcpy(ini->file_order, kv, n_keys * sizeof(ini_key_t));
            qsort(ini->file_order, n_keys, sizeof(ini_key_t), line_qsort);
        }
        ini->n_sections = n_unique;
        ini->n_keys = (uint32_t)n_keys;
    }
    free(slot);
    free(sorted);
    free(secs.data);
    free(keys.data);
    if (!ok) {
        eds_error(f, 0U, "out of memory");
    }
    return ok;
}

/* The first section not ordered before probe (sections are sorted by section_cmp): O(log n). */
static size_t lower_bound(const ini_t *ini, const ini_section_t *probe)
{
    size_t lo = 0U, hi = ini->n_sections;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2U;
        if (section_cmp(&ini->sections[mid], probe) < 0) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return lo;
}

static const ini_section_t *find(const ini_t *ini, const ini_section_t *probe)
{
    size_t at = lower_bound(ini, probe);
    return at < ini->n_sections && section_cmp(&ini->sections[at], probe) == 0 ? &ini->sections[at] : NULL;
}

const ini_section_t *ini_find(const ini_t *ini, ini_kind_t kind, uint16_t index, uint8_t sub)
{
    ini_section_t probe;
    memset(&probe, 0, sizeof probe);
    probe.kind = kind;
    probe.index = index;
    probe.sub = sub;
    return find(ini, &probe);
}

/* A binary search too: named sections sort first, by name (a scan per look-up made a file of many named
 * sections take quadratic time). */
const ini_section_t *ini_find_named(const ini_t *ini, const char *name)
{
    ini_section_t probe;
    memset(&probe, 0, sizeof probe);
    probe.kind = INI_OTHER;
    probe.name = name;
    return find(ini, &probe);
}

const ini_section_t *ini_find_subs(const ini_t *ini, uint16_t index, uint32_t *count)
{
    ini_section_t probe;
    memset(&probe, 0, sizeof probe);
    probe.kind = INI_SUB;
    probe.index = index;
    size_t first = lower_bound(ini, &probe), end = first;
    while (end < ini->n_sections && ini->sections[end].kind == INI_SUB && ini->sections[end].index == index) {
        end++;
    }
    *count = (uint32_t)(end - first);
    return &ini->sections[first];
}

const ini_key_t *ini_get(const ini_t *ini, const ini_section_t *s, const char *key)
{
    if (s == NULL) {
        return NULL;
    }
    size_t lo = s->first, hi = (size_t)s->first + s->count;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2U;
        int d = eds_casecmp(ini->keys[mid].key, key);
        if (d == 0) {
            return &ini->keys[mid];
        }
        if (d < 0) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

const char *ini_number_text(eds_file_t *f, const ini_key_t *k)
{
    const char *semi = strchr(k->value, ';');
    if (semi == NULL) {
        return k->value;
    }
    size_t n = (size_t)(semi - k->value);
    while (n > 0U && (k->value[n - 1U] == ' ' || k->value[n - 1U] == '\t')) {
        n--;
    }
    eds_warn(f, k->line, "%s: inline comment '%s' removed (CiA 306 has comments on lines of their own)", k->key, semi);
    const char *copy = eds_strndup(f, k->value, n);
    return copy != NULL ? copy : "";
}
