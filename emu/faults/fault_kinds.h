/*
 * The kinds of protocol fault (emu_faults.h, docs/emulator.md "Protocol faults"): each one's name, its argument
 * words, their limits and what it does, in one table. The command language's usages and refusals are made from it,
 * and the control protocol serves it (`tables`, docs/control-protocol.md) to the web view, which makes its fault
 * forms from that: a kind added here is in all three.
 */
#ifndef EMU_FAULT_KINDS_H
#define EMU_FAULT_KINDS_H

typedef enum fault_kind {
    FAULT_SDO_IGNORE = 0,
    FAULT_SDO_DELAY,
    FAULT_SDO_ABORT,
    FAULT_HB_STOP,
    FAULT_HB_JITTER,
    FAULT_HB_STATE,
    FAULT_TPDO_FREEZE,
    FAULT_TPDO_DROP,
    FAULT_TPDO_LENGTH,
    FAULT_EMCY_BURST,
    FAULT_REBOOT,
    FAULT_BUS_OFF,
    FAULT_LSS_SILENT,
    FAULT_KIND_COUNT
} fault_kind_t;

/** What the table says of one kind. Strings, never NULL; "" where there is nothing to say. */
typedef struct fault_kind_info {
    const char *name;   /**< as the commands and the events give it: "sdo-delay" */
    const char *args;   /**< the argument words after the kind, as a usage writes them: "MS", "[N|P% [SEED]]" */
    const char *limits; /**< what the arguments may be, for a refusal: "1..600000" */
    const char *text;   /**< one line: what the fault does */
} fault_kind_info_t;

/** The table's row of a kind (kind < FAULT_KIND_COUNT). */
const fault_kind_info_t *fault_kind_info(fault_kind_t kind);

/** The name of a fault kind ("sdo-ignore"); "?" for a value that is no kind. */
const char *fault_kind_name(fault_kind_t kind);

/** The kind of a name, or -1 when it names none. */
int fault_kind_of(const char *name);

#endif /* EMU_FAULT_KINDS_H */
