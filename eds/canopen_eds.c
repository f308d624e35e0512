/**
 * @file canopen_eds.c
 * @brief canopen-eds: checks, converts and dumps EDS/DCF files with the project's one reader (eds/).
 *
 *   canopen-eds check [--strict] FILE...          diagnostics on stderr, one summary line per file on stdout
 *   canopen-eds json [--strict] FILE              the repaired model as JSON (what tools/odgen.py generates from)
 *   canopen-eds convert [--dcf] [--node-id N] FILE OUT   writes it back as an EDS or DCF ('-': stdout)
 *
 * Exit status: 0 usable, 2 a file that cannot be emulated (or, with --strict, any warning), 1 usage.
 */
#include "eds.h"

#include <stdlib.h>
#include <string.h>

static void usage(FILE *out)
{
    fputs("usage: canopen-eds check [--strict] FILE...\n"
          "       canopen-eds json [--strict] FILE\n"
          "       canopen-eds convert [--dcf] [--node-id N] FILE OUT\n"
          "Reads CiA 306 EDS/DCF files as canopen-emu does; see docs/eds.md.\n"
          "  --strict    warnings count as errors (exit status 2)\n"
          "  --dcf       write a DCF (ParameterValue and [DeviceComissioning])\n"
          "  --node-id N the DCF's NodeID (1..127)\n",
          out);
}

static void json_string(FILE *out, const char *s, size_t len)
{
    fputc('"', out);
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '"' || c == '\\') {
            fprintf(out, "\\%c", c);
        } else if (c < 0x20U || c == 0x7FU) {
            fprintf(out, "\\u%04x", c);
        } else {
            fputc(c, out);
        }
    }
    fputc('"', out);
}

static void json_text(FILE *out, const char *s)
{
    if (s == NULL) {
        fputs("null", out);
    } else {
        json_string(out, s, strlen(s));
    }
}

static void json_value(FILE *out, uint8_t type, const eds_value_t *v)
{
    char text[64];
    switch (v->kind) {
    case EDS_V_INT:
        fprintf(out, "%lld", (long long)v->i);
        break;
    case EDS_V_UINT:
        fprintf(out, "%llu", (unsigned long long)v->u);
        break;
    case EDS_V_REAL:
        eds_format_value(text, sizeof text, type, v);
        fputs(text, out);
        break;
    case EDS_V_BYTES:
        if (type == 0x09U) {
            json_string(out, (const char *)v->bytes, v->len);
        } else {
            fputc('"', out);
            for (size_t i = 0; i < v->len; i++) {
                fprintf(out, "%02X", v->bytes[i]);
            }
            fputc('"', out);
        }
        break;
    default:
        fputs("null", out);
        break;
    }
}

static void json_dump(FILE *out, const eds_file_t *f)
{
    fputs("{\"file\": ", out);
    json_text(out, f->path);
    fprintf(out, ", \"warnings\": %lu, \"errors\": %lu, \"diagnostics\": [", (unsigned long)f->warnings,
            (unsigned long)f->errors);
    for (uint32_t i = 0; i < f->n_diagnostics; i++) {
        fputs(i ? ", " : "", out);
        json_text(out, f->diagnostics[i]);
    }
    fputs("],\n \"device\": {\"vendor_name\": ", out);
    json_text(out, f->vendor_name);
    fputs(", \"product_name\": ", out);
    json_text(out, f->product_name);
    fprintf(out, ", \"vendor_number\": %lu, \"product_number\": %lu, \"revision_number\": %lu, \"nr_of_rxpdo\": %u, "
                 "\"nr_of_txpdo\": %u, \"granularity\": %u, \"lss_supported\": %s, \"baud_rates\": %u, "
                 "\"dummy_usage\": %u, \"is_dcf\": %s},\n",
            (unsigned long)f->vendor_number, (unsigned long)f->product_number, (unsigned long)f->revision_number,
            (unsigned)f->nr_of_rxpdo, (unsigned)f->nr_of_txpdo, (unsigned)f->granularity,
            f->lss_supported ? "true" : "false", (unsigned)f->baud_rates, (unsigned)f->dummy_usage,
            f->is_dcf ? "true" : "false");
    if (f->comm.present) {
        fprintf(out, " \"commissioning\": {\"node_id\": %u, \"baudrate_kbit\": %u, \"node_name\": ",
                (unsigned)f->comm.node_id, (unsigned)f->comm.baudrate_kbit);
        json_text(out, f->comm.node_name);
        fprintf(out, ", \"lss_serial_number\": %lu},\n", (unsigned long)f->comm.lss_serial_number);
    } else {
        fputs(" \"commissioning\": null,\n", out);
    }
    fputs(" \"objects\": [", out);
    for (uint32_t i = 0; i < f->n_objects; i++) {
        const eds_object_t *o = &f->objects[i];
        fprintf(out, "%s\n  {\"index\": %u, \"object_type\": %u, \"name\": ", i ? "," : "", (unsigned)o->index,
                (unsigned)o->object_type);
        json_text(out, o->name);
        fprintf(out, ", \"count\": %u, \"compact\": %u, \"line\": %lu, \"links\": [", (unsigned)o->count,
                (unsigned)o->compact, (unsigned long)o->line);
        for (unsigned k = 0; k < o->n_links; k++) {
            fprintf(out, "%s%u", k ? ", " : "", (unsigned)o->links[k]);
        }
        fputs("]}", out);
    }
    fputs("],\n \"entries\": [", out);
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        fprintf(out, "%s\n  {\"index\": %u, \"sub\": %u, \"name\": ", i ? "," : "", (unsigned)e->index,
                (unsigned)e->sub);
        json_text(out, e->name);
        fprintf(out, ", \"type\": %u, \"access\": \"%s\", \"pdo_mapping\": %s, \"line\": %lu, \"default\": ",
                (unsigned)e->type, eds_access_name(e->access), e->pdo_mapping ? "true" : "false",
                (unsigned long)e->line);
        json_value(out, e->type, &e->def);
        fprintf(out, ", \"nodeid\": %s, \"low\": ", e->def.nodeid ? "true" : "false");
        json_value(out, e->type, &e->low);
        fputs(", \"high\": ", out);
        json_value(out, e->type, &e->high);
        fputs(", \"param\": ", out);
        json_value(out, e->type, &e->param);
        fprintf(out, ", \"param_nodeid\": %s, \"denotation\": ", e->param.nodeid ? "true" : "false");
        json_text(out, e->denotation);
        fputc('}', out);
    }
    fputs("]}\n", out);
}

