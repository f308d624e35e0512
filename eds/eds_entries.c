/**
 * @file eds_entries.c
 * @brief One entry (a VAR, or a sub-index) from its keys: name, type, access, PDOMapping, limits, DefaultValue and a
 * DCF's ParameterValue, each repaired and reported.
 */
#include "eds_builder.h"

#include <ctype.h>
#include <string.h>

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
void eds_read_param(builder_t *b, const ini_section_t *s, const ini_key_t *value_key, eds_entry_t *e)
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
bool eds_read_fields(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
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

bool eds_read_entry(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
                       uint8_t default_type, eds_entry_t *e)
{
    if (!eds_read_fields(b, s, index, sub, name, default_type, e)) {
        return false;
    }
    eds_read_param(b, s, NULL, e);
    return true;
}
