// A CAN frame read in CANopen terms (CiA 301, LSS of CiA 305) for the trace: which service it is (its kind), the node
// it concerns, and a line saying what it says. By the predefined connection set (COB-ID = function + node-ID); a PDO's
// values need its mapping, which the caller looks up (web/pdomap.js); so do an SDO's values their object's data type,
// and its abort codes their texts (the emulator's `tables`). No DOM: tested with node --test (tests/web/js).

import {typeBits, valueText} from "./pdomap.js";

/** The kinds of frame, as the trace's filter offers them. */
export const KINDS = ["NMT", "SYNC", "EMCY", "TIME", "PDO", "SDO", "heartbeat", "LSS", "extended", "other"];

/**
 * The texts of the SDO abort codes by code, from the emulator's `tables` answer (its `aborts`: the core's table,
 * include/co/co_abort.h, the texts the emulator's own messages use): the page holds no copy of them.
 */
export function abortTexts(aborts) {
  return new Map(aborts.map(({code, text}) => [code, text]));
}

/** The emergency error codes of CiA 301 (7.2.7.1): a code not listed takes its class (0xFF00, then 0xF000). */
export const EMCY_CLASSES = new Map([
  [0x0000, "error reset or no error"],
  [0x1000, "generic error"],
  [0x2000, "current"],
  [0x2100, "current, device input side"],
  [0x2200, "current inside the device"],
  [0x2300, "current, device output side"],
  [0x3000, "voltage"],
  [0x3100, "mains voltage"],
  [0x3200, "voltage inside the device"],
  [0x3300, "output voltage"],
  [0x4000, "temperature"],
  [0x4100, "ambient temperature"],
  [0x4200, "device temperature"],
  [0x5000, "device hardware"],
  [0x6000, "device software"],
  [0x6100, "internal software"],
  [0x6200, "user software"],
  [0x6300, "data set"],
  [0x7000, "additional modules"],
  [0x8000, "monitoring"],
  [0x8100, "communication"],
  [0x8110, "CAN overrun (objects lost)"],
  [0x8120, "CAN in error passive mode"],
  [0x8130, "life guard error or heartbeat error"],
  [0x8140, "recovered from bus off"],
  [0x8150, "CAN-ID collision"],
  [0x8200, "protocol error"],
  [0x8210, "PDO not processed due to length error"],
  [0x8220, "PDO length exceeded"],
  [0x8230, "DAM MPDO not processed, destination object not available"],
  [0x8240, "unexpected SYNC data length"],
  [0x8250, "RPDO timeout"],
  [0x9000, "external error"],
  [0xF000, "additional functions"],
  [0xFF00, "device specific"],
]);

/** The bits of the error register (0x1001), bit 0 first; bit 6 is reserved. */
const REGISTER_BITS = ["generic", "current", "voltage", "temperature", "communication", "device profile", null,
  "manufacturer"];

const NMT_COMMANDS = new Map([[0x01, "start"], [0x02, "stop"], [0x80, "pre-operational"], [0x81, "reset node"],
  [0x82, "reset communication"]]);

const NMT_STATES = new Map([[0x00, "boot-up"], [0x04, "stopped"], [0x05, "operational"], [0x7F, "pre-operational"]]);

/** The PDOs of the predefined connection set by function code (COB-ID >> 7). */
const PDO_FUNCTIONS = new Map([[0x3, "TPDO1"], [0x4, "RPDO1"], [0x5, "TPDO2"], [0x6, "RPDO2"], [0x7, "TPDO3"],
  [0x8, "RPDO3"], [0x9, "TPDO4"], [0xA, "RPDO4"]]);

/** LSS (CiA 305): the bit timing table 0 by index, kbit/s (5 is reserved, 9 automatic bit rate detection). */
const LSS_BIT_RATES = ["1000 kbit/s", "800 kbit/s", "500 kbit/s", "250 kbit/s", "125 kbit/s", null, "50 kbit/s",
  "20 kbit/s", "10 kbit/s", "automatic bit rate detection"];
const LSS_IDENTITY = ["vendor-ID", "product code", "revision number", "serial number"];
const LSS_REMOTE = ["vendor-ID", "product code", "revision number low", "revision number high", "serial number low",
  "serial number high"];

/** 0x-prefixed upper-case hex of `digits` digits at least. */
function hex(value, digits) {
  return "0x" + value.toString(16).toUpperCase().padStart(digits, "0");
}

