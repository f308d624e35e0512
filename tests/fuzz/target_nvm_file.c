/*
 * Fuzz target "nvm_file": the NVM files of ports/linux/nvm_file.c as a crash, a user or another program may leave
 * them, loaded by a device of a registered class (devices/registry.c) through the nvm_file port functions, as
 * canopen-emu runs it: nvm_file_open (which recovers an interrupted store), device_init (the core loads the LSS
 * and parameter areas, the model its device area), SDO writes, a 0x1010 save, a power cycle or a restart.
 *
 * The files live in a scratch directory made once per process under $TMPDIR (default /tmp) and emptied at every
 * run: <dir>/<key>.params, .lss, .device, their .tmp files, <key>.journal and .journal.tmp (key "<class>-<id>" as
 * canopen-emu names it), and two files that are not ours: "other-1.params" (another node's) and "<key>.params.old".
 * On a disk the fsyncs make a run 2-5 times slower: the ctest test and long runs use TMPDIR=/dev/shm.
 *
 * Input: [0] bits 0-1 device class (pro-ionizer, sds, buerkert), bits 2-4 variant (0 the default); [1] node-ID on
 * the command line (0 the class default, else 1 + value % 127); then records until the input ends (reading past
 * it gives zeros; at most 32 records). Records before the node starts are the directory as found; later ones are
 * edits by hand.
 *   0x00-0x7F file: name = low nibble (modulo the 10 names), kind = bits 4-6:
 *             0 a regular file of u16 % 2049 given bytes; 1 the same, sealed as its name's kind of blob (the
 *             core's header, length and CRC for .params-type names, with the own OD signature unless the first
 *             byte given is odd; "COL1" and CRC for .lss-type; a trailing CRC-32 for .device-type; "CONVJ1",
 *             three area bytes (mod 3) and '\n' for journals); 2 a parameter blob of u8 % 40 records, each an
 *             object and value: u16 selector (bit 15 clear: a stored row of the OD, selector % their count;
 *             set: u16 index and u8 sub follow), u8 length (0xFF: the row's size), the value's bytes;
 *             3 an empty file; 4 an empty directory; 5 a directory holding a file; 6 a FIFO; 7 a symbolic link
 *             to another node's file, "<key>.params.old", a name that does not exist, or <key>.params.
 *   0x80-0x9F an SDO-origin write (co_od_write) of an object and value as in a parameter blob's record.
 *   0xA0-0xAF and 0xD0-0xFF a 0x1010:01 save (flags u8: bit 0 by an SDO frame, else co_od_write; bits 1-2 an edit by
 *             hand of the params file after a successful save: none, delete, truncate to u16 % size, flip the
 *             byte at u16 % size; bit 3 restart instead of device_power_cycle), then that power cycle.
 *   0xB0-0xBF time passes ((u8 + 1) x 10 s) and the device runs: the models' own saves of the device area.
 *   0xC0-0xCF a power cycle without a save (bit 0: a restart: nvm_file_close, nvm_file_open, device_init).
 * The node starts at the first record that is not a file; an input without a save ends with one (flags 0).
 *
 * Invariants (a violation prints "==fuzz== INVARIANT VIOLATION" and aborts):
 *  - recovery (nvm_file_open), against a reference reading of nvm_file.h: a journal (a regular file, not a link,
 *    starting "CONVJ1" + a byte per area + '\n') has each area it lists (byte 1) renamed from its .tmp, as
 *    rename(2) would; afterwards nothing is left at a temporary or journal name but a directory the input put
 *    there (a directory may hold someone's files: never removed), and the area files are what the reference says;
 *  - every load: the LSS area's status (CO_EV_NVM_LOADED 0x7E5) and the node-ID, and the parameter area's status
 *    (co_node_t.nvm_status and CO_EV_NVM_LOADED 0x1010), are what a reference reading of the file at that moment
 *    gives (absent or a dangling link: none; a directory, FIFO, link loop, short, bad header or CRC, an LSS
 *    node-ID or bit timing the node never writes: corrupt; another OD's signature: foreign; else loaded, for the
 *    parameters also refused); a load changes no file (the model may save its own device area);
 *  - a save answered OK leaves a valid parameter blob of this OD in <key>.params, and after the power cycle the
 *    node reports CO_NVM_LOADED and every stored row holds the value it had when saved (as the save read it: a read
 *    may normalise a value; node-ID-relative rows at their relative default move with the node-ID; a visible
 *    string up to its first NUL; a Buerkert's 0x2001:01/02 are its LSS area's, so not after an edit by hand);
 *    after an edit by hand the load reports what the edited file is, never a stale copy;
 *  - a failed or unanswered save leaves every area file as it was; a write refused changes no file;
 *  - no step creates a file at a temporary or journal name that outlives it, or any name not listed above; the
 *    files that are not ours never change (a link is never followed to write);
 *  - no crash, leak or undefined behaviour (ASan, UBSan, LeakSanitizer).
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz_abort.h"
#include "device.h"
#include "nvm_file.h"

/* ---- Input --------------------------------------------------------------------------------------------------- */

typedef struct rd {
    const uint8_t *p;
    size_t n;
    size_t pos;
} rd_t;

static uint8_t u8(rd_t *r) { return r->pos < r->n ? r->p[r->pos++] : 0U; }
static uint16_t u16(rd_t *r)
{
    const uint16_t lo = u8(r);
    return (uint16_t)(lo | (uint16_t)(u8(r) << 8));
}

/* ---- Names --------------------------------------------------------------------------------------------------- */

