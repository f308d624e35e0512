/* A CAN bus on an IP multicast group in python-can's udp_multicast format: see udp_multicast.h. */
#define _GNU_SOURCE
#include "udp_multicast.h"

#include <arpa/inet.h>
#include <errno.h>
#include <stdarg.h>
#include <linux/filter.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#define SUMMARY_INTERVAL_US 1000000U

static void logf_(udp_multicast_t *u, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void logf_(udp_multicast_t *u, const char *fmt, ...)
{
    if (u->log == NULL) {
        return;
    }
    char text[320];
    char line[sizeof u->name + 330];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    (void)snprintf(line, sizeof line, "%s: %s", u->name, text);
    u->log(u->log_ctx, line);
}

static int socket_error(char *err, size_t errlen, int e, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static int socket_error(char *err, size_t errlen, int e, const char *fmt, ...)
{
    if (err != NULL && errlen > 0U) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return e;
}

/* ttl=N and iface=NAME, comma-separated. */
static int parse_options(char *opts, udp_multicast_config_t *cfg, char *err, size_t errlen)
{
    for (char *opt = opts; opt != NULL && opt[0] != '\0';) {
        char *next = strchr(opt, ',');
        if (next != NULL) {
            *next++ = '\0';
        }
        if (strncmp(opt, "ttl=", 4U) == 0) {
            char *end = NULL;
            errno = 0;
            const unsigned long ttl = strtoul(opt + 4, &end, 10);
            if (opt[4] < '0' || opt[4] > '9' || *end != '\0' || errno != 0 || ttl > 255U) {
                return socket_error(err, errlen, EINVAL, "udp_multicast: ttl takes 0..255 (1: this link only), not '%s'",
                            opt + 4);
            }
            cfg->hop_limit = (uint8_t)ttl;
        } else if (strncmp(opt, "iface=", 6U) == 0) {
            if (opt[6] == '\0' || strlen(opt + 6) >= sizeof cfg->iface) {
                return socket_error(err, errlen, EINVAL, "udp_multicast: iface takes an interface name, not '%s'", opt + 6);
            }
            (void)snprintf(cfg->iface, sizeof cfg->iface, "%s", opt + 6);
        } else {
            return socket_error(err, errlen, EINVAL, "udp_multicast: unknown option '%s' (ttl=N, iface=NAME)", opt);
        }
        opt = next;
    }
    return 0;
}

int udp_multicast_parse(const char *text, udp_multicast_config_t *cfg, char *err, size_t errlen)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->port = UDP_MULTICAST_DEFAULT_PORT;
    cfg->hop_limit = 1U;
    char buf[160];
    if (strlen(text) >= sizeof buf) {
        return socket_error(err, errlen, EINVAL, "udp_multicast: '%s' is too long", text);
    }
    (void)snprintf(buf, sizeof buf, "%s", text);
    char *opts = strchr(buf, ',');
    if (opts != NULL) {
        *opts++ = '\0';
    }
    char *group = buf;
    if (group[0] == ':') {
        group++;
    } else if (group[0] != '\0') {
        return socket_error(err, errlen, EINVAL, "udp_multicast takes udp_multicast[:GROUP[:PORT]][,ttl=N][,iface=NAME], "
                    "not 'udp_multicast%s'", text);
    }
    char *port = NULL;
    if (group[0] == '[') {
        char *close = strchr(group, ']');
        if (close == NULL || (close[1] != '\0' && close[1] != ':')) {
            return socket_error(err, errlen, EINVAL, "udp_multicast: an IPv6 group goes in brackets: [ff15::1]:43113");
        }
        *close = '\0';
        port = close[1] == ':' ? close + 2 : NULL;
        group++;
    } else {
        char *colon = strchr(group, ':');
        if (colon != NULL && strchr(colon + 1, ':') == NULL) { /* one colon: GROUP:PORT; more: an IPv6 group alone */
            *colon = '\0';
            port = colon + 1;
        }
    }
    if (port != NULL) {
        char *end = NULL;
        errno = 0;
        const unsigned long p = strtoul(port, &end, 10);
        if (port[0] < '0' || port[0] > '9' || *end != '\0' || errno != 0 || p == 0U || p > 65535U) {
            return socket_error(err, errlen, EINVAL, "udp_multicast: the port is 1..65535, not '%s'", port);
        }
        cfg->port = (uint16_t)p;
    }
    if (group[0] == '\0') {
        group = (char *)UDP_MULTICAST_DEFAULT_GROUP_V4; /* only read: python-can's IPv4 default */
    }
    struct sockaddr_in *v4 = (struct sockaddr_in *)&cfg->group;
    struct sockaddr_in6 *v6 = (struct sockaddr_in6 *)&cfg->group;
    if (inet_pton(AF_INET, group, &v4->sin_addr) == 1) {
        if (!IN_MULTICAST(ntohl(v4->sin_addr.s_addr))) {
            return socket_error(err, errlen, EINVAL, "udp_multicast: %s is not an IPv4 multicast group (224.0.0.0/4; "
                        "python-can's default: " UDP_MULTICAST_DEFAULT_GROUP_V4 ")", group);
        }
        v4->sin_family = AF_INET;
        v4->sin_port = htons(cfg->port);
        cfg->group_len = (socklen_t)sizeof *v4;
    } else if (inet_pton(AF_INET6, group, &v6->sin6_addr) == 1) {
        if (!IN6_IS_ADDR_MULTICAST(&v6->sin6_addr)) {
            return socket_error(err, errlen, EINVAL, "udp_multicast: %s is not an IPv6 multicast group (ff00::/8; "
                        "python-can's default: " UDP_MULTICAST_DEFAULT_GROUP_V6 ")", group);
        }
        v6->sin6_family = AF_INET6;
        v6->sin6_port = htons(cfg->port);
        cfg->group_len = (socklen_t)sizeof *v6;
    } else {
        return socket_error(err, errlen, EINVAL, "udp_multicast: '%s' is not an IP multicast group (e.g. "
                    UDP_MULTICAST_DEFAULT_GROUP_V4 " or [" UDP_MULTICAST_DEFAULT_GROUP_V6 "])", group);
    }
    (void)inet_ntop(cfg->group.ss_family, cfg->group.ss_family == AF_INET ? (const void *)&v4->sin_addr
                                                                          : (const void *)&v6->sin6_addr,
                    cfg->group_text, sizeof cfg->group_text);
    return parse_options(opts, cfg, err, errlen);
}

void udp_multicast_name(const udp_multicast_config_t *cfg, char *out, size_t len)
{
    const bool v6 = cfg->group.ss_family == AF_INET6;
    (void)snprintf(out, len, "udp_multicast:%s%s%s:%u", v6 ? "[" : "", cfg->group_text, v6 ? "]" : "",
                   (unsigned)cfg->port);
}

/* The interface of the route to the group (what the kernel would join on when asked for none): one RTM_GETROUTE
 * request, as `ip route get GROUP`. 0 when there is none. */
static unsigned route_ifindex(const udp_multicast_config_t *cfg)
{
    const int fd = socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE);
    if (fd < 0) {
        return 0U;
    }
    struct timeval tv = {1, 0}; /* the kernel answers at once; a bound all the same */
    (void)setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    struct {
        struct nlmsghdr nh;
        struct rtmsg rt;
        char attrs[64];
    } req;
    memset(&req, 0, sizeof req);
    const bool v6 = cfg->group.ss_family == AF_INET6;
    const void *addr = v6 ? (const void *)&((const struct sockaddr_in6 *)&cfg->group)->sin6_addr
                          : (const void *)&((const struct sockaddr_in *)&cfg->group)->sin_addr;
    const size_t addr_len = v6 ? 16U : 4U;
    req.nh.nlmsg_len = NLMSG_LENGTH(sizeof req.rt);
    req.nh.nlmsg_type = RTM_GETROUTE;
    req.nh.nlmsg_flags = NLM_F_REQUEST;
    req.rt.rtm_family = (unsigned char)cfg->group.ss_family;
    req.rt.rtm_dst_len = (unsigned char)(addr_len * 8U);
    struct rtattr *rta = (struct rtattr *)(void *)((char *)&req + NLMSG_ALIGN(req.nh.nlmsg_len));
    rta->rta_type = RTA_DST;
    rta->rta_len = (unsigned short)RTA_LENGTH(addr_len);
    memcpy(RTA_DATA(rta), addr, addr_len);
    req.nh.nlmsg_len = NLMSG_ALIGN(req.nh.nlmsg_len) + RTA_ALIGN(rta->rta_len);
    unsigned ifindex = 0U;
    if (send(fd, &req, req.nh.nlmsg_len, 0) == (ssize_t)req.nh.nlmsg_len) {
        union {
            struct nlmsghdr nh;
            char bytes[4096];
        } answer;
        const ssize_t n = recv(fd, &answer, sizeof answer, 0);
        size_t left = n > 0 ? (size_t)n : 0U;
        for (const struct nlmsghdr *nh = &answer.nh; NLMSG_OK(nh, left); nh = NLMSG_NEXT(nh, left)) {
            if (nh->nlmsg_type != RTM_NEWROUTE) {
                continue;
            }
            const struct rtmsg *rt = (const struct rtmsg *)NLMSG_DATA(nh);
            size_t attr_left = RTM_PAYLOAD(nh);
            for (const struct rtattr *a = RTM_RTA(rt); RTA_OK(a, attr_left); a = RTA_NEXT(a, attr_left)) {
                if (a->rta_type == RTA_OIF && RTA_PAYLOAD(a) >= sizeof(int)) {
                    int oif;
                    memcpy(&oif, RTA_DATA(a), sizeof oif);
                    ifindex = oif > 0 ? (unsigned)oif : 0U;
                }
            }
        }
    }
    (void)close(fd);
    return ifindex;
}

