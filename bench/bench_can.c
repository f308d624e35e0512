/* Shared helpers of the bus benchmarks: see bench_can.h. */
#define _GNU_SOURCE
#include "bench_can.h"

#include <errno.h>
#include <arpa/inet.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static int64_t ts_ns(const struct timespec *ts) { return (int64_t)ts->tv_sec * 1000000000LL + (int64_t)ts->tv_nsec; }

int64_t bench_mono_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts_ns(&ts);
}

int64_t bench_real_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts);
    return ts_ns(&ts);
}

void bench_sleep_until(int64_t mono_ns)
{
    struct timespec ts;
    ts.tv_sec = (time_t)(mono_ns / 1000000000LL);
    ts.tv_nsec = (long)(mono_ns % 1000000000LL);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

static int udp_open(bench_can_t *c, const char *spec, int rcvbuf);
static int scd_open(bench_can_t *c, const char *spec);

int bench_can_open(bench_can_t *c, const char *ifname, int rcvbuf)
{
    memset(c, 0, sizeof *c);
    c->tx_fd = -1;
    if (strncmp(ifname, "udp_multicast:", 14) == 0) {
        c->kind = BENCH_UDP;
        return udp_open(c, ifname + 14, rcvbuf);
    }
    if (strncmp(ifname, "socketcand:", 11) == 0) {
        c->kind = BENCH_SOCKETCAND;
        c->user_time = true;
        return scd_open(c, ifname + 11);
    }
    c->fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (c->fd < 0) {
        fprintf(stderr, "bench: CAN socket: %s\n", strerror(errno));
        return -1;
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", ifname);
    if (ioctl(c->fd, SIOCGIFINDEX, &ifr) < 0) {
        fprintf(stderr, "bench: interface %s: %s\n", ifname, strerror(errno));
        (void)close(c->fd);
        return -1;
    }
    const int one = 1;
    (void)setsockopt(c->fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);
    (void)setsockopt(c->fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    if (rcvbuf > 0) {
        /* FORCE (root) goes past net.core.rmem_max; a busy bus must not overflow the observer itself. */
        if (setsockopt(c->fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
            (void)setsockopt(c->fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
        }
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(c->fd, (struct sockaddr *)&addr, sizeof addr) < 0) {
        fprintf(stderr, "bench: bind %s: %s\n", ifname, strerror(errno));
        (void)close(c->fd);
        return -1;
    }
    return 0;
}

void bench_can_close(bench_can_t *c)
{
    if (c->fd >= 0) {
        (void)close(c->fd);
    }
    if (c->tx_fd >= 0) {
        (void)close(c->tx_fd);
    }
    c->fd = -1;
    c->tx_fd = -1;
}

static int udp_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data);
static int scd_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data);
static int udp_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns);
static int scd_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns);

int bench_can_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
{
    if (c->kind == BENCH_UDP) {
        return udp_send(c, id, len, data);
    }
    if (c->kind == BENCH_SOCKETCAND) {
        return scd_send(c, id, len, data);
    }
    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = id;
    f.can_dlc = len;
    if (len > 0U) {
        memcpy(f.data, data, len);
    }
    for (;;) {
        const ssize_t w = write(c->fd, &f, sizeof f);
        if (w == (ssize_t)sizeof f) {
            return 0;
        }
        if (w < 0 && (errno == ENOBUFS || errno == EAGAIN)) {
            /* The interface queue is full: wait for room rather than lose a request (open-loop senders
             * see the delay as a lower achieved rate, which they report). */
            struct pollfd p = {c->fd, POLLOUT, 0};
            (void)poll(&p, 1, 10);
            continue;
        }
        if (w < 0 && errno == EINTR) {
            continue;
        }
        fprintf(stderr, "bench: write: %s\n", w < 0 ? strerror(errno) : "short write");
        return -1;
    }
}

/* A received frame's kernel arrival time (SO_TIMESTAMPNS; now when there is none) and the socket's drop count
 * (SO_RXQ_OVFL) from the message's control data. */
static int64_t frame_time(bench_can_t *c, struct msghdr *msg)
{
    int64_t t = 0;
    for (struct cmsghdr *cm = CMSG_FIRSTHDR(msg); cm != NULL; cm = CMSG_NXTHDR(msg, cm)) {
        if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SO_TIMESTAMPNS) {
            struct timespec ts;
            memcpy(&ts, CMSG_DATA(cm), sizeof ts);
            t = ts_ns(&ts);
        } else if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SO_RXQ_OVFL) {
            memcpy(&c->drops, CMSG_DATA(cm), sizeof c->drops);
        }
    }
    return t != 0 && !c->user_time ? t : bench_real_ns(); /* no kernel timestamp: the next best thing */
}

