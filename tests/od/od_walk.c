/*
 * od_walk: one node of a generated object dictionary on a fake port, driven by SDO requests on stdin.
 * Used by tests/od/test_od_walk.py to walk every entry of each device through the SDO server.
 *
 *   od_walk DEVICE NODE-ID [segmented]
 * stdin: one request per line, 8 hex bytes ("40 00 10 00 00 00 00 00"), sent to 0x600+NODE-ID.
 * stdout: every frame the node sends in answer, "ID#HEXDATA" one per line, then a line ".".
 * The boot-up frame is printed before the first request. No device behaviour is attached: this is the
 * bare object dictionary as generated from od/DEVICE.eds.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "buerkert_fc_od.h"
#include "co/co.h"
#include "pro_ionizer_od.h"
#include "sds_od.h"

static co_status_t print_frame(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    printf("%03X#", (unsigned)f->id);
    for (uint8_t i = 0U; i < f->len; i++) {
        printf("%02X", f->data[i]);
    }
    printf("\n");
    return CO_OK;
}

static union {
    pro_ionizer_od_values_t pro_ionizer;
    sds_od_values_t sds;
    buerkert_fc_od_values_t buerkert;
} values;

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: od_walk pro-ionizer|sds|buerkert NODE-ID [segmented]\n");
        return 2;
    }
    const co_od_t *od = NULL;
    if (strcmp(argv[1], "pro-ionizer") == 0) {
        od = &pro_ionizer_od;
    } else if (strcmp(argv[1], "sds") == 0) {
        od = &sds_od;
    } else if (strcmp(argv[1], "buerkert") == 0) {
        od = &buerkert_fc_od;
    } else {
        fprintf(stderr, "od_walk: unknown device %s\n", argv[1]);
        return 2;
    }
    const co_port_t port = {print_frame, NULL, NULL, NULL, NULL};
    co_node_cfg_t cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.od = od;
    cfg.values = &values;
    cfg.port = &port;
    cfg.node_id = (uint8_t)strtoul(argv[2], NULL, 0);
    cfg.options = (argc > 3 && strcmp(argv[3], "segmented") == 0) ? CO_OPT_SDO_SEGMENTED : 0U;
    static co_node_t node;
    if (co_node_init(&node, &cfg, 0U) != CO_OK) {
        fprintf(stderr, "od_walk: co_node_init failed\n");
        return 1;
    }
    printf(".\n");
    fflush(stdout);
    char line[128];
    co_time_us_t now = 0U;
    while (fgets(line, sizeof line, stdin) != NULL) {
        co_frame_t f = {0x600U + cfg.node_id, 8U, 0U, {0U}};
        unsigned b[8];
        if (sscanf(line, "%x %x %x %x %x %x %x %x", &b[0], &b[1], &b[2], &b[3], &b[4], &b[5], &b[6], &b[7]) != 8) {
            fprintf(stderr, "od_walk: bad request line: %s", line);
            return 2;
        }
        for (int i = 0; i < 8; i++) {
            f.data[i] = (uint8_t)b[i];
        }
        now += 1000U;
        co_node_rx(&node, &f, now);
        (void)co_node_process(&node, now);
        printf(".\n");
        fflush(stdout);
    }
    return 0;
}