static const char *family_hint(const udp_multicast_config_t *cfg)
{
    return cfg->group.ss_family == AF_INET6
               ? "an IPv6 route to the group (on a machine without one, e.g. inside a network namespace with only "
                 "lo: ip link set lo multicast on; ip -6 route add local ff00::/8 dev lo; docs/buses.md)"
               : "a route to the group (on a machine without one, e.g. inside a network namespace with only lo: "
                 "ip route add 224.0.0.0/4 dev lo; docs/buses.md)";
}

/* The receiving socket: bound to the group's port, joined on ifindex. */
static int open_rx(udp_multicast_t *u, unsigned ifindex, char *err, size_t errlen)
{
    const udp_multicast_config_t *cfg = &u->cfg;
    const int family = cfg->group.ss_family;
    const int fd = socket(family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        return socket_error(err, errlen, errno, "%s: cannot open a UDP socket: %s", u->name, strerror(errno));
    }
    u->rx_fd = fd;
    const int on = 1;
    const int off = 0;
    /* Others on this machine (python-can, another canopen-emu) bind the same port: python-can sets both */
    (void)setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    (void)setsockopt(fd, SOL_SOCKET, SO_REUSEPORT, &on, sizeof on);
    (void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on); /* each datagram tells the drops so far */
    int e = 0;
    if (family == AF_INET) {
        /* Only the group joined here, not every group some socket on this machine joined on the port */
        (void)setsockopt(fd, IPPROTO_IP, IP_MULTICAST_ALL, &off, sizeof off);
        struct ip_mreqn join;
        memset(&join, 0, sizeof join);
        join.imr_multiaddr = ((const struct sockaddr_in *)&cfg->group)->sin_addr;
        join.imr_ifindex = (int)ifindex;
        struct sockaddr_in any;
        memset(&any, 0, sizeof any);
        any.sin_family = AF_INET;
        any.sin_port = htons(cfg->port);
        /* Bound to the group address: datagrams to other groups on the same port stay out */
        if (bind(fd, (const struct sockaddr *)&cfg->group, cfg->group_len) != 0 &&
            bind(fd, (const struct sockaddr *)&any, sizeof any) != 0) {
            e = errno;
        } else if (setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &join, sizeof join) != 0) {
            e = errno;
        }
    } else {
#ifdef IPV6_MULTICAST_ALL
        (void)setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_ALL, &off, sizeof off);
