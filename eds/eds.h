/**
 * @file eds.h
 * @brief The project's one reader (and writer) of CiA 306 device descriptions: EDS and DCF files.
 *
 * Used at build time by tools/odgen.py (through the canopen-eds program) and at run time by canopen-emu, so
 * the generated tables and the emulated devices never disagree about a file. Not part of the core: it
 * allocates, and it is built for the host only.
 *
 * The reader is tolerant: it reads what real vendor files contain (a UTF-8 BOM, Latin-1 text, inline `;`
 * comments, unsorted or miscounted object lists, CompactSubObj, every CiA 301 basic type, `$NODEID` sums,
 * octal/hex/decimal numbers per CiA 306) and reports every deviation as a diagnostic with its line:
 *   "FILE:LINE: warning: WHAT; WHAT WAS DONE INSTEAD"   the file still describes a device that can be emulated
 *   "FILE:LINE: error: WHY"                             it does not (eds_file_t.errors > 0)
 * The model it returns is already repaired: every entry has a known type, a value representable in it, and
 * PDO mappings that the core accepts.
 */
#ifndef EDS_H
#define EDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/** Largest file the reader takes: real device descriptions stay far below (the largest seen: 2 MB). */
#define EDS_MAX_FILE_BYTES (16UL * 1024UL * 1024UL)
/**
 * Diagnostics given in full per file. Repeated ones are grouped by kind (the message without the places and values
 * it names): the first three of a kind in full, the rest in one note line ("... and 126 more like this, lines ...");
 * the first of every kind is given while there is room, so the cap never hides a different one behind many of one.
 */
#define EDS_MAX_DIAGNOSTICS 200U

/** What a value holds (the kind follows from the entry's data type). */
typedef enum eds_value_kind {
    EDS_V_NONE = 0,  /**< Not given. */
    EDS_V_INT,       /**< Signed integer types: i. */
    EDS_V_UINT,      /**< Unsigned integer types, BOOLEAN, TIME_OF_DAY, TIME_DIFFERENCE: u. */
    EDS_V_REAL,      /**< REAL32, REAL64: r (REAL32 values are exactly representable as float). */
    EDS_V_BYTES      /**< Strings and DOMAIN: bytes/len (VISIBLE_STRING: the text; UNICODE_STRING: UTF-16LE). */
} eds_value_kind_t;

typedef struct eds_value {
    eds_value_kind_t kind;
    bool nodeid;        /**< $NODEID is to be added (integers only; i/u hold the rest of the sum). */
    int64_t i;
    uint64_t u;
    double r;
    uint8_t *bytes;     /**< Owned by the file; NUL-terminated for convenience (not counted in len). */
    size_t len;
} eds_value_t;

/** EDS AccessType. */
typedef enum eds_access {
    EDS_RO = 0, EDS_WO, EDS_RW, EDS_RWR, EDS_RWW, EDS_CONST
} eds_access_t;

/** One sub-index as the device has it (a VAR object is one entry with sub 0). */
typedef struct eds_entry {
    uint16_t index;
    uint8_t sub;
    uint8_t type;           /**< CiA 301 basic data type number (eds_type_name() knows it). */
    eds_access_t access;
    bool pdo_mapping;
    const char *name;       /**< ParameterName (for compact sub-objects: from [xxxxName] or formed). */
    const char *denotation; /**< DCF Denotation, or NULL. */
    eds_value_t def;        /**< DefaultValue (repaired: always given, representable, within limits when possible). */
    eds_value_t low, high;  /**< LowLimit/HighLimit (EDS_V_NONE when absent). */
    eds_value_t param;      /**< DCF ParameterValue (or [xxxxValue]), EDS_V_NONE when absent. */
    uint32_t line;          /**< Line of the section (or key) that defines it. */
} eds_entry_t;

