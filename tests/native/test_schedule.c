/*
 * The emulator's schedule of a bus's nodes (emu/runtime/emu_schedule.c): the earliest deadline, the nodes a pass
 * runs (marked or due, each once, in the order of the bus), refused frames, a node leaving; against a model that
 * scans every node, over many random steps with up to 127 nodes.
 */
#include <string.h>

#include "runtime/emu_schedule.h"
#include "unity.h"

static emu_schedule_t s;

void setUp(void)
{
    schedule_init(&s);
}

void tearDown(void)
{
}

/* the deadline a node gets when it runs, by node (what device_process would return) */
static co_time_us_t after_run[SCHEDULE_NODES_MAX];

/* One round of a pass as emu_bus_pass.c runs it: the marked nodes, then the due ones; each node that runs gets
 * after_run[i]. Returns how many ran, in ran[]. */
static size_t take_pass(co_time_us_t now, uint32_t *ran)
{
    size_t count = 0U;
    schedule_new_round(&s);
    for (int round = 0; round < 2; round++) {
        schedule_sort_marked(&s);
        for (size_t k = 0U; k < s.n_marked; k++) {
            const uint32_t i = s.marked[k];
            if (schedule_take_mark(&s, i)) {
                ran[count++] = i;
                schedule_set(&s, i, after_run[i]);
                if (after_run[i] <= now) {
                    schedule_set_again(&s, i);
                }
            }
        }
        s.n_marked = 0U;
        if (round == 0) {
            for (int i = schedule_due(&s, now); i >= 0; i = schedule_due(&s, now)) {
                ran[count++] = (uint32_t)i;
                schedule_set(&s, (uint32_t)i, after_run[i]);
                if (after_run[i] <= now) {
                    schedule_set_again(&s, (uint32_t)i);
                }
            }
        }
    }
    return count;
}

static void test_empty_schedule_has_no_deadline_and_no_work(void)
{
    TEST_ASSERT_TRUE(schedule_next(&s) == CO_NEVER);
    TEST_ASSERT_FALSE(schedule_has_work(&s, 1000U));
    TEST_ASSERT_FALSE(schedule_any_tx_waiting(&s));
}

static void test_added_nodes_are_due_at_once_in_bus_order(void)
{
    for (uint32_t i = 0U; i < 5U; i++) {
        schedule_add(&s, i, 0U);
        after_run[i] = 1000U + i;
    }
    TEST_ASSERT_TRUE(schedule_has_work(&s, 0U));
    uint32_t ran[8];
    TEST_ASSERT_EQUAL_UINT(5U, take_pass(0U, ran));
    for (uint32_t i = 0U; i < 5U; i++) {
        TEST_ASSERT_EQUAL_UINT32(i, ran[i]);
    }
    TEST_ASSERT_TRUE(schedule_next(&s) == 1000U);
    TEST_ASSERT_EQUAL_UINT32(0U, schedule_first(&s));
}

static void test_a_marked_node_runs_once_however_often_marked(void)
{
    for (uint32_t i = 0U; i < 3U; i++) {
        schedule_add(&s, i, 100U * (i + 1U));
        after_run[i] = 100U * (i + 1U); /* unchanged by its run */
    }
    schedule_mark(&s, 2U);
    schedule_mark(&s, 2U);
    schedule_mark(&s, 0U);
    TEST_ASSERT_TRUE(schedule_has_work(&s, 50U));
    uint32_t ran[8];
    TEST_ASSERT_EQUAL_UINT(2U, take_pass(50U, ran));
    TEST_ASSERT_EQUAL_UINT32(0U, ran[0]); /* bus order, not marking order */
    TEST_ASSERT_EQUAL_UINT32(2U, ran[1]);
    TEST_ASSERT_FALSE(schedule_has_work(&s, 50U));
    TEST_ASSERT_TRUE(schedule_next(&s) == 100U);
}

