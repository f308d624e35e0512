// The trace's model: the frames received, each decoded once as it comes (web/decode.js), in a bounded ring, and
// again as what decodes them comes (a node's PDO mapping or dictionary, the abort texts); the filter; the texts of a
// row. No DOM: tested with node --test (tests/web/js).

import {cobId} from "./candump.js";
import {KINDS, decode} from "./decode.js";
import {Ring} from "./ring.js";

/** The frames kept: a minute of 127 nodes with 100 ms heartbeats is 76,200; this is about the last 15 s of that. */
export const CAPACITY = 20_000;

/** The columns of the trace, in order: field (the cell's data-field) and title. */
export const COLUMNS = [
  ["time", "time"], ["bus", "bus"], ["dir", "dir"], ["id", "COB-ID"], ["node", "node"], ["kind", "kind"],
  ["text", "decoded"], ["data", "data"],
].map(([field, title]) => ({field, title}));

/** "12.345": seconds.milliseconds of the emulator's clock (since it started). */
export function sinceStart(timeUs) {
  const ms = Math.floor(timeUs / 1000);
  return `${Math.floor(ms / 1000)}.${String(ms % 1000).padStart(3, "0")}`;
}

/** "14:03:07.250": the local wall-clock time of a time in µs since 1970. */
export function wallClock(unixUs) {
  const date = new Date(Math.floor(unixUs / 1000));
  const two = (n) => String(n).padStart(2, "0");
  return `${two(date.getHours())}:${two(date.getMinutes())}:${two(date.getSeconds())}.` +
    String(date.getMilliseconds()).padStart(3, "0");
}

/**
 * The filter from what the user typed: text (found, in any case, in the row's COB-ID, kind, decoded text or data),
 * kind (one of KINDS, or "" for all) and node ("" for all, else a node-ID 1..127). {match(entry), error}: error is
 * the reason a field cannot be used (then match is null).
 */
export function parseFilter({text = "", kind = "", node = ""} = {}) {
  if (kind !== "" && !KINDS.includes(kind)) {
    return {match: null, error: `kind: ${kind} is not one of ${KINDS.join(", ")}`};
  }
  const nodeText = node.trim();
  let nodeId = null;
  if (nodeText !== "") {
    nodeId = /^(0x[0-9a-f]+|\d+)$/i.test(nodeText) ? Number(nodeText) : NaN;
    if (!(nodeId >= 1 && nodeId <= 127)) {
      return {match: null, error: `node: "${nodeText}" is not a node-ID (1 to 127)`};
    }
  }
  const needle = text.trim().toLowerCase();
  return {
    match: (entry) => (kind === "" || entry.kind === kind) && (nodeId === null || entry.about === nodeId) &&
      (needle === "" || searchText(entry).includes(needle)),
    error: null,
  };
}

function searchText(entry) {
  entry.search ??= `${cobId(entry.id, entry.eff)}#${entry.data} ${entry.kind} ${entry.text}`.toLowerCase();
  return entry.search;
}

export class TraceLog {
  ring;
  #seq = 0; // the seq of the newest entry (entries are numbered 1, 2, ... and never again, even after clear())
  #guarded = new Set(); // "bus/COB-ID" of node guarding requests not answered yet
  #pdo;
  #sdo;

  /** pdo: the PDO lookup of decode() (PdoMaps.lookup); type: its SDO type lookup, type(frame, node, index, sub). */
  constructor(capacity = CAPACITY, pdo = () => null, type = () => null) {
    this.ring = new Ring(capacity);
    this.#pdo = pdo;
    this.#sdo = {type, aborts: null};
  }

  /** The abort codes' texts (web/decode.js abortTexts()) came: the SDO aborts kept are decoded again with them. True
   * when any text changed. */
  useAbortTexts(texts) {
    this.#sdo.aborts = texts;
    return this.redecode(null);
  }

  get newest() {
    return this.#seq;
  }

  /** A frame event: its entry, decoded ({seq, time_us, bus, dir, node, id, data, rtr, eff, kind, about, text}). */
  add(ev) {
    const key = `${ev.bus}/${ev.id}`;
    const frame = {time_us: ev.time_us, bus: ev.bus, dir: ev.dir, node: ev.node ?? null, id: ev.id, data: ev.data,
      rtr: Boolean(ev.rtr), eff: Boolean(ev.eff), guarded: false};
    if (!frame.eff && ev.id >> 7 === 0xE && ev.id <= 0x77F) { // the answer to a guard request has the toggle bit
      frame.guarded = !frame.rtr && this.#guarded.delete(key);
      if (frame.rtr) {
        this.#guarded.add(key);
      }
    }
    const entry = {seq: ++this.#seq, ...frame, ...this.#decode(frame)};
    this.ring.push(entry);
    return entry;
  }

  #decode(frame) {
    const {kind, node, text} = decode(frame, this.#pdo, this.#sdo);
    return {kind, about: node, text};
  }

  /** Decodes the PDOs and SDOs of `bus` (null: of every bus) again, and the frames not known (a PDO on a COB-ID of
   * its own), as a node's mapping or dictionary came; true when any text changed. */
  redecode(bus) {
    let changed = false;
    for (const entry of this.ring) {
      if (["PDO", "SDO", "other"].includes(entry.kind) && (bus === null || entry.bus === bus)) {
        const {kind, about, text} = this.#decode(entry);
        if (text !== entry.text || kind !== entry.kind) {
          Object.assign(entry, {kind, about, text, search: undefined});
          changed = true;
        }
      }
    }
    return changed;
  }

  clear() {
    this.ring.clear();
    this.#guarded.clear();
  }

  /** The entries after `seq` that are kept, oldest first. */
  since(seq) {
    const count = Math.min(this.#seq - seq, this.ring.length);
    const out = [];
    for (let i = this.ring.length - count; i < this.ring.length; i++) {
      out.push(this.ring.at(i));
    }
    return out;
  }

  /** The newest `limit` entries that `match`, oldest first. */
  lastMatching(match, limit) {
    const out = [];
    for (let i = this.ring.length - 1; i >= 0 && out.length < limit; i--) {
      const entry = this.ring.at(i);
      if (match(entry)) {
        out.push(entry);
      }
    }
    return out.reverse();
  }
}

/** The texts of an entry's cells by field; time by `clock` (hello's {time_us, unix_us}) when wall is asked. */
export function cells(entry, {wall = false, clock = null} = {}) {
  return {
    time: wall && clock !== null ? wallClock(clock.unix_us + entry.time_us - clock.time_us) : sinceStart(entry.time_us),
    bus: entry.bus,
    dir: entry.dir,
    id: cobId(entry.id, entry.eff),
    node: entry.about === null ? "" : String(entry.about),
    kind: entry.kind,
    text: entry.text,
    data: entry.rtr ? "remote request" : entry.data.replace(/(..)(?!$)/g, "$1 "),
  };
}
