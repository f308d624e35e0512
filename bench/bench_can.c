/* Shared helpers of the bus benchmarks: see bench_can.h. */
#define _GNU_SOURCE
#include "bench_can.h"
#include "bench_can_net.h"

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

int bench_can_open(bench_can_t *c, const char *ifname, int rcvbuf)
{
    memset(c, 0, sizeof *c);
    c->tx_fd = -1;
    if (strncmp(ifname, "udp_multicast:", 14) == 0) {
        c->kind = BENCH_UDP;
        return bench_udp_open(c, ifname + 14, rcvbuf);
    }
    if (strncmp(ifname, "socketcand:", 11) == 0) {
        c->kind = BENCH_SOCKETCAND;
        c->user_time = true;
        return bench_scd_open(c, ifname + 11);
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

int bench_can_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
{
    if (c->kind == BENCH_UDP) {
        return bench_udp_send(c, id, len, data);
    }
    if (c->kind == BENCH_SOCKETCAND) {
        return bench_scd_send(c, id, len, data);
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
int64_t bench_frame_time(bench_can_t *c, struct msghdr *msg)
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
    return c->kind == BENCH_UDP ? bench_udp_recv1(c, f, t_ns) : bench_scd_recv1(c, f, t_ns);
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
            *t_ns = bench_frame_time(c, &msg);
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
        t_ns[kept] = bench_frame_time(c, &mm[i].msg_hdr);
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
