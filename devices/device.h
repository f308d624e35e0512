/**
 * @file device.h
 * @brief Emulated devices: the contract between a device model (devices/<name>/) and whoever runs it
 *        (the canopen-emu program, a unit test with simulated time, a microcontroller port).
 *
 * A device is a class (const, one per device type: its object dictionary, defaults, behaviour) and
 * instances (one per emulated node: a co_node_t, its OD values, the model's state). Device code uses the
 * core's API only: it allocates nothing, reads no clock (time is an argument), touches no OS. It keeps
 * persistent data of its own (operating-hour counters) in the port's CO_NVM_DEVICE area.
 *
 * Life of an instance:
 *   device_init(dev, cls, cfg, now)      set up model (zeroed, environment defaults) + node (power-on: loads NVM, boot-up)
 *   loop: device_rx(dev, frame, t)       for every received frame
 *         next = device_process(dev, now)  model step + core processing; call again at `next` at the latest
 *         device_command(dev, argv, now, out)  control commands (inputs, faults, power cycle), replies to out
 *         device_get_value / device_set_value    an object's value, typed, read or written as the device would
 *
 * Files: device.c (an instance's life), device_value.c (typed values), device_commands.c (the common commands),
 * device_words.c (the words of the command language).
 */
#ifndef DEVICE_H
#define DEVICE_H

#include <stdarg.h>

#include "co/co.h"
#include "device_words.h"

#if CO_CONFIG_TIME32
#error "the device models (and canopen-emu) need 64-bit time: build them with CO_CONFIG_TIME32 0"
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef struct device device_t;

/** Where a device writes lines (one line per call, no newline, shorter than 512 bytes: device_printf's buffer). */
typedef void (*device_print_fn)(void *ctx, const device_t *dev, const char *line);

/** A destination of lines: the replies of one device_command call. */
typedef struct device_output {
    device_print_fn print;
    void *ctx;
} device_output_t;

/** Result of device_command(). */
typedef enum device_cmd_result {
    DEVICE_CMD_OK = 0,       /**< Done (a reply may have been printed). */
    DEVICE_CMD_UNKNOWN = 1,  /**< Not a command of this device. */
    DEVICE_CMD_ERROR = 2     /**< A known command with bad arguments or refused; the reason was printed. */
} device_cmd_result_t;

