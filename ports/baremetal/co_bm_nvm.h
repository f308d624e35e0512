/*
 * Power-safe storage of the core's NVM areas (co_port_t nvm_write/nvm_commit/nvm_read) in flash: two
 * slots per area, each blob with a sequence number and a CRC-32, the newest valid slot wins.
 *
 * Slot layout: header (16 bytes, padded to prog_unit) then the blob.
 *   header = magic "CoBM" | sequence (u32) | blob length (u32) | CRC-32 of (sequence, length, blob)
 * A commit erases the *other* slot (never the valid one), programs the blob, and programs the header
 * last. A power cut at any step leaves the old slot untouched and the new one without a valid header
 * (erased, half-programmed or with a CRC that does not match), so the next load finds either the old
 * blob or, once the header is complete, the new one; never a mix and never neither.
 *
 * RAM: nvm_write() stages the blob in a caller-provided buffer (the core writes a blob in pieces, in any
 * order, then commits), so the buffer must hold the largest blob: CO_NVM_PARAMS is 16 bytes of the
 * core's header plus, per stored object, 4 bytes + its size (a few hundred bytes for the shipped
 * devices); CO_NVM_LSS is 12 bytes. One buffer serves all areas (the core commits one area before it
 * writes the next).
 */
#ifndef CO_BM_NVM_H
#define CO_BM_NVM_H

#include "co_bm_flash.h"

#define CO_BM_NVM_AREAS 3U    /**< CO_NVM_PARAMS, CO_NVM_LSS, CO_NVM_DEVICE. */
#define CO_BM_NVM_HEADER 16U  /**< Slot header bytes before padding to prog_unit. */

/** Where one area lives: two slots of slot_size bytes each, page-aligned, not overlapping. */
typedef struct co_bm_nvm_area {
    uint32_t slot_addr[2];   /**< 0 slot_size = area not stored (reads answer CO_ERR_NO_DATA). */
    uint32_t slot_size;      /**< Multiple of page_size; >= padded header + largest blob. */
} co_bm_nvm_area_t;

typedef struct co_bm_nvm {
    const co_bm_flash_t *flash;
    co_bm_nvm_area_t area[CO_BM_NVM_AREAS];
    uint8_t *stage;          /**< Staging buffer for nvm_write. */
    uint32_t stage_size;
    int8_t stage_area;       /**< Area being staged, -1 none. */
    /* What the last scan found per area (kept up to date by commits). */
    int8_t active[CO_BM_NVM_AREAS];   /**< Valid slot with the newest sequence, -1 none. */
    uint32_t seq[CO_BM_NVM_AREAS];
    uint32_t len[CO_BM_NVM_AREAS];
} co_bm_nvm_t;

/**
 * Sets up the layer and scans every area's two slots (reads and checks both CRCs). Call at power-on,
 * before co_node_init(). CO_ERR_ARG when a slot is not page-aligned, too small or the staging buffer
 * is NULL; CO_ERR_IO when the flash cannot be read.
 */
co_status_t co_bm_nvm_init(co_bm_nvm_t *nvm, const co_bm_flash_t *flash, const co_bm_nvm_area_t area[CO_BM_NVM_AREAS],
                           uint8_t *stage, uint32_t stage_size);

/* The co_port_t contract (include/co/co_port.h), with ctx = the co_bm_nvm_t. */
co_status_t co_bm_nvm_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len);
co_status_t co_bm_nvm_commit(void *ctx, co_nvm_area_t area, uint32_t total_len);
co_status_t co_bm_nvm_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len);

/** CRC-32 (IEEE 802.3, reflected, as zlib), continued from crc (start with 0). */
uint32_t co_bm_crc32(uint32_t crc, const uint8_t *data, size_t len);

#endif /* CO_BM_NVM_H */
