/**
 * @file co_config.h
 * @brief Compile-time knobs of the core, each with one default.
 *
 * Override any of them by defining it on the compiler command line, or by defining CO_CONFIG_HEADER
 * as the name of a header that defines them (included first). Sizes here fix the size of co_node_t.
 */
#ifndef CO_CONFIG_H
#define CO_CONFIG_H

#ifdef CO_CONFIG_HEADER
#include CO_CONFIG_HEADER
#endif

/** 1: co_time_us_t is 32 bits wide and wraps every 2^32 µs (71.6 minutes): no 64-bit arithmetic on a 32-bit (or
 *  8-bit) core and 4 bytes less per deadline. The core then compares times wrap-safe, which holds while the
 *  caller calls co_node_process() no later than 2^31 µs (35.8 minutes) after the deadline it returned (a main
 *  loop calls it every few ms). 0: 64-bit time that never wraps.
 *  The default follows the target: 0 on a host with an operating system (Linux and other Unix, macOS, Windows:
 *  its clock is 64-bit and the cost of 64-bit arithmetic does not matter there; canopen-emu's device models need
 *  it), 1 on everything else, a microcontroller bare metal or under an RTOS (Cortex-M, RISC-V, AVR), where 64-bit
 *  comparisons and sums cost flash on every deadline (the Bürkert image on a Cortex-M0+: 520 bytes). */
#ifndef CO_CONFIG_TIME32
#if defined(__linux__) || defined(__unix__) || defined(__APPLE__) || defined(_WIN32)
#define CO_CONFIG_TIME32 0
#else
#define CO_CONFIG_TIME32 1
#endif
#endif

/** 1: compact dictionary rows (co_od_entry_t, 10 bytes instead of 16 on 32-bit targets): the limits by number (at
 *  most 255 distinct pairs per dictionary), 16-bit value offsets (a values block of at most 64 KiB), 8-bit sizes (no
 *  string or domain over 255 bytes). For a firmware: it saves 6 bytes of flash per row. The generated tables and CO_OD_ROW() fit either layout; canopen-emu, which builds
 *  dictionaries from EDS files at run time, needs 0 (the default). */
#ifndef CO_CONFIG_OD_COMPACT
#define CO_CONFIG_OD_COMPACT 0
#endif

/** 1: value limits of any numeric row, as 64-bit pairs (16 bytes each). 0: 32-bit pairs (8 bytes) and 32-bit
 *  compares; then only integer rows of at most 4 bytes may have limits (a generated table with a REAL or wider
 *  limited row fails to compile; <c_name>_od_config.h sets 0 where the dictionary allows it). */
#ifndef CO_CONFIG_OD_LIMITS_64
#define CO_CONFIG_OD_LIMITS_64 1
#endif

/** 1 (with CO_CONFIG_OD_LIMITS_64 0): 16-bit limit pairs (4 bytes each) instead of 32-bit ones; then every limit must
 *  fit 16 bits, signed for signed rows (a generated table with a wider one fails to compile; <c_name>_od_config.h
 *  sets 1 where the dictionary allows it). The compares stay 32-bit. */
#ifndef CO_CONFIG_OD_LIMITS_16
#define CO_CONFIG_OD_LIMITS_16 0
#endif

/** Most receive PDOs one node can have (the OD may declare fewer). */
#ifndef CO_RPDO_MAX
#define CO_RPDO_MAX 4U
#endif

/** Most transmit PDOs one node can have (the OD may declare fewer). */
#ifndef CO_TPDO_MAX
#define CO_TPDO_MAX 4U
#endif

/** Most heartbeat-consumer entries (0x1016 sub-indices) one node can monitor. */
#ifndef CO_HB_CONSUMER_MAX
#define CO_HB_CONSUMER_MAX 127U
#endif

/** Errors that can be active at once (they define 0x1001 and are cleared one by one). */
#ifndef CO_EMCY_ACTIVE_MAX
#define CO_EMCY_ACTIVE_MAX 8U
#endif

/** EMCY frames that can wait for the inhibit time 0x1015 or for leaving Stopped. */
#ifndef CO_EMCY_QUEUE_LEN
#define CO_EMCY_QUEUE_LEN 8U
#endif

/** Frames that can wait for a busy port (all services share this queue). */
#ifndef CO_TX_QUEUE_LEN
#define CO_TX_QUEUE_LEN 16U
#endif

/** Retry interval for frames the port refused with CO_ERR_BUSY, in µs. */
#ifndef CO_TX_RETRY_US
#define CO_TX_RETRY_US 1000U
#endif

/** 1: segmented SDO transfer is compiled in (a device switches it on with CO_OPT_SDO_SEGMENTED). */
#ifndef CO_CONFIG_SDO_SEGMENTED
#define CO_CONFIG_SDO_SEGMENTED 1
#endif

/** 1: SDO block transfer (CiA 301 §7.2.4.3.9-16, with CRC) is compiled in (a device switches it on with
 *  CO_OPT_SDO_BLOCK). */
#ifndef CO_CONFIG_SDO_BLOCK
#define CO_CONFIG_SDO_BLOCK 1
#endif

/** 1: additional SDO servers (0x1201..0x127F in the OD, co_node_cfg_t.sdo_servers) are compiled in. 0: an OD
 *  that declares one is refused by co_node_init (CO_ERR_RANGE). */
#ifndef CO_CONFIG_SDO_SERVERS
#define CO_CONFIG_SDO_SERVERS 1
#endif

/** Largest object a segmented or block SDO transfer can move, in bytes. */
#ifndef CO_SDO_BUF_SIZE
#define CO_SDO_BUF_SIZE 64U
#endif

