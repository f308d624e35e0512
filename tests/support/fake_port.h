/*
 * A fake port for unit tests: records every frame sent (with the simulated time), can refuse sends
 * (busy or I/O error) and simulates the NVM areas with staging and atomic commit, with failure injection. Stores
 * of several areas are grouped as co_port.h describes: CO_NVM_MORE commits stay pending until the last commit
 * of the store applies them all, or none when it fails or the store is discarded (CO_NVM_DISCARD).
 */
#ifndef FAKE_PORT_H
#define FAKE_PORT_H

#include "co/co.h"

/* Frames recorded and bytes per NVM area. A RAM-constrained target build (tests/target/) may lower them. */
#ifndef FAKE_PORT_MAX_FRAMES
#define FAKE_PORT_MAX_FRAMES 4096U
#endif
#ifndef FAKE_NVM_SIZE
#define FAKE_NVM_SIZE 4096U
#endif

typedef struct fake_nvm_area {
    uint8_t stored[FAKE_NVM_SIZE];
    uint32_t stored_len;    /* 0 = nothing stored (unless empty_blob) */
    bool empty_blob;        /* with stored_len 0: a blob of 0 bytes is there (an empty file), not nothing */
    uint8_t staging[FAKE_NVM_SIZE];
    uint8_t pending[FAKE_NVM_SIZE]; /* committed with CO_NVM_MORE, waiting for the store's last commit */
    uint32_t pending_len;
    bool is_pending;
    uint32_t commits;       /* commits that replaced the stored blob */
    uint32_t more_commits;  /* CO_NVM_MORE commits of this area */
    uint32_t background_commits; /* CO_NVM_BACKGROUND commits of this area (applied at once, counted in commits) */
} fake_nvm_area_t;

typedef struct fake_port {
    co_port_t port;          /* the vtable handed to the node; ctx = this struct */
    co_frame_t sent[FAKE_PORT_MAX_FRAMES];
    co_time_us_t sent_at[FAKE_PORT_MAX_FRAMES];
    uint32_t n_sent;
    const co_time_us_t *clock; /* where the test keeps "now", to timestamp frames */
    uint32_t busy_count;     /* the next n sends answer CO_ERR_BUSY */
    bool send_io_error;      /* sends answer CO_ERR_IO */
    bool nvm_fail_write;     /* nvm_write answers CO_ERR_IO */
    bool nvm_fail_commit;    /* nvm_commit answers CO_ERR_IO (the last commit of a store: none of it is applied) */
    uint8_t nvm_fail_area_mask; /* nvm_commit of an area whose bit (1 << area) is set answers CO_ERR_IO */
    uint32_t nvm_discards;   /* nvm_commit calls with CO_NVM_DISCARD */
    char nvm_log[64];        /* commits in order: area digit, then '+' (CO_NVM_MORE), '.' (last) or 'x' (discard) */
    fake_nvm_area_t nvm[3];
    uint32_t bit_rate_kbit;  /* last set_bit_rate */
    uint32_t bit_rate_calls;
} fake_port_t;

/* Initialises with every port function present. */
void fake_port_init(fake_port_t *fp, const co_time_us_t *clock);
/* Forgets the recorded frames (keeps NVM). */
void fake_port_clear(fake_port_t *fp);
/* A node's configuration on this port: dictionary od with its values block, node-ID node_id, no hooks, no options
 * (what a test with a dictionary of its own starts from). */
co_node_cfg_t fake_port_node_cfg(fake_port_t *fp, const co_od_t *od, void *values, uint8_t node_id);

#endif
