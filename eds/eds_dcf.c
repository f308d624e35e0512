/**
 * @file eds_dcf.c
 * @brief A DCF's values at a node-ID other than the file's: a ParameterValue that is its node-ID-relative
 * DefaultValue worked out at the file's NodeID follows the node-ID the device runs at.
 *
 * A configuration tool writes a DCF for one node and resolves $NODEID there: DefaultValue=$NODEID+0x80 with
 * ParameterValue=0xA0 at NodeID=0x20. Run at node-ID 20 (FILE.dcf:20), such a device answered 0x1014 = 0xA0, node
 * 0x20's EMCY COB-ID. A value equal to the default at the file's NodeID is the default as configured there, so it
 * becomes node-ID-relative again (bits 29..31 of a COB-ID may differ: a PDO disabled in the DCF stays disabled); any
 * other value is the one configured, and is kept, with a warning where it names a COB-ID of another node.
 */
#include "eds_internal.h"

#include <inttypes.h>

/* Bits 29..31 of a COB-ID are flags (CiA 301: valid, RTR, frame); bits 0..28 the CAN-ID. */
#define COB_ID_FLAGS 0xE0000000U
/* The 11-bit CAN-ID in which CiA 301's predefined connection set adds the node-ID. */
#define CAN_ID_11 0x7FFU

/* "[1014]" for a VAR, "[1800sub1]" for a sub-index: the section the value comes from. */
static void section_name(const eds_file_t *f, const eds_entry_t *e, char *buf, size_t cap)
{
    const eds_object_t *o = eds_find_object(f, e->index);
    const bool var = o != NULL && (o->object_type == 0x7U || o->object_type == 0x2U || o->object_type == 0x5U);
    if (var) {
        snprintf(buf, cap, "[%04X]", (unsigned)e->index);
    } else {
        snprintf(buf, cap, "[%04Xsub%X]", (unsigned)e->index, (unsigned)e->sub);
    }
}

bool eds_value_follows_node_id(const eds_entry_t *e, const eds_value_t *value, uint8_t node_id, eds_value_t *relative)
{
    if (node_id == 0U || node_id > 127U || !e->def.nodeid || value->nodeid || value->kind != e->def.kind) {
        return false;
    }
    eds_value_t r = *value;
    r.nodeid = true;
    if (value->kind == EDS_V_UINT) {
        if (value->u < node_id) {
            return false;
        }
        r.u = value->u - node_id;
        const bool cob_id = e->type == 0x07U;
        if (r.u != e->def.u && !(cob_id && ((r.u ^ e->def.u) & ~(uint64_t)COB_ID_FLAGS) == 0U)) {
            return false;
        }
    } else if (value->kind == EDS_V_INT) {
        if (value->i < INT64_MIN + node_id || value->i - node_id != e->def.i) {
            return false;
        }
        r.i = value->i - node_id;
    } else {
        return false;
    }
    if (!eds_value_fits(e->type, &r)) {
        return false; /* a value near the type's top would overflow at node-ID 127: it stays as it is */
    }
    *relative = r;
    return true;
}

/* A COB-ID kept as written that is the default's at some node-ID other than the file's (1..127): warned. */
static void warn_other_node(eds_file_t *f, const eds_entry_t *e, uint8_t node_id)
{
    const long other = (long)(e->param.u & CAN_ID_11) - (long)(e->def.u & CAN_ID_11);
    if (e->type != 0x07U || other < 1 || other > 127 || other == (long)node_id) {
        return;
    }
    char name[24];
    section_name(f, e, name, sizeof name);
    if (node_id != 0U) {
        eds_warn(f, e->line, "%s ParameterValue 0x%" PRIX64 " is the COB-ID of node-ID %ld ($NODEID+0x%" PRIX64
                 "), not of the file's NodeID %u; kept as 0x%" PRIX64 " at any node-ID", name, e->param.u, other,
                 e->def.u, (unsigned)node_id, e->param.u);
    } else {
        eds_warn(f, e->line, "%s ParameterValue 0x%" PRIX64 " is the COB-ID of node-ID %ld ($NODEID+0x%" PRIX64
                 "), and the file has no NodeID to tell whether that is its own; kept as 0x%" PRIX64 " at any node-ID",
                 name, e->param.u, other, e->def.u, e->param.u);
    }
}

void eds_relative_params(eds_file_t *f)
{
    const uint8_t node_id = f->comm.node_id; /* 0: none, or not 1..127 */
    for (uint32_t i = 0; i < f->n_entries; i++) {
        eds_entry_t *e = &f->entries[i];
        if (!e->def.nodeid || e->param.nodeid || e->param.kind != e->def.kind) {
            continue;
        }
        eds_value_t relative;
        if (eds_value_follows_node_id(e, &e->param, node_id, &relative)) {
            e->param = relative;
        } else if (e->param.kind == EDS_V_UINT) {
            warn_other_node(f, e, node_id);
        }
    }
}

/* CiA 301 §7.3.5: the CAN-IDs no configurable COB-ID may use, as the core refuses them from a master
 * (co_cob_id_restricted in src/co_node.c). */
static bool can_id_restricted(uint64_t id)
{
    return id <= 0x07FU || (id >= 0x101U && id <= 0x180U) || (id >= 0x581U && id <= 0x5FFU) ||
           (id >= 0x601U && id <= 0x67FU) || (id >= 0x6E0U && id <= 0x6FFU) || id >= 0x701U;
}

/* The COB-IDs the core checks so when a master writes them (the default SDO server 0x1200 has CiA 301's own). */
static bool configurable_cob_id(const eds_entry_t *e)
{
    if (e->type != 0x07U) {
        return false;
    }
    if (e->index == 0x1005U || e->index == 0x1014U) {
        return e->sub == 0U;
    }
    if (e->index >= 0x1201U && e->index <= 0x127FU) {
        return e->sub == 1U || e->sub == 2U;
    }
    return ((e->index >= 0x1400U && e->index <= 0x15FFU) || (e->index >= 0x1800U && e->index <= 0x19FFU)) &&
           e->sub == 1U;
}

unsigned eds_node_id_warnings(const eds_file_t *f, uint8_t node_id, FILE *out)
{
    unsigned count = 0U;
    for (uint32_t i = 0; i < f->n_entries; i++) {
        const eds_entry_t *e = &f->entries[i];
        const eds_value_t *v = e->param.kind != EDS_V_NONE ? &e->param : &e->def;
        if (!configurable_cob_id(e) || v->kind != EDS_V_UINT || !v->nodeid) {
            continue;
        }
        const uint64_t cob_id = v->u + node_id;
        if ((cob_id & 0x80000000U) != 0U || !can_id_restricted(cob_id & CAN_ID_11)) {
            continue;
        }
        char name[24];
        section_name(f, e, name, sizeof name);
        fprintf(out, "%s:%lu: warning: %s $NODEID+0x%" PRIX64 " is 0x%" PRIX64 " at node-ID %u, a restricted CAN-ID "
                "(CiA 301): the node uses it as the file says, a master's write of it is refused (0x06090030)\n",
                f->path, (unsigned long)e->line, name, v->u, cob_id, (unsigned)node_id);
        count++;
    }
    return count;
}
