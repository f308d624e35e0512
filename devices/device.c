/*
 * The device framework: instance set-up, hook trampolines into the device class, and the control
 * commands every device understands (show, get, set, power-cycle). Device-specific commands come first.
 */
#include "device.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static device_t *dev_of(void *ctx) { return (device_t *)ctx; }

static uint32_t tramp_write(void *ctx, co_node_t *node, const co_od_entry_t *e, const uint8_t *data, size_t len,
                            co_od_origin_t origin)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    if (e->index >= 0x2000U) {
        dev->touched = true; /* a communication object is the core's: no step for it (an SDO client's 0x1017) */
    }
    return dev->cls->on_write != NULL ? dev->cls->on_write(dev, e, data, len, origin) : 0U;
}

static uint32_t tramp_read(void *ctx, co_node_t *node, const co_od_entry_t *e)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    return dev->cls->on_read != NULL ? dev->cls->on_read(dev, e) : 0U;
}

static void tramp_nmt(void *ctx, co_node_t *node, co_nmt_state_t from, co_nmt_state_t to)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    dev->touched = true;
    if (dev->cls->on_nmt_change != NULL) {
        dev->cls->on_nmt_change(dev, from, to);
    }
}

static void tramp_reset(void *ctx, co_node_t *node, co_reset_t what)
{
    device_t *dev = dev_of(ctx);
    dev->touched = true;
    if (what == CO_RESET_COMMUNICATION && dev->cfg.serial != 0U) {
        (void)co_od_set_u32(node, 0x1018, 4, dev->cfg.serial); /* the 0x1000 area was just re-initialised */
    }
    if (dev->cls->on_reset != NULL) {
        dev->cls->on_reset(dev, what);
    }
}

static co_status_t tramp_store(void *ctx, co_node_t *node, uint16_t index, uint8_t sub)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    dev->touched = true;
    return dev->cls->on_store != NULL ? dev->cls->on_store(dev, index, sub) : CO_OK;
}

static void tramp_event(void *ctx, co_node_t *node, const co_event_t *ev)
{
    device_t *dev = dev_of(ctx);
    (void)node;
    if (ev->kind != CO_EV_RX_FILTER && ev->kind != CO_EV_TX_DROPPED) {
        dev->touched = true; /* an LSS change, a timeout, an EMCY...: the model may follow it */
    }
    if (dev->cls->on_event != NULL) {
        dev->cls->on_event(dev, ev);
    }
    if (dev->cfg.on_event != NULL) {
        dev->cfg.on_event(dev->cfg.event_ctx, dev, ev);
    }
}

static co_status_t boot(device_t *dev, co_time_us_t now)
{
    dev->now = now;
    dev->touched = true;
    co_od_copy_defaults(dev->cls->od, 0U, dev->cls->od->values_size, dev->values);
    /* The model block is not cleared here: power_on re-initialises the running state and keeps the
     * environment (device.h). */
    if (dev->cls->power_on != NULL) {
        dev->cls->power_on(dev, now);
    }
    co_node_cfg_t nc;
    memset(&nc, 0, sizeof nc);
    nc.od = dev->cls->od;
    nc.values = dev->values;
    nc.port = dev->cfg.port;
    nc.port_ctx = dev->cfg.port_ctx;
    nc.hooks = &dev->hooks;
    nc.hooks_ctx = dev;
    nc.node_id = dev->cfg.node_id;
    nc.bit_timing = dev->cls->default_bit_timing;
    nc.bit_rates_kbit = dev->cls->bit_rates_kbit;
    nc.options = dev->cls->core_options;
    uint8_t *core_state = (uint8_t *)dev->model;
    const device_class_t *cls = dev->cls;
    if (cls->rpdo_count > 0U || cls->tpdo_count > 0U || cls->sdo_server_count > 0U) {
        nc.rpdo = (co_rpdo_t *)core_state;
        nc.rpdo_count = cls->rpdo_count;
        core_state += (size_t)cls->rpdo_count * sizeof(co_rpdo_t);
        nc.tpdo = (co_tpdo_t *)core_state;
        nc.tpdo_count = cls->tpdo_count;
        core_state += (size_t)cls->tpdo_count * sizeof(co_tpdo_t);
        nc.sdo_servers = (co_sdo_server_t *)core_state;
        nc.sdo_server_count = cls->sdo_server_count;
        core_state += (size_t)cls->sdo_server_count * sizeof(co_sdo_server_t);
        nc.routes = (co_rx_route_t *)core_state;
        nc.route_count = (uint16_t)(CO_RX_ROUTES_FIXED + cls->rpdo_count + cls->sdo_server_count);
    }
    return co_node_init(&dev->node, &nc, now);
}