#endif
        (void)setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &on, sizeof on);
        struct ipv6_mreq join;
        memset(&join, 0, sizeof join);
        join.ipv6mr_multiaddr = ((const struct sockaddr_in6 *)&cfg->group)->sin6_addr;
        join.ipv6mr_interface = ifindex;
        struct sockaddr_in6 any;
        memset(&any, 0, sizeof any);
        any.sin6_family = AF_INET6;
        any.sin6_port = htons(cfg->port);
        if (bind(fd, (const struct sockaddr *)&cfg->group, cfg->group_len) != 0 &&
            bind(fd, (const struct sockaddr *)&any, sizeof any) != 0) {
            e = errno;
        } else if (setsockopt(fd, IPPROTO_IPV6, IPV6_JOIN_GROUP, &join, sizeof join) != 0) {
            e = errno;
        }
    }
    if (e != 0) {
        return socket_error(err, errlen, e, "%s: cannot join group %s port %u on %s: %s", u->name, cfg->group_text,
                    (unsigned)cfg->port, u->ifname, strerror(e));
    }
    return 0;
}

/* The sending socket: its own port (so that its datagrams are told from everyone else's), the hop limit, multicast
 * out of ifindex with loopback on, connected to the group (its address then tells the source of what it sends). */
static int open_tx(udp_multicast_t *u, unsigned ifindex, char *err, size_t errlen)
{
    const udp_multicast_config_t *cfg = &u->cfg;
    const int fd = socket(cfg->group.ss_family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        return socket_error(err, errlen, errno, "%s: cannot open a UDP socket: %s", u->name, strerror(errno));
    }
    u->tx_fd = fd;
    const int hops = cfg->hop_limit;
    const int on = 1;
    int e = 0;
    if (cfg->group.ss_family == AF_INET) {
        struct ip_mreqn out;
        memset(&out, 0, sizeof out);
        out.imr_ifindex = (int)ifindex;
        const unsigned char ttl = cfg->hop_limit;
        const unsigned char loop = 1U;
        if (setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0 ||
            setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) != 0 ||
            setsockopt(fd, IPPROTO_IP, IP_MULTICAST_IF, &out, sizeof out) != 0) {
            e = errno;
        }
    } else {
        const int index = (int)ifindex;
        if (setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_HOPS, &hops, sizeof hops) != 0 ||
            setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_LOOP, &on, sizeof on) != 0 ||
            setsockopt(fd, IPPROTO_IPV6, IPV6_MULTICAST_IF, &index, sizeof index) != 0) {
            e = errno;
        }
    }
    if (e != 0) {
        return socket_error(err, errlen, e, "%s: cannot set up multicast on %s: %s", u->name, u->ifname, strerror(e));
    }
    if (connect(fd, (const struct sockaddr *)&cfg->group, cfg->group_len) != 0) {
        e = errno;
        return socket_error(err, errlen, e, "%s: cannot send to group %s: %s; it needs %s", u->name, cfg->group_text,
                    strerror(e), family_hint(cfg));
    }
    u->self_len = (socklen_t)sizeof u->self;
    if (getsockname(fd, (struct sockaddr *)&u->self, &u->self_len) != 0) {
        e = errno;
        return socket_error(err, errlen, e, "%s: getsockname: %s", u->name, strerror(e));
    }
    return 0;
}

