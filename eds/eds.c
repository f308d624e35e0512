/**
 * @file eds.c
 * @brief Entry points of the EDS reader: the file's bytes (size, encoding), the steps, lookups, freeing.
 */
#include "eds_internal.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static eds_file_t *new_file(const char *name)
{
    eds_file_t *f = calloc(1U, sizeof *f);
    if (f == NULL) {
        return NULL;
    }
    f->path = eds_strndup(f, name, strlen(name));
    if (f->path == NULL) {
        free(f);
        return NULL;
    }
    return f;
}

size_t eds_utf8_len(const unsigned char *s, size_t n)
{
    unsigned char c = s[0];
    size_t len;
    uint32_t min;
    if (c < 0x80U) {
        return 1U;
    } else if ((c & 0xE0U) == 0xC0U) {
        len = 2U, min = 0x80U;
    } else if ((c & 0xF0U) == 0xE0U) {
        len = 3U, min = 0x800U;
    } else if ((c & 0xF8U) == 0xF0U) {
        len = 4U, min = 0x10000U;
    } else {
        return 0U;
    }
    if (n < len) {
        return 0U;
    }
    uint32_t cp = c & (0x7FU >> len);
    for (size_t i = 1U; i < len; i++) {
        if ((s[i] & 0xC0U) != 0x80U) {
            return 0U;
        }
        cp = (cp << 6) | (s[i] & 0x3FU);
    }
    if (cp < min || cp > 0x10FFFFU || (cp >= 0xD800U && cp < 0xE000U)) {
        return 0U;
    }
    return len;
}

static uint32_t line_of(const char *data, size_t pos)
{
    uint32_t line = 1U;
    for (size_t i = 0U; i < pos; i++) {
        if (data[i] == '\n' || (data[i] == '\r' && (i + 1U >= pos || data[i + 1U] != '\n'))) {
            line++;
        }
    }
    return line;
}

/* The text as UTF-8 in the arena (Latin-1 converted), NUL-terminated; NULL when it cannot be text. */
static char *decode(eds_file_t *f, const char *data, size_t len, size_t *out_len)
{
    if (len >= 3U && memcmp(data, "\xEF\xBB\xBF", 3U) == 0) {
        data += 3, len -= 3U; /* UTF-8 byte order mark: allowed, not part of the text */
    } else if (len >= 2U && ((unsigned char)data[0] == 0xFFU || (unsigned char)data[0] == 0xFEU) &&
               ((unsigned char)data[1] == 0xFEU || (unsigned char)data[1] == 0xFFU)) {
        eds_error(f, 1U, "UTF-16 text: CiA 306 files are 8-bit text (save the file as UTF-8 or Latin-1)");
        return NULL;
    }
    const void *nul = memchr(data, '\0', len);
    if (nul != NULL) {
        eds_error(f, line_of(data, (size_t)((const char *)nul - data)),
                  "a NUL byte: this is binary data, not an EDS/DCF text file");
        return NULL;
    }
    size_t bad = len;
    for (size_t i = 0U; i < len;) {
        size_t l = eds_utf8_len((const unsigned char *)data + i, len - i);
        if (l == 0U) {
            bad = i;
            break;
        }
        i += l;
    }
    char *text;
    if (bad == len) {
        text = eds_strndup(f, data, len);
        *out_len = len;
    } else {
        /* Not UTF-8: vendor tools on Windows write Latin-1 (Windows-1252 is a superset: its 0x80-0x9F are rare). */
        eds_warn(f, line_of(data, bad), "not UTF-8 (byte 0x%02X); the file is read as Latin-1",
                 (unsigned)(unsigned char)data[bad]);
        text = eds_alloc(f, len * 2U + 1U);
        size_t o = 0U;
        for (size_t i = 0U; text != NULL && i < len; i++) {
            unsigned char c = (unsigned char)data[i];
            if (c < 0x80U) {
                text[o++] = (char)c;
            } else {
                text[o++] = (char)(0xC0U | (c >> 6));
                text[o++] = (char)(0x80U | (c & 0x3FU));
            }
        }
        *out_len = o;
    }
    if (text == NULL) {
        eds_error(f, 0U, "out of memory");
    }
    return text;
}

/* The line of a diagnostic ("PATH:LINE: ..."), or UINT32_MAX for one about the whole file (those go last). */
static unsigned long diagnostic_line(const eds_file_t *f, const char *d)
{
    const char *p = d + strlen(f->path);
    if (*p != ':' || p[1] < '0' || p[1] > '9') {
        return UINT32_MAX;
    }
    return strtoul(p + 1, NULL, 10);
}

