/*
 * Fuzz target "<device>": one emulated device of devices/registry.c (FZ_DEVICE_NAME: "pro-ionizer", "sds" or
 * "buerkert") run through device_init / device_rx / device_process / device_command / device_power_cycle,
 * written against devices/device.h only. The class is copied so its on_reset hook can be observed; the
 * model's code is the registered one.
 *
 * Header: [0] bits 0-2 variant (0 = default, 1..n = the class's variants, n+1 = an unknown name that must
 *         be refused), bit 3 no NVM functions, bit 4 no set_bit_rate; [1] node-ID (0 = the class default,
 *         128..254 must be refused); [2] serial number selector (0 = the OD default).
 *
 * Read-only rows the model may change (fzt_ro_exempt): every TPDO-mappable row (process values), and per
 * device the rows its manual describes as live readings or counters:
 *   pro-ionizer  0x2000:01-0C operating/discharging hours, 0x2001:01-19 readings, 0x2002:05 burn-in state,
 *                0x2002:09/0A current and power set-points in use
 *   sds          0x2000:01-08 operating/HV hours, 0x2001:01-0A readings, 0x2002:03 active length,
 *                0x2002:05 burn-in state
 *   buerkert     0x2001:06/08 CAN error counters, 0x2001:0A CAN operation status, 0x2004:01-08 NAMUR status
 * Everything else without CO_OD_WRITE (identity, 0x1000, PDO parameters of static mappings, sub-index 0 of
 * every object, descriptors) must keep its power-on value.
 */
#include <string.h>

#include "device.h"
#include "fuzz.h"

#ifndef FZ_DEVICE_NAME
#error "FZ_DEVICE_NAME must name a registered device class"
#endif

static fz_t *g_h;
static const device_class_t *g_orig;
static device_class_t g_cls;
static device_t *g_dev;
static void *g_values;
static void *g_model;
static device_cfg_t g_cfg;

static void w_on_reset(device_t *dev, co_reset_t what)
{
    fz_note_reset(g_h, what);
    if (g_orig->on_reset != NULL) {
        g_orig->on_reset(dev, what);
    }
}

static void on_event(void *ctx, const device_t *dev, const co_event_t *ev)
{
    if (ctx != g_h || dev != g_dev) {
        fz_fail(g_h, "device on_event with a foreign context");
    }
    fz_note_event(g_h, ev);
}

static void on_print(void *ctx, const device_t *dev, const char *line)
{
    if (ctx != g_h || dev != g_dev || line == NULL || strlen(line) >= 512U) {
        fz_fail(g_h, "device print callback with a bad line or context");
    }
    if (getenv("FUZZ_TRACE") != NULL) {
        fprintf(stderr, "             | %s\n", line);
    }
}

bool fzt_ro_exempt(const co_od_entry_t *e)
{
    const char *n = g_orig->name;
    const uint8_t s = e->sub;
    if ((e->flags & CO_OD_TPDO) != 0U) {
        return true;
    }
    if (strcmp(n, "pro-ionizer") == 0) {
        return (e->index == 0x2000U && s >= 0x01U && s <= 0x0CU) || (e->index == 0x2001U && s >= 0x01U && s <= 0x19U) ||
               (e->index == 0x2002U && (s == 0x05U || s == 0x09U || s == 0x0AU));
    }
    if (strcmp(n, "sds") == 0) {
        return (e->index == 0x2000U && s >= 0x01U && s <= 0x08U) || (e->index == 0x2001U && s >= 0x01U && s <= 0x0AU) ||
               (e->index == 0x2002U && (s == 0x03U || s == 0x05U));
    }
    if (strcmp(n, "buerkert") == 0) {
        return (e->index == 0x2001U && (s == 0x06U || s == 0x08U || s == 0x0AU)) ||
               (e->index == 0x2004U && s >= 0x01U && s <= 0x08U);
    }
    return false;
}

