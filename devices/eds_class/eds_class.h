/*
 * A device class built at run time from an EDS or DCF (the project's reader, eds/): the object dictionary the
 * core serves (rows, limits, defaults, names) in memory allocated here, once per file, shared by every node of it.
 * How a file becomes a device (capacities, storage, a DCF's values and commissioning): docs/eds.md.
 */
#ifndef EDS_CLASS_H
#define EDS_CLASS_H

#include <stdbool.h>
#include <stdio.h>

#include "device.h"

/** True when a DEVICE argument names a file (it ends in .eds or .dcf, any case). */
bool eds_class_is_file(const char *name);

/**
 * The class of a file, read once (later calls with the same path return the same class). The reader's warnings
 * go to log (none when quiet); on errors they go there too and NULL is returned.
 */
const device_class_t *eds_class_load(const char *path, FILE *log, bool quiet);

/**
 * Says, for a node of the class at node_id, what its file holds that such a node takes but a master could not
 * write (eds_node_id_warnings: a restricted COB-ID at that node-ID), to log unless quiet.
 */
void eds_class_warn_node_id(const device_class_t *cls, uint8_t node_id, FILE *log, bool quiet);

/**
 * Writes a node of a class read from a file as a DCF (export-dcf): the file's objects, each with its current value
 * as ParameterValue, [DeviceComissioning] with the node's node-ID. The file appears whole or not at all (written
 * beside, then renamed). false with the reason in why (also for a built-in device: it has no file model here).
 */
bool eds_class_export(device_t *dev, const char *path, char *why, size_t cap);

/**
 * Attaches a rules file (--rules, docs/eds.md "Rules") to the class it names (its `device:` key, the file name of an
 * EDS/DCF on the command line) or, without one, to the only such class. false after printing why.
 */
bool eds_class_attach_rules(const char *path, FILE *log);

/** Frees every class loaded (at exit, after the nodes are gone). */
void eds_class_free_all(void);

#endif /* EDS_CLASS_H */
