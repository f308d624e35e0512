/* The unit tests' object dictionary (see test_od.h). Written by hand, in the generator's output format: arrays of
 * like sub-indices are runs (one row for 0x1003:01-08, 0x1016:01-04, ...), as the generator writes them. */
#include "test_od.h"

#include <stddef.h>

#define V test_od_values_t
#define E(i, s, t, f, m) CO_OD_ROW(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m))
/* A run: n sub-indices from s, the elements of array m (co_od.h) */
#define R(i, s, n, t, f, m) CO_OD_RUN(i, s, n, t, f, sizeof(((V *)0)->m[0]), offsetof(V, m))
#define EL(i, s, t, f, m, n) CO_OD_ROW_LIMITED(i, s, t, f, sizeof(((V *)0)->m), offsetof(V, m), limits, n)

#define RO CO_OD_READ
#define WO CO_OD_WRITE
#define RW (CO_OD_READ | CO_OD_WRITE)
#define RWS (CO_OD_READ | CO_OD_WRITE | CO_OD_STORE)
#define CONST (CO_OD_READ | CO_OD_CONST)

static const co_od_limits_t limits[] = {
    {{.u = 100U}, {.u = 60000U}}, /* 0: 0x2000 (UNSIGNED16) */
    {{.i = -100}, {.i = 100}},  /* 1: 0x2001 */
};

static const co_od_entry_t entries[] = {
    E(0x1000, 0x00, CO_T_UNSIGNED32, RO, x1000_device_type),
    E(0x1001, 0x00, CO_T_UNSIGNED8, RO | CO_OD_TPDO, x1001_error_register),
    E(0x1003, 0x00, CO_T_UNSIGNED8, RW, x1003_count),
    R(0x1003, 0x01, 8U, CO_T_UNSIGNED32, RO, x1003_errors),
    E(0x1005, 0x00, CO_T_UNSIGNED32, RWS, x1005_cob_id_sync),
    E(0x1006, 0x00, CO_T_UNSIGNED32, RWS, x1006_cycle_period),
    E(0x1007, 0x00, CO_T_UNSIGNED32, RWS, x1007_window),
    E(0x1008, 0x00, CO_T_VISIBLE_STRING, CONST, x1008_name),
    E(0x1009, 0x00, CO_T_VISIBLE_STRING, CONST, x1009_hw_version),
    E(0x100C, 0x00, CO_T_UNSIGNED16, RWS, x100c_guard_time),
    E(0x100D, 0x00, CO_T_UNSIGNED8, RWS, x100d_life_factor),
    E(0x1010, 0x00, CO_T_UNSIGNED8, RO, x1010_n),
    E(0x1010, 0x01, CO_T_UNSIGNED32, RW, x1010_store[0]),
    E(0x1010, 0x02, CO_T_UNSIGNED32, RW, x1010_store[1]),
    E(0x1010, 0x03, CO_T_UNSIGNED32, RW, x1010_store[2]),
    E(0x1010, 0x04, CO_T_UNSIGNED32, RW, x1010_store[3]),
    E(0x1011, 0x00, CO_T_UNSIGNED8, RO, x1011_n),
    E(0x1011, 0x01, CO_T_UNSIGNED32, RW, x1011_restore[0]),
    E(0x1011, 0x02, CO_T_UNSIGNED32, RW, x1011_restore[1]),
    E(0x1011, 0x03, CO_T_UNSIGNED32, RW, x1011_restore[2]),
    E(0x1011, 0x04, CO_T_UNSIGNED32, RW, x1011_restore[3]),
    E(0x1014, 0x00, CO_T_UNSIGNED32, RWS | CO_OD_NODEID, x1014_cob_id_emcy),
    E(0x1015, 0x00, CO_T_UNSIGNED16, RWS, x1015_inhibit_emcy),
    E(0x1016, 0x00, CO_T_UNSIGNED8, RO, x1016_n),
    R(0x1016, 0x01, 4U, CO_T_UNSIGNED32, RWS, x1016_consumer),
    E(0x1017, 0x00, CO_T_UNSIGNED16, RWS, x1017_producer_hb),
    E(0x1018, 0x00, CO_T_UNSIGNED8, RO, x1018_n),
    R(0x1018, 0x01, 4U, CO_T_UNSIGNED32, RO, x1018_identity),
    E(0x1019, 0x00, CO_T_UNSIGNED8, RWS, x1019_sync_overflow),
    E(0x1200, 0x00, CO_T_UNSIGNED8, RO, x1200_n),
    R(0x1200, 0x01, 2U, CO_T_UNSIGNED32, RO | CO_OD_NODEID, x1200_cob),
#define RPDO_COMM(k)                                                                    \
    E(0x1400 + k, 0x00, CO_T_UNSIGNED8, RO, rpdo_comm[k].n),                            \
    E(0x1400 + k, 0x01, CO_T_UNSIGNED32, RWS | CO_OD_NODEID, rpdo_comm[k].cob_id),      \
    E(0x1400 + k, 0x02, CO_T_UNSIGNED8, RWS, rpdo_comm[k].type),                        \
    E(0x1400 + k, 0x05, CO_T_UNSIGNED16, RWS, rpdo_comm[k].event_timer)
    RPDO_COMM(0), RPDO_COMM(1),
#define PDO_MAP(base, arr, k)                                                           \
    E(base + k, 0x00, CO_T_UNSIGNED8, RWS, arr[k].n),                                   \
    R(base + k, 0x01, 8U, CO_T_UNSIGNED32, RWS, arr[k].entry)
    PDO_MAP(0x1600, rpdo_map, 0), PDO_MAP(0x1600, rpdo_map, 1),
#define TPDO_COMM(k)                                                                    \
    E(0x1800 + k, 0x00, CO_T_UNSIGNED8, RO, tpdo_comm[k].n),                            \
    E(0x1800 + k, 0x01, CO_T_UNSIGNED32, RWS | CO_OD_NODEID, tpdo_comm[k].cob_id),      \
    E(0x1800 + k, 0x02, CO_T_UNSIGNED8, RWS, tpdo_comm[k].type),                        \
    E(0x1800 + k, 0x03, CO_T_UNSIGNED16, RWS, tpdo_comm[k].inhibit),                    \
    E(0x1800 + k, 0x05, CO_T_UNSIGNED16, RWS, tpdo_comm[k].event_timer),                \
    E(0x1800 + k, 0x06, CO_T_UNSIGNED8, RWS, tpdo_comm[k].sync_start)
    TPDO_COMM(0), TPDO_COMM(1),
    PDO_MAP(0x1A00, tpdo_map, 0), PDO_MAP(0x1A00, tpdo_map, 1),
    EL(0x2000, 0x00, CO_T_UNSIGNED16, RWS, x2000_cycle_ms, 0),
    EL(0x2001, 0x00, CO_T_INTEGER16, RWS, x2001_offset, 1),
    E(0x2002, 0x00, CO_T_UNSIGNED8, RWS | CO_OD_KEEP, x2002_address),
    E(0x2003, 0x00, CO_T_UNSIGNED32, RW, x2003_volatile),
    E(0x2004, 0x00, CO_T_REAL32, RW | CO_OD_RPDO | CO_OD_TPDO, x2004_setpoint),
    E(0x2005, 0x00, CO_T_VISIBLE_STRING, RWS, x2005_description),
    E(0x2006, 0x00, CO_T_UNSIGNED64, RO, x2006_counter),
    E(0x6000, 0x00, CO_T_UNSIGNED8, RO, x6000_n),
    R(0x6000, 0x01, 2U, CO_T_UNSIGNED8, RO | CO_OD_TPDO, x6000_inputs),
    E(0x6200, 0x00, CO_T_UNSIGNED8, RO, x6200_n),
    E(0x6200, 0x01, CO_T_UNSIGNED8, WO | CO_OD_RPDO, x6200_output),
    E(0x6300, 0x00, CO_T_UNSIGNED8, RO, x6300_n),
    E(0x6300, 0x01, CO_T_UNSIGNED32, RWS | CO_OD_RPDO | CO_OD_TPDO, x6300_value),
    E(0x6401, 0x00, CO_T_UNSIGNED8, RO, x6401_n),
    R(0x6401, 0x01, 2U, CO_T_UNSIGNED16, RO | CO_OD_TPDO, x6401_analog),
};