static void test_due_nodes_run_earliest_first_then_in_bus_order(void)
{
    const co_time_us_t at[6] = {500U, 200U, 500U, 200U, 900U, 450U};
    for (uint32_t i = 0U; i < 6U; i++) {
        schedule_add(&s, i, at[i]);
        after_run[i] = 5000U;
    }
    uint32_t ran[8];
    TEST_ASSERT_EQUAL_UINT(0U, take_pass(199U, ran));
    TEST_ASSERT_EQUAL_UINT(2U, take_pass(200U, ran));
    TEST_ASSERT_EQUAL_UINT32(1U, ran[0]);
    TEST_ASSERT_EQUAL_UINT32(3U, ran[1]);
    TEST_ASSERT_TRUE(schedule_next(&s) == 450U);
    TEST_ASSERT_EQUAL_UINT(3U, take_pass(600U, ran));
    TEST_ASSERT_EQUAL_UINT32(5U, ran[0]);
    TEST_ASSERT_EQUAL_UINT32(0U, ran[1]);
    TEST_ASSERT_EQUAL_UINT32(2U, ran[2]);
    TEST_ASSERT_TRUE(schedule_next(&s) == 900U);
}

static void test_a_node_due_again_at_once_runs_once_a_round_and_holds_no_one_back(void)
{
    for (uint32_t i = 0U; i < 4U; i++) {
        schedule_add(&s, i, 100U + i);
        after_run[i] = 5000U;
    }
    after_run[0] = 0U; /* node 0 stays due: it must not run again in this round, nor keep 1..3 waiting */
    uint32_t ran[8];
    TEST_ASSERT_EQUAL_UINT(4U, take_pass(200U, ran));
    for (uint32_t i = 0U; i < 4U; i++) {
        TEST_ASSERT_EQUAL_UINT32(i, ran[i]);
    }
    TEST_ASSERT_TRUE(schedule_next(&s) == 0U);
    TEST_ASSERT_EQUAL_UINT(1U, take_pass(300U, ran)); /* the next round runs it again, alone */
    TEST_ASSERT_EQUAL_UINT32(0U, ran[0]);
}

static void test_refused_frames_are_remembered_per_node(void)
{
    schedule_add(&s, 0U, 10U);
    schedule_add(&s, 1U, 10U);
    schedule_set_tx_waiting(&s, 1U, true);
    TEST_ASSERT_TRUE(schedule_any_tx_waiting(&s));
    TEST_ASSERT_EQUAL_UINT64(2U, s.tx_waiting[0]);
    schedule_set_tx_waiting(&s, 1U, false);
    TEST_ASSERT_FALSE(schedule_any_tx_waiting(&s));
    schedule_set_tx_waiting(&s, 100U, true); /* the second word: nodes 64..126 */
    TEST_ASSERT_EQUAL_UINT64((uint64_t)1U << 36, s.tx_waiting[1]);
}

static void test_the_last_node_leaves_with_its_mark_and_deadline(void)
{
    schedule_add(&s, 0U, 300U);
    schedule_add(&s, 1U, 100U);
    schedule_mark(&s, 1U);
    schedule_set_tx_waiting(&s, 1U, true);
    schedule_remove_last(&s, 1U);
    TEST_ASSERT_TRUE(schedule_next(&s) == 300U);
    TEST_ASSERT_FALSE(schedule_is_marked(&s, 1U));
    TEST_ASSERT_FALSE(schedule_any_tx_waiting(&s));
    schedule_add(&s, 1U, 50U);
    TEST_ASSERT_TRUE(schedule_next(&s) == 50U);
}

static void test_too_many_marks_run_every_node(void)
{
    for (uint32_t i = 0U; i < 4U; i++) {
        schedule_add(&s, i, 1000U);
        after_run[i] = 1000U;
    }
    /* more entries than the list holds: marked, taken without running, marked again... */
    for (size_t k = 0U; k < sizeof s.marked + 1U; k++) {
        schedule_mark(&s, 3U);
        (void)schedule_take_mark(&s, 3U);
    }
    TEST_ASSERT_TRUE(s.marked_overflow);
    TEST_ASSERT_TRUE(schedule_has_work(&s, 0U));
    uint32_t ran[8];
    TEST_ASSERT_EQUAL_UINT(4U, take_pass(0U, ran));
    TEST_ASSERT_FALSE(s.marked_overflow);
}

