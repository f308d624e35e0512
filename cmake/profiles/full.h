/*
 * Configuration profile "full": every service compiled in, the default sizes of include/co/co_config.h
 * (4 RPDOs, 4 TPDOs, 127 heartbeat-consumer slots, 64-byte segmented SDO buffer, 16-frame TX queue,
 * 8 active errors, 8 queued EMCY frames), and compact dictionary rows as a firmware would build them. The host
 * build (canopen-emu, the host tests) uses the defaults, which are this profile but for CO_CONFIG_OD_COMPACT (the
 * emulator builds dictionaries from EDS files at run time). It serves all three shipped devices, the Bürkert flow
 * controller included (segmented and block SDO, SYNC, node guarding, 0x1016 with 127 entries, 4+4 PDOs).
 * Use it with -DCO_PROFILE=full (CMake) or -DCO_CONFIG_HEADER='"path/to/full.h"'.
 */
#ifndef CO_PROFILE_FULL_H
#define CO_PROFILE_FULL_H

#define CO_CONFIG_SDO_SEGMENTED 1
#define CO_CONFIG_SDO_BLOCK 1
#define CO_CONFIG_SDO_SERVERS 1
#define CO_CONFIG_MPDO 1
#define CO_SDO_BUF_SIZE 64U
#define CO_CONFIG_SYNC 1
#define CO_CONFIG_SYNC_PRODUCER 1
#define CO_CONFIG_TPDO_RTR 1
#define CO_CONFIG_NODE_GUARDING 1
#define CO_CONFIG_HB_CONSUMER 1
#define CO_CONFIG_PDO_DYNAMIC_MAPPING 1
#define CO_CONFIG_LSS_FASTSCAN 1
#define CO_RPDO_MAX 4U
#define CO_TPDO_MAX 4U
#define CO_HB_CONSUMER_MAX 127U
#define CO_EMCY_ACTIVE_MAX 8U
#define CO_EMCY_QUEUE_LEN 8U
#define CO_TX_QUEUE_LEN 16U

#define CO_CONFIG_OD_COMPACT 1

#endif /* CO_PROFILE_FULL_H */
