// The overview table (docs/web.md): one row per node, its cells from NodeTable.rows(). The page draws everything an
// exchange brought in one animation frame (web/app.js), and only the cells whose text changed are touched here, so
// that 127 nodes redrawn four times a second cost little. A click on a row opens that node.

import {tableHead} from "./dom.js";
import {COLUMNS, busLabel, nodeCount, withBusHeadings} from "./nodes.js";

export class Overview {
  #body;
  #status;
  #rows = new Map(); // key -> {tr, cells: {field: td}}
  #onPick;

  /** onPick(key): a row was clicked (or Enter pressed on it): the page shows that node. */
  constructor(table, status, onPick = () => {}) {
    this.#onPick = onPick;
    tableHead(table, COLUMNS);
    this.#body = table.createTBody();
    this.#status = status;
  }

  /** Shows `rows` (NodeTable.rows()) and in the status line `problem`, or when it is null the count of nodes and the
   * buses (NodeTable.buses(): each named with its kind) they are on. */
  render(rows, problem, buses = []) {
    const kinds = new Map(buses.map((b) => [b.name, b.kind]));
    const items = withBusHeadings(rows, buses);
    const keys = new Set(items.map((r) => r.key));
    for (const [key, {tr}] of this.#rows) {
      if (!keys.has(key)) {
        tr.remove();
        this.#rows.delete(key);
      }
    }
    let previous = null;
    for (const row of items) {
      if (row.heading !== undefined) {
        previous = this.#place(this.#headingRow(row), previous);
        continue;
      }
      const {tr, cells} = this.#rows.get(row.key) ?? this.#add(row.key);
      for (const [field, text] of Object.entries(row.cells)) {
        if (cells[field].textContent !== text) {
          cells[field].textContent = text; // text, never markup: nothing the emulator says becomes HTML
        }
      }
      const age = cells["heartbeat-age"];
      if (age.classList.contains("overdue") !== row.overdue) {
        age.classList.toggle("overdue", row.overdue); // style.css: in red
      }
      const busTitle = busLabel(row.cells.bus, kinds.get(row.cells.bus)); // the kind on hovering over the bus
      if (cells.bus.title !== busTitle) {
        cells.bus.title = busTitle;
      }
      if (tr.dataset.heard !== String(row.heard)) {
        tr.dataset.heard = String(row.heard); // a node heard on the bus: not emulated, nothing to open
        tr.title = row.heard ? "a node heard on the bus (not emulated here)" : "open this node";
      }
      if (tr.dataset.state !== row.state) {
        tr.dataset.state = row.state; // style.css colours the state by it
      }
      previous = this.#place(tr, previous);
    }
    this.#status.textContent = problem ?? nodeCount(rows, buses);
    this.#status.classList.toggle("problem", problem !== null);
  }

  /** Puts tr right after `previous` (first when null) unless it is there already; returns tr. */
  #place(tr, previous) {
    const expected = previous === null ? this.#body.firstElementChild : previous.nextElementSibling;
    if (expected !== tr) {
      if (previous === null) {
        this.#body.prepend(tr);
      } else {
        previous.after(tr);
      }
    }
    return tr;
  }

  /** The heading row of a bus (several buses: withBusHeadings), made once, its text kept up to date. */
  #headingRow({key, heading}) {
    let entry = this.#rows.get(key);
    if (entry === undefined) {
      const tr = document.createElement("tr");
      tr.dataset.key = key;
      tr.className = "bus-heading";
      const th = document.createElement("th");
      th.scope = "rowgroup";
      th.colSpan = COLUMNS.length;
      tr.append(th);
      entry = {tr, cells: {heading: th}};
      this.#rows.set(key, entry);
    }
    if (entry.cells.heading.textContent !== heading) {
      entry.cells.heading.textContent = heading;
    }
    return entry.tr;
  }

  #add(key) {
    const tr = document.createElement("tr");
    tr.dataset.key = key;
    tr.tabIndex = 0; // reachable by keyboard: Enter opens the node as a click does
    tr.addEventListener("click", () => this.#onPick(key));
    tr.addEventListener("keydown", (e) => {
      if (e.key === "Enter") {
        this.#onPick(key);
      }
    });
    const cells = {};
    for (const {field} of COLUMNS) {
      const td = tr.insertCell();
      td.dataset.field = field;
      cells[field] = td;
    }
    const entry = {tr, cells};
    this.#rows.set(key, entry);
    return entry;
  }
}