/** The bytes of a frame event's hex data. */
export function bytesOf(data) {
  const bytes = new Uint8Array(data.length >> 1);
  for (let i = 0; i < bytes.length; i++) {
    bytes[i] = parseInt(data.substr(2 * i, 2), 16);
  }
  return bytes;
}

/** An unsigned little-endian number of bytes[from, from + count) (at most 4 bytes: a JS number). */
function le(bytes, from, count) {
  let value = 0;
  for (let i = count - 1; i >= 0; i--) {
    value = value * 256 + bytes[from + i];
  }
  return value;
}

function hexBytes(bytes) {
  return [...bytes].map((b) => b.toString(16).toUpperCase().padStart(2, "0")).join("");
}

function lengthProblem(service, expected, given) {
  return `${service} (${expected} expected, ${given} given)`;
}

/** The class of an emergency error code (EMCY_CLASSES), or null. */
export function emcyClass(code) {
  return EMCY_CLASSES.get(code) ?? (code === 0 || (code & 0xFF00) === 0 ? null :
    EMCY_CLASSES.get(code & 0xFF00) ?? EMCY_CLASSES.get(code & 0xF000) ?? null);
}

/** An emergency error code with its class: "0x8130 life guard error or heartbeat error", "0x0012 unknown code". The
 * trace's EMCY text and the overview's last EMCY (web/format.js) both. */
export function emcyCode(code) {
  return `${hex(code, 4)} ${emcyClass(code) ?? "unknown code"}`;
}

/** "0x11 (generic, communication)", "0x00". */
export function errorRegister(value) {
  const bits = REGISTER_BITS.map((name, bit) => ((value >> bit) & 1 ? name ?? `bit ${bit}` : null))
    .filter((name) => name !== null);
  return bits.length === 0 ? hex(value, 2) : `${hex(value, 2)} (${bits.join(", ")})`;
}

/** The text of an SDO abort code by `texts` (abortTexts()): "0x06020000 object does not exist"; the code alone while
 * the texts have not come (null). */
export function abortText(code, texts = null) {
  return texts === null ? hex(code, 8) : `${hex(code, 8)} ${texts.get(code) ?? "unknown abort code"}`;
}

function nmt(bytes) {
  if (bytes.length !== 2) {
    return {node: null, text: lengthProblem("NMT", "2 bytes", bytes.length)};
  }
  const command = NMT_COMMANDS.get(bytes[0]) ?? `command ${hex(bytes[0], 2)} (unknown)`;
  const target = bytes[1];
  return {node: target === 0 ? null : target, text: `NMT ${command}: ${target === 0 ? "all nodes" : `node ${target}`}`};
}

function sync(bytes) {
  if (bytes.length === 0) {
    return "SYNC";
  }
  return bytes.length === 1 ? `SYNC counter ${bytes[0]}` : lengthProblem("SYNC", "0 or 1 byte", bytes.length);
}

function emcy(bytes) {
  if (bytes.length < 3) {
    return lengthProblem("EMCY", "8 bytes", bytes.length);
  }
  return `EMCY ${emcyCode(le(bytes, 0, 2))}, register ${errorRegister(bytes[2])}, info ${hexBytes(bytes.subarray(3))}`;
}

/** TIME: ms after midnight (28 bits) and days since 1984-01-01 (CiA 301 TIME_OF_DAY), in UTC. */
function time(bytes) {
  if (bytes.length !== 6) {
    return lengthProblem("TIME", "6 bytes", bytes.length);
  }
  const ms = le(bytes, 0, 4) & 0x0FFFFFFF;
  const days = le(bytes, 4, 2);
  const date = new Date(Date.UTC(1984, 0, 1) + days * 86_400_000 + ms);
  return `TIME ${date.toISOString().replace("T", " ").replace("Z", "")}`;
}

function objectOf(bytes) {
  return `${hex(le(bytes, 1, 2), 4)}:${bytes[3].toString(16).toUpperCase().padStart(2, "0")}`;
}

/**
 * An expedited value: "1000 (0x03E8)", as an unsigned number; by the object's data type where it is known (null:
 * not) a VISIBLE_STRING as its text ("\"ES61\""), a signed type as signed ("-5 (0xFFFB)"), a REAL32 as a float
 * ("1.5 (0x3FC00000)"), a BOOLEAN as true or false ("true (0x01)"). A type the bytes cannot hold: as unsigned.
 */