/* In the order of their lines, as a reader of the file goes (insertion sort: stable, at most some 460 of them:
 * EDS_MAX_DIAGNOSTICS, a note per kind, one of those not shown). */
static void sort_diagnostics(eds_file_t *f)
{
    for (uint32_t i = 1U; i < f->n_diagnostics; i++) {
        char *d = f->diagnostics[i];
        const unsigned long line = diagnostic_line(f, d);
        uint32_t j = i;
        while (j > 0U && diagnostic_line(f, f->diagnostics[j - 1U]) > line) {
            f->diagnostics[j] = f->diagnostics[j - 1U];
            j--;
        }
        f->diagnostics[j] = d;
    }
}

static eds_file_t *read_buffer(const char *name, const char *data, size_t len)
{
    eds_file_t *f = new_file(name);
    if (f == NULL) {
        return NULL;
    }
    if (len > EDS_MAX_FILE_BYTES) {
        eds_error(f, 0U, "%lu bytes: larger than any device description (limit %lu bytes); not read",
                  (unsigned long)len, (unsigned long)EDS_MAX_FILE_BYTES);
        return f;
    }
    size_t text_len = 0U;
    char *text = decode(f, data, len, &text_len);
    ini_t ini;
    memset(&ini, 0, sizeof ini);
    if (text == NULL || !ini_parse(f, &ini, text, text_len)) {
        return f;
    }
    if (ini.n_sections == 0U) {
        eds_error(f, 0U, "no [section] at all: not an EDS or DCF file");
        return f;
    }
    eds_read_model(f, &ini);
    if (f->errors == 0U) {
        eds_relative_params(f);
        eds_check_pdos(f);
    }
    return f;
}

eds_file_t *eds_read_buffer(const char *name, const char *data, size_t len)
{
    eds_file_t *f = read_buffer(name, data, len);
    if (f != NULL) {
        eds_diagnostics_done(f);
        sort_diagnostics(f);
    }
    return f;
}

eds_file_t *eds_read_file(const char *path)
{
    FILE *in = fopen(path, "rb");
    if (in == NULL) {
        eds_file_t *f = new_file(path);
        if (f != NULL) {
            eds_error(f, 0U, "cannot open: %s", strerror(errno));
        }
        return f;
    }
    size_t cap = 65536U, len = 0U;
    char *buf = malloc(cap);
    bool too_big = false;
    while (buf != NULL) {
        if (len == cap) {
            if (cap > EDS_MAX_FILE_BYTES) {
                too_big = true;
                break;
            }
            char *b = realloc(buf, cap * 2U);
            if (b == NULL) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = b;
            cap *= 2U;
        }
        size_t n = fread(buf + len, 1U, cap - len, in);
        if (n == 0U) {
            break;
        }
        len += n;
    }
    bool read_error = ferror(in) != 0;
    fclose(in);
    eds_file_t *f;
    if (buf == NULL) {
        f = new_file(path);
        if (f != NULL) {
            eds_error(f, 0U, "out of memory");
        }
    } else if (too_big) {
        f = new_file(path);
        if (f != NULL) {
            eds_error(f, 0U, "larger than any device description (limit %lu bytes); not read",
                      (unsigned long)EDS_MAX_FILE_BYTES);
        }
    } else if (read_error) {
        f = new_file(path);
        if (f != NULL) {
            eds_error(f, 0U, "read error (a directory?)");
        }
    } else {
        f = eds_read_buffer(path, buf, len);
    }
    free(buf);
    return f;
}

void eds_free(eds_file_t *file)
{
    if (file == NULL) {
        return;
    }
    free(file->diagnostics);
    free(file->entries);
    free(file->objects);
    eds_arena_free(file->arena);
    free(file);
}

eds_entry_t *eds_find_mut(eds_file_t *f, uint16_t index, uint8_t sub)
{
    size_t lo = 0U, hi = f->n_entries;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2U;
        const eds_entry_t *e = &f->entries[mid];
        if (e->index == index && e->sub == sub) {
            return &f->entries[mid];
        }
        if (e->index < index || (e->index == index && e->sub < sub)) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

const eds_entry_t *eds_find(const eds_file_t *file, uint16_t index, uint8_t sub)
{
    return eds_find_mut((eds_file_t *)file, index, sub);
}

const eds_object_t *eds_find_object(const eds_file_t *file, uint16_t index)
{
    size_t lo = 0U, hi = file->n_objects;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2U;
        if (file->objects[mid].index == index) {
            return &file->objects[mid];
        }
        if (file->objects[mid].index < index) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return NULL;
}