/** A device type. All fields const; shared by every instance. */
typedef struct device_class {
    const char *name;              /**< Command-line name, e.g. "pro-ionizer". */
    const char *summary;           /**< One line for --list-devices. */
    const co_od_t *od;             /**< Generated object dictionary. */
    const char *const *od_names;   /**< Its rows' EDS names, in table order (generated with it), or NULL. */
    const char *const *od_units;   /**< Its rows' units (NULL entries where none), in table order, or NULL. */
    const char *const *od_object_names; /**< Its objects' EDS names, in the order of od->objects, or NULL. */
    uint8_t default_node_id;       /**< Node-ID when the user gives none (the manual's factory setting). */
    uint8_t default_bit_timing;    /**< LSS bit-timing index at the factory setting. */
    uint32_t core_options;         /**< CO_OPT_* for co_node_init. */
    const uint16_t *bit_rates_kbit;/**< LSS bit-timing table of the device (NULL: CiA 305). */
    size_t model_size;             /**< Bytes of the model state the caller provides (device_t.model). */
    const char *const *variants;   /**< NULL-terminated variant names (first = default), or NULL. */
    const char *commands_help;     /**< Help text of the device's own commands (lines, '\n'-separated). */

    /** Sets the model's environment inputs (the simulated outside world: loads, pollution, temperature,
     *  supply voltage, sensor signals ...) to their defaults. Called once, by device_init(), on the zeroed
     *  model block, before the first power_on(). May be NULL (then the environment starts zeroed). */
    void (*init)(device_t *dev);
    /** A power-on (device_init() and every device_power_cycle(), before co_node_init). The model block is
     *  zeroed only by device_init(), never at a power cycle: power_on must re-initialise the model's running
     *  state itself (release, timers, measured values, active faults that the environment does not cause,
     *  persistent data reloaded from NVM) and keep its environment inputs as they are, since switching the
     *  device off and on does not change the world around it. The values block already holds the defaults;
     *  NVM is not loaded yet. */
    void (*power_on)(device_t *dev, co_time_us_t now);
    /** The core's hooks, with dev as context (any may be NULL). */
    uint32_t (*on_write)(device_t *dev, const co_od_entry_t *e, const uint8_t *data, size_t len, co_od_origin_t origin);
    uint32_t (*on_read)(device_t *dev, const co_od_entry_t *e);
    /** on_write and on_read see objects from this index on only (co_hooks_t.first_index); 0: every object. */
    uint16_t hooks_first_index;
    void (*on_nmt_change)(device_t *dev, co_nmt_state_t from, co_nmt_state_t to);
    void (*on_reset)(device_t *dev, co_reset_t what);
    /** Advances the model to now (values move, timers run). Returns its next deadline or CO_NEVER. Called at that
     *  deadline and after anything that may change the model: a write of an object from 0x2000 on, another hook or
     *  a core event of the node, a command, a power-on; not for every frame (a frame that reaches no hook cannot
     *  change the model) nor for a write of a communication object (0x1000-0x1FFF: the core's, which on_write
     *  sees and may refuse; a step that reads one sees it at its next deadline). */
    co_time_us_t (*step)(device_t *dev, co_time_us_t now);
    /** A control command (argv[0] is the command word). */
    device_cmd_result_t (*command)(device_t *dev, int argc, const char *const *argv, co_time_us_t now);
    /** A core event, before the runner's cfg.on_event sees it (may be NULL): lets a model follow what the
     *  core did on its own, e.g. an LSS store (CO_EV_STORE with index 0x7E5). */
    void (*on_event)(device_t *dev, const co_event_t *ev);
    /** The core's on_store hook (co_node.h; may be NULL): stages the model's own data that belongs to a store
     *  (0x1010, 0x1011, LSS store 0x7E5) so that it becomes durable with it, all or none. */
    co_status_t (*on_store)(device_t *dev, uint16_t index, uint8_t sub);
    /** For an OD with more PDOs than CO_RPDO_MAX / CO_TPDO_MAX (a device read from its EDS: CiA 301 allows 512),
     *  or with additional SDO servers (0x1201..0x127F): when non-zero, the model block starts with
     *  co_rpdo_t[rpdo_count], co_tpdo_t[tpdo_count], co_sdo_server_t[sdo_server_count] and the frame router's
     *  co_rx_route_t[CO_RX_ROUTES_FIXED + rpdo_count + sdo_server_count] (model_size counts them),
     *  which device_init gives the node; the model's own state follows at device_core_state_size().
     *  0: the node's own PDO arrays, no additional SDO server. */
    uint16_t rpdo_count;
    uint16_t tpdo_count;
    uint8_t sdo_server_count;
} device_class_t;

/** What the runner gives an instance. */
typedef struct device_cfg {
    uint8_t node_id;               /**< 0 = the class default. */
    uint32_t serial;               /**< 0x1018:04 of this node (0 = the OD default). Several nodes of one
                                        type need distinct serials, or LSS selects them all at once. */
    const char *variant;           /**< NULL = the class default. */
    const co_port_t *port;         /**< CAN + NVM of this node. */
    void *port_ctx;
    device_print_fn print;         /**< The model's messages outside a command, and the replies of a command given no
                                        output of its own (may be NULL). */
    void *print_ctx;
    void (*on_event)(void *ctx, const device_t *dev, const co_event_t *ev); /**< Core events, for logs (may be NULL). */
    void *event_ctx;
} device_cfg_t;

/** One emulated node. Memory is the caller's: values (cls->od->values_size) and model (cls->model_size). */
struct device {
    const device_class_t *cls;
    co_node_t node;
    void *values;
    void *model;
    device_cfg_t cfg;
    co_hooks_t hooks;              /**< Trampolines to cls (set by device_init). */
    uint8_t variant;               /**< Index into cls->variants. */
    co_time_us_t now;              /**< Time of the call in progress. */
    co_time_us_t step_due;         /**< What cls->step returned last. */
    co_time_us_t core_due;         /**< What co_node_process returned last (device_rx asks co_node_settled). */
    bool touched;                  /**< Something that may change the model ran since (see step): step at the next
                                        process. */
    const device_output_t *replies;/**< While device_command runs: its output argument, where device_printf writes;
                                        NULL otherwise (then cfg.print). */
};

