/*
 * Configuration profile "eltex": what the two Eltex devices need (PRO IONIZER, SDS), nothing more.
 * Use it as the core's configuration header: -DCO_PROFILE=eltex with CMake (or
 * -DCO_CONFIG_HEADER='"path/to/eltex.h"'). Every value is checked against od/pro-ionizer.eds and
 * od/sds.eds (the generated tables in <build>/od/) and against the device models:
 *
 * - No segmented or block SDO: every object of both dictionaries fits an expedited transfer (the longest are
 *   the 4-byte strings 0x1008/0x100A), and the device models set neither CO_OPT_SDO_SEGMENTED nor
 *   CO_OPT_SDO_BLOCK (their manuals rule both out). One SDO server: neither dictionary has 0x1201... The SDO
 *   buffer must still hold the largest object read by SDO (uploads are staged in it): 8 bytes.
 * - No SYNC: neither dictionary has 0x1005/0x1006/0x1007/0x1019, and the PDO transmission types
 *   (0x1400:02, 0x1800:02, 0x1801:02, 0x1802:02) are read-only and event-driven (254/255).
 * - No node guarding: neither dictionary has 0x100C/0x100D (heartbeat only).
 * - No remote requests of TPDOs (CO_CONFIG_TPDO_RTR): the manuals name none; remote frames on the TPDO COB-IDs are
 *   ignored (their COB-IDs, read-only, leave bit 30 "no RTR" clear; the host build, with the default, answers them).
 * - No dynamic PDO mapping: 0x1600/0x1A00.. are read-only in both.
 * - No PDO timers: neither dictionary has an RPDO event timer (0x1400:05) or a TPDO inhibit time or event timer
 *   (0x1800..:03/05); their TPDOs go at each change (the manuals name no timer).
 * - LSS fastscan kept: both manuals claim CiA 305 LSS, and the emulator relies on fastscan to
 *   tell several nodes of one type apart (distinct serial numbers).
 * - PDO counts: 1 RPDO (both), 3 TPDOs (PRO IONIZER; the SDS has 2).
 * - No heartbeat consumer: neither dictionary has 0x1016.
 * - No EMCY inhibit time: neither dictionary has 0x1015.
 * - EMCY: the defaults (8 active errors, 8 queued frames): the PRO IONIZER can have several warnings and
 *   errors active at once and logs when the list is full; keeping the default keeps its behaviour.
 * - 32-bit time (CO_CONFIG_TIME32): a Cortex-M or AVR firmware then has no 64-bit arithmetic in the core. The device
 *   models of the emulator assume 64-bit time: their tests with this profile (tools/profile-tests) set it to 0.
 * - Compact dictionary rows (CO_CONFIG_OD_COMPACT): 10 bytes a row; both dictionaries are far below 64 KiB of
 *   values and 255 distinct limit pairs.
 * - 16-bit limit pairs (CO_CONFIG_OD_LIMITS_64 0, CO_CONFIG_OD_LIMITS_16 1): both dictionaries limit only 8- and
 *   16-bit integers, within 16 bits.
 * - TX queue: 8 frames. The largest burst of these devices is boot-up + 3 TPDOs on entering
 *   Operational + an EMCY + an SDO response + a heartbeat (7 frames) against a port that is busy.
 *
 * The device tests of both devices pass with this profile on the host (tools/profile-tests eltex, ctest
 * profile/eltex; docs/footprint.md gives sizeof(co_node_t) with it).
 */
#ifndef CO_PROFILE_ELTEX_H
#define CO_PROFILE_ELTEX_H

#define CO_CONFIG_SDO_SEGMENTED 0
#define CO_CONFIG_SDO_BLOCK 0
#define CO_CONFIG_SDO_SERVERS 0
#define CO_CONFIG_MPDO 0
#define CO_SDO_BUF_SIZE 8U
#define CO_CONFIG_SYNC 0
#define CO_CONFIG_SYNC_PRODUCER 0
#define CO_CONFIG_TPDO_RTR 0
#define CO_CONFIG_NODE_GUARDING 0
#define CO_CONFIG_PDO_DYNAMIC_MAPPING 0
#define CO_CONFIG_PDO_TIMERS 0
#define CO_CONFIG_LSS_FASTSCAN 1
#define CO_RPDO_MAX 1U
#define CO_TPDO_MAX 3U
#define CO_CONFIG_HB_CONSUMER 0
#define CO_TX_QUEUE_LEN 8U
#ifndef CO_CONFIG_TIME32
#define CO_CONFIG_TIME32 1
#endif

#define CO_CONFIG_OD_COMPACT 1
#define CO_CONFIG_OD_LIMITS_64 0
#define CO_CONFIG_OD_LIMITS_16 1
#define CO_CONFIG_EMCY_INHIBIT 0

#endif /* CO_PROFILE_ELTEX_H */
