/* What a file configures, the node does, and stores (issue 35, rule 3): a dictionary whose power-on values make the
 * node a SYNC producer (0x1005 bit 30), give TPDOs the RTR-only types 252/253, map entries above the count that name
 * missing objects (CiA 301 checks the entries up to the count only) and make PDOs valid with nothing mapped. A fresh
 * node of it saves (0x1010) and loads what it has, does what it says, and takes the same values from a master. */
#include <string.h>

#include "fixture.h"

#define SAVE 0x65766173UL /* "save" */
#define MS ((co_time_us_t)1000U)

static test_od_values_t file_defaults;
static co_od_t file_od;

enum { GEN = 1, RTR_TYPES = 2, ENTRIES = 4, EMPTY = 8, ALL = 15 };

/* The test dictionary with these power-on values, node 5 powered on with it, in Pre-operational. */
static void power_on_with(unsigned what)
{
    memcpy(&file_defaults, test_od.defaults, sizeof file_defaults);
    if ((what & GEN) != 0U) {
        file_defaults.x1005_cob_id_sync = 0x40000080UL; /* produces the SYNC */
        file_defaults.x1006_cycle_period = 10000U;        /* every 10 ms */
        file_defaults.x1019_sync_overflow = 4U;           /* with a counter 1..4 */
    }
    if ((what & RTR_TYPES) != 0U) {
        file_defaults.tpdo_comm[0].type = 252U; /* TPDO1 0x185 (0x1001): sampled at the SYNC, sent on RTR */
        file_defaults.tpdo_comm[1].type = 253U; /* TPDO2: sampled and sent on RTR */
    }
    if ((what & ENTRIES) != 0U) {
        file_defaults.tpdo_map[0].entry[3] = 0x21000108UL; /* 0x1A00:04, above the count 1: no object 0x2100 */
        file_defaults.tpdo_map[0].entry[7] = 0x99990120UL; /* 0x1A00:08: neither */
        file_defaults.rpdo_map[1].entry[0] = 0x77770008UL; /* 0x1601:01 above the count 0 */
    }
    if ((what & EMPTY) != 0U) {
        file_defaults.tpdo_comm[1].cob_id = 0x00000280UL; /* TPDO2 0x285 valid, mapping nothing (13 vendor files) */
        file_defaults.tpdo_map[1].n = 0U;
        file_defaults.rpdo_comm[1].cob_id = 0x00000300UL; /* RPDO2 0x305 valid, mapping nothing */
    }
    file_od = test_od;
    file_od.defaults = &file_defaults;
    fx.cfg.od = &file_od;
    fx_power_cycle();
    fake_port_clear(&fx.port);
    fx.n_events = 0U;
}

void setUp(void) { fx_start(5U, 0U); }
void tearDown(void) {}

static uint32_t events(co_event_kind_t kind)
{
    uint32_t n = 0U;
    for (uint32_t i = 0U; i < fx.n_events; i++) {
        n += fx.events[i].kind == kind ? 1U : 0U;
    }
    return n;
}

/* A fresh node saves (was 0x08000020 for the first three) and loads what it has. */
static void saves_and_loads(unsigned what)
{
    power_on_with(what);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1010, 1, SAVE, 4U));
    TEST_ASSERT_EQUAL_UINT32(0U, events(CO_EV_NVM_REFUSED));
    fx_power_cycle();
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    RX(0x000, 0x82, 0x05); /* reset communication: the stored communication area again */
    TEST_ASSERT_EQUAL_INT(CO_NVM_LOADED, fx.node.nvm_status);
    TEST_ASSERT_EQUAL_UINT32(0U, events(CO_EV_NVM_REFUSED));
    TEST_ASSERT_EQUAL_MEMORY(&file_defaults.x1005_cob_id_sync, &fx.values.x1005_cob_id_sync, 4U);
    TEST_ASSERT_EQUAL_MEMORY(&file_defaults.tpdo_comm[1].type, &fx.values.tpdo_comm[1].type, 1U);
    TEST_ASSERT_EQUAL_MEMORY(&file_defaults.tpdo_map[0].entry[3], &fx.values.tpdo_map[0].entry[3], 4U);
}
static void a_sync_producer_saves_and_loads(void) { saves_and_loads(GEN); }
static void rtr_only_tpdos_save_and_load(void) { saves_and_loads(RTR_TYPES); }
static void entries_above_the_count_save_and_load(void) { saves_and_loads(ENTRIES); }
static void valid_pdos_mapping_nothing_save_and_load(void) { saves_and_loads(EMPTY); }
static void all_of_them_save_and_load(void) { saves_and_loads(ALL); }

static void the_node_does_what_its_file_configures(void)
{
    power_on_with(ALL);
    const co_time_us_t t0 = fx.now;
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port);
    fx_run_until(t0 + 10U * MS); /* the first SYNC, a full period after the boot-up */
    TEST_ASSERT_EQUAL_UINT32(1U, fx.port.n_sent);
    ASSERT_FRAME(0, 0x080U, 1, 0x01);
    TEST_ASSERT_EQUAL_UINT64(t0 + 10U * MS, fx.port.sent_at[0]);
    const co_frame_t rtr185 = {0x185U, 1U, CO_FRAME_RTR, {0U}};
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &rtr185, fx.now));
    ASSERT_FRAME(1, 0x185U, 1, 0x00); /* 0x1001 as the SYNC sampled it */
    const co_frame_t rtr285 = {0x285U, 0U, CO_FRAME_RTR, {0U}};
    TEST_ASSERT_FALSE(co_node_rx(&fx.node, &rtr285, fx.now)); /* mapping nothing: silent */
    TEST_ASSERT_EQUAL_UINT32(2U, fx.port.n_sent);
}

static void a_master_re_enables_what_the_file_enabled(void)
{
    power_on_with(ALL);
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1801, 1, 0x80000285UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1801, 1, 0x00000285UL, 4U)); /* was 0x06090030 */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1401, 1, 0x80000305UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1401, 1, 0x00000305UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1801, 2, 253U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1800, 2, 252U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1005, 0, 0x40000080UL, 4U));
    /* and maps the empty PDO by the procedure: invalid, entries, count, valid */
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1801, 1, 0x80000285UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1A01, 1, 0x60000108UL, 4U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1A01, 0, 1U, 1U));
    TEST_ASSERT_EQUAL_HEX32(0U, fx_sdo_write_u32(0x1801, 1, 0x00000285UL, 4U));
    RX(0x000, 0x01, 0x05);
    fake_port_clear(&fx.port);
    fx.values.x6000_inputs[0] = 0x3CU;
    const co_frame_t rtr285 = {0x285U, 0U, CO_FRAME_RTR, {0U}};
    TEST_ASSERT_TRUE(co_node_rx(&fx.node, &rtr285, fx.now));
    ASSERT_FRAME(0, 0x285U, 1, 0x3C);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(a_sync_producer_saves_and_loads);
    RUN_TEST(rtr_only_tpdos_save_and_load);
    RUN_TEST(entries_above_the_count_save_and_load);
    RUN_TEST(valid_pdos_mapping_nothing_save_and_load);
    RUN_TEST(all_of_them_save_and_load);
    RUN_TEST(the_node_does_what_its_file_configures);
    RUN_TEST(a_master_re_enables_what_the_file_enabled);
    return UNITY_END();
}
