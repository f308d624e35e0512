/*
 * A program that uses the installed core the way a firmware engineer's application would: one node of the
 * Eltex SDS object dictionary, a port that records the frames the node sends, no storage. It prints every
 * frame as "ID DLC BYTES..." (hex) and exits 0; tests/install/test_install.py checks the lines: the boot-up,
 * then the answer to an SDO upload of 0x1018:01 (vendor ID) that the program feeds the node.
 */
#include <stdio.h>

#include "frame_recorder.h"
#include "co/co.h"
#include "sds_od.h"

#if !defined(CO_VERSION) || CO_VERSION < CO_VERSION_NUMBER(0, 1, 0)
#error "co/co_version.h missing or older than 0.1.0"
#endif

#define NODE_ID 0x0AU

int main(void)
{
    static co_node_t node;
    static sds_od_values_t values;
    static const co_port_t port = {record_frame, NULL, NULL, NULL, NULL};
    const co_node_cfg_t cfg = {.od = &sds_od, .values = &values, .port = &port, .node_id = NODE_ID, .bit_timing = 4U};
    co_time_us_t now = 0U;
    if (co_node_init(&node, &cfg, now) != CO_OK) {
        fprintf(stderr, "co_node_init failed\n");
        return 1;
    }
    (void)co_node_process(&node, now);
    const co_frame_t upload = {0x600U + NODE_ID, 8U, 0U, {0x40U, 0x18U, 0x10U, 0x01U, 0U, 0U, 0U, 0U}};
    now += 1000U;
    if (!co_node_rx(&node, &upload, now)) {
        fprintf(stderr, "the node ignored the SDO request\n");
        return 1;
    }
    (void)co_node_process(&node, now);
    printf("core %s\n", CO_VERSION_STRING);
    print_recorded_frames();
    return 0;
}