/* The kernel drops this process's own datagrams before they reach the receiving socket. Multicast loopback (which the
 * other programs here need) gives each one back: at 8 x 127 nodes 50,800 a second, each queued, read and skipped
 * (a fifth of the emulator's time, measured) and each a wake-up of the loop. A classic BPF program on the socket
 * compares the UDP source port (the program sees the datagram from its UDP header) and the IP source address
 * (SKF_NET_OFF: the network header) with the sending socket's, as from_self() does; from_self() stays for where it
 * cannot be attached. BPF loads are big-endian: the constants are the values as they appear on the wire. */
/* Instruction n of a filter whose last one (last) accepts: on when the loaded value is k, else to the last. */
static struct sock_filter equal_or_accept(uint32_t k, unsigned n, unsigned last)
{
    const struct sock_filter j = BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, k, 0, (uint8_t)(last - n - 1U));
    return j;
}

static bool drop_own(udp_multicast_t *u)
{
    struct sock_filter f[16];
    unsigned n = 0U;
    const unsigned accept_at = u->self.ss_family == AF_INET ? 5U : 11U; /* index of the last instruction */
    if (u->self.ss_family == AF_INET) {
        const struct sockaddr_in *s = (const struct sockaddr_in *)&u->self;
        f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 0);
        f[n] = equal_or_accept(ntohs(s->sin_port), n, accept_at);
        n++;
        f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_W | BPF_ABS, (uint32_t)SKF_NET_OFF + 12U);
        f[n] = equal_or_accept(ntohl(s->sin_addr.s_addr), n, accept_at);
        n++;
    } else if (u->self.ss_family == AF_INET6) {
        const struct sockaddr_in6 *s = (const struct sockaddr_in6 *)&u->self;
        f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_H | BPF_ABS, 0);
        f[n] = equal_or_accept(ntohs(s->sin6_port), n, accept_at);
        n++;
        for (unsigned w = 0U; w < 4U; w++) { /* the source address: bytes 8-23 of the IPv6 header */
            uint32_t word;
            memcpy(&word, &s->sin6_addr.s6_addr[4U * w], sizeof word);
            f[n++] = (struct sock_filter)BPF_STMT(BPF_LD | BPF_W | BPF_ABS, (uint32_t)SKF_NET_OFF + 8U + 4U * w);
            f[n] = equal_or_accept(ntohl(word), n, accept_at);
            n++;
        }
    } else {
        return false;
    }
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, 0U);          /* own: dropped */
    f[n++] = (struct sock_filter)BPF_STMT(BPF_RET | BPF_K, 0xFFFFFFFFU); /* anyone else's: whole */
    const struct sock_fprog prog = {(unsigned short)n, f};
    return setsockopt(u->rx_fd, SOL_SOCKET, SO_ATTACH_FILTER, &prog, sizeof prog) == 0;
}

