/* A rules file read event by event into a libyaml document, with its bounds: see rules_yaml.h. */
#define _GNU_SOURCE
#include "eds_class/rules_yaml.h"
#include "text_escape.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* A mapping or a list whose end has not come yet. */
typedef struct open_collection {
    int node;     /* its id in the document */
    bool mapping;
    int key;      /* a mapping's key that waits for its value (0: the next node is a key) */
} open_collection_t;

typedef struct reader {
    const char *path;
    FILE *log;
    yaml_document_t *doc;
    open_collection_t open[RULES_YAML_MAX_DEPTH];
    size_t depth;
    size_t nodes;
    unsigned documents;
    bool failed;
} reader_t;

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static void refuse(reader_t *r, yaml_mark_t at, const char *fmt, ...)
{
    fprintf(r->log, "%s:%lu:%lu: error: ", r->path, (unsigned long)at.line + 1UL, (unsigned long)at.column + 1UL);
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    const size_t len = n < 0 ? 0U : (size_t)n < sizeof text ? (size_t)n : sizeof text - 1U;
    /* the message quotes the file's words (a key, an anchor's name): escaped, one line, no control byte */
    char shown[sizeof text * 4U];
    fwrite(shown, 1U, text_escape(shown, sizeof shown, text, len, TEXT_ONE_LINE), r->log);
    fputc('\n', r->log);
    r->failed = true;
}

/* The whole file in memory, its size checked before any parsing (a pipe has no size to ask for). */
static unsigned char *read_whole(const char *path, FILE *log, size_t *len)
{
    FILE *in = fopen(path, "rb");
    if (in == NULL) {
        fprintf(log, "%s: error: cannot open: %s\n", path, strerror(errno));
        return NULL;
    }
    unsigned char *text = malloc(RULES_YAML_MAX_BYTES + 1U);
    if (text == NULL) {
        fprintf(log, "%s: error: out of memory\n", path);
        fclose(in);
        return NULL;
    }
    *len = fread(text, 1U, RULES_YAML_MAX_BYTES + 1U, in);
    const int read_errno = errno;
    const bool read_failed = ferror(in) != 0;
    fclose(in);
    if (read_failed) {
        fprintf(log, "%s: error: cannot read: %s\n", path, strerror(read_errno));
    } else if (*len > RULES_YAML_MAX_BYTES) {
        fprintf(log, "%s: error: larger than %u bytes: not read (a rules file with every behaviour is a few kB)\n",
                path, RULES_YAML_MAX_BYTES);
    } else {
        return text;
    }
    free(text);
    return NULL;
}

static int by_text_then_place(const void *a, const void *b)
{
    const yaml_node_t *x = *(const yaml_node_t *const *)a, *y = *(const yaml_node_t *const *)b;
    const int order = strcmp((const char *)x->data.scalar.value, (const char *)y->data.scalar.value);
    if (order != 0) {
        return order;
    }
    return (x->start_mark.index > y->start_mark.index) - (x->start_mark.index < y->start_mark.index);
}

/* A key twice in the mapping `map` refused at its second place, the earliest such in the file. Sorted, not compared
 * pairwise: a mapping may have tens of thousands of keys (all scalars: attach refuses others). */
static void refuse_duplicate_keys(reader_t *r, int map)
{
    const yaml_node_t *m = yaml_document_get_node(r->doc, map);
    const size_t n = (size_t)(m->data.mapping.pairs.top - m->data.mapping.pairs.start);
    if (n < 2U) {
        return;
    }
    const yaml_node_t **keys = malloc(n * sizeof *keys);
    if (keys == NULL) {
        refuse(r, m->start_mark, "out of memory");
        return;
    }
    for (size_t i = 0U; i < n; i++) {
        keys[i] = yaml_document_get_node(r->doc, m->data.mapping.pairs.start[i].key);
    }
    qsort(keys, n, sizeof *keys, by_text_then_place);
    const yaml_node_t *again = NULL, *first = NULL;
    for (size_t i = 1U, group = 0U; i < n; i++) {
        if (strcmp((const char *)keys[i]->data.scalar.value, (const char *)keys[group]->data.scalar.value) != 0) {
            group = i;
        } else if (again == NULL || keys[i]->start_mark.index < again->start_mark.index) {
            again = keys[i];
            first = keys[group];
        }
    }
    if (again != NULL) {
        refuse(r, again->start_mark, "the key '%.80s' is given twice in this mapping (first at line %lu, column %lu)",
               (const char *)again->data.scalar.value, (unsigned long)first->start_mark.line + 1UL,
               (unsigned long)first->start_mark.column + 1UL);
    }
    free(keys);
}

/* The new node `id` into the open collection around it: a list's next item, a mapping's key or the key's value. */
static void attach(reader_t *r, int id, bool collection, yaml_mark_t at)
{
    if (r->depth == 0U) {
        return; /* the document's root: libyaml's first node */
    }
    open_collection_t *around = &r->open[r->depth - 1U];
    int ok = 1;
    if (!around->mapping) {
        ok = yaml_document_append_sequence_item(r->doc, around->node, id);
    } else if (around->key == 0) {
        if (collection) {
            refuse(r, at, "a key that is a list or a mapping: the keys of a rules file are plain values");
            return;
        }
        around->key = id;
    } else {
        ok = yaml_document_append_mapping_pair(r->doc, around->node, around->key, id);
        around->key = 0;
    }
    if (!ok) {
        refuse(r, at, "out of memory");
    }
}

