/*
 * The parts of the web view's HTTP side (emu_web.h) that its files share: the checks every request passes
 * (emu_web_checks.c) and the answers, with the headers every answer carries, and the static files
 * (emu_web_answers.c). emu_web.c runs libmicrohttpd and the API on top of them. Only the web's own files include
 * this header (it brings libmicrohttpd's).
 */
#ifndef EMU_WEB_HTTP_H
#define EMU_WEB_HTTP_H

#include <microhttpd.h>
#include <stdbool.h>

#include "web/emu_web.h"

/** The header every /api request must carry, with the token of the page. */
#define WEB_TOKEN_HEADER "X-Canopen-Emu"

/** The request headers the checks read (NULL: absent). */
typedef struct web_request_headers {
    const char *host;
    const char *token;          /* WEB_TOKEN_HEADER */
    const char *content_length;
} web_request_headers_t;

/** Finds them in one pass over the request's headers; of a name given twice, the first counts (as
 *  MHD_lookup_connection_value's). */
void web_read_headers(struct MHD_Connection *c, web_request_headers_t *h);

/** Whether the Host header (NULL: none) names this server (emu_web_checks.c says which names do). */
bool web_host_ok(const emu_web_t *w, struct MHD_Connection *c, const char *host);

/** Whether token (the request's WEB_TOKEN_HEADER, NULL: none) is this run's (compared in constant time). */
bool web_token_ok(const emu_web_t *w, const char *token);

/** Adds the headers every answer carries (the API's: also Cache-Control: no-store); false: out of memory. */
bool web_add_headers(struct MHD_Response *r, bool api);

/** Queues r (NULL: out of memory, the connection is closed) with the headers of every answer; api adds
 *  Cache-Control: no-store. r is released. */
enum MHD_Result web_send(struct MHD_Connection *c, unsigned status, struct MHD_Response *r, bool api);

/** An error: {"error":"TEXT"} on the API, TEXT as a plain text line elsewhere; allow: the Allow header of a 405.
 *  text must need no JSON escaping (the web's own constants). */
enum MHD_Result web_send_error(struct MHD_Connection *c, unsigned status, bool api, const char *text,
                               const char *allow);

/** The session id of an API request's state (emu_web.c's; "" for a path without one). */
const char *web_request_id(const void *state);

/** GET of a static file: the embedded one with exactly this path ("/" is "/index.html", which carries the token),
 *  or 404. */
enum MHD_Result web_serve_file(const emu_web_t *w, struct MHD_Connection *c, const char *path);

#endif /* EMU_WEB_HTTP_H */
