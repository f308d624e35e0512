/**
 * @file co_node.h
 * @brief One CANopen slave node: configuration, lifecycle, frame input, processing, hooks.
 *
 * A node is one co_node_t in caller-owned memory plus a values block of od->values_size bytes. The core
 * allocates nothing and has no writable globals, so any number of nodes (of the same or different
 * devices) live in one process. Time is always an argument.
 *
 * Main loop:
 *   co_node_init(&node, &cfg, now);
 *   for (;;) {
 *       while (a frame f arrived at time t) co_node_rx(&node, &f, t);
 *       next = co_node_process(&node, now);      // absolute deadline, or CO_NEVER
 *       sleep until next or until a frame arrives;
 *   }
 * Call co_node_process() also after the application changed OD values (change-of-state TPDOs are detected
 * there) and after co_emcy_raise()/co_emcy_clear().
 *
 * Between those events co_node_process() costs almost nothing: it returns the deadline of its last full pass
 * unless a frame was taken or an API call changed something since. The core therefore has to hear of every
 * change: values written with co_od_write()/co_od_set_*() are seen; a value written around them (through
 * co_od_value()'s pointer or the generated values struct) is seen only after co_node_values_changed() (process
 * values) or co_od_changed() (any object, communication parameters included).
 *
 * The fields of co_node_t are visible so it can be allocated statically; treat them as read-only.
 */
#ifndef CO_NODE_H
#define CO_NODE_H

#include "co_config.h"
#include "co_od.h"
#include "co_port.h"
#include "co_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Reset kinds (NMT 0x81 reset node = application, 0x82 = communication). */
typedef enum co_reset {
    CO_RESET_APPLICATION = 0, /**< 0x2000-0x9FFF re-initialised, then a communication reset follows. */
    CO_RESET_COMMUNICATION = 1 /**< 0x1000-0x1FFF re-initialised, pending node-ID adopted. */
} co_reset_t;

/** Things worth a log line, reported through co_hooks_t.on_event. */
typedef enum co_event_kind {
    CO_EV_NMT_STATE = 1,      /**< value = new state, code = previous state. */
    CO_EV_SDO_ABORT,          /**< index/sub of the request, code = abort code sent. */
    CO_EV_EMCY,               /**< value = error code, code = error register; sent (or queued while Stopped); its 8 bytes
                                   are then the newest entry of node->emcy.queue. */
    CO_EV_STORE,              /**< 0x1010 sub or LSS store; code = 0 or abort code. */
    CO_EV_RESTORE,            /**< 0x1011 sub; code = 0 or abort code. */
    CO_EV_NVM_LOADED,         /**< value = co_nvm_status_t; index 0x1010: the parameter area, after every
                                   reset application; index 0x7E5: the LSS area, once at power-on. */
    CO_EV_LSS_NODE_ID,        /**< value = new pending node-ID. */
    CO_EV_LSS_BIT_TIMING,     /**< value = new pending bit-timing index. */
    CO_EV_LSS_ACTIVATE,       /**< value = kbit/s switched to. */
    CO_EV_HB_TIMEOUT,         /**< value = monitored node-ID whose heartbeat is missing. */
    CO_EV_GUARD_TIMEOUT,      /**< life guarding: no guard request within the node life time. */
    CO_EV_TX_DROPPED,         /**< a frame could not be queued or sent; value = CAN-ID. */
    CO_EV_NVM_REFUSED,        /**< a stored value an SDO write of it would be refused: index/sub of the object,
                                   code = the abort code, value 0: the area then loads as CO_NVM_REFUSED (defaults).
                                   value 1: at a 0x1010 save, the object holds a value its load would refuse (the
                                   application wrote it past the limits): the save fails (0x08000020), nothing kept. */
    CO_EV_RX_FILTER           /**< the COB-IDs the node takes changed (co_node_rx_ids): a port with hardware
                                   filters reprograms them, a runner of many nodes its frame routing. */
} co_event_kind_t;

typedef struct co_event {
    co_event_kind_t kind;
    uint16_t index;
    uint8_t sub;
    uint32_t value;
    uint32_t code;
} co_event_t;

/**
 * Device behaviour hooks. Each gets ctx = co_node_cfg_t.hooks_ctx. All are optional (NULL).
 * They run inside co_node_rx/co_node_process/co_od_* calls: they may read and write OD values with the
 * co_od_* functions of the same node, raise/clear EMCY, but must not call co_node_rx/co_node_process, nor
 * co_node_reset: a reset from a write hook would run before the SDO confirmation is sent (the boot-up first,
 * then the confirmation from the new node-ID) and the written value would land in the freshly reset OD.
 * Defer such work to the next co_node_process() call (a device model does it in its step()).
 */