size_t device_core_state_size(const device_class_t *cls)
{
    if (cls->rpdo_count == 0U && cls->tpdo_count == 0U && cls->sdo_server_count == 0U) {
        return 0U; /* the node's own arrays */
    }
    const size_t size = (size_t)cls->rpdo_count * sizeof(co_rpdo_t) + (size_t)cls->tpdo_count * sizeof(co_tpdo_t) +
                        (size_t)cls->sdo_server_count * sizeof(co_sdo_server_t) +
                        (CO_RX_ROUTES_FIXED + (size_t)cls->rpdo_count + cls->sdo_server_count) * sizeof(co_rx_route_t);
    return (size + 15U) & ~(size_t)15U; /* the model's state that follows keeps any alignment it needs */
}

co_status_t device_init(device_t *dev, const device_class_t *cls, void *values, void *model, const device_cfg_t *cfg,
                        co_time_us_t now)
{
    if (dev == NULL || cls == NULL || values == NULL || cfg == NULL || (cls->model_size > 0U && model == NULL)) {
        return CO_ERR_ARG;
    }
    memset(dev, 0, sizeof *dev);
    dev->cls = cls;
    dev->values = values;
    dev->model = model;
    dev->cfg = *cfg;
    if (dev->cfg.node_id == 0U) {
        dev->cfg.node_id = cls->default_node_id;
    }
    if (cfg->variant != NULL) {
        bool found = false;
        for (uint8_t i = 0U; cls->variants != NULL && cls->variants[i] != NULL; i++) {
            if (strcmp(cls->variants[i], cfg->variant) == 0) {
                dev->variant = i;
                found = true;
            }
        }
        if (!found) {
            return CO_ERR_ARG;
        }
    }
    dev->hooks.on_write = tramp_write;
    dev->hooks.on_read = tramp_read;
    dev->hooks.first_index = cls->hooks_first_index;
    dev->hooks.on_nmt_change = tramp_nmt;
    dev->hooks.on_reset = tramp_reset;
    dev->hooks.on_event = tramp_event;
    dev->hooks.on_store = tramp_store;
    if (cls->model_size > 0U) {
        memset(model, 0, cls->model_size); /* only here: a power cycle keeps the environment */
    }
    if (cls->init != NULL) {
        cls->init(dev);
    }
    return boot(dev, now);
}

co_status_t device_power_cycle(device_t *dev, co_time_us_t now) { return boot(dev, now); }

void device_clear_running_state(device_t *dev, size_t env_offset, size_t env_size)
{
    uint8_t *m = (uint8_t *)dev->model;
    const size_t size = dev->cls->model_size;
    if (m == NULL || env_offset > size || env_size > size - env_offset) {
        return;
    }
    memset(m, 0, env_offset);
    memset(m + env_offset + env_size, 0, size - env_offset - env_size);
}

void device_printf(const device_t *dev, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (dev->cfg.print != NULL) {
        dev->cfg.print(dev->cfg.print_ctx, dev, line);
    }
}

/* [+|-] then decimal digits or 0x and hex digits, nothing else: strtoll's base 0 read a leading zero as octal
 * ("010" was 8, "08" no number), skipped leading blanks and clamped an overflow without a word. */