static int report(const eds_file_t *f, bool strict)
{
    for (uint32_t i = 0; i < f->n_diagnostics; i++) {
        fprintf(stderr, "%s\n", f->diagnostics[i]);
    }
    return f->errors > 0U || (strict && f->warnings > 0U) ? 2 : 0;
}

static int cmd_check(int argc, char **argv, bool strict)
{
    int status = 0;
    for (int i = 0; i < argc; i++) {
        eds_file_t *f = eds_read_file(argv[i]);
        if (f == NULL) {
            fprintf(stderr, "canopen-eds: out of memory\n");
            return 2;
        }
        int rc = report(f, strict);
        printf("%s: %s (%lu objects, %lu entries, %lu warnings, %lu errors)\n", argv[i],
               rc == 0 ? "OK" : "cannot be used", (unsigned long)f->n_objects, (unsigned long)f->n_entries,
               (unsigned long)f->warnings, (unsigned long)f->errors);
        if (rc > status) {
            status = rc;
        }
        eds_free(f);
    }
    return status;
}

int main(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    const char *cmd = argv[1];
    bool strict = false, dcf = false;
    long node_id = 0;
    int i = 2;
    for (; i < argc && strncmp(argv[i], "--", 2) == 0; i++) {
        if (strcmp(argv[i], "--strict") == 0) {
            strict = true;
        } else if (strcmp(argv[i], "--dcf") == 0) {
            dcf = true;
        } else if (strcmp(argv[i], "--node-id") == 0 && i + 1 < argc) {
            char *end;
            node_id = strtol(argv[++i], &end, 0);
            if (*end != '\0' || node_id < 1 || node_id > 127) {
                fprintf(stderr, "canopen-eds: --node-id %s: not a node-ID 1..127\n", argv[i]);
                return 1;
            }
        } else {
            fprintf(stderr, "canopen-eds: unknown option %s\n", argv[i]);
            usage(stderr);
            return 1;
        }
    }
    int rest = argc - i;
    if (strcmp(cmd, "check") == 0 && rest >= 1) {
        return cmd_check(rest, argv + i, strict);
    }
    if ((strcmp(cmd, "json") == 0 && rest == 1) || (strcmp(cmd, "convert") == 0 && rest == 2)) {
        eds_file_t *f = eds_read_file(argv[i]);
        if (f == NULL) {
            fprintf(stderr, "canopen-eds: out of memory\n");
            return 2;
        }
        int rc = report(f, strict);
        if (rc == 0 && cmd[0] == 'j') {
            json_dump(stdout, f);
        } else if (rc == 0) {
            const char *path = argv[i + 1];
            FILE *out = strcmp(path, "-") == 0 ? stdout : fopen(path, "w");
            if (out == NULL) {
                perror(path);
                rc = 2;
            } else {
                const char *base = strrchr(path, '/');
                eds_write_options_t o;
                memset(&o, 0, sizeof o);
                o.dcf = dcf;
                o.node_id = (uint8_t)node_id;
                o.file_name = strcmp(path, "-") == 0 ? NULL : (base != NULL ? base + 1 : path);
                char why[512] = "";
                o.error = why;
                o.error_cap = sizeof why;
                const int written = eds_write(out, f, &o);
                const bool closed = out == stdout || fclose(out) == 0;
                if (written != 0 || !closed) {
                    if (why[0] != '\0') {
                        fprintf(stderr, "canopen-eds: %s: %s\n", path, why);
                    } else {
                        perror(path);
                    }
                    if (out != stdout) {
                        (void)remove(path); /* no partial file */
                    }
                    rc = 2;
                }
            }
        }
        eds_free(f);
        return rc;
    }
    usage(stderr);
    return 1;
}
