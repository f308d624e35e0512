/* Behaviour rules of an EDS device: see rules.h and docs/eds.md "Rules". YAML by libyaml (Debian libyaml-dev). */
#define _GNU_SOURCE
#include "eds_class/rules.h"
#include "text_escape.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "eds_class/cia402.h"
#include "eds_class/rules_yaml.h"

/* Every rule is a write to the dictionary each tick, every alarm a read: these bound the work of a node's tick. */
#define RULES_MAX_OBJECTS 1024U
#define RULES_MAX_ALARMS 256U
/* Error lines of one file shown at most (a file of thousands of wrong keys would fill the terminal). */
#define RULES_MAX_ERRORS 20U

typedef enum behaviour {
    B_CONSTANT = 0, B_RAMP, B_SINE, B_WALK, B_STEPS, B_COUNTER, B_FOLLOW
} behaviour_t;

static const char *const BEHAVIOURS[] = {"constant", "ramp", "sine", "random_walk", "steps", "counter", "follow"};

typedef struct rule {
    behaviour_t kind;
    co_od_entry_t row;             /* copies: a sub-index inside a run has no row of its own in the table */
    co_od_entry_t source;          /* follow */
    double a, b, c, d;             /* per kind: see rule_value */
    double lo, hi;                 /* random_walk bounds */
    uint64_t seed;
    uint64_t every_us;             /* up to a day: more than 32 bits of µs */
    bool repeat;
    double *values;                /* steps */
    uint64_t *ends_us;             /* each step's end from the cycle's start: found by bisection in a tick */
    uint32_t n_steps;
} rule_t;

typedef struct alarm {
    co_od_entry_t row;
    bool has_above, has_below;
    double above, below, hysteresis;
    uint16_t code;
    uint8_t reg;
} alarm_t;

struct rules {
    rule_t *rules;
    uint32_t n_rules;
    alarm_t *alarms;
    uint32_t n_alarms;
    bool cia402;
    cia402_objects_t drive;
    uint64_t tick_us;
    char *device;
};

/* Per node, in its model block. */
typedef struct rule_state {
    double value;
    uint64_t rng;
    co_time_us_t next;
} rule_state_t;

typedef struct rules_state {
    co_time_us_t start, last;
    cia402_state_t drive;
    /* rule_state_t[n_rules] then bool[n_alarms] follow */
} rules_state_t;

/* ---- Numbers in OD rows -------------------------------------------------------------------------------------------- */

