/**
 * @file nvm_file.h
 * @brief The port's non-volatile memory as files: one file per area of one node, replaced atomically.
 *
 * Writes go to "<file>.tmp"; commit truncates it to the blob's length, fsyncs it, renames it over the
 * file and fsyncs the directory, so after a crash at any moment the file is the whole old blob or the
 * whole new one (the core also checks a CRC on load). Files: <dir>/<key>.params, .lss, .device.
 */
#ifndef NVM_FILE_H
#define NVM_FILE_H

#include <limits.h>

#include "co/co.h"

typedef struct nvm_file {
    char path[3][PATH_MAX];
    int staging[3]; /**< fd of <file>.tmp while a blob is being written, else -1 */
    int dir_fd;
} nvm_file_t;

/** Prepares the files of one node (key e.g. "pro-ionizer-99") in dir, creating dir if needed.
 *  Returns 0 or an errno value with a message for the user in err. */
int nvm_file_open(nvm_file_t *n, const char *dir, const char *key, char *err, size_t errlen);
void nvm_file_close(nvm_file_t *n);

/** Checks that dir exists or can be created and that files can be written there. */
int nvm_file_check_dir(const char *dir, char *err, size_t errlen);

co_status_t nvm_file_write(void *ctx, co_nvm_area_t area, uint32_t offset, const void *data, size_t len);
co_status_t nvm_file_commit(void *ctx, co_nvm_area_t area, uint32_t total_len);
co_status_t nvm_file_read(void *ctx, co_nvm_area_t area, uint32_t offset, void *data, size_t len);

#endif
