/*
 * The control sockets of canopen-emu: --control-socket PATH (Unix domain, mode 0600) and --control-tcp HOST:PORT
 * (loopback unless another address is named, which is warned about). Each client is a control session
 * (emu_session.h): the command language or JSON lines, answered on its own connection, events if it subscribes.
 *
 * Nothing a client does can stop the nodes: sockets are non-blocking; what a client sends waits in its session
 * and runs a line at a time within the pass's budget for all sessions (emu_session_work.c), so that many busy
 * clients together cannot hold the loop; a client whose answers wait unread runs nothing more until it reads, and
 * no more of its input is read meanwhile; a large answer is streamed as the client reads it. A client that lets
 * more than CLIENT_OUTPUT_MAX bytes pile up unread (events it does not take) is disconnected (logged); a client that
 * vanishes mid-line loses that line and nothing else; one that connects and sends nothing costs a descriptor.
 * At most MAX_CLIENTS at once: the next is told so in one JSON line and closed.
 *
 * Neither socket is a web server, and a browser must not reach the nodes through them (any page the engineer has
 * open may send a cross-origin POST to a local port): a connection whose first line is an HTTP request line is
 * closed with nothing of it run. A TCP socket may require a token (--control-token-file; required where the
 * address is not a loopback one): the first line must then be hello with it, or the connection is closed.
 * Refusals are logged at a bounded rate (emu_log_limit.h).
 */
#ifndef EMU_SOCKET_H
#define EMU_SOCKET_H

#include <poll.h>
#include <stdbool.h>
#include <stddef.h>
#include <sys/un.h>

#include "control/emu_buffer.h"
#include "runtime/emu_log_limit.h"
#include "control/emu_session.h"

struct emu;

#define MAX_CLIENTS 64
#define CLIENT_OUTPUT_MAX (1024U * 1024U)
/** Bytes of one client read at once, at most (less when its session's input has less room). */
#define CLIENT_READ_MAX 4096U

/** Bytes of a token (--control-token-file), at most; at least SOCKETS_TOKEN_MIN. */
#define SOCKETS_TOKEN_MAX 256U
#define SOCKETS_TOKEN_MIN 16U

typedef struct control_client {
    int fd;
    emu_session_t session;
    byte_buffer_t out;      /* bytes waiting for the client (up to CLIENT_OUTPUT_MAX) */
    bool overflow;          /* more than CLIENT_OUTPUT_MAX waited: closed at the next pass */
    bool gone;              /* an error happened or the peer vanished: closed at the next pass */
    bool eof;               /* the peer sent all it will: closed once its lines ran and their answers left */
} control_client_t;

typedef struct emu_sockets {
    int unix_fd;                            /* -1: none */
    char unix_path[sizeof(((struct sockaddr_un *)0)->sun_path)];
    int tcp_fd;                             /* -1: none */
    char tcp_name[80];                      /* address:port actually bound (port 0 gets one from the kernel) */
    control_client_t *clients[MAX_CLIENTS];
    size_t n_clients;
    unsigned long next_number;              /* clients are numbered from 1 in the log */
    const char *tcp_token;                  /* non-NULL (tcp_token_text): a TCP client's first line is hello with it */
    char tcp_token_text[SOCKETS_TOKEN_MAX + 1];
    log_limit_t refusals;                   /* log lines of refused or hung-up clients, rate-limited */
} emu_sockets_t;

void sockets_init(emu_sockets_t *k);

/** Listens on a Unix socket at path (a stale socket file is replaced; a live one or any other file is an error).
 *  0, or an errno with a message in err. */
int sockets_listen_unix(emu_sockets_t *k, const char *path, char *err, size_t errlen);

/** Listens on TCP HOST:PORT ("127.0.0.1:5020", "[::1]:5020", "localhost:0"; emu_tcp.h). 0, or an errno with a
 *  message in err; *remote is set when the address is not a loopback one (the caller warns). */
int sockets_listen_tcp(emu_sockets_t *k, const char *host_port, bool *remote, char *err, size_t errlen);

/** Reads the token TCP clients must give first from a file: one line of SOCKETS_TOKEN_MIN..SOCKETS_TOKEN_MAX
 *  printable bytes without spaces (a final newline is not part of it). 0, or an errno with a message in err. */
int sockets_load_token(emu_sockets_t *k, const char *path, char *err, size_t errlen);

/** Adds the listeners and clients to pfd (at most max entries); returns how many. */
nfds_t sockets_poll_fds(const emu_sockets_t *k, struct pollfd *pfd, nfds_t max);

/** After poll: accepts, reads and runs lines, writes what waits, closes what ended. pfd as sockets_poll_fds
 *  filled it. */
void sockets_service(struct emu *emu, emu_sockets_t *k, const struct pollfd *pfd, nfds_t n);

/** Writes what waits for each client without blocking, and closes the clients that ended (once per pass of the
 *  main loop, after the sessions' work). */
void sockets_tidy(struct emu *emu, emu_sockets_t *k);

/** Closes everything: what waits for the clients gets up to 200 ms; the Unix socket file is removed. */
void sockets_close(struct emu *emu, emu_sockets_t *k);

#endif /* EMU_SOCKET_H */
