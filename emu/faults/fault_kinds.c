/* The kinds of protocol fault: see fault_kinds.h. */
#include "faults/fault_kinds.h"

#include <string.h>

/* By fault_kind_t. The texts are the help line of each of the page's forms; docs/emulator.md "Protocol faults" says
 * the same at length. A kind without its row here would have a NULL name: the tests of the served table (every kind
 * that `fault NODE` names, each taking its usage's arguments) find it. */
static const fault_kind_info_t kinds[FAULT_KIND_COUNT] = {
    [FAULT_SDO_IGNORE] = {"sdo-ignore", "[N | P% [SEED]]", "N 1..1000000, P 0..100 %",
                          "the next N SDO requests (1) or a share P % of them get no answer"},
    [FAULT_SDO_DELAY] = {"sdo-delay", "MS", "1..600000", "every SDO answer leaves MS ms late"},
    [FAULT_SDO_ABORT] = {"sdo-abort", "INDEX[:SUB] CODE", "hex object; CODE 1..0xFFFFFFFF, e.g. 0x08000020",
                         "requests for that object are answered with the abort CODE"},
    [FAULT_HB_STOP] = {"heartbeat-stop", "", "", "no heartbeat (nor node-guarding answer); boot-ups still go out"},
    [FAULT_HB_JITTER] = {"heartbeat-jitter", "MS", "1..60000", "each heartbeat leaves 0..MS ms late"},
    [FAULT_HB_STATE] = {"heartbeat-state", "BYTE", "0..0xFF; 0x05 Operational, 0x7F Pre-operational",
                        "heartbeats carry this state byte"},
    [FAULT_TPDO_FREEZE] = {"tpdo-freeze", "N", "a TPDO of the node, from 1", "TPDO N keeps the data of its first frame"},
    [FAULT_TPDO_DROP] = {"tpdo-drop", "N EVERY", "a TPDO of the node, from 1; EVERY 1..1000000",
                         "every EVERY-th frame of TPDO N is dropped"},
    [FAULT_TPDO_LENGTH] = {"tpdo-length", "N LEN", "a TPDO of the node, from 1; LEN 0..8",
                           "TPDO N goes out with LEN data bytes"},
    [FAULT_EMCY_BURST] = {"emcy-burst", "COUNT [CODE]", "COUNT 1..100; CODE default 0x1000",
                          "COUNT EMCY frames (CODE, default 0x1000) at once"},
    [FAULT_REBOOT] = {"reboot", "", "", "the node restarts at once, as after a brown-out"},
    [FAULT_BUS_OFF] = {"bus-off", "MS", "1..3600000", "for MS ms nothing goes out or comes in; then EMCY 0x8140"},
    [FAULT_LSS_SILENT] = {"lss-silent", "", "", "LSS requests are not answered"},
};

const fault_kind_info_t *fault_kind_info(fault_kind_t kind) { return &kinds[kind]; }

const char *fault_kind_name(fault_kind_t kind) { return kind < FAULT_KIND_COUNT ? kinds[kind].name : "?"; }

int fault_kind_of(const char *name)
{
    for (int k = 0; k < (int)FAULT_KIND_COUNT; k++) {
        if (strcmp(kinds[k].name, name) == 0) {
            return k;
        }
    }
    return -1;
}
