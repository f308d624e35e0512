/**
 * @file co_port.h
 * @brief The port: what the core needs from the platform (a CAN controller, non-volatile memory, a bit rate).
 *
 * Every function gets the ctx pointer given in co_node_cfg_t.port_ctx, so one port implementation can serve
 * many nodes, buses or storage files. The core calls these functions only from co_node_init(),
 * co_node_rx() and co_node_process() (and the co_* API functions), never from anywhere else; a port
 * needs no locking as long as those are called from one context.
 */
#ifndef CO_PORT_H
#define CO_PORT_H

#include "co_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Non-volatile storage areas. Each area holds one blob that the core replaces as a whole. */
typedef enum co_nvm_area {
    CO_NVM_PARAMS = 0, /**< Object values saved with 0x1010 (a few hundred bytes for the shipped devices). */
    CO_NVM_LSS = 1,    /**< LSS configuration: node-ID and bit-timing index (12 bytes). */
    CO_NVM_DEVICE = 2  /**< The device model's own data (e.g. operating-hour counters); never used by the core. */
} co_nvm_area_t;

/**
 * CRC-32 (IEEE 802.3, reflected, the zlib/PNG one) over len bytes, continuing from crc (0 to start). The core
 * checks its NVM blobs with it; ports and device models may use it for their own data. Bitwise, no table.
 */
uint32_t co_crc32(uint32_t crc, const uint8_t *data, size_t len);

/** nvm_commit() total_len flag: more areas of the same store follow (see co_port_t.nvm_commit). */
#define CO_NVM_MORE ((uint32_t)0x80000000UL)
/** nvm_commit() total_len flag: a save of the device model's own data that no answer waits for (see
 *  co_port_t.nvm_commit); the port may make it durable later. */
#define CO_NVM_BACKGROUND ((uint32_t)0x40000000UL)
/** The flags of nvm_commit()'s total_len: total_len & ~CO_NVM_FLAGS is the blob's length. */
#define CO_NVM_FLAGS (CO_NVM_MORE | CO_NVM_BACKGROUND)
/** nvm_commit() total_len: the store in progress is abandoned; its pending areas keep their old blobs. */
#define CO_NVM_DISCARD ((uint32_t)0xFFFFFFFFUL)

typedef struct co_port {
    /**
     * Sends one frame. Must not block. Return CO_OK when the frame is queued in the controller or the
     * OS, CO_ERR_BUSY when there is no room now (the core keeps the frame and calls again at the next
     * co_node_process(); the frame is not lost), CO_ERR_IO when it can never be sent (the frame is
     * dropped and counted in co_node_t.stats.tx_dropped). Mandatory.
     */
    co_status_t (*send)(void *ctx, const co_frame_t *frame);

    /**
     * Writes len bytes at offset into the staging copy of an area. A sequence of writes followed by
     * nvm_commit() replaces the area; a sequence without a commit must leave the stored blob as it was.
     * NULL when the device has no storage: 0x1010 then answers 0x06060000 and LSS store answers "not
     * supported".
     */
    co_status_t (*nvm_write)(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len);

    /**
     * Makes the staged blob of total_len bytes the area's content, atomically and durably: when it returns
     * CO_OK the new blob survives a power loss; after a power loss at any moment, a later nvm_read() sees
     * either the whole old blob or the whole new one. On an error the area keeps its old blob. The core
     * answers a store (0x1010, LSS store) only after this returned, with its result.
     *
     * One store may span several areas (an Eltex 0x1010 save: parameters, LSS configuration and device data).
     * Then every area but the last is committed with CO_NVM_MORE set in total_len, and the last without it:
     * a port that can, keeps the CO_NVM_MORE areas pending and makes them durable together with the last one,
     * all or none (the result of the last commit is the store's). A store abandoned after CO_NVM_MORE commits
     * ends with total_len == CO_NVM_DISCARD: every pending area keeps its old blob. A port that cannot group
     * areas commits a CO_NVM_MORE area on its own (mask the flag off) and ignores CO_NVM_DISCARD; a store of
     * several areas is then only atomic per area.
     *
     * CO_NVM_BACKGROUND in total_len (never with CO_NVM_MORE; the core never sets it): a device model's save of
     * its own data (CO_NVM_DEVICE: an operating-time counter, a drag indicator) that no answer waits for. The port
     * may return before the blob is durable and make it durable later (the kernel's asynchronous I/O, an idle
     * moment), each area's blobs in the order committed; a later nvm_read() sees the newest blob at once, and a
     * commit without the flag (a store someone waits for) of the same node lands after it. A background write that
     * fails leaves the area's old blob and is reported by that commit when found before it returns, else by a
     * later commit of that area (the port says which: the Linux files, the next background commit). A port that
     * cannot write later masks the flag off and commits at once, as it does when a store of several areas is open
     * (it then ends that store, as any commit without CO_NVM_MORE).
     * NULL with nvm_write.
     */
    co_status_t (*nvm_commit)(void *ctx, co_nvm_area_t area, uint32_t total_len);

    /**
     * Reads len bytes at offset from the committed blob of an area. CO_ERR_NO_DATA when nothing is
     * stored or the blob is shorter than offset + len; a port that can tell the two apart should answer
     * CO_ERR_IO for a blob that is there but too short (e.g. an empty file), so that it counts as damaged.
     * The core checks its own header and CRC, so a damaged blob is detected by the core
     * (co_node_t.nvm_status, CO_EV_NVM_LOADED). NULL: nothing is ever stored.
     */
    co_status_t (*nvm_read)(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len);

    /**
     * Switches the CAN controller to a new bit rate (LSS activate bit timing, or a stored LSS bit timing
     * at power-on). NULL when the bit rate is fixed; the core then only records the value.
     */
    co_status_t (*set_bit_rate)(void *ctx, uint32_t kbit_per_s);
} co_port_t;

#ifdef __cplusplus
}
#endif
#endif /* CO_PORT_H */
