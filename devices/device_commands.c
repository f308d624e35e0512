/* The commands every device understands (show, get, set, emcy, emcy-clear, power-cycle), after the device's own:
 * see device.h (device_command). */
#include "device.h"

#include <stdio.h>
#include <string.h>

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

/* The reply of get and set: "0x1017:00 = 5000 (0x1388)", or why the value cannot be read. */
static void print_value(device_t *dev, uint16_t index, uint8_t sub)
{
    uint8_t buf[256];
    device_value_t v;
    const uint32_t r = device_get_value(dev, index, sub, dev->now, buf, sizeof buf, &v);
    if (r != 0U) {
        device_printf(dev, "0x%04X:%02X: %s (0x%08lX)", index, sub, co_abort_text(r), (unsigned long)r);
        return;
    }
    switch (v.kind) {
    case DEVICE_VALUE_TEXT: {
        /* Up to its first NUL, as the JSON get. A device line is shorter than 512 bytes (device_print_fn): a string
         * whose escapes do not fit is cut, and the line says so (JSON get has it whole). With canopen-emu's
         * CO_SDO_BUF_SIZE of 64, the longest string an SDO client can write, every byte escaped, fits. */
        char shown[400];
        const size_t taken = escape_string(shown, sizeof shown, v.bytes, v.len);
        if (taken == v.len) {
            device_printf(dev, "0x%04X:%02X = \"%s\"", index, sub, shown);
        } else {
            device_printf(dev, "0x%04X:%02X = \"%s\"... (cut: %u of %u bytes shown)", index, sub, shown, (unsigned)taken,
                          (unsigned)v.len);
        }
        break;
    }
    case DEVICE_VALUE_REAL:
        if (v.type == CO_T_REAL32) {
            device_printf(dev, "0x%04X:%02X = %g", index, sub, v.as.r);
        } else {
            device_printf(dev, "0x%04X:%02X = %.17g", index, sub, v.as.r);
        }
        break;
    case DEVICE_VALUE_BYTES: {
        char hex[2U * sizeof buf + 1U];
        for (size_t i = 0U; i < v.len; i++) {
            (void)snprintf(hex + 2U * i, 3U, "%02X", v.bytes[i]);
        }
        hex[2U * v.len] = '\0';
        device_printf(dev, "0x%04X:%02X = %s (%u bytes)", index, sub, hex, (unsigned)v.len);
        break;
    }
    case DEVICE_VALUE_SIGNED:
        device_printf(dev, "0x%04X:%02X = %lld", index, sub, (long long)v.as.i);
        break;
    case DEVICE_VALUE_BOOLEAN:
        device_printf(dev, "0x%04X:%02X = %u (0x%X)", index, sub, v.as.b ? 1U : 0U, v.as.b ? 1U : 0U);
        break;
    case DEVICE_VALUE_UNSIGNED:
        device_printf(dev, "0x%04X:%02X = %llu (0x%llX)", index, sub, (unsigned long long)v.as.u,
                      (unsigned long long)v.as.u);
        break;
    }
}

/* set INDEX[:SUB] VALUE: the word in the object's type (device_set_value), then the value as it is now. */
static device_cmd_result_t set_from_words(device_t *dev, const char *addr, const char *word)
{
    uint16_t index;
    uint8_t sub;
    if (!device_parse_address(addr, &index, &sub)) {
        device_printf(dev, "error: '%s' is not INDEX[:SUB]", addr);
        return DEVICE_CMD_ERROR;
    }
    device_value_t v;
    memset(&v, 0, sizeof v);
    v.kind = DEVICE_VALUE_TEXT;
    v.bytes = (const uint8_t *)word;
    v.len = strlen(word);
    char why[256];
    if (!device_set_value(dev, index, sub, &v, dev->now, why, sizeof why)) {
        device_printf(dev, "error: %s", why);
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

/* The command itself: device_command sets its output around it. */
static device_cmd_result_t run(device_t *dev, int argc, const char *const *argv, co_time_us_t now)
{
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
        return set_from_words(dev, argv[1], argv[2]);
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

device_cmd_result_t device_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now,
                                   const device_output_t *out)
{
    dev->now = now;
    dev->touched = true;
    if (argc < 1) {
        return DEVICE_CMD_UNKNOWN;
    }
    const device_output_t *outer = dev->replies; /* a device's command that runs another's keeps its caller's */
    if (out != NULL) {
        dev->replies = out;
    }
    const device_cmd_result_t r = run(dev, argc, argv, now);
    dev->replies = outer;
    return r;
}