enum {
    A_PARAMS, A_LSS, A_DEVICE,  /* the areas */
    T_PARAMS, T_LSS, T_DEVICE,  /* their temporary files */
    J_JOURNAL, J_TMP,           /* the journal and its temporary file */
    F_OTHER, F_OLD,             /* not ours */
    N_NAMES
};
static const char *const suffixes[N_NAMES] = {".params", ".lss", ".device", ".params.tmp", ".lss.tmp",
                                              ".device.tmp", ".journal", ".journal.tmp", NULL, ".params.old"};
#define INNER "inner" /* the file inside a directory the input makes */

static bool is_temp(int i) { return i >= T_PARAMS && i <= J_TMP; }
static bool is_foreign(int i) { return i >= F_OTHER; }
/* Which kind of blob a name holds (for sealing): 0 params, 1 LSS, 2 device, 3 journal. */
static int blob_kind(int i)
{
    static const int kinds[N_NAMES] = {0, 1, 2, 0, 1, 2, 3, 3, 0, 0};
    return kinds[i];
}

/* ---- Directory snapshots ------------------------------------------------------------------------------------- */

typedef enum { E_ABSENT, E_FILE, E_DIR, E_DIR_FULL, E_FIFO, E_LINK, E_OTHER } ekind_t;

/* A file is told by its inode, size and modification time, not its content: a rename keeps all three, a write
 * changes the time, and reading every file at every step made a run twice as slow. */
typedef struct ent {
    ekind_t kind;
    unsigned long long ino;   /* E_FILE */
    long long size;
    long long mtime_ns;
    uint8_t head[10];         /* E_FILE: the first bytes (a journal's content) */
    size_t head_len;
    char target[80];          /* E_LINK */
} ent_t;

typedef struct snap {
    ent_t e[N_NAMES];
} snap_t;

static snap_t g_cur; /* the directory as the last snapshot found it */
static bool g_cur_ok; /* ... and nothing was made by hand since */

static const char *const kind_names[] = {"absent", "file", "empty directory", "directory with a file", "FIFO",
                                         "symbolic link", "something else"};

/* ---- State of a run ------------------------------------------------------------------------------------------ */

static struct {
    char root[PATH_MAX];            /* $TMPDIR/fuzz-nvm-file.<pid> */
    char dir[PATH_MAX];             /* root/nvm: the node's NVM directory */
    char key[64];
    char name[N_NAMES][96];
    char path[N_NAMES][PATH_MAX + 100];
    const device_class_t *cls;
    const char *variant;
    uint8_t id;                     /* command-line node-ID */
    device_t *dev;
    void *values;
    void *model;
    device_cfg_t cfg;
    co_port_t port;
    nvm_file_t nvm;
    bool nvm_open;
    bool up;                        /* the node runs */
    co_time_us_t now;
    int lss_status;                 /* last CO_EV_NVM_LOADED 0x7E5, -1 none */
    int params_status;              /* last CO_EV_NVM_LOADED 0x1010, -1 none */
    int store_code;                 /* last CO_EV_STORE code, -1 none */
    bool sdo_answered;
    uint8_t sdo_resp[8];
    bool saved_once;
    bool edited;                    /* a file was made by hand since the last load */
    unsigned step;
    const char *what;               /* the step in progress, for messages */
    co_od_entry_t store_subs[1024]; /* the OD's CO_OD_STORE sub-indices (those of a run one by one) */
    uint16_t n_store;
} g;

#if defined(__GNUC__)
__attribute__((noreturn, format(printf, 1, 2)))
#endif
static void fail(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "\n==fuzz== INVARIANT VIOLATION [nvm_file %s:%u] step %u (%s), directory %s:\n==fuzz==   ",
            g.cls != NULL ? g.cls->name : "?", g.id, g.step, g.what != NULL ? g.what : "?", g.dir);
    va_start(ap, fmt);
    fz_vabort(fmt, ap);
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_le32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0U; i < 4U; i++) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
}

/* CRC-32 (IEEE, reflected), written again here: the harness does not use the code it checks. */
static uint32_t crc32_ieee(const uint8_t *d, size_t n)
{
    uint32_t crc = 0xFFFFFFFFU;
    for (size_t i = 0U; i < n; i++) {
        crc ^= d[i];
        for (unsigned b = 0U; b < 8U; b++) {
            crc = (crc >> 1) ^ (0xEDB88320U & (0U - (crc & 1U)));
        }
    }
    return ~crc;
}

/* Reads a whole file (following links); false when it cannot be opened. */
static bool read_all(const char *path, uint8_t **data, size_t *len)
{
    const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    *data = NULL;
    *len = 0U;
    if (fd < 0) {
        return false;
    }
    size_t cap = 0U;
    for (;;) {
        if (*len == cap) {
            cap = cap == 0U ? 4096U : cap * 2U;
            uint8_t *p = realloc(*data, cap);
            if (p == NULL) {
                abort();
            }
            *data = p;
        }
        const ssize_t r = read(fd, *data + *len, cap - *len);
        if (r <= 0) {
            break;
        }
        *len += (size_t)r;
    }
    (void)close(fd);
    return true;
}

static void take(ent_t *e, const char *path)
{
    struct stat st;
    memset(e, 0, sizeof *e);
    if (lstat(path, &st) != 0) {
        e->kind = E_ABSENT;
    } else if (S_ISREG(st.st_mode)) {
        e->kind = E_FILE;
        e->ino = (unsigned long long)st.st_ino;
        e->size = (long long)st.st_size;
        e->mtime_ns = (long long)st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec;
        if (strstr(path, ".journal") != NULL) {
            const int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
            const ssize_t r = fd >= 0 ? read(fd, e->head, sizeof e->head) : -1;
            e->head_len = r > 0 ? (size_t)r : 0U;
            if (fd >= 0) {
                (void)close(fd);
            }
        }
    } else if (S_ISDIR(st.st_mode)) {
        char inner[PATH_MAX + 120];
        (void)snprintf(inner, sizeof inner, "%s/" INNER, path);
        e->kind = access(inner, F_OK) == 0 ? E_DIR_FULL : E_DIR;
    } else if (S_ISFIFO(st.st_mode)) {
        e->kind = E_FIFO;
    } else if (S_ISLNK(st.st_mode)) {
        e->kind = E_LINK;
        const ssize_t n = readlink(path, e->target, sizeof e->target - 1U);
        e->target[n > 0 ? n : 0] = '\0';
    } else {
        e->kind = E_OTHER;
    }
}

