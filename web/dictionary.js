// The node view's object dictionary as a tree (docs/web.md "The node view"): the `objects` answer grouped by index,
// the values' texts, what a user typed made into the value a `set` takes. No DOM: tested with node --test.

import {hex} from "./format.js";
import {chunks, parseObject} from "./objects.js";

/**
 * The entries of an `objects` answer ([{object: "0x1018:01", name, object_name, type, access, unit, low, high}], in
 * (index, sub) order) grouped by index: [{index: "0x1018", name (the object's name), entries}], in the same order.
 * Each entry gets `index` and `sub` ("01") besides its own fields.
 */
export function groupObjects(objects) {
  const groups = [];
  let group = null;
  for (const o of objects) {
    const [index, sub] = o.object.split(":");
    if (group === null || group.index !== index) {
      group = {index, name: o.object_name ?? o.name ?? "", entries: []};
      groups.push(group);
    }
    group.entries.push({...o, index, sub});
  }
  return groups;
}

/** An object of one sub-index (a VAR): shown as one row, not as a tree of its own. */
export function isSingle(group) {
  return group.entries.length === 1 && group.entries[0].sub === "00";
}

/** Whether a `set` may write it: rw and wo (rww, rwr are rw in `objects`); ro and const are not edited. */
export function isWritable(entry) {
  return entry.access === "rw" || entry.access === "wo";
}

/** The limits column: "0..60000", "≥ 100", "≤ 8", or "" (the EDS has none). */
export function limits(entry) {
  const low = entry.low ?? null;
  const high = entry.high ?? null;
  if (low !== null && high !== null) {
    return `${low}..${high}`;
  }
  if (low !== null) {
    return `≥ ${low}`;
  }
  return high === null ? "" : `≤ ${high}`;
}

const COB_ID_NAME = /\bCOB[- ]?ID\b/i;

/**
 * Whether an entry is a COB-ID, shown in hex: an UNSIGNED32 that is 0x1005 (SYNC), 0x1012 (TIME), 0x1014 (EMCY),
 * sub 1 or 2 of an SDO parameter (0x1200-0x12FF), sub 1 of a PDO's communication parameter (0x1400-0x15FF,
 * 0x1800-0x19FF), or whose name says so ("COB-ID", "COB ID": a device's own).
 */
export function isCobId(entry) {
  const at = parseObject(entry.object);
  if (entry.type !== "UNSIGNED32" || at === null) {
    return false;
  }
  const {index, sub} = at;
  return index === 0x1005 || index === 0x1012 || index === 0x1014 ||
    (index >= 0x1200 && index <= 0x12FF && (sub === 1 || sub === 2)) ||
    (((index >= 0x1400 && index <= 0x15FF) || (index >= 0x1800 && index <= 0x19FF)) && sub === 1) ||
    COB_ID_NAME.test(entry.name ?? entry.object_name ?? "");
}

/** A value as `get` gives it (docs/control-protocol.md "Typed values") as the text of its cell; the value of a
 * COB-ID (isCobId(entry)) in hex of 8 digits, as the page writes 32-bit values: "0x00000080". */
export function valueText(value, entry = null) {
  if (value === undefined || value === null) {
    return "";
  }
  if (entry !== null && isCobId(entry) && Number.isSafeInteger(value) && value >= 0) {
    return hex(value, 8);
  }
  return typeof value === "string" ? value : String(value);
}

/** The tooltip of a value's cell: the other form of an unsigned integer, its decimal for a COB-ID (shown in hex:
 * "128"), else its hex (hexHint); "" for anything else. */
export function valueHint(value, entry) {
  if (isCobId(entry) && Number.isSafeInteger(value) && value >= 0) {
    return String(value);
  }
  return hexHint(value, entry.type);
}

/** A hint beside an unsigned integer's decimal text (identities and bit fields read better in hex):
 * "0x0000024E"; "" for anything else. */
export function hexHint(value, type) {
  const digits = {UNSIGNED8: 2, UNSIGNED16: 4, UNSIGNED24: 6, UNSIGNED32: 8}[type];
  if (digits === undefined || !Number.isSafeInteger(value) || value < 0) {
    return "";
  }
  return `0x${value.toString(16).toUpperCase().padStart(digits, "0")}`;
}

const DECIMAL = /^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/;

/**
 * What a user typed for an entry of `type`, as the `value` of a `set`: {value} or {error}. A VISIBLE_STRING takes
 * the text as it is; `true`/`false` are booleans; a decimal number is a JSON number (but an integer beyond 2^53,
 * which a double would change, stays a string, as does "0x2A": the emulator reads the command language's numbers).
 * Anything else goes as a string, and the emulator's refusal says what is wrong with it.
 */
export function parseInput(text, type) {
  if (type === "VISIBLE_STRING") {
    return {value: text};
  }
  const word = text.trim();
  if (word === "") {
    return {error: "a value is needed"};
  }
  if (word === "true" || word === "false") {
    return {value: word === "true"};
  }
  if (DECIMAL.test(word)) {
    const number = Number(word);
    const exact = !/^[+-]?\d+$/.test(word) || Number.isSafeInteger(number);
    return {value: exact && Number.isFinite(number) ? number : word};
  }
  return {value: word};
}

/**
 * When to read the values shown: a round (one `get` per 64 objects) about once a second, at once when something
 * shown has never been read (a group just expanded), and never a round while the last one is unanswered, however
 * slow the answers come.
 */
export class ValuePoll {
  #periodMs;
  #busy = false;
  #last = -Infinity;

  constructor(periodMs = 1000) {
    this.#periodMs = periodMs;
  }

  get busy() {
    return this.#busy;
  }

  /** The batches to ask at `ms` for the objects `shown` ([]: none now); `unread`: some of them were never read. Each
   * non-empty answer must be followed by done() once all its requests are answered (or failed). */
  take(ms, shown, unread) {
    if (this.#busy || shown.length === 0 || (ms - this.#last < this.#periodMs && !unread)) {
      return [];
    }
    this.#busy = true;
    this.#last = ms;
    return chunks(shown);
  }

  done() {
    this.#busy = false;
  }
}
