// Reads the PDO mapping of the nodes whose PDOs the trace shows, lazily and a few at a time, over the control protocol:
// `list` (which device each node is), `objects` once per device and variant (the names, types and units of its
// dictionary, the same for every node of it), then `get` of the node's PDO COB-IDs and mapping entries (64 objects a
// request at most). Read again when the mapping may have changed (mappingMayChange()). For a node that only serves
// SDOs, the dictionary alone (its objects' data types decode the SDOs' values). No DOM: tested with node --test.

import {Dictionary, pdosOf} from "./pdomap.js";

/** Nodes read at once: 127 nodes whose PDOs all start at one NMT start are read in turn, not in one burst of
 * answers (a session's answers may not pile up past 1 MiB; 16 nodes are at most 32 gets of 64 objects). At 4, the trace of
 * 127 nodes took 20 s to name every node's TPDO (a node or two per exchange); at 16, a few seconds. */
export const PARALLEL = 16;

/** SDO downloads to these indices change a PDO's COB-ID or mapping (0x1400-0x1BFF). */
const PDO_PARAMETERS = [0x1400, 0x1BFF];

/**
 * After which frame a node's PDOs may have changed, so that its mapping is read again: an NMT command that puts it in
 * pre-operational (pre-operational, reset node, reset communication: where a master remaps), its boot-up, an SDO
 * download to its PDO parameters answered. {bus, node} (node null: every node of the bus), or null.
 * frame: {id, data (hex), rtr, eff, bus}.
 */
export function mappingMayChange(frame) {
  if (frame.rtr || frame.eff) {
    return null; // an extended frame is no NMT command, boot-up or SDO answer, whatever its identifier
  }
  const data = frame.data.toUpperCase();
  if (frame.id === 0x000 && data.length === 4 && ["80", "81", "82"].includes(data.slice(0, 2))) {
    const node = parseInt(data.slice(2, 4), 16);
    return {bus: frame.bus, node: node === 0 ? null : node};
  }
  const node = frame.id & 0x7F;
  if (node === 0) {
    return null;
  }
  if (frame.id >> 7 === 0xE && data === "00") {
    return {bus: frame.bus, node};
  }
  if (frame.id >> 7 === 0xB && data.length === 16 && data.slice(0, 2) === "60") {
    const index = parseInt(data.slice(4, 6) + data.slice(2, 4), 16);
    return index >= PDO_PARAMETERS[0] && index <= PDO_PARAMETERS[1] ? {bus: frame.bus, node} : null;
  }
  return null;
}

export class PdoReader {
  #maps;
  #onRead;
  // "bus/node" -> {bus, node, state: wanted | reading | read | absent | failed, again (read it once more when done),
  // pdos (its mapping is wanted; false: its dictionary alone)}
  #nodes = new Map();
  #types = new Map(); // "bus/node" -> the Dictionary of a node read (for its objects' data types)
  #devices = null; // "bus/node" -> "device/variant", from `list`; null: not asked in this session
  #listing = null; // the `list` under way
  #dictionaries = new Map(); // "device/variant" -> Promise<Dictionary>
  #reading = 0;
  problem = null; // the last reading that failed, for the trace's status line

  /** maps: the PdoMaps to fill; onRead(bus, node): a node's PDOs were (re)read. */
  constructor(maps, onRead = () => {}) {
    this.#maps = maps;
    this.#onRead = onRead;
  }

  /** A PDO of node `node` on `bus` was seen: read its mapping unless it is known or being read. */
  want(bus, node) {
    const key = `${bus}/${node}`;
    const n = this.#nodes.get(key);
    if (n === undefined) {
      this.#nodes.set(key, {bus, node, state: "wanted", again: false, pdos: true});
    } else if (!n.pdos) { // its dictionary was wanted alone: now its mapping too
      n.pdos = true;
      if (n.state === "reading") {
        n.again = true;
      } else if (n.state !== "absent") {
        n.state = "wanted";
      }
    }
  }

  /** An SDO of node `node` on `bus` was seen: read its dictionary (not its mapping) unless it is known or being read. */
  wantTypes(bus, node) {
    const key = `${bus}/${node}`;
    if (!this.#nodes.has(key)) {
      this.#nodes.set(key, {bus, node, state: "wanted", again: false, pdos: false});
    }
  }