static bool parse_sign_magnitude(const char *text, bool *negative, unsigned long long *magnitude)
{
    const char *p = text;
    *negative = *p == '-';
    if (*p == '-' || *p == '+') {
        p++;
    }
    unsigned base = 10U;
    if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        base = 16U;
        p += 2;
    }
    if (*p == '\0') {
        return false;
    }
    unsigned long long v = 0U;
    for (; *p != '\0'; p++) {
        const char c = *p;
        const unsigned d = (c >= '0' && c <= '9') ? (unsigned)(c - '0')
                           : (c >= 'a' && c <= 'f') ? (unsigned)(c - 'a' + 10)
                           : (c >= 'A' && c <= 'F') ? (unsigned)(c - 'A' + 10) : 16U;
        if (d >= base || v > (ULLONG_MAX - d) / base) {
            return false;
        }
        v = v * base + d;
    }
    *magnitude = v;
    return true;
}

bool device_parse_int(const char *text, long long lo, long long hi, long long *out)
{
    bool negative;
    unsigned long long magnitude;
    if (text == NULL || !parse_sign_magnitude(text, &negative, &magnitude)) {
        return false;
    }
    const unsigned long long most_negative = (unsigned long long)LLONG_MAX + 1U;
    long long v;
    if (negative) {
        if (magnitude > most_negative) {
            return false;
        }
        v = magnitude == most_negative ? LLONG_MIN : -(long long)magnitude;
    } else {
        if (magnitude > (unsigned long long)LLONG_MAX) {
            return false;
        }
        v = (long long)magnitude;
    }
    if (v < lo || v > hi) {
        return false;
    }
    *out = v;
    return true;
}

/* One hex field of an address: optional 0x, hex digits only. */
static bool parse_hex(const char *text, size_t n, unsigned long max, unsigned long *out)
{
    if (n > 2U && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        text += 2;
        n -= 2U;
    }
    if (n == 0U || n > 4U) {
        return false;
    }
    unsigned long v = 0U;
    for (size_t i = 0U; i < n; i++) {
        const char c = text[i];
        const int d = (c >= '0' && c <= '9') ? c - '0' : (c >= 'a' && c <= 'f') ? c - 'a' + 10 : (c >= 'A' && c <= 'F') ? c - 'A' + 10 : -1;
        if (d < 0) {
            return false;
        }
        v = v * 16U + (unsigned long)d;
    }
    if (v > max) {
        return false;
    }
    *out = v;
    return true;
}

bool device_parse_address(const char *text, uint16_t *index, uint8_t *sub)
{
    const char *colon = strchr(text, ':');
    const size_t ilen = colon != NULL ? (size_t)(colon - text) : strlen(text);
    unsigned long i, s = 0U;
    if (!parse_hex(text, ilen, 0xFFFFU, &i) || (colon != NULL && !parse_hex(colon + 1, strlen(colon + 1), 0xFFU, &s))) {
        return false;
    }
    *index = (uint16_t)i;
    *sub = (uint8_t)s;
    return true;
}

/* A VISIBLE_STRING as a C string: CiA 301 gives it the printable ASCII characters 0x20..0x7E, which are shown as
 * they are, but any SDO client may write any byte: every other byte as \xNN, a backslash as \\ and a quote as \",
 * so that nothing reaches a terminal that it would act on (ESC[2J clears it) and every byte can be told from the
 * line. Into out (cap bytes with its NUL) as many whole bytes of text[0..len) as fit: returns how many. */
static size_t escape_string(char *out, size_t cap, const uint8_t *text, size_t len)
{
    static const char hex[] = "0123456789abcdef";
    size_t w = 0U;
    size_t i = 0U;
    for (; i < len; i++) {
        const uint8_t c = text[i];
        const size_t need = (c == '\\' || c == '"') ? 2U : (c >= 0x20U && c < 0x7FU) ? 1U : 4U;
        if (need >= cap - w) {
            break;
        }
        if (need == 2U) {
            out[w++] = '\\';
            out[w++] = (char)c;
        } else if (need == 1U) {
            out[w++] = (char)c;
        } else {
            out[w++] = '\\';
            out[w++] = 'x';
            out[w++] = hex[c >> 4];
            out[w++] = hex[c & 0x0FU];
        }
    }
    out[w] = '\0';
    return i;
}

