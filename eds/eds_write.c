/**
 * @file eds_write.c
 * @brief Writes the model back as a CiA 306 EDS or DCF: every object with explicit sub-index sections, values in
 * the forms the reader reads back to the same model (the round-trip tests hold it to that).
 */
#include "eds_internal.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* Decodes raw little-endian bytes of an entry's type into a value (for a DCF's current values). */
static bool decode_raw(eds_file_t *scratch, uint8_t type, const uint8_t *raw, size_t len, eds_value_t *out)
{
    memset(out, 0, sizeof *out);
    if (eds_type_is_bytes(type)) {
        if (type == 0x09U) { /* a string ends at its first NUL */
            const void *nul = memchr(raw, 0, len);
            if (nul != NULL) {
                len = (size_t)((const uint8_t *)nul - raw);
            }
        } else if (type == 0x0BU) { /* at its first U+0000 */
            for (size_t i = 0U; i + 1U < len; i += 2U) {
                if (raw[i] == 0U && raw[i + 1U] == 0U) {
                    len = i;
                    break;
                }
            }
        }
        out->kind = EDS_V_BYTES;
        out->bytes = eds_alloc(scratch, len + 1U);
        if (out->bytes == NULL) {
            return false;
        }
        memcpy(out->bytes, raw, len);
        out->len = len;
        return true;
    }
    size_t size = eds_type_size(type);
    if (size == 0U || len < size) {
        return false;
    }
    eds_value_t lo;
    eds_type_bound(type, false, &lo);
    out->kind = lo.kind;
    uint64_t u = 0U;
    for (size_t i = size; i-- > 0U;) {
        u = (u << 8) | raw[i];
    }
    if (lo.kind == EDS_V_REAL) {
        out->r = eds_real_from_bits(u, size);
    } else if (lo.kind == EDS_V_INT) {
        if (size < 8U && (u >> (size * 8U - 1U)) != 0U) {
            u |= ~0ULL << (size * 8U); /* sign-extend */
        }
        memcpy(&out->i, &u, sizeof out->i);
    } else {
        out->u = u;
    }
    return true;
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void refuse(const eds_write_options_t *o, const char *fmt, ...)
{
    if (o->error != NULL && o->error_cap > 0U) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(o->error, o->error_cap, fmt, ap);
        va_end(ap);
    }
}

/* What in a string value a line of the file cannot hold so that it reads back as the same bytes (NULL: nothing),
 * and its byte offset. CiA 306 has no escapes: a line break would end the line, and what follows it would be read
 * as keys and sections of their own; bytes that are not UTF-8 would make the reader take the whole file as Latin-1. */
static const char *unwritable(uint8_t type, const eds_value_t *v, size_t *at)
{
    if (v->kind != EDS_V_BYTES || (type != 0x09U && type != 0x0BU)) {
        return NULL; /* numbers, and OCTET_STRING and DOMAIN as hexadecimal digits */
    }
    for (size_t i = 0U; i < v->len;) {
        *at = i;
        if (type == 0x09U) {
            const uint8_t c = v->bytes[i];
            if (c == '\n' || c == '\r') {
                return "a line break";
            }
            if (c == '\0') {
                return "a NUL byte";
            }
            const size_t l = eds_utf8_len(v->bytes + i, v->len - i);
            if (l == 0U) {
                return "bytes that are not UTF-8";
            }
            i += l;
            continue;
        }
        if (i + 1U >= v->len) {
            return "an odd number of bytes (UTF-16 has two per character)";
        }
        const unsigned unit = (unsigned)v->bytes[i] | (unsigned)v->bytes[i + 1U] << 8;
        if (unit == 0x0AU || unit == 0x0DU) {
            return "a line break";
        }
        if (unit == 0U) {
            return "a NUL character";
        }
        if (unit >= 0xD800U && unit < 0xE000U) {
            const unsigned low = i + 3U < v->len ? ((unsigned)v->bytes[i + 2U] | (unsigned)v->bytes[i + 3U] << 8) : 0U;
            if (unit >= 0xDC00U || low < 0xDC00U || low >= 0xE000U) {
                return "an unpaired UTF-16 surrogate";
            }
            i += 2U;
        }
        i += 2U;
    }
    return NULL;
}

