/*
 * A hand-written object dictionary for the core's unit tests. It follows the assumptions of the facts
 * sheet's test vectors (0x1000 = 0x000F0191, 0x1018 = 4/0x24E/0x1234/0x00010002/0x00ABCDEF, 0x1017 = 0,
 * 0x1019 = 0, 0x6200:01 U8 write-only, no 0x2100) and adds what the other tests need: two RPDOs and two
 * TPDOs with writable mapping, 0x1016 with 4 entries, strings, limits, stored and kept rows.
 * Device dictionaries are generated from EDS files by tools/odgen.py; this one is written by hand only
 * because it exercises the core in isolation.
 */
#ifndef TEST_OD_H
#define TEST_OD_H

#include "co/co.h"

typedef struct test_od_values {
    uint32_t x1000_device_type;
    uint8_t x1001_error_register;
    uint8_t x1003_count;
    uint32_t x1003_errors[8];
    uint32_t x1005_cob_id_sync;
    uint32_t x1006_cycle_period;
    uint32_t x1007_window;
    char x1008_name[4];
    uint8_t x1008_name_len[CO_OD_LEN_SIZE]; /* each string's length after it (co_od.h) */
    char x1009_hw_version[24];
    uint8_t x1009_hw_version_len[CO_OD_LEN_SIZE];
    uint16_t x100c_guard_time;
    uint8_t x100d_life_factor;
    uint8_t x1010_n;
    uint32_t x1010_store[4];
    uint8_t x1011_n;
    uint32_t x1011_restore[4];
    uint32_t x1014_cob_id_emcy;
    uint16_t x1015_inhibit_emcy;
    uint8_t x1016_n;
    uint32_t x1016_consumer[4];
    uint16_t x1017_producer_hb;
    uint8_t x1018_n;
    uint32_t x1018_identity[4];
    uint8_t x1019_sync_overflow;
    uint8_t x1200_n;
    uint32_t x1200_cob[2];
    struct {
        uint8_t n;
        uint32_t cob_id;
        uint8_t type;
        uint16_t event_timer;
    } rpdo_comm[2];
    struct {
        uint8_t n;
        uint32_t entry[8];
    } rpdo_map[2];
    struct {
        uint8_t n;
        uint32_t cob_id;
        uint8_t type;
        uint16_t inhibit;
        uint16_t event_timer;
        uint8_t sync_start;
    } tpdo_comm[2];
    struct {
        uint8_t n;
        uint32_t entry[8];
    } tpdo_map[2];
    uint16_t x2000_cycle_ms;     /* U16 RW 100..60000, stored */
    int16_t x2001_offset;        /* I16 RW -100..100, stored */
    uint8_t x2002_address;       /* U8 RW, stored, kept by restore */
    uint32_t x2003_volatile;     /* U32 RW, not stored */
    float x2004_setpoint;        /* REAL32 RW, RPDO/TPDO */
    char x2005_description[20];  /* VISIBLE_STRING RW, stored */
    uint8_t x2005_description_len[CO_OD_LEN_SIZE];
    uint64_t x2006_counter;      /* U64 RO (an 8-byte object) */
    uint8_t x6000_n;
    uint8_t x6000_inputs[2];     /* U8 RO TPDO */
    uint8_t x6200_n;
    uint8_t x6200_output;        /* U8 WO RPDO */
    uint8_t x6300_n;
    uint32_t x6300_value;        /* U32 RW RPDO+TPDO, stored */
    uint8_t x6401_n;
    uint16_t x6401_analog[2];    /* U16 RO TPDO */
} test_od_values_t;

extern const co_od_t test_od;

#endif