/** The steps of a download of a large object (co_hooks_t.large_write). */
typedef enum co_large_step {
    CO_LARGE_BEGIN = 0, /**< A download starts: at = the size the client indicated, 0 when it gave none. */
    CO_LARGE_DATA = 1,  /**< len bytes of it at offset at, in order, from the start. */
    CO_LARGE_END = 2,   /**< It is complete: at = its length. Accept it (0: it is now the value) or refuse it. */
    CO_LARGE_ABORT = 3  /**< It ended without END (an abort, a timeout, a bad CRC, a reset): drop what came; the old
                             value stays. The answer is ignored. */
} co_large_step_t;

typedef struct co_hooks {
    /**
     * An object is about to be written (by SDO, RPDO or a co_od_write with CO_ORIGIN_LOCAL), after all of
     * the core's checks passed. Return 0 to accept (the value is then stored at once), or an SDO abort
     * code to refuse (e.g. CO_ABORT_VALUE_HIGH, CO_ABORT_DEVICE_STATE); RPDO refusals are dropped silently.
     * entry describes the one sub-index written (its index, sub, offset); for a sub-index inside a run it is a
     * copy that lives during the call only (co_od_find()): compare index and sub, not the pointer.
     */
    uint32_t (*on_write)(void *ctx, co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                         size_t len, co_od_origin_t origin);
    /**
     * An object is about to be read by SDO or sampled for a TPDO: refresh a live value here. Return 0, or
     * an SDO abort code to refuse an SDO read (e.g. CO_ABORT_NO_SUBINDEX for an entry this device variant
     * lacks); the code is ignored for TPDO sampling, so never hide PDO-mapped entries.
     */
    uint32_t (*on_read)(void *ctx, co_node_t *node, const co_od_entry_t *entry);
    /** The NMT state changed (after the change; boot-up reports INITIALISING -> PRE_OPERATIONAL). */
    void (*on_nmt_change)(void *ctx, co_node_t *node, co_nmt_state_t from, co_nmt_state_t to);
    /** An OD area was re-initialised from stored values/defaults (before the boot-up frame). */
    void (*on_reset)(void *ctx, co_node_t *node, co_reset_t what);
    /** Something worth logging happened. */
    void (*on_event)(void *ctx, co_node_t *node, const co_event_t *event);
    /**
     * A store is being made: 0x1010 save or 0x1011 restore (sub = the sub-index written), or LSS store
     * configuration (index 0x7E5, sub 0x17). The core has staged its own area and commits it last, so the
     * whole store becomes durable at once (co_port_t.nvm_commit): stage the device's own data of the same
     * store here (nvm_write, then nvm_commit with CO_NVM_MORE; the LSS area with co_lss_stage()) and return
     * CO_OK, or an error to fail the store (answer 0x06060000 or LSS error 2; the core discards what was
     * staged). Change the device's own state only when the outcome arrives (CO_EV_STORE / CO_EV_RESTORE
     * with code 0): the store can still fail after this hook.
     */
    co_status_t (*on_store)(void *ctx, co_node_t *node, uint16_t index, uint8_t sub);
    /**
     * on_read and on_write are called for objects from this index on only; 0: for every object. A device whose
     * hooks have rules for its own objects alone (0x2000 on) spares every access to a communication object two
     * indirect calls: a master's configuration of a node (heartbeat, PDO parameters, ...) is such accesses only.
     * Stored values being loaded are checked by on_write the same way (from this index on).
     */
    uint16_t first_index;
    /**
     * Large objects (CO_CONFIG_LARGE_OBJECTS): a row of type VISIBLE_STRING, OCTET_STRING, UNICODE_STRING or DOMAIN
     * whose size is 0 holds nothing in the values block; the application keeps its value, of any length, and these
     * two calls move it. An SDO transfer of it (segmented or block, with CRC) goes through them in pieces of at most
     * CO_SDO_BUF_SIZE bytes; co_od_read()/co_od_write() (an expedited transfer, the application's own access) in one
     * piece. on_read is called before a read as for any object; on_write is not (large_write takes the data and
     * decides). Such a row is not stored by 0x1010 and cannot be mapped. NULL: its reads and writes are refused
     * (0x06010000).
     * large_read: copies len bytes of the value from offset into buf and gives its length in *length; len 0: only the
     * length. Return 0 or an abort code (an upload ends with it), e.g. 0x08000024 when offset + len is past the end
     * (the value changed during an upload).
     */
    uint32_t (*large_read)(void *ctx, co_node_t *node, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                           size_t len, uint32_t *length);
    /**
     * large_write: a download in steps (co_large_step_t): BEGIN, DATA in order, then END or ABORT. Return 0, or an
     * abort code that ends the download: 0x06070012 for more than the object takes (at BEGIN when the size is
     * indicated, else at the DATA that goes beyond), 0x05040005 when there is no room. After a refused DATA, ABORT
     * follows; a refused BEGIN or END has dropped the download itself. A new value takes effect at END only: until
     * then reads give the old one.
     */
    uint32_t (*large_write)(void *ctx, co_node_t *node, const co_od_entry_t *entry, co_large_step_t step,
                            uint32_t at, const uint8_t *data, size_t len);
} co_hooks_t;

