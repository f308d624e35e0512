/**
 * @file eds_internal.h
 * @brief What the modules of the EDS reader share: the arena, diagnostics, the INI layer and value parsing.
 */
#ifndef EDS_INTERNAL_H
#define EDS_INTERNAL_H

#include "eds.h"

/* ---- Arena: every string and array of one file, freed at once ------------------------------------------ */
typedef struct eds_arena eds_arena_t;
void *eds_alloc(eds_file_t *f, size_t size);            /* zeroed; NULL only when out of memory */
char *eds_strndup(eds_file_t *f, const char *s, size_t n);
void eds_arena_free(eds_arena_t *arena);

/* ---- Diagnostics ---------------------------------------------------------------------------------------- */
#if defined(__GNUC__)
#define EDS_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define EDS_PRINTF(a, b)
#endif
void eds_warn(eds_file_t *f, uint32_t line, const char *fmt, ...) EDS_PRINTF(3, 4);
void eds_error(eds_file_t *f, uint32_t line, const char *fmt, ...) EDS_PRINTF(3, 4);
/* Adds the notes of the grouped diagnostics (once, when the file is read). */
void eds_diagnostics_done(eds_file_t *f);

/* ---- INI layer: sections and keys with their lines ------------------------------------------------------ */
typedef enum ini_kind {
    INI_OTHER = 0,   /* named: [DeviceInfo], [MandatoryObjects], ... */
    INI_OBJECT,      /* [1018] */
    INI_SUB,         /* [1018sub2] */
    INI_NAME,        /* [2000Name] (CompactSubObj names) */
    INI_VALUE,       /* [2000Value] (CompactSubObj DCF values) */
    INI_LINKS        /* [2000ObjectLinks] */
} ini_kind_t;

typedef struct ini_key {
    const char *key;
    const char *value;   /* trimmed; inline comments are still in it (see ini_number_text) */
    uint32_t line;
    uint32_t section;    /* index into ini.sections */
} ini_key_t;

typedef struct ini_section {
    const char *name;    /* as written (the first time) */
    uint32_t line;
    ini_kind_t kind;
    uint16_t index;
    uint8_t sub;
    uint32_t first, count; /* its keys: ini.keys[first .. first+count-1], sorted by key (case-insensitive) */
} ini_section_t;

typedef struct ini {
    ini_section_t *sections; /* sorted by (kind, index, sub, name) */
    uint32_t n_sections;
    ini_key_t *keys;         /* grouped by section, sorted by key, duplicates removed (the later one kept) */
    uint32_t n_keys;
    ini_key_t *file_order;   /* every kept key in file order (for [FileInfo] etc.) */
} ini_t;

/* Parses text (already UTF-8, BOM removed) into sections and keys. Problems become warnings. */
bool ini_parse(eds_file_t *f, ini_t *ini, char *text, size_t len);
const ini_section_t *ini_find(const ini_t *ini, ini_kind_t kind, uint16_t index, uint8_t sub);
const ini_section_t *ini_find_named(const ini_t *ini, const char *name);
/* The sub-index sections [xxxxsubN] of an index, by sub-index: *count of them from the one returned. */
const ini_section_t *ini_find_subs(const ini_t *ini, uint16_t index, uint32_t *count);
/* ASCII case-insensitive strcmp (section and key names). */
int eds_casecmp(const char *a, const char *b);
const ini_key_t *ini_get(const ini_t *ini, const ini_section_t *s, const char *key);

/* ---- Values ------------------------------------------------------------------------------------------------ */
/* Numeric text of a key: an inline comment (" ;...") is cut off with a warning. Returns the arena copy. */
const char *ini_number_text(eds_file_t *f, const ini_key_t *k);

typedef enum eds_parse {
    EDS_PARSE_OK = 0,
    EDS_PARSE_BAD,        /* not a number of the type's form */
    EDS_PARSE_RANGE,      /* a number outside the type's range: the value is clamped to it */
    EDS_PARSE_NODEID_BAD  /* $NODEID where it has no meaning (reals, strings, limits): the value is without it */
} eds_parse_t;

/* Parses one CiA 306 integer term or $NODEID sum: "0x1A", "012" (octal), "-5", "$NODEID+0x180". *octal_like: a
 * term with a leading 0 and an 8 or 9, read as decimal; *octal: a term read as octal to a value other than its
 * decimal reading ("010": 8). */
bool eds_parse_integer(const char *text, bool *negative, uint64_t *magnitude, bool *nodeid, bool *octal_like,
                       bool *octal);
/* Parses text as a value of type (DefaultValue, LowLimit, HighLimit, ParameterValue). */
eds_parse_t eds_parse_value(eds_file_t *f, uint8_t type, const char *text, eds_value_t *out, char *why, size_t why_cap);
/* The REAL32 (size 4) or REAL64 of IEEE 754 bits. */
double eds_real_from_bits(uint64_t bits, size_t size);
/* Reads a whole unsigned number (object lists, SubNumber, DeviceInfo): CiA 306 forms, no $NODEID. */
bool eds_parse_unsigned(const char *text, uint64_t max, uint64_t *out);

/* Length of the UTF-8 sequence at s (at most n bytes, n > 0), or 0 if it is not valid UTF-8. */
size_t eds_utf8_len(const unsigned char *s, size_t n);

/* ---- Steps of eds_read -------------------------------------------------------------------------------------- */
void eds_read_model(eds_file_t *f, const ini_t *ini);
/* A DCF's ParameterValues that are their $NODEID default at the file's NodeID become node-ID-relative (eds_dcf.c). */
void eds_relative_params(eds_file_t *f);
void eds_check_pdos(eds_file_t *f);
eds_entry_t *eds_find_mut(eds_file_t *f, uint16_t index, uint8_t sub);

#endif /* EDS_INTERNAL_H */
