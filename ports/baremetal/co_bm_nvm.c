#include "co_bm_nvm.h"

#include <string.h>

#define MAGIC 0x4D426F43UL /* "CoBM" little-endian */

uint32_t co_bm_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    crc = ~crc;
    for (size_t i = 0U; i < len; i++) {
        crc ^= data[i];
        for (uint8_t b = 0U; b < 8U; b++) {
            crc = (crc >> 1) ^ (0xEDB88320UL & (0U - (crc & 1U)));
        }
    }
    return ~crc;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint32_t round_up(uint32_t n, uint32_t unit) { return (n + unit - 1U) / unit * unit; }

static uint32_t header_span(const co_bm_flash_t *f) { return round_up(CO_BM_NVM_HEADER, f->prog_unit); }

/* Reads and checks one slot: true with its sequence and blob length when the header and CRC are valid. */
static bool slot_valid(const co_bm_nvm_t *nvm, const co_bm_nvm_area_t *a, uint8_t s, uint32_t *seq, uint32_t *len)
{
    const co_bm_flash_t *f = nvm->flash;
    uint8_t h[CO_BM_NVM_HEADER];
    if (f->read(f->ctx, a->slot_addr[s], h, sizeof h) != CO_OK || get_u32(h) != MAGIC) {
        return false;
    }
    const uint32_t n = get_u32(&h[8]);
    if (n > a->slot_size - header_span(f)) {
        return false;
    }
    uint32_t crc = co_bm_crc32(0U, &h[4], 8U);
    uint8_t chunk[32];
    for (uint32_t pos = 0U; pos < n;) {
        const uint32_t k = n - pos < sizeof chunk ? n - pos : (uint32_t)sizeof chunk;
        if (f->read(f->ctx, a->slot_addr[s] + header_span(f) + pos, chunk, k) != CO_OK) {
            return false;
        }
        crc = co_bm_crc32(crc, chunk, k);
        pos += k;
    }
    if (crc != get_u32(&h[12])) {
        return false;
    }
    *seq = get_u32(&h[4]);
    *len = n;
    return true;
}

/* Newer in serial-number arithmetic: the sequence may wrap at 2^32. */
static bool seq_newer(uint32_t a, uint32_t b) { return (int32_t)(a - b) > 0; }

static void scan(co_bm_nvm_t *nvm, uint8_t i)
{
    const co_bm_nvm_area_t *a = &nvm->area[i];
    uint32_t seq[2] = {0U, 0U};
    uint32_t len[2] = {0U, 0U};
    bool ok[2] = {false, false};
    nvm->active[i] = -1;
    if (a->slot_size == 0U) {
        return;
    }
    for (uint8_t s = 0U; s < 2U; s++) {
        ok[s] = slot_valid(nvm, a, s, &seq[s], &len[s]);
    }
    const int8_t pick = (ok[0] && ok[1]) ? (seq_newer(seq[1], seq[0]) ? 1 : 0) : ok[0] ? 0 : ok[1] ? 1 : -1;
    nvm->active[i] = pick;
    if (pick >= 0) {
        nvm->seq[i] = seq[pick];
        nvm->len[i] = len[pick];
    }
}

co_status_t co_bm_nvm_init(co_bm_nvm_t *nvm, const co_bm_flash_t *flash, const co_bm_nvm_area_t area[CO_BM_NVM_AREAS],
                           uint8_t *stage, uint32_t stage_size)
{
    if (nvm == NULL || flash == NULL || area == NULL || stage == NULL || flash->page_size == 0U ||
        flash->prog_unit == 0U || flash->page_size % flash->prog_unit != 0U) {
        return CO_ERR_ARG;
    }
    memset(nvm, 0, sizeof *nvm);
    nvm->flash = flash;
    nvm->stage = stage;
    nvm->stage_size = stage_size;
    nvm->stage_area = -1;
    for (uint8_t i = 0U; i < CO_BM_NVM_AREAS; i++) {
        const co_bm_nvm_area_t *a = &area[i];
        if (a->slot_size != 0U &&
            (a->slot_size % flash->page_size != 0U || a->slot_addr[0] % flash->page_size != 0U ||
             a->slot_addr[1] % flash->page_size != 0U || a->slot_size <= header_span(flash) ||
             (a->slot_addr[0] < a->slot_addr[1] + a->slot_size && a->slot_addr[1] < a->slot_addr[0] + a->slot_size))) {
            return CO_ERR_ARG;
        }
        nvm->area[i] = *a;
        scan(nvm, i);
    }
    return CO_OK;
}