/** Options, per node (usually per device type). */
enum co_node_option {
    CO_OPT_NMT_ACCEPT_LONG = 0x01U,   /**< Accept NMT frames with DLC > 2 (extra bytes ignored). Default: DLC == 2 only. */
    CO_OPT_SDO_SEGMENTED = 0x02U,     /**< Segmented SDO transfer (needs CO_CONFIG_SDO_SEGMENTED). */
    CO_OPT_LSS_NO_UNCONFIGURE = 0x04U, /**< LSS configure node-ID refuses 0xFF (only 1..127), as Bürkert devices do. */
    CO_OPT_TPDO_NO_COS = 0x08U,        /**< Event-driven TPDOs go out on co_tpdo_trigger() and the event timer only,
                                            not when a mapped value changes (devices that send cyclically). */
    CO_OPT_NO_LSS = 0x10U,             /**< No LSS slave: LSS requests (0x7E5) are ignored (EDS LSS_Supported=0). */
    CO_OPT_SDO_BLOCK = 0x20U           /**< SDO block upload and download with CRC (needs CO_CONFIG_SDO_BLOCK). */
};

/** Number of entries of an LSS bit-timing table (CiA 305 indices 0..9). */
#define CO_LSS_BIT_TIMING_COUNT 10U

typedef struct co_node_cfg {
    const co_od_t *od;          /**< The device's generated object dictionary. */
    void *values;               /**< Caller-owned block of od->values_size bytes (this node's values). */
    const co_port_t *port;      /**< The port (send mandatory, the rest optional). */
    void *port_ctx;             /**< Passed to every port function. */
    const co_hooks_t *hooks;    /**< Device behaviour, or NULL. */
    void *hooks_ctx;            /**< Passed to every hook. */
    uint8_t node_id;            /**< Node-ID when none is stored by LSS: 1..127, or 0xFF (unconfigured). */
    uint8_t bit_timing;         /**< Bit-timing index when none is stored by LSS. */
    /** kbit/s per LSS bit-timing index (0 = not supported); NULL = the CiA 305 table without index 9. */
    const uint16_t *bit_rates_kbit;
    uint32_t options;           /**< co_node_option bits. */
    /**
     * PDO state for an OD with more PDOs than CO_RPDO_MAX/CO_TPDO_MAX (CiA 301 allows 512 each way): caller-owned
     * arrays of rpdo_count/tpdo_count entries, used instead of the node's own. NULL: the node's own arrays.
     */
    struct co_rpdo *rpdo;
    uint16_t rpdo_count;
    struct co_tpdo *tpdo;
    uint16_t tpdo_count;
    /**
     * Additional SDO servers (CiA 301: 0x1201..0x127F in the OD, each with its own COB-IDs and transfer state):
     * caller-owned array of sdo_server_count entries, at least one per such object. NULL/0 when the OD has none.
     */
    struct co_sdo_server *sdo_servers;
    uint8_t sdo_server_count;
    /**
     * The frame router's table (one entry per COB-ID the node takes) for a node whose PDO or SDO server arrays are
     * the caller's: at least CO_RX_ROUTES_FIXED + rpdo_count + sdo_server_count entries. NULL: the node's own
     * (CO_RX_ROUTES_FIXED + CO_RPDO_MAX entries, enough without caller-owned arrays).
     */
    struct co_rx_route *routes;
    uint16_t route_count;
} co_node_cfg_t;

/** What the last load of the parameter area found. */
typedef enum co_nvm_status {
    CO_NVM_NONE = 0,     /**< Nothing stored (or no storage): defaults used. */
    CO_NVM_LOADED = 1,   /**< Stored values loaded. */
    CO_NVM_CORRUPT = 2,  /**< A blob was there but its header, length or CRC is wrong: defaults used. */
    CO_NVM_FOREIGN = 3,  /**< A valid blob of another object dictionary: defaults used. */
    CO_NVM_REFUSED = 4   /**< A valid blob with a value its object refuses (CO_EV_NVM_REFUSED): defaults used. */
} co_nvm_status_t;