static void print_value(device_t *dev, uint16_t index, uint8_t sub)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(dev->cls->od, index, sub, &one);
    uint8_t buf[256];
    size_t len = 0U;
    const uint32_t r = co_od_read(&dev->node, index, sub, buf, sizeof buf - 1U, &len, CO_ORIGIN_LOCAL);
    if (r != 0U) {
        device_printf(dev, "0x%04X:%02X: %s (0x%08lX)", index, sub, co_abort_text(r), (unsigned long)r);
        return;
    }
    uint64_t u = 0U;
    for (size_t i = len; i > 0U; i--) {
        u = (u << 8) | buf[i - 1U];
    }
    switch (e->type) {
    case CO_T_VISIBLE_STRING: {
        /* Up to its first NUL, as the JSON get. A device line is shorter than 512 bytes (device_print_fn): a string
         * whose escapes do not fit is cut, and the line says so (JSON get has it whole). With canopen-emu's
         * CO_SDO_BUF_SIZE of 64, the longest string an SDO client can write, every byte escaped, fits. */
        char shown[400];
        const uint8_t *nul = memchr(buf, 0, len);
        const size_t text_len = nul != NULL ? (size_t)(nul - buf) : len;
        const size_t taken = escape_string(shown, sizeof shown, buf, text_len);
        if (taken == text_len) {
            device_printf(dev, "0x%04X:%02X = \"%s\"", index, sub, shown);
        } else {
            device_printf(dev, "0x%04X:%02X = \"%s\"... (cut: %u of %u bytes shown)", index, sub, shown, (unsigned)taken,
                          (unsigned)text_len);
        }
        break;
    }
    case CO_T_REAL32: {
        float f;
        const uint32_t u32 = (uint32_t)u;
        memcpy(&f, &u32, sizeof f);
        device_printf(dev, "0x%04X:%02X = %g", index, sub, (double)f);
        break;
    }
    case CO_T_REAL64: {
        double d;
        memcpy(&d, &u, sizeof d);
        device_printf(dev, "0x%04X:%02X = %.17g", index, sub, d);
        break;
    }
    case CO_T_OCTET_STRING:
    case CO_T_UNICODE_STRING:
    case CO_T_DOMAIN: {
        char hex[2U * sizeof buf + 1U];
        for (size_t i = 0U; i < len; i++) {
            (void)snprintf(hex + 2U * i, 3U, "%02X", buf[i]);
        }
        hex[2U * len] = '\0';
        device_printf(dev, "0x%04X:%02X = %s (%u bytes)", index, sub, hex, (unsigned)len);
        break;
    }
    default:
        if (device_type_is_signed(e->type) && len > 0U) {
            const unsigned bits = (unsigned)len * 8U;
            int64_t v = (int64_t)u;
            if (bits < 64U && (u >> (bits - 1U)) != 0U) {
                v = (int64_t)(u | ~((UINT64_C(1) << bits) - 1U));
            }
            device_printf(dev, "0x%04X:%02X = %lld", index, sub, (long long)v);
            break;
        }
        device_printf(dev, "0x%04X:%02X = %llu (0x%llX)", index, sub, (unsigned long long)u, (unsigned long long)u);
        break;
    }
}

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

