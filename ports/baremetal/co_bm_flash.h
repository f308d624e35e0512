/*
 * The flash interface the NVM layer (co_bm_nvm.h) needs: three functions, no registers, no vendor SDK.
 * Implement them with the MCU's flash driver (HAL_FLASHEx_Erase/HAL_FLASH_Program on STM32,
 * esp_partition_erase_range/esp_partition_write on ESP-IDF, the ROM API on others) or over an external
 * SPI NOR chip. Addresses are whatever the implementation understands (absolute or partition offsets).
 *
 * Semantics assumed (NOR flash; they hold for internal MCU flash and SPI NOR alike):
 *  - erase(addr) sets every byte of the page that starts at addr to `erased` (0xFF for almost all parts).
 *  - program(addr, data, len): addr and len are multiples of prog_unit; each unit is programmed at most
 *    once between erases (ECC flash such as STM32L4/G4/H7 forbids a second write).
 *  - read(addr, data, len): any address and length.
 *  - Each may take milliseconds and may stall the CPU (code running from the same bank). They are called
 *    only from inside co_node_rx()/co_node_process() (a store request), i.e. from the main loop.
 *  - A power cut during erase or program leaves that page or unit in an undefined state; the NVM layer
 *    never depends on it (tests/test_bm_nvm.c cuts power at every step).
 * Each returns CO_OK or CO_ERR_IO.
 */
#ifndef CO_BM_FLASH_H
#define CO_BM_FLASH_H

#include "co/co_types.h"
#include "co/co_port.h"

typedef struct co_bm_flash {
    co_status_t (*erase)(void *ctx, uint32_t page_addr);
    co_status_t (*program)(void *ctx, uint32_t addr, const void *data, size_t len);
    co_status_t (*read)(void *ctx, uint32_t addr, void *data, size_t len);
    void *ctx;
    uint32_t page_size;  /**< Erase granularity in bytes (e.g. 2048 on STM32F0/G4, 4096 on SPI NOR). */
    uint32_t prog_unit;  /**< Program granularity in bytes: 1, 2, 4, 8 (STM32L4/G4), 16 or 32 (STM32H7). */
    uint8_t erased;      /**< Value of an erased byte (0xFF). */
} co_bm_flash_t;

#endif /* CO_BM_FLASH_H */