/* The directory now; any entry that is not one of the names (or a probe file of nvm_file_check_dir, which must be
 * gone too) is a violation. One readdir, then only the entries there: a lookup of an absent name is slow (a third
 * of a run was failed lookups), and a run takes many snapshots. */
static void snapshot(snap_t *s)
{
    bool seen[N_NAMES] = {false};
    /* The models' own saves are background commits (co_port.h CO_NVM_BACKGROUND): the directory a step leaves is
     * the one once they are written (and no edit by hand may race with them). */
    if (g.nvm_open) {
        nvm_file_flush(&g.nvm);
    }
    DIR *d = opendir(g.dir);
    if (d == NULL) {
        fail("the NVM directory %s is gone", g.dir);
    }
    const struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0) {
            continue;
        }
        int i = 0;
        while (i < N_NAMES && strcmp(de->d_name, g.name[i]) != 0) {
            i++;
        }
        if (i == N_NAMES) {
            char n[256];
            (void)snprintf(n, sizeof n, "%s", de->d_name);
            (void)closedir(d);
            fail("the directory holds '%s', which nobody should have made", n);
        }
        seen[i] = true;
    }
    (void)closedir(d);
    for (int i = 0; i < N_NAMES; i++) {
        if (seen[i]) {
            take(&s->e[i], g.path[i]);
        } else {
            memset(&s->e[i], 0, sizeof s->e[i]);
            s->e[i].kind = E_ABSENT;
        }
    }
    g_cur = *s;
    g_cur_ok = true;
}

/* The directory before a step: as the last snapshot found it, unless a file was made by hand since. */
static void current(snap_t *s)
{
    if (!g_cur_ok) {
        snapshot(&g_cur);
    }
    *s = g_cur;
}

static bool ent_eq(const ent_t *a, const ent_t *b)
{
    if (a->kind != b->kind) {
        return false;
    }
    if (a->kind == E_FILE) {
        return a->ino == b->ino && a->size == b->size && a->mtime_ns == b->mtime_ns;
    }
    return a->kind != E_LINK || strcmp(a->target, b->target) == 0;
}

static const char *describe(const ent_t *e)
{
    static char buf[4][200]; /* a message describes up to three entries */
    static unsigned k;
    char *b = buf[k++ & 3U];
    if (e->kind == E_FILE) {
        (void)snprintf(b, sizeof buf[0], "file of %lld bytes (inode %llu, mtime %lld ns)", e->size, e->ino, e->mtime_ns);
    } else if (e->kind == E_LINK) {
        (void)snprintf(b, sizeof buf[0], "link to %s", e->target);
    } else {
        (void)snprintf(b, sizeof buf[0], "%s", kind_names[e->kind]);
    }
    return b;
}

static bool is_dir(const ent_t *e) { return e->kind == E_DIR || e->kind == E_DIR_FULL; }

/* What any step may do to the directory: the names that are not ours never change; a temporary or journal name
 * ends as it was or empty (nothing made there outlives the step). Areas are checked by the caller. */
static void check_step(const snap_t *before, const snap_t *after)
{
    for (int i = 0; i < N_NAMES; i++) {
        const ent_t *b = &before->e[i];
        const ent_t *a = &after->e[i];
        if (is_foreign(i) && !ent_eq(b, a)) {
            fail("%s, not ours, changed: was %s, is %s", g.name[i], describe(b), describe(a));
        }
        if (is_temp(i) && !ent_eq(b, a) && a->kind != E_ABSENT) {
            fail("%s was %s and is left as %s", g.name[i], describe(b), describe(a));
        }
    }
}

/* ---- Reference: recovery -------------------------------------------------------------------------------------- */

/* rename(2) on the model: false (nothing changes) where the kernel refuses. */
static bool model_rename(snap_t *s, int from, int to)
{
    ent_t *f = &s->e[from];
    ent_t *t = &s->e[to];
    if (f->kind == E_ABSENT) {
        return false;
    }
    if (is_dir(t) ? !is_dir(f) || t->kind == E_DIR_FULL : is_dir(f) && t->kind != E_ABSENT) {
        return false; /* EISDIR, ENOTEMPTY, ENOTDIR */
    }
    *t = *f;
    memset(f, 0, sizeof *f);
    f->kind = E_ABSENT;
    return true;
}

static void model_unlink(snap_t *s, int i)
{
    if (!is_dir(&s->e[i])) {
        memset(&s->e[i], 0, sizeof s->e[i]);
        s->e[i].kind = E_ABSENT;
    }
}

/* nvm_file_open's recovery as nvm_file.h describes it: a journal decides the renames it lists; every temporary
 * file outside a carried-out rename goes, and so does the journal (or whatever is at its name that is not a
 * directory: a FIFO or a link there is not a journal of ours). */
static void reference_recovery(snap_t *s)
{
    const ent_t *j = &s->e[J_JOURNAL];
    const bool journal = j->kind == E_FILE && j->head_len == 10U && memcmp(j->head, "CONVJ1", 6U) == 0 && j->head[9] == '\n';
    for (int a = 0; a < 3; a++) {
        if (journal && j->head[6 + a] == 1U) {
            (void)model_rename(s, T_PARAMS + a, A_PARAMS + a);
        }
        model_unlink(s, T_PARAMS + a);
    }
    model_unlink(s, J_JOURNAL);
    model_unlink(s, J_TMP);
}

