// The overview's model (docs/web.md): every node as the last `show all` gave it, kept up to date between two of them
// by the events, and the emulator's clock estimated on the page's, for the ages. No DOM: tested with node --test.

import * as format from "./format.js";

/** The columns of the overview, in order: field (the cell's data-field) and title. */
export const COLUMNS = [
  ["node", "node"], ["bus", "bus"], ["device", "device"], ["state", "NMT state"], ["device-type", "device type"],
  ["heartbeat", "heartbeat"], ["heartbeat-age", "last heartbeat"], ["error-register", "error register"],
  ["faults", "faults"], ["emcy", "last EMCY"], ["emcy-age", "EMCY sent"],
].map(([field, title]) => ({field, title}));

/**
 * The emulator's clock (µs since it started: the events' time_us) estimated from the page's own (ms, as
 * performance.now() gives it): set by each `show` answer's time_us, moved forward by any later event time.
 */
export class EmuClock {
  #us = null;
  #ms = 0;

  set(us, ms) {
    this.#us = us;
    this.#ms = ms;
  }

  /** An event happened at `us`: the clock is at least there (the estimate lags by the answer's trip). */
  advance(us, ms) {
    const now = this.now(ms);
    if (now === null || us > now) {
      this.set(us, ms);
    }
  }

  now(ms) {
    return this.#us === null ? null : this.#us + Math.max(0, ms - this.#ms) * 1000;
  }
}

/** A node's key: node-IDs are unique per bus only. */
export function nodeKey(bus, node) {
  return `${bus}/${node}`;
}

/** The control protocol's node of a key: "vcan0/16" -> "16@vcan0" (right with several buses; a bus name may hold
 * a slash, a node-ID not). */
export function nodeRef(key) {
  const slash = key.lastIndexOf("/");
  return `${key.slice(slash + 1)}@${key.slice(0, slash)}`;
}

/**
 * A bus as the page names it: its name and its kind (python-can's interface name, show's bus_kind), "vcan0
 * (socketcan)", "plant (virtual)"; a udp_multicast bus's name says its kind already
 * ("udp_multicast:239.74.163.2:43113"), and an emulator older than bus_kind gives none: the name alone then.
 */
export function busLabel(name, kind) {
  return !kind || name.startsWith(`${kind}:`) ? name : `${name} (${kind})`;
}

/** A heartbeat is overdue once it is this many times its producer time (0x1017) old (docs/web.md). */
export const HEARTBEAT_OVERDUE = 1.5;

/**
 * Whether a node's heartbeat is overdue: it sends one (0x1017 not 0), it was heard once (as a heartbeat consumer,
 * CiA 301, watches only after the first), and at the last `show` the last one was more than HEARTBEAT_OVERDUE times
 * its period old. Judged at the show, where both times are the emulator's own: the age the page counts on between
 * two shows would mark a running heartbeat whose next one the page cannot know of yet (it learns of heartbeats only
 * from a show). A boot-up event since (a heartbeat after the show) ends it at once.
 */
export function heartbeatOverdue(n) {
  return n.heartbeat_ms > 0 && n.last_heartbeat_us !== null && n.shown_us !== undefined &&
    n.shown_us - n.last_heartbeat_us > HEARTBEAT_OVERDUE * n.heartbeat_ms * 1000;
}

export class NodeTable {
  #nodes = new Map(); // key -> the node as `show` gives it, changed in place by events
  #buses = new Map(); // bus name -> its kind (null: not given), in the order of the last show
  clock = new EmuClock();

  get size() {
    return this.#nodes.size;
  }

