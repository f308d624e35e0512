/*
 * When the nodes of one bus run: a min-heap of their deadlines (what device_process last returned), the nodes marked
 * to run in the next pass (a frame or a command concerned them) and the nodes whose frames the interface refused.
 * A wake-up then costs work for the nodes it concerns only: finding the due nodes is the heap's top, not a scan of
 * all nodes (a scan cost about 17 instructions a node per wake-up: at 127 nodes an SDO request cost 3.6 times what
 * it cost with one, docs/performance.md "Scale").
 *
 * Nodes are named by their index on the bus (emu_node_t.index, < MAX_NODES). A pass runs the nodes marked first, in
 * the order of the bus, then the nodes due, the earliest deadline first (on a tie the order of the bus).
 */
#ifndef EMU_SCHEDULE_H
#define EMU_SCHEDULE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "co/co_types.h"

#define SCHEDULE_NODES_MAX 127U
#define SCHEDULE_LEAVES_MAX 128U /* the tree's leaves: a power of two */

/*
 * The deadlines are the leaves of a tournament tree: each inner node holds the earliest deadline of its subtree and
 * whose it is (the lower index on a tie), the root the earliest of all. A new deadline walks from its leaf up against
 * the sibling of each step: log2 of the nodes steps (7 at 127 nodes) of a few instructions, no swaps, no positions
 * to keep. The tree is as wide as the nodes
 * need (a power of two, at least 2), so one node costs one step.
 */
typedef struct emu_schedule {
    co_time_us_t at[2U * SCHEDULE_LEAVES_MAX]; /* inner node k (1..leaves-1): its earliest; leaves + i: node i's */
    uint8_t who[2U * SCHEDULE_LEAVES_MAX];     /* whose deadline at[k] is; who[leaves + i] = i */
    size_t leaves;
    size_t n_nodes;
    uint64_t again[2];          /* bit i: node i ran in this round of the pass and is due again at once */
    /* The nodes to run in the next pass: a bit each, and their list in the order they were marked. A node marked
     * again while its run goes on adds a second entry, so twice the nodes is room enough; the run skips an entry
     * whose bit is clear. */
    uint64_t marked_bits[2];
    uint8_t marked[2U * SCHEDULE_NODES_MAX];
    size_t n_marked;
    bool marked_overflow;       /* more entries than room (never expected): schedule_sort_marked marks every node */
    uint64_t tx_waiting[2];     /* bit i: node i holds frames the interface refused */
} emu_schedule_t;

/** Empty: no node. */
void schedule_init(emu_schedule_t *s);

/** Node `node` (the next index: nodes are added in order) enters with deadline `at`. */
void schedule_add(emu_schedule_t *s, uint32_t node, co_time_us_t at);

/** The last node added leaves (its start failed). */
void schedule_remove_last(emu_schedule_t *s, uint32_t node);

void schedule_update(emu_schedule_t *s, uint32_t node);

/** Node `node`'s deadline is now `at`. Inline: an unchanged deadline (an SDO request answered at once) costs no
 *  walk. */
static inline void schedule_set(emu_schedule_t *s, uint32_t node, co_time_us_t at)
{
    if (s->at[s->leaves + node] != at) {
        s->at[s->leaves + node] = at;
        schedule_update(s, node);
    }
}

/** The node whose deadline is earliest (a node of the bus unless there is none: then its deadline is CO_NEVER). */
static inline uint32_t schedule_first(const emu_schedule_t *s)
{
    return s->who[1];
}

/** The earliest deadline of all nodes; CO_NEVER with none. */
static inline co_time_us_t schedule_next(const emu_schedule_t *s)
{
    return s->at[1];
}

/** Node `node`'s deadline. */
static inline co_time_us_t schedule_deadline(const emu_schedule_t *s, uint32_t node)
{
    return s->at[s->leaves + node];
}

static inline bool schedule_is_marked(const emu_schedule_t *s, uint32_t node)
{
    return (s->marked_bits[node >> 6] & ((uint64_t)1U << (node & 63U))) != 0U;
}

/** The node is to run in the next pass (once, however often it is marked before). */
static inline void schedule_mark(emu_schedule_t *s, uint32_t node)
{
    const uint64_t bit = (uint64_t)1U << (node & 63U);
    if ((s->marked_bits[node >> 6] & bit) == 0U) {
        s->marked_bits[node >> 6] |= bit;
        if (s->n_marked < sizeof s->marked) {
            s->marked[s->n_marked++] = (uint8_t)node;
        } else {
            s->marked_overflow = true;
        }
    }
}

/** Takes the node's mark as it runs; true when it was marked. */
static inline bool schedule_take_mark(emu_schedule_t *s, uint32_t node)
{
    const uint64_t bit = (uint64_t)1U << (node & 63U);
    const bool was = (s->marked_bits[node >> 6] & bit) != 0U;
    s->marked_bits[node >> 6] &= ~bit;
    return was;
}

/** Whether a pass has nodes to run at now: marked ones, or due ones. */
static inline bool schedule_has_work(const emu_schedule_t *s, co_time_us_t now)
{
    return s->n_marked > 0U || s->marked_overflow || now >= schedule_next(s);
}

/** Puts the marked nodes in the order of the bus, the order a pass runs them in (after an overflow: every node). */
void schedule_sort_marked(emu_schedule_t *s);

/** A round of a pass begins: no node has run in it. */
static inline void schedule_new_round(emu_schedule_t *s)
{
    s->again[0] = 0U;
    s->again[1] = 0U;
}

/** The node ran in this round and its run left it due at once (deadline <= now): it is not to run again in this
 *  round (each node runs once a round; a node that ran and is not due is not taken anyway). */
static inline void schedule_set_again(emu_schedule_t *s, uint32_t node)
{
    s->again[node >> 6] |= (uint64_t)1U << (node & 63U);
}

static inline bool schedule_has_run(const emu_schedule_t *s, uint32_t node)
{
    return (s->again[node >> 6] & ((uint64_t)1U << (node & 63U))) != 0U;
}

/** Marks the nodes due at now that have not run in this round and sorts the marked ones (schedule_due's rare
 *  case). */
void schedule_mark_due(emu_schedule_t *s, co_time_us_t now);

/** The next node due at now that has not run in this round: the earliest deadline first; -1 with none. When the
 *  earliest has run already (its run left it due at once), the others due are marked instead (in the order of the
 *  bus) and -1 returned: each runs once a round, and none waits behind a node that is due again at once. */
static inline int schedule_due(emu_schedule_t *s, co_time_us_t now)
{
    if (s->at[1] > now) {
        return -1;
    }
    const uint32_t first = s->who[1];
    if (!schedule_has_run(s, first)) {
        return (int)first;
    }
    schedule_mark_due(s, now);
    return -1;
}

/** Whether node holds refused frames (set after each run of it). */
static inline void schedule_set_tx_waiting(emu_schedule_t *s, uint32_t node, bool waiting)
{
    const uint64_t bit = (uint64_t)1U << (node & 63U);
    if (waiting) {
        s->tx_waiting[node >> 6] |= bit;
    } else {
        s->tx_waiting[node >> 6] &= ~bit;
    }
}

static inline bool schedule_any_tx_waiting(const emu_schedule_t *s)
{
    return (s->tx_waiting[0] | s->tx_waiting[1]) != 0U;
}

#endif /* EMU_SCHEDULE_H */
