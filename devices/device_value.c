/* Objects' values read and written as the device itself would, typed: see device.h (device_get_value,
 * device_set_value). The command language's `get`/`set` (device_commands.c) and canopen-emu's JSON get/set both come
 * here, so that a value is checked the same way whichever way it comes. */
#include "device.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *device_type_name(uint8_t type)
{
    static const struct {
        uint8_t type;
        const char *name;
    } names[] = {
        {CO_T_BOOLEAN, "BOOLEAN"}, {CO_T_INTEGER8, "INTEGER8"}, {CO_T_INTEGER16, "INTEGER16"},
        {CO_T_INTEGER32, "INTEGER32"}, {CO_T_UNSIGNED8, "UNSIGNED8"}, {CO_T_UNSIGNED16, "UNSIGNED16"},
        {CO_T_UNSIGNED32, "UNSIGNED32"}, {CO_T_REAL32, "REAL32"}, {CO_T_VISIBLE_STRING, "VISIBLE_STRING"},
        {CO_T_OCTET_STRING, "OCTET_STRING"}, {CO_T_UNICODE_STRING, "UNICODE_STRING"}, {CO_T_TIME_OF_DAY, "TIME_OF_DAY"},
        {CO_T_TIME_DIFFERENCE, "TIME_DIFFERENCE"}, {CO_T_DOMAIN, "DOMAIN"}, {CO_T_INTEGER24, "INTEGER24"},
        {CO_T_REAL64, "REAL64"}, {CO_T_INTEGER40, "INTEGER40"}, {CO_T_INTEGER48, "INTEGER48"},
        {CO_T_INTEGER56, "INTEGER56"}, {CO_T_INTEGER64, "INTEGER64"}, {CO_T_UNSIGNED24, "UNSIGNED24"},
        {CO_T_UNSIGNED40, "UNSIGNED40"}, {CO_T_UNSIGNED48, "UNSIGNED48"}, {CO_T_UNSIGNED56, "UNSIGNED56"},
        {CO_T_UNSIGNED64, "UNSIGNED64"},
    };
    for (size_t i = 0U; i < sizeof names / sizeof names[0]; i++) {
        if (names[i].type == type) {
            return names[i].name;
        }
    }
    return "type";
}

bool device_type_is_signed(uint8_t type)
{
    return type == CO_T_INTEGER8 || type == CO_T_INTEGER16 || type == CO_T_INTEGER24 || type == CO_T_INTEGER32 ||
           type == CO_T_INTEGER40 || type == CO_T_INTEGER48 || type == CO_T_INTEGER56 || type == CO_T_INTEGER64;
}

/* The values an integer object of at most 8 bytes holds: for the signed types -2^(n-1)..2^(n-1)-1, for BOOLEAN 0..1,
 * for the unsigned ones (and short octet strings, written as a number) 0..2^n-1, n = 8 * size. As magnitudes, so
 * that UNSIGNED64 fits. */
typedef struct integer_range {
    bool is_signed;
    unsigned long long most_negative; /* magnitude of the lowest value (0 for unsigned types) */
    unsigned long long highest;
} integer_range_t;

static integer_range_t integer_range(const co_od_entry_t *e)
{
    const unsigned bits = 8U * e->size;
    const unsigned long long all_ones = bits >= 64U ? ULLONG_MAX : (1ULL << bits) - 1U;
    integer_range_t r = {false, 0U, e->type == CO_T_BOOLEAN ? 1U : all_ones};
    if (device_type_is_signed(e->type)) {
        r.is_signed = true;
        r.highest = all_ones >> 1;
        r.most_negative = r.highest + 1U;
    }
    return r;
}

static device_value_kind_t kind_of(uint8_t type)
{
    switch (type) {
    case CO_T_BOOLEAN:
        return DEVICE_VALUE_BOOLEAN;
    case CO_T_REAL32:
    case CO_T_REAL64:
        return DEVICE_VALUE_REAL;
    case CO_T_VISIBLE_STRING:
        return DEVICE_VALUE_TEXT;
    case CO_T_OCTET_STRING:
    case CO_T_UNICODE_STRING:
    case CO_T_DOMAIN:
        return DEVICE_VALUE_BYTES;
    default:
        return device_type_is_signed(type) ? DEVICE_VALUE_SIGNED : DEVICE_VALUE_UNSIGNED;
    }
}

/* The first 8 bytes, little-endian (CiA 301's byte order). */
static uint64_t little_endian(const uint8_t *b, size_t len)
{
    uint64_t u = 0U;
    for (size_t i = len < 8U ? len : 8U; i > 0U; i--) {
        u = (u << 8) | b[i - 1U];
    }
    return u;
}

