/* bench_can.c's buses other than a raw SocketCAN socket (bench_can_net.c): opened, sent to and read by
 * bench_can_open/send/recv according to the name they were given (bench_can.h). Returns as those. */
#ifndef BENCH_CAN_NET_H
#define BENCH_CAN_NET_H

#include "bench_can.h"

#include <sys/socket.h>

int bench_udp_open(bench_can_t *c, const char *spec, int rcvbuf);
int bench_udp_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data);
int bench_udp_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns);

int bench_scd_open(bench_can_t *c, const char *spec);
int bench_scd_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data);
int bench_scd_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns);

/* A received datagram's or frame's arrival time (the kernel's SO_TIMESTAMPNS unless user_time) and the socket's
 * drop count (SO_RXQ_OVFL) from its control data. */
int64_t bench_frame_time(bench_can_t *c, struct msghdr *msg);

#endif