/**
 * Powers an instance on. values and model must point to blocks of the class's sizes.
 * @return CO_OK, CO_ERR_ARG (bad node-ID or unknown variant), or co_node_init's error.
 */
co_status_t device_init(device_t *dev, const device_class_t *cls, void *values, void *model, const device_cfg_t *cfg,
                        co_time_us_t now);

/** A power cycle: the model restarts (power_on; the environment inputs stay), the node re-initialises from NVM
 *  and boots. */
co_status_t device_power_cycle(device_t *dev, co_time_us_t now);

/** Feeds a received frame to the node. Returns co_node_rx's answer: true when the frame concerned this node
 *  (call device_process before sleeping, unless device_settled says the frame left nothing for it), false when it
 *  was ignored (the node's deadline is unchanged). */
static inline bool device_rx(device_t *dev, const co_frame_t *frame, co_time_us_t now)
{
    dev->now = now; /* inline: every received frame comes this way */
    return co_node_rx(&dev->node, frame, now);
}

/** After a frame device_rx took: true when it left nothing for device_process, which would return what it last
 *  returned: the core settled on its last deadline (co_node_settled: an expedited SDO request answered at once) and
 *  the model not touched (an SDO or RPDO write of one of its objects, an event, an NMT change touch it; so does
 *  what the model's own step raised in device_process's second round, rarely: then the next pass runs its step). A
 *  runner of many nodes may then skip the node's pass. */
static inline bool device_settled(const device_t *dev)
{
    return !dev->touched && co_node_settled(&dev->node, dev->core_due);
}

/** Runs the model (when due or touched) and the core; returns the earliest deadline of both. Inline, as device_rx:
 *  a runner calls it after every frame that concerned the node and at each of its deadlines. */
static inline co_time_us_t device_process(device_t *dev, co_time_us_t now)
{
    dev->now = now;
    if (dev->cls->step == NULL) {
        dev->touched = false; /* no model to follow anything */
        dev->core_due = co_node_process(&dev->node, now);
        return dev->core_due;
    }
    for (unsigned round = 0U;; round++) {
        if (dev->touched || now >= dev->step_due) {
            dev->touched = false;
            dev->step_due = dev->cls->step(dev, now);
            co_node_values_changed(&dev->node); /* the models write their process values directly */
        }
        dev->core_due = co_node_process(&dev->node, now);
        /* What the core's pass did may concern the model (a timeout, an EMCY, an NMT change: dev->touched): its
         * step runs now, not at its next deadline, which the runner would sleep until. Once: the EMCY a step raises
         * touches the model too, and the step that follows it changes nothing more. */
        if (!dev->touched || round == 1U) {
            break;
        }
    }
    return dev->core_due < dev->step_due ? dev->core_due : dev->step_due;
}

/** Runs a control command: the device's own first, then the common ones (device_commands.c). A command of the
 *  device (a common one, or one of cls->commands_help) that neither takes with these words is DEVICE_CMD_ERROR, with
 *  "error: WORD takes ARGS" (or "takes no arguments") printed; DEVICE_CMD_UNKNOWN only for a word that is none.
 *  Its reply lines go to out (device_printf of the command's code), or to cfg.print when out is NULL. */
device_cmd_result_t device_command(device_t *dev, int argc, const char *const *argv, co_time_us_t now,
                                   const device_output_t *out);

/** What a value is, by the data type of its object. */
typedef enum device_value_kind {
    DEVICE_VALUE_UNSIGNED = 0, /**< as.u: UNSIGNED8 .. UNSIGNED64 (the 24/40/48/56-bit ones too), TIME_OF_DAY and
                                    TIME_DIFFERENCE (their 6 bytes as a number) */
    DEVICE_VALUE_SIGNED,       /**< as.i: INTEGER8 .. INTEGER64 */
    DEVICE_VALUE_BOOLEAN,      /**< as.b */
    DEVICE_VALUE_REAL,         /**< as.r: REAL32, REAL64 */
    DEVICE_VALUE_TEXT,         /**< bytes, len: VISIBLE_STRING. To write, also a number as its word ("0x2A", "2.5") */
    DEVICE_VALUE_BYTES         /**< bytes, len: OCTET_STRING, UNICODE_STRING, DOMAIN */
} device_value_kind_t;