co_status_t co_bm_nvm_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    co_bm_nvm_t *nvm = (co_bm_nvm_t *)ctx;
    const uint8_t i = (uint8_t)area;
    if (i >= CO_BM_NVM_AREAS || nvm->area[i].slot_size == 0U || offset > nvm->stage_size ||
        len > nvm->stage_size - offset ||
        offset + len > nvm->area[i].slot_size - header_span(nvm->flash)) {
        return CO_ERR_IO;
    }
    if (nvm->stage_area != (int8_t)i) {
        nvm->stage_area = (int8_t)i; /* a new blob (an uncommitted one of another area is dropped) */
        memset(nvm->stage, 0, nvm->stage_size);
    }
    memcpy(&nvm->stage[offset], data, len);
    return CO_OK;
}

/* Programs len bytes from src at addr, padding the last program unit with the erased value. */
static co_status_t program_padded(const co_bm_flash_t *f, uint32_t addr, const uint8_t *src, uint32_t len)
{
    const uint32_t whole = len / f->prog_unit * f->prog_unit;
    if (whole > 0U && f->program(f->ctx, addr, src, whole) != CO_OK) {
        return CO_ERR_IO;
    }
    if (whole < len) {
        uint8_t unit[32];
        if (f->prog_unit > sizeof unit) {
            return CO_ERR_IO;
        }
        memset(unit, f->erased, f->prog_unit);
        memcpy(unit, &src[whole], len - whole);
        return f->program(f->ctx, addr + whole, unit, f->prog_unit);
    }
    return CO_OK;
}

co_status_t co_bm_nvm_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    co_bm_nvm_t *nvm = (co_bm_nvm_t *)ctx;
    const uint8_t i = (uint8_t)area;
    if (i >= CO_BM_NVM_AREAS || nvm->stage_area != (int8_t)i || total_len > nvm->stage_size) {
        return CO_ERR_IO;
    }
    nvm->stage_area = -1;
    const co_bm_flash_t *f = nvm->flash;
    const co_bm_nvm_area_t *a = &nvm->area[i];
    const uint32_t hspan = header_span(f);
    if (total_len > a->slot_size - hspan) {
        return CO_ERR_IO;
    }
    /* 1. The target is the slot that does not hold the valid blob: the valid one is never touched. */
    const uint8_t target = nvm->active[i] == 0 ? 1U : 0U;
    const uint32_t seq = nvm->active[i] >= 0 ? nvm->seq[i] + 1U : 1U;
    const uint32_t base = a->slot_addr[target];
    /* 2. Erase the pages the new blob needs (header included). */
    for (uint32_t off = 0U; off < round_up(hspan + total_len, f->page_size); off += f->page_size) {
        if (f->erase(f->ctx, base + off) != CO_OK) {
            return CO_ERR_IO;
        }
    }
    /* 3. The blob. */
    if (total_len > 0U && program_padded(f, base + hspan, nvm->stage, total_len) != CO_OK) {
        return CO_ERR_IO;
    }
    /* 4. The header last: until it is complete, the slot is not valid. */
    uint8_t h[CO_BM_NVM_HEADER];
    put_u32(h, MAGIC);
    put_u32(&h[4], seq);
    put_u32(&h[8], total_len);
    put_u32(&h[12], co_bm_crc32(co_bm_crc32(0U, &h[4], 8U), nvm->stage, total_len));
    if (program_padded(f, base, h, sizeof h) != CO_OK) {
        return CO_ERR_IO;
    }
    /* 5. Verify by reading back (a flash that failed silently must not replace the old blob in RAM). */
    uint32_t rseq;
    uint32_t rlen;
    if (!slot_valid(nvm, a, target, &rseq, &rlen) || rseq != seq || rlen != total_len) {
        return CO_ERR_IO;
    }
    nvm->active[i] = (int8_t)target;
    nvm->seq[i] = seq;
    nvm->len[i] = total_len;
    return CO_OK;
}

co_status_t co_bm_nvm_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    co_bm_nvm_t *nvm = (co_bm_nvm_t *)ctx;
    const uint8_t i = (uint8_t)area;
    if (i >= CO_BM_NVM_AREAS || nvm->active[i] < 0 || offset > nvm->len[i] || len > nvm->len[i] - offset) {
        return CO_ERR_NO_DATA;
    }
    const co_bm_flash_t *f = nvm->flash;
    const uint32_t addr = nvm->area[i].slot_addr[nvm->active[i]] + header_span(f) + offset;
    return f->read(f->ctx, addr, data, len) == CO_OK ? CO_OK : CO_ERR_IO;
}