/*
 * The ParameterValue of every entry, in the order of f->entries: the current one where the caller gives it, else
 * the file's value or default. Every one is checked before anything is written: NULL when one cannot be written
 * (o->error names it and says why).
 */
static const eds_value_t *dcf_values(eds_file_t *scratch, const eds_file_t *f, const eds_write_options_t *o)
{
    eds_value_t *values = eds_alloc(scratch, ((size_t)f->n_entries + 1U) * sizeof *values);
    if (values == NULL) {
        refuse(o, "out of memory");
        errno = ENOMEM;
        return NULL;
    }
    const uint8_t node_id = o->node_id != 0U ? o->node_id : f->comm.node_id; /* the NodeID written */
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        values[i] = e->param.kind != EDS_V_NONE ? e->param : e->def;
        if (o->current != NULL) {
            uint8_t raw[1024];
            eds_value_t current;
            const long n = o->current(o->ctx, e, raw, sizeof raw);
            if (n >= 0 && (size_t)n <= sizeof raw && decode_raw(scratch, e->type, raw, (size_t)n, &current)) {
                values[i] = current;
            }
        }
        /* What the reader makes of it at the DCF's NodeID: written so (a value read back is the value written). */
        eds_value_t relative;
        if (eds_value_follows_node_id(e, &values[i], node_id, &relative)) {
            values[i] = relative;
        }
        size_t at = 0U;
        const char *why = unwritable(e->type, &values[i], &at);
        if (why != NULL) {
            refuse(o, "0x%04X:%02X: its %s value has %s (at byte %lu), which a line of a CiA 306 file cannot hold; "
                      "nothing written", (unsigned)e->index, (unsigned)e->sub, eds_type_name(e->type), why,
                   (unsigned long)at);
            errno = EINVAL;
            return NULL;
        }
    }
    return values;
}

static void put(FILE *out, const char *key, const char *value)
{
    fprintf(out, "%s=%s\n", key, value != NULL ? value : "");
}

/* A key with a value of the entry's type; the text is as long as the value needs (a fixed buffer cut long strings
 * and domains). False when out of memory. */
static bool put_value(FILE *out, const char *key, uint8_t type, const eds_value_t *v)
{
    char small[64];
    const size_t cap = v->kind == EDS_V_BYTES ? v->len * 2U + 8U : sizeof small;
    char *text = cap <= sizeof small ? small : malloc(cap);
    if (text == NULL) {
        return false;
    }
    eds_format_value(text, cap, type, v);
    put(out, key, text);
    if (text != small) {
        free(text);
    }
    return true;
}

/* param: the entry's DCF value (NULL for an EDS). False when out of memory. */
static bool write_entry(FILE *out, const eds_entry_t *e, const char *section, uint8_t object_type,
                        const eds_write_options_t *o, const eds_value_t *param)
{
    fprintf(out, "\n[%s]\n", section);
    put(out, "ParameterName", e->name);
    if (o->dcf && e->denotation != NULL) {
        put(out, "Denotation", e->denotation);
    }
    fprintf(out, "ObjectType=0x%X\nDataType=0x%04X\nAccessType=%s\n", (unsigned)object_type, (unsigned)e->type,
            eds_access_name(e->access));
    bool ok = put_value(out, "DefaultValue", e->type, &e->def);
    fprintf(out, "PDOMapping=%d\n", e->pdo_mapping ? 1 : 0);
    if (e->low.kind != EDS_V_NONE) {
        ok = put_value(out, "LowLimit", e->type, &e->low) && ok;
    }
    if (e->high.kind != EDS_V_NONE) {
        ok = put_value(out, "HighLimit", e->type, &e->high) && ok;
    }
    if (param != NULL) {
        ok = put_value(out, "ParameterValue", e->type, param) && ok;
    }
    return ok;
}

