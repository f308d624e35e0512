/**
 * @file eds_info.c
 * @brief The sections about the device rather than its objects: [DeviceInfo], [DummyUsage], [DeviceComissioning],
 * the keys kept for the writer, and the object lists ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects]).
 */
#include "eds_builder.h"

#include <stdlib.h>
#include <string.h>

/* ---- [DeviceInfo], [DummyUsage], [DeviceComissioning], and the keys kept for the writer ----------------------- */

void eds_read_device_info(builder_t *b)
{
    eds_file_t *f = b->f;
    const ini_section_t *s = ini_find_named(b->ini, "DeviceInfo");
    if (s == NULL) {
        eds_warn(f, 0U, "no [DeviceInfo]; the identity comes from object 0x1018 where it has one");
    } else {
        f->device_info_line = s->line;
    }
    static const char *const required[] = {"VendorName", "VendorNumber", "ProductName", "ProductNumber",
                                           "RevisionNumber", "NrOfRXPDO", "NrOfTXPDO"};
    for (size_t i = 0; s != NULL && i < sizeof required / sizeof required[0]; i++) {
        if (ini_get(b->ini, s, required[i]) == NULL) {
            eds_warn(f, s->line, "[DeviceInfo] has no %s; %s", required[i],
                     strncmp(required[i], "Nr", 2) == 0 ? "counted from the PDO objects" :
                     (strstr(required[i], "Name") != NULL ? "left empty" : "taken from object 0x1018 (or 0)"));
        }
    }
    const char *v = text_of(b, s, "VendorName");
    f->vendor_name = v != NULL ? v : "";
    v = text_of(b, s, "ProductName");
    f->product_name = v != NULL ? v : "";
    /* UINT64_MAX: not given; filled from 0x1018 once the objects are read (identity_from_1018). */
    b->identity[0] = number_of(b, s, "VendorNumber", UINT32_MAX, UINT64_MAX);
    b->identity[1] = number_of(b, s, "ProductNumber", UINT32_MAX, UINT64_MAX);
    b->identity[2] = number_of(b, s, "RevisionNumber", UINT32_MAX, UINT64_MAX);
    f->nr_of_rxpdo = (uint16_t)number_of(b, s, "NrOfRXPDO", 512U, 0xFFFFU);
    f->nr_of_txpdo = (uint16_t)number_of(b, s, "NrOfTXPDO", 512U, 0xFFFFU);
    f->granularity = (uint8_t)number_of(b, s, "Granularity", 64U, 8U);
    f->lss_supported = number_of(b, s, "LSS_Supported", 1U, 0U) != 0U;
    for (unsigned i = 0; i < EDS_CIA305_RATES; i++) {
        char key[24];
        snprintf(key, sizeof key, "BaudRate_%u", (unsigned)eds_cia305_kbit[i]);
        if (eds_cia305_kbit[i] != 0U && number_of(b, s, key, 1U, 0U) != 0U) {
            f->baud_rates = (uint16_t)(f->baud_rates | (1U << i));
        }
    }
    const ini_section_t *d = ini_find_named(b->ini, "DummyUsage");
    for (unsigned t = 1U; t <= 7U; t++) {
        char key[16];
        snprintf(key, sizeof key, "Dummy%04X", t);
        if (number_of(b, d, key, 1U, 0U) != 0U) {
            f->dummy_usage = (uint8_t)(f->dummy_usage | (1U << t));
        }
    }
    const ini_section_t *c = ini_find_named(b->ini, "DeviceComissioning");
    if (c == NULL) {
        c = ini_find_named(b->ini, "DeviceCommissioning");
        if (c != NULL) {
            eds_warn(f, c->line, "[DeviceCommissioning]: CiA 306 spells it [DeviceComissioning]; read as such");
        }
    }
    if (c != NULL) {
        f->is_dcf = true;
        f->comm.present = true;
        const ini_key_t *node_id = ini_get(b->ini, c, "NodeID");
        const char *id_text = node_id != NULL ? ini_number_text(f, node_id) : "";
        f->comm.node_id_given = *id_text != '\0';
        uint64_t id = 0U;
        if (f->comm.node_id_given && (!eds_parse_unsigned(id_text, UINT64_MAX, &id) || id < 1U || id > 127U)) {
            /* 0 and 255 too (255: how some tools write "not configured"): the node-ID must come from elsewhere */
            eds_warn(f, node_id->line, "[DeviceComissioning] NodeID=%s is not a node-ID (1..127); ignored", id_text);
            id = 0U;
        }
        f->comm.node_id = (uint8_t)id;
        f->comm.baudrate_kbit = (uint16_t)number_of(b, c, "Baudrate", 1000U, 0U);
        f->comm.node_name = text_of(b, c, "NodeName");
        f->comm.net_number = (uint32_t)number_of(b, c, "NetNumber", UINT32_MAX, 0U);
        f->comm.network_name = text_of(b, c, "NetworkName");
        f->comm.canopen_manager = number_of(b, c, "CANopenManager", 1U, 0U) != 0U;
        f->comm.lss_serial_number = (uint32_t)number_of(b, c, "LSS_SerialNumber", UINT32_MAX, 0U);
    }
    /* [FileInfo], [DeviceInfo] and [Comments] as written, for the writer (each section looked up once: a look-up
     * per key made a file of many sections take quadratic time). */
    static const char *const kept[] = {"FileInfo", "DeviceInfo", "Comments"};
    const ini_section_t *kept_section[3];
    size_t n = 0U;
    for (size_t j = 0; j < 3U; j++) {
        kept_section[j] = ini_find_named(b->ini, kept[j]);
        n += kept_section[j] != NULL ? kept_section[j]->count : 0U;
    }
    f->info = eds_alloc(f, (n + 1U) * sizeof *f->info);
    for (uint32_t i = 0; f->info != NULL && i < b->ini->n_keys; i++) {
        const ini_key_t *k = &b->ini->file_order[i];
        const ini_section_t *sec = &b->ini->sections[k->section];
        for (size_t j = 0; j < 3U; j++) {
            if (sec == kept_section[j]) {
                f->info[f->n_info].section = kept[j];
                f->info[f->n_info].key = k->key;
                f->info[f->n_info].value = k->value;
                f->n_info++;
            }
        }
    }
}

