/**
 * @file eds_value.c
 * @brief Data types and values of the EDS reader: CiA 306 number forms, $NODEID sums, ranges, text out.
 *
 * CiA 306 numbers: "0x" hexadecimal, a leading "0" octal (so "010" is 8, as CANopenEditor, objdictgen and Lely
 * read it; a warning says so where the decimal reading differs), otherwise decimal; a hexadecimal value of a signed
 * type is its bit pattern ("0xFD" in an INTEGER8: -3). A value may be a sum of such terms with one "$NODEID" among them
 * ("0x80000000+$NODEID+0x180").
 */
#include "eds_internal.h"

#include <ctype.h>
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct type_info {
    uint8_t number;
    const char *name;
    uint8_t size;   /* bytes; 0: strings and DOMAIN */
    eds_value_kind_t kind;
    uint8_t bits;   /* integer width (BOOLEAN: 1) */
} type_info_t;

static const type_info_t TYPES[] = {
    {0x01, "BOOLEAN", 1, EDS_V_UINT, 1},          {0x02, "INTEGER8", 1, EDS_V_INT, 8},
    {0x03, "INTEGER16", 2, EDS_V_INT, 16},        {0x04, "INTEGER32", 4, EDS_V_INT, 32},
    {0x05, "UNSIGNED8", 1, EDS_V_UINT, 8},        {0x06, "UNSIGNED16", 2, EDS_V_UINT, 16},
    {0x07, "UNSIGNED32", 4, EDS_V_UINT, 32},      {0x08, "REAL32", 4, EDS_V_REAL, 32},
    {0x09, "VISIBLE_STRING", 0, EDS_V_BYTES, 0},  {0x0A, "OCTET_STRING", 0, EDS_V_BYTES, 0},
    {0x0B, "UNICODE_STRING", 0, EDS_V_BYTES, 0},  {0x0C, "TIME_OF_DAY", 6, EDS_V_UINT, 48},
    {0x0D, "TIME_DIFFERENCE", 6, EDS_V_UINT, 48}, {0x0F, "DOMAIN", 0, EDS_V_BYTES, 0},
    {0x10, "INTEGER24", 3, EDS_V_INT, 24},        {0x11, "REAL64", 8, EDS_V_REAL, 64},
    {0x12, "INTEGER40", 5, EDS_V_INT, 40},        {0x13, "INTEGER48", 6, EDS_V_INT, 48},
    {0x14, "INTEGER56", 7, EDS_V_INT, 56},        {0x15, "INTEGER64", 8, EDS_V_INT, 64},
    {0x16, "UNSIGNED24", 3, EDS_V_UINT, 24},      {0x18, "UNSIGNED40", 5, EDS_V_UINT, 40},
    {0x19, "UNSIGNED48", 6, EDS_V_UINT, 48},      {0x1A, "UNSIGNED56", 7, EDS_V_UINT, 56},
    {0x1B, "UNSIGNED64", 8, EDS_V_UINT, 64},
};

static const type_info_t *type_info(uint8_t type)
{
    for (size_t i = 0; i < sizeof TYPES / sizeof TYPES[0]; i++) {
        if (TYPES[i].number == type) {
            return &TYPES[i];
        }
    }
    return NULL;
}

const char *eds_type_name(uint8_t type)
{
    const type_info_t *t = type_info(type);
    return t != NULL ? t->name : NULL;
}

size_t eds_type_size(uint8_t type)
{
    const type_info_t *t = type_info(type);
    return t != NULL ? t->size : 0U;
}

bool eds_type_is_bytes(uint8_t type)
{
    const type_info_t *t = type_info(type);
    return t != NULL && t->kind == EDS_V_BYTES;
}

const uint16_t eds_cia305_kbit[EDS_CIA305_RATES] = {1000, 800, 500, 250, 125, 0, 50, 20, 10};

bool eds_access_writable(eds_access_t access)
{
    return access == EDS_WO || access == EDS_RW || access == EDS_RWR || access == EDS_RWW;
}