static device_cmd_result_t cmd_set(device_t *dev, const char *addr, const char *text)
{
    uint16_t index;
    uint8_t sub;
    co_od_entry_t one;
    const co_od_entry_t *e;
    if (!device_parse_address(addr, &index, &sub) || (e = co_od_find(dev->cls->od, index, sub, &one)) == NULL) {
        device_printf(dev, "error: no object %s", addr);
        return DEVICE_CMD_ERROR;
    }
    uint8_t wire[256];
    size_t len = e->size;
    if (e->type == CO_T_VISIBLE_STRING) {
        len = strlen(text);
        if (len > e->size) {
            device_printf(dev, "error: %s holds at most %u characters", addr, e->size);
            return DEVICE_CMD_ERROR;
        }
        memcpy(wire, text, len);
    } else if (e->type == CO_T_REAL32) {
        char *end = NULL;
        errno = 0;
        const float f = strtof(text, &end);
        uint32_t u;
        if (end == NULL || end == text || *end != '\0') {
            device_printf(dev, "error: '%s' is not a number", text);
            return DEVICE_CMD_ERROR;
        }
        if (errno == ERANGE && isinf(f)) { /* beyond the largest REAL32; an explicit "inf" is taken as it is */
            device_printf(dev, "error: %s is out of range: 0x%04X:%02X (REAL32) holds -3.4e38..3.4e38", text, index, sub);
            return DEVICE_CMD_ERROR;
        }
        memcpy(&u, &f, sizeof u);
        for (size_t i = 0U; i < 4U; i++) {
            wire[i] = (uint8_t)(u >> (8U * i));
        }
    } else if (e->size <= 8U) {
        /* Checked against the object's type before it is cut to e->size bytes: 70000 stored 4464 in an UNSIGNED16,
         * -1 stored 65535, and 65636 stored 100, which then passed the Eltex rule that refuses 50. */
        bool negative;
        unsigned long long magnitude;
        if (!parse_sign_magnitude(text, &negative, &magnitude)) {
            device_printf(dev, "error: '%s' is not a number", text);
            return DEVICE_CMD_ERROR;
        }
        const integer_range_t range = integer_range(e);
        if (negative ? magnitude > range.most_negative : magnitude > range.highest) {
            if (range.is_signed) {
                device_printf(dev, "error: %s is out of range: 0x%04X:%02X (%s) holds -%llu..%llu", text, index, sub,
                              device_type_name(e->type), range.most_negative, range.highest);
            } else {
                device_printf(dev, "error: %s is out of range: 0x%04X:%02X (%s) holds 0..%llu", text, index, sub,
                              device_type_name(e->type), range.highest);
            }
            return DEVICE_CMD_ERROR;
        }
        const unsigned long long twos_complement = negative ? 0U - magnitude : magnitude;
        for (size_t i = 0U; i < e->size; i++) {
            wire[i] = (uint8_t)(twos_complement >> (8U * i));
        }
    } else {
        device_printf(dev, "error: %s cannot be set from the command line", addr);
        return DEVICE_CMD_ERROR;
    }
    const uint32_t r = co_od_write(&dev->node, index, sub, wire, len, CO_ORIGIN_LOCAL);
    if (r != 0U) {
        device_printf(dev, "error: 0x%04X:%02X: %s (0x%08lX)", index, sub, co_abort_text(r), (unsigned long)r);
        return DEVICE_CMD_ERROR;
    }
    print_value(dev, index, sub);
    return DEVICE_CMD_OK;
}

/* The common commands in the form of a class's commands_help: what device_command says when one of them comes with
 * the wrong number of words. */
static const char common_usage[] = "  show\n"
                                   "  get INDEX[:SUB]\n"
                                   "  set INDEX[:SUB] VALUE\n"
                                   "  emcy CODE [REGISTER [B0..B4]]\n"
                                   "  emcy-clear CODE [B0..B4]\n"
                                   "  power-cycle\n";

/* The first " / " in [p, end), or end. */
static const char *next_alternative(const char *p, const char *end)
{
    for (; p + 3 <= end; p++) {
        if (p[0] == ' ' && p[1] == '/' && p[2] == ' ') {
            return p;
        }
    }
    return end;
}

