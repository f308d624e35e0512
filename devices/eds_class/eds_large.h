/*
 * Large objects of a device made from an EDS/DCF (issue 35, rule 5): its DOMAINs (a firmware image 0x1F50, a log, a
 * parameter blob) and the strings whose file value is longer than the core's SDO buffer are rows of size 0 whose
 * values live here, on the heap, per node, up to EDS_LARGE_MAX bytes each; the core moves them by segmented and block
 * SDO transfer through co_hooks_t.large_read/large_write (CO_CONFIG_LARGE_OBJECTS). Host-only code: it allocates.
 * A power-on gives each its file value again; an NMT reset does not touch them. docs/eds.md.
 */
#ifndef EDS_LARGE_H
#define EDS_LARGE_H

#include <stdbool.h>
#include <stdint.h>

#include "device.h"
#include "eds.h"

/** Bytes a large object takes at most: a longer download is refused (0x06070012, or 0x05040005 without memory). */
#define EDS_LARGE_MAX (16UL * 1024UL * 1024UL)

/** True when the entry of a file becomes a large object: a DOMAIN, or a string whose value is longer than
 *  CO_SDO_BUF_SIZE, that no PDO may map. */
bool eds_large_entry(const eds_entry_t *e);

typedef struct eds_large eds_large_t;

/**
 * The large objects of a class: the rows of od (built from f, in the order of f's entries) for which
 * eds_large_entry() is true. NULL when it has none, or without memory (*failed then true).
 */
eds_large_t *eds_large_create(const co_od_t *od, const eds_file_t *f, bool *failed);

/** A node of the class powers on: its large objects take their file values, and its hooks the two calls. */
void eds_large_power_on(eds_large_t *l, device_t *dev);

/** Frees the class's large objects and every node's values of them. */
void eds_large_free(eds_large_t *l);

#endif /* EDS_LARGE_H */