double rules_get(co_node_t *node, const co_od_entry_t *row)
{
    uint8_t buf[8] = {0};
    size_t len = 0U;
    if (row->size > 8U || co_od_read(node, row->index, row->sub, buf, sizeof buf, &len, CO_ORIGIN_LOCAL) != 0U) {
        return 0.0;
    }
    uint64_t u = 0U;
    for (size_t i = len; i > 0U; i--) {
        u = (u << 8) | buf[i - 1U];
    }
    if (row->type == CO_T_REAL32) {
        const uint32_t b = (uint32_t)u;
        float f;
        memcpy(&f, &b, sizeof f);
        return (double)f;
    }
    if (row->type == CO_T_REAL64) {
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    if (device_type_is_signed(row->type) && len > 0U && len < 8U && (u >> (len * 8U - 1U)) != 0U) {
        u |= ~((UINT64_C(1) << (len * 8U)) - 1U);
    }
    return device_type_is_signed(row->type) ? (double)(int64_t)u : (double)u;
}

void rules_set(co_node_t *node, const co_od_entry_t *row, double value)
{
    uint8_t wire[8];
    if (row->size > 8U || !isfinite(value)) {
        return;
    }
    if (row->type == CO_T_REAL32) {
        const float f = (float)value;
        uint32_t b;
        memcpy(&b, &f, sizeof b);
        for (size_t i = 0U; i < 4U; i++) {
            wire[i] = (uint8_t)(b >> (8U * i));
        }
    } else if (row->type == CO_T_REAL64) {
        uint64_t b;
        memcpy(&b, &value, sizeof b);
        for (size_t i = 0U; i < 8U; i++) {
            wire[i] = (uint8_t)(b >> (8U * i));
        }
    } else {
        const unsigned bits = 8U * row->size;
        double lo = 0.0, hi = ldexp(1.0, (int)bits) - 1.0;
        if (device_type_is_signed(row->type)) {
            lo = -ldexp(1.0, (int)bits - 1);
            hi = ldexp(1.0, (int)bits - 1) - 1.0;
        } else if (row->type == CO_T_BOOLEAN) {
            hi = 1.0;
        }
        double v = nearbyint(value);
        v = v < lo ? lo : (v > hi ? hi : v);
        const uint64_t u = v < 0.0 ? (uint64_t)(int64_t)v : (v >= 18446744073709549568.0 ? UINT64_MAX : (uint64_t)v);
        for (size_t i = 0U; i < row->size; i++) {
            wire[i] = (uint8_t)(u >> (8U * i));
        }
    }
    (void)co_od_write(node, row->index, row->sub, wire, row->size, CO_ORIGIN_LOCAL);
}

/* ---- Parsing ------------------------------------------------------------------------------------------------------- */

typedef struct parse {
    const char *path;
    yaml_document_t doc;
    const co_od_t *od;
    FILE *log;
    bool failed;
    unsigned errors;
} parse_t;

/* "FILE:LINE:COLUMN: error: " (or "FILE: error: " without a place) and fmt with a and b; the first
 * RULES_MAX_ERRORS errors, then a line that says more were found. */
static void rules_parse_error(parse_t *p, const yaml_node_t *at, const char *fmt, const char *a, const char *b)
{
    p->failed = true;
    if (++p->errors > RULES_MAX_ERRORS) {
        if (p->errors == RULES_MAX_ERRORS + 1U) {
            fprintf(p->log, "%s: error: more errors follow; the first %u are shown\n", p->path, RULES_MAX_ERRORS);
        }
        return;
    }
    if (at != NULL) {
        fprintf(p->log, "%s:%lu:%lu: error: ", p->path, (unsigned long)at->start_mark.line + 1UL,
                (unsigned long)at->start_mark.column + 1UL);
    } else {
        fprintf(p->log, "%s: error: ", p->path);
    }
    /* a and b quote the file's own words: escaped, so that an error stays one line and no control byte of the
     * file reaches the terminal (text_escape.h) */
    char ea[256];
    char eb[256];
    ea[text_escape(ea, sizeof ea - 1U, a != NULL ? a : "", a != NULL ? strlen(a) : 0U, TEXT_ONE_LINE)] = '\0';
    eb[text_escape(eb, sizeof eb - 1U, b != NULL ? b : "", b != NULL ? strlen(b) : 0U, TEXT_ONE_LINE)] = '\0';
    fprintf(p->log, fmt, ea, eb);
    fputc('\n', p->log);
}

static const char *scalar(const yaml_node_t *n)
{
    return n != NULL && n->type == YAML_SCALAR_NODE ? (const char *)n->data.scalar.value : NULL;
}

static yaml_node_t *node_at(parse_t *p, int id) { return yaml_document_get_node(&p->doc, id); }

/* The value of key in a mapping, or NULL. */
static yaml_node_t *lookup(parse_t *p, const yaml_node_t *map, const char *key)
{
    if (map == NULL || map->type != YAML_MAPPING_NODE) {
        return NULL;
    }
    for (yaml_node_pair_t *pair = map->data.mapping.pairs.start; pair < map->data.mapping.pairs.top; pair++) {
        const char *k = scalar(node_at(p, pair->key));
        if (k != NULL && strcmp(k, key) == 0) {
            return node_at(p, pair->value);
        }
    }
    return NULL;
}

/* Every key of a mapping must be one of allowed (NULL-terminated). */
static void only_keys(parse_t *p, const yaml_node_t *map, const char *const *allowed, const char *what)
{
    if (map == NULL || map->type != YAML_MAPPING_NODE) {
        rules_parse_error(p, map, "%s: a mapping (key: value) is expected here%s", what, NULL);
        return;
    }
    for (yaml_node_pair_t *pair = map->data.mapping.pairs.start; pair < map->data.mapping.pairs.top; pair++) {
        const yaml_node_t *kn = node_at(p, pair->key);
        const char *k = scalar(kn);
        bool ok = false;
        for (size_t i = 0U; k != NULL && allowed[i] != NULL; i++) {
            ok = ok || strcmp(k, allowed[i]) == 0;
        }
        if (!ok) {
            char list[256] = "";
            for (size_t i = 0U; allowed[i] != NULL; i++) {
                strncat(list, i > 0U ? ", " : "", sizeof list - strlen(list) - 1U);
                strncat(list, allowed[i], sizeof list - strlen(list) - 1U);
            }
            char known[300];
            snprintf(known, sizeof known, "%s: unknown key '%%s' (known: %s)", what, list);
            rules_parse_error(p, kn, known, k != NULL ? k : "?", NULL);
        }
    }
}

static double number(parse_t *p, const yaml_node_t *n, const char *what)
{
    const char *t = scalar(n);
    char *end = NULL;
    errno = 0;
    double v = 0.0;
    if (t != NULL) {
        v = (strncmp(t, "0x", 2) == 0 || strncmp(t, "0X", 2) == 0) ? (double)strtoull(t, &end, 16) : strtod(t, &end);
    }
    if (t == NULL || end == t || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        rules_parse_error(p, n, "%s: '%s' is not a number", what, t != NULL ? t : "(not a value)");
        return 0.0;
    }
    return v;
}

static double key_number(parse_t *p, const yaml_node_t *map, const char *key, double dflt, bool required, const char *what)
{
    const yaml_node_t *n = lookup(p, map, key);
    if (n == NULL) {
        if (required) {
            rules_parse_error(p, map, "%s needs '%s'", what, key);
        }
        return dflt;
    }
    return number(p, n, what);
}

/* A duration given in ms (1 ms .. 1 day), in µs. */
static uint64_t key_ms(parse_t *p, const yaml_node_t *map, const char *key, double dflt, const char *what)
{
    const double ms = key_number(p, map, key, dflt, false, what);
    if (!(ms >= 1.0 && ms <= 86400000.0)) {
        rules_parse_error(p, lookup(p, map, key), "%s: %s must be 1 ms .. 1 day", what, key);
        return 1000U;
    }
    return (uint64_t)(ms * 1000.0); /* a day is 8.64e10 µs: past 32 bits (found by the long run of fuzz_rules) */
}

/* true/false (absent: false) */
static bool flag(parse_t *p, const yaml_node_t *n, const char *what)
{
    const char *t = scalar(n);
    if (n == NULL) {
        return false;
    }
    if (t != NULL && (strcmp(t, "true") == 0 || strcmp(t, "false") == 0)) {
        return t[0] == 't';
    }
    rules_parse_error(p, n, "%s: '%s' is not true or false", what, t != NULL ? t : "?");
    return false;
}

/* "0x6064", "0x6064:00", "6064:1": an existing numeric object of at most 8 bytes. */
/* The numeric object n names into *out; false (and a failure) if it is none. */
static bool object(parse_t *p, const yaml_node_t *n, const char *what, co_od_entry_t *out)
{
    uint16_t index;
    uint8_t sub;
    const char *t = scalar(n);
    if (t == NULL || !device_parse_address(t, &index, &sub)) {
        rules_parse_error(p, n, "%s: '%s' is not an object (0xINDEX or 0xINDEX:SUB)", what, t != NULL ? t : "(not a value)");
        return false;
    }
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(p->od, index, sub, &one);
    if (e == NULL) {
        rules_parse_error(p, n, "%s: the device has no object %s", what, t);
        return false;
    }
    if (e->size > 8U || e->type == CO_T_VISIBLE_STRING || e->type == CO_T_OCTET_STRING || e->type == CO_T_UNICODE_STRING ||
        e->type == CO_T_DOMAIN) {
        rules_parse_error(p, n, "%s: %s is not a number", what, t);
        return false;
    }
    *out = *e;
    return true;
}

static void parse_rule(parse_t *p, rule_t *r, const yaml_node_t *key, const yaml_node_t *body)
{
    const char *name = scalar(key);
    (void)object(p, key, "objects", &r->row);
    if (body == NULL || body->type != YAML_MAPPING_NODE || body->data.mapping.pairs.top - body->data.mapping.pairs.start != 1) {
        rules_parse_error(p, body != NULL ? body : key, "%s: one behaviour is expected (constant, ramp, sine, random_walk, steps, "
                                          "counter, follow)%s", name, NULL);
        return;
    }
    const yaml_node_pair_t *pair = body->data.mapping.pairs.start;
    const char *kind = scalar(node_at(p, pair->key));
    const yaml_node_t *v = node_at(p, pair->value);
    size_t k = 0U;
    while (k < sizeof BEHAVIOURS / sizeof BEHAVIOURS[0] && (kind == NULL || strcmp(kind, BEHAVIOURS[k]) != 0)) {
        k++;
    }
    if (k == sizeof BEHAVIOURS / sizeof BEHAVIOURS[0]) {
        rules_parse_error(p, node_at(p, pair->key), "%s: unknown behaviour '%s' (constant, ramp, sine, random_walk, steps, counter, "
                                       "follow)", name, kind);
        return;
    }
    r->kind = (behaviour_t)k;
    switch (r->kind) {
    case B_CONSTANT:
        r->a = number(p, v, "constant");
        break;
    case B_RAMP:
        only_keys(p, v, (const char *const[]){"from", "to", "per_s", "repeat", NULL}, "ramp");
        r->a = key_number(p, v, "from", 0.0, true, "ramp");
        r->b = key_number(p, v, "to", 0.0, true, "ramp");
        r->c = fabs(key_number(p, v, "per_s", 0.0, true, "ramp"));
        r->repeat = flag(p, lookup(p, v, "repeat"), "ramp");
        if (r->c == 0.0) {
            rules_parse_error(p, v, "ramp: per_s must not be 0%s%s", NULL, NULL);
        }
        break;
    case B_SINE:
        only_keys(p, v, (const char *const[]){"offset", "amplitude", "period_ms", "phase_deg", NULL}, "sine");
        r->a = key_number(p, v, "offset", 0.0, false, "sine");
        r->b = key_number(p, v, "amplitude", 0.0, true, "sine");
        r->c = (double)key_ms(p, v, "period_ms", 1000.0, "sine") / 1e6;
        r->d = key_number(p, v, "phase_deg", 0.0, false, "sine");
        break;
    case B_WALK:
        only_keys(p, v, (const char *const[]){"start", "step", "min", "max", "seed", "every_ms", NULL}, "random_walk");
        r->a = key_number(p, v, "start", 0.0, true, "random_walk");
        r->b = fabs(key_number(p, v, "step", 0.0, true, "random_walk"));
        r->lo = key_number(p, v, "min", -INFINITY, false, "random_walk");
        r->hi = key_number(p, v, "max", INFINITY, false, "random_walk");
        const double seed = key_number(p, v, "seed", 1.0, false, "random_walk");
        if (!(seed >= 0.0 && seed <= 9007199254740992.0)) {
            rules_parse_error(p, lookup(p, v, "seed"), "random_walk: seed must be 0 .. 2^53%s%s", NULL, NULL);
        } else {
            r->seed = (uint64_t)seed;
        }
        r->every_us = key_ms(p, v, "every_ms", 100.0, "random_walk");
        if (r->lo > r->hi) {
            rules_parse_error(p, v, "random_walk: min > max%s%s", NULL, NULL);
        }
        break;
    case B_COUNTER:
        only_keys(p, v, (const char *const[]){"start", "step", "every_ms", "wrap", NULL}, "counter");
        r->a = key_number(p, v, "start", 0.0, false, "counter");
        r->b = key_number(p, v, "step", 1.0, false, "counter");
        r->c = key_number(p, v, "wrap", INFINITY, false, "counter");
        r->every_us = key_ms(p, v, "every_ms", 1000.0, "counter");
        break;
    case B_FOLLOW:
        only_keys(p, v, (const char *const[]){"object", "lag_ms", "gain", "offset", NULL}, "follow");
        (void)object(p, lookup(p, v, "object"), "follow", &r->source);
        r->a = key_number(p, v, "lag_ms", 0.0, false, "follow") / 1000.0;
        r->b = key_number(p, v, "gain", 1.0, false, "follow");
        r->c = key_number(p, v, "offset", 0.0, false, "follow");
        if (r->a < 0.0) {
            rules_parse_error(p, v, "follow: lag_ms must not be negative%s%s", NULL, NULL);
        }
        break;
    case B_STEPS: {
        /* steps: [[VALUE, MS], ...] (repeating) */
        if (v->type != YAML_SEQUENCE_NODE || v->data.sequence.items.top == v->data.sequence.items.start) {
            rules_parse_error(p, v, "steps: a list of [value, ms] pairs is expected%s%s", NULL, NULL);
            break;
        }
        const size_t n = (size_t)(v->data.sequence.items.top - v->data.sequence.items.start);
        r->values = calloc(n, sizeof *r->values);
        r->ends_us = calloc(n, sizeof *r->ends_us);
        if (r->values == NULL || r->ends_us == NULL) {
            rules_parse_error(p, v, "out of memory%s%s", NULL, NULL);
            break;
        }
        for (size_t i = 0U; i < n; i++) {
            const yaml_node_t *item = node_at(p, v->data.sequence.items.start[i]);
            if (item == NULL || item->type != YAML_SEQUENCE_NODE || item->data.sequence.items.top - item->data.sequence.items.start != 2) {
                rules_parse_error(p, item, "steps: each step is [value, ms]%s%s", NULL, NULL);
                break;
            }
            r->values[i] = number(p, node_at(p, item->data.sequence.items.start[0]), "steps");
            const double ms = number(p, node_at(p, item->data.sequence.items.start[1]), "steps");
            if (!(ms >= 1.0 && ms <= 86400000.0)) {
                rules_parse_error(p, item, "steps: a step lasts 1 ms .. 1 day%s%s", NULL, NULL);
                break;
            }
            r->ends_us[i] = (i > 0U ? r->ends_us[i - 1U] : 0U) + (uint64_t)(ms * 1000.0); /* < 2^16 days: < 2^53 us */
            r->n_steps++;
        }
        break;
    }
    }
}

static void parse_alarm(parse_t *p, alarm_t *a, const yaml_node_t *n)
{
    only_keys(p, n, (const char *const[]){"object", "above", "below", "hysteresis", "emcy", "register", NULL}, "alarms");
    (void)object(p, lookup(p, n, "object"), "alarms", &a->row);
    a->has_above = lookup(p, n, "above") != NULL;
    a->has_below = lookup(p, n, "below") != NULL;
    a->above = key_number(p, n, "above", 0.0, false, "alarms");
    a->below = key_number(p, n, "below", 0.0, false, "alarms");
    a->hysteresis = fabs(key_number(p, n, "hysteresis", 0.0, false, "alarms"));
    const double code = key_number(p, n, "emcy", 0.0, true, "alarms");
    const double reg = key_number(p, n, "register", 0x01, false, "alarms");
    if (!a->has_above && !a->has_below) {
        rules_parse_error(p, n, "alarms: give 'above' or 'below' (or both)%s%s", NULL, NULL);
    }
    if (!(code >= 0x1000 && code <= 0xFFFF && reg >= 1 && reg <= 0xFF)) {
        rules_parse_error(p, n, "alarms: emcy is an error code 0x1000..0xFFFF, register the 0x1001 bits 0x01..0xFF%s%s", NULL, NULL);
        return; /* no cast of a number out of range (undefined behaviour: found by fuzz_rules) */
    }
    a->code = (uint16_t)code;
    a->reg = (uint8_t)((unsigned)reg | 0x01U); /* CiA 301: bit 0 (generic error) with every error */
}

/* Two keys of objects that name one object ("0x2000" and "0x2000:00"): the duplicate keys the YAML reader cannot
 * see. Two rules would write the object in turn every tick. At most RULES_MAX_OBJECTS rules: compared pairwise. */
static void refuse_same_object_twice(parse_t *p, const rules_t *r, const yaml_node_t *objects)
{
    for (uint32_t i = 1U; i < r->n_rules; i++) {
        const co_od_entry_t *row = &r->rules[i].row;
        for (uint32_t j = 0U; j < i; j++) {
            if (r->rules[j].row.size != 0U && row->size != 0U && r->rules[j].row.index == row->index &&
                r->rules[j].row.sub == row->sub) {
                const yaml_node_t *first = node_at(p, objects->data.mapping.pairs.start[j].key);
                char place[64];
                snprintf(place, sizeof place, "line %lu, column %lu", (unsigned long)first->start_mark.line + 1UL,
                         (unsigned long)first->start_mark.column + 1UL);
                rules_parse_error(p, node_at(p, objects->data.mapping.pairs.start[i].key),
                     "objects: '%s' names an object that has a rule already (at %s)",
                     scalar(node_at(p, objects->data.mapping.pairs.start[i].key)), place);
                break;
            }
        }
    }
}

static void parse_document(parse_t *p, rules_t *r)
{
    const yaml_node_t *root = yaml_document_get_root_node(&p->doc);
    if (root == NULL) {
        rules_parse_error(p, NULL, "an empty rules file%s%s", NULL, NULL);
        return;
    }
    only_keys(p, root, (const char *const[]){"device", "tick_ms", "objects", "alarms", "profile", NULL}, "rules");
    if (p->failed) {
        return;
    }
    const char *device = scalar(lookup(p, root, "device"));
    if (device != NULL) {
        r->device = strdup(device);
    }
    r->tick_us = key_ms(p, root, "tick_ms", 10.0, "tick_ms");
    const yaml_node_t *objects = lookup(p, root, "objects");
    if (objects != NULL) {
        if (objects->type != YAML_MAPPING_NODE) {
            rules_parse_error(p, objects, "objects: a mapping of 0xINDEX[:SUB]: behaviour is expected%s%s", NULL, NULL);
            return;
        }
        const size_t n = (size_t)(objects->data.mapping.pairs.top - objects->data.mapping.pairs.start);
        if (n > RULES_MAX_OBJECTS) {
            char most[48];
            snprintf(most, sizeof most, "%u", RULES_MAX_OBJECTS);
            rules_parse_error(p, objects, "objects: more than %s objects (each one is written every tick)%s", most, NULL);
            return;
        }
        r->rules = calloc(n + 1U, sizeof *r->rules);
        for (size_t i = 0U; r->rules != NULL && i < n; i++) {
            const yaml_node_pair_t *pair = &objects->data.mapping.pairs.start[i];
            parse_rule(p, &r->rules[r->n_rules++], node_at(p, pair->key), node_at(p, pair->value));
        }
        refuse_same_object_twice(p, r, objects);
    }
    const yaml_node_t *alarms = lookup(p, root, "alarms");
    if (alarms != NULL) {
        if (alarms->type != YAML_SEQUENCE_NODE) {
            rules_parse_error(p, alarms, "alarms: a list is expected%s%s", NULL, NULL);
            return;
        }
        const size_t n = (size_t)(alarms->data.sequence.items.top - alarms->data.sequence.items.start);
        if (n > RULES_MAX_ALARMS) {
            char most[48];
            snprintf(most, sizeof most, "%u", RULES_MAX_ALARMS);
            rules_parse_error(p, alarms, "alarms: more than %s alarms (each one reads its object every tick)%s", most, NULL);
            return;
        }
        r->alarms = calloc(n + 1U, sizeof *r->alarms);
        for (size_t i = 0U; r->alarms != NULL && i < n; i++) {
            parse_alarm(p, &r->alarms[r->n_alarms++], node_at(p, alarms->data.sequence.items.start[i]));
        }
    }
    const yaml_node_t *profile = lookup(p, root, "profile");
    if (profile != NULL) {
        const char *name = scalar(profile);
        char why[160];
        if (name == NULL || strcmp(name, "cia402") != 0) {
            rules_parse_error(p, profile, "profile: '%s' is not a profile (cia402)%s", name != NULL ? name : "?", NULL);
        } else if (!cia402_resolve(p->od, &r->drive, why, sizeof why)) {
            rules_parse_error(p, profile, "profile: %s%s", why, NULL);
        } else {
            r->cia402 = true;
        }
    }
}

rules_t *rules_load(const char *path, const co_od_t *od, FILE *log, const char **device)
{
    *device = NULL;
    parse_t p;
    memset(&p, 0, sizeof p);
    p.path = path;
    p.od = od;
    p.log = log;
    if (!rules_yaml_read(path, log, &p.doc)) {
        return NULL;
    }
    rules_t *r = calloc(1U, sizeof *r);
    if (r == NULL) {
        fprintf(log, "%s: error: out of memory\n", path);
        yaml_document_delete(&p.doc);
        return NULL;
    }
    parse_document(&p, r);
    yaml_document_delete(&p.doc);
    if (p.failed) {
        rules_free(r);
        return NULL;
    }
    *device = r->device;
    return r;
}

void rules_free(rules_t *r)
{
    if (r == NULL) {
        return;
    }
    for (uint32_t i = 0U; r->rules != NULL && i < r->n_rules; i++) {
        free(r->rules[i].values);
        free(r->rules[i].ends_us);
    }
    free(r->rules);
    free(r->alarms);
    free(r->device);
    free(r);
}

/* ---- Running ------------------------------------------------------------------------------------------------------- */

size_t rules_state_size(const rules_t *r)
{
    return sizeof(rules_state_t) + r->n_rules * sizeof(rule_state_t) + r->n_alarms * sizeof(bool);
}

static rule_state_t *rule_states(void *state) { return (rule_state_t *)((rules_state_t *)state + 1); }

static bool *alarm_states(const rules_t *r, void *state) { return (bool *)(rule_states(state) + r->n_rules); }

static uint64_t xorshift(uint64_t *s)
{
    uint64_t x = *s != 0U ? *s : 0x9E3779B97F4A7C15ULL;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *s = x;
    return x;
}

void rules_power_on(const rules_t *r, void *state, device_t *dev, co_time_us_t now)
{
    rules_state_t *st = state;
    st->start = now;
    st->last = now;
    rule_state_t *rs = rule_states(state);
    for (uint32_t i = 0U; i < r->n_rules; i++) {
        const rule_t *rule = &r->rules[i];
        rs[i].rng = rule->seed * 0x9E3779B97F4A7C15ULL + 1U;
        rs[i].next = now + rule->every_us;
        rs[i].value = rule->kind == B_WALK || rule->kind == B_COUNTER ? rule->a
                      : rule->kind == B_FOLLOW ? rules_get(&dev->node, &rule->row) : 0.0;
    }
    bool *active = alarm_states(r, state);
    for (uint32_t i = 0U; i < r->n_alarms; i++) {
        active[i] = false;
    }
    if (r->cia402) {
        cia402_power_on(&r->drive, &st->drive, dev, now);
    }
}

/* The value of a rule at time t (seconds since power-on); dt: since the last step. */
static double rule_value(const rule_t *r, rule_state_t *s, device_t *dev, double t, double dt, co_time_us_t now)
{
    switch (r->kind) {
    case B_CONSTANT:
        return r->a;
    case B_RAMP: {
        const double span = fabs(r->b - r->a), done = r->c * t;
        const double dir = r->b >= r->a ? 1.0 : -1.0;
        if (done < span || span == 0.0) {
            return r->a + dir * (span == 0.0 ? 0.0 : done);
        }
        return r->repeat ? r->a + dir * fmod(done, span) : r->b;
    }
    case B_SINE:
        return r->a + r->b * sin(2.0 * M_PI * t / r->c + r->d * M_PI / 180.0);
    case B_WALK:
        while (now >= s->next) {
            const double u = (double)(xorshift(&s->rng) >> 11) / 9007199254740992.0; /* [0, 1) */
            s->value += (2.0 * u - 1.0) * r->b;
            s->value = s->value < r->lo ? r->lo : (s->value > r->hi ? r->hi : s->value);
            s->next += r->every_us;
        }
        return s->value;
    case B_COUNTER:
        while (now >= s->next) {
            s->value += r->b;
            if (s->value > r->c) {
                s->value = r->a;
            }
            s->next += r->every_us;
        }
        return s->value;
    case B_STEPS: {
        if (r->n_steps == 0U) {
            return 0.0;
        }
        const uint64_t at = (uint64_t)(t * 1e6) % r->ends_us[r->n_steps - 1U];
        uint32_t lo = 0U, hi = r->n_steps - 1U; /* the first step that ends after at */
        while (lo < hi) {
            const uint32_t mid = lo + (hi - lo) / 2U;
            if (r->ends_us[mid] > at) {
                hi = mid;
            } else {
                lo = mid + 1U;
            }
        }
        return r->values[lo];
    }
    case B_FOLLOW: {
        const double x = rules_get(&dev->node, &r->source) * r->b + r->c;
        s->value = r->a <= 0.0 ? x : s->value + (x - s->value) * (1.0 - exp(-dt / r->a));
        return s->value;
    }
    }
    return 0.0;
}

co_time_us_t rules_step(const rules_t *r, void *state, device_t *dev, co_time_us_t now)
{
    rules_state_t *st = state;
    if (now < st->last) {
        now = st->last;
    }
    const double t = (double)(now - st->start) / 1e6, dt = (double)(now - st->last) / 1e6;
    st->last = now;
    co_time_us_t next = CO_NEVER;
    rule_state_t *rs = rule_states(state);
    for (uint32_t i = 0U; i < r->n_rules; i++) {
        const rule_t *rule = &r->rules[i];
        /* After a long stall (a suspended host, a jump of the clock) a walk or a counter simulates only its last
         * 1000 ticks: the grid moves on, and the node is never held up by a catch-up linear in the gap. */
        if ((rule->kind == B_WALK || rule->kind == B_COUNTER) && now >= rs[i].next) {
            const uint64_t behind = (now - rs[i].next) / rule->every_us;
            if (behind > 1000U) {
                rs[i].next += (behind - 1000U) * rule->every_us;
            }
        }
        rules_set(&dev->node, &rule->row, rule_value(rule, &rs[i], dev, t, dt, now));
        const co_time_us_t due = rule->kind == B_CONSTANT ? CO_NEVER
                                 : (rule->kind == B_WALK || rule->kind == B_COUNTER) ? rs[i].next : now + r->tick_us;
        next = due < next ? due : next;
    }
    bool *active = alarm_states(r, state);
    for (uint32_t i = 0U; i < r->n_alarms; i++) {
        const alarm_t *a = &r->alarms[i];
        const double v = rules_get(&dev->node, &a->row);
        const bool out = (a->has_above && v > a->above) || (a->has_below && v < a->below);
        const bool back = (!a->has_above || v <= a->above - a->hysteresis) && (!a->has_below || v >= a->below + a->hysteresis);
        if (out && !active[i]) {
            active[i] = co_emcy_raise(&dev->node, a->code, a->reg, NULL);
        } else if (active[i] && back) {
            (void)co_emcy_clear(&dev->node, a->code, NULL);
            active[i] = false;
        }
    }
    if (r->cia402) {
        const co_time_us_t due = cia402_step(&r->drive, &st->drive, dev, now);
        next = due < next ? due : next;
    }
    return next;
}

uint32_t rules_on_write(const rules_t *r, void *state, device_t *dev, const co_od_entry_t *e, const uint8_t *data,
                        size_t len)
{
    rules_state_t *st = state;
    if (r->cia402 && e != NULL && e->index == r->drive.controlword->index && e->sub == r->drive.controlword->sub && len >= 2U) {
        /* the hook runs before the value is stored: the statusword is set from the new controlword */
        cia402_control(&r->drive, &st->drive, dev, (uint16_t)(data[0] | (data[1] << 8)));
    }
    return 0U;
}