/* ---- Service state (read-only for the application) ------------------------------------------------ */

/** A frame waiting in the TX queue: the core sends only data frames with 11-bit CAN-IDs (12 bytes, not 16). */
typedef struct co_txq_frame {
    uint16_t id;
    uint8_t len;
    uint8_t data[8];
} co_txq_frame_t;

typedef struct co_txq {
    uint8_t head;
    uint8_t count;
    co_txq_frame_t frame[CO_TX_QUEUE_LEN];
} co_txq_t;

typedef struct co_hb_producer {
    co_time_us_t due;           /**< Next heartbeat, CO_NEVER when 0x1017 = 0. */
    uint16_t period_ms;         /**< 0x1017, kept here by the write path (no dictionary look-up per pass). */
} co_hb_producer_t;

typedef struct co_guard {
    uint8_t toggle;             /**< 0x00 or 0x80: bit 7 of the next guard reply. */
    bool armed;                 /**< A guard request was seen: life guarding runs. */
    bool failed;                /**< Life-guarding event raised, not yet cleared. */
    bool present;               /**< The OD has 0x100C and 0x100D (else guard requests are not answered). */
    uint8_t life_factor;        /**< 0x100D, kept here by the write path. */
    uint16_t guard_ms;          /**< 0x100C, kept here by the write path. */
    co_time_us_t deadline;      /**< Life-guarding deadline (or a step towards it: rest_ms). */
    uint32_t rest_ms;           /**< Life time still to wait after the deadline (long life times, src/priv/co_priv.h). */
} co_guard_t;

typedef struct co_hb_consumer_slot {
    co_time_us_t deadline;      /**< When the monitored heartbeat is late. */
    uint8_t node_id;            /**< 0 = slot unused. */
    uint8_t state;              /**< 0 unused, 1 waiting for the first heartbeat, 2 monitoring, 3 timed out. */
    uint8_t remote_state;       /**< Last NMT state byte received from that node. */
    uint16_t time_ms;           /**< Consumer time of its 0x1016 entry. */
} co_hb_consumer_slot_t;

typedef struct co_hb_consumer {
    uint8_t count;              /**< Slots in use = sub-indices of 0x1016 (capped at CO_HB_CONSUMER_MAX). */
    uint8_t used;               /**< 1 + the last slot that monitors a node (0: none): the loops stop there. */
    uint8_t monitored[16];      /**< Bit n: node-ID n is monitored by some slot (a heartbeat of another node
                                     is rejected without a loop). */
    co_hb_consumer_slot_t slot[CO_HB_CONSUMER_MAX];
} co_hb_consumer_t;

typedef struct co_emcy_error {
    uint16_t code;
    uint8_t reg;                /**< Error register bits this error sets. */
    uint8_t msef[5];            /**< Manufacturer-specific error field sent with it. */
} co_emcy_error_t;

typedef struct co_emcy {
    uint8_t n_active;
    uint8_t q_head;
    uint8_t q_count;
#if CO_CONFIG_EMCY_INHIBIT
    uint16_t inhibit_100us;     /**< 0x1015, kept here by the write path. */
    co_time_us_t next_allowed;  /**< Inhibit time 0x1015: earliest time of the next EMCY. */
#endif
    uint32_t lost;              /**< EMCY frames dropped because the queue was full. */
    uint32_t cob_id;            /**< 0x1014 (or 0x80 + node-ID without it), kept here by the write path. */
    co_emcy_error_t active[CO_EMCY_ACTIVE_MAX];
    uint8_t queue[CO_EMCY_QUEUE_LEN][8]; /**< The 8 bytes of each EMCY waiting (its COB-ID is taken at sending). */
} co_emcy_t;

/** A CAN-ID field that holds no CAN-ID (an object the OD lacks, a COB-ID not valid). */
#define CO_NO_CAN_ID 0xFFFFU
/** co_sdo_server_t.rx_id of a server whose COB-IDs are not both valid (it takes no request). */
#define CO_SDO_NO_ID CO_NO_CAN_ID

