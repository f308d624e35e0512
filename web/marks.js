// The marks of the plots' time axis (docs/web.md "Plots"): the EMCYs a node sent and its NMT state changes, from
// the events, at their time on the emulator's clock, with a short label. No DOM: tested with node --test.

import {nodeKey} from "./nodes.js";
import {hex} from "./format.js";

/** Marks kept per node: the newest; older ones are dropped (a node raising EMCYs in a loop stays bounded). */
export const MARKS_PER_NODE = 256;

/** The mark of an event: {t (s), kind ("emcy", "nmt"), label} ("EMCY 0x5000", "OPERATIONAL"); null for others. */
export function markOf(event) {
  switch (event.event) {
    case "emcy":
      return {t: event.time_us / 1e6, kind: "emcy", label: `EMCY ${hex(event.code, 4)}`};
    case "nmt":
      return {t: event.time_us / 1e6, kind: "nmt", label: event.to};
    default:
      return null;
  }
}

export class Marks {
  #perNode;
  #byNode = new Map(); // node key -> marks, oldest first

  constructor(perNode = MARKS_PER_NODE) {
    this.#perNode = perNode;
  }

  /** An event (of any kind: those that are no mark are ignored). Kept for every node, plotted or not, so that a
   * series added later shows what happened before. */
  event(event) {
    const mark = markOf(event);
    if (mark === null || event.node === undefined) {
      return;
    }
    const key = nodeKey(event.bus, event.node);
    const list = this.#byNode.get(key) ?? [];
    list.push(mark);
    if (list.length > this.#perNode) {
      list.splice(0, list.length - this.#perNode);
    }
    this.#byNode.set(key, list);
  }

  /** The marks of node `key` from `from` to `to` (s, both included), oldest first. */
  between(key, from, to) {
    return (this.#byNode.get(key) ?? []).filter((m) => m.t >= from && m.t <= to);
  }
}