static const test_od_values_t defaults = {
    .x1000_device_type = 0x000F0191UL,
    .x1005_cob_id_sync = 0x80UL,
    .x1008_name = {'E', 'S', '6', '1'},
    .x1008_name_len = {4U, 0U},
    .x1009_hw_version = "Hardware rev. 2.3 (test)",
    .x1009_hw_version_len = {24U, 0U},
    .x1010_n = 4U,
    .x1010_store = {1U, 1U, 1U, 1U},
    .x1011_n = 4U,
    .x1011_restore = {1U, 1U, 1U, 1U},
    .x1014_cob_id_emcy = 0x80UL,
    .x1016_n = 4U,
    .x1018_n = 4U,
    .x1018_identity = {0x0000024EUL, 0x00001234UL, 0x00010002UL, 0x00ABCDEFUL},
    .x1200_n = 2U,
    .x1200_cob = {0x600UL, 0x580UL},
    .rpdo_comm = {{5U, 0x200UL, 255U, 0U}, {5U, 0x80000300UL, 255U, 0U}},
    .rpdo_map = {{1U, {0x63000120UL}}, {0U, {0U}}},
    .tpdo_comm = {{6U, 0x180UL, 255U, 0U, 0U, 0U}, {6U, 0x80000280UL, 255U, 0U, 0U, 0U}},
    .tpdo_map = {{1U, {0x10010008UL}}, {2U, {0x60000108UL, 0x64010110UL}}},
    .x2000_cycle_ms = 500U,
    .x2002_address = 99U,
    .x2005_description = "test node",
    .x2005_description_len = {9U, 0U},
    .x2006_counter = 0x0102030405060708ULL,
    .x6000_n = 2U,
    .x6200_n = 1U,
    .x6300_n = 1U,
    .x6401_n = 2U,
};

const co_od_t test_od = {
    .name = "test-device",
    .entries = entries,
    .count = (uint16_t)(sizeof entries / sizeof entries[0]),
    .defaults = &defaults,
    .values_size = (uint32_t)sizeof(test_od_values_t),
    .signature = 0x7E570D01UL,
    .dummy_usage = 1U << CO_T_UNSIGNED8, /* dummy UNSIGNED8 entries in RPDOs (test_pdo) */
    .objects = NULL, /* no object table: look-ups search the rows (the generated tables have one, and a hash) */
    .limits = limits,
    .defaults_size = 0U, /* the whole defaults image */
};
