/* libmicrohttpd's own cost of one request, the floor under the web view's idle exchange (bench/web_floor.py):
 * a daemon started as emu/web/emu_web.c starts its own (MHD_USE_EPOLL, no thread: run by a poll loop; the same
 * limits, the connection memory given on the command line) that answers every request with one empty response
 * made at start, carrying the web view's headers, as an exchange with nothing to give is answered. No checks, no
 * session, no nodes: what is left is libmicrohttpd's and the loop's.
 *
 *     web_floor PORT CONNECTION_MEMORY     (ends on SIGTERM)
 */
#define _POSIX_C_SOURCE 200809L
#include <microhttpd.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>

static struct MHD_Response *empty_answer;
static volatile sig_atomic_t stop;
static int request_mark; /* a request's state after its first call (emu_web.c's is its own) */

static void on_term(int sig)
{
    (void)sig;
    stop = 1;
}

/* As emu_web.c's: the first call sees the headers, the next ones the body (discarded), the last one answers. */
static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url, const char *method,
                                  const char *version, const char *data, size_t *size, void **state)
{
    (void)url;
    (void)method;
    (void)version;
    (void)data;
    if (*state == NULL) {
        *state = cls;
        return MHD_YES;
    }
    if (*size > 0U) {
        *size = 0U;
        return MHD_YES;
    }
    return MHD_queue_response(c, MHD_HTTP_OK, empty_answer);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        (void)fprintf(stderr, "usage: web_floor PORT CONNECTION_MEMORY\n");
        return 2;
    }
    const unsigned long port = strtoul(argv[1], NULL, 10), memory = strtoul(argv[2], NULL, 10);
    struct sigaction sa = {0};
    sa.sa_handler = on_term;
    (void)sigaction(SIGTERM, &sa, NULL);
    empty_answer = MHD_create_response_from_buffer(0U, (void *)"", MHD_RESPMEM_PERSISTENT);
    if (empty_answer == NULL ||
        MHD_add_response_header(empty_answer, MHD_HTTP_HEADER_CONTENT_TYPE, "application/x-ndjson") != MHD_YES ||
        MHD_add_response_header(empty_answer, "Content-Security-Policy",
                                "default-src 'self'; frame-ancestors 'none'") != MHD_YES ||
        MHD_add_response_header(empty_answer, "X-Content-Type-Options", "nosniff") != MHD_YES ||
        MHD_add_response_header(empty_answer, "Referrer-Policy", "no-referrer") != MHD_YES ||
        MHD_add_response_header(empty_answer, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store") != MHD_YES) {
        return 1;
    }
    struct MHD_Daemon *d = MHD_start_daemon(MHD_USE_EPOLL | MHD_USE_ERROR_LOG, (uint16_t)port, NULL, NULL,
                                            on_request, &request_mark,
                                            MHD_OPTION_CONNECTION_LIMIT, 16U,
                                            MHD_OPTION_PER_IP_CONNECTION_LIMIT, 8U,
                                            MHD_OPTION_CONNECTION_TIMEOUT, 30U,
                                            MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)memory,
                                            MHD_OPTION_END);
    const union MHD_DaemonInfo *info = d != NULL ? MHD_get_daemon_info(d, MHD_DAEMON_INFO_EPOLL_FD) : NULL;
    if (info == NULL) {
        return 1;
    }
    struct pollfd pfd = {.fd = info->epoll_fd, .events = POLLIN};
    while (!stop) {
        MHD_UNSIGNED_LONG_LONG ms = 0U;
        const int timeout = MHD_get_timeout(d, &ms) == MHD_YES ? (int)(ms < 1000U ? ms : 1000U) : 1000;
        (void)poll(&pfd, 1U, timeout);
        (void)MHD_run(d);
    }
    MHD_stop_daemon(d);
    MHD_destroy_response(empty_answer);
    return 0;
}
