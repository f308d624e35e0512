/*
 * Multiplexed PDOs (CiA 301 MPDO), compiled in with CO_CONFIG_MPDO. An MPDO carries one object per frame, always
 * 8 bytes: byte 0 address (bit 7 clear: source address mode, the producer's node-ID; set: destination address mode,
 * the consumer's node-ID or 0 for all), bytes 1-2 index, byte 3 sub-index, bytes 4-7 the value (zero-padded).
 * - SAM producer: a TPDO whose mapping sub 0 is 0xFE sends, at each of its events (event timer, co_tpdo_trigger,
 *   entering Operational), the next object of the object scanner list 0x1FA0..0x1FCF in turn.
 * - DAM consumer: an RPDO with 0xFF writes the object the frame names when it is addressed to this node or to all
 *   (co_pdo.c raises EMCY 0x8230 when it cannot, with the RPDO's other errors).
 * - SAM consumer: an RPDO with 0xFE writes the local object the object dispatching list 0x1FD0..0x1FFF gives for the
 *   producer's node-ID, index and sub-index; frames of objects not in the list are ignored.
 * co_pdo.c configures the PDOs and routes their events and frames here.
 */
#include "priv/co_priv.h"

#if CO_CONFIG_MPDO

#define SCANNER_FIRST 0x1FA0U
#define SCANNER_LAST 0x1FCFU
#define DISPATCH_FIRST 0x1FD0U
#define DISPATCH_LAST 0x1FFFU

/* An object an MPDO can carry: mapped into PDOs in that direction, with a value of at most 4 bytes. */
static const co_od_entry_t *mpdo_object(const co_node_t *node, uint16_t index, uint8_t sub, uint16_t pdo_flag,
                                        co_od_entry_t *one)
{
    const co_od_entry_t *e = co_od_find(node->od, index, sub, one);
    return (e != NULL && (e->flags & pdo_flag) != 0U && e->size <= 4U) ? e : NULL;
}

/* Sub-indices an entry covers: sub .. sub + block - 1 (block size 0 counts as 1), not past 0xFF. */
static uint32_t block_length(uint32_t block, uint8_t first)
{
    const uint32_t n = block == 0U ? 1U : block;
    return n > 0x100U - first ? 0x100U - first : n;
}

bool co_mpdo_sam_next(co_node_t *node, co_tpdo_t *p, uint8_t frame[8])
{
    /* One walk over the scanner list: the first object that can go out at or after scan_next, else the first one
     * before it (the list wraps). Ordinals count every sub-index the entries name. */
    uint32_t ordinal = 0U;
    uint32_t first_ordinal = 0U;
    const co_od_entry_t *first = NULL; /* the first object that can go out, for the wrap */
    const co_od_entry_t *found = NULL;
    co_od_entry_t first_one;
    co_od_entry_t one;
    for (uint16_t list = SCANNER_FIRST; list <= SCANNER_LAST && found == NULL; list++) {
        const uint32_t entries = co_od_u32_or(node, list, 0U, 0U);
        for (uint32_t k = 1U; k <= entries && k <= 0xFEU && found == NULL; k++) {
            const uint32_t v = co_od_u32_or(node, list, (uint8_t)k, 0U);
            const uint16_t index = (uint16_t)(v >> 8);
            const uint8_t first_sub = (uint8_t)v;
            const uint32_t n = v == 0U ? 0U : block_length(v >> 24, first_sub);
            for (uint32_t i = 0U; i < n; i++, ordinal++) {
                const co_od_entry_t *e = mpdo_object(node, index, (uint8_t)(first_sub + i), CO_OD_TPDO, &one);
                if (e == NULL || (e->flags & CO_OD_READ) == 0U) {
                    continue;
                }
                if (first == NULL) {
                    first_one = *e;
                    first = &first_one;
                    first_ordinal = ordinal;
                }
                if (ordinal >= p->scan_next) {
                    found = e;
                    break;
                }
            }
        }
    }
    if (found == NULL) {
        if (first == NULL) {
            return false;
        }
        found = first;
        ordinal = first_ordinal;
    }
    p->scan_next = (uint16_t)(ordinal + 1U);
    memset(frame, 0, 8U);
    frame[0] = node->node_id;
    co_put_u16(&frame[1], found->index);
    frame[3] = found->sub;
    (void)co_od_sample(node, found, &frame[4], 4U);
    return true;
}

/* The local object of a SAM-MPDO from the dispatching list: entries (UNSIGNED64) are block size (bits 56-63),
 * local index (40-55), local sub-index (32-39), producer's index (16-31), sub-index (8-15), node-ID (0-7). */
static bool dispatch(co_node_t *node, uint8_t producer, uint16_t *index, uint8_t *sub)
{
    for (uint16_t list = DISPATCH_FIRST; list <= DISPATCH_LAST; list++) {
        const uint32_t entries = co_od_u32_or(node, list, 0U, 0U);
        for (uint32_t k = 1U; k <= entries && k <= 0xFEU; k++) {
            co_od_entry_t one;
            const co_od_entry_t *e = co_od_find(node->od, list, (uint8_t)k, &one);
            if (e == NULL || e->size != 8U) {
                continue;
            }
            uint64_t v;
            memcpy(&v, co_od_ptr(node, e), 8U);
            const uint8_t first = (uint8_t)(v >> 8);
            if ((uint8_t)v != producer || (uint16_t)(v >> 16) != *index || *sub < first ||
                (uint32_t)(*sub - first) >= block_length((uint32_t)(v >> 56), first)) {
                continue;
            }
            *index = (uint16_t)(v >> 40);
            *sub = (uint8_t)((uint8_t)(v >> 32) + (*sub - first));
            return true;
        }
    }
    return false;
}

int co_mpdo_receive(co_node_t *node, const co_rpdo_t *p, const uint8_t frame[8])
{
    const uint8_t address = frame[0];
    uint16_t index = co_get_u16(&frame[1]);
    uint8_t sub = frame[3];
    const bool dam = (address & 0x80U) != 0U;
    if (dam != (p->mpdo == CO_MPDO_DAM)) {
        return 0; /* the other addressing mode: not for this RPDO */
    }
    if (dam) {
        const uint8_t to = (uint8_t)(address & 0x7FU);
        if (to != 0U && to != node->node_id) {
            return 0; /* addressed to another node */
        }
    } else if (!dispatch(node, address, &index, &sub)) {
        return 0; /* an object of a producer this node does not listen to */
    }
    co_od_entry_t one;
    const co_od_entry_t *e = mpdo_object(node, index, sub, CO_OD_RPDO, &one);
    if (e != NULL && co_od_write(node, index, sub, &frame[4], e->size, CO_ORIGIN_RPDO) == CO_ABORT_NONE) {
        return 1;
    }
    return dam ? -1 : 0; /* CiA 301 defines no error for SAM: a refused value is dropped like an RPDO's */
}

#endif /* CO_CONFIG_MPDO */