  /** A `show all` answer (received at `ms`): the nodes it lists, and nothing else, from now on; by bus (in the
   * emulator's order) and node-ID. */
  show(answer, ms) {
    this.clock.set(answer.time_us, ms);
    // The nodes heard on the bus that the emulator does not emulate (show all's "heard"): rows of their own
    const heard = (answer.heard ?? []).map((h) => ({...h, heard: true, faults: []}));
    const all = [...answer.nodes, ...heard];
    const buses = [...new Set(all.map((n) => n.bus))];
    const sorted = all.sort((a, b) => buses.indexOf(a.bus) - buses.indexOf(b.bus) || a.node - b.node);
    this.#nodes = new Map(sorted.map((n) => [nodeKey(n.bus, n.node),
      {...n, faults: [...n.faults], shown_us: answer.time_us}]));
    this.#buses = new Map(buses.map((bus) => [bus, all.find((n) => n.bus === bus).bus_kind ?? null]));
  }

  /** The buses of the last show, in its order: [{name, kind}] (kind null from an emulator that gives none). */
  buses() {
    return [...this.#buses].map(([name, kind]) => ({name, kind}));
  }

  /** Whether `key` is a node heard on the bus rather than an emulated one (nothing to open of it). */
  isHeard(key) {
    return this.#nodes.get(key)?.heard === true;
  }

  /** An event of the kinds the overview subscribes to (nmt, boot-up, emcy, fault) received at `ms`. */
  event(ev, ms) {
    this.clock.advance(ev.time_us, ms);
    const n = this.#nodes.get(nodeKey(ev.bus, ev.node));
    if (n === undefined) {
      return; // a node the next `show` brings (its ID changed by LSS, or the show has not come yet)
    }
    switch (ev.event) {
      case "nmt":
        n.state = ev.to;
        break;
      case "boot-up": // a boot-up counts as the heartbeat (show's last_heartbeat_us does)
        n.state = "PRE-OPERATIONAL";
        n.last_heartbeat_us = ev.time_us;
        break;
      case "emcy":
        n.last_emcy = {code: ev.code, register: ev.register, info: ev.info, time_us: ev.time_us};
        n.error_register = ev.register;
        break;
      case "fault":
        n.faults = n.faults.filter((f) => f !== ev.fault);
        if (ev.action === "injected") {
          n.faults.push(ev.fault);
        }
        break;
      default:
        break;
    }
  }

  /** The rows to show at `ms`: {key, state, heard, overdue (heartbeatOverdue), cells: {field: text}}, in the order
   * of show(). */
  rows(ms) {
    const now = this.clock.now(ms);
    return [...this.#nodes.entries()].map(([key, n]) => n.heard ? heardRow(key, n, now) : this.#row(key, n, now));
  }

  #row(key, n, now) {
    const overdue = heartbeatOverdue(n);
    return {
      key,
      state: n.state,
      heard: false,
      overdue,
      cells: {
        "node": String(n.node),
        "bus": n.bus,
        "device": format.device(n),
        "state": n.state,
        "device-type": format.hex(n.device_type, 8),
        "heartbeat": format.heartbeatPeriod(n.heartbeat_ms),
        "heartbeat-age": n.last_heartbeat_us === null ? "never" :
          format.ago(n.last_heartbeat_us, now) + (overdue ? " (overdue)" : ""),
        "error-register": format.hex(n.error_register, 2),
        "faults": n.faults.join(", "),
        "emcy": n.last_emcy === null ? "" : format.emcy(n.last_emcy),
        "emcy-age": n.last_emcy === null ? "" : format.ago(n.last_emcy.time_us, now),
      },
    };
  }
}

/** A node heard on the bus: what its heartbeats tell (its state and their age), nothing the emulator knows of it. */
function heardRow(key, n, now) {
  const cells = Object.fromEntries(COLUMNS.map(({field}) => [field, ""]));
  return {
    key,
    state: n.state,
    heard: true,
    overdue: false, // its period is not known here
    cells: {
      ...cells,
      "node": String(n.node),
      "bus": n.bus,
      "device": n.boot_up ? "heard on the bus (boot-up)" : "heard on the bus",
      "state": n.state,
      "heartbeat-age": format.ago(n.last_heartbeat_us, now),
    },
  };
}

/**
 * The overview's rows with a heading before each bus's first row when there are several buses (one table, a part
 * per bus): [{key: "bus:vcan1", heading: "vcan1 (socketcan): 2 nodes, 1 heard on the bus"}, row, ...], each bus named
 * with its kind from `buses` (NodeTable.buses()). With one bus, the rows as they are.
 */
export function withBusHeadings(rows, known = []) {
  const kinds = new Map(known.map((b) => [b.name, b.kind]));
  const buses = [...new Set(rows.map((r) => r.cells.bus))];
  if (buses.length < 2) {
    return rows;
  }
  const items = [];
  for (const bus of buses) {
    const own = rows.filter((r) => r.cells.bus === bus);
    const heard = own.filter((r) => r.heard).length;
    const emulated = own.length - heard;
    const count = `${emulated} ${emulated === 1 ? "node" : "nodes"}` + (heard > 0 ? `, ${heard} heard on the bus` : "");
    items.push({key: `bus:${bus}`, heading: `${busLabel(bus, kinds.get(bus))}: ${count}`});
    items.push(...own);
  }
  return items;
}

/** The status line: the buses, each with its kind, and the count of nodes on them: "vcan0 (socketcan): 3 nodes",
 * "plant (virtual), udp_multicast:239.74.163.2:43113: 2 nodes, 1 heard on the bus"; the count alone without buses. */
export function nodeCount(rows, buses = []) {
  const heard = rows.filter((r) => r.heard).length;
  const emulated = rows.length - heard;
  const count = `${emulated} ${emulated === 1 ? "node" : "nodes"}` + (heard > 0 ? `, ${heard} heard on the bus` : "");
  return buses.length === 0 ? count : `${buses.map((b) => busLabel(b.name, b.kind)).join(", ")}: ${count}`;
}