/* ---- Reference: what a load finds ----------------------------------------------------------------------------- */

#define REF_VALID (-1) /* a valid blob of this OD: loaded, or refused by a check of a value */

static int reference_params(void)
{
    struct stat st;
    if (stat(g.path[A_PARAMS], &st) != 0) {
        return errno == ENOENT ? (int)CO_NVM_NONE : (int)CO_NVM_CORRUPT;
    }
    if (!S_ISREG(st.st_mode)) {
        return CO_NVM_CORRUPT;
    }
    uint8_t *d;
    size_t n;
    if (!read_all(g.path[A_PARAMS], &d, &n)) {
        return CO_NVM_CORRUPT;
    }
    int r = CO_NVM_CORRUPT;
    if (n >= 16U && memcmp(d, "COS1", 4U) == 0 && le32(&d[8]) <= 0x10000U && 16U + le32(&d[8]) <= n &&
        crc32_ieee(&d[16], le32(&d[8])) == le32(&d[12])) {
        r = le32(&d[4]) == g.cls->od->signature ? REF_VALID : (int)CO_NVM_FOREIGN;
    }
    free(d);
    return r;
}

static int reference_lss(uint8_t *id)
{
    struct stat st;
    if (stat(g.path[A_LSS], &st) != 0) {
        return errno == ENOENT ? (int)CO_NVM_NONE : (int)CO_NVM_CORRUPT;
    }
    uint8_t *d;
    size_t n;
    if (!S_ISREG(st.st_mode) || !read_all(g.path[A_LSS], &d, &n)) {
        return CO_NVM_CORRUPT;
    }
    int r = CO_NVM_CORRUPT;
    /* Values the node writes: a node-ID 1-127, or "unconfigured" where LSS may unconfigure; a bit timing of the
     * device's table. */
    const bool unconfigure = (g.cls->core_options & CO_OPT_LSS_NO_UNCONFIGURE) == 0U;
    if (n >= 12U && memcmp(d, "COL1", 4U) == 0 && crc32_ieee(d, 8U) == le32(&d[8]) &&
        ((d[4] >= 1U && d[4] <= 127U) || (d[4] == CO_NODE_ID_UNCONFIGURED && unconfigure)) &&
        d[5] < CO_LSS_BIT_TIMING_COUNT && g.cls->bit_rates_kbit != NULL && g.cls->bit_rates_kbit[d[5]] != 0U) {
        r = CO_NVM_LOADED;
        *id = d[4];
    }
    free(d);
    return r;
}

/* ---- The node ------------------------------------------------------------------------------------------------- */

static co_status_t port_send(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    if (g.up && f->id == 0x580U + g.dev->node.node_id && f->len == 8U) {
        g.sdo_answered = true;
        memcpy(g.sdo_resp, f->data, 8U);
    }
    return CO_OK;
}

static co_status_t port_bit_rate(void *ctx, uint32_t kbit)
{
    (void)ctx;
    (void)kbit;
    return CO_OK;
}

static void on_event(void *ctx, const device_t *dev, const co_event_t *ev)
{
    (void)ctx;
    (void)dev;
    if (getenv("FUZZ_TRACE") != NULL) {
        fprintf(stderr, "step %u event %d 0x%04X:%02X value 0x%lX code 0x%08lX\n", g.step, (int)ev->kind, ev->index,
                ev->sub, (unsigned long)ev->value, (unsigned long)ev->code);
    }
    if (ev->kind == CO_EV_NVM_LOADED) {
        if (ev->index == 0x7E5U) {
            g.lss_status = (int)ev->value;
        } else {
            g.params_status = (int)ev->value;
        }
    } else if (ev->kind == CO_EV_STORE && ev->index == 0x1010U) {
        g.store_code = (int)ev->code;
    }
}

static void on_print(void *ctx, const device_t *dev, const char *line)
{
    (void)ctx;
    (void)dev;
    if (line == NULL || strnlen(line, 512U) >= 512U) {
        fail("a device line is NULL or not shorter than 512 bytes");
    }
}

static void nvm_open(void)
{
    char err[512];
    snap_t before;
    snap_t after;
    snap_t want;
    g.what = "nvm_file_open";
    current(&before);
    for (int i = 0; i < N_NAMES; i++) {
        want.e[i] = before.e[i];
    }
    reference_recovery(&want);
    if (nvm_file_open(&g.nvm, g.dir, g.key, err, sizeof err) != 0) {
        fail("nvm_file_open failed: %s", err);
    }
    g.nvm_open = true;
    snapshot(&after);
    check_step(&before, &after);
    for (int i = 0; i < N_NAMES; i++) {
        if (!ent_eq(&want.e[i], &after.e[i])) {
            fail("after recovery %s is %s; it was %s, the reference says %s", g.name[i], describe(&after.e[i]),
                 describe(&before.e[i]), describe(&want.e[i]));
        }
    }
}

/* Checks what a load (device_init or a power cycle) found against the files as they were just before it. */
static void check_load(int ref_params, int ref_lss, uint8_t lss_id)
{
    const co_node_t *node = &g.dev->node;
    if (g.lss_status != ref_lss) {
        fail("the LSS area loaded as %d, the file says %d", g.lss_status, ref_lss);
    }
    const uint8_t want_id = ref_lss == CO_NVM_LOADED ? lss_id : g.cfg.node_id;
    if (node->node_id != want_id) {
        fail("node-ID %u after power-on, expected %u (LSS file status %d)", node->node_id, want_id, ref_lss);
    }
    if (g.params_status != (int)node->nvm_status) {
        fail("CO_EV_NVM_LOADED said %d, nvm_status is %d", g.params_status, (int)node->nvm_status);
    }
    if (ref_params == REF_VALID ? node->nvm_status != CO_NVM_LOADED && node->nvm_status != CO_NVM_REFUSED
                                : (int)node->nvm_status != ref_params) {
        fail("the parameters loaded as %d, the file says %d (-1: loaded or refused)", (int)node->nvm_status, ref_params);
    }
}