/** One object (index). Its entries are entries[first .. first + count - 1], sorted by sub-index. */
typedef struct eds_object {
    uint16_t index;
    uint8_t object_type;    /**< 0x2 DOMAIN, 0x5 DEFTYPE, 0x6 DEFSTRUCT, 0x7 VAR, 0x8 ARRAY, 0x9 RECORD. */
    const char *name;
    const char *denotation;
    uint32_t first;
    uint16_t count;
    uint8_t compact;        /**< CompactSubObj of the file (0: sub-index sections or a VAR). */
    uint16_t *links;        /**< [xxxxObjectLinks], n_links indices. */
    uint16_t n_links;
    uint32_t line;
} eds_object_t;

/** [DeviceComissioning] of a DCF. */
typedef struct eds_commissioning {
    bool present;
    uint8_t node_id;        /**< 0 when not given or not 1..127. */
    bool node_id_given;     /**< The section has a NodeID key (node_id is 0 when its value is not 1..127). */
    uint16_t baudrate_kbit; /**< 0 when not given. */
    const char *node_name;
    uint32_t net_number;
    const char *network_name;
    bool canopen_manager;
    uint32_t lss_serial_number;
} eds_commissioning_t;

/** A key of a section the model does not interpret ([FileInfo], [DeviceInfo], [Comments], ...), kept for the writer. */
typedef struct eds_info_key {
    const char *section;
    const char *key;
    const char *value;
} eds_info_key_t;

typedef struct eds_file {
    const char *path;
    /* [DeviceInfo] */
    const char *vendor_name;
    const char *product_name;
    uint32_t vendor_number, product_number, revision_number;
    uint16_t nr_of_rxpdo, nr_of_txpdo; /**< As the file says (repaired to the objects present). */
    uint8_t granularity;
    bool lss_supported;
    uint16_t baud_rates;    /**< Bit n: the rate of CiA 305 bit-timing index n is supported (BaudRate_<kbit>=1). */
    uint8_t dummy_usage;    /**< Bit n (1..7): [DummyUsage] Dummy000n = 1. */
    uint32_t device_info_line; /**< Line of [DeviceInfo] (0: none), for diagnostics about its keys. */
    eds_commissioning_t comm;
    bool is_dcf;            /**< Has [DeviceComissioning] or ParameterValue keys. */
    eds_object_t *objects;  /**< Sorted by index. */
    uint32_t n_objects;
    eds_entry_t *entries;   /**< Sorted by (index, sub). */
    uint32_t n_entries;
    eds_info_key_t *info;   /**< Uninterpreted keys, in file order. */
    uint32_t n_info;
    char **diagnostics;     /**< "FILE:LINE: warning|error: ..." lines, at most EDS_MAX_DIAGNOSTICS, then "note:" lines
                                 that group the repeated ones (one per kind) and count any not shown. */
    uint32_t n_diagnostics;
    uint32_t warnings, errors; /**< Counts, also of those not kept. */
    struct eds_arena *arena;   /**< Owns every string and byte array above. */
    struct eds_diag_kinds *kinds; /**< The reader's own: diagnostics by kind (in the arena). */
} eds_file_t;

/** Reads a file. Never NULL except when out of memory; check ->errors. Free with eds_free(). */
eds_file_t *eds_read_file(const char *path);
/** Reads a file's contents (name is used in diagnostics). */
eds_file_t *eds_read_buffer(const char *name, const char *data, size_t len);
void eds_free(eds_file_t *file);

/** Finds an entry, or NULL. O(log n). */
const eds_entry_t *eds_find(const eds_file_t *file, uint16_t index, uint8_t sub);
/** Finds an object, or NULL. O(log n). */
const eds_object_t *eds_find_object(const eds_file_t *file, uint16_t index);

/** CiA 301 name of a basic data type ("UNSIGNED8"), or NULL if the reader does not know it. */
const char *eds_type_name(uint8_t type);
/** Size in bytes of a fixed-size type, 0 for strings and DOMAIN. */
size_t eds_type_size(uint8_t type);
/** True for VISIBLE_STRING, OCTET_STRING, UNICODE_STRING, DOMAIN. */
bool eds_type_is_bytes(uint8_t type);
/** EDS spelling of an access type ("rw"). */
const char *eds_access_name(eds_access_t access);
/** True when an SDO client may write an entry of this access type (wo, rw, rwr, rww). */
bool eds_access_writable(eds_access_t access);
/** True when an entry of this access type (and PDOMapping=1) may be mapped into an RPDO (receive) or a TPDO. */
bool eds_access_maps(eds_access_t access, bool receive);