bool eds_access_maps(eds_access_t access, bool receive)
{
    return receive ? (access == EDS_WO || access == EDS_RW || access == EDS_RWW)
                   : (access == EDS_RO || access == EDS_CONST || access == EDS_RW || access == EDS_RWR);
}

double eds_real_from_bits(uint64_t bits, size_t size)
{
    if (size == 4U) {
        const uint32_t b32 = (uint32_t)bits;
        float f;
        memcpy(&f, &b32, sizeof f);
        return (double)f;
    }
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

const char *eds_access_name(eds_access_t access)
{
    static const char *const names[] = {"ro", "wo", "rw", "rwr", "rww", "const"};
    return (unsigned)access < 6U ? names[access] : "ro";
}

/* One term: [+-] then 0x<hex>, 0<octal>, or <decimal>. *octal_like: a leading 0 with digits 8/9 (read as decimal).
 * *octal: read as octal, to a value other than its decimal reading ("010"; not "00" or "07"). */
static bool parse_term(const char *s, size_t n, bool *negative, uint64_t *magnitude, bool *octal_like, bool *octal)
{
    *negative = false;
    size_t i = 0U;
    if (i < n && (s[i] == '+' || s[i] == '-')) {
        *negative = s[i] == '-';
        i++;
    }
    if (i >= n) {
        return false;
    }
    unsigned base = 10U;
    if (n - i > 2U && s[i] == '0' && (s[i + 1U] == 'x' || s[i + 1U] == 'X')) {
        base = 16U;
        i += 2U;
    } else if (n - i > 1U && s[i] == '0') {
        base = 8U;
        for (size_t j = i; j < n; j++) {
            if (s[j] == '8' || s[j] == '9') {
                base = 10U; /* "08" cannot be octal: the caller warns */
                *octal_like = true;
            }
        }
    }
    uint64_t v = 0U;
    for (; i < n; i++) {
        int c = (unsigned char)s[i];
        unsigned d;
        if (isdigit(c)) {
            d = (unsigned)(c - '0');
        } else if (base == 16U && isxdigit(c)) {
            d = (unsigned)(tolower(c) - 'a' + 10);
        } else {
            return false;
        }
        if (d >= base || v > (UINT64_MAX - d) / base) {
            return false;
        }
        v = v * base + d;
    }
    if (base == 8U && v >= 8U) {
        *octal = true;
    }
    *magnitude = v;
    return true;
}

bool eds_parse_integer(const char *text, bool *negative, uint64_t *magnitude, bool *nodeid, bool *octal_like,
                       bool *octal)
{
    /* A sum of terms: signed 128-bit arithmetic emulated with a sign and a magnitude of at most 2^64-1. */
    bool neg = false;
    uint64_t mag = 0U;
    *nodeid = false;
    *octal_like = false;
    *octal = false;
    const char *p = text;
    bool first = true;
    for (;;) {
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        const char *start = p;
        while (*p != '\0' && *p != '+' && *p != ' ' && *p != '\t') {
            if (p != start && *p == '-') {
                return false;
            }
            p++;
        }
        /* a leading sign belongs to the first term */
        if (p == start && first && *p == '+') {
            p++;
            continue;
        }
        size_t n = (size_t)(p - start);
        if (n == 0U) {
            return false;
        }
        if (n == 7U && (strncmp(start, "$NODEID", 7) == 0 || strncmp(start, "$nodeid", 7) == 0 ||
                        strncmp(start, "$NodeId", 7) == 0 || strncmp(start, "$NodeID", 7) == 0)) {
            if (*nodeid) {
                return false;
            }
            *nodeid = true;
        } else {
            bool tneg;
            uint64_t tmag;
            if (!parse_term(start, n, &tneg, &tmag, octal_like, octal)) {
                return false;
            }
            if (tneg == neg) {
                if (mag > UINT64_MAX - tmag) {
                    return false;
                }
                mag += tmag;
            } else if (tmag > mag) {
                mag = tmag - mag;
                neg = tneg;
            } else {
                mag -= tmag;
            }
        }
        first = false;
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        if (*p == '\0') {
            break;
        }
        if (*p != '+') {
            return false;
        }
        p++;
    }
    *negative = neg && mag != 0U;
    *magnitude = mag;
    return true;
}

bool eds_parse_unsigned(const char *text, uint64_t max, uint64_t *out)
{
    bool neg, nodeid, octal_like, octal;
    uint64_t mag;
    if (!eds_parse_integer(text, &neg, &mag, &nodeid, &octal_like, &octal) || neg || nodeid || mag > max) {
        return false;
    }
    *out = mag;
    return true;
}

void eds_type_bound(uint8_t type, bool high, eds_value_t *out)
{
    const type_info_t *t = type_info(type);
    memset(out, 0, sizeof *out);
    if (t == NULL) {
        return;
    }
    out->kind = t->kind;
    switch (t->kind) {
    case EDS_V_INT:
        out->i = high ? (int64_t)(UINT64_MAX >> (65U - t->bits)) : -(int64_t)(UINT64_MAX >> (65U - t->bits)) - 1;
        break;
    case EDS_V_UINT:
        out->u = high ? UINT64_MAX >> (64U - t->bits) : 0U;
        break;
    case EDS_V_REAL:
        out->r = t->size == 4U ? (high ? (double)FLT_MAX : -(double)FLT_MAX) : (high ? DBL_MAX : -DBL_MAX);
        break;
    default:
        break;
    }
}

int eds_value_cmp(const eds_value_t *a, const eds_value_t *b)
{
    switch (a->kind) {
    case EDS_V_INT:
        return a->i < b->i ? -1 : (a->i > b->i ? 1 : 0);
    case EDS_V_UINT:
        return a->u < b->u ? -1 : (a->u > b->u ? 1 : 0);
    case EDS_V_REAL:
        return a->r < b->r ? -1 : (a->r > b->r ? 1 : 0);
    default:
        return 0;
    }
}

bool eds_value_fits(uint8_t type, const eds_value_t *v)
{
    eds_value_t lo, hi;
    eds_type_bound(type, false, &lo);
    eds_type_bound(type, true, &hi);
    if (v->kind != lo.kind) {
        return false;
    }
    if (v->kind == EDS_V_INT || v->kind == EDS_V_UINT) {
        if (v->nodeid) { /* every node-ID 1..127 must give a representable value */
            if (v->kind == EDS_V_INT) {
                return v->i <= hi.i - 127 && (v->i >= 0 || v->i + 1 >= lo.i);
            }
            return hi.u >= 127U && v->u <= hi.u - 127U;
        }
        return eds_value_cmp(v, &lo) >= 0 && eds_value_cmp(v, &hi) <= 0;
    }
    return v->kind != EDS_V_REAL || (isfinite(v->r) && v->r >= lo.r && v->r <= hi.r);
}

static bool hex_bytes(eds_file_t *f, const char *text, eds_value_t *out)
{
    size_t digits = 0U;
    for (const char *p = text; *p != '\0'; p++) {
        if (isxdigit((unsigned char)*p)) {
            digits++;
        } else if (*p != ' ' && *p != '\t') {
            return false;
        }
    }
    if (digits % 2U != 0U) {
        return false;
    }
    out->bytes = eds_alloc(f, digits / 2U + 1U);
    if (out->bytes == NULL) {
        return false;
    }
    size_t n = 0U;
    int hi = -1;
    for (const char *p = text; *p != '\0'; p++) {
        if (!isxdigit((unsigned char)*p)) {
            continue;
        }
        int d = isdigit((unsigned char)*p) ? *p - '0' : tolower((unsigned char)*p) - 'a' + 10;
        if (hi < 0) {
            hi = d;
        } else {
            out->bytes[n++] = (uint8_t)(hi * 16 + d);
            hi = -1;
        }
    }
    out->len = n;
    return true;
}

/* UTF-8 text to UTF-16LE (UNICODE_STRING). The reader has validated the UTF-8 already. */
static bool utf16(eds_file_t *f, const char *text, eds_value_t *out)
{
    size_t n = strlen(text);
    out->bytes = eds_alloc(f, n * 4U + 1U);
    if (out->bytes == NULL) {
        return false;
    }
    size_t o = 0U;
    for (size_t i = 0U; i < n;) {
        unsigned char c = (unsigned char)text[i];
        uint32_t cp;
        size_t len = c < 0x80U ? 1U : (c < 0xE0U ? 2U : (c < 0xF0U ? 3U : 4U));
        cp = len == 1U ? c : (len == 2U ? c & 0x1FU : (len == 3U ? c & 0x0FU : c & 0x07U));
        for (size_t k = 1U; k < len && i + k < n; k++) {
            cp = (cp << 6) | ((unsigned char)text[i + k] & 0x3FU);
        }
        i += len;
        if (cp >= 0x10000U) {
            cp -= 0x10000U;
            uint32_t h = 0xD800U + (cp >> 10), l = 0xDC00U + (cp & 0x3FFU);
            out->bytes[o++] = (uint8_t)h, out->bytes[o++] = (uint8_t)(h >> 8);
            out->bytes[o++] = (uint8_t)l, out->bytes[o++] = (uint8_t)(l >> 8);
        } else {
            out->bytes[o++] = (uint8_t)cp, out->bytes[o++] = (uint8_t)(cp >> 8);
        }
    }
    out->len = o;
    return true;
}

/* "0x" and hexadecimal digits only: one term, no sign, no $NODEID. */
static bool is_one_hex_term(const char *s)
{
    if (s[0] != '0' || (s[1] != 'x' && s[1] != 'X') || s[2] == '\0') {
        return false;
    }
    for (s += 2; *s != '\0'; s++) {
        if (!isxdigit((unsigned char)*s)) {
            return false;
        }
    }
    return true;
}

static bool is_decimal_real(const char *s)
{
    const char *p = s;
    if (*p == '+' || *p == '-') {
        p++;
    }
    bool digits = false;
    while (isdigit((unsigned char)*p)) {
        p++, digits = true;
    }
    if (*p == '.') {
        p++;
        while (isdigit((unsigned char)*p)) {
            p++, digits = true;
        }
    }
    if (!digits) {
        return false;
    }
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-') {
            p++;
        }
        if (!isdigit((unsigned char)*p)) {
            return false;
        }
        while (isdigit((unsigned char)*p)) {
            p++;
        }
    }
    return *p == '\0';
}

