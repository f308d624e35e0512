/**
 * @file nvm_file_store.h
 * @brief The NVM files' transactions, for nvm_file.c only: temporary files, the journal of a store of several
 *        areas, the recovery at open (nvm_file.h: the guarantees; nvm_writer.c replaces one area in the background).
 */
#ifndef NVM_FILE_STORE_H
#define NVM_FILE_STORE_H

#include "nvm_file.h"

/** The staged blob of total_len bytes to "<file>.tmp" (write + fsync); pending[area] when it is there. The rename
 *  that makes it the file comes with the store's last commit (nvm_store_finish). */
co_status_t nvm_store_write_tmp(nvm_file_t *n, co_nvm_area_t area, uint32_t total_len);
/** The store is abandoned: its temporary files go, every area keeps its file. */
void nvm_store_discard(nvm_file_t *n);
/** Makes the store's pending areas the files, as one transaction: 0 when durable, -1 when nothing changed. */
int nvm_store_finish(nvm_file_t *n);
/** At open: finishes a transaction a journal decided, removes the leftovers of undecided ones. */
void nvm_store_recover(nvm_file_t *n);

#endif
