/*
 * Freestanding link check (tools/size-report): the core and one device's object dictionary linked with
 * -nostdlib and only libgcc, with the four C library functions the core may use defined here. A link
 * error means the core needs something else from the C library. The image's size is also the flash a
 * node of that device costs (core + tables), without the application and the port.
 * CO_CHECK_OD names the device's co_od_t (e.g. sds_od).
 */
#include <stddef.h>

#include "co/co.h"

void *memcpy(void *dst, const void *src, size_t n);
void *memmove(void *dst, const void *src, size_t n);
void *memset(void *dst, int c, size_t n);
int memcmp(const void *a, const void *b, size_t n);

void *memcpy(void *dst, const void *src, size_t n)
{
    unsigned char *d = (unsigned char *)dst;
    const unsigned char *s = (const unsigned char *)src;
    while (n-- > 0U) {
        *d++ = *s++;
    }
    return dst;
}

void *memmove(void *dst, const void *src, size_t n)
{
    unsigned char *d = (unsigned char *)dst;
    const unsigned char *s = (const unsigned char *)src;
    if (d < s) {
        return memcpy(dst, src, n);
    }
    while (n-- > 0U) {
        d[n] = s[n];
    }
    return dst;
}

void *memset(void *dst, int c, size_t n)
{
    unsigned char *d = (unsigned char *)dst;
    while (n-- > 0U) {
        *d++ = (unsigned char)c;
    }
    return dst;
}

int memcmp(const void *a, const void *b, size_t n)
{
    const unsigned char *x = (const unsigned char *)a;
    const unsigned char *y = (const unsigned char *)b;
    for (size_t i = 0U; i < n; i++) {
        if (x[i] != y[i]) {
            return x[i] < y[i] ? -1 : 1;
        }
    }
    return 0;
}

extern const co_od_t CO_CHECK_OD;

static co_status_t send(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    (void)frame;
    return CO_OK;
}
static co_status_t nvm_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    (void)ctx, (void)area, (void)offset, (void)data, (void)len;
    return CO_ERR_IO;
}
static co_status_t nvm_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    (void)ctx, (void)area, (void)total_len;
    return CO_ERR_IO;
}
static co_status_t nvm_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    (void)ctx, (void)area, (void)offset, (void)data, (void)len;
    return CO_ERR_NO_DATA;
}

/* Every public entry point an application uses, so the linker keeps all of the core that is reachable. */
void co_freestanding_entry(co_node_t *node, void *values, const co_frame_t *frame);
void co_freestanding_entry(co_node_t *node, void *values, const co_frame_t *frame)
{
    static const co_port_t port = {send, nvm_write, nvm_commit, nvm_read, NULL};
    const co_node_cfg_t cfg = {.od = &CO_CHECK_OD, .values = values, .port = &port, .node_id = 1U, .bit_timing = 4U};
    uint8_t b[4] = {0U};
    size_t n = 0U;
    (void)co_node_init(node, &cfg, 0U);
    co_node_rx(node, frame, 1U);
    (void)co_node_process(node, 2U);
    co_node_reset(node, CO_RESET_COMMUNICATION, 3U);
    (void)co_od_read(node, 0x1000U, 0U, b, sizeof b, &n, CO_ORIGIN_LOCAL);
    (void)co_od_write(node, 0x1017U, 0U, b, 2U, CO_ORIGIN_LOCAL);
    (void)co_od_set_u32(node, 0x6000U, 1U, 1U);
    (void)co_emcy_raise(node, 0x5000U, 1U, NULL);
    (void)co_emcy_clear(node, 0x5000U, NULL);
    co_tpdo_trigger(node, 0U);
    (void)co_lss_set_pending_node_id(node, 5U);
}