bool device_help_usage(const char *help, const char *word, const char **args, size_t *args_len)
{
    const size_t word_len = strlen(word);
    if (help == NULL || word_len == 0U) {
        return false;
    }
    const char *line = help;
    while (*line != '\0') {
        const char *end = strchr(line, '\n');
        if (end == NULL) {
            end = line + strlen(line);
        }
        if (end - line > 2 && line[0] == ' ' && line[1] == ' ' && line[2] != ' ') {
            const char *usage = line + 2;
            const char *stop = usage; /* the usage column ends at two blanks in a row */
            while (stop < end && !(stop[0] == ' ' && stop + 1 < end && stop[1] == ' ')) {
                stop++;
            }
            for (const char *alt = usage; alt < stop;) {
                const char *alt_end = next_alternative(alt, stop);
                if ((size_t)(alt_end - alt) >= word_len && strncmp(alt, word, word_len) == 0 &&
                    (alt + word_len == alt_end || alt[word_len] == ' ')) {
                    const char *a = alt + word_len;
                    while (a < alt_end && *a == ' ') {
                        a++;
                    }
                    *args = a;
                    *args_len = (size_t)(alt_end - a);
                    return true;
                }
                alt = alt_end == stop ? stop : alt_end + 3;
            }
        }
        line = *end == '\n' ? end + 1 : end;
    }
    return false;
}

device_cmd_result_t device_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
    dev->now = now;
    dev->touched = true;
    if (argc < 1) {
        return DEVICE_CMD_UNKNOWN;
    }
    if (dev->cls->command != NULL) {
        const device_cmd_result_t r = dev->cls->command(dev, argc, argv, now);
        if (r != DEVICE_CMD_UNKNOWN) {
            return r;
        }
    }
    const char *cmd = argv[0];
    if (strcmp(cmd, "show") == 0 && argc == 1) {
        const co_node_t *n = &dev->node;
        device_printf(dev, "%s node-ID %u%s: %s, error register 0x%02X, %u active error(s), tx %lu, rx %lu, dropped %lu",
                      dev->cls->name, n->node_id, n->node_id == CO_NODE_ID_UNCONFIGURED ? " (unconfigured)" : "",
                      co_nmt_state_name(n->nmt_state), co_od_get_u8(&dev->node, 0x1001, 0), n->emcy.n_active,
                      (unsigned long)n->stats.tx_frames, (unsigned long)n->stats.rx_frames,
                      (unsigned long)n->stats.tx_dropped);
        for (uint8_t i = 0U; i < n->emcy.n_active; i++) {
            const co_emcy_error_t *er = &n->emcy.active[i];
            device_printf(dev, "  error 0x%04X register 0x%02X info %02X %02X %02X %02X %02X", er->code, er->reg,
                          er->msef[0], er->msef[1], er->msef[2], er->msef[3], er->msef[4]);
        }
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "get") == 0 && argc == 2) {
        uint16_t index;
        uint8_t sub;
        if (!device_parse_address(argv[1], &index, &sub)) {
            device_printf(dev, "error: '%s' is not INDEX[:SUB]", argv[1]);
            return DEVICE_CMD_ERROR;
        }
        print_value(dev, index, sub);
        return DEVICE_CMD_OK;
    }
    if (strcmp(cmd, "set") == 0 && argc == 3) {
        return cmd_set(dev, argv[1], argv[2]);
    }
    if ((strcmp(cmd, "emcy") == 0 || strcmp(cmd, "emcy-clear") == 0) && argc >= 2) {
        /* Raw CiA EMCY injection: emcy CODE [REGISTER [B0 B1 B2 B3 B4]], emcy-clear CODE [B0 B1 B2 B3 B4]. */
        const bool raise = strcmp(cmd, "emcy") == 0;
        const int first_msef = raise ? 3 : 2;
        long long code, reg = 0x01, b;
        uint8_t msef[5] = {0U, 0U, 0U, 0U, 0U};
        if (!device_parse_int(argv[1], 1, 0xFFFF, &code) || (raise && argc >= 3 && !device_parse_int(argv[2], 0, 0xFF, &reg)) ||
            argc > first_msef + 5) {
            device_printf(dev, "error: usage: emcy CODE [REGISTER [B0..B4]] | emcy-clear CODE [B0..B4]");
            return DEVICE_CMD_ERROR;
        }
        for (int i = first_msef; i < argc; i++) {
            if (!device_parse_int(argv[i], 0, 0xFF, &b)) {
                device_printf(dev, "error: '%s' is not a byte", argv[i]);
                return DEVICE_CMD_ERROR;
            }
            msef[i - first_msef] = (uint8_t)b;
        }
        const bool ok = raise ? co_emcy_raise(&dev->node, (uint16_t)code, (uint8_t)reg, msef)
                              : co_emcy_clear(&dev->node, (uint16_t)code, msef);
        device_printf(dev, "%s 0x%04X: %s", raise ? "emcy" : "emcy-clear", (unsigned)code,
                      ok ? "done" : (raise ? "refused (too many active errors)" : "not active"));
        return ok ? DEVICE_CMD_OK : DEVICE_CMD_ERROR;
    }
    if (strcmp(cmd, "power-cycle") == 0 && argc == 1) {
        if (device_power_cycle(dev, now) != CO_OK) {
            device_printf(dev, "error: power-on failed");
            return DEVICE_CMD_ERROR;
        }
        device_printf(dev, "power cycled");
        return DEVICE_CMD_OK;
    }
    /* A command of the device with too few or too many words: what it takes, not "unknown command". */
    const char *args;
    size_t args_len;
    if (device_help_usage(common_usage, cmd, &args, &args_len) ||
        device_help_usage(dev->cls->commands_help, cmd, &args, &args_len)) {
        if (args_len == 0U) {
            device_printf(dev, "error: %s takes no arguments", cmd);
        } else {
            device_printf(dev, "error: %s takes %.*s", cmd, (int)args_len, args);
        }
        return DEVICE_CMD_ERROR;
    }
    return DEVICE_CMD_UNKNOWN;
}

