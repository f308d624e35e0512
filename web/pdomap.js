// PDOs by their mapping, for the trace: which objects of a node to read to know its PDOs (their COB-IDs and mapping
// entries), the PDOs those values give, and a PDO's payload as "name=value unit" of its mapped objects. The names,
// types and units come from the node's dictionary (`objects`). No DOM: tested with node --test (tests/web/js).

import {chunks, objectName, parseObject} from "./objects.js";

/** The communication and mapping parameters of the PDOs: the first index of each range, and how a PDO is named. */
const RANGES = [
  {comm: 0x1400, mapping: 0x1600, prefix: "RPDO", dir: "rx"},
  {comm: 0x1800, mapping: 0x1A00, prefix: "TPDO", dir: "tx"},
];
const PDO_COUNT = 512; // CiA 301: 0x1400-0x15FF and the rest, 512 PDOs of each direction at most

function key(index, sub) {
  return index * 256 + sub;
}

/** The bits of a type, by its name (UNSIGNED24: 24); null: a type without a fixed size. */
export function typeBits(type) {
  if (type === "BOOLEAN") {
    return 1;
  }
  const match = /^(?:UNSIGNED|INTEGER|REAL)(\d+)$/.exec(type ?? "");
  return match === null ? null : Number(match[1]);
}

/**
 * A node's dictionary as `objects` lists it, for the PDOs: each sub-index's label, type and unit. The label is the
 * sub-index's own name where that is unique in the dictionary ("Read Working Distance"); a name that several objects
 * share ("Value") is told apart by its object's name ("Sensor Value", or "Sensor Status Value" when the object's name
 * does not end with it).
 */
export class Dictionary {
  #entries = new Map(); // key(index, sub) -> {object, label, type, unit}

  constructor(objects) {
    const counts = new Map();
    for (const o of objects) {
      counts.set(o.name, (counts.get(o.name) ?? 0) + 1);
    }
    for (const o of objects) {
      const {index, sub} = parseObject(o.object);
      let label = o.name ?? o.object_name ?? o.object;
      if (o.name !== null && o.name !== undefined && counts.get(o.name) > 1 && o.object_name) {
        label = o.object_name.toLowerCase().endsWith(o.name.toLowerCase()) ? o.object_name :
          `${o.object_name} ${o.name}`;
      }
      this.#entries.set(key(index, sub), {object: objectName(index, sub), label, type: o.type, unit: o.unit ?? null});
    }
  }

  has(index, sub) {
    return this.#entries.has(key(index, sub));
  }

  /** {object, label, type, unit} of index:sub, or null. */
  entry(index, sub) {
    return this.#entries.get(key(index, sub)) ?? null;
  }

  /** The `get` lists (at most GET_MAX objects each) that read every PDO's COB-ID and mapping the node has. */
  mappingObjects() {
    const wanted = [];
    for (const {comm, mapping} of RANGES) {
      for (let n = 0; n < PDO_COUNT; n++) {
        if (this.has(comm + n, 1)) {
          wanted.push(objectName(comm + n, 1));
        }
        for (let sub = 0; sub <= 0x40 && this.has(mapping + n, 0); sub++) {
          if (this.has(mapping + n, sub)) {
            wanted.push(objectName(mapping + n, sub));
          }
        }
      }
    }
    return chunks(wanted);
  }
}

/**
 * The node's valid PDOs from the values of its mapping objects (the `values` of the `get`s of mappingObjects(), in
 * any order; an object with an error counts as absent): [{name ("TPDO1"), dir ("tx": the node sends it; "rx": it
 * receives it), cobId, mpdo (null, "SAM" or "DAM": a multiplexed PDO), entries: [{object, label, type, unit, bits}
 * (object null: a dummy entry, its bits skipped)]}].
 */
