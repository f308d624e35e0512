/*
 * The YAML side of a rules file (rules.c, docs/eds.md "Rules"): the file read event by event (libyaml's parser,
 * not its loader) into a libyaml document, refusing as the events come, before anything is built from them, what a
 * rules file never needs and what would let a small file cost much time or memory: aliases and anchors (an alias
 * repeats a whole subtree: a 1.65 MB file once became gigabytes of rules), nesting deeper than RULES_YAML_MAX_DEPTH
 * (read to its end, 400 kB of nesting took minutes: time quadratic in the depth), more than RULES_YAML_MAX_NODES
 * values, a file larger than RULES_YAML_MAX_BYTES, a duplicate key in a mapping (which value would count?), a key
 * that is a list or a mapping, a value with a NUL character, and a second document in the file.
 */
#ifndef EDS_CLASS_RULES_YAML_H
#define EDS_CLASS_RULES_YAML_H

#include <stdbool.h>
#include <stdio.h>
#include <yaml.h>

/* A rules file with every behaviour is a few kB; these leave room for hand-written files far beyond need. */
#define RULES_YAML_MAX_BYTES (1024U * 1024U)
/* Mappings and lists inside each other: a rules file needs 5 (file, objects, rule, steps, one step). */
#define RULES_YAML_MAX_DEPTH 16U
/* Scalars, lists and mappings together. */
#define RULES_YAML_MAX_NODES 65536U

/**
 * Reads the YAML document of the file at path into *doc: true, and the caller deletes it with yaml_document_delete
 * (an empty file gives a document without a root node). false after one line "FILE:LINE:COLUMN: error: ..." (or
 * "FILE: error: ..." when the file as a whole is wrong) to log; *doc is then empty and needs no deleting.
 */
bool rules_yaml_read(const char *path, FILE *log, yaml_document_t *doc);

#endif /* EDS_CLASS_RULES_YAML_H */