/** A value of an object, typed. */
typedef struct device_value {
    device_value_kind_t kind;
    uint8_t type;          /**< device_get_value: the object's co_od_type_t; device_set_value does not read it */
    union {
        uint64_t u;
        int64_t i;
        bool b;
        double r;
    } as;
    const uint8_t *bytes;  /**< TEXT and BYTES: len bytes (device_get_value: in the caller's buffer) */
    size_t len;
} device_value_t;

/** Reads object index:sub of the node as the device holds it now: a local read (the model's read hook brings it up
 *  to now, no SDO access check). buf (size bytes, 256 hold any value canopen-emu's nodes have) takes the bytes;
 *  *out the value by the object's data type (a VISIBLE_STRING up to its first NUL; TEXT and BYTES point into buf).
 *  Returns 0, or the SDO abort code an upload would get (CO_ABORT_NO_OBJECT, ...; CO_ABORT_OUT_OF_MEMORY when the
 *  value does not fit buf). */
uint32_t device_get_value(device_t *dev, uint16_t index, uint8_t sub, co_time_us_t now, uint8_t *buf, size_t size,
                          device_value_t *out);

/** Writes object index:sub of the node as the device itself would (an input, a measurement): a local write, without
 *  SDO access checks nor the EDS limits (they bind an SDO client), but within the object's data type and the device's
 *  rules (its write hook). The value is taken in the object's type: a number of any kind in a number (an integer type
 *  takes a REAL only when it is whole; BOOLEAN true/false as 1/0), TEXT in a VISIBLE_STRING or as a number's word
 *  (device_parse_magnitude, strtod for REAL32 and REAL64); an OCTET_STRING of up to 8 bytes as the number of its
 *  bytes, little-endian. Nothing is cut to size: a value the type cannot hold is refused. Returns true when written;
 *  false with why (a line for a person, why_size bytes: "70000 is out of range: 0x1017:00 (UNSIGNED16) holds
 *  0..65535", or the write hook's abort: "0x2002:06: value range exceeded: value too low (0x06090032)"). */
bool device_set_value(device_t *dev, uint16_t index, uint8_t sub, const device_value_t *value, co_time_us_t now,
                      char *why, size_t why_size);

/**
 * For a class's power_on: zeroes the model block except the environment inputs, which are the bytes
 * [env_offset, env_offset + env_size) (e.g. offsetof(my_model_t, env), sizeof(my_env_t)). The running state
 * must then be set up again by power_on itself.
 */
void device_clear_running_state(device_t *dev, size_t env_offset, size_t env_size);

/** printf-style reply/log line through cfg.print. */
void device_printf(const device_t *dev, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** The CiA 301 name of a co_od_type_t ("UNSIGNED16", "VISIBLE_STRING"...). */
const char *device_type_name(uint8_t type);

/** True for the signed integer types (INTEGER8 .. INTEGER64, the 24/40/48/56-bit ones too). */
bool device_type_is_signed(uint8_t type);

/** The EDS name of an object of the device, or NULL. */
const char *device_object_name(const device_class_t *cls, const co_od_entry_t *e);

/** The unit of an object's value (od/<device>.toml [units]), or NULL. */
const char *device_object_unit(const device_class_t *cls, const co_od_entry_t *e);

/** The EDS name of an object as a whole, by index ("Identity object" for 0x1018), or NULL. */
const char *device_object_title(const device_class_t *cls, uint16_t index);

/**
 * When a node's periodic NVM writes fall within each minute: (configured node-ID mod 60) seconds past it.
 * Nodes powered on together (an emulator's 127) would otherwise all write, and wait for the disk, in the same
 * instant of every minute and hold up every other node's frames meanwhile. Models saving "every minute" save
 * when their clock passes this phase (docs/devices/eltex.md E13, docs/devices/buerkert-behaviour.md).
 */
co_time_us_t device_save_phase_us(const device_t *dev);

/** Bytes at the start of a class's model block that hold core state: PDOs and additional SDO servers
 *  (device_class_t.rpdo_count/tpdo_count/sdo_server_count). */
size_t device_core_state_size(const device_class_t *cls);

/** The OD default of 0x1018:04 (serial number) of a class, 0 if it has none. */
uint32_t device_default_serial(const device_class_t *cls);

/** The registered device classes, NULL-terminated. */
extern const device_class_t *const device_classes[];

/** Finds a class by name, or NULL. */
const device_class_t *device_find_class(const char *name);

#ifdef __cplusplus
}
#endif
#endif /* DEVICE_H */