export function pdosOf(values, dictionary) {
  const read = new Map();
  for (const v of values) {
    if (!("error" in v)) {
      const {index, sub} = parseObject(v.object);
      read.set(key(index, sub), Number(v.value));
    }
  }
  const pdos = [];
  for (const {comm, mapping, prefix, dir} of RANGES) {
    for (let n = 0; n < PDO_COUNT; n++) {
      const cob = read.get(key(comm + n, 1));
      const count = read.get(key(mapping + n, 0));
      if (cob === undefined || count === undefined || cob >= 0x80000000) {
        continue; // not there, or not valid (bit 31)
      }
      const cobId = (cob & 0x20000000) !== 0 ? cob & 0x1FFFFFFF : cob & 0x7FF;
      const mpdo = count === 0xFE ? "SAM" : count === 0xFF ? "DAM" : null;
      const entries = [];
      for (let sub = 1; mpdo === null && sub <= count; sub++) {
        const entry = read.get(key(mapping + n, sub));
        if (entry === undefined) {
          break; // a mapping that says more than the node has: what there is
        }
        const [index, objectSub, bits] = [Math.floor(entry / 0x10000), (entry >> 8) & 0xFF, entry & 0xFF];
        const known = index >= 0x1000 ? dictionary.entry(index, objectSub) : null;
        entries.push(known === null ?
          {object: index >= 0x1000 ? objectName(index, objectSub) : null, label: objectName(index, objectSub),
            type: null, unit: null, bits} :
          {...known, bits});
      }
      pdos.push({name: `${prefix}${n + 1}`, dir, cobId, mpdo, entries});
    }
  }
  return pdos;
}

/** `bits` bits of `bytes` from bit `offset` on, little-endian (CiA 301: the first mapped object from bit 0), as a BigInt. */
function bitsOf(bytes, offset, bits) {
  let value = 0n;
  for (let i = bits - 1; i >= 0; i--) {
    const at = offset + i;
    value = (value << 1n) | BigInt((bytes[at >> 3] >> (at & 7)) & 1);
  }
  return value;
}

/** 7 significant digits at most: a REAL32 as it was written (0.1, not 0.10000000149011612). */
function real32(raw) {
  const view = new DataView(new ArrayBuffer(4));
  view.setUint32(0, Number(raw), true);
  const value = view.getFloat32(0, true);
  return Number.isFinite(value) ? String(Number(value.toPrecision(7))) : String(value);
}

function real64(raw) {
  const view = new DataView(new ArrayBuffer(8));
  view.setBigUint64(0, raw, true);
  return String(view.getFloat64(0, true));
}

/** The value of `bits` raw bits as `type` says. */
export function valueText(raw, bits, type) {
  if (type === "BOOLEAN") {
    return raw === 0n ? "false" : "true";
  }
  if (type?.startsWith("INTEGER")) {
    return String(BigInt.asIntN(bits, raw));
  }
  if (type === "REAL32" && bits === 32) {
    return real32(raw);
  }
  if (type === "REAL64" && bits === 64) {
    return real64(raw);
  }
  if (type === "VISIBLE_STRING") {
    let text = "";
    for (let i = 0; i < bits; i += 8) {
      const c = Number((raw >> BigInt(i)) & 0xFFn);
      if (c !== 0) {
        text += String.fromCharCode(c);
      }
    }
    return JSON.stringify(text);
  }
  if (type === null || type.startsWith("UNSIGNED")) {
    return String(raw);
  }
  return "0x" + raw.toString(16).toUpperCase().padStart(Math.ceil(bits / 4), "0"); // OCTET_STRING, DOMAIN...
}

function named(entry, value) {
  return `${entry.label}=${value}${entry.unit ? ` ${entry.unit}` : ""}`;
}