bool fzt_init(fz_t *h, const uint8_t hdr[4])
{
    g_h = h;
    g_orig = device_find_class(FZ_DEVICE_NAME);
    if (g_orig == NULL) {
        fz_fail(h, "device class '%s' is not registered", FZ_DEVICE_NAME);
    }
    g_cls = *g_orig;
    g_cls.on_reset = w_on_reset;
    h->target = FZ_DEVICE_NAME;
    g_values = malloc(g_orig->od->values_size + 0U);
    g_model = malloc(g_orig->model_size > 0U ? g_orig->model_size : 1U);
    g_dev = (device_t *)calloc(1U, sizeof *g_dev);
    if (g_values == NULL || g_model == NULL || g_dev == NULL) {
        abort();
    }
    memset(g_values, 0xA5, g_orig->od->values_size); /* device_init must initialise all of it */
    memset(g_model, 0xA5, g_orig->model_size > 0U ? g_orig->model_size : 1U);
    unsigned n_variants = 0U;
    while (g_orig->variants != NULL && g_orig->variants[n_variants] != NULL) {
        n_variants++;
    }
    const unsigned v = (hdr[0] & 0x07U) % (n_variants + 2U);
    if ((hdr[0] & 0x08U) != 0U) {
        h->port.nvm_write = NULL;
        h->port.nvm_commit = NULL;
        h->port.nvm_read = NULL;
    }
    if ((hdr[0] & 0x10U) != 0U) {
        h->port.set_bit_rate = NULL;
    }
    memset(&g_cfg, 0, sizeof g_cfg);
    g_cfg.node_id = hdr[1];
    g_cfg.serial = hdr[2] == 0U ? 0U : 0x00A10000UL + hdr[2];
    g_cfg.variant = v == 0U ? NULL : v <= n_variants ? g_orig->variants[v - 1U] : "no-such-variant";
    g_cfg.port = &h->port;
    g_cfg.port_ctx = &h->fp;
    g_cfg.print = on_print;
    g_cfg.print_ctx = h;
    g_cfg.on_event = on_event;
    g_cfg.event_ctx = h;
    h->node = &g_dev->node;
    h->od = g_orig->od;
    h->values = (uint8_t *)g_values;
    h->options = g_orig->core_options;
    const co_status_t st = device_init(g_dev, &g_cls, g_values, g_model, &g_cfg, h->now);
    const bool bad_id = hdr[1] > 127U && hdr[1] != CO_NODE_ID_UNCONFIGURED;
    if (bad_id || v > n_variants) {
        if (st != CO_ERR_ARG) {
            fz_fail(h, "device_init accepted node-ID %u / variant %s (status %d)", hdr[1],
                    g_cfg.variant != NULL ? g_cfg.variant : "(default)", (int)st);
        }
        return false;
    }
    if (st != CO_OK) {
        fz_fail(h, "device_init failed with status %d", (int)st);
    }
    return true;
}

void fzt_fini(fz_t *h)
{
    (void)h;
    free(g_values);
    free(g_model);
    free(g_dev);
    g_values = NULL;
    g_model = NULL;
    g_dev = NULL;
}

bool fzt_rx(fz_t *h, const co_frame_t *f, bool *pending)
{
    const bool taken = device_rx(g_dev, f, h->now);
    *pending = taken && !device_settled(g_dev);
    return taken;
}

co_time_us_t fzt_process(fz_t *h, bool direct)
{
    return direct ? co_node_process(&g_dev->node, h->now) : device_process(g_dev, h->now);
}

bool fzt_power_cycle(fz_t *h) { return device_power_cycle(g_dev, h->now) == CO_OK; }

/* ---- Control commands: templates, valid and invalid, for all three devices (a command another device does
 * not know must be answered DEVICE_CMD_UNKNOWN). Placeholders take values from the input:
 * {i} integer, {u} small unsigned, {x} byte in hex, {X} 16-bit hex, {f} decimal fraction, {s} string. */

