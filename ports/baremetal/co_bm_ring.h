/*
 * Lock-free single-producer/single-consumer ring of CAN frames: the CAN receive interrupt pushes, the
 * main loop pops and feeds co_node_rx(). No lock and no interrupt masking: the producer only writes
 * `head`, the consumer only writes `tail`, both are 32-bit (one load/store on any 32-bit MCU) and
 * free-running (they wrap at 2^32; the fill level is head - tail in unsigned arithmetic).
 *
 * Memory ordering: CO_BM_FENCE() separates the slot copy from the index update. The default is a full
 * barrier (__atomic_thread_fence: DMB on Cortex-M, FENCE on RISC-V), correct on single-core MCUs and on
 * dual-core parts where the ISR runs on another core (ESP32). Define CO_BM_FENCE() yourself for
 * compilers other than GCC/Clang.
 */
#ifndef CO_BM_RING_H
#define CO_BM_RING_H

#include "co/co_types.h"

#ifndef CO_BM_RING_LEN
#define CO_BM_RING_LEN 32U /**< Frames the ring holds; a power of two. */
#endif

#ifndef CO_BM_FENCE
#if defined(__GNUC__)
#define CO_BM_FENCE() __atomic_thread_fence(__ATOMIC_SEQ_CST)
#else
#error "define CO_BM_FENCE() as a full memory barrier for this compiler"
#endif
#endif

typedef char co_bm_ring_len_is_a_power_of_two[((CO_BM_RING_LEN & (CO_BM_RING_LEN - 1U)) == 0U && CO_BM_RING_LEN >= 2U) ? 1 : -1];

typedef struct co_bm_ring {
    co_frame_t slot[CO_BM_RING_LEN];
    volatile uint32_t head;     /**< Written by the producer only: slots filled so far. */
    volatile uint32_t tail;     /**< Written by the consumer only: slots consumed so far. */
    volatile uint32_t overruns; /**< Written by the producer only: frames dropped because the ring was full. */
} co_bm_ring_t;

/** Empties the ring. Call before the interrupt is enabled. */
void co_bm_ring_init(co_bm_ring_t *r);

/**
 * Producer side (the CAN receive interrupt): copies the frame in. False (and overruns + 1) when full;
 * the frame is dropped, as a CAN controller's own FIFO would drop it.
 */
bool co_bm_ring_push(co_bm_ring_t *r, const co_frame_t *frame);

/** Consumer side (the main loop): copies the oldest frame out. False when empty. */
bool co_bm_ring_pop(co_bm_ring_t *r, co_frame_t *frame);

/** Frames waiting (either side may ask; the answer may be stale by the time it is used). */
uint32_t co_bm_ring_count(const co_bm_ring_t *r);

#endif /* CO_BM_RING_H */