/* One frame of a udp_multicast or socketcand bus without waiting: 1, 0 (none pending) or -1. */
static int other_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns)
{
    return c->kind == BENCH_UDP ? udp_recv1(c, f, t_ns) : scd_recv1(c, f, t_ns);
}

int bench_can_recv(bench_can_t *c, struct can_frame *f, int64_t *t_ns, int64_t deadline_ns)
{
    for (;;) {
        if (c->kind != BENCH_RAW) {
            const int r = other_recv1(c, f, t_ns);
            if (r != 0) {
                return r;
            }
            const int64_t now = bench_mono_ns();
            if (deadline_ns <= now) {
                return 0;
            }
            const int64_t wait = deadline_ns - now;
            struct timespec ts = {(time_t)(wait / 1000000000LL), (long)(wait % 1000000000LL)};
            struct pollfd p = {c->fd, POLLIN, 0};
            if (ppoll(&p, 1, &ts, NULL) < 0 && errno != EINTR) {
                fprintf(stderr, "bench: poll: %s\n", strerror(errno));
                return -1;
            }
            continue;
        }
        struct iovec iov = {f, sizeof *f};
        char ctrl[CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(uint32_t))];
        struct msghdr msg;
        memset(&msg, 0, sizeof msg);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = ctrl;
        msg.msg_controllen = sizeof ctrl;
        const ssize_t r = recvmsg(c->fd, &msg, MSG_DONTWAIT);
        if (r == (ssize_t)sizeof *f) {
            *t_ns = frame_time(c, &msg);
            return 1;
        }
        if (r >= 0) {
            continue; /* not a classic frame (CAN FD): ignored */
        }
        if (errno == EINTR) {
            continue;
        }
        if (errno != EAGAIN && errno != EWOULDBLOCK) {
            fprintf(stderr, "bench: recvmsg: %s\n", strerror(errno));
            return -1;
        }
        const int64_t now = bench_mono_ns();
        if (deadline_ns <= now) {
            return 0;
        }
        const int64_t wait = deadline_ns - now;
        struct timespec ts = {(time_t)(wait / 1000000000LL), (long)(wait % 1000000000LL)};
        struct pollfd p = {c->fd, POLLIN, 0};
        const int pr = ppoll(&p, 1, &ts, NULL);
        if (pr < 0 && errno != EINTR) {
            fprintf(stderr, "bench: poll: %s\n", strerror(errno));
            return -1;
        }
    }
}

#define RECV_MANY_MAX 64

int bench_can_recv_many(bench_can_t *c, struct can_frame *f, int64_t *t_ns, int max)
{
    struct mmsghdr mm[RECV_MANY_MAX];
    struct iovec iov[RECV_MANY_MAX];
    char ctrl[RECV_MANY_MAX][CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(uint32_t))];
    if (max > RECV_MANY_MAX) {
        max = RECV_MANY_MAX;
    }
    if (c->kind != BENCH_RAW) {
        int got = 0;
        while (got < max) {
            const int r = other_recv1(c, &f[got], &t_ns[got]);
            if (r < 0) {
                return -1;
            }
            if (r == 0) {
                break;
            }
            got++;
        }
        return got;
    }
    memset(mm, 0, sizeof mm);
    for (int i = 0; i < max; i++) {
        iov[i].iov_base = &f[i];
        iov[i].iov_len = sizeof f[i];
        mm[i].msg_hdr.msg_iov = &iov[i];
        mm[i].msg_hdr.msg_iovlen = 1;
        mm[i].msg_hdr.msg_control = ctrl[i];
        mm[i].msg_hdr.msg_controllen = sizeof ctrl[i];
    }
    int n;
    do {
        n = recvmmsg(c->fd, mm, (unsigned)max, MSG_DONTWAIT, NULL);
    } while (n < 0 && errno == EINTR);
    if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK) {
            return 0;
        }
        fprintf(stderr, "bench: recvmmsg: %s\n", strerror(errno));
        return -1;
    }
    int kept = 0;
    for (int i = 0; i < n; i++) {
        if (mm[i].msg_len != sizeof f[i]) {
            continue; /* not a classic frame (CAN FD): ignored */
        }
        f[kept] = f[i];
        t_ns[kept] = frame_time(c, &mm[i].msg_hdr);
        kept++;
    }
    return kept;
}