int udp_multicast_open(udp_multicast_t *u, const udp_multicast_config_t *cfg, const char *name,
                       udp_multicast_log_fn log, void *log_ctx, char *err, size_t errlen)
{
    memset(u, 0, sizeof *u);
    u->rx_fd = -1;
    u->tx_fd = -1;
    u->cfg = *cfg;
    u->log = log;
    u->log_ctx = log_ctx;
    (void)snprintf(u->name, sizeof u->name, "%s", name);
    unsigned ifindex;
    if (cfg->iface[0] != '\0') {
        ifindex = if_nametoindex(cfg->iface);
        if (ifindex == 0U) {
            return socket_error(err, errlen, ENODEV, "%s: interface %s: %s", name, cfg->iface, strerror(errno));
        }
    } else {
        ifindex = route_ifindex(cfg);
        if (ifindex == 0U) {
            return socket_error(err, errlen, ENETUNREACH, "%s: no route to group %s: it needs %s", name, cfg->group_text,
                        family_hint(cfg));
        }
    }
    if (if_indextoname(ifindex, u->ifname) == NULL) {
        (void)snprintf(u->ifname, sizeof u->ifname, "#%u", ifindex);
    }
    int e = open_rx(u, ifindex, err, errlen);
    if (e == 0) {
        e = open_tx(u, ifindex, err, errlen);
    }
    if (e != 0) {
        udp_multicast_close(u);
        return e;
    }
    u->rx_own_filtered = drop_own(u);
    return 0;
}

void udp_multicast_close(udp_multicast_t *u)
{
    udp_multicast_flush(u); /* what the last pass sent, as far as the socket takes it */
    if (u->rx_fd >= 0) {
        (void)close(u->rx_fd);
        u->rx_fd = -1;
    }
    if (u->tx_fd >= 0) {
        (void)close(u->tx_fd);
        u->tx_fd = -1;
    }
}

/* Points each message of the read-ahead at its buffer, sender and control space; the kernel changes the lengths of
 * the last two, so they are set again before every call. */
static void rx_setup(udp_multicast_t *u)
{
    for (unsigned i = 0U; i < UDP_MULTICAST_RX_BATCH; i++) {
        u->rx_iov[i].iov_base = u->rx_buf[i];
        u->rx_iov[i].iov_len = sizeof u->rx_buf[i];
        memset(&u->rx_msgs[i], 0, sizeof u->rx_msgs[i]);
        u->rx_msgs[i].msg_hdr.msg_iov = &u->rx_iov[i];
        u->rx_msgs[i].msg_hdr.msg_iovlen = 1U;
        u->rx_msgs[i].msg_hdr.msg_name = &u->rx_from[i];
        u->rx_msgs[i].msg_hdr.msg_control = u->rx_control[i].bytes;
    }
}