static const char *const commands[] = {
    /* device.c */
    "show", "get 0x1017", "get 0x1001", "get 0x1018:04", "get {X}:{u}", "get 0x2001:{u}", "get 0x6401:{u}",
    "get 0x2002:{u}", "get zz", "get", "get 0x12345", "set 0x1017 {i}", "set 0x1000 {i}", "set {X}:{u} {i}",
    "set 0x2002:{u} {i}", "set 0x1008 {s}", "set 0x2002:01 {s}", "set 0x2540:01 {f}", "set 0x1017", "set 0x1001 {i}",
    "set 0x1014 {i}", "set 0x1800:01 {i}", "set 0x1A00:00 {i}", "set 0x6200:01 {i}", "set 0x1010:01 1702257011",
    "set 0x1011:01 1684107116", "emcy {X}", "emcy {X} {u} {u} {u} {u} {u} {u}", "emcy-clear {X}",
    "emcy-clear {X} {u} {u} {u} {u} {u}", "emcy 0", "emcy 0x10000", "emcy 1 2 3 4 5 6 7 8 9", "emcy 0x1000 0x100",
    "power-cycle", "power-cycle now", "help", "", "nonsense {i}",
    /* pro-ionizer */
    "status", "load {u} {i}", "load 1 short", "load 5 100", "load 2", "temperature {i}", "supply {i}",
    "hw-release on", "hw-release off", "hw-release maybe", "keypad release on", "keypad release off",
    "keypad lock on", "speed {u} {i}", "speed 1 off", "efield {u} {i}", "efield 1 {i} {i}", "sensor D{u} {u}",
    "sensor A1 3", "sensor X9 1", "error {x}", "warning {x}", "clear-error {x}", "clear-warning {x}",
    "bit-timing {u}", "bit-timing 9", "bit-timing 4", "bit-timing 5",
    /* sds */
    "pollution {u}", "conductance {i}", "load {i}", "air {u}", "supply {f}", "supply 24.0", "supply 17",
    "faults", "model",
    /* buerkert */
    "setpoint {f}", "setpoint -5", "setpoint 150", "setpoint nan", "flow-fault on", "flow-fault off",
    "valve-fault on", "valve-fault off", "error {X} {u}", "mode auto", "mode hand", "mode flashing", "mode foo",
};

static const char *const ints[] = {"0", "1", "-1", "2", "5", "9", "10", "60", "61", "70", "75", "76", "99",
                                   "100", "127", "128", "255", "256", "1000", "5000", "20000", "21600", "28800",
                                   "60000", "65535", "65536", "2147483647", "-2147483648", "9223372036854775807",
                                   "-9223372036854775808", "99999999999999999999", "0x", "1e3", "-", "+7", " 3"};
static const char *const smalls[] = {"0", "1", "2", "3", "4", "5", "6", "7", "8", "9", "10", "11", "99", "127",
                                     "128", "255", "256", "-1"};
static const uint16_t codes[] = {0x0000, 0x0001, 0x0012, 0x0050, 0x0051, 0x0060, 0x0061, 0x00FF, 0x1000,
                                 0x3110, 0x3120, 0x4210, 0x5010, 0x5020, 0x8130, 0xFF00, 0xFFFF};
static const char *const strings[] = {"", "A", "hello", "ES61", "0123456789012345678901234567890123456789",
                                      "\xC3\xA4\xC3\xB6", "%s%n%x"};

static void fill(fz_in_t *in, char kind, char *out, size_t cap)
{
    const uint8_t k = fz_u8(in);
    switch (kind) {
    case 'i':
        if (k < sizeof ints / sizeof ints[0]) {
            (void)snprintf(out, cap, "%s", ints[k]);
        } else {
            (void)snprintf(out, cap, "%d", (int)(int16_t)fz_u16(in));
        }
        break;
    case 'u':
        if (k < sizeof smalls / sizeof smalls[0]) {
            (void)snprintf(out, cap, "%s", smalls[k]);
        } else {
            (void)snprintf(out, cap, "%u", (unsigned)fz_u8(in));
        }
        break;
    case 'x':
        (void)snprintf(out, cap, "0x%02X", (unsigned)fz_u8(in));
        break;
    case 'X':
        if (k < sizeof codes / sizeof codes[0]) {
            (void)snprintf(out, cap, "0x%04X", (unsigned)codes[k]);
        } else {
            (void)snprintf(out, cap, "0x%04X", (unsigned)fz_u16(in));
        }
        break;
    case 'f':
        (void)snprintf(out, cap, "%d.%u", (int)(int8_t)k, (unsigned)(fz_u8(in) % 10U));
        break;
    default:
        if (k < sizeof strings / sizeof strings[0]) {
            (void)snprintf(out, cap, "%s", strings[k]);
        } else { /* a long string: longer than every string object */
            const size_t n = (size_t)k + 40U < cap - 1U ? (size_t)k + 40U : cap - 1U;
            memset(out, 'x', n);
            out[n] = '\0';
        }
        break;
    }
}