/* Powers the node on (device_init, or device_power_cycle on the running node) and checks the load; a load reads
 * and never writes (the model may save its own device area). */
static void power_on(bool cycle)
{
    snap_t before;
    snap_t after;
    uint8_t lss_id = 0U;
    current(&before);
    const int ref_params = reference_params();
    const int ref_lss = reference_lss(&lss_id);
    g.lss_status = -1;
    g.params_status = -1;
    g.edited = false;
    g.what = cycle ? "device_power_cycle" : "device_init";
    const co_status_t st = cycle ? device_power_cycle(g.dev, g.now) : device_init(g.dev, g.cls, g.values, g.model, &g.cfg, g.now);
    if (st != CO_OK) {
        fail("%s failed (%d)", g.what, (int)st);
    }
    g.up = true;
    snapshot(&after);
    check_step(&before, &after);
    for (int a = A_PARAMS; a <= A_DEVICE; a++) {
        /* The model may save its own data as it starts (a Buerkert's drag indicators below the present values). */
        if (!ent_eq(&before.e[a], &after.e[a]) && (a != A_DEVICE || after.e[a].kind != E_FILE)) {
            fail("power-on changed %s: was %s, is %s", g.name[a], describe(&before.e[a]), describe(&after.e[a]));
        }
    }
    check_load(ref_params, ref_lss, lss_id);
}

static void start(void)
{
    nvm_open();
    power_on(false);
}

static void close_checked(void)
{
    snap_t before;
    snap_t after;
    g.what = "nvm_file_close";
    current(&before);
    g.up = false;
    nvm_file_close(&g.nvm);
    g.nvm_open = false;
    snapshot(&after);
    for (int i = 0; i < N_NAMES; i++) {
        if (!ent_eq(&before.e[i], &after.e[i])) {
            fail("nvm_file_close changed %s: was %s, is %s", g.name[i], describe(&before.e[i]), describe(&after.e[i]));
        }
    }
}

static void restart(void)
{
    close_checked();
    start();
}

/* ---- Files the input makes ------------------------------------------------------------------------------------ */

static void remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        return;
    }
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        if (d != NULL) {
            const struct dirent *de;
            while ((de = readdir(d)) != NULL) {
                if (strcmp(de->d_name, ".") != 0 && strcmp(de->d_name, "..") != 0) {
                    char sub[PATH_MAX + 300];
                    (void)snprintf(sub, sizeof sub, "%s/%s", path, de->d_name);
                    remove_tree(sub);
                }
            }
            (void)closedir(d);
        }
        (void)rmdir(path);
    } else {
        (void)unlink(path);
    }
}

static void write_file(const char *path, const uint8_t *d, size_t n)
{
    const int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0 || (n > 0U && write(fd, d, n) != (ssize_t)n) || close(fd) != 0) {
        perror(path);
        abort();
    }
}

static void seal(int name, uint8_t *b, size_t *len)
{
    switch (blob_kind(name)) {
    case 0: {
        const bool own = (b[0] & 1U) == 0U;
        if (*len < 16U) {
            memset(b + *len, 0, 16U - *len);
            *len = 16U;
        }
        memcpy(b, "COS1", 4U);
        if (own) {
            put_le32(&b[4], g.cls->od->signature);
        }
        put_le32(&b[8], (uint32_t)(*len - 16U));
        put_le32(&b[12], crc32_ieee(&b[16], *len - 16U));
        break;
    }
    case 1:
        if (*len < 12U) {
            memset(b + *len, 0, 12U - *len);
            *len = 12U;
        }
        memcpy(b, "COL1", 4U);
        put_le32(&b[8], crc32_ieee(b, 8U));
        break;
    case 2:
        if (*len < 4U) {
            memset(b + *len, 0, 4U - *len);
            *len = 4U;
        }
        put_le32(&b[*len - 4U], crc32_ieee(b, *len - 4U));
        break;
    default:
        if (*len < 10U) {
            memset(b + *len, 0, 10U - *len);
        }
        memcpy(b, "CONVJ1", 6U);
        for (int a = 6; a < 9; a++) {
            b[a] = (uint8_t)(b[a] % 3U);
        }
        b[9] = '\n';
        *len = 10U;
        break;
    }
}

/* An object and a value from the input: u16 selector (bit 15 clear: the OD's stored row selector % count; set: u16
 * index and u8 sub follow, any object), u8 length (0xFF: the row's size), the value's bytes (at most 255). */
static size_t object_value(rd_t *in, uint16_t *index, uint8_t *sub, uint8_t *v)
{
    const uint16_t sel = u16(in);
    const co_od_entry_t *e = NULL;
    if ((sel & 0x8000U) != 0U || g.n_store == 0U) {
        *index = u16(in);
        *sub = u8(in);
        static co_od_entry_t one; /* e may be returned in it */
        e = co_od_find(g.cls->od, *index, *sub, &one);
    } else {
        e = &g.store_subs[sel % g.n_store];
        *index = e->index;
        *sub = e->sub;
    }
    const uint8_t l = u8(in);
    const size_t len = l != 0xFFU ? l : e != NULL && e->size < 255U ? e->size : 0U;
    for (size_t i = 0U; i < len; i++) {
        v[i] = u8(in);
    }
    return len;
}

