// The plots view (docs/web.md "Plots"): process values over time, by default the objects the TPDOs of the picked
// node map, any numeric object on demand (its own picker, or page.plot from another view), with the EMCYs and NMT
// changes of the plotted nodes marked on the time axis. The model and the sampling are web/plotting.js; a chart is
// web/plotchart.js. Samples are taken at every exchange whether the view is shown or not (a plot has its history
// when the user comes to it); the charts are drawn only while it is shown, once per exchange.

import {element} from "./dom.js";
import {nodeRef} from "./nodes.js";
import {Plotting} from "./plotting.js";
import {PlotChart} from "./plotchart.js";

/** The time spans the charts can show (s), and the one they show first. */
const SPANS = [[30, "30 s"], [60, "1 min"], [120, "2 min"], [300, "5 min"], [600, "10 min"]];
const FIRST_SPAN = 60;

/** The panel (web/app.js): it also sets page.plot. */
export function makePlots(page) {
  const plotting = new Plotting(page.session, page.nodes);
  const view = new PlotsView(document.getElementById("view-plots"), plotting, page);
  page.plot = (key, object) => view.add(key, object);
  return {
    view: "plots",
    events: ["emcy", "nmt"],
    tick: (session, ms) => plotting.tick(ms),
    event: (event) => plotting.event(event),
    select: (key) => plotting.select(key, performance.now()),
    shown: (visible) => view.shown(visible),
    draw: (ms) => view.draw(ms),
  };
}

class PlotsView {
  #plotting;
  #page;
  #visible = false;
  #nodeSelect;
  #objectSelect;
  #spanSelect;
  #status;
  #list;
  #chartsBox;
  #charts = new Map(); // chart id -> PlotChart
  #drawnChanges = -1; // Plotting.changes when the list and the charts were last made
  #nodeKeys = ""; // the node select's keys, to refill it only when they change
  #error = null; // what the user's last action was refused for

