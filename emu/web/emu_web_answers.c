/* The answers of the web view, and its static files: see emu_web_http.h. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include "web/emu_web_http.h"

#include <stdio.h>
#include <string.h>

#include "web/emu_web_files.h"

/* ---- Answers ----------------------------------------------------------------------------------------------------- */

/* Every answer: the page runs only its own files and is framed by nobody; API answers are never stored. */
bool web_add_headers(struct MHD_Response *r, bool api)
{
    return MHD_add_response_header(r, "Content-Security-Policy", "default-src 'self'; frame-ancestors 'none'") ==
               MHD_YES &&
           MHD_add_response_header(r, "X-Content-Type-Options", "nosniff") == MHD_YES &&
           MHD_add_response_header(r, "Referrer-Policy", "no-referrer") == MHD_YES &&
           (!api || MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store") == MHD_YES);
}

enum MHD_Result web_send(struct MHD_Connection *c, unsigned status, struct MHD_Response *r, bool api)
{
    if (r == NULL) {
        return MHD_NO; /* out of memory: the connection is closed */
    }
    if (!web_add_headers(r, api)) {
        MHD_destroy_response(r);
        return MHD_NO; /* an answer without its headers is never sent */
    }
    const enum MHD_Result result = MHD_queue_response(c, status, r);
    MHD_destroy_response(r);
    return result;
}

/* An error: {"error":"TEXT"} on the API, TEXT as plain text elsewhere; allow: the Allow header of a 405. text is
 * one of this file's constants (no quotes or backslashes to escape). */
enum MHD_Result web_send_error(struct MHD_Connection *c, unsigned status, bool api, const char *text,
                                  const char *allow)
{
    char body[256];
    (void)snprintf(body, sizeof body, api ? "{\"error\":\"%s\"}\n" : "%s\n", text);
    struct MHD_Response *r = MHD_create_response_from_buffer(strlen(body), body, MHD_RESPMEM_MUST_COPY);
    if (r != NULL) {
        (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE,
                                      api ? "application/json" : "text/plain; charset=utf-8");
        if (allow != NULL) {
            (void)MHD_add_response_header(r, MHD_HTTP_HEADER_ALLOW, allow);
        }
    }
    return web_send(c, status, r, api);
}

/* ---- Static files ------------------------------------------------------------------------------------------------ */

/* A file of the embedded table, by exact path ("/" is "/index.html"): nothing is read from disk, no path joined. */
enum MHD_Result web_serve_file(const emu_web_t *w, struct MHD_Connection *c, const char *path)
{
    if (strcmp(path, "/") == 0) {
        path = "/index.html";
    }
    const web_file_t *f = NULL;
    for (size_t i = 0U; i < web_files_count && f == NULL; i++) {
        f = strcmp(web_files[i].path, path) == 0 ? &web_files[i] : NULL;
    }
    if (f == NULL) {
        return web_send_error(c, MHD_HTTP_NOT_FOUND, false, "not found", NULL);
    }
    if (strcmp(f->path, "/index.html") == 0) {
        /* It carries this run's token: never stored, and a page from an earlier run is not reused. */
        struct MHD_Response *r = MHD_create_response_from_buffer(w->index_len, w->index_html, MHD_RESPMEM_PERSISTENT);
        if (r != NULL) {
            (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, f->mime);
            (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
        }
        return web_send(c, MHD_HTTP_OK, r, false);
    }
    const char *match = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_IF_NONE_MATCH);
    const bool same = match != NULL && strcmp(match, f->etag) == 0;
    struct MHD_Response *r =
        MHD_create_response_from_buffer(same ? 0U : f->size, (void *)f->data, MHD_RESPMEM_PERSISTENT);
    if (r != NULL) {
        if (!same) {
            (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, f->mime);
        }
        (void)MHD_add_response_header(r, MHD_HTTP_HEADER_ETAG, f->etag);
        (void)MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache"); /* asked again, 304 if same */
    }
    return web_send(c, same ? MHD_HTTP_NOT_MODIFIED : MHD_HTTP_OK, r, false);
}