/* The text of sub-index e in a table with one per sub-index of the dictionary, in order (a run of the table's rows
 * has one text per sub-index). */
static const char *row_text(const device_class_t *cls, const char *const *table, const co_od_entry_t *e)
{
    const co_od_t *od = cls->od;
    size_t ordinal = 0U;
    for (uint16_t i = 0U; table != NULL && i < od->count; i++) {
        const co_od_entry_t *row = &od->entries[i];
        const unsigned k = (unsigned)(e->sub - row->sub);
        if (row->index == e->index && e->sub >= row->sub && k < co_od_entry_subs(row)) {
            return table[ordinal + k];
        }
        ordinal += co_od_entry_subs(row);
    }
    return NULL;
}

const char *device_object_name(const device_class_t *cls, const co_od_entry_t *e)
{
    return row_text(cls, cls->od_names, e);
}

const char *device_object_unit(const device_class_t *cls, const co_od_entry_t *e)
{
    return row_text(cls, cls->od_units, e);
}

const char *device_object_title(const device_class_t *cls, uint16_t index)
{
    const co_od_t *od = cls->od;
    size_t lo = 0U;
    size_t hi = cls->od_object_names != NULL && od->objects != NULL ? od->n_objects : 0U;
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2U;
        if (od->objects[mid].index < index) {
            lo = mid + 1U;
        } else {
            hi = mid;
        }
    }
    return lo < od->n_objects && cls->od_object_names != NULL && od->objects != NULL && od->objects[lo].index == index
               ? cls->od_object_names[lo]
               : NULL;
}

co_time_us_t device_save_phase_us(const device_t *dev)
{
    return (co_time_us_t)(dev->cfg.node_id % 60U) * 1000000U;
}

uint32_t device_default_serial(const device_class_t *cls)
{
    co_od_entry_t one;
    const co_od_entry_t *e = co_od_find(cls->od, 0x1018, 4, &one);
    uint32_t serial = 0U;
    if (e != NULL && e->size == sizeof serial) {
        co_od_copy_defaults(cls->od, e->offset, sizeof serial, &serial);
    }
    return serial;
}

const device_class_t *device_find_class(const char *name)
{
    for (size_t i = 0U; device_classes[i] != NULL; i++) {
        if (strcmp(device_classes[i]->name, name) == 0) {
            return device_classes[i];
        }
    }
    return NULL;
}