eds_parse_t eds_parse_value(eds_file_t *f, uint8_t type, const char *text, eds_value_t *out, char *why, size_t why_cap)
{
    const type_info_t *t = type_info(type);
    memset(out, 0, sizeof *out);
    why[0] = '\0';
    if (t == NULL) {
        snprintf(why, why_cap, "unknown data type");
        return EDS_PARSE_BAD;
    }
    out->kind = t->kind;
    if (t->kind == EDS_V_BYTES) {
        bool ok;
        if (type == 0x09) { /* VISIBLE_STRING: the text itself */
            size_t n = strlen(text);
            out->bytes = (uint8_t *)eds_strndup(f, text, n);
            out->len = n;
            ok = out->bytes != NULL;
        } else if (type == 0x0B) {
            ok = utf16(f, text, out);
        } else {
            ok = hex_bytes(f, text, out);
            if (!ok) {
                snprintf(why, why_cap, "is not pairs of hexadecimal digits");
            }
        }
        if (!ok) {
            out->bytes = (uint8_t *)eds_strndup(f, "", 0U);
            out->len = 0U;
            return EDS_PARSE_BAD;
        }
        return EDS_PARSE_OK;
    }
    while (*text == ' ' || *text == '\t') {
        text++;
    }
    if (*text == '\0') {
        return EDS_PARSE_OK; /* empty: 0 */
    }
    if (t->kind == EDS_V_REAL) {
        if (strchr(text, '$') != NULL) {
            snprintf(why, why_cap, "$NODEID in a %s value", t->name);
            return EDS_PARSE_BAD;
        }
        if ((text[0] == '0' && (text[1] == 'x' || text[1] == 'X'))) {
            /* Some tools write a REAL's IEEE bits in hex: read them as such. */
            uint64_t bits;
            if (!eds_parse_unsigned(text, t->size == 4U ? UINT32_MAX : UINT64_MAX, &bits)) {
                snprintf(why, why_cap, "is not a number");
                return EDS_PARSE_BAD;
            }
            out->r = eds_real_from_bits(bits, t->size);
            if (!isfinite(out->r)) {
                out->r = 0.0;
                snprintf(why, why_cap, "is the bit pattern of a non-finite number");
                return EDS_PARSE_BAD;
            }
            snprintf(why, why_cap, "hexadecimal %s read as its IEEE 754 bits (%.9g)", t->name, out->r);
            return EDS_PARSE_OK;
        }
        if (!is_decimal_real(text)) {
            snprintf(why, why_cap, "is not a number");
            return EDS_PARSE_BAD;
        }
        out->r = strtod(text, NULL);
        if (t->size == 4U) {
            /* below FLT_MAX + half its ULP a value rounds to a finite float (the writer's "3.4028235e+38") */
            if (!(fabs(out->r) < (double)FLT_MAX + 0x1p103)) {
                out->r = out->r < 0 ? -(double)FLT_MAX : (double)FLT_MAX;
                snprintf(why, why_cap, "does not fit %s", t->name);
                return EDS_PARSE_RANGE;
            }
            out->r = (double)(float)out->r; /* a REAL32 holds a float: limits compare as the device will */
        } else if (!isfinite(out->r)) {
            out->r = out->r < 0 ? -DBL_MAX : DBL_MAX;
            snprintf(why, why_cap, "does not fit %s", t->name);
            return EDS_PARSE_RANGE;
        }
        return EDS_PARSE_OK;
    }
    bool neg, nodeid, octal_like, octal;
    uint64_t mag;
    if (!eds_parse_integer(text, &neg, &mag, &nodeid, &octal_like, &octal)) {
        snprintf(why, why_cap, "is not an integer (CiA 306: 0x hexadecimal, 0 octal, decimal, $NODEID+...)");
        return EDS_PARSE_BAD;
    }
    out->nodeid = nodeid;
    eds_value_t lo, hi;
    eds_type_bound(type, false, &lo);
    eds_type_bound(type, true, &hi);
    bool range = false;
    if (t->kind == EDS_V_INT && !neg && !nodeid && mag > (uint64_t)hi.i && mag <= UINT64_MAX >> (64U - t->bits) &&
        is_one_hex_term(text)) {
        /* "0xFD" in an INTEGER8 is its bit pattern, -3, as tools that write signed values in hex mean it (and as
         * python-canopen reads limits): 0xFD - 0x100, computed without overflow for INTEGER64 too. */
        out->i = -(int64_t)((UINT64_MAX >> (64U - t->bits)) - mag) - 1;
    } else if (t->kind == EDS_V_INT) {
        if (!neg && mag > (uint64_t)hi.i) {
            out->i = hi.i, range = true;
        } else if (neg && mag > (uint64_t)(-(lo.i + 1)) + 1U) {
            out->i = lo.i, range = true;
        } else {
            out->i = neg ? -(int64_t)(mag - 1U) - 1 : (int64_t)mag;
        }
    } else {
        if (neg) {
            out->u = 0U, range = true;
        } else if (mag > hi.u) {
            out->u = hi.u, range = true;
        } else {
            out->u = mag;
        }
    }
    if (!range && nodeid && !eds_value_fits(type, out)) {
        out->nodeid = false;
        snprintf(why, why_cap, "does not fit %s for every node-ID 1..127", t->name);
        return EDS_PARSE_RANGE;
    }
    if (range) {
        out->nodeid = false;
        snprintf(why, why_cap, "does not fit %s", t->name);
        return EDS_PARSE_RANGE;
    }
    if (octal_like) {
        snprintf(why, why_cap, "has a leading 0 but is not octal: read as decimal");
    } else if (octal) {
        /* CiA 306 says so, but "01000" is more often meant as 1000 than as 512: say which was read */
        if (t->kind == EDS_V_INT) {
            snprintf(why, why_cap, "has a leading 0: read as octal (CiA 306), %s%" PRId64, nodeid ? "$NODEID+" : "",
                     out->i);
        } else {
            snprintf(why, why_cap, "has a leading 0: read as octal (CiA 306), %s%" PRIu64, nodeid ? "$NODEID+" : "",
                     out->u);
        }
    }
    return EDS_PARSE_OK;
}