function expedited(bytes, size, type) {
  const value = le(bytes, 4, size);
  const raw = BigInt(value);
  const shown = `(${hex(value, 2 * size)})`;
  if (type === "VISIBLE_STRING") {
    return valueText(raw, 8 * size, type);
  }
  const bits = type === "BOOLEAN" ? 8 : typeBits(type);
  const fits = bits !== null && bits <= 8 * size;
  if (fits && (type === "BOOLEAN" || type.startsWith("INTEGER") || (type === "REAL32" && size === 4))) {
    return `${valueText(raw & ((1n << BigInt(bits)) - 1n), bits, type)} ${shown}`; // "size not indicated": its bytes
  }
  return `${value} ${shown}`;
}

/** Segment data: its byte count, and its text in quotes when every byte is printable ASCII. */
function segment(bytes, count) {
  const data = bytes.subarray(1, 1 + count);
  const printable = count > 0 && data.every((b) => b >= 0x20 && b < 0x7F);
  return `${count} bytes${printable ? ` "${String.fromCharCode(...data)}"` : ""}`;
}

function initiate(bytes, service, word, sdo) {
  const object = objectOf(bytes);
  const e = bytes[0] & 0x02;
  const s = bytes[0] & 0x01;
  if (e) {
    const size = s ? 4 - ((bytes[0] >> 2) & 3) : 4;
    return `SDO ${service} ${word} ${object} expedited ${s ? `${size} bytes` : "size not indicated"} = ` +
      expedited(bytes, size, sdo.typeOf(le(bytes, 1, 2), bytes[3]));
  }
  return `SDO ${service} ${word} ${object} segmented ${s ? `${le(bytes, 4, 4)} bytes` : "size not indicated"}`;
}

/**
 * The SDO lookups of one frame: typeOf(index, sub) the data type of an object of the server node (null: not known),
 * aborts the abort texts (abortTexts(); null: not come yet).
 */
function sdoRequest(bytes, sdo) {
  const command = bytes[0];
  switch (command >> 5) {
    case 0:
      return `SDO download segment toggle ${(command >> 4) & 1}, ${segment(bytes, 7 - ((command >> 1) & 7))}` +
        `${command & 1 ? ", last" : ""}`;
    case 1:
      return initiate(bytes, "download", "request", sdo);
    case 2:
      return `SDO upload request ${objectOf(bytes)}`;
    case 3:
      return `SDO upload segment request toggle ${(command >> 4) & 1}`;
    case 4:
      return `SDO abort ${objectOf(bytes)}: ${abortText(le(bytes, 4, 4), sdo.aborts)}`;
    case 5:
      switch (command & 3) {
        case 0:
          return `SDO block upload request ${objectOf(bytes)} block size ${bytes[4]}${command & 4 ? ", CRC" : ""}`;
        case 1:
          return "SDO block upload end response";
        case 2:
          return `SDO block upload block response ackseq ${bytes[1]}, block size ${bytes[2]}`;
        default:
          return "SDO block upload start";
      }
    case 6:
      if (command & 1) {
        return `SDO block download end request, ${(command >> 2) & 7} bytes not data, CRC ${hex(le(bytes, 1, 2), 4)}`;
      }
      return `SDO block download request ${objectOf(bytes)} ` +
        `${command & 2 ? `${le(bytes, 4, 4)} bytes` : "size not indicated"}${command & 4 ? ", CRC" : ""}`;
    default:
      return `SDO command ${hex(command, 2)} (unknown)`;
  }
}