static void write_list(FILE *out, const eds_file_t *f, const char *name, int which)
{
    unsigned n = 0U;
    for (uint32_t pass = 0; pass < 2U; pass++) {
        if (pass == 1U) {
            fprintf(out, "\n[%s]\nSupportedObjects=%u\n", name, n);
            n = 0U;
        }
        for (uint32_t i = 0; i < f->n_objects; i++) {
            uint16_t x = f->objects[i].index;
            int kind = (x == 0x1000U || x == 0x1001U || x == 0x1018U) ? 0 : (x >= 0x2000U && x <= 0x5FFFU ? 2 : 1);
            if (kind != which) {
                continue;
            }
            n++;
            if (pass == 1U) {
                fprintf(out, "%u=0x%04X\n", n, (unsigned)x);
            }
        }
    }
}

/* [DeviceInfo] keys the model holds (written from it, so repairs are kept); the rest are written as read. */
static const char *const MODEL_KEYS[] = {"VendorName", "VendorNumber", "ProductName", "ProductNumber",
                                         "RevisionNumber", "NrOfRXPDO", "NrOfTXPDO", "LSS_Supported", "Granularity"};

static bool model_key(const char *key)
{
    char prefix[10];
    snprintf(prefix, sizeof prefix, "%s", key);
    if (eds_casecmp(prefix, "BaudRate_") == 0) {
        return true;
    }
    for (size_t i = 0; i < sizeof MODEL_KEYS / sizeof MODEL_KEYS[0]; i++) {
        if (eds_casecmp(key, MODEL_KEYS[i]) == 0) {
            return true;
        }
    }
    return false;
}

static void write_info(FILE *out, const eds_file_t *f, const char *section, const eds_write_options_t *o)
{
    fprintf(out, "%s[%s]\n", strcmp(section, "FileInfo") == 0 ? "" : "\n", section);
    bool is_device = strcmp(section, "DeviceInfo") == 0;
    if (is_device) {
        fprintf(out, "VendorName=%s\nVendorNumber=0x%08lX\nProductName=%s\nProductNumber=0x%08lX\n"
                     "RevisionNumber=0x%08lX\nNrOfRXPDO=%u\nNrOfTXPDO=%u\nLSS_Supported=%d\nGranularity=%u\n",
                f->vendor_name, (unsigned long)f->vendor_number, f->product_name, (unsigned long)f->product_number,
                (unsigned long)f->revision_number, (unsigned)f->nr_of_rxpdo, (unsigned)f->nr_of_txpdo,
                f->lss_supported ? 1 : 0, (unsigned)f->granularity);
        for (unsigned i = EDS_CIA305_RATES; i-- > 0U;) {
            if (eds_cia305_kbit[i] != 0U) {
                fprintf(out, "BaudRate_%u=%d\n", (unsigned)eds_cia305_kbit[i], (f->baud_rates >> i) & 1U);
            }
        }
    }
    for (uint32_t i = 0; i < f->n_info; i++) {
        const eds_info_key_t *k = &f->info[i];
        if (strcmp(k->section, section) != 0 || (is_device && model_key(k->key))) {
            continue;
        }
        if (strcmp(section, "FileInfo") == 0 && o->file_name != NULL && eds_casecmp(k->key, "FileName") == 0) {
            put(out, k->key, o->file_name);
        } else {
            put(out, k->key, k->value);
        }
    }
}