uint32_t device_get_value(device_t *dev, uint16_t index, uint8_t sub, co_time_us_t now, uint8_t *buf, size_t size,
                          device_value_t *out)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(dev->cls->od, index, sub, &one);
    dev->now = now; /* a model's read hook brings the value up to now */
    size_t len = 0U;
    const uint32_t r = co_od_read(&dev->node, index, sub, buf, size, &len, CO_ORIGIN_LOCAL);
    if (r != 0U) {
        return r;
    }
    if (e == NULL) {
        return CO_ABORT_NO_OBJECT; /* read by the core but not in the dictionary: not a value of the device's */
    }
    memset(out, 0, sizeof *out);
    out->type = e->type;
    out->kind = kind_of(e->type);
    out->bytes = buf;
    out->len = len;
    const uint64_t u = little_endian(buf, len);
    switch (out->kind) {
    case DEVICE_VALUE_BOOLEAN:
        out->as.b = u != 0U;
        break;
    case DEVICE_VALUE_REAL:
        if (len == 4U) {
            float f;
            const uint32_t u32 = (uint32_t)u;
            memcpy(&f, &u32, sizeof f);
            out->as.r = (double)f;
        } else {
            memcpy(&out->as.r, &u, sizeof out->as.r);
        }
        break;
    case DEVICE_VALUE_TEXT: {
        const uint8_t *nul = memchr(buf, 0, len); /* a VISIBLE_STRING padded with NULs ends at the first */
        out->len = nul != NULL ? (size_t)(nul - buf) : len;
        break;
    }
    case DEVICE_VALUE_SIGNED: {
        const unsigned bits = (unsigned)(len < 8U ? len : 8U) * 8U;
        uint64_t v = u;
        if (bits > 0U && bits < 64U && (u >> (bits - 1U)) != 0U) {
            v |= ~((UINT64_C(1) << bits) - 1U); /* sign-extended */
        }
        out->as.i = (int64_t)v;
        break;
    }
    case DEVICE_VALUE_UNSIGNED:
        out->as.u = u;
        break;
    case DEVICE_VALUE_BYTES:
        break;
    }
    return 0U;
}

