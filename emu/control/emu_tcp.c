/* A listening TCP socket by HOST:PORT: see emu_tcp.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "control/emu_tcp.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "device.h" /* device_parse_int */

static bool is_loopback(const struct sockaddr *a)
{
    if (a->sa_family == AF_INET) {
        return (ntohl(((const struct sockaddr_in *)(const void *)a)->sin_addr.s_addr) >> 24) == 127U;
    }
    if (a->sa_family == AF_INET6) {
        const struct in6_addr *v6 = &((const struct sockaddr_in6 *)(const void *)a)->sin6_addr;
        return IN6_IS_ADDR_LOOPBACK(v6) ||
               (IN6_IS_ADDR_V4MAPPED(v6) && v6->s6_addr[12] == 127U);
    }
    return false;
}

/* HOST and PORT of text; false when it is not HOST:PORT. */
static bool split_host_port(const char *text, char *host, size_t hostlen, long long *port)
{
    const char *colon = strrchr(text, ':');
    if (colon == NULL || colon == text || colon[1] == '\0' || (size_t)(colon - text) >= hostlen ||
        !device_parse_int(colon + 1, 0, 65535, port)) {
        return false;
    }
    memcpy(host, text, (size_t)(colon - text));
    host[colon - text] = '\0';
    const size_t len = strlen(host);
    if (len >= 2U && host[0] == '[' && host[len - 1U] == ']') { /* [::1] */
        memmove(host, host + 1, len - 2U);
        host[len - 2U] = '\0';
    }
    return host[0] != '\0';
}

bool tcp_host_port_ok(const char *text)
{
    char host[256];
    long long port;
    return split_host_port(text, host, sizeof host, &port);
}

int tcp_listen(tcp_listener_t *l, const char *option, const char *host_port, int backlog, char *err, size_t errlen)
{
    memset(l, 0, sizeof *l);
    l->fd = -1;
    long long port;
    if (!split_host_port(host_port, l->host, sizeof l->host, &port)) {
        (void)snprintf(err, errlen, "%s takes HOST:PORT (127.0.0.1:5020, [::1]:5020, localhost:0; port 0..65535, 0: "
                       "any free one), not '%s'", option, host_port);
        return EINVAL;
    }
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_NUMERICSERV;
    char service[8];
    (void)snprintf(service, sizeof service, "%lld", port);
    const int gai = getaddrinfo(l->host, service, &hints, &res);
    if (gai != 0 || res == NULL) {
        (void)snprintf(err, errlen, "%s: cannot resolve '%s': %s", option, l->host, gai_strerror(gai));
        return EINVAL;
    }
    int fd = -1, e = 0;
    for (const struct addrinfo *a = res; a != NULL && fd < 0; a = a->ai_next) {
        fd = socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) {
            e = errno;
            continue;
        }
        const int one = 1;
        (void)setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        if (bind(fd, a->ai_addr, a->ai_addrlen) != 0 || listen(fd, backlog) != 0) {
            e = errno;
            (void)close(fd);
            fd = -1;
            continue;
        }
        l->remote = !is_loopback(a->ai_addr);
    }
    freeaddrinfo(res);
    if (fd < 0) {
        (void)snprintf(err, errlen, "%s %s: %s", option, host_port, strerror(e));
        return e != 0 ? e : EINVAL;
    }
    struct sockaddr_storage bound;
    socklen_t len = sizeof bound;
    (void)snprintf(l->address, sizeof l->address, "?");
    if (getsockname(fd, (struct sockaddr *)&bound, &len) == 0) {
        if (bound.ss_family == AF_INET) {
            const struct sockaddr_in *v4 = (const struct sockaddr_in *)(const void *)&bound;
            (void)inet_ntop(AF_INET, &v4->sin_addr, l->address, sizeof l->address);
            l->port = ntohs(v4->sin_port);
        } else if (bound.ss_family == AF_INET6) {
            const struct sockaddr_in6 *v6 = (const struct sockaddr_in6 *)(const void *)&bound;
            (void)inet_ntop(AF_INET6, &v6->sin6_addr, l->address, sizeof l->address);
            l->port = ntohs(v6->sin6_port);
        }
    }
    (void)snprintf(l->name, sizeof l->name, strchr(l->address, ':') != NULL ? "[%s]:%u" : "%s:%u", l->address, l->port);
    l->fd = fd;
    return 0;
}
