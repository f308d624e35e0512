/*
 * Fuzz target "control": control lines on canopen-emu's stdin, through the program's own code: control_start /
 * control_read (emu/control/emu_control.c), the session (emu/control/emu_session.c: text or JSON framing, subscriptions),
 * the line reader (emu/control/emu_lines.c), the JSON requests (emu/control/emu_json.c), the events (emu/runtime/emu_events.c)
 * and the command language (emu/control/emu_commands.c, device_command of devices/device.c and the models), driving
 * six emulated nodes, two of each device class, on fake ports (tests/support/fake_port.c: no socket; NVM in memory)
 * and two named buses.
 *
 * Input: the bytes that arrive on stdin. They go through a non-blocking pipe in chunks whose sizes (1 byte to
 * 8 KiB, from a hash of the input) put the ends of reads anywhere in a line; after each chunk the harness calls
 * control_read until the pipe is empty and processes the nodes as the main loop does, and stops, like the main
 * loop, once a command set emu.quit. At the end the pipe is closed (end of input).
 *
 * Replaced for the test: the output of emu_output.c (reply(), output_reply_line(), output_stdout_replies,
 * logline(): the harness records the lines instead of writing them), socketcan_now_us() (a clock that advances
 * 1 ms per call: runs are repeatable), and session_run_line() is wrapped (-Wl,--wrap=session_run_line) to see
 * which lines the control path hands on.
 *
 * Invariants (a violation prints "==fuzz== INVARIANT VIOLATION" and aborts), against a reference cutting of the
 * input into lines by docs/emulator.md "Command language":
 *  - each line of at most 2047 bytes without a NUL byte is run, once, with exactly its text, in input order; a last
 *    line without a newline is run at the end of input;
 *  - a longer line is refused whole with the reply "error: stdin line N is longer than 2047 bytes: ignored", a line
 *    holding a NUL byte with "error: stdin line N holds a NUL byte: ignored" (N its number from 1), and no part of it
 *    runs; when what was kept of it starts with '{' (blanks skipped), the refusal is the JSON
 *    {"id":null,"ok":false,"error":"line N is longer than 2047 bytes: ignored"} (or "holds a NUL byte");
 *  - emu.quit is set exactly when a line that was run has `quit` (or its alias `exit`) as its first word and at
 *    most 16 words, or is the JSON request {"cmd":"quit"} (or "exit"; with at most an "id" that is a string, an
 *    integer or null besides), and no line after that one is run or answered;
 *  - every JSON line (first byte '{' after blanks) is answered by exactly one JSON object with "ok" true or false;
 *    event lines ("event ..." or {"event":...}) may come at any time;
 *  - an input whose first byte is 0x01 runs (without that byte) in a restricted session, as a web session's: then
 *    nothing stops the emulator, a line whose first word is quit, exit or export-dcf (and a JSON quit) is answered
 *    with the web session's refusal, export-dcf's writer is never called; a session that is not restricted never
 *    answers with that refusal;
 *  - an input whose first byte is 0x02 runs (without that byte) in a session of a line server (emu_session_t.
 *    refuse_http, as a control socket's client): when its first line (what the line reader keeps of it) is an HTTP
 *    request line (RFC 9112: METHOD SP TARGET SP HTTP/..., a CR at the end allowed), nothing of the input runs or is
 *    answered and nothing stops the emulator; otherwise the rules above hold;
 *  - replies and device lines are NUL-terminated, device lines shorter than 512 bytes; every node's NMT state is
 *    a legal one; no crash, leak or undefined behaviour.
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <jansson.h>

#include "fuzz_abort.h"
#include "runtime/emu.h"
#include "control/emu_commands.h"
#include "control/emu_control.h"
#include "runtime/emu_bus.h"
#include "runtime/emu_events.h"
#include "faults/emu_faults.h"
#include "runtime/emu_output.h"
#include "control/emu_session.h"
#include "fake_port.h"

#define DOC_LINE_MAX 2047U
#define N_NODES 6U

typedef enum { L_RUN, L_TOO_LONG, L_NUL } verdict_t;

typedef struct ref_line {
    verdict_t verdict;
    const char *text; /* into the input */
    size_t len;
    bool quits;
    bool json;        /* a JSON request (what a refusal kept of it starts with '{') */
    bool refused;     /* restricted session: must be answered "... is refused in a web session: ..." */
} ref_line_t;