  constructor(section, plotting, page) {
    this.#plotting = plotting;
    this.#page = page;
    this.#nodeSelect = element("select", {name: "node"}, element("option", {value: "", textContent: "node"}));
    this.#objectSelect = element("select", {name: "object", disabled: true},
      element("option", {value: "", textContent: "object"}));
    this.#spanSelect = element("select", {name: "span"}, ...SPANS.map(([s, text]) =>
      element("option", {value: String(s), textContent: text, selected: s === FIRST_SPAN})));
    const form = element("form", {className: "plots-picker"},
      element("label", {}, "plot ", this.#nodeSelect), " ",
      element("label", {}, this.#objectSelect), " ",
      element("button", {type: "submit", textContent: "add"}), " ",
      element("label", {className: "plots-span"}, "time span ", this.#spanSelect));
    this.#status = element("p", {className: "plots-status"});
    this.#status.setAttribute("role", "status");
    this.#list = element("ul", {className: "plots-series"});
    this.#chartsBox = element("div", {className: "plots-charts"});
    section.append(form, this.#status, this.#list, this.#chartsBox);

    this.#nodeSelect.addEventListener("change", () => this.#fillObjects());
    this.#spanSelect.addEventListener("change", () => page.redraw());
    form.addEventListener("submit", (e) => {
      e.preventDefault();
      if (this.#nodeSelect.value === "" || this.#objectSelect.value === "") {
        this.#error = "pick a node and one of its objects first";
        page.redraw();
        return;
      }
      this.add(this.#nodeSelect.value, this.#objectSelect.value);
    });
    window.addEventListener("resize", () => page.redraw());
  }

  /** Plots `object` of node `key`; resolves to null when it is plotted, or to why not (also shown in the view). */
  add(key, object) {
    const adding = this.#plotting.add(key, object).then(() => {
      this.#error = null;
      return null;
    }, (error) => {
      this.#error = `${object}: ${error.message}`;
      return this.#error;
    }).finally(() => this.#page.redraw());
    this.#page.exchangeSoon(); // the node's dictionary may be needed: ask now, not at the next tick
    return adding;
  }

  shown(visible) {
    this.#visible = visible;
  }

  draw(ms) {
    if (!this.#visible) {
      return;
    }
    this.#fillNodes(ms);
    const problem = this.#error ?? this.#plotting.problem;
    this.#status.textContent = problem ?? this.#describe();
    this.#status.classList.toggle("problem", problem !== null);
    if (this.#drawnChanges !== this.#plotting.changes) {
      this.#drawnChanges = this.#plotting.changes;
      this.#makeList();
      this.#makeCharts();
    }
    const width = Math.max(300, this.#chartsBox.clientWidth);
    const span = Number(this.#spanSelect.value);
    const now = this.#page.nodes.clock.now(ms);
    const charts = this.#plotting.charts();
    // The right edge: the emulator's clock now (or the newest sample, when the estimate lags behind it).
    let to = now === null ? null : now / 1e6;
    for (const c of charts) {
      const times = this.#plotting.buffer(c.key).times;
      if (times.length > 0) {
        to = Math.max(to ?? -Infinity, times[times.length - 1]);
      }
    }
    // The first `span` seconds of a run: from 0, the lines growing to the right; then the last `span` seconds.
    const from = to === null ? null : Math.max(0, to - span);
    to = from === null ? null : Math.max(to, from + span);
    for (const c of charts) {
      const chart = this.#charts.get(c.id);
      chart.resize(width);
      const marks = this.#plotting.marks.between(c.key, from ?? -Infinity, to ?? Infinity);
      chart.update(this.#plotting.buffer(c.key), c.series.map((s) => s.object), from, to, marks);
    }
  }

  #describe() {
    const count = this.#plotting.series.length;
    const key = this.#plotting.defaultKey;
    if (key !== null) {
      return `the objects the TPDOs of node ${nodeRef(key)} map (${count}): they follow the node picked in the ` +
        "network view until a series is added or removed here";
    }
    return count === 0 ? "nothing plotted: pick a node and an object" : `${count} series`;
  }

  /** The node select: the nodes of the last show, refilled when they change; the choice kept. */
  #fillNodes(ms) {
    const rows = this.#page.nodes.rows(ms).filter((r) => !r.heard); // a node only heard has nothing to read
    const keys = rows.map((r) => r.key).join(" ");
    if (keys === this.#nodeKeys) {
      return;
    }
    this.#nodeKeys = keys;
    const chosen = this.#nodeSelect.value;
    this.#nodeSelect.replaceChildren(element("option", {value: "", textContent: "node"}),
      ...rows.map((r) => element("option", {value: r.key, textContent: `${nodeRef(r.key)} ${r.cells.device}`,
        selected: r.key === chosen})));
  }

  /** The object select: the numeric objects of the chosen node (its dictionary asked once). */
  async #fillObjects() {
    const key = this.#nodeSelect.value;
    this.#objectSelect.disabled = true;
    this.#objectSelect.replaceChildren(element("option", {value: "", textContent: key === "" ? "object" : "loading…"}));
    if (key === "") {
      return;
    }
    const loading = this.#plotting.plottable(key);
    this.#page.exchangeSoon();
    let rows;
    try {
      rows = await loading;
    } catch (error) {
      this.#error = `node ${nodeRef(key)}: its objects: ${error.message}`;
      this.#page.redraw();
      return;
    }
    if (this.#nodeSelect.value !== key) {
      return; // another node was chosen meanwhile
    }
    this.#objectSelect.replaceChildren(element("option", {value: "", textContent: "object"}),
      ...rows.map((r) => element("option", {value: r.object,
        textContent: `${r.object} ${r.name ?? r.object_name ?? ""}${r.unit ? ` [${r.unit}]` : ""}`})));
    this.#objectSelect.disabled = false;
  }

  /** The list of series, each with its remove button. The item of a series still plotted is kept, not made anew:
   * a click begun on one while another series is removed (the list redrawn between press and release) still lands. */
  #makeList() {
    const kept = new Map([...this.#list.children].map((li) => [`${li.dataset.node} ${li.dataset.object}`, li]));
    this.#list.replaceChildren(...this.#plotting.series.map((s) => kept.get(`${s.key} ${s.object}`) ??
      this.#listItem(s)));
  }

  #listItem(s) {
    const remove = element("button", {type: "button", className: "remove", textContent: "×",
      title: "stop plotting this"});
    remove.setAttribute("aria-label", `stop plotting ${s.object} of node ${nodeRef(s.key)}`);
    remove.addEventListener("click", () => {
      this.#plotting.remove(s.key, s.object);
      this.#error = null;
      this.#page.redraw();
    });
    const li = element("li", {}, element("span", {textContent:
      `${nodeRef(s.key)} ${s.label}${s.unit ? ` [${s.unit}]` : ""}`}), remove);
    li.dataset.node = s.key;
    li.dataset.object = s.object;
    return li;
  }

  /** The charts as the series group them: one that still fits is kept (with its zoom and cursor), others made. */
  #makeCharts() {
    const width = Math.max(300, this.#chartsBox.clientWidth);
    const wanted = this.#plotting.charts();
    const ids = new Set(wanted.map((c) => c.id));
    for (const [id, chart] of this.#charts) {
      if (!ids.has(id)) {
        chart.destroy();
        this.#charts.delete(id);
      }
    }
    for (const c of wanted) {
      const kept = this.#charts.get(c.id);
      if (kept !== undefined && kept.signature !== PlotChart.signatureOf(c)) {
        kept.destroy();
        this.#charts.delete(c.id);
      }
      if (!this.#charts.has(c.id)) {
        this.#charts.set(c.id, new PlotChart(c, `node ${nodeRef(c.key)} · ${c.unit === "" ? "no unit" : c.unit}`,
          width));
      }
    }
    this.#chartsBox.replaceChildren(...wanted.map((c) => this.#charts.get(c.id).element));
  }
}