/** kbit/s of each CiA 305 bit-timing index (0 for index 5, which EDS files have no BaudRate_ key for). */
#define EDS_CIA305_RATES 9U
extern const uint16_t eds_cia305_kbit[EDS_CIA305_RATES];

/** What eds_write() writes. */
typedef struct eds_write_options {
    bool dcf;                 /**< Write a DCF: [DeviceComissioning] and a ParameterValue for every entry. */
    uint8_t node_id;          /**< DCF NodeID (0: the file's, if any). */
    uint16_t baudrate_kbit;   /**< DCF Baudrate (0: the file's, if any). */
    const char *file_name;    /**< [FileInfo] FileName; NULL: keep the file's. */
    /**
     * The current value of an entry as raw little-endian bytes (DCF ParameterValue), or NULL to write the
     * model's ParameterValue/DefaultValue. Return the length, or -1 when the entry has no current value.
     */
    long (*current)(void *ctx, const eds_entry_t *entry, uint8_t *buf, size_t cap);
    void *ctx;
    /** Where eds_write() says why it refused to write (error_cap bytes), or NULL. */
    char *error;
    size_t error_cap;
} eds_write_options_t;

/**
 * Writes the model as an EDS (or DCF): every object with explicit sub-index sections. 0, or -1 on a write error
 * or a refusal. A refusal writes nothing (errno EINVAL, options->error says why): a DCF value a line of a CiA 306
 * file cannot hold so that it reads back as the same bytes, that is a string with a line break (CR, LF), a NUL,
 * bytes that are not UTF-8, or a UNICODE_STRING that is not well-formed UTF-16 (an SDO master can write any bytes);
 * also a file_name with a line break.
 */
int eds_write(FILE *out, const eds_file_t *file, const eds_write_options_t *options);

/** The type's smallest (high false) or largest value. */
void eds_type_bound(uint8_t type, bool high, eds_value_t *out);
/** -1, 0, 1: a <=> b for two integer or real values of one type ($NODEID ignored). */
int eds_value_cmp(const eds_value_t *a, const eds_value_t *b);
/** True when the value is of the type's kind and fits it (node-ID-relative: for every node-ID 1..127). */
bool eds_value_fits(uint8_t type, const eds_value_t *v);

/**
 * A DCF value at node_id (the file's NodeID) of an entry whose DefaultValue is node-ID-relative: true, with *relative
 * set, when value is that default worked out at node_id (bits 29..31 of an UNSIGNED32 COB-ID may differ), so that
 * it follows the node-ID the device runs at. The reader applies it to ParameterValues, the writer to the values of
 * the DCF it writes (docs/eds.md, "A DCF at another node-ID").
 */
bool eds_value_follows_node_id(const eds_entry_t *e, const eds_value_t *value, uint8_t node_id, eds_value_t *relative);

/**
 * What the file holds that a node at node_id takes but a master could not write (issue 35, rule 3), known only once
 * the node-ID is: a valid COB-ID of the EMCY, SYNC, an additional SDO server (0x1201..0x127F) or a PDO that is a
 * restricted CAN-ID of CiA 301 there ($NODEID+0x6A0 at node-ID 0x40..0x5F). One "FILE:LINE: warning: ..." line to
 * out for each; returns how many.
 */
unsigned eds_node_id_warnings(const eds_file_t *f, uint8_t node_id, FILE *out);

/** Formats a value as CiA 306 text (hex for unsigned, decimal for signed, %.9g/%.17g for reals, hex bytes). */
void eds_format_value(char *buf, size_t cap, uint8_t type, const eds_value_t *value);

#endif /* EDS_H */
