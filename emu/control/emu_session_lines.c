/* A session's byte stream cut into lines: see emu_session.h (session_feed, session_finish). Apart from the
 * protocol (emu_session.c), as the transports' side of it: a line that cannot be a command is refused here, in
 * the framing it seems to have, and only the others are handed to session_run_line. */
#define _GNU_SOURCE /* PATH_MAX, ssize_t and POSIX calls, as in every file of the Linux program */
#include <string.h>

#include <jansson.h>

#include "runtime/emu.h"
#include "control/emu_json.h"
#include "control/emu_session.h"

/* Whether a line is an HTTP request line: METHOD SP TARGET SP HTTP/x (RFC 9112 section 3), what a browser sends
 * first on any connection it opens, a page's simple cross-origin POST to a control port included. The command
 * language has no such line. */
static bool is_http_request_line(const char *line)
{
    static const char tchar[] = "!#$%&'*+-.^_`|~0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz";
    const size_t method = strspn(line, tchar);
    if (method == 0U || line[method] != ' ') {
        return false;
    }
    const char *target = line + method + 1;
    const size_t target_len = strcspn(target, " \t\r");
    if (target_len == 0U || target[target_len] != ' ') {
        return false;
    }
    const char *version = target + target_len + 1;
    return strncmp(version, "HTTP/", 5U) == 0 && strcspn(version, " \t") == strlen(version);
}

/* The token equals the session's (compared in constant time for equal lengths: the token is a credential). */
static bool token_matches(const emu_session_t *s, const char *given)
{
    const size_t len = strlen(s->token);
    if (given == NULL || strlen(given) != len) {
        return false;
    }
    unsigned char diff = 0U;
    for (size_t i = 0U; i < len; i++) {
        diff |= (unsigned char)(s->token[i] ^ given[i]);
    }
    return diff == 0U;
}

/* The first line of a session that needs the token: hello with it, or the session ends (hang_up set, an error
 * answered). true: run the line (a JSON hello, answered by json_run); false: answered here or refused. */
static bool authenticate(emu_session_t *s, char *text, bool json)
{
    bool ok = false;
    if (json) {
        json_t *req = json_loads(text, JSON_REJECT_DUPLICATES, NULL);
        const char *cmd = json_is_object(req) ? json_string_value(json_object_get(req, "cmd")) : NULL;
        ok = cmd != NULL && strcmp(cmd, "hello") == 0 &&
             token_matches(s, json_string_value(json_object_get(req, "token")));
        json_decref(req);
    } else {
        char *save = NULL;
        const char *verb = strtok_r(text, " \t\r", &save);
        const char *token = verb != NULL && strcmp(verb, "hello") == 0 ? strtok_r(NULL, " \t\r", &save) : NULL;
        ok = token != NULL && strtok_r(NULL, " \t\r", &save) == NULL && token_matches(s, token);
        if (ok) {
            s->authenticated = true;
            session_printf(s, "hello: authenticated");
            return false; /* answered here: the command language has no hello */
        }
    }
    if (ok) {
        s->authenticated = true;
        return true;
    }
    static const char why[] = "this control connection needs the token first: hello TOKEN, or {\"cmd\":\"hello\","
                              "\"token\":\"TOKEN\"} (the token of --control-token-file)";
    if (json) {
        json_error(s, "%s", why);
    } else {
        session_printf(s, "error: %s", why);
    }
    s->hang_up = "it did not give the token first";
    return false;
}

static void on_line(void *ctx, line_verdict_t verdict, char *text, unsigned long lineno)
{
    void **pair = (void **)ctx;
    emu_t *emu = (emu_t *)pair[0];
    emu_session_t *s = (emu_session_t *)pair[1];
    if (emu->quit || s->hang_up != NULL) {
        return; /* the program is stopping (what came after `quit` does not run), or the session is ending */
    }
    const bool first = s->lines_seen++ == 0U;
    if (first && s->refuse_http && is_http_request_line(text)) {
        /* A browser (any page the engineer has open) or an HTTP client: nothing of it runs, its body least of all. */
        s->hang_up = "its first line is an HTTP request: a control socket takes control lines only";
        return;
    }
    const bool json = text[strspn(text, " \t\r")] == '{';
    if (s->token != NULL && !s->authenticated) {
        if (verdict != LINE_OK) {
            text[0] = '\0'; /* too long or cut by a NUL: refused as a line without the token */
        }
        if (!authenticate(s, text, json)) {
            return; /* answered, or refused and ending */
        }
    }
    if (verdict == LINE_TOO_LONG) {
        if (json) {
            json_error(s, "line %lu is longer than %d bytes: ignored", lineno, COMMAND_LINE_MAX);
        } else {
            session_printf(s, "error: %s line %lu is longer than %d bytes: ignored", s->name, lineno, COMMAND_LINE_MAX);
        }
    } else if (verdict == LINE_HAS_NUL) {
        if (json) {
            json_error(s, "line %lu holds a NUL byte: ignored", lineno);
        } else {
            session_printf(s, "error: %s line %lu holds a NUL byte: ignored", s->name, lineno);
        }
    } else {
        session_run_line(emu, s, text);
    }
}

void session_feed(emu_t *emu, emu_session_t *s, const char *data, size_t n)
{
    void *pair[2] = {emu, s};
    line_reader_feed(&s->lines, data, n, on_line, pair);
}

void session_finish(emu_t *emu, emu_session_t *s)
{
    void *pair[2] = {emu, s};
    line_reader_finish(&s->lines, on_line, pair);
}
