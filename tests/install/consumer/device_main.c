/*
 * A program that uses the installed device models: one emulated Eltex SDS node with simulated time, driven
 * through the device API (devices/device.h) the way canopen-emu drives it. Prints the frames as main.c does;
 * tests/install/test_install.py checks the boot-up and the SDO answer with the vendor ID.
 */
#include <stdio.h>

#include "frame_recorder.h"
#include "device.h"
#include "sds/sds.h"

#define NODE_ID 0x0BU

/* The caller owns the memory of the node's values and of the model (their sizes are the class's). */
static union {
    long double align;
    unsigned char bytes[16384];
} values, model;

int main(void)
{
    static device_t dev;
    static const co_port_t port = {record_frame, NULL, NULL, NULL, NULL};
    if (sds_class.od->values_size > sizeof values.bytes || sds_class.model_size > sizeof model.bytes) {
        fprintf(stderr, "buffers too small: values %lu, model %lu\n", (unsigned long)sds_class.od->values_size,
                (unsigned long)sds_class.model_size);
        return 1;
    }
    device_cfg_t cfg = {0};
    cfg.node_id = NODE_ID;
    cfg.port = &port;
    co_time_us_t now = 0U;
    if (device_init(&dev, &sds_class, values.bytes, model.bytes, &cfg, now) != CO_OK) {
        fprintf(stderr, "device_init failed\n");
        return 1;
    }
    (void)device_process(&dev, now);
    const co_frame_t upload = {0x600U + NODE_ID, 8U, 0U, {0x40U, 0x18U, 0x10U, 0x01U, 0U, 0U, 0U, 0U}};
    now += 1000U;
    (void)device_rx(&dev, &upload, now);
    (void)device_process(&dev, now);
    printf("device %s\n", dev.cls->name);
    print_recorded_frames();
    return 0;
}
