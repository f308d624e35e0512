/*
 * Shared helpers of the bus benchmarks (docs/performance.md): a raw CAN socket with kernel receive
 * timestamps and drop counting, expedited SDO frames, sample statistics and a tiny JSON writer.
 *
 * Arrival times are the kernel's (SO_TIMESTAMPNS, CLOCK_REALTIME based): they are taken when the frame
 * reaches the socket, so the scheduling delay of the reading process does not enter a measured period
 * or round trip. Send times are CLOCK_REALTIME read just before write(), the same clock.
 */
#ifndef BENCH_CAN_H
#define BENCH_CAN_H

#include <linux/can.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef enum bench_bus_kind { BENCH_RAW, BENCH_UDP, BENCH_SOCKETCAND } bench_bus_kind_t;

typedef struct bench_can {
    int fd;
    uint32_t drops; /* SO_RXQ_OVFL: frames the kernel dropped because this socket's buffer was full */
    bench_bus_kind_t kind;
    bool user_time; /* arrival time = CLOCK_REALTIME after the read returned, not the kernel's time stamp */
    int tx_fd;      /* udp_multicast: the socket frames are sent from (its own datagrams are skipped) */
    uint16_t tx_port;
    uint8_t addr[28]; /* udp_multicast: the group's sockaddr_in */
    int rcvbuf;       /* the receive buffer the kernel granted (SO_RCVBUF read back) */
    char in[8192];    /* socketcand: bytes read, not yet parsed */
    size_t in_len;
} bench_can_t;

/* Opens the bus ifname with a receive buffer of rcvbuf bytes (0: the default); returns 0 or -1 (message on stderr).
 * Frames are read with bench_can_recv. ifname is a SocketCAN interface (a raw socket), or
 *   udp_multicast:GROUP:PORT         python-can's udp_multicast bus (IPv4 group; TTL 0: never leaves the machine;
 *                                    run it in tests/udp/netns-run), frames as msgpack datagrams
 *   socketcand:HOST:PORT:BUS         a socketcand server's BUS in rawmode over TCP (HOST an IPv4 address);
 *                                    arrival time: after the read (TCP has no per-frame kernel time stamp) */
int bench_can_open(bench_can_t *c, const char *ifname, int rcvbuf);
void bench_can_close(bench_can_t *c);

/* Sends one classic frame; waits for room when the socket's queue is full (never drops). 0 or -1. */
int bench_can_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data);

/* Receives one frame, waiting until the absolute CLOCK_MONOTONIC time deadline_ns (0: do not wait).
 * Returns 1 (frame, *t_ns = kernel arrival time, realtime ns), 0 (deadline passed) or -1 (error). */
int bench_can_recv(bench_can_t *c, struct can_frame *f, int64_t *t_ns, int64_t deadline_ns);

/* Receives up to max frames that are already pending, in one system call (recvmmsg), without waiting.
 * Returns how many (f[i], t_ns[i] as bench_can_recv), 0 when none is pending, -1 on error. */
int bench_can_recv_many(bench_can_t *c, struct can_frame *f, int64_t *t_ns, int max);

int64_t bench_mono_ns(void);
int64_t bench_real_ns(void);
void bench_sleep_until(int64_t mono_ns);

/* Parses a number (decimal or 0x-hex) into [lo, hi]; exits with status 2 and a message otherwise. */
long long bench_num(const char *text, long long lo, long long hi, const char *what);
/* "A" or "A-B" (numbers as bench_num) into *lo, *hi. */
void bench_range(const char *text, long long lo, long long hi, long long *a, long long *b, const char *what);

/* Samples (doubles) with percentiles by nearest rank on the sorted values. */
typedef struct bench_samples {
    double *v;
    size_t n;
    size_t cap;
    bool sorted;
} bench_samples_t;

void samples_add(bench_samples_t *s, double x);
double samples_pct(bench_samples_t *s, double p); /* p in [0, 100]; 0 for an empty set */
double samples_mean(const bench_samples_t *s);
void samples_free(bench_samples_t *s);

/* Expedited SDO requests (client -> server, 8 bytes). */
void sdo_upload_req(uint8_t out[8], uint16_t index, uint8_t sub);
void sdo_download_req(uint8_t out[8], uint16_t index, uint8_t sub, uint8_t size, uint32_t value);

/* Reads utime + stime (clock ticks) of a process from /proc/<pid>/stat; -1 when it cannot. */
long long bench_proc_cpu_ticks(int pid, long long *utime, long long *stime);

/* Minimal JSON output: the programs print one object; the driver (bench/run_bus.py) parses it. */
void json_stats(FILE *out, const char *key, bench_samples_t *s, double scale, bool last);

#endif