/* Expands a template into argv (words split at spaces, placeholders filled from the input). */
static int expand(fz_in_t *in, const char *tmpl, char words[][320], const char *argv[], int max)
{
    int argc = 0;
    const char *p = tmpl;
    while (*p != '\0' && argc < max) {
        while (*p == ' ') {
            p++;
        }
        if (*p == '\0') {
            break;
        }
        char *w = words[argc];
        size_t n = 0U;
        while (*p != '\0' && *p != ' ') {
            if (p[0] == '{' && p[1] != '\0' && p[2] == '}') {
                char val[300];
                fill(in, p[1], val, sizeof val);
                const size_t l = strlen(val);
                if (n + l < 319U) {
                    memcpy(w + n, val, l);
                    n += l;
                }
                p += 3;
            } else {
                if (n < 319U) {
                    w[n++] = *p;
                }
                p++;
            }
        }
        w[n] = '\0';
        argv[argc] = w;
        argc++;
    }
    return argc;
}

bool fzt_app(fz_t *h, fz_in_t *in)
{
    const uint8_t sel = fz_u8(in);
    if (sel < 0xC0U) {
        static char words[12][320];
        const char *argv[12];
        const char *tmpl = commands[fz_u8(in) % (sizeof commands / sizeof commands[0])];
        int argc = expand(in, tmpl, words, argv, 12);
        if (argc == 0) { /* "": an empty word as the command */
            words[0][0] = '\0';
            argv[0] = words[0];
            argc = (sel & 1U) != 0U ? 1 : 0;
        }
        if (getenv("FUZZ_TRACE") != NULL) {
            fprintf(stderr, "             command:");
            for (int i = 0; i < argc; i++) {
                fprintf(stderr, " '%s'", argv[i]);
            }
            fprintf(stderr, "\n");
        }
        const device_cmd_result_t r = device_command(g_dev, argc, argv, h->now, NULL);
        if (r != DEVICE_CMD_OK && r != DEVICE_CMD_UNKNOWN && r != DEVICE_CMD_ERROR) {
            fz_fail(h, "device_command(%s) returned %d", tmpl, (int)r);
        }
        if (argc == 0 && r != DEVICE_CMD_UNKNOWN) {
            fz_fail(h, "device_command with argc 0 returned %d", (int)r);
        }
        return true; /* commands may set anything locally ("set", "power-cycle", the model's inputs) */
    }
    /* The core API as a device application uses it; none of these may change a read-only value. */
    co_node_t *node = &g_dev->node;
    const co_od_t *od = g_orig->od;
    const co_od_entry_t *e = &od->entries[fz_u16(in) % od->count];
    uint8_t buf[80];
    switch (sel % 6U) {
    case 0: {
        const size_t cap = fz_u8(in) % (sizeof buf + 1U);
        size_t len = 777U;
        const uint32_t r = co_od_read(node, e->index, e->sub, buf, cap, &len, CO_ORIGIN_SDO);
        if ((r == 0U && len > cap) || (r != 0U && len != 0U)) {
            fz_fail(h, "co_od_read(0x%04X:%02X, cap %lu) = 0x%08lX with length %lu", e->index, e->sub,
                    (unsigned long)cap, (unsigned long)r, (unsigned long)len);
        }
        break;
    }
    case 1:
    case 2: {
        const size_t len = (fz_u8(in) & 1U) != 0U ? e->size % (sizeof buf + 1U) : fz_u8(in) % 9U;
        for (size_t i = 0U; i < len; i++) {
            buf[i] = fz_u8(in);
        }
        (void)co_od_write(node, e->index, e->sub, buf, len, sel % 6U == 1U ? CO_ORIGIN_SDO : CO_ORIGIN_RPDO);
        break;
    }
    case 3:
        co_tpdo_trigger(node, (uint8_t)(fz_u8(in) % 6U));
        break;
    case 4:
        (void)co_emcy_is_active(node, fz_u16(in));
        (void)co_od_get_u32(node, e->index, e->sub);
        break;
    default:
        (void)device_default_serial(g_orig);
        (void)device_find_class("no-such-device");
        break;
    }
    return false;
}