/* A parameter blob of records (object_value), with a valid header. */
static size_t params_blob(rd_t *in, uint8_t *b, size_t cap)
{
    size_t pos = 16U;
    const unsigned n = u8(in) % 40U;
    for (unsigned k = 0U; k < n; k++) {
        uint16_t index;
        uint8_t sub;
        uint8_t v[256];
        const size_t len = object_value(in, &index, &sub, v);
        if (pos + 4U + len > cap) {
            break;
        }
        b[pos] = (uint8_t)index;
        b[pos + 1U] = (uint8_t)(index >> 8);
        b[pos + 2U] = sub;
        b[pos + 3U] = (uint8_t)len;
        memcpy(&b[pos + 4U], v, len);
        pos += 4U + len;
    }
    b[0] = 0U; /* own signature */
    seal(A_PARAMS, b, &pos);
    return pos;
}

static void file_record(rd_t *in, uint8_t t)
{
    static uint8_t buf[4096];
    const int name = (t & 0x0F) % N_NAMES;
    const char *path = g.path[name];
    g.edited = g.edited || g.up;
    g_cur_ok = false;
    remove_tree(path);
    switch ((t >> 4) & 7U) {
    case 0:
    case 1: {
        size_t len = u16(in) % 2049U;
        for (size_t i = 0U; i < len; i++) {
            buf[i] = u8(in);
        }
        if (((t >> 4) & 7U) == 1U) {
            seal(name, buf, &len);
        }
        write_file(path, buf, len);
        break;
    }
    case 2:
        write_file(path, buf, params_blob(in, buf, sizeof buf));
        break;
    case 3:
        write_file(path, buf, 0U);
        break;
    case 4:
    case 5:
        if (mkdir(path, 0755) != 0) {
            perror(path);
            abort();
        }
        if (((t >> 4) & 7U) == 5U) {
            char inner[PATH_MAX + 120];
            (void)snprintf(inner, sizeof inner, "%s/" INNER, path);
            write_file(inner, (const uint8_t *)"x", 1U);
        }
        break;
    case 6:
        if (mkfifo(path, 0644) != 0) {
            perror(path);
            abort();
        }
        break;
    default: {
        const char *targets[4] = {g.name[F_OTHER], g.name[F_OLD], "missing", g.name[A_PARAMS]};
        if (symlink(targets[u8(in) % 4U], path) != 0) {
            perror(path);
            abort();
        }
        break;
    }
    }
}

/* ---- Writes, saves, time -------------------------------------------------------------------------------------- */

/* An SDO write of a stored row. Some are stored by the write itself (a Buerkert's address and baud rate in the LSS
 * area, its drag indicators in the device area): those areas may become files; nothing else changes. */
static void write_record(rd_t *in)
{
    uint8_t v[256];
    uint16_t index;
    uint8_t sub;
    const size_t len = object_value(in, &index, &sub, v);
    snap_t before;
    snap_t after;
    current(&before);
    g.what = "SDO write";
    const uint32_t r = co_od_write(&g.dev->node, index, sub, v, len, CO_ORIGIN_SDO);
    if (getenv("FUZZ_TRACE") != NULL) {
        fprintf(stderr, "step %u write 0x%04X:%02X (%zu bytes, first 0x%02X): 0x%08lX\n", g.step, index, sub, len,
                len > 0U ? v[0] : 0U, (unsigned long)r);
    }
    snapshot(&after);
    check_step(&before, &after);
    if (!ent_eq(&before.e[A_PARAMS], &after.e[A_PARAMS])) {
        fail("a write changed %s: was %s, is %s", g.name[A_PARAMS], describe(&before.e[A_PARAMS]),
             describe(&after.e[A_PARAMS]));
    }
    for (int a = A_LSS; a <= A_DEVICE; a++) {
        if (!ent_eq(&before.e[a], &after.e[a]) && (after.e[a].kind != E_FILE || r != 0U)) {
            fail("a write answered 0x%08lX left %s as %s (was %s)", (unsigned long)r, g.name[a], describe(&after.e[a]),
                 describe(&before.e[a]));
        }
    }
}

/* The value a stored row must have after a save and a reload: as saved, or, for a node-ID-relative row that was at
 * its relative default (not stored: co_store.c), the default moved to the node-ID after the reload. */
static void expected_value(const co_od_entry_t *e, const uint8_t *saved, uint8_t old_id, uint8_t new_id, uint8_t *out)
{
    memcpy(out, saved + e->offset, e->size);
    if ((e->flags & CO_OD_NODEID) == 0U || e->size > 4U) {
        return;
    }
    uint8_t def[4];
    co_od_copy_defaults(g.cls->od, e->offset, e->size, def);
    uint32_t d = 0U;
    uint32_t v = 0U;
    for (unsigned i = 0U; i < e->size; i++) {
        d |= (uint32_t)def[i] << (8U * i);
        v |= (uint32_t)saved[e->offset + i] << (8U * i);
    }
    if (v != d + (old_id != CO_NODE_ID_UNCONFIGURED ? old_id : 0U)) {
        return; /* unconfigured: the default is the table's value (co_od_defaults_area adds no node-ID) */
    }
    const uint32_t moved = new_id != CO_NODE_ID_UNCONFIGURED ? d + new_id : d;
    for (unsigned i = 0U; i < e->size; i++) {
        out[i] = (uint8_t)(moved >> (8U * i));
    }
}

static void hand_edit(unsigned how, uint16_t param)
{
    uint8_t *d;
    size_t n;
    g.what = "edit by hand";
    g_cur_ok = false;
    if (how == 1U) {
        (void)unlink(g.path[A_PARAMS]);
        return;
    }
    if (!read_all(g.path[A_PARAMS], &d, &n) || n == 0U) {
        fail("the saved params file cannot be read");
    }
    if (how == 2U) {
        n = param % n;
    } else {
        d[param % n] ^= 0x5AU;
    }
    write_file(g.path[A_PARAMS], d, n);
    free(d);
}

