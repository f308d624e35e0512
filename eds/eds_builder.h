/**
 * @file eds_builder.h
 * @brief What the steps that build the model from the INI sections share (eds_objects.c: objects and the whole
 * model; eds_info.c: [DeviceInfo], commissioning and the object lists; eds_entries.c: one entry's keys).
 */
#ifndef EDS_BUILDER_H
#define EDS_BUILDER_H

#include "eds_internal.h"

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

static inline const char *text_of(const builder_t *b, const ini_section_t *s, const char *key)
{
    const ini_key_t *k = ini_get(b->ini, s, key);
    return k != NULL ? k->value : NULL;
}

/* An unsigned number key; absent -> dflt silently, malformed -> dflt with a warning. */
static inline uint64_t number_of(builder_t *b, const ini_section_t *s, const char *key, uint64_t max, uint64_t dflt)
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

/* [DeviceInfo], [DummyUsage], [DeviceComissioning] and the keys kept for the writer (eds_info.c). */
void eds_read_device_info(builder_t *b);
/* The indices the object lists name, sorted and unique; sections no list names are added (with a warning). */
uint16_t *eds_object_indices(builder_t *b, uint32_t *count);

/*
 * Reads an entry but for its DCF value from section s (for CompactSubObj objects, the object's own section). name
 * overrides ParameterName (compact sub-objects). Returns false when the entry cannot be emulated (unknown data
 * type): the caller leaves it out (eds_entries.c).
 */
bool eds_read_fields(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
                     uint8_t default_type, eds_entry_t *e);
/* The DCF value of an entry: value_key (the [xxxxValue] key of a compact sub-object), else its ParameterValue. */
void eds_read_param(builder_t *b, const ini_section_t *s, const ini_key_t *value_key, eds_entry_t *e);
/* eds_read_fields and eds_read_param. */
bool eds_read_entry(builder_t *b, const ini_section_t *s, uint16_t index, uint8_t sub, const char *name,
                    uint8_t default_type, eds_entry_t *e);

#endif /* EDS_BUILDER_H */