typedef struct co_sdo_server {
    uint8_t state;              /**< 0 idle, 1 segmented download, 2 segmented upload, 3.. block (co_sdo_block.c). */
    uint8_t toggle;
    uint8_t sub;
    uint16_t index;
    uint16_t param_index;       /**< Its server SDO parameter object: 0x1200 (the default server), 0x1201.. */
    uint16_t rx_id;             /**< CAN-ID of requests (client to server), CO_SDO_NO_ID while not valid. */
    uint16_t tx_id;             /**< CAN-ID of responses (server to client). */
    uint32_t size;              /**< Bytes of the transfer (download: indicated, or 0 if not). */
    uint32_t pos;               /**< Segmented: bytes moved. Block download: 7 per segment received; block
                                     upload: bytes the client acknowledged (start of the current block). */
    uint8_t seq;                /**< Block: last sequence number received (download) or sent (upload). */
    uint8_t blksize;            /**< Block: segments per block, 1..127. */
    bool crc;                   /**< Block: both sides use the CRC. */
#if CO_CONFIG_LARGE_OBJECTS
    bool large;                 /**< The transfer's object is a large one (co_hooks_t.large_read): the buffer holds
                                     a piece of it. */
    uint16_t crc_value;         /**< Large block download: the CRC of the bytes handed over so far. */
    uint32_t done;              /**< Large download: bytes handed to large_write so far. */
#endif
    co_time_us_t deadline;
    uint8_t buf[CO_SDO_BUF_SIZE];
} co_sdo_server_t;

typedef struct co_sync {
    co_time_us_t due;           /**< A consumer's timeout, 1.5 x 0x1006 after the last SYNC; a producer's next SYNC (or
                                     a step towards either: rest_ms); CO_NEVER: none (yet). */
    uint32_t rest_ms;           /**< Time still to wait after due (periods above 11 minutes). */
    uint32_t period_us;         /**< 0x1006, kept here by the write path. */
    uint16_t can_id;            /**< CAN-ID of 0x1005, CO_NO_CAN_ID without the object. */
    uint8_t overflow;           /**< 0x1019 (0: SYNC without a counter). */
    bool timeout_error;
    bool length_error;
#if CO_CONFIG_SYNC_PRODUCER
    bool producer;              /**< 0x1005 bit 30: this node produces the SYNC (and takes none from the bus). */
    uint8_t counter;            /**< The counter of the last SYNC produced (0x1019 > 0), 0 before the first. */
#endif
} co_sync_t;

/** co_pdo_map_t.row of a dummy entry (RPDO): its bytes are skipped. */
#define CO_PDO_MAP_DUMMY 0xFFFFU

typedef struct co_pdo_map {
    uint16_t row;               /**< The mapped object's row in co_od_t.entries, or CO_PDO_MAP_DUMMY. */
    uint8_t len;                /**< Bytes. */
    uint8_t k;                  /**< Which of the row's sub-indices (0 unless the row is a run). */
} co_pdo_map_t;

typedef struct co_rpdo {
    uint8_t n_map;
    uint8_t map_len;            /**< Mapped bytes. */
    uint8_t type;
    bool valid;                 /**< COB-ID valid and mapping non-empty. */
    bool length_error;
#if CO_CONFIG_PDO_TIMERS
    bool timeout_error;         /**< EMCY 0x8250 active: no RPDO within its event time. */
#endif
#if CO_CONFIG_SYNC
    bool sync_pending;          /**< Synchronous RPDO received, applied at the next SYNC. */
#endif
#if CO_CONFIG_MPDO
    uint8_t mpdo;               /**< 0, or the MPDO kind of its mapping: 0xFE SAM (dispatching list), 0xFF DAM. */
    bool mpdo_error;            /**< A DAM-MPDO's object could not be written (EMCY 0x8230 active). */
#endif
#if CO_CONFIG_PDO_TIMERS
    uint16_t event_ms;          /**< Its event timer (sub 5): reception deadline monitoring, 0 = off. */
#endif
    uint32_t cob_id;            /**< 0x1400+n sub 1 as configured. */
#if CO_CONFIG_PDO_TIMERS
    co_time_us_t deadline;      /**< Event-timer deadline monitoring, CO_NEVER when off. */
#endif
    co_pdo_map_t map[8];
#if CO_CONFIG_SYNC
    uint8_t sync_data[8];       /**< Its map_len bytes. */
#endif
} co_rpdo_t;

typedef struct co_tpdo {
    uint8_t n_map;
    uint8_t map_len;
    uint8_t type;
    bool valid;
    bool sent_once;             /**< last[] holds what was sent last. */
    bool event;                 /**< Application event (co_tpdo_trigger) or a change waiting for the inhibit time. */
#if CO_CONFIG_SYNC
    uint8_t sync_start;
    uint8_t sync_count;         /**< SYNCs since the last synchronous transmission. */
    bool sync_started;          /**< The SYNC start value was reached (or none is set). */
#endif
#if CO_CONFIG_MPDO
    uint8_t mpdo;               /**< 0, or 0xFE: a SAM-MPDO producer of the object scanner list. */
    uint16_t scan_next;         /**< SAM-MPDO: position in the scanner list of the next object to send. */
#endif
    uint32_t cob_id;
#if CO_CONFIG_PDO_TIMERS
    co_time_us_t next_allowed;  /**< End of the inhibit time. */
    co_time_us_t event_due;     /**< Event timer, CO_NEVER when off. */
    uint32_t inhibit_us;
    uint32_t event_us;
#endif
    co_pdo_map_t map[8];
    uint8_t last[8];            /**< What was sent last; type 252: what the last SYNC sampled (sent_once: there is). */
} co_tpdo_t;