static void save_record(rd_t *in)
{
    const uint8_t flags = u8(in);
    const uint16_t param = u16(in);
    co_node_t *node = &g.dev->node;
    const co_od_t *od = g.cls->od;
    snap_t before;
    snap_t after;
    current(&before);
    uint8_t *image = malloc(od->values_size);
    if (image == NULL) {
        abort();
    }
    const uint8_t old_id = node->node_id;
    bool answered = false;
    bool ok = false;
    g.store_code = -1;
    if ((flags & 1U) != 0U) {
        g.what = "0x1010 save by SDO";
        if (node->node_id >= 1U && node->node_id <= 127U) {
            const co_frame_t f = {0x600U + node->node_id, 8U, 0U, {0x23, 0x10, 0x10, 0x01, 's', 'a', 'v', 'e'}};
            g.sdo_answered = false;
            (void)device_rx(g.dev, &f, g.now);
            answered = g.sdo_answered;
            ok = answered && g.sdo_resp[0] == 0x60U && g.sdo_resp[1] == 0x10U && g.sdo_resp[2] == 0x10U &&
                 g.sdo_resp[3] == 0x01U;
            if (answered && !ok && (g.sdo_resp[0] != 0x80U || le32(&g.sdo_resp[4]) == 0U)) {
                fail("the save was answered with %02X ... %08lX", g.sdo_resp[0], (unsigned long)le32(&g.sdo_resp[4]));
            }
        }
    } else {
        g.what = "0x1010 save by co_od_write";
        answered = true;
        ok = co_od_write(node, 0x1010U, 0x01U, "save", 4U, CO_ORIGIN_SDO) == 0U;
    }
    /* The values as saved: after the save, whose reads may normalise a value as a read over SDO does (a PRO IONIZER
     * release timeout below 500 ms reads, and is saved, as 0). */
    memcpy(image, g.values, od->values_size);
    if (answered && g.store_code >= 0 && (g.store_code == 0) != ok) {
        fail("CO_EV_STORE code 0x%08X but the save was answered %s", (unsigned)g.store_code, ok ? "OK" : "with an abort");
    }
    snapshot(&after);
    check_step(&before, &after);
    for (int a = A_PARAMS; a <= A_DEVICE; a++) {
        if (!ok && !ent_eq(&before.e[a], &after.e[a])) {
            fail("a failed save changed %s: was %s, is %s", g.name[a], describe(&before.e[a]), describe(&after.e[a]));
        }
        if (ok && !ent_eq(&before.e[a], &after.e[a]) && after.e[a].kind != E_FILE) {
            fail("a save left %s as %s", g.name[a], describe(&after.e[a]));
        }
    }
    if (ok && reference_params() != REF_VALID) {
        fail("a save answered OK left %s as %s, not a valid blob of this OD (%d)", g.name[A_PARAMS],
             describe(&after.e[A_PARAMS]), reference_params());
    }
    const bool edited = g.edited;
    const unsigned edit = ok ? (flags >> 1) & 3U : 0U;
    if (edit != 0U) {
        hand_edit(edit, param);
    }
    if ((flags & 8U) != 0U) {
        restart();
    } else {
        power_on(true);
    }
    if (ok && edit == 0U) {
        if (node->nvm_status != CO_NVM_LOADED) {
            fail("after a save answered OK the parameters load as %d", (int)node->nvm_status);
        }
        static uint8_t want[65536];
        for (uint16_t k = 0U; k < g.n_store; k++) {
            const co_od_entry_t *e = &g.store_subs[k];
            if (edited && strcmp(g.cls->name, "buerkert") == 0 && e->index == 0x2001U && e->sub <= 0x02U) {
                continue; /* the Buerkert's address and baud rate are the LSS area's (co_lss_store), edited by hand */
            }
            expected_value(e, image, old_id, node->node_id, want);
            const uint8_t *have = (const uint8_t *)g.values + e->offset;
            if (e->type == CO_T_VISIBLE_STRING) {
                /* A visible string's value ends at its first NUL (co_od_read): what follows is not saved. */
                const size_t lw = strnlen((const char *)want, e->size);
                if (lw != strnlen((const char *)have, e->size) || memcmp(want, have, lw) != 0) {
                    fail("0x%04X:%02X saved as \"%.*s\" is \"%.*s\" after the power cycle", e->index, e->sub, (int)lw,
                         (const char *)want, (int)strnlen((const char *)have, e->size), (const char *)have);
                }
                continue;
            }
            if (memcmp(want, have, e->size) != 0) {
                uint32_t w = 0U;
                uint32_t got = 0U;
                memcpy(&w, want, e->size < 4U ? e->size : 4U);
                memcpy(&got, (const uint8_t *)g.values + e->offset, e->size < 4U ? e->size : 4U);
                fail("0x%04X:%02X saved as 0x%lX is 0x%lX after the power cycle (node-ID %u, then %u)", e->index, e->sub,
                     (unsigned long)w, (unsigned long)got, old_id, node->node_id);
            }
        }
    }
    free(image);
    g.saved_once = true;
}

/* The device runs for a while: the models save their own data (counters, drag indicators) on their own. */
static void time_record(rd_t *in)
{
    snap_t before;
    snap_t after;
    current(&before);
    g.now += (co_time_us_t)(u8(in) + 1U) * 10000000U;
    g.what = "device_process";
    (void)device_process(g.dev, g.now);
    snapshot(&after);
    check_step(&before, &after);
    for (int a = A_PARAMS; a <= A_LSS; a++) {
        if (!ent_eq(&before.e[a], &after.e[a])) {
            fail("the device's own save changed %s: was %s, is %s", g.name[a], describe(&before.e[a]),
                 describe(&after.e[a]));
        }
    }
    if (!ent_eq(&before.e[A_DEVICE], &after.e[A_DEVICE]) && after.e[A_DEVICE].kind != E_FILE) {
        fail("the device's own save left %s as %s", g.name[A_DEVICE], describe(&after.e[A_DEVICE]));
    }
}

