/*
 * The port half both consumer programs share: a send function that records the frames a node sends, and
 * their print-out ("ID DLC BYTES...", hex, one line each) that tests/install/test_install.py reads.
 * Header-only so that a one-line compiler call (the pkg-config test) builds each program.
 */
#ifndef FRAME_RECORDER_H
#define FRAME_RECORDER_H

#include <stdio.h>

#include "co/co.h"

static co_frame_t recorded[64];
static size_t recorded_count;

static co_status_t record_frame(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    if (recorded_count == sizeof recorded / sizeof recorded[0]) {
        return CO_ERR_BUSY;
    }
    recorded[recorded_count++] = *frame;
    return CO_OK;
}

static void print_recorded_frames(void)
{
    for (size_t i = 0U; i < recorded_count; i++) {
        printf("%03X %u", (unsigned)recorded[i].id, (unsigned)recorded[i].len);
        for (size_t b = 0U; b < recorded[i].len; b++) {
            printf(" %02X", (unsigned)recorded[i].data[b]);
        }
        printf("\n");
    }
}

#endif /* FRAME_RECORDER_H */
