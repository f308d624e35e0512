/*
 * A listening TCP socket by HOST:PORT, the same rules for every option that opens one (--control-tcp, --web):
 * HOST is a name or a numeric address ("127.0.0.1", "[::1]", "localhost"), PORT 0 takes any free port; the first
 * address HOST resolves to that can be bound is used. Whether that address is a loopback one is reported, so that
 * the caller warns when it is not: whoever reaches such a socket controls the emulated nodes.
 */
#ifndef EMU_TCP_H
#define EMU_TCP_H

#include <stdbool.h>
#include <stddef.h>

typedef struct tcp_listener {
    int fd;             /* non-blocking, close-on-exec, listening; -1: none */
    char host[256];     /* HOST as given, without the brackets of an IPv6 address */
    char address[64];   /* the address bound, numeric ("127.0.0.1", "::1") */
    unsigned port;      /* the port bound (the kernel's choice for port 0) */
    char name[80];      /* address:port as the log shows it ("127.0.0.1:5020", "[::1]:5020") */
    bool remote;        /* the address is not a loopback one */
} tcp_listener_t;

/** Listens on host_port with the given backlog. 0, or an errno with a message in err that names option
 *  ("--control-tcp"); l->fd is -1 then. */
int tcp_listen(tcp_listener_t *l, const char *option, const char *host_port, int backlog, char *err, size_t errlen);

/** Whether text is HOST:PORT with a port of 0..65535 (checked with the options, before anything starts). */
bool tcp_host_port_ok(const char *text);

#endif /* EMU_TCP_H */