typedef struct co_lss_slave {
    uint8_t state;              /**< 0 waiting, 1 configuration. */
    uint8_t pending_node_id;
    uint8_t pending_bit_timing;
    uint8_t active_bit_timing;
    uint8_t select_step;        /**< Switch-state-selective: next expected cs 0x40..0x43. */
    uint8_t ident_step;         /**< Identify remote slave: next expected cs 0x46..0x4B (0 also after a mismatch). */
    uint8_t fastscan_pos;       /**< LSSSub the slave expects next. */
    bool switch_pending;        /**< Activate bit timing in progress. */
    uint32_t ident_low;
    co_time_us_t switch_at;
    co_time_us_t silent_until;  /**< No frame is sent before this time (activate bit timing). */
} co_lss_slave_t;

/** Kinds of received frames (co_rx_route_t.target >> 12). */
enum co_rx_kind {
    CO_RX_LSS = 0,   /**< 0x7E5. */
    CO_RX_NMT = 1,   /**< 0x000. */
    CO_RX_SYNC = 2,  /**< 0x1005. */
    CO_RX_SDO = 3,   /**< An SDO server's requests; n = 0 the default server, 1.. the additional ones. */
    CO_RX_RPDO = 4   /**< RPDO n (0-based). */
};

/** One COB-ID the node takes (a data frame): the frame router's table, sorted by id, one entry per id. */
typedef struct co_rx_route {
    uint16_t id;                /**< 11-bit CAN-ID. */
    uint16_t target;            /**< co_rx_kind << 12 | n. */
} co_rx_route_t;

/** Routes of the fixed services (LSS, NMT, SYNC, the default SDO server) in a route table. */
#define CO_RX_ROUTES_FIXED 4U

typedef struct co_node_stats {
    uint32_t rx_frames;
    uint32_t tx_frames;
    uint32_t tx_dropped;        /**< Frames lost: queue full or the port reported CO_ERR_IO. */
    uint32_t tx_suppressed;     /**< Frames not sent during the LSS bit-rate switch silence. */
    uint32_t sdo_aborts;
} co_node_stats_t;

struct co_node {
    /* Ordered for small targets: the fields most code touches first, so that Thumb-1 and AVR reach them with a short
     * immediate offset (bytes below 32, halfwords below 64, words below 128 on Cortex-M0+); large arrays last. */
    uint8_t node_id;            /**< Active node-ID, 0xFF while unconfigured. */
    uint8_t wake;               /**< Services whose state changed since they last ran (a frame taken, an API call;
                                     bits in src/priv/co_priv.h): the next co_node_process() runs them, and the
                                     services whose deadline came once next_due has. 0: it returns next_due at
                                     once. */
    bool cos_pending;           /**< A TPDO-mappable value was written: event-driven TPDOs compare what they
                                     would send with what they sent last at the next pass. */
    uint8_t n_sdo_extra;        /**< Additional servers the OD declares. */
    uint8_t default_node_id;
    uint8_t default_bit_timing;
    uint16_t n_rpdo;            /**< PDOs the OD declares (1 + the highest 0x1400+n / 0x1800+n present). */
    uint16_t n_tpdo;
    uint16_t rpdo_cap;          /**< Entries of rpdo[] / tpdo[]: co_node_cfg_t's arrays, or the node's own. */
    uint16_t tpdo_cap;
    uint16_t n_route;           /**< Entries of route[] in use. */
    uint16_t route_cap;
    uint16_t rx_ids_version;    /**< Changes whenever co_node_rx_ids() may answer differently (with each
                                     CO_EV_RX_FILTER): a port that polls it needs no event hook. */
    co_nmt_state_t nmt_state;
    co_nvm_status_t nvm_status;
    co_time_us_t now;           /**< Time of the call in progress (co_node_rx / co_node_process / API). */
    co_time_us_t next_due;      /**< The earliest deadline of any service (svc_due), as the last
                                     co_node_process() returned it or a timer moved it since. */
    const co_od_t *od;
    uint8_t *values;
    const co_port_t *port;
    void *port_ctx;
    const co_hooks_t *hooks;
    void *hooks_ctx;
    const uint16_t *bit_rates_kbit;
    uint32_t options;
    co_rpdo_t *rpdo;            /**< co_node_cfg_t.rpdo, or rpdo_own. */
    co_tpdo_t *tpdo;
    co_sdo_server_t *sdo_extra; /**< co_node_cfg_t.sdo_servers: the servers of 0x1201.. present in the OD. */
    co_rx_route_t *route;       /**< co_node_cfg_t.routes, or route_own. */
    co_hb_producer_t hb;
#if CO_CONFIG_NODE_GUARDING
    co_guard_t guard;
#endif
#if CO_CONFIG_SYNC
    co_sync_t sync;
#endif
    co_lss_slave_t lss;
    uint8_t route_hash[16];     /**< Per CO_ROUTE_HASH(id): 0 no route has it, 1 + the entry of the only one, 0xFF
                                     several (then the table is searched): most frames for others end here. */
    co_node_stats_t stats;
    co_emcy_t emcy;
    co_txq_t txq;
    co_sdo_server_t sdo;        /**< The default SDO server (0x1200: 0x600/0x580 + node-ID). */
#if CO_CONFIG_HB_CONSUMER
    co_hb_consumer_t hbc;
#endif
    co_time_us_t svc_due[8];    /**< Each service's deadline (src/priv/co_priv.h: co_service_index), as it last
                                     ran or a timer moved it: a pass at next_due runs only the services due. */
    co_rpdo_t rpdo_own[CO_RPDO_MAX];
    co_tpdo_t tpdo_own[CO_TPDO_MAX];
    co_rx_route_t route_own[CO_RX_ROUTES_FIXED + CO_RPDO_MAX];
};

