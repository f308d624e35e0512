#include "fake_port.h"

#include <string.h>

static co_status_t fake_send(void *ctx, const co_frame_t *frame)
{
    fake_port_t *fp = (fake_port_t *)ctx;
    if (fp->busy_count > 0U) {
        fp->busy_count--;
        return CO_ERR_BUSY;
    }
    if (fp->send_io_error) {
        return CO_ERR_IO;
    }
    if (fp->n_sent < FAKE_PORT_MAX_FRAMES) {
        fp->sent[fp->n_sent] = *frame;
        fp->sent_at[fp->n_sent] = fp->clock != NULL ? *fp->clock : 0U;
        fp->n_sent++;
    }
    return CO_OK;
}

static co_status_t fake_nvm_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len)
{
    fake_port_t *fp = (fake_port_t *)ctx;
    if (fp->nvm_fail_write || offset + len > FAKE_NVM_SIZE) {
        return CO_ERR_IO;
    }
    memcpy(&fp->nvm[area].staging[offset], data, len);
    return CO_OK;
}

static void log_commit(fake_port_t *fp, co_nvm_area_t area, char kind)
{
    const size_t n = strlen(fp->nvm_log);
    if (n + 2U < sizeof fp->nvm_log) {
        fp->nvm_log[n] = (char)('0' + (int)area);
        fp->nvm_log[n + 1U] = kind;
        fp->nvm_log[n + 2U] = '\0';
    }
}

static void drop_pending(fake_port_t *fp)
{
    for (int a = 0; a < 3; a++) {
        fp->nvm[a].is_pending = false;
    }
}

static co_status_t fake_nvm_commit(void *ctx, co_nvm_area_t area, uint32_t total_len)
{
    fake_port_t *fp = (fake_port_t *)ctx;
    if (total_len == CO_NVM_DISCARD) {
        log_commit(fp, area, 'x');
        fp->nvm_discards++;
        drop_pending(fp);
        return CO_OK;
    }
    const bool more = (total_len & CO_NVM_MORE) != 0U;
    const uint32_t len = total_len & ~CO_NVM_FLAGS; /* a background commit is applied at once */
    if ((total_len & CO_NVM_BACKGROUND) != 0U) {
        fp->nvm[area].background_commits++;
    }
    log_commit(fp, area, more ? '+' : '.');
    if (len > FAKE_NVM_SIZE || (fp->nvm_fail_area_mask & (1U << (unsigned)area)) != 0U) {
        drop_pending(fp);
        return CO_ERR_IO;
    }
    if (more) {
        fake_nvm_area_t *a = &fp->nvm[area];
        memcpy(a->pending, a->staging, (size_t)len);
        a->pending_len = len;
        a->is_pending = true;
        a->more_commits++;
        return CO_OK;
    }
    if (fp->nvm_fail_commit) {
        drop_pending(fp); /* all or none: the pending areas of the store keep their old blobs too */
        return CO_ERR_IO;
    }
    for (int i = 0; i < 3; i++) {
        fake_nvm_area_t *a = &fp->nvm[i];
        if (a->is_pending && i != (int)area) {
            memcpy(a->stored, a->pending, (size_t)a->pending_len);
            a->stored_len = a->pending_len;
            a->commits++;
        }
    }
    drop_pending(fp);
    memcpy(fp->nvm[area].stored, fp->nvm[area].staging, (size_t)len);
    fp->nvm[area].stored_len = len;
    fp->nvm[area].commits++;
    return CO_OK;
}

static co_status_t fake_nvm_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len)
{
    fake_port_t *fp = (fake_port_t *)ctx;
    if (offset + len > fp->nvm[area].stored_len) {
        /* a port that can tell "nothing stored" from "a blob too short" (co_port.h) */
        return fp->nvm[area].stored_len > 0U || fp->nvm[area].empty_blob ? CO_ERR_IO : CO_ERR_NO_DATA;
    }
    memcpy(data, &fp->nvm[area].stored[offset], len);
    return CO_OK;
}

static co_status_t fake_set_bit_rate(void *ctx, uint32_t kbit)
{
    fake_port_t *fp = (fake_port_t *)ctx;
    fp->bit_rate_kbit = kbit;
    fp->bit_rate_calls++;
    return CO_OK;
}

void fake_port_init(fake_port_t *fp, const co_time_us_t *clock)
{
    memset(fp, 0, sizeof *fp);
    fp->port.send = fake_send;
    fp->port.nvm_write = fake_nvm_write;
    fp->port.nvm_commit = fake_nvm_commit;
    fp->port.nvm_read = fake_nvm_read;
    fp->port.set_bit_rate = fake_set_bit_rate;
    fp->clock = clock;
}

void fake_port_clear(fake_port_t *fp) { fp->n_sent = 0U; }

co_node_cfg_t fake_port_node_cfg(fake_port_t *fp, const co_od_t *od, void *values, uint8_t node_id)
{
    co_node_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.od = od;
    cfg.values = values;
    cfg.port = &fp->port;
    cfg.port_ctx = fp;
    cfg.node_id = node_id;
    return cfg;
}