static const struct {
    const char *cls;
    const char *variant;
    uint8_t id;
} specs[N_NODES] = {{"pro-ionizer", NULL, 16}, {"pro-ionizer", "basic", 20}, {"sds", NULL, 17},
                    {"sds", "E", 21},          {"buerkert", NULL, 18},      {"buerkert", NULL, 22}};

static emu_t g_emu;
static emu_bus_t g_buses[2]; /* named only: their sockets are never opened (frames go to the fake ports) */
static emu_node_t g_nodes[N_NODES];
static co_time_us_t g_deadline[N_NODES]; /* each node's, as device_process and its faults gave it */
static fake_port_t g_ports[N_NODES];
static co_time_us_t g_now;

/* What the reference expects next: the lines in order, and where the harness is in them. */
static ref_line_t *g_ref;
static size_t g_ref_n;
static size_t g_next;     /* the next line the control path must hand over (run or refuse) */
static size_t g_quit_at;  /* index of the first line that quits, or g_ref_n */
static int g_in_command;  /* inside session_run_line: replies belong to the line */
static int g_json_answers; /* JSON objects answered to the line being run */
static char g_tmp[COMMAND_LINE_MAX + 1];
static char g_out[1U << 20]; /* one line written to stdout (a JSON answer with a device's help is long) */
static bool g_restricted;    /* the input began with RESTRICTED_MARK: the session is a web session's kind */
static bool g_refusal_seen;  /* the line being run was answered with a web session's refusal */

/* An input whose first byte is this runs in a restricted session (emu_session_t.restricted, as a web session),
 * the byte itself not fed. */
#define RESTRICTED_MARK '\x01'
/* An input whose first byte is this runs in a line server's session (refuse_http: a control socket's client). */
#define LINE_SERVER_MARK '\x02'
static bool g_line_server;   /* the input began with LINE_SERVER_MARK */
static bool g_http_first;    /* ... and its first line is an HTTP request line: nothing may run */

/* The refusals of a restricted session (emu_commands.c command_restriction), as the command language replies them
 * and as a JSON answer's "error" gives them (without "error: "). */
static bool is_refusal(const char *text)
{
    static const char *const refusals[] = {"quit is refused in a web session: it stops the emulator",
                                           "exit is refused in a web session: it stops the emulator",
                                           "export-dcf is refused in a web session: it writes a file"};
    const char *bare = strncmp(text, "error: ", 7U) == 0 ? text + 7 : text;
    for (size_t i = 0U; i < sizeof refusals / sizeof refusals[0]; i++) {
        if (strcmp(bare, refusals[i]) == 0) {
            return true;
        }
    }
    return false;
}

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void fail(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "\n==fuzz== INVARIANT VIOLATION [control] (line %zu of %zu):\n==fuzz==   ", g_next + 1U, g_ref_n);
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