void eds_format_value(char *buf, size_t cap, uint8_t type, const eds_value_t *v)
{
    const type_info_t *t = type_info(type);
    if (cap == 0U) {
        return;
    }
    buf[0] = '\0';
    if (t == NULL || v->kind == EDS_V_NONE) {
        return;
    }
    switch (v->kind) {
    case EDS_V_INT:
        if (v->nodeid) {
            snprintf(buf, cap, v->i != 0 ? "$NODEID+%" PRId64 : "$NODEID", v->i);
        } else {
            snprintf(buf, cap, "%" PRId64, v->i);
        }
        break;
    case EDS_V_UINT:
        if (v->nodeid) {
            snprintf(buf, cap, v->u != 0U ? "$NODEID+0x%" PRIX64 : "$NODEID", v->u);
        } else {
            snprintf(buf, cap, "0x%" PRIX64, v->u);
        }
        break;
    case EDS_V_REAL:
        /* the shortest text that reads back as the same value (of the type's precision) */
        for (int prec = 1; prec <= 17; prec++) {
            snprintf(buf, cap, "%.*g", prec, v->r);
            double back = strtod(buf, NULL);
            if (t->size == 4U ? (float)back == (float)v->r : back == v->r) {
                break;
            }
        }
        break;
    case EDS_V_BYTES:
        if (type == 0x09) {
            snprintf(buf, cap, "%.*s", (int)(v->len < cap ? v->len : cap - 1U), (const char *)v->bytes);
        } else if (type == 0x0B) { /* UTF-16LE back to UTF-8 */
            size_t o = 0U;
            for (size_t i = 0U; i + 1U < v->len && o + 5U < cap; i += 2U) {
                uint32_t cp = (uint32_t)v->bytes[i] | ((uint32_t)v->bytes[i + 1U] << 8);
                if (cp >= 0xD800U && cp < 0xDC00U && i + 3U < v->len) {
                    uint32_t lo = (uint32_t)v->bytes[i + 2U] | ((uint32_t)v->bytes[i + 3U] << 8);
                    cp = 0x10000U + ((cp - 0xD800U) << 10) + (lo - 0xDC00U);
                    i += 2U;
                }
                if (cp < 0x80U) {
                    buf[o++] = (char)cp;
                } else if (cp < 0x800U) {
                    buf[o++] = (char)(0xC0U | (cp >> 6)), buf[o++] = (char)(0x80U | (cp & 0x3FU));
                } else if (cp < 0x10000U) {
                    buf[o++] = (char)(0xE0U | (cp >> 12)), buf[o++] = (char)(0x80U | ((cp >> 6) & 0x3FU));
                    buf[o++] = (char)(0x80U | (cp & 0x3FU));
                } else {
                    buf[o++] = (char)(0xF0U | (cp >> 18)), buf[o++] = (char)(0x80U | ((cp >> 12) & 0x3FU));
                    buf[o++] = (char)(0x80U | ((cp >> 6) & 0x3FU)), buf[o++] = (char)(0x80U | (cp & 0x3FU));
                }
            }
            buf[o] = '\0';
        } else {
            size_t o = 0U;
            for (size_t i = 0U; i < v->len && o + 3U < cap; i++) {
                o += (size_t)snprintf(buf + o, cap - o, "%02X", v->bytes[i]);
            }
        }
        break;
    default:
        break;
    }
}
