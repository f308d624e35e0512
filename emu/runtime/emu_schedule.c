/* The nodes' deadlines and marks: see emu_schedule.h. */
#include "runtime/emu_schedule.h"

#include <string.h>

/* Inner node k from its children: the earlier of theirs (the left one on a tie: the lower index). */
static inline void play(emu_schedule_t *s, size_t k)
{
    const size_t c = s->at[2U * k + 1U] < s->at[2U * k] ? 2U * k + 1U : 2U * k;
    s->at[k] = s->at[c];
    s->who[k] = s->who[c];
}

/* Every inner node again, bottom up, the leaves laid out for `leaves` (the deadlines of the nodes in deadlines). */
static void rebuild(emu_schedule_t *s, size_t leaves, const co_time_us_t *deadlines)
{
    s->leaves = leaves;
    for (size_t i = 0U; i < leaves; i++) {
        s->at[leaves + i] = i < s->n_nodes ? deadlines[i] : CO_NEVER;
        s->who[leaves + i] = (uint8_t)i;
    }
    for (size_t k = leaves - 1U; k >= 1U; k--) {
        play(s, k);
    }
}

void schedule_init(emu_schedule_t *s)
{
    memset(s, 0, sizeof *s);
    rebuild(s, 2U, NULL);
}

/* Always to the root: the common walk is a due node's (the root's) later deadline, which changes every step up,
 * and a test for an early end cost that walk more than it spared the others. */
void schedule_update(emu_schedule_t *s, uint32_t node)
{
    size_t pos = s->leaves + node;
    co_time_us_t best = s->at[pos];
    uint8_t who = (uint8_t)node;
    while (pos > 1U) {
        const size_t sibling = pos ^ 1U;
        const co_time_us_t other = s->at[sibling];
        /* the sibling is the left one when pos is odd: it wins a tie */
        if (other < best || (other == best && (pos & 1U) != 0U)) {
            best = other;
            who = s->who[sibling];
        }
        pos >>= 1;
        s->at[pos] = best;
        s->who[pos] = who;
    }
}

void schedule_add(emu_schedule_t *s, uint32_t node, co_time_us_t at)
{
    if (node >= SCHEDULE_NODES_MAX || node != s->n_nodes) {
        return; /* the bus refuses more nodes before this; nodes come in order */
    }
    if (node + 1U > s->leaves) { /* twice as wide: the deadlines so far laid out again */
        co_time_us_t deadlines[SCHEDULE_LEAVES_MAX];
        for (size_t i = 0U; i < s->n_nodes; i++) {
            deadlines[i] = s->at[s->leaves + i];
        }
        rebuild(s, 2U * s->leaves, deadlines);
    }
    s->n_nodes++;
    s->at[s->leaves + node] = at;
    schedule_update(s, node);
}

void schedule_remove_last(emu_schedule_t *s, uint32_t node)
{
    if (s->n_nodes == 0U || node != s->n_nodes - 1U) {
        return;
    }
    (void)schedule_take_mark(s, node);
    schedule_set_tx_waiting(s, node, false);
    s->at[s->leaves + node] = CO_NEVER;
    schedule_update(s, node);
    s->n_nodes--;
}

/* Insertion sort: the marks of a wake-up are few (one node, mostly) and come mostly in order. */
void schedule_sort_marked(emu_schedule_t *s)
{
    if (s->marked_overflow) {
        s->marked_overflow = false;
        s->n_marked = 0U;
        s->marked_bits[0] = 0U;
        s->marked_bits[1] = 0U;
        for (size_t i = 0U; i < s->n_nodes; i++) {
            schedule_mark(s, (uint32_t)i);
        }
        return; /* in order */
    }
    for (size_t i = 1U; i < s->n_marked; i++) {
        const uint8_t v = s->marked[i];
        size_t j = i;
        while (j > 0U && s->marked[j - 1U] > v) {
            s->marked[j] = s->marked[j - 1U];
            j--;
        }
        s->marked[j] = v;
    }
}

void schedule_mark_due(emu_schedule_t *s, co_time_us_t now)
{
    /* The due leaves are below the inner nodes whose earliest is due: a walk down each branch while it is due finds
     * them all. */
    uint8_t stack[SCHEDULE_LEAVES_MAX]; /* inner nodes to visit: each at most once */
    size_t depth = 0U;
    if (s->at[1] <= now) {
        stack[depth++] = 1U;
    }
    while (depth > 0U) {
        const size_t k = stack[--depth];
        for (size_t c = 2U * k; c <= 2U * k + 1U; c++) {
            if (s->at[c] > now) {
                continue;
            }
            if (c >= s->leaves) {
                if (!schedule_has_run(s, s->who[c])) {
                    schedule_mark(s, s->who[c]);
                }
            } else {
                stack[depth++] = (uint8_t)c;
            }
        }
    }
    schedule_sort_marked(s);
}