static bool ws(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

/* True when a line's first word, as the command language splits words (blanks skipped, '#' before a word starts a
 * comment, a word in double quotes runs to the next quote), is one of `words` (NULL-terminated) and it has at most
 * MAX_ARGS words (a longer line is refused whole). */
static bool first_word_is(const char *l, size_t len, const char *const *words)
{
    size_t p = 0U;
    size_t count = 0U;
    bool matched = false;
    for (;;) {
        while (p < len && ws(l[p])) {
            p++;
        }
        if (p == len || l[p] == '#') {
            break;
        }
        if (count == MAX_ARGS) {
            return false;
        }
        size_t start = p;
        size_t end;
        if (l[p] == '"') {
            start = ++p;
            while (p < len && l[p] != '"') {
                p++;
            }
        } else {
            while (p < len && !ws(l[p])) {
                p++;
            }
        }
        end = p;
        p += p < len ? 1U : 0U; /* the quote or blank that ended the word */
        if (count == 0U) {
            for (const char *const *w = words; *w != NULL; w++) {
                matched = matched || (end - start == strlen(*w) && memcmp(l + start, *w, end - start) == 0);
            }
        }
        count++;
    }
    return matched;
}

/* A line that would stop the emulator: `quit` or its alias `exit`. */
static bool quits(const char *l, size_t len)
{
    static const char *const words[] = {"quit", "exit", NULL};
    return first_word_is(l, len, words);
}

/* A line a restricted (web) session refuses: what stops the emulator or writes a file (command_restriction). */
static bool restricted_word(const char *l, size_t len)
{
    static const char *const words[] = {"quit", "exit", "export-dcf", NULL};
    return first_word_is(l, len, words);
}

/* A JSON request line that stops the emulator: one object, "cmd" "quit" or "exit", nothing else but an "id" that
 * is a string, an integer or null (docs/control-protocol.md). The line has no NUL byte. */
static bool json_quits(const char *l, size_t len)
{
    char *text = malloc(len + 1U);
    if (text == NULL) {
        abort();
    }
    memcpy(text, l, len);
    text[len] = '\0';
    const char *p = text + strspn(text, " \t\r");
    bool q = false;
    json_error_t err;
    json_t *req = json_loads(p, JSON_REJECT_DUPLICATES, &err);
    if (json_is_object(req)) {
        json_t *cmd = json_object_get(req, "cmd");
        json_t *id = json_object_get(req, "id");
        const bool id_ok = id == NULL || json_is_string(id) || json_is_integer(id) || json_is_null(id);
        q = id_ok && json_is_string(cmd) && (strcmp(json_string_value(cmd), "quit") == 0 ||
                                             strcmp(json_string_value(cmd), "exit") == 0) &&
            json_object_size(req) == (id != NULL ? 2U : 1U);
    }
    json_decref(req);
    free(text);
    return q;
}

/* The line (or what a refusal kept of it: the first 2047 bytes, or up to the NUL) is a JSON request. */
static bool is_json(const char *l, size_t len)
{
    size_t p = 0U;
    while (p < len && (l[p] == ' ' || l[p] == '\t' || l[p] == '\r')) {
        p++;
    }
    return p < len && l[p] == '{';
}

/* RFC 9112 section 3: request-line = method SP request-target SP HTTP-version; method a token (tchar), the target
 * without blanks, the version "HTTP/" and what follows without blanks (a CR of a CRLF line may end it). */
static bool http_request_line(const char *l, size_t len)
{
    static const char tchar[] = "!#$%&'*+-.^_`|~";
    size_t i = 0U;
    while (i < len && ((l[i] >= '0' && l[i] <= '9') || (l[i] >= 'A' && l[i] <= 'Z') || (l[i] >= 'a' && l[i] <= 'z') ||
                       (l[i] != '\0' && strchr(tchar, l[i]) != NULL))) {
        i++;
    }
    if (i == 0U || i == len || l[i] != ' ') {
        return false;
    }
    const size_t target = ++i;
    while (i < len && l[i] != ' ' && l[i] != '\t' && l[i] != '\r') {
        i++;
    }
    if (i == target || i == len || l[i] != ' ') {
        return false;
    }
    i++;
    if (len - i < 5U || memcmp(l + i, "HTTP/", 5U) != 0) {
        return false;
    }
    for (i += 5U; i < len; i++) {
        if (l[i] == ' ' || l[i] == '\t') {
            return false;
        }
    }
    return true;
}

static void reference(const char *d, size_t n)
{
    size_t start = 0U;
    g_ref_n = 0U;
    g_quit_at = SIZE_MAX;
    for (size_t i = 0U; i <= n; i++) {
        if (i < n && d[i] != '\n') {
            continue;
        }
        if (i == n && start == n) {
            break;
        }
        ref_line_t *r = &g_ref[g_ref_n];
        r->text = d + start;
        r->len = i - start;
        r->verdict = r->len > DOC_LINE_MAX ? L_TOO_LONG : memchr(r->text, '\0', r->len) != NULL ? L_NUL : L_RUN;
        const size_t kept = r->verdict == L_TOO_LONG ? DOC_LINE_MAX
                          : r->verdict == L_NUL      ? (size_t)((const char *)memchr(r->text, '\0', r->len) - r->text)
                                                     : r->len;
        r->json = is_json(r->text, kept);
        r->quits = r->verdict == L_RUN && (r->json ? json_quits(r->text, r->len) : quits(r->text, r->len));
        /* A JSON export-dcf may fail its field checks first, so only the quits are sure to meet the refusal. */
        r->refused = g_restricted && r->verdict == L_RUN && (r->json ? r->quits : restricted_word(r->text, r->len));
        if (g_restricted) {
            r->quits = false; /* refused: nothing stops the emulator */
        }
        if (g_ref_n == 0U && g_line_server) {
            g_http_first = http_request_line(r->text, kept);
        }
        if (g_http_first) {
            r->quits = false; /* the session ends at its first line: nothing of it runs */
        }
        if (r->quits && g_quit_at == SIZE_MAX) {
            g_quit_at = g_ref_n;
        }
        g_ref_n++;
        start = i + 1U;
    }
    if (g_quit_at == SIZE_MAX) {
        g_quit_at = g_ref_n;
    }
}

/* ---- Replacements of the program's output and clock ---------------------------------------------------------- */

co_time_us_t socketcan_now_us(void)
{
    g_now += 1000U;
    return g_now;
}

/* A line the control path wrote outside a line's run: the refusal of the next line (or an event). */
static void control_path_line(const char *text)
{
    if (strncmp(text, "event ", 6U) == 0 || strncmp(text, "{\"event\":", 9U) == 0) {
        return; /* an event of a subscription, at any time */
    }
    if (g_http_first) {
        fail("reply '%s' in a session whose first line is an HTTP request line", text);
    }
    if (g_next >= g_ref_n || g_next > g_quit_at) {
        fail("reply '%s' with no line left to refuse (or after quit)", text);
    }
    const ref_line_t *r = &g_ref[g_next];
    char want[160];
    const char *what = r->verdict == L_TOO_LONG ? "is longer than 2047 bytes" : "holds a NUL byte";
    if (r->verdict == L_RUN) {
        fail("reply '%s' for line %zu, which must run ('%.60s')", text, g_next + 1U, r->text);
    } else if (r->json) {
        (void)snprintf(want, sizeof want, "{\"id\":null,\"ok\":false,\"error\":\"line %zu %s: ignored\"}", g_next + 1U, what);
    } else {
        (void)snprintf(want, sizeof want, "error: stdin line %zu %s: ignored", g_next + 1U, what);
    }
    if (strcmp(text, want) != 0) {
        fail("reply '%s', expected '%s'", text, want);
    }
    g_next++;
}

/* Replies to stdout outside a session (a device's message between commands): not a line's answer, and none may
 * come while a line runs' answers are checked (reply() fails those outside a line's run). */
static void stdout_reply(void *ctx, const char *text, size_t len)
{
    (void)ctx;
    (void)text;
    (void)len;
}

const reply_sink_t output_stdout_replies = {stdout_reply, NULL};

void reply(const reply_sink_t *to, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(g_tmp, sizeof g_tmp, fmt, ap);
    va_end(ap);
    if (n < 0) {
        fail("a reply could not be formatted (%s)", fmt);
    }
    if (g_in_command == 0) {
        fail("reply '%s' from the command language outside a line's run", g_tmp);
    }
    if (is_refusal(g_tmp)) {
        g_refusal_seen = true;
    }
    to->write(to->ctx, g_tmp, strlen(g_tmp)); /* as emu_output.c: to the session, or captured for JSON */
}

void output_reply_line(const char *line, size_t len)
{
    if (len == 0U || line[len - 1U] != '\n' || memchr(line, '\0', len) != NULL) {
        fail("a line to stdout without its newline, or with a NUL byte (%zu bytes)", len);
    }
    if (len > sizeof g_out) {
        len = sizeof g_out;
    }
    memcpy(g_out, line, len - 1U);
    g_out[len - 1U] = '\0';
    if (g_in_command > 0) {
        if (g_out[0] == '{' && strncmp(g_out, "{\"event\":", 9U) != 0) {
            json_error_t err;
            json_t *answer = json_loads(g_out, 0, &err);
            if (!json_is_object(answer) || !json_is_boolean(json_object_get(answer, "ok"))) {
                fail("the JSON answer '%.80s' is not an object with \"ok\" true or false", g_out);
            }
            const char *error = json_string_value(json_object_get(answer, "error"));
            if (error != NULL && is_refusal(error)) {
                g_refusal_seen = true;
            }
            json_decref(answer);
            g_json_answers++;
        }
        return; /* the line's own answer */
    }
    control_path_line(g_out);
}

void logline(int level, const char *fmt, ...)
{
    (void)level;
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
}

/* The bus of the program (emu_bus.c) is not linked: frames the faults send go to the node's fake port. */
co_status_t bus_send(emu_bus_t *b, emu_node_t *from, const co_frame_t *f)
{
    (void)b;
    return from->port.send(from->dev.cfg.port_ctx, f);
}

/* Nor its routing: this target gives frames to its node directly. */
void bus_routes_update(emu_bus_t *b, const emu_node_t *n)
{
    (void)b;
    (void)n;
}

void __real_session_run_line(emu_t *emu, emu_session_t *s, char *line);
void __wrap_session_run_line(emu_t *emu, emu_session_t *s, char *line);

void __wrap_session_run_line(emu_t *emu, emu_session_t *s, char *line)
{
    if (g_http_first) {
        fail("line '%.60s' run in a session whose first line is an HTTP request line", line);
    }
    if (g_next >= g_ref_n || g_next > g_quit_at) {
        fail("line '%.60s' run with no line left (or after quit)", line);
    }
    const ref_line_t *r = &g_ref[g_next];
    if (r->verdict != L_RUN) {
        fail("line %zu (%s) was run as '%.60s'", g_next + 1U, r->verdict == L_TOO_LONG ? "too long" : "with a NUL byte",
             line);
    }
    if (strlen(line) != r->len || memcmp(line, r->text, r->len) != 0) {
        fail("line %zu was run as '%.60s' (%zu bytes); the input has '%.60s' (%zu bytes)", g_next + 1U, line,
             strlen(line), r->text, r->len);
    }
    g_next++;
    g_in_command++;
    g_json_answers = 0;
    g_refusal_seen = false;
    if (s->restricted != g_restricted) {
        fail("line %zu runs in a session restricted=%d, the input asks %d", g_next, (int)s->restricted, (int)g_restricted);
    }
    __real_session_run_line(emu, s, line);
    g_in_command--;
    if (r->refused && !g_refusal_seen) {
        fail("line %zu ('%.60s') was not refused in a restricted session", g_next, r->text);
    }
    if (g_refusal_seen && !g_restricted) {
        fail("line %zu ('%.60s') was refused as in a web session, but the session is not one", g_next, r->text);
    }
    if (r->json && g_json_answers != 1) {
        fail("the JSON line %zu got %d answers, not one ('%.60s')", g_next, g_json_answers, r->text);
    }
}

bool __real_eds_class_export(device_t *dev, const char *path, char *why, size_t why_len);
bool __wrap_eds_class_export(device_t *dev, const char *path, char *why, size_t why_len);

/* export-dcf's writer: never reached from a restricted session (it writes a file at any path). */
bool __wrap_eds_class_export(device_t *dev, const char *path, char *why, size_t why_len)
{
    if (g_restricted) {
        fail("export-dcf wrote '%.60s' from a restricted session", path);
    }
    return __real_eds_class_export(dev, path, why, why_len);
}

static void device_print(void *ctx, const device_t *dev, const char *line)
{
    (void)ctx;
    (void)dev;
    if (line == NULL || strnlen(line, 512U) >= 512U) {
        fail("a device line is NULL or not shorter than 512 bytes");
    }
}

/* ---- The emulated nodes -------------------------------------------------------------------------------------- */

/* The nodes' state right after power-on, taken at the first run: every run starts from a copy of it. Powering six
 * nodes on (tables, 127 heartbeat-consumer slots of the Buerkert) took 90 % of a run; the copy is the same state,
 * since every pointer in it points into these static blocks and the clock restarts with it. */
static struct {
    emu_node_t node;
    fake_port_t port;
    uint8_t *values;
    uint8_t *model;
} g_pristine[N_NODES];
static co_time_us_t g_pristine_now;

static void nodes_power_on(void)
{
    g_emu.start = socketcan_now_us();
    for (size_t i = 0U; i < N_NODES; i++) {
        emu_node_t *n = &g_nodes[i];
        const device_class_t *cls = device_find_class(specs[i].cls);
        if (cls == NULL) {
            fail("device class %s is not registered", specs[i].cls);
        }
        memset(n, 0, sizeof *n);
        /* Of the exact sizes, so that ASan sees an overrun. */
        n->values = malloc(cls->od->values_size);
        n->model = malloc(cls->model_size > 0U ? cls->model_size : 1U);
        g_pristine[i].values = malloc(cls->od->values_size);
        g_pristine[i].model = malloc(cls->model_size > 0U ? cls->model_size : 1U);
        if (n->values == NULL || n->model == NULL || g_pristine[i].values == NULL || g_pristine[i].model == NULL) {
            abort();
        }
        n->cmdline_id = specs[i].id;
        n->bus = &g_buses[i < N_NODES / 2U ? 0U : 1U];
        faults_init(&n->faults);
        n->index = i;
        (void)snprintf(n->key, sizeof n->key, "%s-%u", cls->name, specs[i].id);
        fake_port_init(&g_ports[i], &g_now);
        n->port = g_ports[i].port;
        device_cfg_t cfg;
        memset(&cfg, 0, sizeof cfg);
        cfg.node_id = specs[i].id;
        cfg.serial = device_default_serial(cls) + specs[i].id;
        cfg.variant = specs[i].variant;
        cfg.port = &n->port;
        cfg.port_ctx = &g_ports[i];
        cfg.print = device_print;
        cfg.on_event = events_device_event; /* the program's: the events of a subscription are fuzzed too */
        cfg.event_ctx = n;
        if (device_init(&n->dev, cls, n->values, n->model, &cfg, g_emu.start) != CO_OK) {
            fail("node %s:%u could not start", specs[i].cls, specs[i].id);
        }
        g_deadline[i] = g_emu.start;
        g_emu.nodes[i] = n;
        g_pristine[i].node = *n;
        g_pristine[i].port = g_ports[i];
        memcpy(g_pristine[i].values, n->values, cls->od->values_size);
        memcpy(g_pristine[i].model, n->model, cls->model_size > 0U ? cls->model_size : 1U);
    }
    g_pristine_now = g_now;
}

static void nodes_start(void)
{
    /* Not memset: the node pointers stay. Two buses, so that NODE@IFACE is read as in a run with two. */
    g_emu.n_nodes = N_NODES;
    g_emu.n_buses = 2U;
    for (size_t b = 0U; b < 2U; b++) {
        (void)snprintf(g_buses[b].can.name, sizeof g_buses[b].can.name, "vcan%zu", b);
        g_buses[b].emu = &g_emu;
        schedule_init(&g_buses[b].schedule); /* the marks a command leaves (node_mark_dirty); deadlines: g_deadline */
        g_emu.buses[b] = &g_buses[b];
    }
    g_emu.log_level = LOG_NORMAL;
    g_emu.quit = false;
    memset(&g_emu.control, 0, sizeof g_emu.control);
    memset(&g_emu.script, 0, sizeof g_emu.script);
    g_emu.control.enabled = true;
    if (g_emu.nodes[0] == NULL) {
        nodes_power_on();
        return;
    }
    g_now = g_pristine_now;
    for (size_t i = 0U; i < N_NODES; i++) {
        emu_node_t *n = &g_nodes[i];
        const device_class_t *cls = n->dev.cls;
        *n = g_pristine[i].node;
        g_deadline[i] = g_emu.start;
        g_ports[i] = g_pristine[i].port;
        memcpy(n->values, g_pristine[i].values, cls->od->values_size);
        memcpy(n->model, g_pristine[i].model, cls->model_size > 0U ? cls->model_size : 1U);
    }
}

/* As the main loop: nodes concerned by a command (marked), or due, run. */
static void nodes_process(void)
{
    const co_time_us_t now = socketcan_now_us();
    for (size_t b = 0U; b < 2U; b++) {
        g_buses[b].schedule.n_marked = 0U; /* the marks' list; each node's mark is taken below */
        g_buses[b].schedule.marked_overflow = false;
    }
    for (size_t i = 0U; i < N_NODES; i++) {
        emu_node_t *n = &g_nodes[i];
        if (schedule_take_mark(&n->bus->schedule, (uint32_t)n->index) || now >= g_deadline[i]) {
            const co_time_us_t d = device_process(&n->dev, now);
            const co_time_us_t held = faults_run(n, now); /* as bus_run: held frames, the end of a bus-off */
            g_deadline[i] = held < d ? held : d;
            g_ports[i].n_sent = 0U; /* frames are not looked at here: keep the recorder from filling */
        }
        const co_nmt_state_t s = co_node_state(&n->dev.node);
        if (s != CO_NMT_INITIALISING && s != CO_NMT_STOPPED && s != CO_NMT_OPERATIONAL && s != CO_NMT_PRE_OPERATIONAL) {
            fail("node %zu is in NMT state 0x%02X", i, (unsigned)s);
        }
    }
}

/* ---- Entry point --------------------------------------------------------------------------------------------- */

static const size_t chunk_sizes[] = {1U, 2U, 3U, 5U, 8U, 64U, 100U, 511U, 2047U, 2048U, 2049U, 4095U, 4096U, 8192U};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    g_restricted = size > 0U && data[0] == (uint8_t)RESTRICTED_MARK;
    g_line_server = size > 0U && data[0] == (uint8_t)LINE_SERVER_MARK;
    g_http_first = false;
    if (g_restricted || g_line_server) {
        data++;
        size--;
    }
    const char *in = (const char *)data;
    g_ref = malloc((size + 1U) * sizeof *g_ref);
    if (g_ref == NULL) {
        abort();
    }
    reference(in, size);
    g_next = 0U;
    g_in_command = 0;

    int fds[2];
    if (pipe2(fds, O_NONBLOCK | O_CLOEXEC) != 0 || dup2(fds[0], STDIN_FILENO) != STDIN_FILENO) {
        perror("stdin pipe");
        abort();
    }
    (void)close(fds[0]);
    nodes_start();
    g_emu.n_sessions = 0U;
    control_start(&g_emu); /* finds O_NONBLOCK set: leaves the flag alone */
    g_emu.control.session.restricted = g_restricted;
    g_emu.control.session.refuse_http = g_line_server;
    nodes_process();

    uint32_t h = 2166136261U;
    for (size_t i = 0U; i < size; i++) {
        h = (h ^ data[i]) * 16777619U;
    }
    for (size_t pos = 0U; pos < size && !g_emu.quit;) {
        h ^= h << 13;
        h ^= h >> 17;
        h ^= h << 5;
        size_t n = chunk_sizes[h % (sizeof chunk_sizes / sizeof chunk_sizes[0])];
        n = n < size - pos ? n : size - pos;
        if (write(fds[1], in + pos, n) != (ssize_t)n) {
            perror("write to stdin pipe");
            abort();
        }
        pos += n;
        int waiting = 0;
        while (!g_emu.quit && ioctl(STDIN_FILENO, FIONREAD, &waiting) == 0 && waiting > 0) {
            control_read(&g_emu);
            nodes_process();
        }
    }
    (void)close(fds[1]);
    if (!g_emu.quit) {
        control_read(&g_emu); /* end of input: the last line without its newline */
        if (g_emu.control.open) {
            fail("stdin ended but the control input is still open");
        }
        nodes_process();
    }

    const bool want_quit = g_quit_at < g_ref_n;
    if (g_emu.quit != want_quit) {
        fail("emu.quit is %d; %s", (int)g_emu.quit,
             want_quit ? "a line says quit" : "no whole line says quit or exit");
    }
    const size_t handled = g_http_first ? 0U : want_quit ? g_quit_at + 1U : g_ref_n;
    if (g_next != handled) {
        fail("%zu lines were run or refused, expected %zu", g_next, handled);
    }
    free(g_ref);
    g_ref = NULL;
    return 0;
}
