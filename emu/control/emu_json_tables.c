/* The control protocol's `tables` request (docs/control-protocol.md): the tables a client shows or makes its forms
 * from, served from the one place the program keeps each, so that a client needs no copy that could fall behind:
 * the protocol fault kinds (faults/fault_kinds.h) and the core's SDO abort texts (co_abort_entry). The web view
 * (web/) builds its fault forms and its trace's abort texts from this answer. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_json_request.h"

#include <stdio.h>

#include "co/co_abort.h"
#include "faults/fault_kinds.h"

static json_t *fault_kinds_json(void)
{
    json_t *faults = json_array();
    for (int k = 0; k < (int)FAULT_KIND_COUNT; k++) {
        const fault_kind_info_t *info = fault_kind_info((fault_kind_t)k);
        char usage[160]; /* the kind and its arguments, as `fault NODE` takes them after NODE */
        (void)snprintf(usage, sizeof usage, "%s%s%s", info->name, info->args[0] != '\0' ? " " : "", info->args);
        json_t *f = json_object();
        (void)json_object_set_new(f, "kind", json_string(info->name));
        (void)json_object_set_new(f, "usage", json_string(usage));
        (void)json_object_set_new(f, "limits", json_string(info->limits));
        (void)json_object_set_new(f, "text", json_string(info->text));
        (void)json_array_append_new(faults, f);
    }
    return faults;
}

static json_t *abort_codes_json(void)
{
    json_t *aborts = json_array();
    uint32_t code = 0U;
    const char *text;
    for (size_t i = 0U; (text = co_abort_entry(i, &code)) != NULL; i++) {
        json_t *a = json_object();
        (void)json_object_set_new(a, "code", json_integer((json_int_t)code));
        (void)json_object_set_new(a, "text", json_string(text));
        (void)json_array_append_new(aborts, a);
    }
    return aborts;
}

void cmd_tables(const request_t *q)
{
    static const char *const fields[] = {NULL};
    if (!only_fields(q, fields)) {
        return;
    }
    json_t *r = response(q->id, true);
    (void)json_object_set_new(r, "faults", fault_kinds_json());
    (void)json_object_set_new(r, "aborts", abort_codes_json());
    send_response(q->s, r);
}
