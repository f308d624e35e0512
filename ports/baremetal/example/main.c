/*
 * Example main loop of a bare-metal node on the reference port (ports/baremetal). Compiles without any
 * vendor SDK: the board_* functions are what a real board implements (see docs/porting.md for bxCAN,
 * FDCAN, MCAN and TWAI). Built (not linked) by every cross build as a compile check.
 */
#include "co_bm_port.h"
#include "sds_od.h" /* the generated object dictionary of the device this node is (tools/odgen.py) */

/* ---- What the board provides (declared here, defined in the board's files) ---------------------- */
uint32_t board_timer_read(void *ctx);                          /* free-running 32-bit 1 MHz counter */
co_status_t board_can_send(void *ctx, const co_frame_t *frame); /* free TX mailbox or CO_ERR_BUSY */
co_status_t board_can_set_bit_rate(void *ctx, uint32_t kbit);
/* acceptance filters: exactly these CAN-IDs, or (ids == NULL) every frame */
co_status_t board_can_set_filters(void *ctx, const uint16_t *ids, uint16_t n);
co_status_t board_flash_erase(void *ctx, uint32_t page_addr);
co_status_t board_flash_program(void *ctx, uint32_t addr, const void *data, size_t len);
co_status_t board_flash_read(void *ctx, uint32_t addr, void *data, size_t len);
void board_can_start(void);                                   /* bit rate, RX interrupt on */
void board_wait_for_event(co_time_us_t now, co_time_us_t deadline, co_bm_clock_t *clock); /* WFI + timer */

/* ---- Static storage: the node, its values, the port ----------------------------------------------- */
static co_node_t node;
static sds_od_values_t values;
static co_bm_port_t port;
static co_bm_clock_t clock_us;
static co_bm_nvm_t nvm;
static uint8_t nvm_stage[512];

static const co_bm_can_t can = {.send = board_can_send, .set_bit_rate = board_can_set_bit_rate,
                                 .set_filters = board_can_set_filters};
/* 2 KiB pages (e.g. STM32G4), 8-byte program unit, the last 12 pages of a 128 KiB part. */
static const co_bm_flash_t flash = {board_flash_erase, board_flash_program, board_flash_read, NULL, 2048U, 8U, 0xFFU};
static const co_bm_nvm_area_t areas[CO_BM_NVM_AREAS] = {
    {{0x0801A000UL, 0x0801B000UL}, 4096U}, /* CO_NVM_PARAMS: 2 x 2 pages */
    {{0x0801C000UL, 0x0801C800UL}, 2048U}, /* CO_NVM_LSS */
    {{0x0801D000UL, 0x0801E000UL}, 4096U}, /* CO_NVM_DEVICE */
};

/* The CAN receive interrupt calls this for every frame it takes out of the controller's FIFO. */
void board_on_can_frame(const co_frame_t *frame);
void board_on_can_frame(const co_frame_t *frame) { (void)co_bm_port_rx_isr(&port, frame); }

int main(void)
{
    co_bm_clock_init(&clock_us, board_timer_read, NULL, 1000000UL, 32U, 0U);
    const bool have_nvm = co_bm_nvm_init(&nvm, &flash, areas, nvm_stage, sizeof nvm_stage) == CO_OK;
    co_bm_port_init(&port, &can, have_nvm ? &nvm : NULL, &clock_us);
    /* Designated fields: members added to co_node_cfg_t later (zero = not used) need no change here. */
    const co_node_cfg_t cfg = {.od = &sds_od, .values = &values, .port = &port.port, .port_ctx = &port,
                               .node_id = 0x10U, .bit_timing = 4U /* 125 kbit/s */, .options = CO_OPT_NMT_ACCEPT_LONG};
    if (co_node_init(&node, &cfg, co_bm_clock_now(&clock_us)) != CO_OK) {
        for (;;) {
        }
    }
    board_can_start(); /* frames arrive from here on */
    for (;;) {
        const co_time_us_t next = co_bm_port_poll(&port, &node);
        /* Application: measure, then co_od_set_*(&node, ...); change-of-state TPDOs go at the next poll. */
        board_wait_for_event(co_bm_clock_now(&clock_us), next, &clock_us);
    }
}
