/* The benchmarks' buses without kernel CAN: python-can's udp_multicast (datagrams coded by the emulator's own
 * ports/linux/udp_datagram.c) and a socketcand server's channel in rawmode over TCP. See bench_can.h. */
#define _GNU_SOURCE
#include "bench_can.h"
#include "bench_can_net.h"

#include "udp_datagram.h"

#include <errno.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

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

int bench_udp_open(bench_can_t *c, const char *spec, int rcvbuf)
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

int bench_udp_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
{
    co_frame_t frame;
    memset(&frame, 0, sizeof frame);
    frame.id = id & CAN_EFF_MASK;
    frame.flags = (id & CAN_EFF_FLAG) != 0U ? CO_FRAME_EFF : 0U;
    frame.len = len;
    memcpy(frame.data, data, len);
    uint8_t d[256];
    const size_t n = udp_datagram_encode(&frame, (double)bench_real_ns() / 1e9, d, sizeof d);
    if (n == 0U) {
        fprintf(stderr, "bench: a frame udp_multicast cannot carry\n");
        return -1;
    }
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

/* A python-can datagram into a classic frame (the emulator's own decoder); 0, or -1 when it is not one. */
static int udp_decode(const uint8_t *p, size_t n, struct can_frame *f)
{
    co_frame_t frame;
    if (udp_datagram_decode(p, n, &frame, NULL, 0U) != UDP_DATAGRAM_FRAME) {
        return -1;
    }
    memset(f, 0, sizeof *f);
    f->can_id = frame.id | ((frame.flags & CO_FRAME_EFF) != 0U ? CAN_EFF_FLAG : 0U) |
                ((frame.flags & CO_FRAME_RTR) != 0U ? CAN_RTR_FLAG : 0U);
    f->can_dlc = frame.len;
    memcpy(f->data, frame.data, sizeof f->data);
    return 0;
}

int bench_udp_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns)
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
        *t_ns = bench_frame_time(c, &msg);
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

int bench_scd_open(bench_can_t *c, const char *spec)
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

int bench_scd_send(bench_can_t *c, uint32_t id, uint8_t len, const uint8_t *data)
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

int bench_scd_recv1(bench_can_t *c, struct can_frame *f, int64_t *t_ns)
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