/** 1: large objects (co_hooks_t.large_read/large_write): a string or DOMAIN row of size 0 whose value the application
 *  keeps (a firmware image 0x1F50, a log), moved by segmented and block SDO transfer of any length in pieces of at
 *  most CO_SDO_BUF_SIZE bytes, so the core holds no more. The default follows the target as CO_CONFIG_TIME32's: 1 on
 *  a host with an operating system (canopen-emu's EDS devices keep their DOMAINs so), 0 on a microcontroller, whose
 *  image and co_sdo_server_t then stay as they were. */
#ifndef CO_CONFIG_LARGE_OBJECTS
#if defined(__linux__) || defined(__unix__) || defined(__APPLE__) || defined(_WIN32)
#define CO_CONFIG_LARGE_OBJECTS 1
#else
#define CO_CONFIG_LARGE_OBJECTS 0
#endif
#endif

/** Segmented and block SDO transfer timeout (no frame from the client), in µs. */
#ifndef CO_SDO_TIMEOUT_US
#define CO_SDO_TIMEOUT_US 1000000U
#endif

/** 1: node guarding and life guarding (0x100C/0x100D) are compiled in. */
#ifndef CO_CONFIG_NODE_GUARDING
#define CO_CONFIG_NODE_GUARDING 1
#endif

/** 1: the heartbeat consumer (0x1016) is compiled in, with CO_HB_CONSUMER_MAX slots. 0: none (a node whose OD has
 *  entries in 0x1016 is then refused by co_node_init with CO_ERR_RANGE). */
#ifndef CO_CONFIG_HB_CONSUMER
#define CO_CONFIG_HB_CONSUMER 1
#endif

/** 1: the SYNC consumer and synchronous PDOs are compiled in. */
#ifndef CO_CONFIG_SYNC
#define CO_CONFIG_SYNC 1
#endif

/** 1 (with CO_CONFIG_SYNC): the SYNC producer (CiA 301 §7.2.5): a node whose 0x1005 has bit 30 (gen) set sends the
 *  SYNC every 0x1006 µs, with a counter 1..0x1019 when 0x1019 is 2..240, and consumes it itself. 0: a 0x1005 with bit
 *  30 is refused (0x06090030), written by a master and stored alike; a dictionary whose 0x1005 has it by default is
 *  then refused by its own save (0x08000020). A generated <c_name>_od_config.h turns it off where 0x1005 cannot
 *  have the bit. */
#ifndef CO_CONFIG_SYNC_PRODUCER
#define CO_CONFIG_SYNC_PRODUCER 1
#endif

/** 1: LSS fastscan (0x51) is compiled in. */
#ifndef CO_CONFIG_LSS_FASTSCAN
#define CO_CONFIG_LSS_FASTSCAN 1
#endif

/** 1: multiplexed PDOs (CiA 301 MPDO) are compiled in: a TPDO whose mapping sub 0 is 0xFE sends SAM-MPDOs of the
 *  object scanner list 0x1FA0..0x1FCF; an RPDO with 0xFF takes DAM-MPDOs, with 0xFE SAM-MPDOs through the object
 *  dispatching list 0x1FD0..0x1FFF. */
#ifndef CO_CONFIG_MPDO
#define CO_CONFIG_MPDO 1
#endif

/** 1: TPDOs answer remote requests (RTR) on their COB-ID, where the COB-ID allows it (bit 30 clear): transmission
 *  types 252 (data sampled at the SYNC, sent on RTR) and 253 (sampled and sent on RTR) are taken, and an RTR asks an
 *  event-driven TPDO (254/255) for a transmission. 0: types 252/253 are refused (0x06090030) and remote frames on
 *  TPDO COB-IDs ignored. A generated <c_name>_od_config.h turns it off where no TPDO can allow RTR. */
#ifndef CO_CONFIG_TPDO_RTR
#define CO_CONFIG_TPDO_RTR 1
#endif

/** 1: writable PDO mapping (the CiA 301 mapping procedure) is compiled in. */
#ifndef CO_CONFIG_PDO_DYNAMIC_MAPPING
#define CO_CONFIG_PDO_DYNAMIC_MAPPING 1
#endif

/** 1: the PDO timers are compiled in: an RPDO's event timer (0x1400+n sub 5, reception deadline monitoring with
 *  EMCY 0x8250), a TPDO's inhibit time (0x1800+n sub 3) and event timer (0x1800+n sub 5). 0: event-driven TPDOs
 *  go at each change or co_tpdo_trigger() at once, RPDOs are not monitored; co_node_init() refuses a dictionary
 *  that has any of these sub-indices (CO_ERR_RANGE), as their values would be ignored. */
#ifndef CO_CONFIG_PDO_TIMERS
#define CO_CONFIG_PDO_TIMERS 1
#endif

/** 1: the pre-defined error field 0x1003 (the EMCY history) is compiled in. 0: errors still set 0x1001 and send
 *  their EMCY, nothing keeps a history; co_node_init() refuses a dictionary that has 0x1003 (CO_ERR_RANGE) rather
 *  than show a history that never fills. A generated <c_name>_od_config.h turns it off for a dictionary without it. */
#ifndef CO_CONFIG_EMCY_HISTORY
#define CO_CONFIG_EMCY_HISTORY 1
#endif

/** 1: the EMCY inhibit time 0x1015 is compiled in. 0: EMCYs go out as they come (none of the three devices has
 *  0x1015); co_node_init() refuses a dictionary that has 0x1015 (CO_ERR_RANGE), whose value would change nothing.
 *  A generated <c_name>_od_config.h turns it off for a dictionary without it. */
#ifndef CO_CONFIG_EMCY_INHIBIT
#define CO_CONFIG_EMCY_INHIBIT 1
#endif

#endif /* CO_CONFIG_H */