/* xorshift: the same steps every run */
static uint32_t rng = 0x9E3779B9U;
static uint32_t next_random(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

/* The model: a scan of every node, as the emulator did before. The tree grows as nodes come (1, 2, 3, 5, 9 ... 127). */
static void random_steps(uint32_t nodes)
{
    co_time_us_t model[SCHEDULE_NODES_MAX];
    bool marked[SCHEDULE_NODES_MAX];
    memset(marked, 0, sizeof marked);
    for (uint32_t i = 0U; i < nodes; i++) {
        model[i] = next_random() % 5000U;
        schedule_add(&s, i, model[i]);
    }
    co_time_us_t now = 0U;
    for (unsigned step = 0U; step < 4000U; step++) {
        co_time_us_t earliest = CO_NEVER;
        for (uint32_t i = 0U; i < nodes; i++) {
            earliest = model[i] < earliest ? model[i] : earliest;
        }
        TEST_ASSERT_TRUE(schedule_next(&s) == earliest);
        const uint32_t what = next_random() % 4U;
        const uint32_t node = next_random() % nodes;
        if (what == 0U) { /* a frame concerns a node */
            schedule_mark(&s, node);
            marked[node] = true;
        } else if (what == 1U) { /* a fault moves its deadline */
            model[node] = now + next_random() % 3000U;
            schedule_set(&s, node, model[node]);
        } else { /* a pass */
            now += next_random() % 400U;
            uint32_t expect[SCHEDULE_NODES_MAX];
            size_t n_expect = 0U;
            for (uint32_t i = 0U; i < nodes; i++) { /* marked first, in bus order */
                if (marked[i]) {
                    expect[n_expect++] = i;
                }
            }
            for (;;) { /* then the due ones, earliest first, on a tie the lower index */
                uint32_t best = SCHEDULE_NODES_MAX;
                for (uint32_t i = 0U; i < nodes; i++) {
                    if (!marked[i] && model[i] <= now && (best == SCHEDULE_NODES_MAX || model[i] < model[best])) {
                        best = i;
                    }
                }
                if (best == SCHEDULE_NODES_MAX) {
                    break;
                }
                expect[n_expect++] = best;
                marked[best] = true;
            }
            for (size_t k = 0U; k < n_expect; k++) {
                marked[expect[k]] = false;
                model[expect[k]] = now + 1U + next_random() % 2000U; /* later than now */
                after_run[expect[k]] = model[expect[k]];
            }
            uint32_t ran[SCHEDULE_NODES_MAX];
            const size_t count = take_pass(now, ran);
            TEST_ASSERT_EQUAL_UINT(n_expect, count);
            if (n_expect > 0U) {
                TEST_ASSERT_EQUAL_UINT32_ARRAY(expect, ran, n_expect);
            }
        }
    }
}

static void test_random_steps_match_a_scan_of_every_node(void)
{
    const uint32_t sizes[] = {1U, 2U, 3U, 5U, 64U, 65U, 127U};
    for (size_t k = 0U; k < sizeof sizes / sizeof sizes[0]; k++) {
        schedule_init(&s);
        random_steps(sizes[k]);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_empty_schedule_has_no_deadline_and_no_work);
    RUN_TEST(test_added_nodes_are_due_at_once_in_bus_order);
    RUN_TEST(test_a_marked_node_runs_once_however_often_marked);
    RUN_TEST(test_due_nodes_run_earliest_first_then_in_bus_order);
    RUN_TEST(test_a_node_due_again_at_once_runs_once_a_round_and_holds_no_one_back);
    RUN_TEST(test_refused_frames_are_remembered_per_node);
    RUN_TEST(test_the_last_node_leaves_with_its_mark_and_deadline);
    RUN_TEST(test_too_many_marks_run_every_node);
    RUN_TEST(test_random_steps_match_a_scan_of_every_node);
    return UNITY_END();
}