/**
 * Powers the node on: loads the LSS configuration and stored parameters through the port, initialises
 * every object, and (when the node-ID is configured) sends the boot-up frame and enters Pre-operational.
 * An unconfigured node (0xFF) runs only the LSS slave until a master gives it a node-ID.
 * @return CO_OK, CO_ERR_ARG (NULL pointers, node-ID 0 or 128..254, no send function, an OD whose object_slots
 *         are set with object_slot_bits outside 1..17), CO_ERR_RANGE (the
 *         OD declares more PDOs than the PDO arrays hold (co_node_cfg_t.rpdo/tpdo, else CO_RPDO_MAX/CO_TPDO_MAX),
 *         more additional SDO servers than co_node_cfg_t.sdo_servers holds, more heartbeat-consumer entries
 *         than co_config.h allows, or PDO timer sub-indices with CO_CONFIG_PDO_TIMERS 0).
 */
co_status_t co_node_init(co_node_t *node, const co_node_cfg_t *cfg, co_time_us_t now);

/**
 * Feeds one received frame (with its arrival time). Frames for other nodes/services are ignored: most in a few
 * instructions (a hash of the COB-IDs the node takes), the others after a search of its table (O(log COB-IDs)).
 * @return true when the frame concerned this node (NMT, LSS, its SDO/RPDO/SYNC/guarding COB-IDs, a consumed
 *         heartbeat): call co_node_process() before sleeping, as the frame may have changed the next deadline
 *         or queued an answer. false: the frame was ignored and the last deadline still holds, so a runner
 *         with many nodes on one bus may skip processing this node (calling it anyway is always correct).
 */
bool co_node_rx(co_node_t *node, const co_frame_t *frame, co_time_us_t now);

/**
 * Runs the timed services and sends what is due. Never blocks. Runs the services whose deadline has come and those
 * a frame or an API call changed, nothing at all (a few instructions) when neither happened.
 * @return the absolute time when it must be called again at the latest (CO_NEVER if nothing is pending); it may be
 *         earlier than needed (a pass then finds nothing to do), or now itself (call again at once: a hook marked a
 *         service the pass had already run).
 */
co_time_us_t co_node_process(co_node_t *node, co_time_us_t now);

/**
 * True when co_node_process() would do nothing now and return `deadline`, the deadline it last returned: no service
 * was marked, no frame waits in the TX queue and no deadline moved forward since. For a runner of many nodes: a frame
 * that concerned a node (co_node_rx() true) may have been handled whole inside co_node_rx(), e.g. an expedited SDO
 * request answered at once; the runner may then skip that node's pass. Calling co_node_process() anyway is always
 * correct; a runner that does not keep the deadline need not ask.
 */
static inline bool co_node_settled(const co_node_t *node, co_time_us_t deadline)
{
    /* co_node_process's early return, for the deadline it gave: only co_node_due() lowers next_due between passes.
     * Inline: a runner asks it for every frame a node took. */
    return node->wake == 0U && node->txq.count == 0U && node->next_due == deadline;
}