long long bench_num(const char *text, long long lo, long long hi, const char *what)
{
    char *end = NULL;
    errno = 0;
    const long long v = strtoll(text, &end, 0);
    if (errno != 0 || end == text || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "bench: bad %s '%s' (%lld..%lld)\n", what, text, lo, hi);
        exit(2);
    }
    return v;
}

void bench_range(const char *text, long long lo, long long hi, long long *a, long long *b, const char *what)
{
    char buf[64];
    (void)snprintf(buf, sizeof buf, "%s", text);
    char *dash = strchr(buf + 1, '-'); /* +1: never a leading sign */
    if (dash != NULL) {
        *dash = '\0';
        *a = bench_num(buf, lo, hi, what);
        *b = bench_num(dash + 1, *a, hi, what);
    } else {
        *a = *b = bench_num(buf, lo, hi, what);
    }
}

void samples_add(bench_samples_t *s, double x)
{
    if (s->n == s->cap) {
        s->cap = s->cap == 0U ? 1024U : s->cap * 2U;
        double *g = realloc(s->v, s->cap * sizeof *g);
        if (g == NULL) {
            fprintf(stderr, "bench: out of memory\n");
            exit(1);
        }
        s->v = g;
    }
    s->v[s->n++] = x;
    s->sorted = false;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a;
    const double y = *(const double *)b;
    return (x > y) - (x < y);
}

double samples_pct(bench_samples_t *s, double p)
{
    if (s->n == 0U) {
        return 0.0;
    }
    if (!s->sorted) {
        qsort(s->v, s->n, sizeof *s->v, cmp_double);
        s->sorted = true;
    }
    /* nearest rank: the smallest value with at least p% of the samples at or below it */
    size_t rank = (size_t)((p / 100.0) * (double)s->n + 0.999999);
    if (rank < 1U) {
        rank = 1U;
    }
    if (rank > s->n) {
        rank = s->n;
    }
    return s->v[rank - 1U];
}

double samples_mean(const bench_samples_t *s)
{
    double sum = 0.0;
    for (size_t i = 0U; i < s->n; i++) {
        sum += s->v[i];
    }
    return s->n > 0U ? sum / (double)s->n : 0.0;
}

void samples_free(bench_samples_t *s)
{
    free(s->v);
    memset(s, 0, sizeof *s);
}

void sdo_upload_req(uint8_t out[8], uint16_t index, uint8_t sub)
{
    memset(out, 0, 8);
    out[0] = 0x40U;
    out[1] = (uint8_t)index;
    out[2] = (uint8_t)(index >> 8);
    out[3] = sub;
}

void sdo_download_req(uint8_t out[8], uint16_t index, uint8_t sub, uint8_t size, uint32_t value)
{
    memset(out, 0, 8);
    out[0] = (uint8_t)(0x23U | ((4U - size) << 2)); /* expedited, size indicated */
    out[1] = (uint8_t)index;
    out[2] = (uint8_t)(index >> 8);
    out[3] = sub;
    for (uint8_t i = 0U; i < size; i++) {
        out[4U + i] = (uint8_t)(value >> (8U * i));
    }
}

long long bench_proc_cpu_ticks(int pid, long long *utime, long long *stime)
{
    char path[64];
    (void)snprintf(path, sizeof path, "/proc/%d/stat", pid);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return -1;
    }
    char buf[1024];
    const size_t n = fread(buf, 1U, sizeof buf - 1U, f);
    fclose(f);
    buf[n] = '\0';
    /* The command name (field 2) may contain spaces: fields are counted after its closing ')'. */
    const char *p = strrchr(buf, ')');
    if (p == NULL) {
        return -1;
    }
    long long u = 0;
    long long s = 0;
    /* after ')': state(3) ppid pgrp session tty tpgid flags minflt cminflt majflt cmajflt utime(14) stime(15) */
    if (sscanf(p + 1, " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lld %lld", &u, &s) != 2) {
        return -1;
    }
    if (utime != NULL) {
        *utime = u;
    }
    if (stime != NULL) {
        *stime = s;
    }
    return u + s;
}

