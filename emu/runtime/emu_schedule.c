/* The nodes' deadlines and marks: see emu_schedule.h. */
#include "runtime/emu_schedule.h"

#include <string.h>

/* The winner of inner node k: the earlier of its children's (the left one on a tie: the lower index). */
static inline uint8_t play(const emu_schedule_t *s, size_t k)
{
    const uint8_t a = s->winner[2U * k];
    const uint8_t b = s->winner[2U * k + 1U];
    return s->at[b] < s->at[a] ? b : a;
}

/* Every inner node again, bottom up: after the tree grew. */
static void rebuild(emu_schedule_t *s)
{
    for (size_t i = 0U; i < s->leaves; i++) {
        s->winner[s->leaves + i] = (uint8_t)i;
    }
    for (size_t k = s->leaves - 1U; k >= 1U; k--) {
        s->winner[k] = play(s, k);
    }
}

void schedule_init(emu_schedule_t *s)
{
    memset(s, 0, sizeof *s);
    for (size_t i = 0U; i < SCHEDULE_LEAVES_MAX; i++) {
        s->at[i] = CO_NEVER;
    }
    s->leaves = 2U;
    rebuild(s);
}

void schedule_update(emu_schedule_t *s, uint32_t node)
{
    for (size_t k = (s->leaves + node) >> 1; k >= 1U; k >>= 1) {
        const uint8_t w = play(s, k);
        if (w != node && s->winner[k] == w) {
            break; /* this node lost here before and still does: nothing above changes */
        }
        s->winner[k] = w;
    }
}

void schedule_add(emu_schedule_t *s, uint32_t node, co_time_us_t at)
{
    if (node >= SCHEDULE_NODES_MAX || node != s->n_nodes) {
        return; /* the bus refuses more nodes before this; nodes come in order */
    }
    s->n_nodes++;
    s->at[node] = at;
    if (s->n_nodes > s->leaves) {
        s->leaves *= 2U;
        rebuild(s);
    } else {
        schedule_update(s, node);
    }
}

void schedule_remove_last(emu_schedule_t *s, uint32_t node)
{
    if (s->n_nodes == 0U || node != s->n_nodes - 1U) {
        return;
    }
    (void)schedule_take_mark(s, node);
    schedule_set_tx_waiting(s, node, false);
    s->at[node] = CO_NEVER;
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
    /* The due leaves are where the winners are due: a walk down each branch while its winner is due finds them all. */
    uint8_t stack[SCHEDULE_LEAVES_MAX]; /* inner nodes to visit: each at most once, at most one per leaf */
    size_t depth = 0U;
    if (s->at[s->winner[1]] <= now) {
        stack[depth++] = 1U;
    }
    while (depth > 0U) {
        const size_t k = stack[--depth];
        for (size_t c = 2U * k; c <= 2U * k + 1U; c++) {
            const uint8_t w = s->winner[c];
            if (s->at[w] > now) {
                continue;
            }
            if (c >= s->leaves) {
                if (!schedule_has_run(s, w)) {
                    schedule_mark(s, w);
                }
            } else {
                stack[depth++] = (uint8_t)c;
            }
        }
    }
    schedule_sort_marked(s);
}
