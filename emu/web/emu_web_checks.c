/* The checks every request to the web view passes: see emu_web_http.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web_http.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>

/* ---- Checks every request passes --------------------------------------------------------------------------------- */

/* Whether a header's name (key_size bytes) is name, in any case. */
static bool is_header(const char *key, size_t key_size, const char *name, size_t name_size)
{
    return key_size == name_size && strncasecmp(key, name, name_size) == 0;
}

/* MHD_KeyValueIteratorN: each header of the request in turn; the first of a name counts. */
static enum MHD_Result take_header(void *cls, enum MHD_ValueKind kind, const char *key, size_t key_size,
                                   const char *value, size_t value_size)
{
    web_request_headers_t *h = (web_request_headers_t *)cls;
    (void)kind;
    (void)value_size;
    if (h->host == NULL && is_header(key, key_size, MHD_HTTP_HEADER_HOST, sizeof MHD_HTTP_HEADER_HOST - 1U)) {
        h->host = value;
    } else if (h->token == NULL && is_header(key, key_size, WEB_TOKEN_HEADER, sizeof WEB_TOKEN_HEADER - 1U)) {
        h->token = value;
    } else if (h->content_length == NULL &&
               is_header(key, key_size, MHD_HTTP_HEADER_CONTENT_LENGTH, sizeof MHD_HTTP_HEADER_CONTENT_LENGTH - 1U)) {
        h->content_length = value;
    }
    return MHD_YES;
}

void web_read_headers(struct MHD_Connection *c, web_request_headers_t *h)
{
    h->host = h->token = h->content_length = NULL;
    (void)MHD_get_connection_values_n(c, MHD_HEADER_KIND, take_header, h);
}

/* The numeric address a socket address holds (an IPv4-mapped IPv6 address as IPv4), or "". */
static void numeric_address(const struct sockaddr_storage *a, char *out, size_t size)
{
    out[0] = '\0';
    if (a->ss_family == AF_INET) {
        (void)inet_ntop(AF_INET, &((const struct sockaddr_in *)(const void *)a)->sin_addr, out, (socklen_t)size);
    } else if (a->ss_family == AF_INET6) {
        const struct in6_addr *v6 = &((const struct sockaddr_in6 *)(const void *)a)->sin6_addr;
        if (IN6_IS_ADDR_V4MAPPED(v6)) {
            (void)inet_ntop(AF_INET, &v6->s6_addr[12], out, (socklen_t)size);
        } else {
            (void)inet_ntop(AF_INET6, v6, out, (socklen_t)size);
        }
    }
}

/* Whether the Host header names this server: NAME[:PORT] ([V6]:PORT) with the port bound (80 when none is given)
 * and a name that can only mean this machine or was named on the command line: localhost, 127.0.0.1, ::1, the
 * HOST of --web, the address bound, or the address the connection came in on. A page of another site that
 * rebinds its own DNS name to this machine makes the browser send that name, which is none of these. */
bool web_host_ok(const emu_web_t *w, struct MHD_Connection *c, const char *host)
{
    if (host == NULL) {
        return false;
    }
    char name[256];
    const char *end = host[0] == '[' ? strchr(host, ']') : host + strcspn(host, ":");
    const char *start = host[0] == '[' ? host + 1 : host;
    if (end == NULL || end < start || (size_t)(end - start) >= sizeof name) {
        return false;
    }
    memcpy(name, start, (size_t)(end - start));
    name[end - start] = '\0';
    const char *port_text = end + (host[0] == '[' ? 1 : 0);
    unsigned long port = 80UL;
    if (port_text[0] == ':') {
        const size_t digits = strspn(port_text + 1, "0123456789");
        if (digits == 0U || digits > 5U || port_text[1 + digits] != '\0') {
            return false;
        }
        port = 0UL;
        for (size_t i = 1U; i <= digits; i++) { /* at most 5 digits: no overflow */
            port = port * 10UL + (unsigned long)(port_text[i] - '0');
        }
    } else if (port_text[0] != '\0') {
        return false;
    }
    if (port != w->listener.port || name[0] == '\0') {
        return false;
    }
    static const char *const local[] = {"localhost", "127.0.0.1", "::1"};
    for (size_t i = 0U; i < sizeof local / sizeof local[0]; i++) {
        if (strcasecmp(name, local[i]) == 0) {
            return true;
        }
    }
    if (strcasecmp(name, w->listener.host) == 0 || strcasecmp(name, w->listener.address) == 0) {
        return true;
    }
    const union MHD_ConnectionInfo *info = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    struct sockaddr_storage here;
    socklen_t len = sizeof here;
    char address[INET6_ADDRSTRLEN];
    if (info == NULL || getsockname(info->connect_fd, (struct sockaddr *)&here, &len) != 0) {
        return false;
    }
    numeric_address(&here, address, sizeof address);
    return address[0] != '\0' && strcasecmp(name, address) == 0;
}

/* The token header of an API request, compared in constant time. */
bool web_token_ok(const emu_web_t *w, const char *token)
{
    if (token == NULL || strlen(token) != WEB_ID_HEX) {
        return false;
    }
    unsigned char diff = 0U;
    for (size_t i = 0U; i < WEB_ID_HEX; i++) {
        diff |= (unsigned char)(token[i] ^ w->token[i]);
    }
    return diff == 0U;
}