/* A new node's place in the document: its id, or 0 (and the reason said) when it may not be added. */
static int add_node(reader_t *r, const yaml_event_t *ev)
{
    const yaml_char_t *anchor = ev->type == YAML_SCALAR_EVENT           ? ev->data.scalar.anchor
                                : ev->type == YAML_SEQUENCE_START_EVENT ? ev->data.sequence_start.anchor
                                                                        : ev->data.mapping_start.anchor;
    if (anchor != NULL) {
        refuse(r, ev->start_mark, "an anchor (&%.80s): a rules file takes no anchors or aliases; write each value out",
               (const char *)anchor);
        return 0;
    }
    if (r->nodes >= RULES_YAML_MAX_NODES) {
        refuse(r, ev->start_mark, "more than %u values, lists and mappings: a rules file needs far fewer",
               RULES_YAML_MAX_NODES);
        return 0;
    }
    int id = 0;
    switch (ev->type) {
    case YAML_SCALAR_EVENT:
        if (memchr(ev->data.scalar.value, '\0', ev->data.scalar.length) != NULL) {
            refuse(r, ev->start_mark, "a value with a NUL character (\\0)");
            return 0;
        }
        /* at most RULES_YAML_MAX_BYTES long: an int holds it */
        id = yaml_document_add_scalar(r->doc, ev->data.scalar.tag, ev->data.scalar.value, (int)ev->data.scalar.length,
                                      ev->data.scalar.style);
        break;
    case YAML_SEQUENCE_START_EVENT:
        id = yaml_document_add_sequence(r->doc, ev->data.sequence_start.tag, ev->data.sequence_start.style);
        break;
    default:
        id = yaml_document_add_mapping(r->doc, ev->data.mapping_start.tag, ev->data.mapping_start.style);
        break;
    }
    if (id == 0) {
        refuse(r, ev->start_mark, "out of memory");
        return 0;
    }
    r->nodes++;
    yaml_node_t *node = yaml_document_get_node(r->doc, id);
    node->start_mark = ev->start_mark; /* the document API leaves the marks zero: errors name the place */
    node->end_mark = ev->end_mark;
    return id;
}

static void on_event(reader_t *r, const yaml_event_t *ev)
{
    switch (ev->type) {
    case YAML_DOCUMENT_START_EVENT:
        if (r->documents++ > 0U) {
            refuse(r, ev->start_mark, "a second YAML document: a rules file is one document");
        }
        break;
    case YAML_ALIAS_EVENT:
        refuse(r, ev->start_mark, "an alias (*%.80s): a rules file takes no anchors or aliases; write each value out",
               (const char *)ev->data.alias.anchor);
        break;
    case YAML_SCALAR_EVENT: {
        const int id = add_node(r, ev);
        if (id != 0) {
            attach(r, id, false, ev->start_mark);
        }
        break;
    }
    case YAML_SEQUENCE_START_EVENT:
    case YAML_MAPPING_START_EVENT: {
        if (r->depth >= RULES_YAML_MAX_DEPTH) {
            refuse(r, ev->start_mark, "lists and mappings nested deeper than %u levels: a rules file needs 5",
                   RULES_YAML_MAX_DEPTH);
            break;
        }
        const int id = add_node(r, ev);
        if (id != 0) {
            attach(r, id, true, ev->start_mark);
        }
        if (!r->failed) {
            r->open[r->depth++] = (open_collection_t){id, ev->type == YAML_MAPPING_START_EVENT, 0};
        }
        break;
    }
    case YAML_SEQUENCE_END_EVENT:
    case YAML_MAPPING_END_EVENT: {
        const int id = r->open[--r->depth].node;
        yaml_document_get_node(r->doc, id)->end_mark = ev->end_mark;
        if (ev->type == YAML_MAPPING_END_EVENT) {
            refuse_duplicate_keys(r, id);
        }
        break;
    }
    case YAML_NO_EVENT:
    case YAML_STREAM_START_EVENT:
    case YAML_STREAM_END_EVENT:
    case YAML_DOCUMENT_END_EVENT:
        break;
    }
}

bool rules_yaml_read(const char *path, FILE *log, yaml_document_t *doc)
{
    memset(doc, 0, sizeof *doc);
    size_t len = 0U;
    unsigned char *text = read_whole(path, log, &len);
    if (text == NULL) {
        return false;
    }
    reader_t r = {.path = path, .log = log, .doc = doc};
    yaml_parser_t parser;
    if (!yaml_document_initialize(doc, NULL, NULL, NULL, 1, 1) || !yaml_parser_initialize(&parser)) {
        fprintf(log, "%s: error: out of memory\n", path);
        yaml_document_delete(doc);
        memset(doc, 0, sizeof *doc);
        free(text);
        return false;
    }
    yaml_parser_set_input_string(&parser, text, len);
    for (bool end = false; !end && !r.failed;) {
        yaml_event_t ev;
        if (!yaml_parser_parse(&parser, &ev)) {
            const char *problem = parser.problem != NULL ? parser.problem : "out of memory";
            if (parser.context != NULL) {
                refuse(&r, parser.problem_mark, "not YAML: %s (%s at line %lu, column %lu)", problem, parser.context,
                       (unsigned long)parser.context_mark.line + 1UL, (unsigned long)parser.context_mark.column + 1UL);
            } else {
                refuse(&r, parser.problem_mark, "not YAML: %s", problem);
            }
            break;
        }
        on_event(&r, &ev);
        end = ev.type == YAML_STREAM_END_EVENT;
        yaml_event_delete(&ev);
    }
    yaml_parser_delete(&parser);
    free(text);
    if (r.failed) {
        yaml_document_delete(doc);
        memset(doc, 0, sizeof *doc);
        return false;
    }
    return true;
}
