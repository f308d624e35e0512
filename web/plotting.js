// What the plots show and how they are fed (docs/web.md "Plots"), without the DOM (tested with node --test): the
// series (a node's object each), the default ones (the objects the TPDOs of the picked node map), the sampling (one
// batched get per plotted node per exchange, never a second while the first is unanswered), the samples of each node
// and the marks of its EMCYs and NMT changes. web/plots.js draws it.

import {Marks} from "./marks.js";
import {nodeRef} from "./nodes.js";
import {SampleBuffer} from "./samples.js";
import {chunks, objectName, parseObject, plottableRow} from "./objects.js";
import {mappedObjects, mappingCounts, mappingEntries} from "./tpdo.js";

/** At most this many series in all (each node's then fits in one get of at most 64 objects). */
export const MAX_SERIES = 64;
/** A default that could not be loaded (the node did not answer) is tried again after this long. */
export const RETRY_MS = 2000;

export {plottableRow};

function seriesOf(key, row) {
  const name = row.name ?? row.object_name ?? "";
  return {key, object: row.object, unit: row.unit ?? "", label: `${row.object} ${name}`.trim()};
}

export class Plotting {
  #session;
  #nodes;
  #series = []; // {key, object, unit, label}, in the order added
  #buffers = new Map(); // node key -> SampleBuffer of its plotted objects
  #asked = new Set(); // node keys with a get on its way
  #dictionaries = new Map(); // node key -> Promise of its `objects` rows
  #custom = false; // the user added or removed a series: the plot no longer follows the picked node
  #defaults = null; // {key, since (ms), failed}: whose TPDO objects are (being) the default series
  #problems = new Map(); // node key -> what went wrong with it last
  marks = new Marks();
  /** Counts the changes of the series (not of their samples): a view rebuilds its charts when it moved. */
  changes = 0;

  /** session: web/api.js Session (request()); nodes: web/nodes.js NodeTable (the first node, before one is picked). */
  constructor(session, nodes) {
    this.#session = session;
    this.#nodes = nodes;
  }