/* ---- Entry point ---------------------------------------------------------------------------------------------- */

static void cleanup(void)
{
    if (g.root[0] != '\0') {
        remove_tree(g.root);
    }
}

static void setup_once(void)
{
    if (g.root[0] != '\0') {
        return;
    }
    const char *tmp = getenv("TMPDIR");
    (void)snprintf(g.root, sizeof g.root, "%s/fuzz-nvm-file.%ld", tmp != NULL && tmp[0] != '\0' ? tmp : "/tmp",
                   (long)getpid());
    (void)snprintf(g.dir, sizeof g.dir, "%s/nvm", g.root);
    remove_tree(g.root);
    if (mkdir(g.root, 0700) != 0) {
        perror(g.root);
        abort();
    }
    (void)atexit(cleanup);
}

static void begin(uint8_t h0, uint8_t h1)
{
    static const char *const classes[3] = {"pro-ionizer", "sds", "buerkert"};
    memset(&g.nvm, 0, sizeof g.nvm);
    g.cls = device_find_class(classes[(h0 & 3U) % 3U]);
    if (g.cls == NULL) {
        fail("device class %s is not registered", classes[(h0 & 3U) % 3U]);
    }
    unsigned nv = 0U;
    while (g.cls->variants != NULL && g.cls->variants[nv] != NULL) {
        nv++;
    }
    const unsigned v = (h0 >> 2) & 7U;
    g.variant = v == 0U || nv == 0U ? NULL : g.cls->variants[(v - 1U) % nv];
    g.id = h1 == 0U ? g.cls->default_node_id : (uint8_t)(1U + h1 % 127U);
    (void)snprintf(g.key, sizeof g.key, "%s-%u", g.cls->name, g.id);
    for (int i = 0; i < N_NAMES; i++) {
        if (suffixes[i] != NULL) {
            (void)snprintf(g.name[i], sizeof g.name[i], "%s%s", g.key, suffixes[i]);
        } else {
            (void)snprintf(g.name[i], sizeof g.name[i], "other-1.params");
        }
        (void)snprintf(g.path[i], sizeof g.path[i], "%s/%s", g.dir, g.name[i]);
    }
    g.n_store = 0U;
    for (uint16_t i = 0U; i < g.cls->od->count; i++) {
        const co_od_entry_t *row = &g.cls->od->entries[i];
        for (uint8_t k = 0U; (row->flags & CO_OD_STORE) != 0U && k < co_od_entry_subs(row); k++) {
            co_od_entry_t one;
            if (g.n_store < sizeof g.store_subs / sizeof g.store_subs[0]) {
                g.store_subs[g.n_store++] = *co_od_entry_at(row, k, &one);
            }
        }
    }
    g_cur_ok = false;
    remove_tree(g.dir);
    if (mkdir(g.dir, 0755) != 0) {
        perror(g.dir);
        abort();
    }
    g.values = malloc(g.cls->od->values_size);
    g.model = malloc(g.cls->model_size > 0U ? g.cls->model_size : 1U);
    g.dev = calloc(1U, sizeof *g.dev);
    if (g.values == NULL || g.model == NULL || g.dev == NULL) {
        abort();
    }
    memset(&g.port, 0, sizeof g.port);
    g.port.send = port_send;
    g.port.nvm_write = nvm_file_write;
    g.port.nvm_commit = nvm_file_commit;
    g.port.nvm_read = nvm_file_read;
    g.port.set_bit_rate = port_bit_rate;
    memset(&g.cfg, 0, sizeof g.cfg);
    g.cfg.node_id = g.id;
    g.cfg.serial = device_default_serial(g.cls) + g.id;
    g.cfg.variant = g.variant;
    g.cfg.port = &g.port;
    g.cfg.port_ctx = &g.nvm;
    g.cfg.print = on_print;
    g.cfg.on_event = on_event;
    g.now = 1000000U;
    g.up = false;
    g.nvm_open = false;
    g.saved_once = false;
    g.edited = false;
    g.step = 0U;
}

static void end(void)
{
    if (g.nvm_open) {
        close_checked();
    }
    free(g.values);
    free(g.model);
    free(g.dev);
    g.values = NULL;
    g.model = NULL;
    g.dev = NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rd_t in = {data, size, 0U};
    setup_once();
    const uint8_t h0 = u8(&in);
    const uint8_t h1 = u8(&in);
    begin(h0, h1);
    while (in.pos < in.n && g.step < 32U) {
        const uint8_t t = u8(&in);
        g.step++;
        if (getenv("FUZZ_TRACE") != NULL) {
            fprintf(stderr, "step %u record 0x%02X at byte %zu\n", g.step, t, in.pos - 1U);
        }
        if (t < 0x80U) {
            g.what = "file record";
            file_record(&in, t);
            continue;
        }
        if (!g.up) {
            start();
        }
        if (t < 0xA0U) {
            write_record(&in);
        } else if (t < 0xB0U || t >= 0xD0U) {
            save_record(&in);
        } else if (t < 0xC0U) {
            time_record(&in);
        } else if ((t & 1U) != 0U) {
            restart();
        } else {
            power_on(true);
        }
    }
    if (!g.up) {
        start();
    }
    if (!g.saved_once) {
        static const uint8_t none[1] = {0U};
        rd_t z = {none, 0U, 0U};
        g.step++;
        save_record(&z);
    }
    end();
    return 0;
}