/**
 * The CAN-IDs of the frames this node takes, sorted: data frames of its services (LSS, NMT, SYNC, SDO servers,
 * RPDOs), the heartbeats it consumes, its node-guarding request (a remote frame on 0x700 + node-ID, when the
 * OD has node guarding) and the remote requests of its TPDOs that answer them (CO_CONFIG_TPDO_RTR: valid, COB-ID bit
 * 30 clear, type 252..255; only remote frames are taken on these). co_node_rx() ignores every other frame, so a port
 * may filter on these in hardware and a runner of many nodes may give a frame only to the nodes that take it. Changes
 * are reported with CO_EV_RX_FILTER and change co_node_t.rx_ids_version. @return the number of IDs (at most route
 * entries + 127 + the TPDOs); at most cap are written.
 */
uint16_t co_node_rx_ids(const co_node_t *node, uint16_t *ids, uint16_t cap);

/**
 * The application wrote process values around co_od_write() (through the generated values struct or
 * co_od_value()'s pointer): event-driven TPDOs compare what they would send with what they sent last at the next
 * co_node_process(). Cheap: call it after every batch of such writes.
 */
void co_node_values_changed(co_node_t *node);

/** Performs a reset as NMT 0x81 (CO_RESET_APPLICATION) or 0x82 (CO_RESET_COMMUNICATION) would. */
void co_node_reset(co_node_t *node, co_reset_t what, co_time_us_t now);

/** Current NMT state. */
co_nmt_state_t co_node_state(const co_node_t *node);

/** Active node-ID (0xFF while unconfigured). */
uint8_t co_node_id(const co_node_t *node);

/** Name of an NMT state for logs: "INITIALISING", "STOPPED", "OPERATIONAL", "PRE-OPERATIONAL" (else "UNKNOWN"). */
const char *co_nmt_state_name(co_nmt_state_t state);

/**
 * Raises an error: sets its bits in 0x1001 (bit 0 always), records it in 0x1003 (newest first) and sends
 * an EMCY frame `code | 0x1001 | msef[0..4]` (subject to the inhibit time 0x1015; queued while Stopped).
 * Raising an error that is already active (same code and msef[0..1]) does nothing.
 * @param msef 5 manufacturer-specific bytes, or NULL for zeros.
 * @return false if the active list is full or code is 0x0000 (the error-reset code is never an error).
 */
bool co_emcy_raise(co_node_t *node, uint16_t code, uint8_t reg_bits, const uint8_t *msef);

/**
 * Clears an active error (same code and msef[0..1]); sends the error-reset EMCY `0x0000 | 0x1001 | msef`
 * with the error register of the errors that remain. @return false when no such error was active.
 */
bool co_emcy_clear(co_node_t *node, uint16_t code, const uint8_t *msef);

/** True when an error with this code (any msef) is active. */
bool co_emcy_is_active(const co_node_t *node, uint16_t code);

/** Asks TPDO n (0-based) to be sent: at once for event-driven types (inhibit time permitting), at the next SYNC for type 0. */
void co_tpdo_trigger(co_node_t *node, uint16_t n);

/** Sets the pending node-ID (as LSS configure node-ID does); it becomes active at the next communication reset. */
bool co_lss_set_pending_node_id(co_node_t *node, uint8_t node_id);

/** Sets the pending bit-timing index (as LSS configure bit timing does); false if the device's table lacks it. */
bool co_lss_set_pending_bit_timing(co_node_t *node, uint8_t index);

/**
 * Stores the pending node-ID and bit timing as LSS store configuration does (area CO_NVM_LSS), for devices
 * whose own objects are the same setting (e.g. Bürkert 0x2001:01/02). CO_ERR_IO without NVM or on failure.
 */
co_status_t co_lss_store(co_node_t *node);

/**
 * Stages the LSS area with this node-ID and bit-timing index as one area of the store in progress (committed
 * with CO_NVM_MORE): for an on_store hook whose device keeps the LSS configuration in objects of its own
 * (Eltex 0x2002:06/07). The pending values do not change. CO_ERR_IO without NVM or on failure.
 */
co_status_t co_lss_stage(co_node_t *node, uint8_t node_id, uint8_t bit_timing);

/**
 * Makes the pending bit timing the active one at once, as LSS activate bit timing does after its delay
 * (port set_bit_rate, CO_EV_LSS_ACTIVATE), for devices whose own object switches the bit rate at a reset
 * (e.g. Eltex 0x2002:07): call it from on_reset(CO_RESET_COMMUNICATION), before the boot-up.
 * @return CO_ERR_ARG if the pending index is not in the device's table.
 */
co_status_t co_lss_apply_bit_timing(co_node_t *node);

#ifdef __cplusplus
}
#endif
#endif /* CO_NODE_H */