/** A multiplexed PDO (CiA 301 7.2.3): SAM (the producer's object) or DAM (the destination's), 4 bytes of value. */
function multiplexed(pdo, bytes, dictionary) {
  if (bytes.length !== 8) {
    return `${pdo.mpdo}-MPDO (8 bytes expected, ${bytes.length} given)`;
  }
  const index = bytes[1] | (bytes[2] << 8);
  const sub = bytes[3];
  const address = bytes[0] & 0x7F;
  const raw = bitsOf(bytes, 32, 32);
  if (bytes[0] & 0x80) {
    return `DAM-MPDO to ${address === 0 ? "all nodes" : `node ${address}`} ${objectName(index, sub)} = ` +
      `0x${raw.toString(16).toUpperCase().padStart(8, "0")}`;
  }
  const entry = dictionary?.entry(index, sub) ?? null;
  if (entry === null) {
    return `SAM-MPDO of node ${address} ${objectName(index, sub)} = 0x${raw.toString(16).toUpperCase().padStart(8, "0")}`;
  }
  const bits = Math.min(typeBits(entry.type) ?? 32, 32);
  return `SAM-MPDO of node ${address} ${entry.object} ${named(entry, valueText(raw & ((1n << BigInt(bits)) - 1n), bits,
    entry.type))}`;
}

/** The payload of `pdo` as its mapped objects: "Read Pollution=0 %, Read Working Distance=15 cm". */
export function pdoText(pdo, bytes, dictionary = null) {
  if (pdo.mpdo !== null) {
    return multiplexed(pdo, bytes, dictionary);
  }
  const parts = [];
  let offset = 0;
  for (const entry of pdo.entries) {
    if (offset + entry.bits > bytes.length * 8) {
      break;
    }
    if (entry.object !== null) {
      parts.push(named(entry, valueText(bitsOf(bytes, offset, entry.bits), entry.bits, entry.type)));
    }
    offset += entry.bits;
  }
  const needed = Math.ceil(pdo.entries.reduce((sum, e) => sum + e.bits, 0) / 8);
  if (needed > bytes.length) {
    parts.push(`(mapping needs ${needed} bytes, ${bytes.length} sent)`);
  }
  return parts.join(", ");
}

/**
 * The PDOs of the nodes read so far, found by a frame: a node's frame on one of its TPDOs' COB-IDs, a frame from the
 * bus on one of a node's RPDOs' COB-IDs. Node keys are "bus/node" (web/nodes.js nodeKey).
 */
export class PdoMaps {
  #nodes = new Map(); // key -> {bus, node, pdos, dictionary}
  #tx = new Map(); // `${bus}/${node}/${cobId}` -> {node, pdo, dictionary}
  #rx = new Map(); // `${bus}/${cobId}` -> {node, pdo, dictionary}, the lowest node-ID receiving it

  /** The PDOs of node `node` on `bus` (pdosOf()), and its dictionary (for MPDOs); replaces what it had. */
  set(bus, node, pdos, dictionary) {
    this.#nodes.set(`${bus}/${node}`, {bus, node, pdos, dictionary});
    this.#index();
  }

  /** Forgets a node's PDOs (its node-ID went to another device). */
  delete(bus, node) {
    this.#nodes.delete(`${bus}/${node}`);
    this.#index();
  }

  has(bus, node) {
    return this.#nodes.has(`${bus}/${node}`);
  }

  clear() {
    this.#nodes.clear();
    this.#index();
  }

  #index() {
    this.#tx.clear();
    this.#rx.clear();
    const sorted = [...this.#nodes.values()].sort((a, b) => a.node - b.node);
    for (const {bus, node, pdos, dictionary} of sorted) {
      for (const pdo of pdos) {
        const found = {node, pdo, dictionary};
        if (pdo.dir === "tx") {
          this.#tx.set(`${bus}/${node}/${pdo.cobId}`, found);
        } else if (!this.#rx.has(`${bus}/${pdo.cobId}`)) {
          this.#rx.set(`${bus}/${pdo.cobId}`, found);
        }
      }
    }
  }

  /** The lookup of web/decode.js decode(): {name, node, text} of the PDO `frame` is, or null. */
  lookup(frame, bytes) {
    const found = frame.dir === "tx" ? this.#tx.get(`${frame.bus}/${frame.node}/${frame.id}`) :
      this.#rx.get(`${frame.bus}/${frame.id}`);
    if (found === undefined) {
      return null;
    }
    return {name: found.pdo.name, node: found.node, text: pdoText(found.pdo, bytes, found.dictionary)};
  }
}
