/*
 * Behaviour rules of a device read from its EDS (docs/eds.md "Rules"): a YAML file says how values move
 * (constant, ramp, sine, random walk, steps, counter, follow with a first-order lag), which limits raise an EMCY
 * and 0x1001 bits, and whether the CiA 402 drive profile runs (cia402.h). Parsed once per file (libyaml, with
 * the bounds of rules_yaml.h), resolved against the device's object dictionary; each node keeps its own state in
 * its model block.
 */
#ifndef EDS_CLASS_RULES_H
#define EDS_CLASS_RULES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "device.h"

typedef struct rules rules_t;

/**
 * Reads a rules file for a device of od (names: the EDS names, for messages). NULL after printing
 * "FILE:LINE:COLUMN: error: ..." lines to log (at most 20 and one that says more were found). *device receives the file's `device:` key (NULL when it has none; owned by
 * the rules).
 */
rules_t *rules_load(const char *path, const co_od_t *od, FILE *log, const char **device);
void rules_free(rules_t *rules);

/** Bytes of per-node state the rules need (in the model block). */
size_t rules_state_size(const rules_t *rules);

/** A power-on: the rules start again from their start values at now. */
void rules_power_on(const rules_t *rules, void *state, device_t *dev, co_time_us_t now);
/** Moves the values to now; returns the next time something changes (CO_NEVER: nothing will). */
co_time_us_t rules_step(const rules_t *rules, void *state, device_t *dev, co_time_us_t now);
/** The core's write hook: a write the drive profile must see (0x6040 controlword) or refuse. */
uint32_t rules_on_write(const rules_t *rules, void *state, device_t *dev, const co_od_entry_t *e, const uint8_t *data,
                        size_t len);

/** A number from an OD row of any numeric type (integers exactly up to 2^53). */
double rules_get(co_node_t *node, const co_od_entry_t *row);
/** Writes a number to a numeric row as the device would (rounded, held to the type's range). */
void rules_set(co_node_t *node, const co_od_entry_t *row, double value);

#endif /* EDS_CLASS_RULES_H */