int eds_write(FILE *out, const eds_file_t *f, const eds_write_options_t *options)
{
    eds_write_options_t none;
    memset(&none, 0, sizeof none);
    const eds_write_options_t *o = options != NULL ? options : &none;
    if (o->error != NULL && o->error_cap > 0U) {
        o->error[0] = '\0';
    }
    if (o->file_name != NULL && strpbrk(o->file_name, "\r\n") != NULL) {
        refuse(o, "the file name has a line break, which a line of a CiA 306 file cannot hold; nothing written");
        errno = EINVAL;
        return -1;
    }
    eds_file_t scratch; /* owns decoded current values */
    memset(&scratch, 0, sizeof scratch);
    const eds_value_t *values = NULL;
    if (o->dcf && (values = dcf_values(&scratch, f, o)) == NULL) {
        eds_arena_free(scratch.arena);
        free(scratch.diagnostics);
        return -1;
    }
    bool ok = true;
    write_info(out, f, "FileInfo", o);
    write_info(out, f, "DeviceInfo", o);
    fprintf(out, "\n[DummyUsage]\n");
    for (unsigned t = 1U; t <= 7U; t++) {
        fprintf(out, "Dummy%04X=%d\n", t, (f->dummy_usage >> t) & 1U);
    }
    bool has_comments = false;
    for (uint32_t i = 0; i < f->n_info; i++) {
        has_comments = has_comments || strcmp(f->info[i].section, "Comments") == 0;
    }
    if (has_comments) {
        write_info(out, f, "Comments", o);
    }
    if (o->dcf) {
        uint8_t id = o->node_id != 0U ? o->node_id : f->comm.node_id;
        uint16_t kbit = o->baudrate_kbit != 0U ? o->baudrate_kbit : f->comm.baudrate_kbit;
        fprintf(out, "\n[DeviceComissioning]\nNodeID=%u\nNodeName=%s\nBaudrate=%u\nNetNumber=%lu\nNetworkName=%s\n"
                     "CANopenManager=%d\nLSS_SerialNumber=%lu\n",
                (unsigned)id, f->comm.node_name != NULL ? f->comm.node_name : "", (unsigned)kbit,
                (unsigned long)f->comm.net_number, f->comm.network_name != NULL ? f->comm.network_name : "",
                f->comm.canopen_manager ? 1 : 0, (unsigned long)f->comm.lss_serial_number);
    }
    write_list(out, f, "MandatoryObjects", 0);
    write_list(out, f, "OptionalObjects", 1);
    write_list(out, f, "ManufacturerObjects", 2);
    char section[16];
    for (uint32_t i = 0; i < f->n_objects; i++) {
        const eds_object_t *obj = &f->objects[i];
        const eds_entry_t *first = &f->entries[obj->first];
        bool var = obj->object_type == 0x7U || obj->object_type == 0x2U || obj->object_type == 0x5U;
        snprintf(section, sizeof section, "%04X", (unsigned)obj->index);
        if (var) {
            ok = write_entry(out, first, section, obj->object_type, o, values != NULL ? &values[obj->first] : NULL) && ok;
        } else {
            fprintf(out, "\n[%s]\n", section);
            put(out, "ParameterName", obj->name);
            if (o->dcf && obj->denotation != NULL) {
                put(out, "Denotation", obj->denotation);
            }
            fprintf(out, "ObjectType=0x%X\nSubNumber=0x%X\n", (unsigned)obj->object_type, (unsigned)obj->count);
            for (uint32_t k = 0; k < obj->count; k++) {
                const eds_entry_t *e = &f->entries[obj->first + k];
                snprintf(section, sizeof section, "%04Xsub%X", (unsigned)e->index, (unsigned)e->sub);
                ok = write_entry(out, e, section, 0x7U, o, values != NULL ? &values[obj->first + k] : NULL) && ok;
            }
        }
        if (obj->n_links > 0U) {
            fprintf(out, "\n[%04XObjectLinks]\nObjectLinks=%u\n", (unsigned)obj->index, (unsigned)obj->n_links);
            for (unsigned k = 0; k < obj->n_links; k++) {
                fprintf(out, "%u=0x%04X\n", k + 1U, (unsigned)obj->links[k]);
            }
        }
    }
    eds_arena_free(scratch.arena);
    free(scratch.diagnostics);
    if (!ok) {
        refuse(o, "out of memory");
        errno = ENOMEM;
        return -1;
    }
    return ferror(out) ? -1 : 0;
}