  /** The data type of index:sub of node `node` on `bus` ("VISIBLE_STRING"), or null: not read (yet), or no such object. */
  typeOf(bus, node, index, sub) {
    return this.#types.get(`${bus}/${node}`)?.entry(index, sub)?.type ?? null;
  }

  /** The mapping of `node` (null: of every node read on `bus`) may have changed: read it again (what was read stays
   * in use until then). A node not found before is looked for again (LSS may have given it its ID). */
  stale(bus, node) {
    for (const n of this.#nodes.values()) {
      if (n.bus === bus && (node === null || n.node === node)) {
        if (n.state === "absent") {
          this.#devices = null;
        }
        if (n.state === "reading") {
          n.again = true; // what is being read may be from before the change
        } else {
          n.state = "wanted";
        }
      }
    }
  }

  /** A new session: what failed or was not found is tried again; the list of nodes is asked anew. */
  reset() {
    this.#devices = null;
    this.#listing = null;
    for (const n of this.#nodes.values()) {
      if (n.state !== "read") {
        n.state = "wanted";
      }
    }
  }

  /** Forgets everything read (the trace was cleared: the PDOs seen from now on are read anew). */
  clear() {
    this.#nodes.clear();
    this.#types.clear();
    this.#maps.clear();
    this.#dictionaries.clear();
    this.problem = null;
  }

  /** Before an exchange: starts reading the next wanted nodes, PARALLEL at most at a time. */
  tick(session) {
    for (const n of this.#nodes.values()) {
      if (this.#reading >= PARALLEL) {
        return;
      }
      if (n.state === "wanted") {
        this.#read(session, n);
      }
    }
  }

  async #read(session, n) {
    n.state = "reading";
    this.#reading++;
    const name = `${n.node}@${n.bus}`;
    try {
      const device = (await this.#list(session)).get(`${n.bus}/${n.node}`);
      if (device === undefined) {
        n.state = "absent"; // not an emulated node: a PDO of another device on the bus
        this.#maps.delete(n.bus, n.node);
        this.#types.delete(`${n.bus}/${n.node}`);
        return;
      }
      const dictionary = await this.#dictionary(session, device, name);
      if (!n.pdos) {
        if (this.#nodes.get(`${n.bus}/${n.node}`) === n) { // not cleared meanwhile
          this.#types.set(`${n.bus}/${n.node}`, dictionary);
          n.state = "read";
          this.#onRead(n.bus, n.node);
        }
        return;
      }
      const values = [];
      const answers = await Promise.all(dictionary.mappingObjects().map((objects) =>
        session.request("get", {node: name, objects})));
      for (const answer of answers) {
        values.push(...answer.values);
      }
      if (this.#nodes.get(`${n.bus}/${n.node}`) === n) { // not cleared meanwhile
        this.#types.set(`${n.bus}/${n.node}`, dictionary);
        this.#maps.set(n.bus, n.node, pdosOf(values, dictionary), dictionary);
        n.state = "read";
        this.#onRead(n.bus, n.node);
      }
    } catch (error) {
      n.state = "failed";
      this.problem = `${n.pdos ? "PDO mapping" : "dictionary"} of node ${n.node}: ${error.message}`;
    } finally {
      this.#reading--;
      if (n.again) {
        n.again = false;
        n.state = "wanted";
      }
    }
  }

  #list(session) {
    if (this.#devices !== null) {
      return Promise.resolve(this.#devices);
    }
    if (this.#listing === null) {
      this.#listing = session.request("list").then((answer) => {
        this.#devices = new Map(answer.nodes.map((d) => [`${d.bus}/${d.node}`, `${d.device}/${d.variant}`]));
        return this.#devices;
      }).finally(() => { this.#listing = null; });
    }
    return this.#listing;
  }

  #dictionary(session, device, name) {
    if (!this.#dictionaries.has(device)) {
      const asked = session.request("objects", {node: name}).then((answer) => new Dictionary(answer.objects));
      asked.catch(() => this.#dictionaries.delete(device)); // asked again for the next node of that device
      this.#dictionaries.set(device, asked);
    }
    return this.#dictionaries.get(device);
  }
}