static bool refuse(char *why, size_t why_size, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static bool refuse(char *why, size_t why_size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    if (why_size > 0U) {
        (void)vsnprintf(why, why_size, fmt, ap);
    }
    va_end(ap);
    return false;
}

/* A value as the sign and magnitude of an integer, or false with why. The word of a TEXT value is shown as it came,
 * a REAL only when whole. */
static bool integer_of(const device_value_t *v, bool *negative, unsigned long long *magnitude, char *shown,
                       size_t shown_size, char *why, size_t why_size)
{
    *negative = false;
    switch (v->kind) {
    case DEVICE_VALUE_UNSIGNED:
        *magnitude = v->as.u;
        (void)snprintf(shown, shown_size, "%llu", (unsigned long long)v->as.u);
        return true;
    case DEVICE_VALUE_SIGNED:
        *negative = v->as.i < 0;
        *magnitude = *negative ? 0U - (unsigned long long)v->as.i : (unsigned long long)v->as.i;
        (void)snprintf(shown, shown_size, "%lld", (long long)v->as.i);
        return true;
    case DEVICE_VALUE_BOOLEAN:
        *magnitude = v->as.b ? 1U : 0U;
        (void)snprintf(shown, shown_size, "%s", v->as.b ? "true" : "false");
        return true;
    case DEVICE_VALUE_REAL: {
        /* Whole when its magnitude converts to an integer and back unchanged (NaN and infinities fail the range
         * test): no libm call, as devices/ links no math library. */
        (void)snprintf(shown, shown_size, "%.17g", v->as.r);
        const double size = v->as.r < 0.0 ? -v->as.r : v->as.r;
        if (!(size < 18446744073709551616.0) || (double)(unsigned long long)size != size) {
            return refuse(why, why_size, "%s is not a whole number", shown);
        }
        *negative = v->as.r < 0.0;
        *magnitude = (unsigned long long)size;
        return true;
    }
    case DEVICE_VALUE_TEXT: {
        (void)snprintf(shown, shown_size, "%.*s", (int)(v->len < 64U ? v->len : 64U), (const char *)v->bytes);
        if (v->len < shown_size && strlen(shown) == v->len && device_parse_magnitude(shown, negative, magnitude)) {
            return true;
        }
        /* "2.5" or "1e3": a number all the same, taken as a JSON number is (whole, or refused as not whole) */
        char *end = NULL;
        device_value_t as_real = *v;
        as_real.kind = DEVICE_VALUE_REAL;
        as_real.as.r = strtod(shown, &end);
        if (v->len < shown_size && strlen(shown) == v->len && end != shown && *end == '\0' && isfinite(as_real.as.r)) {
            return integer_of(&as_real, negative, magnitude, shown, shown_size, why, why_size);
        }
        return refuse(why, why_size, "'%s' is not a number", shown);
    }
    case DEVICE_VALUE_BYTES:
        break;
    }
    return refuse(why, why_size, "a byte string is not a number");
}

/* A value as a double, or false with why. */
static bool real_of(const device_value_t *v, double *d, char *why, size_t why_size)
{
    switch (v->kind) {
    case DEVICE_VALUE_REAL:
        *d = v->as.r;
        return true;
    case DEVICE_VALUE_SIGNED:
        *d = (double)v->as.i;
        return true;
    case DEVICE_VALUE_UNSIGNED:
        *d = (double)v->as.u;
        return true;
    case DEVICE_VALUE_TEXT: {
        char text[64];
        char *end = NULL;
        (void)snprintf(text, sizeof text, "%.*s", (int)(v->len < 63U ? v->len : 63U), (const char *)v->bytes);
        errno = 0;
        *d = strtod(text, &end);
        if (v->len >= sizeof text || strlen(text) != v->len || end == text || *end != '\0') {
            return refuse(why, why_size, "'%s' is not a number", text);
        }
        if (errno == ERANGE && isinf(*d)) {
            return refuse(why, why_size, "%s is out of range of a REAL64", text);
        }
        return true;
    }
    case DEVICE_VALUE_BOOLEAN:
    case DEVICE_VALUE_BYTES:
        break;
    }
    return refuse(why, why_size, "a %s is not a number", v->kind == DEVICE_VALUE_BOOLEAN ? "true/false" : "byte string");
}

/* The bytes of the value in the object's type, into wire (*len of them), or false with why. */
static bool encode(const co_od_entry_t *e, const device_value_t *v, uint8_t *wire, size_t wire_size, size_t *len,
                   char *why, size_t why_size)
{
    const uint16_t index = e->index;
    const uint8_t sub = e->sub;
    if (e->type == CO_T_VISIBLE_STRING) {
        if (v->kind != DEVICE_VALUE_TEXT) {
            return refuse(why, why_size, "0x%04X:%02X is a VISIBLE_STRING: give it text", index, sub);
        }
        if (v->len > e->size) {
            return refuse(why, why_size, "0x%04X:%02X holds at most %u characters", index, sub, e->size);
        }
        if (v->len > wire_size) {
            return refuse(why, why_size, "0x%04X:%02X: at most %zu characters are written this way", index, sub,
                          wire_size);
        }
        memcpy(wire, v->bytes, v->len);
        *len = v->len;
        return true;
    }
    if (e->type == CO_T_REAL32 || e->type == CO_T_REAL64) {
        double d = 0.0;
        if (!real_of(v, &d, why, why_size)) {
            return false;
        }
        uint64_t bits;
        if (e->type == CO_T_REAL32) {
            if (isfinite(d) && (d > (double)FLT_MAX || d < -(double)FLT_MAX)) { /* "inf" is taken as it is */
                return refuse(why, why_size, "%g is out of range: 0x%04X:%02X (REAL32) holds -3.4e38..3.4e38", d, index,
                              sub);
            }
            const float f = (float)d;
            uint32_t u32;
            memcpy(&u32, &f, sizeof u32);
            bits = u32;
            *len = 4U;
        } else {
            memcpy(&bits, &d, sizeof bits);
            *len = 8U;
        }
        for (size_t i = 0U; i < *len; i++) {
            wire[i] = (uint8_t)(bits >> (8U * i));
        }
        return true;
    }
    if (e->size > 8U || e->type == CO_T_DOMAIN || e->type == CO_T_UNICODE_STRING) {
        return refuse(why, why_size, "0x%04X:%02X (%s) cannot be set this way: write it over SDO", index, sub,
                      device_type_name(e->type));
    }
    /* Checked against the object's type before it is cut to e->size bytes: 70000 stored 4464 in an UNSIGNED16, -1
     * stored 65535, and 65636 stored 100, which then passed the Eltex rule that refuses 50. */
    bool negative;
    unsigned long long magnitude;
    char shown[72];
    if (!integer_of(v, &negative, &magnitude, shown, sizeof shown, why, why_size)) {
        return false;
    }
    const integer_range_t range = integer_range(e);
    if (negative ? magnitude > range.most_negative : magnitude > range.highest) {
        if (range.is_signed) {
            return refuse(why, why_size, "%s is out of range: 0x%04X:%02X (%s) holds -%llu..%llu", shown, index, sub,
                          device_type_name(e->type), range.most_negative, range.highest);
        }
        return refuse(why, why_size, "%s is out of range: 0x%04X:%02X (%s) holds 0..%llu", shown, index, sub,
                      device_type_name(e->type), range.highest);
    }
    const unsigned long long twos_complement = negative ? 0U - magnitude : magnitude;
    for (size_t i = 0U; i < e->size; i++) {
        wire[i] = (uint8_t)(twos_complement >> (8U * i));
    }
    *len = e->size;
    return true;
}

bool device_set_value(device_t *dev, uint16_t index, uint8_t sub, const device_value_t *value, co_time_us_t now,
                      char *why, size_t why_size)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(dev->cls->od, index, sub, &one);
    if (e == NULL) {
        return refuse(why, why_size, "no object 0x%04X:%02X", index, sub);
    }
    uint8_t wire[512]; /* a JSON set's string is under 512 bytes */
    size_t len = 0U;
    if (!encode(e, value, wire, sizeof wire, &len, why, why_size)) {
        return false;
    }
    dev->now = now;
    dev->touched = true;
    const uint32_t r = co_od_write(&dev->node, index, sub, wire, len, CO_ORIGIN_LOCAL);
    if (r != 0U) {
        return refuse(why, why_size, "0x%04X:%02X: %s (0x%08lX)", index, sub, co_abort_text(r), (unsigned long)r);
    }
    return true;
}