function sdoResponse(bytes, sdo) {
  const command = bytes[0];
  switch (command >> 5) {
    case 0:
      return `SDO upload segment toggle ${(command >> 4) & 1}, ${segment(bytes, 7 - ((command >> 1) & 7))}` +
        `${command & 1 ? ", last" : ""}`;
    case 1:
      return `SDO download segment response toggle ${(command >> 4) & 1}`;
    case 2:
      return initiate(bytes, "upload", "response", sdo);
    case 3:
      return `SDO download response ${objectOf(bytes)}`;
    case 4:
      return `SDO abort ${objectOf(bytes)}: ${abortText(le(bytes, 4, 4), sdo.aborts)}`;
    case 5:
      switch (command & 3) {
        case 0:
          return `SDO block download response ${objectOf(bytes)} block size ${bytes[4]}${command & 4 ? ", CRC" : ""}`;
        case 1:
          return "SDO block download end response";
        case 2:
          return `SDO block download block response ackseq ${bytes[1]}, block size ${bytes[2]}`;
        default:
          return `SDO command ${hex(command, 2)} (unknown)`;
      }
    case 6:
      if (command & 1) {
        return `SDO block upload end request, ${(command >> 2) & 7} bytes not data, CRC ${hex(le(bytes, 1, 2), 4)}`;
      }
      return `SDO block upload response ${objectOf(bytes)} ` +
        `${command & 2 ? `${le(bytes, 4, 4)} bytes` : "size not indicated"}${command & 4 ? ", CRC" : ""}`;
    default:
      return `SDO command ${hex(command, 2)} (unknown)`;
  }
}

/** Heartbeat, boot-up, node guarding (the answer has the toggle bit; `guarded`: a guard request came before). */
function errorControl(bytes, rtr, guarded) {
  if (rtr) {
    return "node guarding request";
  }
  if (bytes.length !== 1) {
    return lengthProblem("heartbeat", "1 byte", bytes.length);
  }
  const state = NMT_STATES.get(bytes[0] & 0x7F) ?? `state ${hex(bytes[0] & 0x7F, 2)} (unknown)`;
  if (guarded || bytes[0] & 0x80) {
    return `node guarding answer: ${state}, toggle ${bytes[0] >> 7}`;
  }
  return bytes[0] === 0 ? "boot-up" : `heartbeat: ${state}`;
}

function lssMaster(bytes) {
  const cs = bytes[0];
  if (cs === 0x04) {
    const mode = ["waiting", "configuration"][bytes[1]] ?? `mode ${hex(bytes[1], 2)} (unknown)`;
    return `LSS switch state global: ${mode}`;
  }
  if (cs >= 0x40 && cs <= 0x43) {
    return `LSS switch state selective ${LSS_IDENTITY[cs - 0x40]} ${hex(le(bytes, 1, 4), 8)}`;
  }
  if (cs >= 0x46 && cs <= 0x4B) {
    return `LSS identify remote slave ${LSS_REMOTE[cs - 0x46]} ${hex(le(bytes, 1, 4), 8)}`;
  }
  if (cs >= 0x5A && cs <= 0x5D) {
    return `LSS inquire identity ${LSS_IDENTITY[cs - 0x5A]}`;
  }
  switch (cs) {
    case 0x11:
      return `LSS configure node-ID ${bytes[1]}`;
    case 0x13: {
      const rate = bytes[1] === 0 ? LSS_BIT_RATES[bytes[2]] ?? "reserved" : null;
      return `LSS configure bit timing table ${bytes[1]} index ${bytes[2]}${rate === null ? "" : ` (${rate})`}`;
    }
    case 0x15:
      return `LSS activate bit timing, switch delay ${le(bytes, 1, 2)} ms`;
    case 0x17:
      return "LSS store configuration";
    case 0x4C:
      return "LSS identify non-configured remote slave";
    case 0x51:
      if (bytes[5] === 0x80) {
        return "LSS fastscan reset";
      }
      return `LSS fastscan ID ${hex(le(bytes, 1, 4), 8)} bit ${bytes[5]}, ${LSS_IDENTITY[bytes[6]] ?? bytes[6]}, ` +
        `next ${LSS_IDENTITY[bytes[7]] ?? bytes[7]}`;
    case 0x5E:
      return "LSS inquire node-ID";
    default:
      return `LSS command ${hex(cs, 2)} (unknown)`;
  }
}

/** An LSS answer's error code: 0 success, 0xFF manufacturer-specific (its code in the next byte). */
function lssResult(bytes, errors) {
  if (bytes[1] === 0) {
    return "success";
  }
  if (bytes[1] === 0xFF) {
    return `manufacturer-specific error ${hex(bytes[2], 2)}`;
  }
  return errors[bytes[1]] ?? `error ${bytes[1]}`;
}