static int read_ahead(udp_multicast_t *u)
{
    if (u->rx_fd < 0) {
        return 0;
    }
    if (u->rx_msgs[0].msg_hdr.msg_iov != &u->rx_iov[0]) {
        rx_setup(u);
    }
    for (unsigned i = 0U; i < UDP_MULTICAST_RX_BATCH; i++) {
        u->rx_msgs[i].msg_hdr.msg_namelen = (socklen_t)sizeof u->rx_from[i];
        u->rx_msgs[i].msg_hdr.msg_controllen = sizeof u->rx_control[i].bytes;
        u->rx_msgs[i].msg_hdr.msg_flags = 0;
    }
    const int n = recvmmsg(u->rx_fd, u->rx_msgs, UDP_MULTICAST_RX_BATCH, MSG_DONTWAIT, NULL);
    if (n <= 0) {
        return 0; /* EAGAIN; an error of the socket is reported once and cleared (nothing to reopen) */
    }
    u->rx_next = 0U;
    u->rx_count = (unsigned)n;
    u->rx_drained = (unsigned)n < UDP_MULTICAST_RX_BATCH;
    return n;
}

/* The datagram came from this process's sending socket. */
static bool from_self(const udp_multicast_t *u, const struct sockaddr_storage *from, socklen_t len)
{
    if (len < sizeof(sa_family_t) || from->ss_family != u->self.ss_family) {
        return false;
    }
    if (from->ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)from;
        const struct sockaddr_in *s = (const struct sockaddr_in *)&u->self;
        return a->sin_port == s->sin_port && a->sin_addr.s_addr == s->sin_addr.s_addr;
    }
    const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)from;
    const struct sockaddr_in6 *s = (const struct sockaddr_in6 *)&u->self;
    return a->sin6_port == s->sin6_port && memcmp(&a->sin6_addr, &s->sin6_addr, sizeof a->sin6_addr) == 0;
}

static void sender_text(const struct sockaddr_storage *from, char *out, size_t len)
{
    char addr[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0U;
    if (from->ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)from;
        (void)inet_ntop(AF_INET, &a->sin_addr, addr, sizeof addr);
        port = ntohs(a->sin_port);
        (void)snprintf(out, len, "%s:%u", addr, port);
    } else {
        const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)from;
        (void)inet_ntop(AF_INET6, &a->sin6_addr, addr, sizeof addr);
        port = ntohs(a->sin6_port);
        (void)snprintf(out, len, "[%s]:%u", addr, port);
    }
}

/* The kernel's count of datagrams dropped for this socket (SO_RXQ_OVFL), as of this datagram. To the kernel a
 * datagram the own-datagram filter (drop_own) refused is a drop too, and every datagram this bus sent comes back to
 * it: those sent so far are taken off. Ones sent after this datagram arrived make the difference low for a moment,
 * never high: a loss may be reported a pass late, never one that did not happen. */
static void take_overflow(udp_multicast_t *u, const struct msghdr *h)
{
    for (struct cmsghdr *c = CMSG_FIRSTHDR(h); c != NULL; c = CMSG_NXTHDR((struct msghdr *)h, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
            uint32_t count;
            memcpy(&count, CMSG_DATA(c), sizeof count);
            const uint32_t more = count - u->rx_overflow_socket; /* the kernel's 32-bit count wraps */
            if (more != 0U && more < 0x80000000U) {
                u->rx_kernel_drops += more;
                u->rx_overflow_socket = count;
            }
            const unsigned long own = u->rx_own_filtered ? u->tx_frames : 0UL;
            if (u->rx_kernel_drops > own + u->rx_dropped) {
                u->rx_dropped = u->rx_kernel_drops - own;
            }
        }
    }
}