/* ---- Object lists ------------------------------------------------------------------------------------------------- */

static int u16_cmp(const void *a, const void *b)
{
    return (int)*(const uint16_t *)a - (int)*(const uint16_t *)b;
}

typedef struct list_item {
    uint32_t pos;
    const ini_key_t *key;
} list_item_t;

static int item_cmp(const void *a, const void *b)
{
    uint32_t x = ((const list_item_t *)a)->pos, y = ((const list_item_t *)b)->pos;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* The indices the object lists name, sorted and unique; sections no list names are added (with a warning). */
uint16_t *eds_object_indices(builder_t *b, uint32_t *count)
{
    eds_file_t *f = b->f;
    static const char *const lists[] = {"MandatoryObjects", "OptionalObjects", "ManufacturerObjects"};
    uint8_t *listed = eds_alloc(f, 65536U);
    uint16_t *out = eds_alloc(f, 65536U * sizeof(uint16_t));
    b->listed_line = eds_alloc(f, 65536U * sizeof(uint32_t));
    uint32_t n = 0U;
    if (listed == NULL || out == NULL || b->listed_line == NULL) {
        b->oom = true;
        return NULL;
    }
    bool any_list = false;
    for (size_t l = 0; l < 3U; l++) {
        const ini_section_t *s = ini_find_named(b->ini, lists[l]);
        if (s == NULL) {
            continue;
        }
        any_list = true;
        uint64_t supported = number_of(b, s, "SupportedObjects", 65535U, 0U);
        /* The keys are sorted as text ("10" before "2"): take them in the order of their numbers. */
        list_item_t *items = eds_alloc(f, ((size_t)s->count + 1U) * sizeof *items);
        if (items == NULL) {
            b->oom = true;
            return NULL;
        }
        uint32_t found = 0U;
        for (uint32_t i = s->first; i < s->first + s->count; i++) {
            const ini_key_t *k = &b->ini->keys[i];
            uint64_t pos;
            if (!eds_parse_unsigned(k->key, 65535U, &pos)) {
                if (k != ini_get(b->ini, s, "SupportedObjects")) {
                    eds_warn(f, k->line, "[%s] %s: not a position number; ignored", lists[l], k->key);
                }
                continue;
            }
            items[found].pos = (uint32_t)pos;
            items[found].key = k;
            found++;
        }
        qsort(items, found, sizeof *items, item_cmp);
        long previous = -1;
        bool warned_order = false;
        for (uint32_t i = 0; i < found; i++) {
            const ini_key_t *k = items[i].key;
            uint64_t index;
            if (items[i].pos == 0U || items[i].pos > supported) {
                eds_warn(f, k->line, "[%s] %s: position outside 1..SupportedObjects (%llu); the object is read anyway",
                         lists[l], k->key, (unsigned long long)supported);
            }
            const char *text = ini_number_text(f, k);
            if (!eds_parse_unsigned(text, 0xFFFFU, &index)) {
                eds_warn(f, k->line, "[%s] %s: '%s' is not an object index; ignored", lists[l], k->key, text);
                continue;
            }
            if (listed[index] != 0U) {
                eds_warn(f, k->line, "[%s] %s: object 0x%04llX is listed twice; read once", lists[l], k->key,
                         (unsigned long long)index);
                continue;
            }
            if ((long)index < previous && !warned_order) {
                eds_warn(f, k->line, "[%s] %s: object 0x%04llX out of order (after 0x%04lX); the objects are sorted",
                         lists[l], k->key, (unsigned long long)index, previous);
                warned_order = true;
            }
            previous = (long)index;
            listed[index] = 1U;
            b->listed_line[index] = k->line;
            out[n++] = (uint16_t)index;
        }
        if (found != supported) {
            eds_warn(f, s->line, "[%s] SupportedObjects=%llu but %lu entries are listed; the listed ones are read",
                     lists[l], (unsigned long long)supported, (unsigned long)found);
        }
    }
    if (!any_list) {
        eds_warn(f, 0U, "no object lists ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects]); every "
                        "object section is read");
    }
    for (uint32_t i = 0; i < b->ini->n_sections; i++) {
        const ini_section_t *s = &b->ini->sections[i];
        if (s->kind == INI_OBJECT && listed[s->index] == 0U) {
            if (any_list) {
                eds_warn(f, s->line, "[%s] is in no object list; read as an object of the device", s->name);
            }
            listed[s->index] = 1U;
            out[n++] = s->index;
        }
    }
    qsort(out, n, sizeof *out, u16_cmp);
    *count = n;
    return out;
}