  get series() {
    return [...this.#series];
  }

  /** The samples of node `key` (undefined when none of its objects is plotted). */
  buffer(key) {
    return this.#buffers.get(key);
  }

  /** The node whose TPDO objects are plotted while the user has not changed the series; null: none or changed. */
  get defaultKey() {
    return this.#custom || this.#defaults === null ? null : this.#defaults.key;
  }

  /** What went wrong last (a node that did not answer, a refused object); null: nothing. */
  get problem() {
    return this.#problems.size === 0 ? null : [...this.#problems.values()].join("; ");
  }

  /** The charts: the series grouped by node and unit (one y axis each; a node's series share its sample times). */
  charts() {
    const charts = new Map();
    for (const s of this.#series) {
      const id = `${s.key} ${s.unit}`;
      if (!charts.has(id)) {
        charts.set(id, {id, key: s.key, unit: s.unit, series: []});
      }
      charts.get(id).series.push(s);
    }
    return [...charts.values()];
  }

  /** The `objects` rows of node `key`, asked once (again after a failure). */
  dictionary(key) {
    if (!this.#dictionaries.has(key)) {
      const rows = this.#session.request("objects", {node: nodeRef(key)}).then((answer) => answer.objects);
      rows.catch(() => this.#dictionaries.delete(key));
      this.#dictionaries.set(key, rows);
    }
    return this.#dictionaries.get(key);
  }

  /** The rows of node `key` that can be plotted. */
  async plottable(key) {
    return (await this.dictionary(key)).filter(plottableRow);
  }

  /** Plots `object` ("0x6401:01") of node `key` (the user's choice: the default no longer follows the picked node).
   * Resolves when it is a series; rejects with what is wrong (no such object, not a number, too many series). */
  async add(key, object) {
    this.#custom = true;
    const parsed = parseObject(object);
    if (parsed === null) {
      throw new Error(`"${object}" is not an object: INDEX:SUB in hex (0x6401:01)`);
    }
    const name = objectName(parsed.index, parsed.sub);
    if (this.#has(key, name)) {
      return;
    }
    const row = (await this.dictionary(key)).find((r) => r.object === name);
    if (row === undefined) {
      throw new Error(`node ${nodeRef(key)} has no object ${name}`);
    }
    if (!plottableRow(row)) {
      throw new Error(`${name} of node ${nodeRef(key)} (${row.type}, ${row.access}) is not a number that can be read`);
    }
    if (this.#has(key, name)) {
      return; // added meanwhile
    }
    if (this.#series.length >= MAX_SERIES) {
      throw new Error(`at most ${MAX_SERIES} series: remove one first`);
    }
    this.#series.push(seriesOf(key, row));
    this.#changed();
  }

  /** Stops plotting `object` of node `key` (the user's choice). */
  remove(key, object) {
    this.#custom = true;
    this.#series = this.#series.filter((s) => !(s.key === key && s.object === object));
    this.#changed();
  }

  /** The node `key` was picked: while the user has not changed the series, its TPDO objects become the plot. */
  select(key, ms) {
    if (!this.#custom && this.#defaults?.key !== key) {
      this.#useDefaults(key, ms);
    }
  }

  /** An event: EMCYs and NMT changes become marks. */
  event(event) {
    this.marks.event(event);
  }

  /** Before an exchange: the default series when there are none yet, and a get for each plotted node that has none
   * on its way. */
  tick(ms) {
    const d = this.#defaults;
    if (!this.#custom && (d === null || (d.failed && ms - d.since >= RETRY_MS))) {
      const key = d?.key ?? this.#firstNode(ms);
      if (key !== null) {
        this.#useDefaults(key, ms);
      }
    }
    const objects = new Map(); // node key -> its plotted objects
    for (const s of this.#series) {
      objects.set(s.key, [...(objects.get(s.key) ?? []), s.object]);
    }
    for (const [key, list] of objects) {
      if (!this.#asked.has(key)) {
        this.#sample(key, list);
      }
    }
  }

  #sample(key, objects) {
    this.#asked.add(key);
    this.#session.request("get", {node: nodeRef(key), objects})
      .then((answer) => {
        this.#problems.delete(key);
        this.#buffers.get(key)?.push(answer.time_us, new Map(answer.values.map((v) => [v.object, v.value])));
      })
      .catch((error) => this.#problems.set(key, `node ${nodeRef(key)}: ${error.message}`))
      .finally(() => this.#asked.delete(key));
  }

  #firstNode(ms) {
    return this.#nodes.rows(ms).find((r) => !r.heard)?.key ?? null; // an emulated one: a heard one has no values
  }

  #has(key, object) {
    return this.#series.some((s) => s.key === key && s.object === object);
  }

  #useDefaults(key, ms) {
    const run = {key, since: ms, failed: false};
    this.#defaults = run;
    this.#tpdoRows(key).then((rows) => {
      if (this.#defaults === run && !this.#custom) {
        this.#problems.delete(key);
        this.#series = rows.slice(0, MAX_SERIES).map((row) => seriesOf(key, row));
        this.#changed();
      }
    }).catch((error) => {
      run.failed = true;
      this.#problems.set(key, `node ${nodeRef(key)}: its TPDO mapping: ${error.message}`);
    });
  }

  /** The rows of the objects node `key`'s TPDOs map (that can be plotted), in mapping order. */
  async #tpdoRows(key) {
    const rows = await this.dictionary(key);
    const counts = await this.#getAll(key, mappingCounts(rows));
    const mapped = mappedObjects(await this.#getAll(key, mappingEntries(counts)));
    const byObject = new Map(rows.map((r) => [r.object, r]));
    return mapped.map((o) => byObject.get(o)).filter((r) => r !== undefined && plottableRow(r));
  }

  /** The values of any number of objects of node `key`: gets of at most 64 objects, at once. */
  async #getAll(key, objects) {
    const answers = await Promise.all(chunks(objects).map((list) =>
      this.#session.request("get", {node: nodeRef(key), objects: list})));
    return answers.flatMap((a) => a.values);
  }

  /** The buffers follow the series: one per plotted node, a column per plotted object. */
  #changed() {
    const plotted = new Map();
    for (const s of this.#series) {
      plotted.set(s.key, [...(plotted.get(s.key) ?? []), s.object]);
    }
    for (const key of this.#buffers.keys()) {
      if (!plotted.has(key)) {
        this.#buffers.delete(key);
        this.#problems.delete(key);
      }
    }
    for (const [key, objects] of plotted) {
      if (!this.#buffers.has(key)) {
        this.#buffers.set(key, new SampleBuffer());
      }
      const buffer = this.#buffers.get(key);
      for (const o of buffer.columns.filter((c) => !objects.includes(c))) {
        buffer.removeColumn(o);
      }
      for (const o of objects) {
        buffer.addColumn(o);
      }
    }
    this.changes++;
  }
}