void json_stats(FILE *out, const char *key, bench_samples_t *s, double scale, bool last)
{
    fprintf(out, "\"%s\": {\"n\": %zu, \"mean\": %.3f, \"p50\": %.3f, \"p99\": %.3f, \"max\": %.3f}%s", key, s->n,
            samples_mean(s) * scale, samples_pct(s, 50.0) * scale, samples_pct(s, 99.0) * scale,
            samples_pct(s, 100.0) * scale, last ? "" : ", ");
}

/* ---- udp_multicast: python-can's format (docs/buses.md "The wire format"), IPv4 groups only. */

static int split_host_port(const char *spec, char *host, size_t host_size, long *port, const char **rest)
{
    const char *colon = strchr(spec, ':');
    if (colon == NULL || (size_t)(colon - spec) >= host_size) {
        return -1;
    }
    memcpy(host, spec, (size_t)(colon - spec));
    host[colon - spec] = '\0';
    char *end = NULL;
    *port = strtol(colon + 1, &end, 10);
    if (end == colon + 1 || *port < 1 || *port > 65535) {
        return -1;
    }
    *rest = end;
    return 0;
}

static int udp_open(bench_can_t *c, const char *spec, int rcvbuf)
{
    char group[64];
    long port;
    const char *rest;
    struct sockaddr_in ga;
    memset(&ga, 0, sizeof ga);
    ga.sin_family = AF_INET;
    if (split_host_port(spec, group, sizeof group, &port, &rest) != 0 || *rest != '\0' ||
        inet_pton(AF_INET, group, &ga.sin_addr) != 1 || !IN_MULTICAST(ntohl(ga.sin_addr.s_addr))) {
        fprintf(stderr, "bench: udp_multicast:%s: want udp_multicast:GROUP:PORT (an IPv4 group)\n", spec);
        return -1;
    }
    ga.sin_port = htons((uint16_t)port);
    memcpy(c->addr, &ga, sizeof ga);
    c->fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    c->tx_fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (c->fd < 0 || c->tx_fd < 0) {
        fprintf(stderr, "bench: UDP socket: %s\n", strerror(errno));
        return -1;
    }
    const int one = 1;
    const int zero = 0;
    (void)setsockopt(c->fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    (void)setsockopt(c->fd, SOL_SOCKET, SO_REUSEPORT, &one, sizeof one);
    (void)setsockopt(c->fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);
    (void)setsockopt(c->fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
    (void)setsockopt(c->fd, IPPROTO_IP, IP_MULTICAST_ALL, &zero, sizeof zero);
    if (rcvbuf > 0 && setsockopt(c->fd, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
        (void)setsockopt(c->fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    socklen_t len = sizeof c->rcvbuf;
    (void)getsockopt(c->fd, SOL_SOCKET, SO_RCVBUF, &c->rcvbuf, &len);
    struct ip_mreq join;
    memset(&join, 0, sizeof join);
    join.imr_multiaddr = ga.sin_addr;
    join.imr_interface.s_addr = htonl(INADDR_ANY);
    if (bind(c->fd, (struct sockaddr *)&ga, sizeof ga) != 0 ||
        setsockopt(c->fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &join, sizeof join) != 0) {
        fprintf(stderr, "bench: udp_multicast:%s: %s\n", spec, strerror(errno));
        return -1;
    }
    const unsigned char ttl = 0; /* never past this machine */
    const unsigned char loop = 1;
    struct sockaddr_in any;
    memset(&any, 0, sizeof any);
    any.sin_family = AF_INET;
    len = sizeof any;
    if (setsockopt(c->tx_fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0 ||
        setsockopt(c->tx_fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) != 0 ||
        bind(c->tx_fd, (struct sockaddr *)&any, sizeof any) != 0 ||
        getsockname(c->tx_fd, (struct sockaddr *)&any, &len) != 0) {
        fprintf(stderr, "bench: udp_multicast:%s: sending socket: %s\n", spec, strerror(errno));
        return -1;
    }
    c->tx_port = ntohs(any.sin_port);
    return 0;
}

static size_t mp_str(uint8_t *p, const char *s)
{
    const size_t n = strlen(s);
    p[0] = (uint8_t)(0xA0U | n);
    memcpy(p + 1, s, n);
    return n + 1U;
}

static int udp_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
{
    uint8_t d[256];
    size_t n = 0U;
    d[n++] = 0x8BU; /* a map of 11, keys in python-can's order */
    n += mp_str(d + n, "timestamp");
    d[n++] = 0xCBU;
    double now = (double)bench_real_ns() / 1e9;
    uint64_t bits;
    memcpy(&bits, &now, sizeof bits);
    for (int k = 7; k >= 0; k--) {
        d[n++] = (uint8_t)(bits >> (8 * k));
    }
    n += mp_str(d + n, "arbitration_id");
    if (id < 0x80U) {
        d[n++] = (uint8_t)id;
    } else if (id < 0x100U) {
        d[n++] = 0xCCU;
        d[n++] = (uint8_t)id;
    } else {
        d[n++] = 0xCDU;
        d[n++] = (uint8_t)(id >> 8);
        d[n++] = (uint8_t)id;
    }
    n += mp_str(d + n, "is_extended_id");
    d[n++] = 0xC2U;
    n += mp_str(d + n, "is_remote_frame");
    d[n++] = 0xC2U;
    n += mp_str(d + n, "is_error_frame");
    d[n++] = 0xC2U;
    n += mp_str(d + n, "channel");
    d[n++] = 0xC0U;
    n += mp_str(d + n, "dlc");
    d[n++] = len;
    n += mp_str(d + n, "data");
    d[n++] = 0xC4U;
    d[n++] = len;
    memcpy(d + n, data, len);
    n += len;
    n += mp_str(d + n, "is_fd");
    d[n++] = 0xC2U;
    n += mp_str(d + n, "bitrate_switch");
    d[n++] = 0xC2U;
    n += mp_str(d + n, "error_state_indicator");
    d[n++] = 0xC2U;
    for (;;) {
        const ssize_t w = sendto(c->tx_fd, d, n, 0, (const struct sockaddr *)c->addr, sizeof(struct sockaddr_in));
        if (w == (ssize_t)n) {
            return 0;
        }
        if (w < 0 && (errno == ENOBUFS || errno == EAGAIN || errno == EINTR)) {
            struct pollfd p = {c->tx_fd, POLLOUT, 0};
            (void)poll(&p, 1, 10);
            continue;
        }
        fprintf(stderr, "bench: sendto: %s\n", w < 0 ? strerror(errno) : "short send");
        return -1;
    }
}

/* The msgpack values python-can's messages hold; *v = an unsigned integer's value or a bin's length (its bytes at
 * *bin), 1/0 for bools. Returns the bytes used, 0 when malformed or another type. */
static size_t mp_value(const uint8_t *p, size_t n, uint64_t *v, const uint8_t **bin)
{
    if (n == 0U) {
        return 0U;
    }
    const uint8_t t = p[0];
    *bin = NULL;
    if (t < 0x80U) {
        *v = t;
        return 1U;
    }
    if (t == 0xC0U || t == 0xC2U || t == 0xC3U) {
        *v = t == 0xC3U ? 1U : 0U;
        return 1U;
    }
    size_t w = t == 0xCCU ? 1U : t == 0xCDU ? 2U : t == 0xCEU ? 4U : t == 0xCFU ? 8U : t == 0xCBU ? 8U : 0U;
    if (w > 0U) {
        if (n < 1U + w) {
            return 0U;
        }
        *v = 0U;
        for (size_t k = 0U; k < w; k++) {
            *v = (*v << 8) | p[1 + k];
        }
        return 1U + w;
    }
    if (t == 0xC4U && n >= 2U && n >= 2U + p[1]) {
        *v = p[1];
        *bin = p + 2;
        return 2U + p[1];
    }
    return 0U;
}

/* A python-can datagram into a classic frame; 0 or -1 (not one). */
static int udp_decode(const uint8_t *p, size_t n, struct can_frame *f)
{
    if (n == 0U || (p[0] & 0xF0U) != 0x80U) {
        return -1;
    }
    const unsigned entries = p[0] & 0x0FU;
    size_t at = 1U;
    memset(f, 0, sizeof *f);
    bool ext = true; /* can.Message's default */
    for (unsigned e = 0U; e < entries; e++) {
        if (at >= n || (p[at] & 0xE0U) != 0xA0U) {
            return -1;
        }
        const size_t klen = p[at] & 0x1FU;
        const char *key = (const char *)p + at + 1;
        at += 1U + klen;
        uint64_t v;
        const uint8_t *bin;
        const size_t used = at <= n ? mp_value(p + at, n - at, &v, &bin) : 0U;
        if (used == 0U) {
            return -1;
        }
        at += used;
        if (klen == 14U && memcmp(key, "arbitration_id", 14) == 0) {
            f->can_id |= (canid_t)v;
        } else if (klen == 14U && memcmp(key, "is_extended_id", 14) == 0) {
            ext = v != 0U;
        } else if (klen == 15U && memcmp(key, "is_remote_frame", 15) == 0 && v != 0U) {
            f->can_id |= CAN_RTR_FLAG;
        } else if (klen == 14U && memcmp(key, "is_error_frame", 14) == 0 && v != 0U) {
            f->can_id |= CAN_ERR_FLAG;
        } else if (klen == 5U && memcmp(key, "is_fd", 5) == 0 && v != 0U) {
            return -1;
        } else if (klen == 4U && memcmp(key, "data", 4) == 0 && bin != NULL) {
            if (v > 8U) {
                return -1;
            }
            f->can_dlc = (uint8_t)v;
            memcpy(f->data, bin, (size_t)v);
        }
    }
    if (ext) {
        f->can_id |= CAN_EFF_FLAG;
    }
    return 0;
}

static int udp_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns)
{
    for (;;) {
        uint8_t d[512];
        struct sockaddr_in from;
        struct iovec iov = {d, sizeof d};
        char ctrl[CMSG_SPACE(sizeof(struct timespec)) + CMSG_SPACE(sizeof(uint32_t))];
        struct msghdr msg;
        memset(&msg, 0, sizeof msg);
        msg.msg_name = &from;
        msg.msg_namelen = sizeof from;
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = ctrl;
        msg.msg_controllen = sizeof ctrl;
        const ssize_t r = recvmsg(c->fd, &msg, MSG_DONTWAIT);
        if (r < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return 0;
            }
            fprintf(stderr, "bench: recvmsg: %s\n", strerror(errno));
            return -1;
        }
        *t_ns = frame_time(c, &msg);
        if (ntohs(from.sin_port) == c->tx_port || udp_decode(d, (size_t)r, f) != 0) {
            continue; /* our own datagram, or not a classic frame */
        }
        return 1;
    }
}

/* ---- socketcand: rawmode over TCP (docs/buses.md "socketcand"). */

static int scd_write(bench_can_t *c, const char *text)
{
    const size_t n = strlen(text);
    size_t done = 0U;
    while (done < n) {
        const ssize_t w = write(c->fd, text + done, n - done);
        if (w < 0 && errno == EINTR) {
            continue;
        }
        if (w <= 0) {
            fprintf(stderr, "bench: socketcand: write: %s\n", w < 0 ? strerror(errno) : "closed");
            return -1;
        }
        done += (size_t)w;
    }
    return 0;
}

/* The next `< ... >` element already read, copied to out without the brackets; 1, 0 (none whole yet). */
static int scd_element(bench_can_t *c, char *out, size_t out_size)
{
    char *lt = memchr(c->in, '<', c->in_len);
    if (lt == NULL) {
        c->in_len = 0U;
        return 0;
    }
    char *gt = memchr(lt, '>', c->in_len - (size_t)(lt - c->in));
    if (gt == NULL) {
        if (lt != c->in) {
            c->in_len -= (size_t)(lt - c->in);
            memmove(c->in, lt, c->in_len);
        }
        return 0;
    }
    (void)snprintf(out, out_size, "%.*s", (int)(gt - lt - 1), lt + 1);
    const size_t used = (size_t)(gt + 1 - c->in);
    c->in_len -= used;
    memmove(c->in, gt + 1, c->in_len);
    return 1;
}

/* Reads what is there (without waiting when nonblocking); 1 read, 0 nothing, -1 error or closed. */
static int scd_fill(bench_can_t *c, bool wait)
{
    if (c->in_len == sizeof c->in) {
        fprintf(stderr, "bench: socketcand: element too long\n");
        return -1;
    }
    for (;;) {
        const ssize_t r = recv(c->fd, c->in + c->in_len, sizeof c->in - c->in_len, wait ? 0 : MSG_DONTWAIT);
        if (r > 0) {
            c->in_len += (size_t)r;
            return 1;
        }
        if (r < 0 && errno == EINTR) {
            continue;
        }
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            return 0;
        }
        fprintf(stderr, "bench: socketcand: %s\n", r < 0 ? strerror(errno) : "connection closed");
        return -1;
    }
}

static int scd_expect(bench_can_t *c, const char *want)
{
    char el[256];
    while (scd_element(c, el, sizeof el) == 0) {
        if (scd_fill(c, true) < 0) {
            return -1;
        }
    }
    if (strcmp(el, want) != 0) {
        fprintf(stderr, "bench: socketcand: got '<%s>', wanted '<%s>'\n", el, want);
        return -1;
    }
    return 0;
}

static int scd_open(bench_can_t *c, const char *spec)
{
    char host[64];
    long port;
    const char *rest;
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    if (split_host_port(spec, host, sizeof host, &port, &rest) != 0 || rest[0] != ':' || rest[1] == '\0' ||
        inet_pton(AF_INET, host, &a.sin_addr) != 1) {
        fprintf(stderr, "bench: socketcand:%s: want socketcand:HOST:PORT:BUS\n", spec);
        return -1;
    }
    a.sin_port = htons((uint16_t)port);
    c->fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    const int one = 1;
    if (c->fd < 0 || setsockopt(c->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0 ||
        connect(c->fd, (struct sockaddr *)&a, sizeof a) != 0) {
        fprintf(stderr, "bench: socketcand %s:%ld: %s\n", host, port, strerror(errno));
        return -1;
    }
    char cmd[128];
    (void)snprintf(cmd, sizeof cmd, "< open %s >", rest + 1);
    if (scd_expect(c, " hi ") != 0 || scd_write(c, cmd) != 0 || scd_expect(c, " ok ") != 0 ||
        scd_write(c, "< rawmode >") != 0 || scd_expect(c, " ok ") != 0) {
        return -1;
    }
    return 0;
}

static int scd_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
{
    char cmd[96];
    int n = snprintf(cmd, sizeof cmd, "< send %03X %u", (unsigned)id, len);
    for (uint8_t k = 0U; k < len; k++) {
        n += snprintf(cmd + n, sizeof cmd - (size_t)n, " %02X", data[k]);
    }
    (void)snprintf(cmd + n, sizeof cmd - (size_t)n, " >");
    return scd_write(c, cmd);
}

/* `< frame ID SEC.USEC DATA >` into a classic frame (other elements: -1, skipped). */
static int scd_decode(const char *el, struct can_frame *f)
{
    char id[16];
    char stamp[32];
    char data[40] = "";
    if (sscanf(el, " frame %15s %31s %39s", id, stamp, data) < 2) {
        return -1;
    }
    memset(f, 0, sizeof *f);
    const size_t idlen = strlen(id);
    f->can_id = (canid_t)strtoul(id, NULL, 16) | (idlen == 8U ? CAN_EFF_FLAG : 0U);
    const size_t dlen = strlen(data);
    if (dlen % 2U != 0U || dlen > 16U) {
        return -1;
    }
    f->can_dlc = (uint8_t)(dlen / 2U);
    for (size_t k = 0U; k < dlen / 2U; k++) {
        char byte[3] = {data[2 * k], data[2 * k + 1], '\0'};
        f->data[k] = (uint8_t)strtoul(byte, NULL, 16);
    }
    return 0;
}

static int scd_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns)
{
    char el[256];
    for (;;) {
        while (scd_element(c, el, sizeof el) == 1) {
            if (scd_decode(el, f) == 0) {
                *t_ns = bench_real_ns();
                return 1;
            }
        }
        const int r = scd_fill(c, false);
        if (r <= 0) {
            return r;
        }
    }
}