static void malformed(udp_multicast_t *u, const char *sender, const char *why, co_time_us_t now)
{
    u->malformed++;
    if (now >= u->malformed_window_end) {
        u->malformed_window_end = now + SUMMARY_INTERVAL_US;
        logf_(u, "a datagram from %s is not a python-can message (%s): ignored; such datagrams are logged at most "
              "once a second", sender, why);
    } else {
        u->malformed_unlogged++; /* summed up by udp_multicast_service at the end of the second */
        (void)snprintf(u->malformed_last, sizeof u->malformed_last, "from %s: %s", sender, why);
    }
}

int udp_multicast_read(udp_multicast_t *u, co_frame_t *frame, co_time_us_t now)
{
    for (;;) {
        if (u->rx_next == u->rx_count && read_ahead(u) <= 0) {
            return 0;
        }
        const unsigned k = u->rx_next++;
        const struct msghdr *h = &u->rx_msgs[k].msg_hdr;
        if (h->msg_controllen > 0U) {
            take_overflow(u, h);
        }
        if (from_self(u, &u->rx_from[k], h->msg_namelen)) {
            u->rx_own++; /* the local nodes had it from the bus's queue */
            continue;
        }
        char sender[INET6_ADDRSTRLEN + 10];
        char why[120];
        if ((h->msg_flags & MSG_TRUNC) != 0) {
            sender_text(&u->rx_from[k], sender, sizeof sender);
            (void)snprintf(why, sizeof why, "longer than %u bytes", UDP_DATAGRAM_MAX);
            malformed(u, sender, why, now);
            continue;
        }
        switch (udp_datagram_decode(u->rx_buf[k], u->rx_msgs[k].msg_len, frame, why, sizeof why)) {
        case UDP_DATAGRAM_FRAME:
            u->rx_frames++;
            return 1;
        case UDP_DATAGRAM_FD:
            sender_text(&u->rx_from[k], sender, sizeof sender);
            if (u->rx_fd_frames++ == 0U) {
                logf_(u, "a CAN FD frame from %s: the nodes take classic CAN only; such frames are ignored and "
                      "counted, not logged again", sender);
            }
            break;
        case UDP_DATAGRAM_ERROR_FRAME:
            sender_text(&u->rx_from[k], sender, sizeof sender);
            if (u->rx_error_frames++ == 0U) {
                logf_(u, "an error frame from %s: a bus of datagrams has no bus errors for the nodes; such frames are "
                      "ignored and counted, not logged again", sender);
            }
            break;
        default:
            sender_text(&u->rx_from[k], sender, sizeof sender);
            malformed(u, sender, why, now);
            break;
        }
    }
}

static void log_drops(udp_multicast_t *u)
{
    if (u->rx_dropped > u->rx_dropped_reported) {
        logf_(u, "%lu received datagram(s) lost (%lu in all): the receive buffer was full, the emulator fell behind",
              u->rx_dropped - u->rx_dropped_reported, u->rx_dropped);
        u->rx_dropped_reported = u->rx_dropped;
    }
}

static void log_malformed_summary(udp_multicast_t *u)
{
    if (u->malformed_unlogged > 0U) {
        logf_(u, "%lu more datagram(s) that are not python-can messages ignored (the last %s; %lu in all)",
              u->malformed_unlogged, u->malformed_last, u->malformed);
        u->malformed_unlogged = 0U;
    }
}

co_time_us_t udp_multicast_service(udp_multicast_t *u, co_time_us_t now)
{
    if (u->malformed_unlogged == 0U && u->rx_dropped == u->rx_dropped_reported) {
        return CO_NEVER;
    }
    if (now < u->malformed_window_end) {
        return u->malformed_window_end;
    }
    log_malformed_summary(u);
    log_drops(u);
    u->malformed_window_end = now + SUMMARY_INTERVAL_US; /* the next line of either kind a second from now at most */
    return CO_NEVER;
}

void udp_multicast_flush_log(udp_multicast_t *u)
{
    log_malformed_summary(u);
    log_drops(u);
    if (u->malformed > 0U || u->rx_fd_frames > 0U || u->rx_error_frames > 0U || u->tx_not_carried > 0U) {
        logf_(u, "%lu datagram(s) not python-can messages, %lu CAN FD and %lu error frame(s) read and not given to "
              "the nodes, %lu error frame(s) of the nodes not sent", u->malformed, u->rx_fd_frames,
              u->rx_error_frames, u->tx_not_carried);
    }
}