function lssSlave(bytes) {
  const cs = bytes[0];
  if (cs >= 0x5A && cs <= 0x5D) {
    return `LSS inquire identity ${LSS_IDENTITY[cs - 0x5A]} response ${hex(le(bytes, 1, 4), 8)}`;
  }
  switch (cs) {
    case 0x11:
      return `LSS configure node-ID response: ${lssResult(bytes, {1: "node-ID out of range"})}`;
    case 0x13:
      return `LSS configure bit timing response: ${lssResult(bytes, {1: "bit timing not supported"})}`;
    case 0x17:
      return `LSS store configuration response: ${lssResult(bytes,
        {1: "store not supported", 2: "storage media access error"})}`;
    case 0x44:
      return "LSS switch state selective response";
    case 0x4F:
      return "LSS identify slave response";
    case 0x50:
      return "LSS identify non-configured slave response";
    case 0x5E:
      return `LSS inquire node-ID response ${bytes[1]}`;
    default:
      return `LSS response ${hex(cs, 2)} (unknown)`;
  }
}

/**
 * What `frame` says: {kind (KINDS), node (the node-ID it concerns; null: none or all), text}.
 * frame: {id, data (hex, as frame events give it), rtr, eff (a 29-bit frame), dir ("tx": a node sent it; "rx": it
 * came from the bus), node (the sender, for tx), guarded (a node guarding request of this COB-ID came before: the
 * answer's toggle)}.
 * pdo(frame, bytes): the PDO the frame is by the mapping read from its node, {name: "TPDO1", node, text: the values}
 * (web/pdomap.js), or null when it is not known (yet): the PDO is then named by the predefined connection set only.
 * sdo: {type(frame, node, index, sub): the data type ("VISIBLE_STRING") of an object of the SDO server `node`, or null
 * when it is not known (yet): its expedited values are then unsigned numbers; aborts: the abort codes' texts
 * (abortTexts()), or null while they have not come: an abort then shows its code only}.
 */
export function decode(frame, pdo = () => null, sdo = {}) {
  const id = frame.id;
  const bytes = bytesOf(frame.data);
  const rtr = Boolean(frame.rtr);
  const own = frame.dir === "tx" ? frame.node ?? null : null;
  const low = id & 0x7F;
  const fn = id >> 7;
  const sized = (kind, text, node = low) => ({kind, node, text});
  if (frame.eff || id > 0x7FF) {
    // CANopen is 11-bit frames only: an extended frame 0x181 (J1939, a gateway) is no TPDO1 of node 1
    return {kind: "extended", node: own, text: ""};
  }
  if (!rtr) {
    const mapped = pdo(frame, bytes); // first: a PDO may be given any COB-ID, not only its predefined one
    if (mapped) {
      return {kind: "PDO", node: mapped.node, text: mapped.text === "" ? mapped.name : `${mapped.name} ${mapped.text}`};
    }
  }
  if (id === 0x000) {
    const {node, text} = nmt(bytes);
    return {kind: "NMT", node, text};
  }
  if (id === 0x080) {
    return {kind: "SYNC", node: null, text: sync(bytes)};
  }
  if (fn === 0x1) {
    return sized("EMCY", emcy(bytes));
  }
  if (id === 0x100) {
    return {kind: "TIME", node: null, text: time(bytes)};
  }
  if (PDO_FUNCTIONS.has(fn) && low !== 0) {
    return sized("PDO", `${PDO_FUNCTIONS.get(fn)}${rtr ? " remote request" : ""}`);
  }
  if ((fn === 0xB || fn === 0xC) && low !== 0) {
    if (bytes.length !== 8) {
      return sized("SDO", lengthProblem("SDO", "8 bytes", bytes.length));
    }
    const lookups = {typeOf: (index, sub) => sdo.type?.(frame, low, index, sub) ?? null, aborts: sdo.aborts ?? null};
    return sized("SDO", fn === 0xB ? sdoResponse(bytes, lookups) : sdoRequest(bytes, lookups));
  }
  if (fn === 0xE && low !== 0) {
    return sized("heartbeat", errorControl(bytes, rtr, frame.guarded));
  }
  if (id === 0x7E5 || id === 0x7E4) {
    if (bytes.length !== 8) {
      return {kind: "LSS", node: null, text: lengthProblem("LSS", "8 bytes", bytes.length)};
    }
    return {kind: "LSS", node: null, text: id === 0x7E5 ? lssMaster(bytes) : lssSlave(bytes)};
  }
  return {kind: "other", node: own, text: ""};
}
